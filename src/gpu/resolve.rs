//! Host side of `shaders/resolve.wgsl`: the max-count reduction (density mode) and the
//! full-screen draw that turns the accumulation buffer into colours on any render target, the
//! window's surface or an offscreen texture alike (`draw(&TextureView)`). Its parameters
//! ([`ResolveArgs`], [`ResolveParams`]) and its CPU twin live in `src/resolve.rs`; keep the
//! three in sync. With the solid look a draw may take the light (normals, occlusion) from a
//! per-pixel cache that a light pass refreshes for some rows ([`LightRows`]; the live view
//! refreshes a band per frame at rest); refreshed whole, it gives the inline light's bytes.

use crate::resolve::{ResolveArgs, ResolveParams};
use crate::scene::spec::SplatMode;

use super::GpuContext;
use super::chaos_game::GpuChaosGame;

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

/// Bytes of the colour table bound as a uniform (`colors` in `shaders/resolve.wgsl`).
const COLORS_BYTES: u64 = 256 * 16;

/// What a draw pipeline is specialized for: target format, splat mode, lighting (shading or
/// occlusion) on, light read from the light cache, which light terms run, the spatial filter's
/// taps.
type DrawKey = (wgpu::TextureFormat, SplatMode, bool, bool, LightTerms, u32);

/// Which of the solid look's costly terms a light pipeline runs: the shadow map's lookups and
/// the ambient occlusion's samples. Pipeline constants, not uniform branches: a SIMD software
/// rasterizer runs a branch it cannot prove uniform on every lane, so with occlusion at 0 (a
/// dragged camera, a playing timeline) its 16 samples a pixel still ran, most of the resolve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LightTerms {
    shadows: bool,
    occlusion: bool,
    /// The normals' plane fit radius (`ResolveParams::normal_radius_px`): its loops unroll.
    normal_radius_px: u32,
}

impl LightTerms {
    fn constants(self) -> [(&'static str, f64); 3] {
        [
            ("SHADOWS", self.shadows as u32 as f64),
            ("OCCLUSION", self.occlusion as u32 as f64),
            ("NORMAL_RADIUS_PX", self.normal_radius_px as f64),
        ]
    }
}
/// A bind group with the generation of the chaos game's buffers and of the light cache it binds.
type Bound = Option<((u64, u64), wgpu::BindGroup)>;

/// Which rows of the light cache a draw refreshes before it reads the light from the cache
/// (see [`GpuResolve::draw`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightRows {
    /// No cache: every pixel's light is computed in the resolve (exactly what the CPU twin does).
    Inline,
    /// Refresh rows `start..end` of the cache, then resolve with the cached light of all rows.
    Refresh { start: u32, end: u32 },
}

/// The light cache: per pixel the bits of its light factors (Rg32Uint), the accumulation's size.
struct LightCache {
    width: u32,
    height: u32,
    generation: u64,
    view: wgpu::TextureView,
}

pub struct GpuResolve {
    module: wgpu::ShaderModule,
    max_pipeline: wgpu::ComputePipeline,
    /// One draw pipeline per target format, mode and lighting on/off (the shader's pipeline
    /// constants), made on first use, with its bind group and the generation of the chaos
    /// game's buffers it binds.
    draw_pipelines: Vec<(DrawKey, wgpu::RenderPipeline, Bound)>,
    params: wgpu::Buffer,
    stats: wgpu::Buffer,
    /// Generation of the chaos game's buffers and the max-count pass's two bind groups.
    bound: Option<(u64, wgpu::BindGroup, wgpu::BindGroup)>,
    light: Option<LightCache>,
    light_generations: u64,
    /// The light pass's pipeline, its bind group (with the chaos game's generation) and
    /// the terms it runs.
    light_pipeline: Option<(wgpu::RenderPipeline, Bound, LightTerms)>,
}

