//! A prepared [`Shot`] run on the GPU chaos game in bounded submissions, its accumulation read
//! back as the CPU's [`Framebuffer`], so that the CPU resolve and every image output (PNG, 16-bit,
//! EXR, alpha) serve GPU renders and GPU-recorded frames alike.
//!
//! The shot's points are split by a [`BatchPlan`]: `threads` persistent GPU points, each advanced
//! through its transient (not splatted) and then `steps_per_thread` splatted steps, in batches
//! of a bounded number of steps, one queue submission each, so that no submission runs long
//! enough to trip a driver watchdog.
//! Batch `b` of a shot draws from the GPU streams `(batch_seed(seed, b), shot.stream, thread)`:
//! the shot's stream is the chaos game's `frame` argument as on the CPU, and the accumulation
//! (a minimum of keys, sums of integers) does not depend on the order of the splats, so the
//! framebuffer is a pure function of the shot and the plan on one adapter.
//!
//! In the average and density modes the GPU's u32 colour sums could wrap past 2^24 splats on
//! one pixel, so these modes accumulate in passes of at most [`PASS_SPLATS`] splats, each read
//! back and added up on the host with the CPU merge's saturating sums.
//!
//! Two ways of sizing the batches:
//! - fixed ([`BatchSizing::Fixed`], the recorder): [`FIXED_BATCH_SPLATS`] point steps a batch,
//!   whatever the machine's speed, so a frame has the same bytes on every run on one adapter.
//!   2^23 point steps take under 10 ms on a GPU that runs 10^9 a second, far from a watchdog's
//!   2 s; on lavapipe with two cores (about 10^7 a CPU second, docs/performance.md) about half
//!   a second, on a software rasterizer that no watchdog watches;
//! - timed ([`BatchSizing::Timed`], `render --backend gpu`): the first batch is small, its
//!   measured speed sizes the next to about [`TARGET_BATCH_SECS`], and every batch re-measures;
//!   the image then depends on the batch sizes (it agrees with the CPU's in distribution, as
//!   every GPU render does, not bit for bit).

use crate::platform::Instant;

use crate::rng::pcg_hash;
use crate::scene::spec::SplatMode;
use crate::shot::Shot;
use crate::splat::Framebuffer;

use super::chaos_game::{FrameArgs, GpuChaosGame};
use super::{GpuContext, GpuError};

/// Most persistent GPU points of one shot.
pub const MAX_BATCH_THREADS: u64 = 1 << 20;
/// Splats every thread makes at least, when the shot has that many points: the transient each
/// thread runs first is paid once per thread.
pub const MIN_STEPS_PER_THREAD: u64 = 16;
/// Point steps (splatted or transient) of one batch with fixed sizing.
pub const FIXED_BATCH_SPLATS: u64 = 1 << 23;
/// Point steps of the first, measuring batch with timed sizing.
pub const FIRST_TIMED_BATCH_SPLATS: u64 = 1 << 20;
/// Most splats a pass of the average and density modes accumulates on the GPU before it is
/// added up on the host: each splat adds at most 255 to a pixel's u32 colour sums, so 2^24
/// splats cannot wrap one.
pub const PASS_SPLATS: u64 = 1 << 24;
/// What a timed batch aims at: well under the 2 s after which Windows resets a GPU, and under
/// the few hundred milliseconds a desktop stays usable for.
pub const TARGET_BATCH_SECS: f64 = 0.2;

/// How a shot's points are split over GPU threads and steps (see the module comment).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BatchPlan {
    /// Persistent GPU points.
    pub threads: u32,
    /// Steps every point splats (after its transient).
    pub steps_per_thread: u64,
}

impl BatchPlan {
    /// The plan for `points` points: up to [`MAX_BATCH_THREADS`] threads (enough to fill a
    /// GPU), each splatting at least [`MIN_STEPS_PER_THREAD`] steps where the points allow.
    pub fn new(points: u64) -> Self {
        let threads = (points / MIN_STEPS_PER_THREAD).clamp(1, MAX_BATCH_THREADS);
        Self { threads: threads as u32, steps_per_thread: points.max(1).div_ceil(threads) }
    }

    /// Points splatted: `points` rounded up to whole steps of every thread.
    pub fn splats(&self) -> u64 {
        self.threads as u64 * self.steps_per_thread
    }

