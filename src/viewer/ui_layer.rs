//! egui drawn once per change, not once per frame. The panels are tessellated and rendered
//! into a cached texture of the window's size (premultiplied alpha over transparent) only when
//! egui's output differs from the last frame's (other shapes, texture updates, another size
//! or scale); every frame composites that texture over the attractor (`shaders/composite.wgsl`),
//! scissored to the union of the clip rectangles egui drew in.
//!
//! Why: on a software rasterizer (lavapipe) rendering the panels cost about as much CPU as the
//! resolve and present together (≈ 35 ms a frame at 1280×720, docs/performance.md), while the
//! panels change a few times a second at most (the statistics text is refreshed twice a
//! second). The composite is one unfiltered texture load per covered pixel. The result is the
//! same image: egui's blending (colour One/OneMinusSrcAlpha, alpha OneMinusDstAlpha/One) into a
//! transparent texture yields the premultiplied "over" of its shapes, and compositing that with
//! premultiplied blending equals drawing the shapes onto the frame directly.

/// The cached layer: texture, the egui output it shows, and the composite pipeline.
pub struct UiLayer {
    pipeline: wgpu::RenderPipeline,
    format: wgpu::TextureFormat,
    target: Option<Target>,
    /// What the texture shows: egui's shapes and pixels per point.
    shown: Option<(Vec<egui::epaint::ClippedShape>, f32)>,
    /// Where egui drew (window pixels: x, y, width, height); None when it drew nothing.
    scissor: Option<[u32; 4]>,
    /// Frames whose egui output was re-rendered (statistics for `--log-fps`).
    pub renders: u64,
}

struct Target {
    size: [u32; 2],
    view: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
}

impl UiLayer {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let module = crate::gpu::shaders::module(device, "composite");
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("composite"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("composite"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self { pipeline, format, target: None, shown: None, scissor: None, renders: 0 }
    }

    /// Brings the cached texture up to date with this frame's egui output (`shapes` at
    /// `pixels_per_point`, `textures_changed`: egui uploaded or freed textures this frame), in a
    /// window of `size_px`. Renders only when something changed; records into `encoder`.
    #[expect(clippy::too_many_arguments, reason = "the egui frame's parts and the device handles, used once per frame")]
    pub fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        renderer: &mut egui_wgpu::Renderer,
        egui_ctx: &egui::Context,
        shapes: Vec<egui::epaint::ClippedShape>,
        pixels_per_point: f32,
        textures_changed: bool,
        size_px: [u32; 2],
    ) -> Vec<wgpu::CommandBuffer> {
        if self.target.as_ref().is_none_or(|t| t.size != size_px) {
            self.target = Some(self.make_target(device, size_px));
            self.shown = None;
        }
        let unchanged =
            !textures_changed && self.shown.as_ref().is_some_and(|(s, ppp)| *ppp == pixels_per_point && *s == shapes);
        if unchanged {
            return Vec::new();
        }
        let Some(target) = &self.target else { return Vec::new() };
        let paint_jobs = egui_ctx.tessellate(shapes.clone(), pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor { size_in_pixels: size_px, pixels_per_point };
        let extra = renderer.update_buffers(device, queue, encoder, &paint_jobs, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui_layer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            renderer.render(&mut pass.forget_lifetime(), &paint_jobs, &screen);
        }
        self.scissor = scissor_of(&paint_jobs, pixels_per_point, size_px);
        self.shown = Some((shapes, pixels_per_point));
        self.renders += 1;
        extra
    }

    /// Records the composite of the cached layer over `view` (the frame, of the layer's size).
    pub fn composite(&self, encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView) {
        let (Some(target), Some([x, y, w, h])) = (&self.target, self.scissor) else { return };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_scissor_rect(x, y, w, h);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &target.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    fn make_target(&self, device: &wgpu::Device, size_px: [u32; 2]) -> Target {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("egui_layer"),
            size: wgpu::Extent3d { width: size_px[0], height: size_px[1], depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("composite"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) }],
        });
        Target { size: size_px, view, bind_group }
    }
}

/// Where the primitives draw, in window pixels (x, y, width, height): the union of each mesh's
/// bounding box within its clip rectangle, clamped to the window; None when nothing is drawn.
fn scissor_of(paint_jobs: &[egui::ClippedPrimitive], pixels_per_point: f32, size_px: [u32; 2]) -> Option<[u32; 4]> {
    let drawn = |p: &egui::ClippedPrimitive| match &p.primitive {
        egui::epaint::Primitive::Mesh(mesh) => mesh.calc_bounds().intersect(p.clip_rect),
        egui::epaint::Primitive::Callback(_) => p.clip_rect,
    };
    let union = paint_jobs.iter().map(drawn).filter(|r| r.is_positive()).reduce(|a, b| a.union(b))?;
    let [w, h] = size_px.map(|v| v as f32);
    let x0 = (union.min.x * pixels_per_point).floor().clamp(0.0, w);
    let y0 = (union.min.y * pixels_per_point).floor().clamp(0.0, h);
    let x1 = (union.max.x * pixels_per_point).ceil().clamp(0.0, w);
    let y1 = (union.max.y * pixels_per_point).ceil().clamp(0.0, h);
    (x1 > x0 && y1 > y0).then_some([x0 as u32, y0 as u32, (x1 - x0) as u32, (y1 - y0) as u32])
}
