//! Regenerates the bundled scenes in `assets/`:
//!
//! ```text
//! cargo run -p caustica-renderer --example make_assets -- assets
//! ```
//!
//! The test `bundled_assets_are_regenerable` checks that the committed files are exactly what
//! this program writes.

use caustica_renderer::procedural::bundled_assets;
use std::path::PathBuf;

fn main() -> std::io::Result<()> {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "assets".into()));
    std::fs::create_dir_all(&dir)?;
    for (name, text) in bundled_assets() {
        let path = dir.join(name);
        std::fs::write(&path, text)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
