//! Depth of field (`src/splat/lens.rs`, the `lens_*` functions of `shaders/chaos_game.wgsl`),
//! each against an oracle with its tolerance stated:
//!
//! 1. Aperture 0 gives the same bytes as no depth of field, on the CPU and on the GPU.
//! 2. Points on the focus plane stay on their pixels; a tiny cluster at depth d spreads into a
//!    disc of radius aperture · |1/f − 1/d| / footprint (parallel projection: the same with
//!    (d − f)/f), within a pixel.
//! 3. The GPU splat of the GPU's own points agrees with the CPU lens splat of the same points
//!    (the same hash gives the same lens samples), up to f32 rounding at pixel edges.
//! 4. Bad values are located errors (scene file, keys, command line).

mod common;

use common::gpu;
use glam::{DVec3, Vec3};
use nlifs::camera::{OrbitCamera, Projection};
use nlifs::chaos_game::{CompiledIfs, PointBatch, PointSink};
use nlifs::gpu::chaos_game::{FrameArgs, GpuChaosGame};
use nlifs::gpu::readback::read_buffer;
use nlifs::rng::Pcg32;
use nlifs::scene::Scene;
use nlifs::scene::spec::{RenderSettings, SplatMode};
use nlifs::shot::{Accumulation, Framing, Shot};
use nlifs::splat::{EMPTY, Framebuffer, Lens, SplatView};

/// A small render of plant2 (3D) with `aperture`, `focus` over the scene's settings.
fn plant2_settings(aperture: f32, focus: Option<f32>) -> (Scene, RenderSettings) {
    let scene = common::load_scene("plant2");
    let mut settings = scene.render.clone();
    (settings.width, settings.height, settings.points) = (160, 120, 200_000);
    (settings.aperture, settings.focus_distance) = (aperture, focus);
    (scene, settings)
}

fn shot(aperture: f32, focus: Option<f32>) -> Shot {
    let (scene, settings) = plant2_settings(aperture, focus);
    Shot::prepare(&scene, 0.0, &settings, Framing::Scene, None).unwrap()
}

fn splat_points(view: SplatView, points: &[Vec3]) -> Framebuffer {
    let mut fb = Framebuffer::new(view, vec![[0.8, 0.5, 0.2]]);
    let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
        points.iter().map(|p| p.x).collect(),
        points.iter().map(|p| p.y).collect(),
        points.iter().map(|p| p.z).collect(),
    );
    let functions = vec![0u8; points.len()];
    fb.consume(PointBatch { x: &x, y: &y, z: &z, functions: &functions });
    fb
}

/// The camera's right, up and forward unit vectors.
fn basis(camera: &OrbitCamera) -> (Vec3, Vec3, Vec3) {
    let back = camera.eye_direction();
    let right = Vec3::Y.cross(back).normalize();
    (right, back.cross(right), -back)
}

#[test]
fn aperture_zero_is_the_pinhole_render_on_the_cpu() {
    let pinhole = shot(0.0, None);
    // A focus distance without an aperture changes nothing either.
    let zero = shot(0.0, Some(3.0));
    assert_eq!(zero.view.lens, Lens::NONE);
    let (a, b) = (pinhole.splat(|| {}), zero.splat(|| {}));
    assert!(a.closest == b.closest && a.covered_pixels() > 1000, "{} pixels", a.covered_pixels());
    // And a lens does change it (the comparison is not vacuous).
    let blurred = shot(0.05 * pinhole.camera.distance, None).splat(|| {});
    assert_ne!(a.closest, blurred.closest);
}

/// The lens samples are a function of the point alone: per-thread framebuffers and one shared
/// framebuffer (other batches, other order) hold the same integers (tolerance 0).
#[test]
fn lens_render_does_not_depend_on_the_accumulation() {
    for mode in [SplatMode::Closest, SplatMode::Density] {
        let (scene, mut settings) = plant2_settings(2.0, None);
        settings.mode = mode;
        let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Scene, None).unwrap();
        let chunks = 0..shot.plan.chunks();
        let a = shot.splat_chunks(chunks.clone(), Accumulation::PerThread, || {});
        let b = shot.splat_chunks(chunks, Accumulation::Shared, || {});
        assert!(a.closest == b.closest && a.accum == b.accum, "{mode:?}");
        assert!(a.covered_pixels() > 1000);
    }
}

#[test]
fn aperture_zero_is_the_pinhole_render_on_the_gpu() {
    let Some(ctx) = gpu() else { return };
    let pinhole = nlifs::gpu::render::render_gpu(&ctx, &shot(0.0, None)).unwrap();
    let zero = nlifs::gpu::render::render_gpu(&ctx, &shot(0.0, Some(3.0))).unwrap();
    assert!(pinhole.image == zero.image, "aperture 0 changed the GPU render");
    assert!(pinhole.framebuffer.closest == zero.framebuffer.closest);
    let lens = shot(0.05 * shot(0.0, None).camera.distance, None);
    let blurred = nlifs::gpu::render::render_gpu(&ctx, &lens).unwrap();
    assert!(blurred.framebuffer.closest != pinhole.framebuffer.closest);
}

