//! `nlifs bench cpu`: chaos-game throughput of the CPU reference on one core, map only and
//! map + splat at 1920×1080, side by side in one run so their ratio is meaningful; and the
//! library side of `bench coverage` and `bench record` (frames per second of a recording, and
//! of a ray-traced one the hierarchy's rebuild alone).

use std::time::Instant;

use glam::Vec3;

use crate::chaos_game::{self, ChunkPlan, CompiledIfs, PlanError, PointBatch, PointSink};
use crate::scene::Scene;
use crate::scene::spec::{RenderSettings, SplatMode};
use crate::shot::{Framing, Shot, ShotError};
use crate::splat::{Framebuffer, SplatView};

/// A sink that only keeps the points alive (so mapping is not optimized away).
struct MapOnly {
    acc: Vec3,
}

impl PointSink for MapOnly {
    fn consume(&mut self, batch: PointBatch<'_>) {
        if let Some(last) = batch.len().checked_sub(1) {
            self.acc += batch.point(last);
        }
    }
}

pub struct CpuBench {
    pub map_points_per_sec: f64,
    pub splat_points_per_sec: Vec<(SplatMode, f64)>,
}

/// Runs `points` chaos-game points of `scene` on the current thread, map only and then map +
/// splat into a `width`×`height` framebuffer in each mode; the best of `repeats` runs each.
/// For profiling one of them alone (e.g. under callgrind), env `NLIFS_BENCH_ONLY` = `map`,
/// `closest`, `average` or `density` skips the others (their rate is reported as 0).
pub fn cpu(scene: &Scene, points: u64, width: u32, height: u32, repeats: usize) -> Result<CpuBench, ShotError> {
    let settings = RenderSettings {
        width,
        height,
        points,
        seed: 1,
        depth_cue: 0.75,
        background: [0.0; 3],
        ..scene.render.clone()
    };
    let shot = Shot::prepare(scene, 0.0, &settings, Framing::Scene, None)?;
    let (compiled, plan) = (&shot.compiled, &shot.plan);
    let time = |sink: &mut dyn FnMut(u32, usize)| -> f64 {
        let mut best = f64::INFINITY;
        for _ in 0..repeats {
            let start = Instant::now();
            for chunk in plan.iter() {
                sink(chunk.index, chunk.steps);
            }
            best = best.min(start.elapsed().as_secs_f64());
        }
        points as f64 / best
    };
    let only = std::env::var("NLIFS_BENCH_ONLY").ok();
    let wanted = |name: &str| only.as_deref().is_none_or(|o| o == name);
    let mut map_only = MapOnly { acc: Vec3::ZERO };
    let map_points_per_sec =
        if !wanted("map") { 0.0 } else { time(&mut |c, n| chaos_game::run_chunk(compiled, 1, 0, c, n, &mut map_only)) };
    std::hint::black_box(map_only.acc);
    let mut splat_points_per_sec = Vec::new();
    for mode in SplatMode::ALL {
        if !wanted(mode.name()) {
            splat_points_per_sec.push((mode, 0.0));
            continue;
        }
        let mut fb = Framebuffer::new(SplatView { mode, ..shot.view }, compiled.colors.clone());
        let rate = time(&mut |c, n| chaos_game::run_chunk(compiled, 1, 0, c, n, &mut fb));
        std::hint::black_box(fb.covered_pixels());
        splat_points_per_sec.push((mode, rate));
    }
    Ok(CpuBench { map_points_per_sec, splat_points_per_sec })
}

/// Coverage of the attractor by a fixed budget of points under each way of choosing
/// probabilities: the fraction of the reference image's lit pixels (from `reference_points`
/// points under both the contractivity and the adaptive rule) that `budget` points light.
pub fn coverage(
    scene: &Scene,
    budget: u64,
    reference_points: u64,
    size: u32,
) -> Result<Vec<(&'static str, f64)>, PlanError> {
    use crate::model::ProbabilityMode;
    let base = scene.at(0.0);
    let variants: Vec<(&'static str, crate::model::Ifs)> = vec![
        ("uniform", {
            let mut ifs = base.clone();
            ifs.probability_mode = ProbabilityMode::Explicit;
            ifs.functions.iter_mut().for_each(|f| f.weight = Some(1.0));
            ifs
        }),
        ("contractivity", {
            let mut ifs = base.clone();
            ifs.probability_mode = ProbabilityMode::Contractivity;
            ifs
        }),
        ("adaptive", {
            let mut ifs = base.clone();
            ifs.probability_mode = ProbabilityMode::Adaptive;
            ifs
        }),
    ];
    let compiled: Vec<CompiledIfs> =
        variants.iter().map(|(_, ifs)| CompiledIfs::new(ifs).expect("functions")).collect();
    let bounds = chaos_game::attractor_bounds(&compiled[1], 1);
    let camera = scene.camera_for(bounds);
    let view = SplatView::new(&camera, size, size, bounds, SplatMode::Closest, 0.0, [0.0; 3]);
    let (budget, reference_points) = (ChunkPlan::new(budget)?, ChunkPlan::new(reference_points)?);
    let run = |c: &CompiledIfs, plan: &ChunkPlan, seed: u32| -> Framebuffer {
        chaos_game::run_parallel(
            c,
            seed,
            0,
            plan,
            || Framebuffer::new(view, c.colors.clone()),
            Framebuffer::merge,
            || {},
        )
    };
    let reference = run(&compiled[1], &reference_points, 101).merge(run(&compiled[2], &reference_points, 202));
    let lit: Vec<bool> = reference.closest.iter().map(|&k| k != crate::splat::EMPTY).collect();
    let total = lit.iter().filter(|&&l| l).count().max(1);
    Ok(variants
        .iter()
        .zip(&compiled)
        .map(|((name, _), c)| {
            let fb = run(c, &budget, 7);
            let hit = fb.closest.iter().zip(&lit).filter(|(k, l)| **l && **k != crate::splat::EMPTY).count();
            (*name, hit as f64 / total as f64)
        })
        .collect())
}

