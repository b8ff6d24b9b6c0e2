// Tone mapping of the render's linear float image, drawn by an egui paint callback over the
// visible part of the image. Curves mirror caustica_renderer::image::ToneCurve.

struct Uniforms {
    uv_min: vec2<f32>,
    uv_max: vec2<f32>,
    size: vec2<f32>,
    scale: f32,
    curve: u32,
    encode_srgb: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var image: texture_2d<f32>;

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

fn tone(x_in: f32, curve: u32) -> f32 {
    let x = max(x_in, 0.0);
    if (curve == 1u) {
        return x / (1.0 + x);
    }
    if (curve == 2u) {
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

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let uv = mix(u.uv_min, u.uv_max, in.uv);
    let texel = vec2<i32>(clamp(floor(uv * u.size), vec2<f32>(0.0), u.size - vec2<f32>(1.0)));
    let c = textureLoad(image, texel, 0).rgb * u.scale;
    var m = vec3<f32>(tone(c.r, u.curve), tone(c.g, u.curve), tone(c.b, u.curve));
    if (u.encode_srgb == 1u) {
        m = vec3<f32>(srgb(m.r), srgb(m.g), srgb(m.b));
    }
    return vec4<f32>(m, 1.0);
}