/// The lens's footprint is `resolve::pixel_footprint`'s (kept in two places to avoid a module
/// cycle): radius_px = aperture / footprint, exactly.
#[test]
fn lens_footprint_is_the_resolve_footprint() {
    for projection in [Projection::Perspective, Projection::Parallel] {
        let mut camera = OrbitCamera::framing((DVec3::ZERO, DVec3::ONE), 3);
        camera.projection = projection;
        let lens = Lens::new(&camera, 480, 0.25, None, 1).unwrap();
        let (footprint, perspective) = nlifs::resolve::pixel_footprint(&camera, 480);
        assert_eq!((lens.radius_px, lens.perspective), (0.25 / footprint, perspective));
        assert_eq!(lens.inv_focus, 1.0 / camera.distance, "the default focus is the target's distance");
    }
}

fn focus_plane_and_disc(projection: Projection) {
    let bounds = (DVec3::splat(-1.0), DVec3::splat(1.0));
    let mut camera = OrbitCamera::framing(bounds, 3);
    camera.projection = projection;
    let (w, h) = (241, 201);
    let pinhole = SplatView::new(&camera, w, h, bounds, SplatMode::Closest, 0.0, [0.0; 3]);
    let f = camera.distance;
    let aperture = 0.2 * f;
    let lens = Lens::new(&camera, h, aperture, Some(f), 7).unwrap();
    let view = pinhole.with_lens(lens);
    let (right, up, forward) = basis(&camera);
    let eye = camera.eye();
    let mut r = Pcg32::for_stream(5, 0, 0);

    // Points on the focus plane (view depth f), spread over the picture.
    let half = 0.3 * f;
    let plane: Vec<Vec3> = (0..20_000)
        .map(|_| eye + f * forward + (2.0 * r.next_f32() - 1.0) * half * right + (2.0 * r.next_f32() - 1.0) * half * up)
        .collect();
    let (sharp, with_lens) = (splat_points(pinhole, &plane), splat_points(view, &plane));
    let differ = sharp.closest.iter().zip(&with_lens.closest).filter(|(a, b)| a != b).count();
    // A point on the plane is at depth f up to f32 rounding (a few ulps): its offset is at most
    // the blur of a point 8 ulps off the plane, and it moves to another pixel only within that
    // of one of its 4 pixel edges.
    let offset_px = lens.blur_radius_px(f * (1.0 + 8.0 * f32::EPSILON));
    let bound = (plane.len() as f32 * 4.0 * offset_px).ceil() as usize + 2;
    assert!(sharp.covered_pixels() > 5000);
    assert!(differ <= bound, "{projection:?}: {differ} of the focus plane's pixels moved (bound {bound})");

    // A cluster far smaller than a pixel at depth d, off the focus plane.
    for d in [0.75 * f, 1.3 * f] {
        let centre = eye + d * forward + 0.05 * f * right;
        let cluster: Vec<Vec3> =
            (0..60_000).map(|_| centre + 1e-6 * f * Vec3::new(r.next_f32(), r.next_f32(), r.next_f32())).collect();
        let fb = splat_points(view, &cluster);
        let radius = lens.blur_radius_px(d);
        let expected = match projection {
            Projection::Perspective => lens.radius_px * (1.0 / f - 1.0 / d).abs(),
            Projection::Parallel => lens.radius_px * ((d - f) / f).abs(),
        };
        assert!((radius - expected).abs() <= 1e-4 * expected, "{radius} vs {expected}");
        assert!(radius > 8.0 && radius < 60.0, "a disc of {radius} pixels tests little");
        // The cluster's pinhole position (pixel coordinates, continuous).
        let q = view.pixel_from_world * centre.extend(1.0);
        let (cx, cy) = (q.x / q.w, q.y / q.w);
        let covered: Vec<(f32, f32)> = (0..fb.closest.len())
            .filter(|&i| fb.closest[i] != EMPTY)
            .map(|i| ((i % w as usize) as f32 + 0.5, (i / w as usize) as f32 + 0.5))
            .collect();
        let reach = covered.iter().map(|&(x, y)| ((x - cx).powi(2) + (y - cy).powi(2)).sqrt()).fold(0.0, f32::max);
        // A covered pixel's centre lies within √2/2 of a landed point, which lies within the
        // disc; 60 000 samples reach the disc's edge (within a pixel) all round.
        assert!((reach - radius).abs() <= 1.0, "{projection:?} d = {d}: reach {reach} px, disc radius {radius} px");
        // The covered area is the disc's, up to the pixels its edge crosses (2πR · √2/2 each side).
        let area = std::f32::consts::PI * radius * radius;
        let edge = 2.0 * std::f32::consts::PI * radius * std::f32::consts::FRAC_1_SQRT_2;
        let n = covered.len() as f32;
        assert!((n - area).abs() <= edge, "{projection:?} d = {d}: {n} pixels covered, disc area {area}");
    }
}