    /// Steps of a fixed-size batch (of every thread: [`FIXED_BATCH_SPLATS`] point steps in all,
    /// at least one step).
    pub fn fixed_batch_steps(&self) -> u64 {
        (FIXED_BATCH_SPLATS / self.threads as u64).max(1)
    }
}

/// How batches are sized.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatchSizing {
    /// [`BatchPlan::fixed_batch_steps`]: reproducible bytes.
    Fixed,
    /// From the measured speed of the previous batch: [`TARGET_BATCH_SECS`] a batch.
    Timed,
}

/// The seed of batch `batch` of a shot seeded with `seed`: the seed itself for the first, a
/// hash of both for the others (each batch draws fresh random numbers for the kept points).
pub fn batch_seed(seed: u32, batch: u32) -> u32 {
    if batch == 0 { seed } else { pcg_hash(seed ^ pcg_hash(batch)) }
}

/// What a GPU shot did, for reports and benchmarks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BatchStats {
    pub splats: u64,
    pub batches: u32,
    /// Wall seconds of the longest batch (submission to completion).
    pub longest_batch_secs: f64,
    /// Wall seconds of all batches.
    pub secs: f64,
}

/// The GPU chaos game of shots, its buffers kept from shot to shot (a recording's frames).
pub struct GpuSplatter {
    game: Option<GpuChaosGame>,
    pub sizing: BatchSizing,
}

impl GpuSplatter {
    pub fn new(sizing: BatchSizing) -> Self {
        Self { game: None, sizing }
    }

    /// Runs `shot`'s chaos game on `ctx` and reads its accumulation back as a framebuffer.
    pub fn splat(&mut self, ctx: &GpuContext, shot: &Shot) -> Result<(Framebuffer, BatchStats), GpuError> {
        let plan = BatchPlan::new(shot.settings.points);
        let (width, height) = (shot.view.width, shot.view.height);
        check_fits(ctx, width, height, plan.threads)?;
        let game = self.game.get_or_insert_with(|| GpuChaosGame::new(&ctx.device, plan.threads, width, height));
        game.resize(&ctx.device, width, height);
        game.set_point_count(&ctx.device, plan.threads);
        game.set_ifs(&ctx.device, &ctx.queue, &shot.compiled);
        // Every thread runs its transient (not splatted), then its splatted steps; batches cut
        // this sequence anywhere, the transient included, so no batch outgrows its size.
        let transient = shot.compiled.transient as u64;
        let total = transient + plan.steps_per_thread;
        // Sums (average and density modes) are u32 on the GPU: a pass of at most PASS_SPLATS
        // splats cannot wrap one, and passes add up on the host, saturating as the CPU's merge.
        let pass_steps = match shot.view.mode {
            SplatMode::Closest => u64::MAX,
            SplatMode::Average | SplatMode::Density => (PASS_SPLATS / plan.threads as u64).max(1),
        };
        let mut pass_end = transient.saturating_add(pass_steps);
        let mut passes: Option<Framebuffer> = None;
        let mut clear = true;
        let mut stats = BatchStats::default();
        let mut done = 0u64;
        let mut steps = match self.sizing {
            BatchSizing::Fixed => plan.fixed_batch_steps(),
            BatchSizing::Timed => (FIRST_TIMED_BATCH_SPLATS / plan.threads as u64).max(1),
        };
        let start = Instant::now();
        while done < total {
            steps = steps.clamp(1, total - done).min(pass_end - done).min(u32::MAX as u64);
            let first = stats.batches == 0;
            let args = FrameArgs {
                view: &shot.view,
                seed: batch_seed(shot.settings.seed, stats.batches),
                frame: shot.stream,
                steps: steps as u32,
                skip_steps: transient.saturating_sub(done).min(steps) as u32,
                restart: first,
                clear,
            };
            clear = false;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            // Encoding may build the pipeline (first use): not part of the submission's time.
            game.encode(&ctx.device, &ctx.queue, &mut encoder, &args);
            let batch_start = Instant::now();
            let submission = ctx.queue.submit([encoder.finish()]);
            ctx.device
                .poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: None })
                .map_err(|e| GpuError::Readback(e.to_string()))?;
            let secs = batch_start.elapsed().as_secs_f64();
            stats.longest_batch_secs = stats.longest_batch_secs.max(secs);
            stats.batches += 1;
            done += steps;
            if done == pass_end && done < total {
                let pass = read_framebuffer(ctx, game, shot)?;
                passes = Some(match passes {
                    None => pass,
                    Some(sum) => sum.merge(pass),
                });
                pass_end = pass_end.saturating_add(pass_steps);
                clear = true;
            }
            if self.sizing == BatchSizing::Timed {
                // Steps per second of every thread, so that the next batch takes the target.
                let rate = steps as f64 / secs.max(1e-6);
                steps = (rate * TARGET_BATCH_SECS) as u64;
            }
        }
        stats.secs = start.elapsed().as_secs_f64();
        stats.splats = plan.splats();
        let last = read_framebuffer(ctx, game, shot)?;
        let mut framebuffer = match passes {
            None => last,
            Some(sum) => sum.merge(last),
        };
        framebuffer.points_drawn = stats.splats;
        Ok((framebuffer, stats))
    }
}

