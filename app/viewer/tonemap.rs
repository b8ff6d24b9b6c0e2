//! GPU display of the linear render, in two steps. The frame goes to an `Rgba32Float`
//! texture (uploaded only when a new frame arrived) and a tone-mapping pass turns it into an
//! 8-bit display texture, pixel for pixel (exposure, tone curve, sRGB encoding), only when the
//! frame, the exposure or the curve changed; every UI frame then draws the visible part of the
//! display texture, a texel fetch per screen pixel. Display changes cost no CPU work and never
//! touch the render. Texels are fetched with `textureLoad` (nearest), as a pixel inspector
//! should.
//!
//! Why the cache: with software rendering (lavapipe, llvmpipe) tone mapping in the UI frame's
//! own pass (a float fetch, the curve, a `pow` per channel) cost about 45 ns of CPU per screen
//! pixel, 19 ms a frame for an image filling a 1280 x 800 window's centre; the cached texture's
//! fetch is about half of that, and the tone-mapping pass runs at the image's resolution about
//! once a second (a pass), or while the user drags the exposure.

use caustica_renderer::image::{Image, ToneCurve};
use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, RenderState, wgpu};
use std::time::{Duration, Instant};

/// The tone-mapping pass's uniforms (tonemap.wgsl, `ToneUniforms`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ToneUniforms {
    scale: f32,
    pad: [f32; 3],
}

/// The display pass's uniforms (tonemap.wgsl, `ShowUniforms`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShowUniforms {
    uv_min: [f32; 2],
    uv_max: [f32; 2],
    size: [f32; 2],
    pad: [f32; 2],
}

/// The display texture's format: sRGB-encoded values in plain 8-bit channels.
const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

struct ImageTexture {
    /// The frame, linear, as uploaded.
    texture: wgpu::Texture,
    tone_bind_group: wgpu::BindGroup,
    /// The tone-mapped frame.
    display_view: wgpu::TextureView,
    show_bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
}

/// What the display texture holds: the upload it was made from, the exposure's bits and the
/// curve.
type DisplayKey = (u64, u32, u32);

pub struct TonemapResources {
    /// One per tone curve (`ToneCurve::index`), drawing into the display texture.
    tone_pipelines: Vec<wgpu::RenderPipeline>,
    show_pipeline: wgpu::RenderPipeline,
    tone_layout: wgpu::BindGroupLayout,
    show_layout: wgpu::BindGroupLayout,
    tone_uniforms: wgpu::Buffer,
    show_uniforms: wgpu::Buffer,
    /// A window with an sRGB target shows the display texture through an sRGB view, so that
    /// the fetch decodes what the target encodes again.
    srgb_target: bool,
    image: Option<ImageTexture>,
    uploads: u64,
    display: Option<DisplayKey>,
}

fn bind_group_layout(device: &wgpu::Device, uniform: u32, texture: u32) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("caustica tonemap"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: uniform,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: texture,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
        ],
    })
}

