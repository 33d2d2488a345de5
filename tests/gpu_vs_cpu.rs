//! The GPU chaos game against its CPU twin. Runs on any adapter (lavapipe in CI); without one it
//! skips loudly, unless NLIFS_REQUIRE_GPU=1, in which case it fails.
//!
//! 1. One step from the start point: the GPU's random streams, function selection and map agree
//!    with the CPU's for every thread (f32 maps agree to rounding).
//! 2. Normalized densities of the same scene on a coarse grid agree within a tolerance derived
//!    from the sample counts.
//! 3. The live view's CPU route uploads exactly the CPU framebuffer of its frames and shows the
//!    same densities as the GPU route.

mod common;

use common::{
    Density, assert_densities_agree, assert_gpu_density_matches_cpu, coarse_density, gpu, raw_density_settings,
};
use glam::Vec3;
use nlifs::chaos_game::{self, ChunkChains, CompiledIfs, ORBITS_PER_CHUNK, continue_chunk, run_chunk};
use nlifs::gpu::GpuContext;
use nlifs::gpu::chaos_game::{FrameArgs, GpuChaosGame};
use nlifs::gpu::progressive::ProgressiveSettings;
use nlifs::gpu::readback::read_buffer;
use nlifs::live::cpu_source::frame_layout;
use nlifs::live::{ChaosBackend, LiveSettings, LiveView};
use nlifs::resolve::{ResolveStyle, resolve_image};
use nlifs::rng::Pcg32;
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::{Framebuffer, SplatView};

fn scene(name: &str, adaptive: bool) -> Scene {
    let path = common::scene_path(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    if adaptive {
        text = text.replacen("\n[grid]", "\nprobabilities = \"adaptive\"\n\n[grid]", 1);
    }
    Scene::parse(&text, &path.display().to_string()).unwrap()
}

#[test]
fn first_step_matches_cpu_bit_for_bit_streams() {
    let Some(ctx) = gpu() else { return };
    // Both chaos-game programs: IFS tables in uniform buffers (these scenes fit) and in
    // storage buffers (the fallback for large IFS); pipelines specialized for the IFS's shape
    // (shared grid, one selection cell) and the generic one.
    let cases = [
        ("plant2", false, false, false),
        ("twisting", true, false, false),
        ("plant2", false, true, false),
        ("twisting", true, true, false),
        ("plant2", false, false, true),
        ("twisting", true, true, true),
    ];
    for (name, adaptive, storage, generic) in cases {
        let scene = scene(name, adaptive);
        let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
        let bounds = chaos_game::attractor_bounds(&compiled, 1);
        let camera = scene.camera_for(bounds);
        let view = SplatView::new(&camera, 64, 48, bounds, SplatMode::Closest, 0.5, [0.0; 3]);
        let n = 4096u32;
        let (seed, frame) = (9u32, 5u32);
        let mut game = GpuChaosGame::new(&ctx.device, n, 64, 48);
        game.force_storage_tables = storage;
        game.force_generic = generic;
        game.set_ifs(&ctx.device, &ctx.queue, &compiled);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let args = FrameArgs { view: &view, seed, frame, steps: 1, skip_steps: 0, restart: true, clear: true };
        game.encode(&ctx.device, &ctx.queue, &mut encoder, &args);
        ctx.queue.submit([encoder.finish()]);
        let gpu_points: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read_buffer(&ctx, &game.points).unwrap());
        let (lo, hi) = (compiled.domain_lo, compiled.domain_hi);
        // Relative rounding allowance: the map is a handful of f32 multiply-adds that a GPU
        // compiler may fuse; 1e-5 of the domain size is ~100 ulps.
        let tol = 1e-5 * (hi - lo).length();
        for thread in 0..n {
            let mut rng = Pcg32::for_stream(seed, frame, thread);
            let t =
                Vec3::new(rng.next_f32(), rng.next_f32(), if compiled.dimension == 3 { rng.next_f32() } else { 0.0 });
            let start = lo + t * (hi - lo);
            let fi = compiled.selection.select(compiled.selection.cell_of(start), rng.next_u32());
            let p = compiled.map(fi, start);
            let g = gpu_points[thread as usize];
            let name = format!("{name} (storage tables: {storage}, generic pipeline: {generic})");
            assert_eq!(
                g[3] as usize, fi,
                "{name}: thread {thread} chose function {} on the GPU, {fi} on the CPU",
                g[3]
            );
            let d = (Vec3::new(g[0], g[1], g[2]) - p).length();
            assert!(d <= tol, "{name}: thread {thread}: GPU {g:?} vs CPU {p} (distance {d} > {tol})");
        }
    }
}

