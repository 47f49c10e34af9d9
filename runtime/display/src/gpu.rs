//! The wgpu compositor: each layer is a texture (its content rasterised by the same CPU
//! canvas, uploaded only where it changed), composited on the GPU with its opacity into a
//! frame texture; offscreen for tests and screenshots, presented to a winit window by
//! [`run_window`].

use crate::color::Color;
use crate::compose::LayerView;
use crate::display::{Compositor, DisplayError};
use crate::geom::IRect;
use mocu_dataserver::Guid;
use std::collections::HashMap;
use tiny_skia::Pixmap;

const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

const SHADER: &str = r#"
struct Layer {
    rect: vec4<f32>,    // x, y, w, h in frame pixels
    screen: vec4<f32>,  // frame width, height, opacity, unused
};
@group(0) @binding(0) var<uniform> layer: Layer;
@group(0) @binding(1) var tex: texture_2d<f32>;

@vertex
fn vs_layer(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32(i & 1u), f32((i >> 1u) & 1u));
    let p = layer.rect.xy + corner * layer.rect.zw;
    return vec4<f32>(p.x / layer.screen.x * 2.0 - 1.0, 1.0 - p.y / layer.screen.y * 2.0, 0.0, 1.0);
}

@fragment
fn fs_layer(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(floor(pos.xy - layer.rect.xy));
    // Premultiplied texels: opacity scales all four channels.
    return textureLoad(tex, texel, 0) * layer.screen.z;
}

@vertex
fn vs_blit(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@group(0) @binding(1) var frame: texture_2d<f32>;

fn frame_texel(pos: vec4<f32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(frame));
    let p = vec2<i32>(floor(pos.xy));
    if (p.x >= size.x || p.y >= size.y) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    return textureLoad(frame, p, 0);
}

@fragment
fn fs_blit(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return frame_texel(pos);
}

// For an sRGB-only surface: decode, so that the hardware's encode gives back our values.
@fragment
fn fs_blit_decode(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let c = frame_texel(pos);
    let lo = c.rgb / 12.92;
    let hi = pow((c.rgb + 0.055) / 1.055, vec3<f32>(2.4));
    return vec4<f32>(select(hi, lo, c.rgb <= vec3<f32>(0.04045)), c.a);
}
"#;

struct GpuLayer {
    texture: wgpu::Texture,
    size: (u32, u32),
    uniform: wgpu::Buffer,
    bind: wgpu::BindGroup,
}

/// A window surface the compositor presents to.
struct Target {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    view_format: wgpu::TextureFormat,
    blit: wgpu::RenderPipeline,
    blit_bind: wgpu::BindGroup,
}

/// The GPU compositor.
pub struct GpuCompositor {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: String,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    shader: wgpu::ShaderModule,
    frame: wgpu::Texture,
    size: (u32, u32),
    background: wgpu::Color,
    layers: HashMap<Guid, GpuLayer>,
    target: Option<Target>,
    /// Bytes uploaded by the last composite (for tests: damage means small uploads).
    pub uploaded: usize,
}

fn adapter_error(e: impl std::fmt::Display) -> DisplayError {
    DisplayError::NoAdapter(e.to_string())
}

