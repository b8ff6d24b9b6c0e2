// The render's display, in two passes (see tonemap.rs):
// - fs_tone: the linear float image to 8-bit sRGB-encoded display values (exposure, tone
//   curve), pixel for pixel into the display texture, run only when the frame or the display
//   settings change. Curves mirror caustica_renderer::image::ToneCurve.
// - fs_show: the visible part of the display texture over the callback's rectangle, nearest
//   texel, every UI frame.

// The curve is a pipeline constant, not a uniform: a software rasteriser (llvmpipe) runs
// every side of a branch on a uniform, so a pipeline per curve costs one curve.
override CURVE: u32 = 0u;

struct ToneUniforms {
    scale: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
};

struct ShowUniforms {
    uv_min: vec2<f32>,
    uv_max: vec2<f32>,
    size: vec2<f32>,
    pad0: vec2<f32>,
};

@group(0) @binding(0) var<uniform> tone_u: ToneUniforms;
@group(0) @binding(1) var image: texture_2d<f32>;

@group(0) @binding(2) var<uniform> show_u: ShowUniforms;
@group(0) @binding(3) var display: texture_2d<f32>;

struct VsOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

// One triangle covering the viewport; uv runs from the top-left corner.
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> VsOut {
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    var out: VsOut;
    out.position = vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
    out.uv = vec2<f32>(x, y);
    return out;
}

fn tone(x_in: f32) -> f32 {
    let x = max(x_in, 0.0);
    if (CURVE == 1u) {
        return x / (1.0 + x);
    }
    if (CURVE == 2u) {
        return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    }
    return min(x, 1.0);
}

fn srgb(x: f32) -> f32 {
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// The display texture has the image's size, so the fragment's pixel is the image's texel.
@fragment
fn fs_tone(in: VsOut) -> @location(0) vec4<f32> {
    let c = textureLoad(image, vec2<i32>(in.position.xy), 0).rgb * tone_u.scale;
    let m = vec3<f32>(tone(c.r), tone(c.g), tone(c.b));
    return vec4<f32>(srgb(m.r), srgb(m.g), srgb(m.b), 1.0);
}

@fragment
fn fs_show(in: VsOut) -> @location(0) vec4<f32> {
    let uv = mix(show_u.uv_min, show_u.uv_max, in.uv);
    let size = show_u.size;
    let texel = vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), size - vec2<f32>(1.0)));
    return vec4<f32>(textureLoad(display, texel, 0).rgb, 1.0);
}
