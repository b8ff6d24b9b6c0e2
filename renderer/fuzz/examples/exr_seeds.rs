//! Writes the EXR fuzz target's seeds: a small image in each compression, in scan lines and in
//! tiles, RGB and RGBA, with a `caustica:` attribute (`cargo +nightly run --example exr_seeds
//! -- DIR`).

use exr::prelude::*;

fn main() {
    let dir = std::env::args().nth(1).expect("the folder to write the seeds to");
    let compressions = [
        ("none", Compression::Uncompressed),
        ("rle", Compression::RLE),
        ("zip1", Compression::ZIP1),
        ("zip16", Compression::ZIP16),
        ("piz", Compression::PIZ),
        ("pxr24", Compression::PXR24),
        ("b44", Compression::B44),
    ];
    for (name, compression) in compressions {
        for tiled in [false, true] {
            let blocks = if tiled {
                Blocks::Tiles(Vec2(4, 4))
            } else {
                Blocks::ScanLines
            };
            let encoding = Encoding {
                compression,
                blocks,
                line_order: LineOrder::Increasing,
            };
            let mut attributes = LayerAttributes::named("");
            attributes.other.insert(
                Text::from("caustica:passes"),
                AttributeValue::Text(Text::from("3")),
            );
            let rgba = SpecificChannels::rgba(|p: Vec2<usize>| {
                let v = (p.x() + 7 * p.y()) as f32 / 40.0;
                (v, 1.0 - v, f16::from_f32(0.5 * v), 1.0f32)
            });
            let layer = Layer::new((9, 5), attributes, encoding, rgba);
            let kind = if tiled { "tiles" } else { "lines" };
            Image::from_layer(layer)
                .write()
                .to_file(format!("{dir}/{name}-{kind}.exr"))
                .unwrap();
        }
    }
}
