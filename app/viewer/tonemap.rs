//! GPU display of the linear render: the frame goes to an `Rgba32Float` texture (uploaded
//! only when a new frame arrived), and a paint callback draws it with exposure, tone curve and
//! sRGB encoding applied in a shader, so display changes cost no CPU work and never touch the
//! render. Texels are fetched with `textureLoad` (nearest), as a pixel inspector should.

use caustica_renderer::image::{Image, ToneCurve};
use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, RenderState, wgpu};
use std::time::{Duration, Instant};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Uniforms {
    uv_min: [f32; 2],
    uv_max: [f32; 2],
    size: [f32; 2],
    scale: f32,
    curve: u32,
    encode_srgb: u32,
    pad: [u32; 3],
}

struct ImageTexture {
    texture: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
}

pub struct TonemapResources {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    encode_srgb: bool,
    image: Option<ImageTexture>,
}

/// Creates the pipeline once and stores it with egui's renderer.
pub fn init(rs: &RenderState) {
    let device = &rs.device;
    let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("caustica tonemap"),
        source: wgpu::ShaderSource::Wgsl(include_str!("tonemap.wgsl").into()),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("caustica tonemap"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("caustica tonemap"),
        bind_group_layouts: &[Some(&layout)],
        ..Default::default()
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("caustica tonemap"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &shader,
            entry_point: Some("vs_main"),
            buffers: &[],
            compilation_options: Default::default(),
        },
        fragment: Some(wgpu::FragmentState {
            module: &shader,
            entry_point: Some("fs_main"),
            targets: &[Some(wgpu::ColorTargetState {
                format: rs.target_format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
            compilation_options: Default::default(),
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    });
    let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("caustica tonemap uniforms"),
        size: std::mem::size_of::<Uniforms>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    // egui draws into a non-sRGB target and expects gamma-encoded values there.
    let encode_srgb = !rs.target_format.is_srgb();
    rs.renderer
        .write()
        .callback_resources
        .insert(TonemapResources {
            pipeline,
            layout,
            uniforms,
            encode_srgb,
            image: None,
        });
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
        let texture = rs.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("caustica frame"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let bind_group = rs.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("caustica frame"),
            layout: &res.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: res.uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
            ],
        });
        res.image = Some(ImageTexture {
            texture,
            bind_group,
            width: w,
            height: h,
        });
    }
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
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
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
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(res) = resources.get::<TonemapResources>()
            && let Some(t) = &res.image
        {
            let u = Uniforms {
                uv_min: self.uv_min,
                uv_max: self.uv_max,
                size: [t.width as f32, t.height as f32],
                scale: 2f32.powf(self.exposure),
                curve: self.curve.index(),
                encode_srgb: res.encode_srgb as u32,
                pad: [0; 3],
            };
            queue.write_buffer(&res.uniforms, 0, bytemuck::bytes_of(&u));
        }
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
            pass.set_pipeline(&res.pipeline);
            pass.set_bind_group(0, &t.bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

use eframe::egui;
