//! egui drawn once per change, not once per frame. The panels are tessellated and rendered
//! into cached textures of the window's size (premultiplied alpha over transparent) only when
//! egui's output differs from the last frame's (other shapes, texture updates, another size
//! or scale); every frame composites those textures over the attractor
//! (`shaders/composite.wgsl`), each scissored to the union of the clip rectangles egui drew in.
//!
//! Why: on a software rasterizer (lavapipe) rendering the panels cost about as much CPU as the
//! resolve and present together (≈ 35 ms a frame at 1280×720, docs/performance.md), while the
//! panels change a few times a second at most (the statistics text is refreshed twice a
//! second). The composite is one unfiltered texture load per covered pixel. The result is the
//! same image: egui's blending (colour One/OneMinusSrcAlpha, alpha OneMinusDstAlpha/One) into a
//! transparent texture yields the premultiplied "over" of its shapes, and compositing that with
//! premultiplied blending equals drawing the shapes onto the frame directly.
//!
//! The timeline strip changes every frame while the timeline plays or is scrubbed (its time
//! field and playhead), so it has a layer of its own ([`split_strip`]): the strip's shapes are
//! rendered into a second texture composited after the first, and playing re-renders only the
//! strip. The split keeps egui's painting order: it is made only when the strip's shapes are
//! one run of the output and nothing painted after them overlaps the strip (a tooltip or a
//! menu over it puts everything back into one layer for those frames).

/// One frame's egui output, as [`UiLayer::update`] takes it.
pub struct EguiFrame {
    pub shapes: Vec<egui::epaint::ClippedShape>,
    pub pixels_per_point: f32,
    /// egui uploaded or freed textures this frame.
    pub textures_changed: bool,
    /// The timeline strip (egui points), rendered apart when it can be.
    pub strip: Option<egui::Rect>,
    /// The event loop's clock (seconds).
    pub now_secs: f64,
    /// How long the panels' layer may keep showing older shapes (None: never); the strip's
    /// layer is always current.
    pub panels_lag_secs: Option<f64>,
}

/// The cached layers (the panels, the timeline strip) and the composite pipeline.
pub struct UiLayer {
    pipeline: wgpu::RenderPipeline,
    format: wgpu::TextureFormat,
    layers: [Layer; 2],
    /// Layer renders so far (statistics for `--log-fps`; a frame that re-renders both counts 2).
    pub renders: u64,
}

/// One cached texture and what it shows.
#[derive(Default)]
struct Layer {
    target: Option<Target>,
    /// What the texture shows: egui's shapes and pixels per point.
    shown: Option<(Vec<egui::epaint::ClippedShape>, f32)>,
    /// Where egui drew (window pixels: x, y, width, height); None when it drew nothing.
    scissor: Option<[u32; 4]>,
    /// When it was last rendered (the event loop's clock, seconds).
    rendered_secs: f64,
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
        Self { pipeline, format, layers: Default::default(), renders: 0 }
    }

    /// Brings the cached textures up to date with this frame's egui output in a window of
    /// `size_px`. Renders (and submits, one submission a layer: egui's renderer stages its
    /// buffers in the queue) only the layers whose shapes changed, the panels' not before
    /// `panels_lag_secs` have passed when that is set. True when a layer was left showing
    /// older shapes (another frame must follow).
    pub fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &mut egui_wgpu::Renderer,
        egui_ctx: &egui::Context,
        frame: EguiFrame,
        size_px: [u32; 2],
    ) -> bool {
        let EguiFrame { shapes, pixels_per_point, textures_changed, strip, now_secs, panels_lag_secs } = frame;
        let mut stale = false;
        let (panels, strip) = match strip {
            Some(rect) => split_strip(shapes, rect),
            None => (shapes, Vec::new()),
        };
        for (i, shapes) in [panels, strip].into_iter().enumerate() {
            if self.layers[i].target.as_ref().is_none_or(|t| t.size != size_px) {
                let target = self.make_target(device, size_px);
                self.layers[i] = Layer { target: Some(target), ..Layer::default() };
            }
            let layer = &mut self.layers[i];
            let unchanged = !textures_changed
                && layer.shown.as_ref().is_some_and(|(s, ppp)| *ppp == pixels_per_point && *s == shapes);
            if unchanged {
                continue;
            }
            let may_lag = i == 0 && !textures_changed && layer.shown.is_some();
            if let Some(lag) = panels_lag_secs.filter(|_| may_lag)
                && now_secs - layer.rendered_secs < lag
            {
                stale = true;
                continue;
            }
            if shapes.is_empty() {
                // Nothing to draw: nothing to composite either.
                layer.scissor = None;
                layer.shown = Some((shapes, pixels_per_point));
                continue;
            }
            let Some(target) = &layer.target else { continue };
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("egui_layer") });
            let paint_jobs = egui_ctx.tessellate(shapes.clone(), pixels_per_point);
            let screen = egui_wgpu::ScreenDescriptor { size_in_pixels: size_px, pixels_per_point };
            let extra = renderer.update_buffers(device, queue, &mut encoder, &paint_jobs, &screen);
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
            queue.submit(extra.into_iter().chain([encoder.finish()]));
            layer.scissor = scissor_of(&paint_jobs, pixels_per_point, size_px);
            layer.shown = Some((shapes, pixels_per_point));
            layer.rendered_secs = now_secs;
            self.renders += 1;
        }
        stale
    }

    /// Records the composite of the cached layers over `view` (the frame, of the layers' size),
    /// the panels' first.
    pub fn composite(&self, encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView) {
        for layer in &self.layers {
            let (Some(target), Some([x, y, w, h])) = (&layer.target, layer.scissor) else { continue };
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

/// Splits egui's shapes into the panels' and the strip's (`strip`: the timeline's rectangle,
/// egui points) when that keeps the painting order: the shapes clipped to within the strip are
/// one run, and nothing painted after that run overlaps what the run paints (then compositing
/// the strip's layer last paints what egui would paint; the panel's border line, painted later
/// along the strip's edge, only touches it). Otherwise every shape stays in the first part and
/// the second is empty.
pub fn split_strip(
    shapes: Vec<egui::epaint::ClippedShape>,
    strip: egui::Rect,
) -> (Vec<egui::epaint::ClippedShape>, Vec<egui::epaint::ClippedShape>) {
    let inside = |s: &egui::epaint::ClippedShape| strip.contains_rect(s.clip_rect);
    let painted = |s: &egui::epaint::ClippedShape| s.shape.visual_bounding_rect().intersect(s.clip_rect);
    let Some(first) = shapes.iter().position(inside) else { return (shapes, Vec::new()) };
    let run = shapes[first..].iter().take_while(|s| inside(s)).count();
    let run_painted = shapes[first..first + run].iter().map(painted).fold(egui::Rect::NOTHING, |a, b| a.union(b));
    let after_overlaps = shapes[first + run..].iter().any(|s| painted(s).intersect(run_painted).is_positive());
    if after_overlaps {
        return (shapes, Vec::new());
    }
    let mut panels = shapes;
    let strip_shapes: Vec<_> = panels.drain(first..first + run).collect();
    (panels, strip_shapes)
}
