//! Host side of `shaders/density_estimation.wgsl`: flam3's adaptive density estimation on the
//! GPU, the twin of `src/resolve/density_estimation.rs` (keep the three in sync). It reads an
//! accumulation buffer in the chaos game's layout, spreads it into a float buffer of estimated
//! sums (two compute passes: each pixel's kernel and each tile's reach, then the gather), and
//! draws that buffer with the resolve's density branch and tone map ([`GpuDensityEstimation::draw`]) or reads it back
//! as the CPU twin's [`Estimated`] ([`GpuDensityEstimation::read`], `render --backend gpu` and
//! the tests). The kernel tables are the CPU twin's ([`KernelTables`]), uploaded when the
//! setting changes. With a spatial filter, a third pass filters the estimate once into a buffer
//! the draws read, until the estimate or what the filtered values depend on changes: the
//! taps' gather costs more than the rest of a draw on a software rasterizer. The toned picture
//! itself is drawn once per estimate and resolve parameters into a texture, which each draw
//! copies into the target ([`PictureDraw`]): in the live view most draws show an estimate made
//! frames before, and on a software rasterizer the resolve costs several times the copy.

use crate::resolve::density_estimation::{Estimated, KernelTables};
use crate::resolve::{ResolveArgs, ResolveParams};
use crate::scene::spec::DensityEstimation;

use super::picture::{PictureDraw, PictureTexture};
use super::resolve::fullscreen_pipeline;
use super::{GpuContext, GpuError};

/// Mirrors `struct DensityEstimationParams` in `shaders/density_estimation.wgsl`: keep in sync.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DensityEstimationParams {
    pub width: u32,
    pub height: u32,
    pub reach_max: u32,
    /// Index of the last kernel step.
    pub last_step: u32,
}
const _: () = assert!(std::mem::size_of::<DensityEstimationParams>() == 16);

/// The shader's group of its own bindings (group 0 is `resolve.wgsl`'s).
const GROUP: u32 = 1;
/// Side of the tiles whose largest reach the gather consults (`TILE` in the shader).
const TILE: u32 = 8;