impl GpuCompositor {
    /// An offscreen compositor on the first adapter wgpu finds (`WGPU_BACKEND=gl|vulkan`
    /// chooses the backend).
    pub fn headless(
        width: u32,
        height: u32,
        background: Color,
    ) -> Result<GpuCompositor, DisplayError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            apply_limit_buckets: false,
            compatible_surface: None,
        }))
        .map_err(adapter_error)?;
        GpuCompositor::on_adapter(&adapter, width, height, background)
    }

    /// A compositor presenting to a window surface (`width` x `height` is the display,
    /// `sw` x `sh` the window's inner size).
    #[allow(clippy::too_many_arguments)]
    pub fn for_window(
        adapter: &wgpu::Adapter,
        surface: wgpu::Surface<'static>,
        width: u32,
        height: u32,
        sw: u32,
        sh: u32,
        background: Color,
    ) -> Result<GpuCompositor, DisplayError> {
        let mut c = GpuCompositor::on_adapter(adapter, width, height, background)?;
        c.attach(surface, adapter, sw.max(1), sh.max(1))?;
        Ok(c)
    }

    fn on_adapter(
        adapter: &wgpu::Adapter,
        width: u32,
        height: u32,
        background: Color,
    ) -> Result<GpuCompositor, DisplayError> {
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("mocu-display"),
            required_limits:
                wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(adapter_error)?;
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("layers"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("layer"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
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
        let pipeline =
            make_pipeline(&device, &shader, &layout, "vs_layer", "fs_layer", FRAME_FORMAT, true);
        let frame = make_frame(&device, width, height);
        let bg = crate::pixel::premultiply(background);
        let f = |v: u8| v as f64 / 255.0;
        Ok(GpuCompositor {
            adapter: format!("{} via {:?}", info.name, info.backend),
            device,
            queue,
            layout,
            pipeline,
            shader,
            frame,
            size: (width, height),
            background: wgpu::Color { r: f(bg[0]), g: f(bg[1]), b: f(bg[2]), a: f(bg[3]) },
            layers: HashMap::new(),
            target: None,
            uploaded: 0,
        })
    }

    fn upload(&mut self, l: &LayerView<'_>) {
        let (w, h) = (l.pixmap.width(), l.pixmap.height());
        let fresh = match self.layers.get(&l.window) {
            Some(g) => g.size != (w, h),
            None => true,
        };
        if fresh {
            let texture = self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("layer"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FRAME_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let uniform = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("layer"),
                size: 32,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("layer"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                ],
            });
            self.layers.insert(l.window, GpuLayer { texture, size: (w, h), uniform, bind });
        }
        let region = if fresh {
            Some(IRect::new(0, 0, w as i32, h as i32))
        } else {
            l.changed.map(|c| c.intersect(&IRect::new(0, 0, w as i32, h as i32)))
        };
        let g = &self.layers[&l.window];
        if let Some(r) = region.filter(|r| !r.is_empty()) {
            let stride = w as usize * 4;
            let start = r.y as usize * stride + r.x as usize * 4;
            let end = (r.bottom() as usize - 1) * stride + r.right() as usize * 4;
            self.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &g.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: r.x as u32, y: r.y as u32, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                &l.pixmap.data()[start..end],
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(stride as u32),
                    rows_per_image: Some(r.h as u32),
                },
                wgpu::Extent3d { width: r.w as u32, height: r.h as u32, depth_or_array_layers: 1 },
            );
            self.uploaded += end - start;
        }
        let u: [f32; 8] = [
            l.x as f32,
            l.y as f32,
            w as f32,
            h as f32,
            self.size.0 as f32,
            self.size.1 as f32,
            // The CPU path quantises opacity to 8 bits; so does this one.
            (l.opacity.clamp(0.0, 1.0) * 255.0).round() / 255.0,
            0.0,
        ];
        let bytes: Vec<u8> = u.iter().flat_map(|f| f.to_le_bytes()).collect();
        self.queue.write_buffer(&g.uniform, 0, &bytes);
    }

    /// Presents the frame to the window surface, if any. Returns whether it did.
    pub fn present(&mut self) -> bool {
        let Some(t) = &self.target else { return false };
        let st = match t.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(s)
            | wgpu::CurrentSurfaceTexture::Suboptimal(s) => s,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                t.surface.configure(&self.device, &t.config);
                return false;
            }
            _ => return false,
        };
        let view = st.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(t.view_format),
            ..Default::default()
        });
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("blit") });
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("blit"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&t.blit);
            pass.set_bind_group(0, &t.blit_bind, &[]);
            pass.draw(0..3, 0..1);
        }
        self.queue.submit([enc.finish()]);
        self.queue.present(st);
        true
    }

    /// Reconfigures the window surface after the OS window was resized.
    pub fn resize_surface(&mut self, width: u32, height: u32) {
        if let Some(t) = &mut self.target
            && width > 0
            && height > 0
        {
            t.config.width = width;
            t.config.height = height;
            t.surface.configure(&self.device, &t.config);
        }
    }

    fn attach(
        &mut self,
        surface: wgpu::Surface<'static>,
        adapter: &wgpu::Adapter,
        w: u32,
        h: u32,
    ) -> Result<(), DisplayError> {
        let mut config = surface
            .get_default_config(adapter, w, h)
            .ok_or_else(|| DisplayError::Window("the surface does not suit the adapter".into()))?;
        // Frame values are sRGB-encoded already. Prefer a non-sRGB surface format; else
        // a non-sRGB view of the sRGB surface; else decode in the blit shader.
        let caps = surface.get_capabilities(adapter);
        let mut fs = "fs_blit";
        if let Some(f) = caps.formats.iter().find(|f| !f.is_srgb()) {
            config.format = *f;
        } else if adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::SURFACE_VIEW_FORMATS)
        {
            config.view_formats = vec![config.format.remove_srgb_suffix()];
        } else {
            fs = "fs_blit_decode";
        }
        let view_format = config.view_formats.first().copied().unwrap_or(config.format);
        config.present_mode = wgpu::PresentMode::AutoVsync;
        surface.configure(&self.device, &config);
        let blit = make_pipeline(
            &self.device,
            &self.shader,
            &self.layout,
            "vs_blit",
            fs,
            view_format,
            false,
        );
        let blit_bind = self.frame_bind();
        self.target = Some(Target { surface, config, view_format, blit, blit_bind });
        Ok(())
    }

    fn frame_bind(&self) -> wgpu::BindGroup {
        let dummy = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blit"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM,
            mapped_at_creation: false,
        });
        let view = self.frame.create_view(&wgpu::TextureViewDescriptor::default());
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: dummy.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
            ],
        })
    }
}

