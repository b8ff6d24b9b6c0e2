//! An EXR file's bytes through the reader of references, environment maps and cameras.
#![no_main]

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let _ = caustica_renderer::image::exr_from_bytes(bytes);
});
