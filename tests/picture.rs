//! The live view without compute shaders (a browser's WebGL2; `src/gpu/picture.rs`): the CPU
//! route fills the accumulation, the resolve's CPU twin resolves it and the picture is drawn as
//! a texture. Against the live view that resolves the same CPU route's accumulation on the GPU:
//! the same accumulation word for word, pictures within the GPU-against-CPU resolve's tolerance
//! (`tests/resolve.rs`: under 0.1 of a level before rounding, so at most one level after), in
//! every splat mode with the solid look, shadows and density estimation; drawn at an origin in a
//! larger target as the viewer draws it right of its panel; and at rest once converged. Runs on
//! any adapter (lavapipe in CI); without one it skips loudly, unless NLIFS_REQUIRE_GPU=1, in
//! which case it fails.

mod common;

use common::gpu;
use nlifs::chaos_game::{self, CompiledIfs};
use nlifs::gpu::GpuContext;
use nlifs::gpu::progressive::ProgressiveSettings;
use nlifs::gpu::readback::draw_offscreen;
use nlifs::live::{ChaosBackend, LiveSettings, LiveView};
use nlifs::scene::spec::{DensityEstimation, SplatMode};

const SIZE: (u32, u32) = (160, 120);

fn settings(mode: SplatMode) -> LiveSettings {
    let closest = mode == SplatMode::Closest;
    let draw = ProgressiveSettings {
        point_count: 1 << 14,
        steps_per_frame: 3,
        seed: 5,
        mode,
        depth_cue: 0.5,
        background: [0.02, 0.03, 0.05],
        shading: if closest { 1.0 } else { 0.0 },
        occlusion: if closest { 0.6 } else { 0.0 },
        shadows: if closest { 0.7 } else { 0.0 },
        point_radius_px: if closest { 1 } else { 0 },
        density_estimation: (mode == SplatMode::Density).then_some(DensityEstimation {
            max_radius_px: 5.0,
            min_radius_px: 0.0,
            curve: 0.4,
        }),
        max_splats: u64::MAX,
        ..ProgressiveSettings::default()
    };
    LiveSettings { draw, chaos_backend: ChaosBackend::Cpu, render_density: None }
}

