//! `nlifs bench gpu`: throughput of the live view (chaos-game steps with their splat, per
//! second, and frames per second including the resolve at 1280×720), the chaos game alone in
//! each splat mode, and how many frames after a scene edit the image is back within sampling
//! noise of converged.

use crate::platform::Instant;
use std::fmt;

use glam::DVec3;

use crate::chaos_game::{CompiledIfs, PlanError};
use crate::model::builder::Step;
use crate::scene::Scene;
use crate::scene::spec::{FunctionDef, SplatMode};
use crate::shot::{Framing, Shot, ShotError};

use super::progressive::{Progressive, ProgressiveSettings};
use super::{GpuContext, GpuError};

pub struct BenchReport {
    pub adapter: String,
    pub points: u32,
    pub steps: u32,
    pub frames: u32,
    pub secs: f64,
    /// Milliseconds per frame of each stage alone, [wall, CPU time of this process] (on a
    /// software rasterizer the CPU time is the work, the wall time depends on the load): the
    /// chaos game with its splat, the resolve onto the target, and a clear of the accumulation
    /// (done only after a change).
    pub chaos_ms: [f64; 2],
    pub resolve_ms: [f64; 2],
    pub clear_ms: [f64; 2],
    /// The chaos game with its splat alone in each splat mode, ms per frame [wall, process CPU].
    pub per_mode_ms: Vec<(SplatMode, [f64; 2])>,
    /// Frames until the image after an edit is within noise; None if not within the window.
    pub frames_to_converge: Option<u32>,
    /// (frame, L1 distance after the edit, L1 distance of a fresh run of as many splats).
    pub convergence: Vec<(u32, f64, f64)>,
}

impl fmt::Display for BenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let steps = self.points as f64 * self.steps as f64 * self.frames as f64;
        writeln!(f, "adapter: {}", self.adapter)?;
        writeln!(
            f,
            "{} points × {} steps per frame at 1280×720, {} frames in {:.3} s",
            self.points, self.steps, self.frames, self.secs
        )?;
        writeln!(
            f,
            "  {:.1} fps, {:.1} M points/s (map + splat + resolve)",
            self.frames as f64 / self.secs,
            steps / self.secs / 1e6
        )?;
        writeln!(f, "  per stage alone, ms per frame (wall / process CPU):")?;
        writeln!(
            f,
            "    chaos game + splat {:.1} / {:.1}, resolve {:.1} / {:.1}, clear {:.1} / {:.1}",
            self.chaos_ms[0],
            self.chaos_ms[1],
            self.resolve_ms[0],
            self.resolve_ms[1],
            self.clear_ms[0],
            self.clear_ms[1]
        )?;
        writeln!(f, "  chaos game + splat per splat mode (M points/s by wall time / by process CPU time):")?;
        for (mode, [wall, cpu]) in &self.per_mode_ms {
            let per_frame = self.points as f64 * self.steps as f64 / 1e6;
            // A process that spent no CPU time it could measure: no rate, rather than one
            // divided by almost nothing.
            let by_cpu =
                if *cpu > 0.0 { format!("{:8.1}", per_frame / (cpu / 1e3)) } else { "   (no CPU time)".into() };
            writeln!(f, "    {:<8} {:8.1} / {by_cpu}", mode.name(), per_frame / (wall / 1e3).max(1e-9))?;
        }
        writeln!(
            f,
            "after an edit (coarse-grid L1 distance to the converged image: edited vs fresh run of equal splats):"
        )?;
        for (k, d_edit, d_fresh) in &self.convergence {
            writeln!(f, "  frame {k:>2}: {d_edit:.4} vs {d_fresh:.4}")?;
        }
        match self.frames_to_converge {
            Some(k) => write!(f, "within noise of converged after {k} frame(s)"),
            None => write!(f, "not within noise in {} frames", self.convergence.len()),
        }
    }
}

fn submit_frame(
    ctx: &GpuContext,
    live: &mut Progressive,
    target: Option<(&wgpu::TextureView, wgpu::TextureFormat)>,
) -> u64 {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let n = live.advance(ctx, &mut encoder);
    if let Some((view, format)) = target {
        live.draw(ctx, &mut encoder, view, format, [0, 0]);
    }
    ctx.queue.submit([encoder.finish()]);
    n
}

/// User + system CPU seconds of this process (all threads, lavapipe's workers included):
/// [`crate::cpu_time::cpu_secs`].
pub fn process_cpu_secs() -> f64 {
    crate::cpu_time::cpu_secs().0
}

fn wait(ctx: &GpuContext) {
    let _ = ctx.device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None });
}

/// The scene with its first grid or builder function shrunk by 5% about the domain's centre:
/// a typical interactive edit.
fn edited(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let center = 0.5 * (s.domain.min() + s.domain.max());
    for f in &mut s.functions {
        match &mut f.def {
            FunctionDef::Grid { points } => {
                for p in points.iter_mut() {
                    *p = center + 0.95 * (*p - center);
                }
                break;
            }
            FunctionDef::Builder { builder, .. } => {
                builder.steps.push(Step::Scale { by: DVec3::splat(0.95), center });
                break;
            }
            _ => {}
        }
    }
    s
}

/// Normalized counts on a coarse grid of the density accumulation.
fn coarse_density(accum: &[u32], width: u32, height: u32, cells: (u32, u32)) -> Vec<f64> {
    let mut out = vec![0.0; (cells.0 * cells.1) as usize];
    for y in 0..height {
        for x in 0..width {
            let c = accum[4 * (y * width + x) as usize + 3] as f64;
            out[((y * cells.1 / height) * cells.0 + x * cells.0 / width) as usize] += c;
        }
    }
    let total: f64 = out.iter().sum::<f64>().max(1.0);
    out.iter().map(|c| c / total).collect()
}

