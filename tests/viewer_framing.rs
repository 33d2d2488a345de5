//! Framing in the viewer: on open, every paper scene's attractor lies inside the view
//! rectangle (right of the side panel) with a margin, checked against a run 16 times longer
//! than the framing sample; `F` frames the attractor, `Shift+F` the attractor and the grid box;
//! a resize reframes only while the user has not moved the camera.

mod common;

use glam::Vec2;
use nlifs::chaos_game::attractor_sample;
use nlifs::live::LiveSettings;
use nlifs::viewer::command::Command;
use nlifs::viewer::picking::project;
use nlifs::viewer::state::ViewerState;

const PAPER_SCENES: &[&str] = &[
    "plant1",
    "plant2",
    "sierpinski",
    "sierpinski-nonlinear",
    "linear4",
    "bent4",
    "tapering",
    "twisting",
    "builders",
    "fantasy",
    "julia",
];

/// The state of the viewer on `name` with the view right of a 310 px panel in a 1280×720 window.
fn opened(name: &str) -> ViewerState {
    let path = common::scene_path(name);
    let mut s = ViewerState::new(nlifs::scene::Scene::load(&path).unwrap(), Some(path), LiveSettings::default());
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 720.0] }]);
    s
}

/// The projected extent (pixels in the view) of a long run of the attractor.
fn extent(s: &ViewerState) -> (Vec2, Vec2) {
    let view = s.splat_view();
    let c = s.compiled.as_ref().unwrap();
    let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
    for seed in 0..64u32 {
        for p in attractor_sample(c, 1000 + seed * 7919) {
            if let Some(q) = project(&view, p.as_dvec3()) {
                lo = lo.min(q);
                hi = hi.max(q);
            }
        }
    }
    (lo, hi)
}

#[test]
fn every_paper_scene_opens_inside_the_view_with_a_margin() {
    for name in PAPER_SCENES {
        let s = opened(name);
        if s.scene.camera.target.is_some() || s.scene.camera.distance.is_some() {
            eprintln!("{name}: the scene sets its own camera; not framed");
            continue;
        }
        let (w, h) = (s.width_px, s.height_px);
        let (lo, hi) = extent(&s);
        let margin = Vec2::new(w, h) * 0.02;
        eprintln!("{name}: attractor spans x {:.0}..{:.0} of {w}, y {:.0}..{:.0} of {h}", lo.x, hi.x, lo.y, hi.y);
        assert!(
            lo.x >= margin.x && lo.y >= margin.y && hi.x <= w - margin.x && hi.y <= h - margin.y,
            "{name}: the attractor spans {lo}..{hi} in a {w}×{h} view (2% margin)"
        );
        // And it is not lost in the middle: it fills most of the view along one axis.
        assert!((hi.x - lo.x) / w > 0.7 || (hi.y - lo.y) / h > 0.7, "{name}: spans only {lo}..{hi}");
    }
}

#[test]
fn f_frames_the_attractor_and_shift_f_the_grid_box_too() {
    let mut s = opened("plant1");
    s.apply([Command::Orbit { dx_px: 200.0, dy_px: 50.0 }, Command::Zoom { steps: 8.0 }]);
    assert!(s.camera_moved);
    let yaw = s.camera.yaw_deg;
    s.apply([Command::FrameAttractor]);
    assert_eq!(s.camera.yaw_deg, yaw, "framing keeps the angles");
    assert!(!s.camera_moved);
    let (lo, hi) = extent(&s);
    assert!(lo.x >= 0.0 && lo.y >= 0.0 && hi.x <= s.width_px && hi.y <= s.height_px, "{lo}..{hi}");
    let attractor_distance = s.camera.distance;
    s.apply([Command::FrameAttractorAndGrid]);
    assert!(s.camera.distance >= attractor_distance, "the grid box is larger than the attractor");
    let view = s.splat_view();
    for p in s.scene.domain.points() {
        let q = project(&view, p).unwrap();
        assert!(q.x >= 0.0 && q.y >= 0.0 && q.x <= s.width_px && q.y <= s.height_px, "grid point at {q}");
    }
}

#[test]
fn a_resize_reframes_only_while_the_camera_is_untouched() {
    let mut s = opened("plant2");
    let framed = s.camera;
    // Narrower than the plant is wide: the fit changes (a vertical field of view keeps a
    // height-bound fit as it is).
    s.apply([Command::SetViewRect { origin_px: [0.0, 0.0], size_px: [300.0, 720.0] }]);
    assert_ne!(s.camera, framed, "an untouched camera follows the new view");
    s.apply([Command::Pan { dx_px: 30.0, dy_px: 0.0 }]);
    let moved = s.camera;
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 720.0] }]);
    assert_eq!(s.camera, moved, "a moved camera stays");
}

#[test]
fn zoom_at_the_cursor_keeps_the_point_under_it() {
    let mut s = opened("plant2");
    let view = s.splat_view();
    // A point of the attractor and where it is on screen.
    let p = attractor_sample(s.compiled.as_ref().unwrap(), 5)[100];
    // (It lies off the target's plane, where the zoom is exact, so it moves a little.)
    let at = project(&view, p.as_dvec3()).unwrap();
    let cursor = [at.x + s.view_origin_px[0], at.y + s.view_origin_px[1]];
    s.apply([Command::ZoomAt { steps: 3.0, cursor_px: cursor }]);
    let after = project(&s.splat_view(), p.as_dvec3()).unwrap();
    // Zooming towards the centre would move a point 0.6 of its distance from the centre outward.
    let centre = Vec2::new(s.width_px, s.height_px) * 0.5;
    let naive = centre + (at - centre) / 0.9f32.powi(3);
    assert!(
        (after - at).length() < 0.25 * (naive - at).length().max(4.0),
        "the point under the cursor moved from {at} to {after} (a centre zoom: {naive})"
    );
}