fn make_frame(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("frame"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: FRAME_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

fn make_pipeline(
    device: &wgpu::Device,
    shader: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    vs: &str,
    fs: &str,
    format: wgpu::TextureFormat,
    blend: bool,
) -> wgpu::RenderPipeline {
    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(fs),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fs),
        layout: Some(&pl),
        vertex: wgpu::VertexState {
            module: shader,
            entry_point: Some(vs),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            topology: if blend {
                wgpu::PrimitiveTopology::TriangleStrip
            } else {
                wgpu::PrimitiveTopology::TriangleList
            },
            ..Default::default()
        },
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: shader,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: blend.then_some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl Compositor for GpuCompositor {
    fn name(&self) -> String {
        format!("wgpu ({})", self.adapter)
    }

    fn resize(&mut self, width: u32, height: u32) {
        self.size = (width, height);
        self.frame = make_frame(&self.device, width, height);
        if self.target.is_some() {
            let bind = self.frame_bind();
            if let Some(t) = &mut self.target {
                t.blit_bind = bind;
            }
        }
    }

    /// Recomposites the whole frame (the GPU does it in well under a millisecond); only
    /// the layer regions that changed are uploaded.
    fn composite(&mut self, layers: &[LayerView<'_>], _damage: IRect) {
        self.uploaded = 0;
        let live: std::collections::HashSet<Guid> = layers.iter().map(|l| l.window).collect();
        self.layers.retain(|g, _| live.contains(g));
        for l in layers {
            self.upload(l);
        }
        let view = self.frame.create_view(&wgpu::TextureViewDescriptor::default());
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("composite") });
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("composite"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(self.background),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            for l in layers {
                if l.opacity <= 0.0 {
                    continue;
                }
                pass.set_bind_group(0, &self.layers[&l.window].bind, &[]);
                pass.draw(0..4, 0..1);
            }
        }
        self.queue.submit([enc.finish()]);
    }

    fn read_frame(&mut self) -> Pixmap {
        let (w, h) = self.size;
        // A frame beyond what the display allocates reads back as one blank pixel.
        let Some(mut out) = crate::alloc::pixmap(w, h) else {
            return crate::alloc::pixmap(1, 1).expect("a 1 px pixmap");
        };
        let stride = (w * 4).div_ceil(256) * 256;
        let buf = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: stride as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.frame,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(stride),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        self.queue.submit([enc.finish()]);
        let slice = buf.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        if self.device.poll(wgpu::PollType::wait_indefinitely()).is_err() {
            return out;
        }
        if let Ok(data) = slice.get_mapped_range() {
            let dst = out.data_mut();
            for y in 0..h as usize {
                let row = &data[y * stride as usize..][..w as usize * 4];
                dst[y * w as usize * 4..][..w as usize * 4].copy_from_slice(row);
            }
        }
        out
    }

    fn present(&mut self) -> bool {
        GpuCompositor::present(self)
    }

    fn resize_surface(&mut self, width: u32, height: u32) {
        GpuCompositor::resize_surface(self, width, height)
    }
}