/// The accumulation of `game` as the CPU framebuffer of `shot` (the same layouts: closest keys
/// in the first width × height words, else four words a pixel).
fn read_framebuffer(ctx: &GpuContext, game: &GpuChaosGame, shot: &Shot) -> Result<Framebuffer, GpuError> {
    let pixels = shot.view.width as u64 * shot.view.height as u64;
    let (closest, accum) = match shot.view.mode {
        SplatMode::Closest => {
            let bytes = super::readback::read_buffer_prefix(ctx, &game.accum, 4 * pixels)?;
            (bytemuck::pod_collect_to_vec(&bytes), Vec::new())
        }
        SplatMode::Average | SplatMode::Density => {
            let bytes = super::readback::read_buffer_prefix(ctx, &game.accum, 16 * pixels)?;
            (Vec::new(), bytemuck::pod_collect_to_vec(&bytes))
        }
    };
    let shadow = super::shadow::read_shadow_map(ctx, &game.shadow, &shot.view)?;
    Ok(Framebuffer { view: shot.view, closest, accum, colors: shot.compiled.colors.clone(), shadow, points_drawn: 0 })
}

/// Whether `ctx`'s adapter is a software rasterizer.
pub fn is_software(ctx: &GpuContext) -> bool {
    ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu
}

/// Checks that a `width`×`height` accumulation (16 bytes a pixel) and `threads` points (16
/// bytes each) fit the largest buffer the device binds.
pub fn check_fits(ctx: &GpuContext, width: u32, height: u32, threads: u32) -> Result<(), GpuError> {
    let limits = ctx.device.limits();
    let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    let bytes = 16 * width as u64 * height as u64;
    if bytes > limit {
        return Err(GpuError::FramebufferTooLarge { width, height, bytes, limit, adapter: ctx.describe() });
    }
    if threads as u64 > ctx.max_points() {
        return Err(GpuError::TooManyPoints(threads as u64));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plans_cover_the_points_with_little_overshoot() {
        for points in [1u64, 15, 16, 17, 20_000, 1 << 20, 16 << 20, (16 << 20) + 1, 1_000_000_007, 1 << 40] {
            let plan = BatchPlan::new(points);
            assert!(plan.splats() >= points, "{points}: {plan:?}");
            // Rounded up by less than one step of every thread.
            assert!(plan.splats() - points < plan.threads as u64, "{points}: {plan:?}");
            assert!(plan.threads as u64 <= MAX_BATCH_THREADS);
            if points >= MIN_STEPS_PER_THREAD * MAX_BATCH_THREADS {
                assert_eq!(plan.threads as u64, MAX_BATCH_THREADS);
            } else if points >= MIN_STEPS_PER_THREAD {
                assert!(plan.steps_per_thread >= MIN_STEPS_PER_THREAD, "{points}: {plan:?}");
            }
            assert!(plan.fixed_batch_steps() * plan.threads as u64 <= FIXED_BATCH_SPLATS.max(plan.threads as u64));
        }
    }

    #[test]
    fn batch_seeds_differ() {
        let seeds: std::collections::BTreeSet<u32> = (0..1000).map(|b| batch_seed(7, b)).collect();
        assert_eq!(seeds.len(), 1000);
        assert_eq!(batch_seed(7, 0), 7);
    }
}