/// plant2 in a live view of [`SIZE`] after `frames` frames.
fn live_view(ctx: &GpuContext, settings: LiveSettings, compute: bool, frames: u32) -> LiveView {
    let scene = common::load_scene("plant2");
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let mut live = match compute {
        true => LiveView::new(ctx, settings, SIZE.0, SIZE.1).unwrap(),
        false => LiveView::without_compute(ctx, settings, SIZE.0, SIZE.1).unwrap(),
    };
    assert!(live.route().cpu);
    live.set_ifs(ctx, &compiled, bounds, true);
    live.set_camera(&scene.camera_for(bounds));
    for _ in 0..frames {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        live.advance(ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
    }
    live
}

#[test]
fn the_picture_resolved_on_the_cpu_matches_the_gpu_resolve() {
    let Some(ctx) = gpu() else { return };
    for mode in [SplatMode::Closest, SplatMode::Average, SplatMode::Density] {
        let s = settings(mode);
        let mut on_gpu = live_view(&ctx, s, true, 3);
        let mut on_cpu = live_view(&ctx, s, false, 3);
        assert_eq!(
            on_gpu.read_accum(&ctx).unwrap()[..on_cpu.cpu_accum().unwrap().len()],
            on_cpu.read_accum(&ctx).unwrap()[..],
            "{mode:?}: the same accumulation"
        );
        let (a, b) = (on_gpu.snapshot(&ctx).unwrap(), on_cpu.snapshot(&ctx).unwrap());
        let background = b.get_pixel(0, 0).0;
        let drawn = b.pixels().filter(|p| p.0 != background).count();
        let lit = on_cpu.lit_pixels().unwrap() as usize;
        assert!(drawn > lit / 2 && drawn > 500, "{mode:?}: {drawn} pixels drawn, {lit} lit");
        let mut differing = 0;
        for (x, y, p) in b.enumerate_pixels() {
            let q = a.get_pixel(x, y);
            let diff = (0..3).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap();
            assert!(diff <= 1, "{mode:?}: pixel ({x}, {y}) CPU {:?}, GPU {:?}", p.0, q.0);
            differing += (diff > 0) as usize;
        }
        eprintln!("{mode:?}: {drawn} pixels drawn, {differing} differ from the GPU resolve by one level");
    }
}

#[test]
fn the_picture_is_drawn_at_its_origin_and_comes_to_rest() {
    let Some(ctx) = gpu() else { return };
    let mut s = settings(SplatMode::Closest);
    // Past the frames whose draws light every pixel (`LIGHT_FULL_FRAMES`): the light cache is
    // refreshed a band of rows a draw, as the viewer's.
    let frames = 14;
    s.draw.max_splats = frames * (1 << 14) * 3;
    let mut live = live_view(&ctx, s, false, 0);
    let origin = [7u32, 5u32];
    let draw_at = |live: &mut LiveView, (w, h): (u32, u32), origin: [u32; 2]| {
        draw_offscreen(&ctx, w, h, |encoder, target, format| live.draw(&ctx, encoder, target, format, origin)).unwrap()
    };
    let mut drawn = 0;
    while !live.converged() {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        live.advance(&ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        draw_at(&mut live, SIZE, [0, 0]);
        drawn += 1;
        assert!(drawn <= frames, "not converged after {drawn} frames");
    }
    // Converged: a few draws (the light's bands) bring it to rest, the light then current.
    let mut draws = 0;
    while !live.at_rest() {
        draw_at(&mut live, SIZE, [0, 0]);
        draws += 1;
        assert!(draws <= 8, "not at rest after {draws} draws of a converged view");
    }
    let (w, h) = (SIZE.0 + 20, SIZE.1 + 9);
    let placed = draw_at(&mut live, (w, h), origin);
    let picture = live.snapshot(&ctx).unwrap();
    assert!(picture.pixels().filter(|p| p.0 != picture.get_pixel(0, 0).0).count() > 500, "a blank picture");
    for (x, y, p) in placed.enumerate_pixels() {
        let inside = (origin[0]..origin[0] + SIZE.0).contains(&x) && (origin[1]..origin[1] + SIZE.1).contains(&y);
        let want = if inside { picture.get_pixel(x - origin[0], y - origin[1]).0 } else { [0, 0, 0] };
        assert_eq!(p.0, want, "pixel ({x}, {y}): the banded light at rest against the whole light, at {origin:?}");
    }
}

/// Frames drawn as the viewer draws them, through an edit and its undo: the picture after the
/// undo is the one before the edit, drawn as the GPU resolve draws it.
#[test]
fn an_edit_and_its_undo_redraw_the_picture() {
    let Some(ctx) = gpu() else { return };
    let scene = common::load_scene("plant2");
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let mut edited_scene = scene.clone();
    edited_scene.functions[1].enabled = false;
    let edited = CompiledIfs::new(&edited_scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let s = settings(SplatMode::Closest);
    let mut views: Vec<LiveView> = [true, false]
        .into_iter()
        .map(|compute| {
            let mut live = match compute {
                true => LiveView::new(&ctx, s, SIZE.0, SIZE.1).unwrap(),
                false => LiveView::without_compute(&ctx, s, SIZE.0, SIZE.1).unwrap(),
            };
            live.set_ifs(&ctx, &compiled, bounds, true);
            live.set_camera(&scene.camera_for(bounds));
            live
        })
        .collect();
    for ifs in [&compiled, &edited, &compiled] {
        for live in &mut views {
            live.set_ifs(&ctx, ifs, bounds, false);
            for _ in 0..12 {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                live.advance(&ctx, &mut encoder);
                ctx.queue.submit([encoder.finish()]);
                draw_offscreen(&ctx, SIZE.0, SIZE.1, |encoder, target, format| {
                    live.draw(&ctx, encoder, target, format, [0, 0])
                })
                .unwrap();
            }
        }
        let [a, b] = [0, 1].map(|i| {
            let live = &mut views[i];
            draw_offscreen(&ctx, SIZE.0, SIZE.1, |encoder, target, format| {
                live.draw(&ctx, encoder, target, format, [0, 0])
            })
            .unwrap()
        });
        let background = b.get_pixel(0, 0).0;
        // plant2 without its crown lights a few hundred pixels here.
        assert!(b.pixels().filter(|p| p.0 != background).count() > 200, "a blank picture");
        let worst =
            a.pixels().zip(b.pixels()).map(|(p, q)| (0..3).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap()).max();
        assert!(worst <= Some(1), "the pictures differ by {worst:?} levels");
    }
}
