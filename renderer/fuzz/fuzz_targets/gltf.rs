//! A glTF or GLB file's bytes through everything a scene goes through: read, built, rendered.
#![no_main]

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    caustica_renderer::fuzzing::load_and_render_gltf(bytes);
});
