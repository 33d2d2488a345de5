//! Playback through a key as the viewer does it: each frame scene time advances by `dt`, the
//! IFS at the new time goes to the live view as an edit (points kept, accumulation cleared,
//! `settle_steps` not splatted) and one frame is drawn. Measures, on both chaos-game routes
//! (GPU, and the CPU route with its persistent chains), in density mode on a coarse grid as
//! `nlifs bench gpu` does, (1) how far each playback frame is from the converged image of its
//! time, against a fresh fully settled run with as many splats, (2) after pausing just past the
//! key, and (3) after an edit (a grid point of plant2 moved), how many frames until the
//! accumulation is within noise of converged.
//! A measurement for docs/performance.md (playback re-convergence): `cargo test --release --test viewer_playback --
//! --ignored --nocapture` (needs a GPU adapter; lavapipe will do).

mod common;

use nlifs::chaos_game::CompiledIfs;
use nlifs::gpu::GpuContext;
use nlifs::gpu::progressive::ProgressiveSettings;
use nlifs::live::{ChaosBackend, LiveSettings, LiveView};
use nlifs::scene::spec::SplatMode;

const W: u32 = 320;
const H: u32 = 180;
const CELLS: (u32, u32) = (32, 18);

/// The coarse density of a density-mode accumulation (its fourth word per pixel is the count).
fn coarse_density(accum: &[u32]) -> Vec<f64> {
    let counts: Vec<u32> = accum.chunks(4).take((W * H) as usize).map(|a| a[3]).collect();
    common::coarse_density(&counts, W as usize, H as usize, (CELLS.0 as usize, CELLS.1 as usize))
}

fn l1(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum()
}

fn frame(ctx: &GpuContext, live: &mut LiveView) -> Vec<f64> {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    live.advance(ctx, &mut encoder);
    ctx.queue.submit([encoder.finish()]);
    coarse_density(&live.read_accum(ctx).unwrap())
}

/// A converged image: 8 frames of 2^17 × 16 points on the CPU route from a fresh start.
fn reference(ctx: &GpuContext, settings: LiveSettings, ifs: &CompiledIfs, view: &View) -> Vec<f64> {
    let settings = LiveSettings {
        draw: ProgressiveSettings { steps_per_frame: 16, seed: 99, ..settings.draw },
        chaos_backend: ChaosBackend::Cpu,
        render_density: None,
    };
    let mut r = LiveView::new(ctx, settings, W, H).unwrap();
    r.set_ifs(ctx, ifs, view.bounds, true);
    r.set_camera(&view.camera);
    let mut d = Vec::new();
    for _ in 0..8 {
        d = frame(ctx, &mut r);
    }
    d
}

/// `frames` frames of a fresh, fully settled run with `settings` (another seed).
fn fresh(ctx: &GpuContext, settings: LiveSettings, ifs: &CompiledIfs, view: &View, frames: usize) -> Vec<Vec<f64>> {
    let mut f =
        LiveView::new(ctx, LiveSettings { draw: ProgressiveSettings { seed: 7, ..settings.draw }, ..settings }, W, H)
            .unwrap();
    f.set_ifs(ctx, ifs, view.bounds, true);
    f.set_camera(&view.camera);
    (0..frames).map(|_| frame(ctx, &mut f)).collect()
}

struct View {
    bounds: (glam::DVec3, glam::DVec3),
    camera: nlifs::camera::OrbitCamera,
}

/// Frames (1..=12) after which `live` (just cleared) is within noise of converged on `ifs`.
fn frames_to_converge(
    ctx: &GpuContext,
    live: &mut LiveView,
    settings: LiveSettings,
    ifs: &CompiledIfs,
    view: &View,
) -> Option<usize> {
    let reference = reference(ctx, settings, ifs, view);
    let fresh = fresh(ctx, settings, ifs, view, 12);
    let mut converged = None;
    for (k, fresh) in fresh.iter().enumerate() {
        let d_live = l1(&frame(ctx, live), &reference);
        let d_fresh = l1(fresh, &reference);
        if converged.is_none() && d_live <= 1.2 * d_fresh {
            converged = Some(k + 1);
        }
    }
    converged
}