#[test]
fn densities_match_cpu() {
    let Some(ctx) = gpu() else { return };
    let (width, height) = (160u32, 120u32);
    let cells = (16usize, 12usize);
    // Steps per orbit on both sides. Samples of one orbit are correlated, at worst perfectly:
    // the variance of a cell's frequency is then at most k·p(1−p)/N for orbits of k steps
    // (Cauchy–Schwarz bound on the covariances), which the tolerance uses.
    let k = 4u32;
    for (name, adaptive) in [("plant2", false), ("tapering", false), ("fantasy", true)] {
        let scene = scene(name, adaptive);
        let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
        let bounds = chaos_game::attractor_bounds(&compiled, 1);
        let camera = scene.camera_for(bounds);
        let bg = [0.0; 3];

        // GPU: 2^18 independent orbits of k steps after the transient.
        let gpu_orbits = 1u32 << 18;
        let settings = raw_density_settings(gpu_orbits, k);
        let mut live = LiveView::new(&ctx, settings, width, height).unwrap();
        live.set_ifs(&ctx, &compiled, bounds, true);
        live.set_camera(&camera);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        live.advance(&ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let accum = live.read_accum(&ctx).unwrap();
        let gpu_counts: Vec<u32> = accum.chunks(4).map(|a| a[3]).collect();

        // CPU: the same number of orbits of k steps, in chunks of ORBITS_PER_CHUNK; within 6
        // standard deviations of the difference of two frequencies with variance ≤ k p (1 − p) / N
        // each.
        let view = SplatView::new(&camera, width, height, bounds, SplatMode::Density, 0.0, bg);
        let found = assert_gpu_density_matches_cpu(name, "GPU", &gpu_counts, &compiled, view, (gpu_orbits, k), cells);
        eprintln!(
            "{name}: {} GPU / {} CPU samples, worst |Δ|/tolerance {:.3}",
            found.gpu_samples, found.cpu_samples, found.worst
        );
    }
}

/// Settings of the CPU-route tests.
fn route_settings(backend: ChaosBackend, mode: SplatMode, points: u32, steps: u32) -> LiveSettings {
    let draw = ProgressiveSettings {
        point_count: points,
        steps_per_frame: steps,
        seed: 5,
        mode,
        depth_cue: 0.5,
        background: [0.02, 0.03, 0.05],
        max_splats: u64::MAX,
        ..ProgressiveSettings::default()
    };
    LiveSettings { draw, chaos_backend: backend, render_density: None }
}

/// The CPU route (`chaos_backend = cpu`) uploads exactly the framebuffer that the CPU chaos
/// game of its frames gives (persistent chains: chunks 0..n started from the streams (seed, 0)
/// and continued every frame, recomputed here into one framebuffer), frame after frame
/// (progressive), in the GPU's accumulation layout; the resolved image shows the attractor.
/// Closest and density modes.
#[test]
fn cpu_route_uploads_the_cpu_framebuffer() {
    let Some(ctx) = gpu() else { return };
    let (width, height) = (160u32, 120u32);
    let scene = scene("plant2", false);
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let camera = scene.camera_for(bounds);
    for mode in [SplatMode::Closest, SplatMode::Density] {
        let settings = route_settings(ChaosBackend::Cpu, mode, 1 << 14, 3);
        let mut live = LiveView::new(&ctx, settings, width, height).unwrap();
        assert!(live.route().cpu);
        live.set_ifs(&ctx, &compiled, bounds, true);
        live.set_camera(&camera);
        let view =
            SplatView::new(&camera, width, height, bounds, mode, settings.draw.depth_cue, settings.draw.background);
        let mut expected = Framebuffer::new(view, compiled.colors.clone());
        let points = settings.draw.point_count as u64 * settings.draw.steps_per_frame as u64;
        let (chunks, steps) = frame_layout(points, rayon::current_num_threads());
        let mut chains: Vec<ChunkChains> =
            (0..chunks).map(|c| ChunkChains::start(&compiled, settings.draw.seed, 0, c)).collect();
        let mut previous_covered = 0;
        for frame in 0..3u32 {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let splats = live.advance(&ctx, &mut encoder);
            ctx.queue.submit([encoder.finish()]);
            assert_eq!(splats, chunks as u64 * ORBITS_PER_CHUNK as u64 * steps as u64);
            assert!(splats >= points);
            let skip = if frame == 0 { compiled.transient } else { 0 };
            for chains in &mut chains {
                continue_chunk(&compiled, chains, skip, steps, &mut expected);
            }
            let uploaded = live.read_accum(&ctx).unwrap();
            let cpu = live.cpu_accum().expect("the CPU route runs");
            let words: &[u32] = match mode {
                SplatMode::Closest => &expected.closest,
                _ => bytemuck::cast_slice(&expected.accum),
            };
            assert_eq!(cpu, words, "{mode:?} frame {frame}: merged CPU accumulation");
            assert_eq!(&uploaded[..words.len()], words, "{mode:?} frame {frame}: uploaded accumulation");
            // Progressive: every frame adds points.
            let covered = expected.covered_pixels();
            assert!(covered >= previous_covered);
            previous_covered = covered;
        }
        assert!(previous_covered > 500, "{mode:?}: {previous_covered} pixels covered");
        // The resolve (unchanged) draws the uploaded accumulation: as many pixels differ from
        // the background as the CPU framebuffer covers, give or take rounding to 8 bits.
        let image = live.snapshot(&ctx).unwrap();
        let bg = resolve_image(&expected, &camera, &ResolveStyle::default()).get_pixel(0, 0).0;
        let drawn = image.pixels().filter(|p| (0..3).any(|k| (p.0[k] as i32 - bg[k] as i32).abs() > 2)).count();
        assert!(
            drawn as f64 > 0.9 * previous_covered as f64,
            "{mode:?}: {drawn} pixels drawn, {previous_covered} covered"
        );
        assert!(drawn <= previous_covered, "{mode:?}: {drawn} pixels drawn, {previous_covered} covered");
    }
}

/// The CPU route and the GPU route show the same attractor: normalized densities on a coarse
/// grid agree within a tolerance derived from the sample counts (as `densities_match_cpu`,
/// with the CPU route's longer orbits in its bound).
#[test]
fn cpu_route_densities_match_gpu_route() {
    let Some(ctx) = gpu() else { return };
    let (width, height) = (160u32, 120u32);
    let cells = (16usize, 12usize);
    let scene = scene("plant2", false);
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let camera = scene.camera_for(bounds);
    let counts = |backend: ChaosBackend, frames: u32| -> (Vec<u32>, u64) {
        let mut settings = route_settings(backend, SplatMode::Density, 1 << 18, 4);
        settings.draw.depth_cue = 0.0;
        let mut live = LiveView::new(&ctx, settings, width, height).unwrap();
        assert_eq!(live.route().cpu, backend == ChaosBackend::Cpu);
        live.set_ifs(&ctx, &compiled, bounds, true);
        live.set_camera(&camera);
        for _ in 0..frames {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            live.advance(&ctx, &mut encoder);
            ctx.queue.submit([encoder.finish()]);
        }
        let accum = live.read_accum(&ctx).unwrap();
        (accum.chunks(4).take((width * height) as usize).map(|a| a[3]).collect(), live.splats_since_clear())
    };
    // GPU route: one frame, 2^18 orbits of 4 steps after the transient.
    let (gpu_counts, _) = counts(ChaosBackend::Gpu, 1);
    // CPU route: 8 frames of 2^20 points from persistent chains, each advancing `cpu_k` steps
    // over the 8 frames.
    let (cpu_counts, splats) = counts(ChaosBackend::Cpu, 8);
    let cpu_k = 8 * frame_layout(1 << 20, rayon::current_num_threads()).1;
    let gpu_k = 4.0;
    let n_gpu: f64 = gpu_counts.iter().map(|&c| c as f64).sum();
    let n_cpu: f64 = cpu_counts.iter().map(|&c| c as f64).sum();
    assert!(n_cpu > 0.5 * splats as f64, "{n_cpu} of {splats} CPU-route points on screen");
    let pg = coarse_density(&gpu_counts, width as usize, height as usize, cells);
    let pc = coarse_density(&cpu_counts, width as usize, height as usize, cells);
    let worst = assert_densities_agree(
        "CPU route vs GPU route",
        &Density { label: "GPU route", density: &pg, samples: n_gpu, steps_per_orbit: gpu_k },
        &Density { label: "CPU route", density: &pc, samples: n_cpu, steps_per_orbit: cpu_k as f64 },
        cells,
    );
    eprintln!("CPU route vs GPU route: {n_gpu} / {n_cpu} samples, worst |Δ|/tolerance {worst:.3}");
}

// ---------------------------------------------------------------------------------------------
// The GPU recorder (`record --backend gpu`) against the CPU recorder.

use nlifs::record::{self, RecordSettings, Recorder};

/// twist-anim (3D, an orbiting camera) drawn in density mode without depth cue, so that a
/// pixel's count is its density.
fn density_scene() -> Scene {
    let mut scene = common::load_scene("twist-anim");
    scene.render.mode = SplatMode::Density;
    scene.render.depth_cue = 0.0;
    scene
}

fn record_settings(scene: &Scene) -> RecordSettings {
    RecordSettings {
        fps: 3.0,
        width: 160,
        height: 120,
        points_per_frame: Some(400_000),
        motion_blur_samples: 2,
        shutter: 1.0,
        ..RecordSettings::for_scene(scene)
    }
}

/// Every temporal sample of a GPU-recorded frame is the CPU recorder's same sample (same time,
/// camera, stream and view), and its densities agree within 6σ on a coarse grid with the CPU
/// chaos game of that sample run in short orbits (k = 4 steps, as in `densities_match_cpu`, so
/// that the bound is tight: the CPU recorder's own orbits of ~10^3 steps would loosen it).
#[test]
fn gpu_recorder_densities_match_cpu_recorder() {
    let Some(ctx) = gpu() else { return };
    let scene = density_scene();
    let settings = RecordSettings { points_per_frame: Some(2_000_000), ..record_settings(&scene) };
    let points = settings.points_per_frame.unwrap().div_ceil(2);
    let cpu = Recorder::new(&scene, settings.clone()).unwrap();
    let gpu = Recorder::new(&scene, settings.clone()).unwrap().on_gpu(ctx).unwrap();
    let cells = (16usize, 12usize);
    let (w, h) = (settings.width as usize, settings.height as usize);
    let k_gpu = nlifs::gpu::batch::BatchPlan::new(points).steps_per_thread as f64;
    let k_cpu = 4u32;
    for frame in [1u32, 5] {
        let cpu_samples = cpu.samples(frame);
        let gpu_samples = gpu.sample_framebuffers(frame).unwrap();
        assert_eq!(cpu_samples.len(), 2);
        assert_eq!(gpu_samples.len(), 2);
        for (s, (a, (fb, shot))) in cpu_samples.iter().zip(&gpu_samples).enumerate() {
            assert_eq!((a.t_secs, a.camera, a.stream, a.bounds), (shot.t_secs, shot.camera, shot.stream, shot.bounds));
            // The CPU twin of this sample: 2^20 points in orbits of k_cpu steps.
            let mut reference = Framebuffer::new(shot.view, shot.compiled.colors.clone());
            for c in 0..(1u32 << 20) / (ORBITS_PER_CHUNK as u32 * k_cpu) {
                run_chunk(&shot.compiled, 77, shot.stream, c, k_cpu as usize, &mut reference);
            }
            let counts = |fb: &Framebuffer| -> Vec<u32> { fb.accum.iter().map(|a| a[3]).collect() };
            let (cg, cc) = (counts(fb), counts(&reference));
            let (ng, nc) = (cg.iter().map(|&c| c as f64).sum::<f64>(), cc.iter().map(|&c| c as f64).sum::<f64>());
            // Most points land on screen (the camera frames the timeline's bounds).
            assert!(ng > 0.5 * points as f64, "{ng} of {points} GPU points on screen");
            let worst = assert_densities_agree(
                &format!("recorder frame {frame} sample {s}"),
                &Density {
                    label: "GPU recorder",
                    density: &coarse_density(&cg, w, h, cells),
                    samples: ng,
                    steps_per_orbit: k_gpu,
                },
                &Density {
                    label: "CPU",
                    density: &coarse_density(&cc, w, h, cells),
                    samples: nc,
                    steps_per_orbit: k_cpu as f64,
                },
                cells,
            );
            eprintln!("recorder frame {frame} sample {s}: {ng} GPU / {nc} CPU samples, worst |Δ|/tolerance {worst:.3}");
        }
    }
}

/// Two GPU recordings of the same frames (separate recorders and GPU contexts, as two runs
/// make them), and the same frames recorded in chunks out of order, have the same bytes, in
/// closest and density modes; a resumed GPU run keeps them and a CPU run over them redoes them
/// (their fingerprints say GPU).
#[test]
fn gpu_recordings_are_reproducible_byte_for_byte() {
    if gpu().is_none() {
        return;
    }
    for (label, scene) in [("closest", common::load_scene("twist-anim")), ("density", density_scene())] {
        let settings = RecordSettings { points_per_frame: Some(300_000), ..record_settings(&scene) };
        let dirs = [common::temp_dir(&format!("gpu-rec-a-{label}")), common::temp_dir(&format!("gpu-rec-b-{label}"))];
        for dir in &dirs {
            let rec = Recorder::new(&scene, settings.clone()).unwrap().on_gpu(gpu().unwrap()).unwrap();
            let report = record::record(&rec, dir, 0..3, false, &mut |_, _| {}).unwrap();
            assert_eq!(report.rendered, vec![0, 1, 2]);
            assert!(report.empty.is_empty(), "{label}: empty frames {:?}", report.empty);
        }
        // The same frames in chunks (frame 2 first), as a job array's tasks make them.
        let chunks = common::temp_dir(&format!("gpu-rec-chunks-{label}"));
        for range in [2..3, 0..2] {
            let rec = Recorder::new(&scene, settings.clone()).unwrap().on_gpu(gpu().unwrap()).unwrap();
            record::record(&rec, &chunks, range, false, &mut |_, _| {}).unwrap();
        }
        for k in 0..3 {
            let a = std::fs::read(record::frame_path(&dirs[0], k)).unwrap();
            let b = std::fs::read(record::frame_path(&dirs[1], k)).unwrap();
            let c = std::fs::read(record::frame_path(&chunks, k)).unwrap();
            assert!(a == b, "{label}: frame {k} differs between two GPU recordings");
            assert!(a == c, "{label}: frame {k} differs between one GPU run and chunks");
        }
        let _ = std::fs::remove_dir_all(&chunks);
        let rec = Recorder::new(&scene, settings.clone()).unwrap().on_gpu(gpu().unwrap()).unwrap();
        assert_eq!(record::frames_to_render(&rec, &dirs[0], 0..3, true), Vec::<u32>::new(), "{label}: GPU resume");
        let cpu = Recorder::new(&scene, settings.clone()).unwrap();
        assert_eq!(record::frames_to_render(&cpu, &dirs[0], 0..3, true), vec![0, 1, 2], "{label}: CPU over GPU frames");
        for dir in &dirs {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// `nlifs record --backend gpu` writes frames and says the adapter; `--backend auto` on a
/// software adapter takes the CPU and says so, and then writes the CPU recorder's bytes.
#[test]
fn record_cli_backends() {
    let Some(ctx) = gpu() else { return };
    let software = nlifs::gpu::batch::is_software(&ctx);
    let scene = common::scene_path("twist-anim");
    let run = |backend: &str, dir: &std::path::Path| {
        let out = common::run_nlifs(&[
            "record",
            scene.to_str().unwrap(),
            "-o",
            dir.to_str().unwrap(),
            "--frames",
            "0..2",
            "--fps",
            "3",
            "--width",
            "64",
            "--height",
            "48",
            "--points-per-frame",
            "20000",
            "--backend",
            backend,
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "record --backend {backend}: {stderr}");
        stderr
    };
    let dirs: Vec<_> = ["cpu", "gpu", "auto"].iter().map(|b| common::temp_dir(&format!("rec-cli-{b}"))).collect();
    let stderr_cpu = run("cpu", &dirs[0]);
    assert!(stderr_cpu.contains("chaos game on the CPU"), "{stderr_cpu}");
    let stderr_gpu = run("gpu", &dirs[1]);
    assert!(stderr_gpu.contains("chaos game on the GPU"), "{stderr_gpu}");
    let stderr_auto = run("auto", &dirs[2]);
    let same_as = |dir: &std::path::Path| {
        (0..2).all(|k| {
            std::fs::read(record::frame_path(dir, k)).unwrap()
                == std::fs::read(record::frame_path(&dirs[2], k)).unwrap()
        })
    };
    if software {
        assert!(stderr_auto.contains("software rasterizer"), "{stderr_auto}");
        assert!(same_as(&dirs[0]), "auto on a software adapter should write the CPU recorder's frames");
    } else {
        assert!(stderr_auto.contains("chaos game on the GPU"), "{stderr_auto}");
        assert!(same_as(&dirs[1]), "auto on a hardware adapter should write the GPU recorder's frames");
    }
    for dir in &dirs {
        let _ = std::fs::remove_dir_all(dir);
    }
}

// ---------------------------------------------------------------------------------------------
// `render --backend gpu` in batches.

/// A GPU still of many points runs in several timed batches and, past 2^24 splats, in passes
/// added up on the host; it keeps the CPU chaos game's densities (6σ on a coarse grid; the CPU
/// side in orbits of 4 steps for a tight bound, the GPU side in orbits of the batch plan's
/// length), and every pass's points are counted.
#[test]
fn batched_gpu_render_densities_match_cpu_render() {
    let Some(ctx) = gpu() else { return };
    let mut scene = scene("plant2", false);
    scene.render.mode = SplatMode::Density;
    scene.render.depth_cue = 0.0;
    // 2^20 GPU points of 20 steps: a pass of 16 steps (2^24 splats) and one of 4.
    let points = 20_000_000u64;
    let settings = nlifs::scene::spec::RenderSettings { width: 160, height: 120, points, ..scene.render.clone() };
    let shot = nlifs::shot::Shot::prepare(&scene, 0.0, &settings, nlifs::shot::Framing::Fit, None).unwrap();
    let gpu = nlifs::gpu::render::render_gpu(&ctx, &shot).unwrap();
    let plan = nlifs::gpu::batch::BatchPlan::new(points);
    assert_eq!(gpu.stats.splats, plan.splats());
    // The first batch splats 2^20 points, so this many points take more than one.
    assert!(gpu.stats.batches >= 2, "{:?}", gpu.stats);
    let k_cpu = 4u32;
    let mut reference = Framebuffer::new(shot.view, shot.compiled.colors.clone());
    for c in 0..(2u32 << 20) / (ORBITS_PER_CHUNK as u32 * k_cpu) {
        run_chunk(&shot.compiled, 77, 0, c, k_cpu as usize, &mut reference);
    }
    let counts = |fb: &Framebuffer| -> Vec<u32> { fb.accum.iter().map(|a| a[3]).collect() };
    let (cg, cc) = (counts(&gpu.framebuffer), counts(&reference));
    let (ng, nc) = (cg.iter().map(|&c| c as f64).sum::<f64>(), cc.iter().map(|&c| c as f64).sum::<f64>());
    assert!(plan.splats() > nlifs::gpu::batch::PASS_SPLATS);
    // Both passes counted (one pass alone would hold at most 2^24 of the 2·10^7).
    assert!(ng > 0.9 * points as f64 && ng <= plan.splats() as f64, "{ng} of {points} on screen");
    let cells = (16usize, 12usize);
    let worst = assert_densities_agree(
        "batched GPU render",
        &Density {
            label: "GPU",
            density: &coarse_density(&cg, 160, 120, cells),
            samples: ng,
            steps_per_orbit: plan.steps_per_thread as f64,
        },
        &Density {
            label: "CPU",
            density: &coarse_density(&cc, 160, 120, cells),
            samples: nc,
            steps_per_orbit: k_cpu as f64,
        },
        cells,
    );
    eprintln!("batched GPU render: {:?}, worst |Δ|/tolerance {worst:.3}", gpu.stats);
    // The resolve of a GPU render is the CPU's resolve of its accumulation.
    assert!(gpu.image == nlifs::resolve::resolve_image(&gpu.framebuffer, &shot.camera, &shot.style));
}

/// An image whose accumulation exceeds what the device binds is refused before any GPU buffer
/// is made: exit 2, the size in the message, no file.
#[test]
fn gpu_render_past_the_device_limits_is_bad_input() {
    let Some(ctx) = gpu() else { return };
    let limits = ctx.device.limits();
    let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    // 16 bytes a pixel: 16384² needs 4 GiB, past any 32-bit binding.
    assert!(16 * 16384u64 * 16384 > limit, "this adapter binds {limit} bytes");
    let dir = common::temp_dir("gpu-too-large");
    let out = dir.join("big.png");
    let scene = common::scene_path("plant2");
    let run = common::run_nlifs(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--backend",
        "gpu",
        "--width",
        "16384",
        "--height",
        "16384",
        "--points",
        "1000",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("16384×16384") && stderr.contains("--backend cpu"), "{stderr}");
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// An IFS whose tables pass the uniform program's capacities needs the storage program's nine
/// storage buffers; on a device that binds eight (WebGPU's default limit) the live view takes
/// the CPU route for it, whatever the backend setting, and says why; an IFS that fits keeps the
/// GPU route there.
#[test]
fn tables_past_the_uniform_limits_take_the_cpu_route_on_eight_storage_buffers() {
    let Some(ctx) = gpu() else { return };
    let limits = wgpu::Limits { max_storage_buffers_per_shader_stage: 8, ..ctx.adapter.limits() };
    let (device, queue) = pollster::block_on(
        ctx.adapter.request_device(&wgpu::DeviceDescriptor { required_limits: limits, ..Default::default() }),
    )
    .unwrap();
    let eight = GpuContext { instance: ctx.instance.clone(), adapter: ctx.adapter.clone(), device, queue };
    // bent4 with its bent maps on 30×30 grids: 2 × 29² cells, past the 512 of the uniform table.
    let text = std::fs::read_to_string(common::scene_path("bent4")).unwrap().replace("[9, 9]", "[30, 30]");
    let bent = Scene::parse(&text, "bent4-30").unwrap();
    let large = CompiledIfs::new(&bent.at(0.0)).unwrap();
    assert!(!nlifs::gpu::chaos_game::tables_fit_uniforms(&large));
    let small = CompiledIfs::new(&scene("plant2", false).at(0.0)).unwrap();
    assert!(nlifs::gpu::chaos_game::tables_fit_uniforms(&small));
    let settings = route_settings(ChaosBackend::Gpu, SplatMode::Closest, 1 << 12, 1);
    for (context, limit) in [(&eight, 8), (&ctx, ctx.device.limits().max_storage_buffers_per_shader_stage)] {
        let mut live = LiveView::new(context, settings, 64, 48).unwrap();
        live.set_ifs(context, &small, chaos_game::attractor_bounds(&small, 1), true);
        assert!(!live.route().cpu, "{limit} storage buffers: plant2 on the GPU");
        let bounds = chaos_game::attractor_bounds(&large, 1);
        live.set_ifs(context, &large, bounds, true);
        live.set_camera(&bent.camera_for(bounds));
        assert_eq!(live.route().cpu, limit < 9, "{limit} storage buffers: {:?}", live.route());
        let mut encoder = context.device.create_command_encoder(&Default::default());
        let splats = live.advance(context, &mut encoder);
        context.queue.submit([encoder.finish()]);
        assert!(splats > 0, "{limit} storage buffers: nothing splatted");
        live.set_ifs(context, &small, chaos_game::attractor_bounds(&small, 1), false);
        assert!(!live.route().cpu, "{limit} storage buffers: plant2 back on the GPU");
    }
}