fn l1(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum()
}

pub fn run(scene: &Scene, points: u32, steps: u32, frames: u32) -> Result<BenchReport, GpuError> {
    let ctx = GpuContext::headless()?;
    let shot = Shot::prepare(scene, 0.0, &scene.render, Framing::Scene, None).map_err(|e| match e {
        ShotError::NoFunctions { .. } => GpuError::NoFunctions,
        ShotError::Points(PlanError::TooManyPoints { points }) => GpuError::TooManyPoints(points),
        ShotError::Lens(e) => GpuError::Lens(e),
    })?;
    let (ifs, bounds, camera) = (&shot.compiled, shot.bounds, shot.camera);
    let (width, height) = (1280, 720);
    let settings = ProgressiveSettings {
        point_count: points,
        steps_per_frame: steps,
        max_splats: u64::MAX,
        ..ProgressiveSettings::default()
    };

    // Throughput: frames into an offscreen target of the window's size.
    let mut live = Progressive::new(&ctx, settings, width, height)?;
    live.set_ifs(&ctx, ifs, bounds, true);
    live.set_camera(&camera);
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let texture =
        super::readback::offscreen_texture(&ctx, "bench", width, height, format, wgpu::TextureUsages::empty());
    let view = texture.create_view(&Default::default());
    for _ in 0..3 {
        submit_frame(&ctx, &mut live, Some((&view, format)));
    }
    wait(&ctx);
    let start = Instant::now();
    for _ in 0..frames {
        submit_frame(&ctx, &mut live, Some((&view, format)));
        // One frame in flight at a time, as a window with vsync off would run.
        wait(&ctx);
    }
    let secs = start.elapsed().as_secs_f64();

    // Each stage alone, to see where the time goes.
    let stage_frames = (frames / 2).max(5);
    let time_stage = |live: &mut Progressive, stage: &dyn Fn(&mut Progressive, &mut wgpu::CommandEncoder)| {
        wait(&ctx);
        let cpu0 = process_cpu_secs();
        let start = Instant::now();
        for _ in 0..stage_frames {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            stage(live, &mut encoder);
            ctx.queue.submit([encoder.finish()]);
            wait(&ctx);
        }
        let per_frame = |secs: f64| 1e3 * secs / stage_frames as f64;
        [per_frame(start.elapsed().as_secs_f64()), per_frame(process_cpu_secs() - cpu0)]
    };
    let chaos_ms = time_stage(&mut live, &|live, encoder| {
        live.advance(&ctx, encoder);
    });
    let resolve_ms = time_stage(&mut live, &|live, encoder| live.draw(&ctx, encoder, &view, format, [0, 0]));
    let clear_ms = time_stage(&mut live, &|live, encoder| live.encode_clear(&ctx, encoder));
    let mut per_mode_ms = Vec::new();
    for mode in [SplatMode::Closest, SplatMode::Average, SplatMode::Density] {
        live.set_settings(&ctx, ProgressiveSettings { mode, ..settings })?;
        // The first frame after the change clears and may build the mode's pipeline.
        submit_frame(&ctx, &mut live, None);
        let ms = time_stage(&mut live, &|live, encoder| {
            live.advance(&ctx, encoder);
        });
        per_mode_ms.push((mode, ms));
    }

    // Convergence after an edit, in density mode on a smaller view (readbacks every frame).
    let (w, h) = (320, 180);
    let cells = (32, 18);
    let density = ProgressiveSettings { mode: SplatMode::Density, ..settings };
    let edited_scene = edited(scene);
    let edited_ifs = CompiledIfs::new(&edited_scene.at(0.0)).ok_or(GpuError::NoFunctions)?;
    // Both runs use the bounds of the original so that the views agree.
    let reference = {
        let mut r = Progressive::new(&ctx, ProgressiveSettings { steps_per_frame: 16, seed: 99, ..density }, w, h)?;
        r.set_ifs(&ctx, &edited_ifs, bounds, true);
        r.set_camera(&camera);
        for _ in 0..8 {
            submit_frame(&ctx, &mut r, None);
        }
        coarse_density(&r.read_accum(&ctx)?, w, h, cells)
    };
    let mut live = Progressive::new(&ctx, density, w, h)?;
    live.set_ifs(&ctx, ifs, bounds, true);
    live.set_camera(&camera);
    for _ in 0..4 {
        submit_frame(&ctx, &mut live, None);
    }
    live.set_ifs(&ctx, &edited_ifs, bounds, false);
    let mut fresh = Progressive::new(&ctx, ProgressiveSettings { seed: 7, ..density }, w, h)?;
    fresh.set_ifs(&ctx, &edited_ifs, bounds, true);
    fresh.set_camera(&camera);
    let mut convergence = Vec::new();
    let mut frames_to_converge = None;
    for k in 1..=12 {
        submit_frame(&ctx, &mut live, None);
        submit_frame(&ctx, &mut fresh, None);
        let d_edit = l1(&coarse_density(&live.read_accum(&ctx)?, w, h, cells), &reference);
        let d_fresh = l1(&coarse_density(&fresh.read_accum(&ctx)?, w, h, cells), &reference);
        convergence.push((k, d_edit, d_fresh));
        // Within noise: no farther from converged than a run that started fully settled,
        // allowing 20% for the noise of the distance itself.
        if frames_to_converge.is_none() && d_edit <= 1.2 * d_fresh {
            frames_to_converge = Some(k);
        }
    }
    Ok(BenchReport {
        adapter: ctx.describe(),
        points,
        steps,
        frames,
        secs,
        chaos_ms,
        resolve_ms,
        clear_ms,
        per_mode_ms,
        frames_to_converge,
        convergence,
    })
}
