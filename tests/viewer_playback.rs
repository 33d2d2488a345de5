//! Playback through a key as the viewer does it: each frame scene time advances by `dt`, the
//! IFS at the new time goes to the live view as an edit (points kept, accumulation cleared,
//! `settle_steps` not splatted) and one frame is drawn. Measures, in density mode on a coarse
//! grid as `nlifs bench gpu` does, (1) how far each playback frame is from the converged image
//! of its time, against a fresh fully settled run with as many splats, and (2) after pausing
//! just past the key, how many frames until the accumulation is within noise of converged.
//! A measurement for docs/performance.md (playback re-convergence): `cargo test --release --test viewer_playback --
//! --ignored --nocapture` (needs a GPU adapter; lavapipe will do).

mod common;

use nlifs::chaos_game::CompiledIfs;
use nlifs::gpu::GpuContext;
use nlifs::live::{LiveSettings, LiveView};
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

#[test]
#[ignore = "measurement for docs/performance.md (playback re-convergence); run with --ignored --nocapture"]
fn playback_through_a_key_reconverges() {
    let Some(ctx) = common::gpu() else { return };
    let scene = common::load_scene("twist-anim");
    let bounds = nlifs::record::timeline_bounds(&scene).unwrap();
    let camera = scene.camera_for_at(0.0, bounds);
    let settings = LiveSettings {
        point_count: 1 << 17,
        mode: SplatMode::Density,
        max_splats: u64::MAX,
        ..LiveSettings::default()
    };
    let compiled = |t: f64| CompiledIfs::new(&scene.at(t)).unwrap();
    let reference = |t: f64| {
        let mut r = LiveView::new(&ctx, LiveSettings { steps_per_frame: 16, seed: 99, ..settings }, W, H).unwrap();
        r.set_ifs(&ctx, &compiled(t), bounds, true);
        r.set_camera(&camera);
        let mut d = Vec::new();
        for _ in 0..8 {
            d = frame(&ctx, &mut r);
        }
        d
    };
    let fresh = |t: f64, frames: usize| {
        let mut f = LiveView::new(&ctx, LiveSettings { seed: 7, ..settings }, W, H).unwrap();
        f.set_ifs(&ctx, &compiled(t), bounds, true);
        f.set_camera(&camera);
        (0..frames).map(|_| frame(&ctx, &mut f)).collect::<Vec<_>>()
    };
    // The key at t = 2 s (twist 0° → 120° → 0°, taper 0 → 0.7 → 0; Catmull-Rom, loop).
    for dt in [1.0 / 24.0, 1.0 / 6.0] {
        let mut live = LiveView::new(&ctx, settings, W, H).unwrap();
        let t0 = 2.0 - 6.0 * dt;
        live.set_ifs(&ctx, &compiled(t0), bounds, true);
        live.set_camera(&camera);
        for _ in 0..4 {
            frame(&ctx, &mut live);
        }
        println!("playback dt = {dt:.4} s (frames before/after the key at 2 s): d_play / d_fresh");
        let mut t = t0;
        let mut worst: f64 = 0.0;
        for k in 0..12 {
            t += dt;
            live.set_ifs(&ctx, &compiled(t), bounds, false);
            let d_play = l1(&frame(&ctx, &mut live), &reference(t));
            let d_fresh = l1(&fresh(t, 1)[0], &reference(t));
            worst = worst.max(d_play / d_fresh);
            println!("  frame {k:2} t = {t:.3}: d_play {d_play:.4} d_fresh {d_fresh:.4} ratio {:.2}", d_play / d_fresh);
        }
        // Pause just past the key: frames until within noise of converged.
        let reference_t = reference(t);
        let fresh_t = fresh(t, 12);
        let mut converged = None;
        for k in 1..=12 {
            let d_edit = l1(&frame(&ctx, &mut live), &reference_t);
            let d_fresh = l1(&fresh_t[k - 1], &reference_t);
            if converged.is_none() && d_edit <= 1.2 * d_fresh {
                converged = Some(k);
            }
        }
        println!(
            "  worst playback ratio {worst:.2}; after pausing at t = {t:.3}: within noise after {converged:?} frame(s)"
        );
    }
}