#[test]
fn views_along_the_axes_frame_the_attractor_as_f_does() {
    use nlifs::viewer::command::ViewAxis;
    for name in ["plant1", "twisting"] {
        for axis in [ViewAxis::Front, ViewAxis::Right, ViewAxis::Top, ViewAxis::Bottom] {
            let mut s = opened(name);
            // Far in and off to the side first: a view that kept the distance cropped the
            // attractor (a tall plant seen from the top, zoomed in).
            s.apply([Command::Zoom { steps: 10.0 }, Command::Pan { dx_px: 120.0, dy_px: 40.0 }]);
            s.apply([Command::ViewAlong(axis)]);
            assert_eq!((s.camera.yaw_deg, s.camera.pitch_deg), axis.angles_deg(), "{name} {axis:?}");
            let (w, h) = (s.width_px, s.height_px);
            let (lo, hi) = extent(&s);
            // Framing fits the fixed framing sample (65,536 points); the 64 other samples here
            // reach a few pixels past its hull at the tips (plant1's stem: 4.8 px of 720).
            let slack = 0.01 * w.max(h);
            assert!(
                lo.x >= -slack && lo.y >= -slack && hi.x <= w + slack && hi.y <= h + slack,
                "{name} {axis:?}: the attractor spans {lo}..{hi} in a {w}×{h} view"
            );
            assert!((hi.x - lo.x) / w > 0.6 || (hi.y - lo.y) / h > 0.6, "{name} {axis:?}: spans only {lo}..{hi}");
            // The same camera as F from those angles.
            let viewed = s.camera;
            s.apply([Command::FrameAttractor]);
            assert_eq!(s.camera, viewed, "{name} {axis:?}");
        }
    }
}

#[test]
fn animate_and_a_resize_keep_the_users_framed_camera() {
    // Orbit, then F (the camera is framed again, from the user's angles), then the panel's
    // Animate: the timeline panel that appears shrinks the view, and the resize used to frame
    // the scene's camera, turning the view back to the scene's angles.
    let mut s = opened("plant2");
    let scene_angles = (s.camera.yaw_deg, s.camera.pitch_deg);
    s.apply([Command::Orbit { dx_px: 150.0, dy_px: -60.0 }, Command::FrameAttractor]);
    let angles = (s.camera.yaw_deg, s.camera.pitch_deg);
    assert_ne!(angles, scene_angles);
    s.apply([Command::SetTime(0.0), Command::AddOrUpdateKey, Command::SetDuration(4.0)]);
    assert!(s.scene.timeline.is_some());
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 610.0] }]);
    assert_eq!((s.camera.yaw_deg, s.camera.pitch_deg), angles, "the user's angles stay");
    // Still framed for the new view, as F frames it there.
    let resized = s.camera;
    s.apply([Command::FrameAttractor]);
    assert_eq!(s.camera, resized);
    // A camera moved after the framing stays as it is.
    s.apply([Command::Orbit { dx_px: 20.0, dy_px: 0.0 }]);
    let moved = s.camera;
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 720.0] }]);
    assert_eq!(s.camera, moved);
    // A view along an axis is refitted on a resize as F is.
    s.apply([Command::ViewAlong(nlifs::viewer::command::ViewAxis::Top)]);
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [600.0, 720.0] }]);
    let refitted = s.camera;
    s.apply([Command::FrameAttractor]);
    assert_eq!(s.camera, refitted);
    assert_eq!((s.camera.yaw_deg, s.camera.pitch_deg), nlifs::viewer::command::ViewAxis::Top.angles_deg());
}

/// A scene that places its camera (an imported flame) frames its render's image: in a view
/// narrower than the image the camera moves back until the image's width fits (the sides were
/// cut off: a 1920×1080 flame in a 743×720 view showed 58 % of its width); in a wider view it
/// is the scene's camera as it is.
#[test]
fn a_placed_camera_fits_the_renders_width_in_a_narrow_view() {
    let text = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n\
        [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n\
        [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]\n\
        [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0, 0.5]\n\
        [camera]\ntarget = [0.5, 0.5, 0]\ndistance = 40\nprojection = \"parallel\"\n\
        [render]\nwidth = 1920\nheight = 1080\n";
    let scene = nlifs::scene::Scene::parse(text, "placed").unwrap();
    let mut s = ViewerState::new(scene, None, LiveSettings::default());
    let render_aspect = 1920.0f32 / 1080.0;
    for ([w, h], distance) in
        [([743.0, 720.0], 40.0 * render_aspect / (743.0 / 720.0)), ([1600.0, 600.0], 40.0), ([1920.0, 1080.0], 40.0)]
    {
        s.apply([Command::SetViewRect { origin_px: [0.0, 0.0], size_px: [w, h] }]);
        assert!(
            (s.camera.distance - distance).abs() < 1e-3 * distance,
            "{w}×{h}: {} for {distance}",
            s.camera.distance
        );
        // The render's image (its visible height at distance 40, its aspect) lies in the view.
        let half_h = 40.0 * (0.5 * s.camera.fov_y_deg.to_radians()).tan();
        let view = s.splat_view();
        for (dx, dy) in [(-1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (1.0, -1.0)] {
            let corner = glam::DVec3::new(
                0.5 + 0.999 * dx * f64::from(half_h * render_aspect),
                0.5 + 0.999 * dy * f64::from(half_h),
                0.0,
            );
            assert!(
                project(&view, corner).is_some(),
                "{w}×{h}: corner {corner} of the render's image outside the view"
            );
        }
    }
}