#[test]
fn focus_plane_stays_sharp_and_a_point_spreads_into_its_disc() {
    focus_plane_and_disc(Projection::Perspective);
}

#[test]
fn parallel_projection_blurs_linearly_in_depth() {
    focus_plane_and_disc(Projection::Parallel);
}

/// The GPU chaos game's first step splats its points through the lens; the CPU lens splat of
/// the same points (read back, bit for bit) must cover the same pixels with the same keys.
#[test]
fn gpu_lens_splat_matches_cpu_lens_splat() {
    let Some(ctx) = gpu() else { return };
    let scene = common::load_scene("plant2");
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = nlifs::chaos_game::attractor_bounds(&compiled, 1);
    let camera = scene.camera_for(bounds);
    let (w, h) = (256u32, 192u32);
    for projection in [Projection::Perspective, Projection::Parallel] {
        let camera = OrbitCamera { projection, ..camera };
        let lens = Lens::new(&camera, h, 0.03 * camera.distance, Some(0.9 * camera.distance), 11).unwrap();
        let view = SplatView::new(&camera, w, h, bounds, SplatMode::Closest, 0.5, [0.0; 3]).with_lens(lens);
        let n = 1u32 << 16;
        let mut game = GpuChaosGame::new(&ctx.device, n, w, h);
        game.set_ifs(&ctx.device, &ctx.queue, &compiled);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let args = FrameArgs { view: &view, seed: 3, frame: 0, steps: 1, skip_steps: 0, restart: true, clear: true };
        game.encode(&ctx.device, &ctx.queue, &mut encoder, &args);
        ctx.queue.submit([encoder.finish()]);
        let points: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read_buffer(&ctx, &game.points).unwrap());
        let accum: Vec<u32> = bytemuck::pod_collect_to_vec(&read_buffer(&ctx, &game.accum).unwrap());
        let gpu_keys = &accum[..(w * h) as usize];

        let mut cpu = Framebuffer::new(view, compiled.colors.clone());
        let x: Vec<f32> = points.iter().map(|p| p[0]).collect();
        let y: Vec<f32> = points.iter().map(|p| p[1]).collect();
        let z: Vec<f32> = points.iter().map(|p| p[2]).collect();
        let functions: Vec<u8> = points.iter().map(|p| p[3] as u8).collect();
        cpu.consume(PointBatch { x: &x, y: &y, z: &z, functions: &functions });

        // The lens samples are the same integers on both sides; what differs is f32 rounding
        // (WGSL's division is within 2.5 ulp, a GPU compiler may fuse multiply-adds): a pixel
        // coordinate below `w` moves by at most 8 ulp(w), so a point changes pixel only within
        // that of one of its 4 pixel edges. Each such point changes at most 2 pixels. The depth
        // fraction is within 8 ulp of 1, i.e. 8 of its 2^24 steps.
        let ulp = f32::EPSILON * (w.max(h) as f32).log2().ceil().exp2();
        let moved = n as f32 * 4.0 * 8.0 * ulp;
        let bound = (2.0 * moved).ceil() as usize + 4;
        let differ = gpu_keys
            .iter()
            .zip(&cpu.closest)
            .filter(|&(&g, &c)| {
                let same_cover = (g == EMPTY) == (c == EMPTY);
                let close =
                    g == c || (g != EMPTY && c != EMPTY && (g & 0xff) == (c & 0xff) && (g >> 8).abs_diff(c >> 8) <= 8);
                !(same_cover && close)
            })
            .count();
        let covered = cpu.covered_pixels();
        assert!(covered > 5000, "{projection:?}: {covered} pixels covered");
        assert!(differ <= bound, "{projection:?}: {differ} pixels differ between GPU and CPU (bound {bound})");
        eprintln!("{projection:?}: {covered} pixels covered, {differ} differ (bound {bound})");
    }
}

