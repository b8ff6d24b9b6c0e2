//! Replays what fuzzing found (renderer/fuzz, cargo-fuzz on nightly) on stable: every input
//! in `tests/fuzz/<target>/` once crashed, hung or over-allocated, or is a seed of the corpus
//! the fuzzer grew from. Each must now load and render, or be refused with a message; a
//! panic fails the test.

use caustica_renderer::fuzzing::load_and_render_gltf;
use caustica_renderer::image::exr_from_bytes;
use std::path::PathBuf;

fn inputs(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{}: no inputs", dir.display());
    files
        .into_iter()
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (p, bytes)
        })
        .collect()
}

#[test]
fn gltf_inputs_found_by_fuzzing_load_and_render_or_are_refused() {
    let (mut rendered, mut refused) = (0, 0);
    for (path, bytes) in inputs("gltf") {
        match load_and_render_gltf(&bytes) {
            Ok(mean) => {
                assert!(mean.is_finite(), "{}", path.display());
                rendered += 1;
            }
            Err(message) => {
                assert!(!message.trim().is_empty(), "{}", path.display());
                refused += 1;
            }
        }
    }
    // The seeds are valid scenes: some inputs must get as far as an image.
    assert!(
        rendered > 0 && refused > 0,
        "{rendered} rendered, {refused} refused"
    );
}

#[test]
fn exr_inputs_found_by_fuzzing_are_read_or_refused() {
    let (mut read, mut refused) = (0, 0);
    for (path, bytes) in inputs("exr") {
        match exr_from_bytes(&bytes) {
            Ok((image, _)) => {
                assert_eq!(
                    image.pixels.len(),
                    image.width * image.height,
                    "{}",
                    path.display()
                );
                read += 1;
            }
            Err(message) => {
                assert!(!message.trim().is_empty(), "{}", path.display());
                refused += 1;
            }
        }
    }
    assert!(read > 0 && refused > 0, "{read} read, {refused} refused");
}
