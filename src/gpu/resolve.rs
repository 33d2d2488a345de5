//! Host side of `shaders/resolve.wgsl`: the max-count reduction (density mode) and the
//! full-screen draw that turns the accumulation buffer into colours on any render target, the
//! window's surface or an offscreen texture alike (`draw(&TextureView)`). Its parameters
//! ([`ResolveArgs`], [`ResolveParams`]) and its CPU twin live in `src/resolve.rs`; keep the
//! three in sync.

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
/// occlusion) on.
type DrawKey = (wgpu::TextureFormat, SplatMode, bool);
/// A bind group with the generation of the chaos game's buffers it binds.
type Bound = Option<(u64, wgpu::BindGroup)>;

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
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let stats = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resolve_stats"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { module, max_pipeline, draw_pipelines: Vec::new(), params, stats, bound: None }
    }

    fn draw_pipeline(&mut self, device: &wgpu::Device, key: DrawKey) -> usize {
        if let Some(i) = self.draw_pipelines.iter().position(|(k, _, _)| *k == key) {
            return i;
        }
        let (format, mode, shaded) = key;
        let constants = [
            ("RESOLVE_MODE", mode.index() as f64),
            ("SHADED", shaded as u32 as f64),
            ("ENCODE_SRGB", !format.is_srgb() as u32 as f64),
        ];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("resolve"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &self.module,
                entry_point: Some("fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &self.module,
                entry_point: Some("resolve"),
                compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
                targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        });
        self.draw_pipelines.push((key, pipeline, None));
        self.draw_pipelines.len() - 1
    }

    /// Records the resolve of `game`'s accumulation buffer onto `target` (of `format`).
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        game: &GpuChaosGame,
        args: &ResolveArgs,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let params = args.params(game.width, game.height, !format.is_srgb());
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let pipeline_index =
            self.draw_pipeline(device, (format, args.mode, params.shading > 0.0 || params.occlusion > 0.0));
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
        let (_, pipeline, draw_bound) = &mut self.draw_pipelines[pipeline_index];
        if draw_bound.as_ref().is_none_or(|b| b.0 != game.generation) {
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
                ],
            });
            *draw_bound = Some((game.generation, draw));
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
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("resolve"),
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
        pass.set_viewport(
            args.origin_px[0] as f32,
            args.origin_px[1] as f32,
            game.width as f32,
            game.height as f32,
            0.0,
            1.0,
        );
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, draw, &[]);
        pass.draw(0..3, 0..1);
    }
}