#[test]
fn bad_lens_values_are_located_errors() {
    let path = common::scene_path("plant2");
    let text = std::fs::read_to_string(&path).unwrap();
    for (field, value, line) in [
        ("aperture", "-0.5", "render.aperture"),
        ("focus_distance", "0.0", "render.focus_distance"),
        ("focus_distance", "-3", "render.focus_distance"),
        ("aperture", "nan", "render.aperture"),
    ] {
        let bad = text.replacen("[render]\n", &format!("[render]\n{field} = {value}\n"), 1);
        assert_ne!(bad, text, "plant2 has a [render] table");
        let e = Scene::parse(&bad, "bad.toml").unwrap_err();
        let at = bad.lines().position(|l| l.starts_with(&format!("{field} ="))).unwrap() + 1;
        assert_eq!((e.line, e.field.as_deref()), (at, Some(line)), "{e}");
        assert!(e.to_string().contains("bad.toml"), "{e}");
    }
    // A key's value too.
    let keyed =
        format!("{text}\n[timeline]\nduration_secs = 2.0\n\n[[key]]\nt_secs = 1.0\n[key.render]\naperture = -1.0\n");
    let e = Scene::parse(&keyed, "keyed.toml").unwrap_err();
    assert!(e.field.as_deref().is_some_and(|f| f.ends_with("render.aperture")), "{e}");
    // The command line: exit 2 with the flag named.
    let out = common::run_nlifs(&["render", path.to_str().unwrap(), "--aperture", "-1", "-o", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--aperture"));
    let out = common::run_nlifs(&["render", path.to_str().unwrap(), "--focus-distance", "0", "-o", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--focus-distance"));
}

/// A scene's lens reads back from its written text, and keys animate it.
#[test]
fn lens_fields_round_trip_and_animate() {
    let path = common::scene_path("plant2");
    let text = std::fs::read_to_string(&path).unwrap();
    let with_lens = text.replacen("[render]\n", "[render]\naperture = 0.5\nfocus_distance = 80.0\n", 1);
    let scene = Scene::parse(&with_lens, "lens.toml").unwrap();
    assert_eq!((scene.render.aperture, scene.render.focus_distance), (0.5, Some(80.0)));
    let again = Scene::parse(&scene.to_toml(), "again.toml").unwrap();
    assert_eq!(again.render, scene.render);
    let keyed = format!(
        "{with_lens}\n[timeline]\nduration_secs = 2.0\n\n[[key]]\nt_secs = 0.0\ninterpolation = \"linear\"\n[key.render]\naperture = 0.0\n\n[[key]]\nt_secs = 2.0\ninterpolation = \"linear\"\n[key.render]\naperture = 1.0\n"
    );
    let scene = Scene::parse(&keyed, "keyed.toml").unwrap();
    // Linear keys: halfway, half the aperture (f32 of an f64 interpolation).
    let halfway = scene.render_at(1.0).aperture;
    assert!((halfway - 0.5).abs() <= 1e-6, "{halfway}");
    assert_eq!(Scene::parse(&scene.to_toml(), "k.toml").unwrap().render_at(1.0).aperture, halfway);
}

/// The viewer's lens is a scene edit: one undo step, the live view following the scene (its
/// accumulation restarts: the live settings change); a bad value changes nothing.
#[test]
fn viewer_lens_edits_are_undoable_scene_edits() {
    use nlifs::live::LiveSettings;
    use nlifs::viewer::command::Command;
    use nlifs::viewer::state::ViewerState;
    let mut state = ViewerState::new(common::load_scene("plant2"), None, LiveSettings::default());
    assert_eq!((state.live.draw.aperture, state.live.draw.focus_distance), (0.0, None));
    let changes = state.apply([Command::SetLens { aperture: 1.5, focus_distance: Some(70.0) }]);
    assert!(changes.live_settings && changes.scene_edited);
    assert_eq!((state.scene.render.aperture, state.scene.render.focus_distance), (1.5, Some(70.0)));
    assert_eq!((state.live.draw.aperture, state.live.draw.focus_distance), (1.5, Some(70.0)));
    assert!(state.modified());
    let changes = state.apply([Command::Undo]);
    assert!(changes.live_settings);
    assert_eq!(
        (state.scene.render.aperture, state.live.draw.aperture, state.live.draw.focus_distance),
        (0.0, 0.0, None)
    );
    state.apply([Command::Redo]);
    assert_eq!(state.live.draw.aperture, 1.5);
    // A preview (a slider being dragged) moves the live view only; its release makes the edit.
    let mut live = state.live;
    live.draw.aperture = 3.0;
    state.apply([Command::SetLiveSettings(live)]);
    assert_eq!((state.scene.render.aperture, state.live.draw.aperture), (1.5, 3.0));
    state.apply([Command::SetLens { aperture: 3.0, focus_distance: Some(70.0) }]);
    assert_eq!(state.scene.render.aperture, 3.0);
    // Refused: the scene and the live view keep their lens, the error says why.
    let before = state.scene.clone();
    state.apply([Command::SetLens { aperture: -1.0, focus_distance: None }]);
    assert_eq!(state.scene, before);
    assert!(state.error.as_deref().is_some_and(|e| e.contains("aperture")), "{:?}", state.error);
}