#[test]
#[ignore = "measurement for docs/performance.md (playback re-convergence); run with --ignored --nocapture"]
fn playback_through_a_key_reconverges() {
    let Some(ctx) = common::gpu() else { return };
    let scene = common::load_scene("twist-anim");
    let bounds = nlifs::record::timeline_bounds(&scene).unwrap();
    let view = View { bounds, camera: scene.camera_for_at(0.0, bounds) };
    let compiled = |t: f64| CompiledIfs::new(&scene.at(t)).unwrap();
    // The key at t = 2 s (twist 0° → 120° → 0°, taper 0 → 0.7 → 0; Catmull-Rom, loop).
    for dt in [1.0 / 24.0, 1.0 / 6.0] {
        let t0 = 2.0 - 6.0 * dt;
        let times: Vec<f64> = (1..=12).map(|k| t0 + k as f64 * dt).collect();
        let base = LiveSettings {
            draw: ProgressiveSettings {
                point_count: 1 << 17,
                mode: SplatMode::Density,
                max_splats: u64::MAX,
                ..ProgressiveSettings::default()
            },
            ..LiveSettings::default()
        };
        let references: Vec<Vec<f64>> = times.iter().map(|&t| reference(&ctx, base, &compiled(t), &view)).collect();
        // The viewer plays navigating (`LiveView::set_navigating`: fewer settle steps).
        for (backend, navigating) in
            [ChaosBackend::Gpu, ChaosBackend::Cpu].into_iter().flat_map(|b| [(b, false), (b, true)])
        {
            let settings = LiveSettings { chaos_backend: backend, ..base };
            let mut live = LiveView::new(&ctx, settings, W, H).unwrap();
            live.set_navigating(&ctx, navigating).unwrap();
            live.set_ifs(&ctx, &compiled(t0), bounds, true);
            live.set_camera(&view.camera);
            for _ in 0..4 {
                frame(&ctx, &mut live);
            }
            println!(
                "{} route{}, playback dt = {dt:.4} s (frames before/after the key at 2 s): d_play / d_fresh",
                backend.name(),
                if navigating { " navigating" } else { "" },
            );
            let mut worst: f64 = 0.0;
            for (k, (&t, reference)) in times.iter().zip(&references).enumerate() {
                live.set_ifs(&ctx, &compiled(t), bounds, false);
                let d_play = l1(&frame(&ctx, &mut live), reference);
                let d_fresh = l1(&fresh(&ctx, settings, &compiled(t), &view, 1)[0], reference);
                worst = worst.max(d_play / d_fresh);
                println!(
                    "  frame {k:2} t = {t:.3}: d_play {d_play:.4} d_fresh {d_fresh:.4} ratio {:.2}",
                    d_play / d_fresh
                );
            }
            // Pause just past the key: frames until within noise of converged.
            let t = times[times.len() - 1];
            let converged = frames_to_converge(&ctx, &mut live, settings, &compiled(t), &view);
            println!(
                "  worst playback ratio {worst:.2}; after pausing at t = {t:.3}: within noise after {converged:?} frame(s)"
            );
        }
    }
}

#[test]
#[ignore = "measurement for docs/performance.md (re-convergence after an edit); run with --ignored --nocapture"]
fn an_edit_reconverges() {
    let Some(ctx) = common::gpu() else { return };
    let path = common::scene_path("plant2");
    let text = std::fs::read_to_string(&path).unwrap();
    let parse = |text: &str| nlifs::scene::Scene::parse(text, &path.display().to_string()).unwrap();
    let scene = parse(&text);
    let ifs = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = nlifs::chaos_game::attractor_bounds(&ifs, 1);
    let view = View { bounds, camera: scene.camera_for(bounds) };
    // A drag of one grid point of f1 by 3 units (7 % of the grid's width), and a small one.
    for (what, moved) in [("3 units", "[3.9, -13.33, -0.1]"), ("0.3 units", "[1.2, -13.33, -0.1]")] {
        let edited = CompiledIfs::new(&parse(&text.replacen("[0.9, -13.33, -0.1]", moved, 1)).at(0.0)).unwrap();
        for backend in [ChaosBackend::Gpu, ChaosBackend::Cpu] {
            let settings = LiveSettings {
                draw: ProgressiveSettings {
                    point_count: 1 << 17,
                    mode: SplatMode::Density,
                    max_splats: u64::MAX,
                    ..ProgressiveSettings::default()
                },
                chaos_backend: backend,
                render_density: None,
            };
            let mut live = LiveView::new(&ctx, settings, W, H).unwrap();
            live.set_ifs(&ctx, &ifs, bounds, true);
            live.set_camera(&view.camera);
            for _ in 0..4 {
                frame(&ctx, &mut live);
            }
            live.set_ifs(&ctx, &edited, bounds, false);
            let converged = frames_to_converge(&ctx, &mut live, settings, &edited, &view);
            println!(
                "{} route, plant2 grid point moved by {what}: within noise after {converged:?} frame(s)",
                backend.name()
            );
        }
    }
}
