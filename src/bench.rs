//! `nlifs bench cpu`: chaos-game throughput of the CPU path on one core, map only and map +
//! splat at 1920×1080, beside a plain batched implementation of the same chaos game and closest
//! splat (`bench/cpu_reference.rs`), all in one run so that their ratios are meaningful; the
//! coverage of an attractor by a budget of points; and `nlifs bench record`'s frames per second
//! (of a ray-traced recording also the hierarchy's rebuild alone).

use std::time::Instant;

use glam::Vec3;

use crate::chaos_game::{self, ChunkPlan, CompiledIfs, PlanError, PointBatch, PointSink};
use crate::scene::Scene;
use crate::scene::spec::{RenderSettings, SplatMode};
use crate::shot::{Framing, Shot, ShotError};
use crate::splat::{Framebuffer, SplatView};

mod cpu_reference;

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

/// A throughput in points per second: by wall-clock time and by the thread's CPU time (what a
/// shared machine's comparisons use: wall time also counts the time other programs run).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rate {
    pub wall: f64,
    pub cpu: f64,
}

impl Rate {
    /// The better of two rates, each measure on its own.
    fn best(self, other: Rate) -> Rate {
        Rate { wall: self.wall.max(other.wall), cpu: self.cpu.max(other.cpu) }
    }
}

/// The rows of `nlifs bench cpu`, each the best of its runs.
pub struct CpuBench {
    /// nlifs's chaos game, map only.
    pub map: Rate,
    /// Map + splat into the image in each mode (the image only: no shadow map).
    pub splat: Vec<(SplatMode, Rate)>,
    /// Map + closest splat with the shadow map the scene's look splats beside the image (None:
    /// the look casts no shadows).
    pub closest_with_shadow: Option<Rate>,
    /// The batched reference (`bench/cpu_reference.rs`): map only, and map + closest splat.
    pub reference_map: Rate,
    pub reference_closest: Rate,
    /// nlifs's map + the reference's closest splat.
    pub reference_splat: Rate,
}

/// The calling thread's CPU seconds (from /proc/thread-self/schedstat, in nanoseconds), if the
/// system tells.
fn thread_cpu_secs() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(text.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
}

/// Runs `points` chaos-game points of `scene` on the current thread in every row of
/// [`CpuBench`]: nlifs's map only, map + splat into a `width`×`height` framebuffer in each mode,
/// closest with the look's shadow map, and the batched reference's map, map + closest and its
/// closest splat behind nlifs's map. The
/// rows take turns, one run each per round, for `rounds` rounds (so that a busy spell of a
/// shared machine spreads over them all), each run into a fresh framebuffer; each row keeps its
/// best. For profiling one row alone (e.g. under callgrind), env `NLIFS_BENCH_ONLY` = `map`,
/// `closest`, `average`, `density`, `shadow` or `reference` skips the others (their rates are
/// reported as 0).
pub fn cpu(scene: &Scene, points: u64, width: u32, height: u32, rounds: usize) -> Result<CpuBench, ShotError> {
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
    let only = std::env::var("NLIFS_BENCH_ONLY").ok();
    let wanted = |name: &str| only.as_deref().is_none_or(|o| o == name);
    // One timed run of every chunk of the plan.
    let run = |chunk: &mut dyn FnMut(u32, usize)| -> Rate {
        let (start, cpu0) = (Instant::now(), thread_cpu_secs());
        for c in plan.iter() {
            chunk(c.index, c.steps);
        }
        let wall = start.elapsed().as_secs_f64();
        let cpu = match (cpu0, thread_cpu_secs()) {
            (Some(a), Some(b)) if b > a => b - a,
            _ => wall,
        };
        Rate { wall: points as f64 / wall, cpu: points as f64 / cpu }
    };
    let image_view = SplatView { shadow: None, ..shot.view };
    let shadow_view = shot.view.shadow.is_some().then_some(shot.view);
    let mut bench = CpuBench {
        map: Rate::default(),
        splat: SplatMode::ALL.iter().map(|&m| (m, Rate::default())).collect(),
        closest_with_shadow: shadow_view.map(|_| Rate::default()),
        reference_map: Rate::default(),
        reference_closest: Rate::default(),
        reference_splat: Rate::default(),
    };
    for _ in 0..rounds.max(1) {
        if wanted("map") {
            let mut sink = MapOnly { acc: Vec3::ZERO };
            bench.map = bench.map.best(run(&mut |c, n| chaos_game::run_chunk(compiled, 1, 0, c, n, &mut sink)));
            std::hint::black_box(sink.acc);
        }
        for (mode, rate) in &mut bench.splat {
            if wanted(mode.name()) {
                let mut fb = Framebuffer::new(SplatView { mode: *mode, ..image_view }, compiled.colors.clone());
                // A zeroed allocation's pages are mapped on first touch: touch them before the
                // clock starts.
                fb.accum.fill([0; 4]);
                *rate = rate.best(run(&mut |c, n| chaos_game::run_chunk(compiled, 1, 0, c, n, &mut fb)));
                std::hint::black_box(fb.covered_pixels());
            }
        }
        if let (Some(view), Some(rate)) = (shadow_view, bench.closest_with_shadow.as_mut())
            && wanted("shadow")
        {
            let mut fb = Framebuffer::new(view, compiled.colors.clone());
            *rate = rate.best(run(&mut |c, n| chaos_game::run_chunk(compiled, 1, 0, c, n, &mut fb)));
            std::hint::black_box(fb.covered_pixels());
        }
        if wanted("reference") {
            let mut sink = cpu_reference::Discard::default();
            bench.reference_map =
                bench.reference_map.best(run(&mut |c, n| cpu_reference::run_chunk(compiled, 1, 0, c, n, &mut sink)));
            std::hint::black_box(sink.acc);
            let mut keys = cpu_reference::ReferenceKeys::new(SplatView { mode: SplatMode::Closest, ..image_view });
            bench.reference_closest = bench
                .reference_closest
                .best(run(&mut |c, n| cpu_reference::run_chunk(compiled, 1, 0, c, n, &mut keys)));
            std::hint::black_box(keys.image().len());
            let mut keys = cpu_reference::ReferenceKeys::new(SplatView { mode: SplatMode::Closest, ..image_view });
            bench.reference_splat =
                bench.reference_splat.best(run(&mut |c, n| chaos_game::run_chunk(compiled, 1, 0, c, n, &mut keys)));
            std::hint::black_box(keys.image().len());
        }
    }
    Ok(bench)
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