// ---------------------------------------------------------------------------------------------
// `nlifs bench record`: frames per second of a recording, per chaos-game backend.

/// What one backend's recording took.
pub struct RecordBench {
    /// `cpu`, or `gpu` with the adapter's name.
    pub backend: String,
    pub frames: u32,
    /// Wall seconds and this process's CPU seconds (all threads, a software rasterizer's too).
    pub secs: f64,
    pub cpu_secs: f64,
}

/// Records frames `0..frames` of `scene` with `settings` into `dir` (PNG frames, as `nlifs
/// record` writes them), the chaos game on `gpu` when given, after one untimed frame (the GPU
/// compiles its pipelines on first use).
pub fn record(
    scene: &Scene,
    settings: crate::record::RecordSettings,
    frames: u32,
    gpu: Option<crate::gpu::GpuContext>,
    dir: &std::path::Path,
) -> Result<RecordBench, crate::record::RecordError> {
    let mut rec = crate::record::Recorder::new(scene, settings)?;
    if let Some(ctx) = gpu {
        rec = rec.on_gpu(ctx)?;
    }
    let backend = rec.gpu_adapter().map_or_else(|| "cpu".to_string(), |a| format!("gpu ({a})"));
    let frames = 0..frames.clamp(1, rec.frame_count());
    rec.frame(0)?;
    let cpu0 = crate::gpu::bench::process_cpu_secs();
    let start = Instant::now();
    crate::record::record(&rec, dir, frames.clone(), false, &mut |_, _| {})?;
    Ok(RecordBench {
        backend,
        frames: frames.len() as u32,
        secs: start.elapsed().as_secs_f64(),
        cpu_secs: crate::gpu::bench::process_cpu_secs() - cpu0,
    })
}

/// The hierarchy rebuilds of a ray-traced recording.
pub struct RebuildBench {
    pub frames: u32,
    /// Wall seconds of all the rebuilds (every temporal sample of every frame), and this
    /// process's CPU seconds in them (all threads).
    pub secs: f64,
    pub cpu_secs: f64,
    /// Leaves and nodes of the last frame's W^n(A).
    pub leaf_count: usize,
    pub node_count: usize,
}

/// Builds W^n(A) for every temporal sample of frames `0..frames` of `scene` recorded with
/// `settings` and ray-traced with `options`, as the recording builds them before tracing,
/// timed alone: what the rebuild takes of [`record`]'s frames.
pub fn raytrace_rebuilds(
    scene: &Scene,
    settings: crate::record::RecordSettings,
    options: &crate::record::TraceOptions,
    frames: u32,
) -> Result<RebuildBench, crate::record::RecordError> {
    let trace = options.settings(settings.width, settings.height, scene.render.seed);
    let rec = crate::record::Recorder::new(scene, settings)?;
    let frames = 0..frames.clamp(1, rec.frame_count());
    let (mut secs, mut cpu_secs, mut leaf_count, mut node_count) = (0.0, 0.0, 0, 0);
    for frame in frames.clone() {
        for sample in rec.samples(frame) {
            let ifs = scene.at(sample.t_secs);
            let (cpu0, start) = (crate::cpu_time::cpu_secs().0, Instant::now());
            let (hierarchy, _) = crate::raytrace::build(scene, &ifs, sample.t_secs, Some(sample.camera), &trace)?;
            secs += start.elapsed().as_secs_f64();
            cpu_secs += crate::cpu_time::cpu_secs().0 - cpu0;
            (leaf_count, node_count) = (hierarchy.leaf_count, hierarchy.nodes.len());
        }
    }
    Ok(RebuildBench { frames: frames.len() as u32, secs, cpu_secs, leaf_count, node_count })
}