impl GpuResolve {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = super::shaders::module(device, "resolve");
        let max_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("max_count"),
            layout: None,
            module: &module,
            entry_point: Some("max_count"),
            compilation_options: Default::default(),
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resolve_params"),
            size: std::mem::size_of::<ResolveParams>() as u64,
            // Read as storage: `params` in the shader says why.
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let stats = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resolve_stats"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            module,
            max_pipeline,
            draw_pipelines: Vec::new(),
            params,
            stats,
            bound: None,
            light: None,
            light_generations: 0,
            light_pipeline: None,
        }
    }

    /// The light cache for an accumulation of `width`×`height` (re-created on a size change).
    fn light_cache(&mut self, device: &wgpu::Device, width: u32, height: u32) -> &LightCache {
        if self.light.as_ref().is_none_or(|l| l.width != width || l.height != height) {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("resolve_light"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rg32Uint,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            self.light_generations += 1;
            let view = texture.create_view(&Default::default());
            self.light = Some(LightCache { width, height, generation: self.light_generations, view });
        }
        self.light.as_ref().expect("made above")
    }

    fn draw_pipeline(&mut self, device: &wgpu::Device, key: DrawKey) -> usize {
        if let Some(i) = self.draw_pipelines.iter().position(|(k, _, _)| *k == key) {
            return i;
        }
        let (format, mode, shaded, cached, terms, filter_taps) = key;
        let [shadows, occlusion, normal_radius] = terms.constants();
        let constants = [
            ("RESOLVE_MODE", mode.index() as f64),
            ("SHADED", shaded as u32 as f64),
            ("ENCODE_SRGB", !format.is_srgb() as u32 as f64),
            ("LIGHT_CACHED", cached as u32 as f64),
            shadows,
            occlusion,
            normal_radius,
            ("FILTER_TAPS", filter_taps as f64),
        ];
        let pipeline = fullscreen_pipeline(device, &self.module, "resolve", &constants, format);
        self.draw_pipelines.push((key, pipeline, None));
        self.draw_pipelines.len() - 1
    }

    /// Records the light pass over rows `rows` of the light cache (the params are written).
    fn refresh_light(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        game: &GpuChaosGame,
        rows: (u32, u32),
        terms: LightTerms,
    ) {
        if rows.0 >= rows.1 {
            return;
        }
        if self.light_pipeline.as_ref().is_none_or(|(_, _, t)| *t != terms) {
            let [shadows, occlusion, normal_radius] = terms.constants();
            let constants = [
                ("RESOLVE_MODE", SplatMode::Closest.index() as f64),
                ("SHADED", 1.0),
                shadows,
                occlusion,
                normal_radius,
            ];
            let pipeline =
                fullscreen_pipeline(device, &self.module, "light_pass", &constants, wgpu::TextureFormat::Rg32Uint);
            self.light_pipeline = Some((pipeline, None, terms));
        }
        let Some((pipeline, bound, _)) = &mut self.light_pipeline else { return };
        if bound.as_ref().is_none_or(|b| b.0.0 != game.generation) {
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("resolve_light"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[entry(0, &self.params), entry(1, &game.accum), entry(5, &game.shadow)],
            });
            *bound = Some(((game.generation, 0), group));
        }
        let (Some(light), Some((_, group))) = (&self.light, bound.as_ref()) else { return };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("resolve_light"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &light.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_scissor_rect(0, rows.0, game.width, rows.1 - rows.0);
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Records the resolve of `game`'s accumulation buffer onto `target` (of `format`). With
    /// the solid look (shading or occlusion on), `light` may refresh some rows of the light
    /// cache and read every pixel's light from it: a cache refreshed in full gives the same
    /// image as [`LightRows::Inline`], bit for bit; rows not refreshed keep the light of an
    /// earlier draw (the live view refreshes a band of rows per frame while the view rests).
    #[expect(clippy::too_many_arguments, reason = "the draw's inputs, each a different kind")]
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        game: &GpuChaosGame,
        args: &ResolveArgs,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        light: LightRows,
    ) {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let params = args.params(game.width, game.height, !format.is_srgb());
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let shaded = params.shading > 0.0 || params.occlusion > 0.0;
        let cached = shaded && matches!(light, LightRows::Refresh { .. });
        // The shadow map must be the view's: the chaos game sized it (`GpuChaosGame::encode`).
        let shadows = params.shadows > 0.0 && game.shadow_side == params.shadow_side_px;
        let terms =
            LightTerms { shadows, occlusion: params.occlusion > 0.0, normal_radius_px: params.normal_radius_px };
        let light_generation = self.light_cache(device, game.width, game.height).generation;
        if let LightRows::Refresh { start, end } = light
            && cached
        {
            self.refresh_light(device, encoder, game, (start.min(game.height), end.min(game.height)), terms);
        }
        let pipeline_index = self.draw_pipeline(device, (format, args.mode, shaded, cached, terms, params.filter_taps));
        if self.bound.as_ref().is_none_or(|b| b.0 != game.generation) {
            let max_layout = self.max_pipeline.get_bind_group_layout(0);
            let max_input = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("max_count_in"),
                layout: &max_layout,
                entries: &[entry(0, &self.params), entry(1, &game.accum)],
            });
            let max_output = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("max_count_out"),
                layout: &self.max_pipeline.get_bind_group_layout(1),
                entries: &[entry(0, &self.stats)],
            });
            self.bound = Some((game.generation, max_input, max_output));
        }
        let light_view = &self.light.as_ref().expect("made above").view;
        let (_, pipeline, draw_bound) = &mut self.draw_pipelines[pipeline_index];
        let generations = (game.generation, light_generation);
        if draw_bound.as_ref().is_none_or(|b| b.0 != generations) {
            let draw = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("resolve"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    entry(0, &self.params),
                    entry(1, &game.accum),
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &game.colors,
                            offset: 0,
                            size: wgpu::BufferSize::new(COLORS_BYTES),
                        }),
                    },
                    entry(3, &self.stats),
                    wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(light_view) },
                    entry(5, &game.shadow),
                ],
            });
            *draw_bound = Some((generations, draw));
        }
        let (_, pipeline, Some((_, draw))) = &self.draw_pipelines[pipeline_index] else { return };
        let Some((_, max_input, max_output)) = &self.bound else { return };
        if args.mode == SplatMode::Density {
            encoder.clear_buffer(&self.stats, 0, None);
            let mut pass = encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("max_count"), timestamp_writes: None });
            pass.set_pipeline(&self.max_pipeline);
            pass.set_bind_group(0, max_input, &[]);
            pass.set_bind_group(1, max_output, &[]);
            let groups = (game.width as u64 * game.height as u64).div_ceil(256);
            let x = groups.min(4096) as u32;
            pass.dispatch_workgroups(x, groups.div_ceil(x as u64) as u32, 1);
        }
        let mut pass = resolve_pass(encoder, "resolve", target, args.origin_px, [game.width, game.height]);
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, draw, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// A render pass labelled `label` that clears `target` to black and draws into the viewport of
/// `size_px` at `origin_px` (the accumulation's rectangle): the resolve's, with or without
/// density estimation.
pub(super) fn resolve_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    target: &wgpu::TextureView,
    origin_px: [u32; 2],
    size_px: [u32; 2],
) -> wgpu::RenderPass<'e> {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_viewport(origin_px[0] as f32, origin_px[1] as f32, size_px[0] as f32, size_px[1] as f32, 0.0, 1.0);
    pass
}

/// A full-screen triangle (`fullscreen` in the shader) whose fragment `entry` writes one
/// `format` target, with the pipeline constants `constants`.
pub(super) fn fullscreen_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    fullscreen_pipeline_in(device, None, module, entry, constants, format)
}

/// [`fullscreen_pipeline`] with the pipeline layout `layout` (None: derived from the shader,
/// whose bind groups then fit this pipeline alone).
pub(super) fn fullscreen_pipeline_in(
    device: &wgpu::Device,
    layout: Option<&wgpu::PipelineLayout>,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry),
        layout,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
            targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
        }),
        multiview_mask: None,
        cache: None,
    })
}