fn storage(device: &wgpu::Device, label: &str, bytes: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

/// The uploaded kernel tables of one setting.
struct Tables {
    de: DensityEstimation,
    reach_max: u32,
    last_step: u32,
    first_count: wgpu::Buffer,
    kernels: wgpu::Buffer,
    weights: wgpu::Buffer,
}

/// The per-pixel buffers of one accumulation size.
struct Pixels {
    width: u32,
    height: u32,
    kernel_of: wgpu::Buffer,
    estimated: wgpu::Buffer,
    estimated_max: wgpu::Buffer,
    tile_reach: wgpu::Buffer,
    /// The spatial filter's average colour and linear density per pixel.
    filtered: wgpu::Buffer,
}

/// What the filtered buffer was made of: the estimate's generation and the parameters its
/// values depend on (the size, the absolute scale, the filter).
#[derive(Clone, Copy, Debug, PartialEq)]
struct FilteredOf {
    estimate: u64,
    size: [u32; 2],
    count_scale: f32,
    taps: u32,
    weights: crate::resolve::filter::Weights,
}

impl FilteredOf {
    fn new(estimate: u64, p: &ResolveParams) -> Self {
        Self {
            estimate,
            size: [p.width, p.height],
            count_scale: p.count_scale,
            taps: p.filter_taps,
            weights: p.filter_weights,
        }
    }
}

pub struct GpuDensityEstimation {
    module: wgpu::ShaderModule,
    index_pipeline: wgpu::ComputePipeline,
    estimate_pipeline: wgpu::ComputePipeline,
    /// The draw pipeline per target format, with the spatial filter or without, made on first use.
    draw_pipelines: Vec<((wgpu::TextureFormat, bool), wgpu::RenderPipeline)>,
    /// The spatial filter's pass per taps, made on first use.
    filter_pipelines: Vec<(u32, wgpu::ComputePipeline)>,
    /// Estimates made or uploaded so far (the filtered buffer's is [`FilteredOf::estimate`]).
    estimates: u64,
    filtered_of: Option<FilteredOf>,
    /// The toned picture of the last estimate, what it was drawn with (the estimate, the
    /// resolve's parameters at the origin), and its drawing into targets.
    picture: Option<PictureTexture>,
    picture_of: Option<(u64, ResolveParams)>,
    picture_draw: PictureDraw,
    params: wgpu::Buffer,
    resolve_params: wgpu::Buffer,
    tables: Option<Tables>,
    pixels: Option<Pixels>,
}

impl GpuDensityEstimation {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = super::shaders::module(device, "density_estimation");
        let compute = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let (index_pipeline, estimate_pipeline) = (compute("kernel_index"), compute("estimate"));
        // Parameters read as storage, not uniforms: `params` in shaders/resolve.wgsl says why.
        let parameters = |label: &str, size: usize| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Self {
            params: parameters("density_estimation_params", std::mem::size_of::<DensityEstimationParams>()),
            resolve_params: parameters("density_estimation_resolve_params", std::mem::size_of::<ResolveParams>()),
            module,
            index_pipeline,
            estimate_pipeline,
            draw_pipelines: Vec::new(),
            filter_pipelines: Vec::new(),
            estimates: 0,
            filtered_of: None,
            picture: None,
            picture_of: None,
            picture_draw: PictureDraw::new(device),
            tables: None,
            pixels: None,
        }
    }

    /// Records density estimation `de` of the `width`×`height` accumulation in `accum` (the
    /// chaos game's layout: r, g, b sums and the count per pixel, STORAGE usage) into the
    /// estimated buffer that [`Self::draw`] and [`Self::read`] use.
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        accum: &wgpu::Buffer,
        width: u32,
        height: u32,
        de: &DensityEstimation,
    ) {
        let device = &ctx.device;
        if self.tables.as_ref().is_none_or(|t| t.de != *de) {
            let t = KernelTables::of(de);
            let upload = |label: &str, bytes: &[u8]| {
                let buffer = storage(device, label, bytes.len() as u64, wgpu::BufferUsages::empty());
                ctx.queue.write_buffer(&buffer, 0, bytes);
                buffer
            };
            self.tables = Some(Tables {
                de: *de,
                reach_max: t.reach_max,
                last_step: t.kernels.len() as u32 - 1,
                first_count: upload("de_first_count", bytemuck::cast_slice(&t.first_count)),
                kernels: upload("de_kernels", bytemuck::cast_slice(&t.kernels)),
                weights: upload("de_weights", bytemuck::cast_slice(&t.weights)),
            });
        }
        self.size_pixels(device, width, height);
        let (Some(t), Some(p)) = (&self.tables, &self.pixels) else { return };
        let params = DensityEstimationParams { width, height, reach_max: t.reach_max, last_step: t.last_step };
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        encoder.clear_buffer(&p.estimated_max, 0, None);
        encoder.clear_buffer(&p.tile_reach, 0, None);
        let group = |pipeline: &wgpu::ComputePipeline, index: u32, entries: &[wgpu::BindGroupEntry]| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("density_estimation"),
                layout: &pipeline.get_bind_group_layout(index),
                entries,
            })
        };
        let index_accum = group(&self.index_pipeline, 0, &[entry(1, accum)]);
        let index_own = group(
            &self.index_pipeline,
            GROUP,
            &[
                entry(8, &self.params),
                entry(9, &t.first_count),
                entry(10, &t.kernels),
                entry(12, &p.kernel_of),
                entry(17, &p.tile_reach),
            ],
        );
        let estimate_accum = group(&self.estimate_pipeline, 0, &[entry(1, accum)]);
        let estimate_own = group(
            &self.estimate_pipeline,
            GROUP,
            &[
                entry(8, &self.params),
                entry(10, &t.kernels),
                entry(11, &t.weights),
                entry(12, &p.kernel_of),
                entry(13, &p.estimated),
                entry(14, &p.estimated_max),
                entry(17, &p.tile_reach),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("density_estimation"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.index_pipeline);
        pass.set_bind_group(0, &index_accum, &[]);
        pass.set_bind_group(GROUP, &index_own, &[]);
        let groups = (width as u64 * height as u64).div_ceil(256).max(1);
        let x = groups.min(4096) as u32;
        pass.dispatch_workgroups(x, groups.div_ceil(x as u64) as u32, 1);
        pass.set_pipeline(&self.estimate_pipeline);
        pass.set_bind_group(0, &estimate_accum, &[]);
        pass.set_bind_group(GROUP, &estimate_own, &[]);
        pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
        self.estimates += 1;
    }

    /// Makes the per-pixel buffers for a `width`×`height` accumulation (kept while the size is).
    fn size_pixels(&mut self, device: &wgpu::Device, width: u32, height: u32) {
        if self.pixels.as_ref().is_none_or(|p| p.width != width || p.height != height) {
            let pixels = width as u64 * height as u64;
            self.pixels = Some(Pixels {
                width,
                height,
                kernel_of: storage(device, "de_kernel_of", 4 * pixels, wgpu::BufferUsages::empty()),
                estimated: storage(device, "de_estimated", 16 * pixels, wgpu::BufferUsages::COPY_SRC),
                estimated_max: storage(device, "de_estimated_max", 16, wgpu::BufferUsages::COPY_SRC),
                tile_reach: storage(
                    device,
                    "de_tile_reach",
                    4 * width.div_ceil(TILE) as u64 * height.div_ceil(TILE) as u64,
                    wgpu::BufferUsages::empty(),
                ),
                filtered: storage(device, "de_filtered", 16 * pixels, wgpu::BufferUsages::empty()),
            });
            self.filtered_of = None;
        }
    }

    /// Takes `e` (the CPU twin's estimate) as the last estimate, for [`Self::draw`]: the live
    /// view's CPU route has its accumulation on the CPU, where the twin's scatter is much
    /// cheaper than the gather on a software rasterizer.
    pub fn upload(&mut self, ctx: &GpuContext, e: &Estimated) {
        self.size_pixels(&ctx.device, e.width, e.height);
        let Some(p) = &self.pixels else { return };
        ctx.queue.write_buffer(&p.estimated, 0, bytemuck::cast_slice(&e.sums));
        ctx.queue.write_buffer(&p.estimated_max, 0, bytemuck::bytes_of(&[e.max_count.to_bits(), 0, 0, 0]));
        self.estimates += 1;
    }

    /// Records the resolve of the last estimate (density mode, with `args`' background and
    /// tone) onto `target` of `format`, the accumulation's pixel (0, 0) at `args.origin_px`, the
    /// rest of the target cleared to black: what `GpuResolve::draw` does with the raw counts.
    /// The toned picture is resolved into its texture where the estimate or the parameters
    /// changed since it last was (with a spatial filter, after the filter's pass where the
    /// estimate or what the filtered values depend on changed), then copied into the target.
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        args: &ResolveArgs,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        let Some(p) = &self.pixels else { return };
        let size_px = [p.width, p.height];
        // The picture holds what the resolve writes into a target of the same kind: sRGB bytes
        // encoded by the shader for a plain target, by the texture for an sRGB one.
        let srgb = format.is_srgb();
        let params = ResolveArgs { origin_px: [0, 0], ..*args }.params(p.width, p.height, !srgb);
        if self.picture_draw.fit(ctx, &mut self.picture, size_px, srgb, wgpu::TextureUsages::empty()) {
            self.picture_of = None;
        }
        if self.picture_of != Some((self.estimates, params)) {
            self.encode_picture(ctx, encoder, &params);
            self.picture_of = Some((self.estimates, params));
        }
        if let Some(picture) = &self.picture {
            self.picture_draw.draw(ctx, encoder, picture, target, format, args.origin_px);
        }
    }

    /// Records the resolve of the last estimate with `params` into the picture.
    fn encode_picture(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, params: &ResolveParams) {
        ctx.queue.write_buffer(&self.resolve_params, 0, bytemuck::bytes_of(params));
        let filter = params.filter_taps > 0;
        if filter && self.filtered_of != Some(FilteredOf::new(self.estimates, params)) {
            self.encode_filter(ctx, encoder, params);
        }
        let (Some(p), Some(picture)) = (&self.pixels, &self.picture) else { return };
        let key = (picture.format(), filter);
        let index = match self.draw_pipelines.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                let constants = [("ENCODE_SRGB", params.encode_srgb as f64)];
                let entry = if filter { "resolve_filtered_estimate" } else { "resolve_estimated" };
                let pipeline = fullscreen_pipeline(&ctx.device, &self.module, entry, &constants, picture.format());
                self.draw_pipelines.push((key, pipeline));
                self.draw_pipelines.len() - 1
            }
        };
        let pipeline = &self.draw_pipelines[index].1;
        let group = |index: u32, entries: &[wgpu::BindGroupEntry]| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("resolve_estimated"),
                layout: &pipeline.get_bind_group_layout(index),
                entries,
            })
        };
        let params_group = group(0, &[entry(0, &self.resolve_params)]);
        let own = if filter {
            group(GROUP, &[entry(19, &p.filtered)])
        } else {
            group(GROUP, &[entry(15, &p.estimated), entry(16, &p.estimated_max)])
        };
        let mut pass =
            super::resolve::resolve_pass(encoder, "resolve_estimated", &picture.view, [0, 0], picture.size_px);
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &params_group, &[]);
        pass.set_bind_group(GROUP, &own, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Records the spatial filter's pass over the last estimate with `params` (written to the
    /// resolve's parameters buffer) into the filtered buffer.
    fn encode_filter(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, params: &ResolveParams) {
        let Some(p) = &self.pixels else { return };
        let taps = params.filter_taps;
        let index = match self.filter_pipelines.iter().position(|(t, _)| *t == taps) {
            Some(i) => i,
            None => {
                let constants = [("FILTER_TAPS", f64::from(taps))];
                let pipeline = ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("filter_estimate"),
                    layout: None,
                    module: &self.module,
                    entry_point: Some("filter_estimate"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                });
                self.filter_pipelines.push((taps, pipeline));
                self.filter_pipelines.len() - 1
            }
        };
        let pipeline = &self.filter_pipelines[index].1;
        let group = |index: u32, entries: &[wgpu::BindGroupEntry]| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("filter_estimate"),
                layout: &pipeline.get_bind_group_layout(index),
                entries,
            })
        };
        let params_group = group(0, &[entry(0, &self.resolve_params)]);
        let own = group(GROUP, &[entry(15, &p.estimated), entry(16, &p.estimated_max), entry(18, &p.filtered)]);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("filter_estimate"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &params_group, &[]);
        pass.set_bind_group(GROUP, &own, &[]);
        pass.dispatch_workgroups(p.width.div_ceil(8), p.height.div_ceil(8), 1);
        drop(pass);
        self.filtered_of = Some(FilteredOf::new(self.estimates, params));
    }

    /// Reads the last estimate back as the CPU twin's [`Estimated`] (waits for the GPU).
    pub fn read(&self, ctx: &GpuContext) -> Result<Estimated, GpuError> {
        let Some(p) = &self.pixels else { return Err(GpuError::Readback("no estimate was made".into())) };
        let pixels = p.width as u64 * p.height as u64;
        let sums = bytemuck::pod_collect_to_vec(&super::readback::read_buffer_prefix(ctx, &p.estimated, 16 * pixels)?);
        let max_bits: Vec<u32> = bytemuck::pod_collect_to_vec(&super::readback::read_buffer(ctx, &p.estimated_max)?);
        Ok(Estimated { width: p.width, height: p.height, sums, max_count: f32::from_bits(max_bits[0]) })
    }

    /// Density estimation `de` of the accumulation `accum` (`width`×`height`, as
    /// [`crate::splat::Framebuffer::accum`]) on the GPU, read back: `render --backend gpu`'s
    /// filter and the tests' view of the GPU twin.
    pub fn estimate(
        &mut self,
        ctx: &GpuContext,
        accum: &[[u32; 4]],
        width: u32,
        height: u32,
        de: &DensityEstimation,
    ) -> Result<Estimated, GpuError> {
        super::batch::check_fits(ctx, width, height, 1)?;
        let buffer = storage(&ctx.device, "de_accum", 16 * accum.len() as u64, wgpu::BufferUsages::empty());
        ctx.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(accum));
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.encode(ctx, &mut encoder, &buffer, width, height, de);
        ctx.queue.submit([encoder.finish()]);
        self.read(ctx)
    }
}