/// A pipeline drawing one triangle over the viewport with `fragment` into `format`.
fn pipeline(
    device: &wgpu::Device,
    shader: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    fragment: &str,
    constants: &[(&str, f64)],
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("caustica tonemap"),
        bind_group_layouts: &[Some(layout)],
        ..Default::default()
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("caustica tonemap"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: shader,
            entry_point: Some("vs_main"),
            buffers: &[],
            compilation_options: Default::default(),
        },
        fragment: Some(wgpu::FragmentState {
            module: shader,
            entry_point: Some(fragment),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

fn uniform_buffer(device: &wgpu::Device, size: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("caustica tonemap uniforms"),
        size: size as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Creates the pipelines once and stores them with egui's renderer.
pub fn init(rs: &RenderState) {
    let device = &rs.device;
    let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("caustica tonemap"),
        source: wgpu::ShaderSource::Wgsl(include_str!("tonemap.wgsl").into()),
    });
    let tone_layout = bind_group_layout(device, 0, 1);
    let show_layout = bind_group_layout(device, 2, 3);
    let tone_pipelines = ToneCurve::ALL
        .iter()
        .map(|curve| {
            let constants = [("CURVE", curve.index() as f64)];
            pipeline(
                device,
                &shader,
                &tone_layout,
                "fs_tone",
                &constants,
                DISPLAY_FORMAT,
            )
        })
        .collect();
    let show_pipeline = pipeline(
        device,
        &shader,
        &show_layout,
        "fs_show",
        &[],
        rs.target_format,
    );
    rs.renderer
        .write()
        .callback_resources
        .insert(TonemapResources {
            tone_pipelines,
            show_pipeline,
            tone_layout,
            show_layout,
            tone_uniforms: uniform_buffer(device, std::mem::size_of::<ToneUniforms>()),
            show_uniforms: uniform_buffer(device, std::mem::size_of::<ShowUniforms>()),
            srgb_target: rs.target_format.is_srgb(),
            image: None,
            uploads: 0,
            display: None,
        });
}

fn extent(width: u32, height: u32) -> wgpu::Extent3d {
    wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    }
}

/// The frame's and the display's textures for an image of `width` x `height`.
fn image_texture(
    rs: &RenderState,
    res: &TonemapResources,
    width: u32,
    height: u32,
) -> ImageTexture {
    let device = &rs.device;
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("caustica frame"),
        size: extent(width, height),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let display = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("caustica display"),
        size: extent(width, height),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DISPLAY_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[DISPLAY_FORMAT.add_srgb_suffix()],
    });
    let display_view = display.create_view(&wgpu::TextureViewDescriptor::default());
    let shown_view = display.create_view(&wgpu::TextureViewDescriptor {
        format: res.srgb_target.then(|| DISPLAY_FORMAT.add_srgb_suffix()),
        ..Default::default()
    });
    let bind_group = |layout, uniforms: &wgpu::Buffer, (u, t), view| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("caustica tonemap"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: u,
                    resource: uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: t,
                    resource: wgpu::BindingResource::TextureView(view),
                },
            ],
        })
    };
    let frame_view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    ImageTexture {
        tone_bind_group: bind_group(&res.tone_layout, &res.tone_uniforms, (0, 1), &frame_view),
        show_bind_group: bind_group(&res.show_layout, &res.show_uniforms, (2, 3), &shown_view),
        texture,
        display_view,
        width,
        height,
    }
}

/// Uploads a frame to the GPU; returns how long the conversion and upload took.
pub fn upload(rs: &RenderState, image: &Image) -> Duration {
    let start = Instant::now();
    let (w, h) = (image.width as u32, image.height as u32);
    let mut texels: Vec<f32> = Vec::with_capacity(image.pixels.len() * 4);
    for p in &image.pixels {
        texels.extend_from_slice(&[p.x, p.y, p.z, 1.0]);
    }
    let mut renderer = rs.renderer.write();
    let Some(res) = renderer.callback_resources.get_mut::<TonemapResources>() else {
        return start.elapsed();
    };
    if res
        .image
        .as_ref()
        .is_none_or(|t| (t.width, t.height) != (w, h))
    {
        res.image = Some(image_texture(rs, res, w, h));
    }
    res.uploads += 1;
    if let Some(t) = &res.image {
        rs.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &t.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 16),
                rows_per_image: Some(h),
            },
            extent(w, h),
        );
    }
    start.elapsed()
}

/// Draws the part `uv_min..uv_max` of the uploaded image over the callback's rectangle.
pub struct TonemapCallback {
    pub uv_min: [f32; 2],
    pub uv_max: [f32; 2],
    pub exposure: f32,
    pub curve: ToneCurve,
}

impl CallbackTrait for TonemapCallback {
    fn prepare(
        &self,
        _device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(res) = resources.get_mut::<TonemapResources>() else {
            return Vec::new();
        };
        let Some(t) = &res.image else {
            return Vec::new();
        };
        let key = (res.uploads, self.exposure.to_bits(), self.curve.index());
        if res.display != Some(key) {
            let tone = ToneUniforms {
                scale: 2f32.powf(self.exposure),
                pad: [0.0; 3],
            };
            queue.write_buffer(&res.tone_uniforms, 0, bytemuck::bytes_of(&tone));
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("caustica tone mapping"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &t.display_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&res.tone_pipelines[self.curve.index() as usize]);
            pass.set_bind_group(0, &t.tone_bind_group, &[]);
            pass.draw(0..3, 0..1);
            drop(pass);
            res.display = Some(key);
        }
        let show = ShowUniforms {
            uv_min: self.uv_min,
            uv_max: self.uv_max,
            size: [t.width as f32, t.height as f32],
            pad: [0.0; 2],
        };
        queue.write_buffer(&res.show_uniforms, 0, bytemuck::bytes_of(&show));
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &CallbackResources,
    ) {
        if let Some(res) = resources.get::<TonemapResources>()
            && let Some(t) = &res.image
        {
            pass.set_pipeline(&res.show_pipeline);
            pass.set_bind_group(0, &t.show_bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

use eframe::egui;
