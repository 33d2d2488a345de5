//! The viewer's state and commands, headless: a bad scene keeps the last good one with a
//! located error, edits recompile, camera moves do not, stale indices are ignored. (These sit
//! here rather than next to `src/viewer/apply.rs` because the foundation's lib tests do not
//! compile at e5acdfd.)

mod common;

use nlifs::live::LiveSettings;
use nlifs::viewer::apply::Changes;
use nlifs::viewer::command::Command;
use nlifs::viewer::state::ViewerState;

fn state() -> ViewerState {
    ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default())
}

#[test]
fn bad_scene_keeps_the_last_good_one() {
    let mut s = state();
    let before = s.scene.clone();
    let dir = common::temp_dir("viewer-test");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "version = 1\n[grid]\nx = [0, 1]\ny = \"oops\"\n").unwrap();
    let changes = s.apply([Command::OpenScene(bad.clone())]);
    assert_eq!(changes, Changes::default());
    assert_eq!(s.scene, before);
    let err = s.error.clone().unwrap();
    assert!(err.contains("bad.toml:4"), "{err}");
    let changes = s.apply([Command::OpenScene(dir.join("missing.toml"))]);
    assert!(!changes.scene_replaced);
    assert_eq!(s.scene, before);
}

#[test]
fn edits_recompile_and_camera_moves_do_not() {
    let mut s = state();
    let changes = s.apply([Command::Orbit { dx_px: 10.0, dy_px: 0.0 }]);
    assert!(changes.camera && !changes.scene_edited);
    let n = s.compiled.as_ref().unwrap().functions.len();
    let changes = s.apply([Command::SetFunctionEnabled { function: 0, enabled: false }]);
    assert!(changes.scene_edited);
    assert_eq!(s.compiled.as_ref().unwrap().functions.len(), n - 1);
    // Out-of-range indices from a stale UI are ignored.
    let changes = s.apply([Command::SetFunctionEnabled { function: 99, enabled: false }]);
    assert!(!changes.scene_edited);
}

#[test]
fn the_first_view_rect_frames_the_attractor_in_it_and_later_ones_keep_the_camera() {
    use nlifs::chaos_game::attractor_sample;
    use nlifs::viewer::picking::project;
    let mut s = state();
    // A narrow view (a wide panel on the left): framing for the default 16:9 window would put
    // the plant's sides outside it.
    let (w, h) = (200.0, 650.0);
    let changes = s.apply([Command::SetViewRect { origin_px: [371.0, 0.0], size_px: [w, h] }]);
    assert!(changes.camera);
    assert_eq!((s.width_px, s.height_px, s.view_origin_px), (w, h, [371.0, 0.0]));
    let view = s.splat_view();
    let sample = attractor_sample(s.compiled.as_ref().unwrap(), s.live.draw.seed);
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
    for p in &sample {
        let q = project(&view, p.as_dvec3()).unwrap();
        lo = lo.min(q);
        hi = hi.max(q);
    }
    // `fit_points` leaves a 5% margin and fills the view along one axis.
    assert!(lo.x >= 0.0 && lo.y >= 0.0 && hi.x <= w && hi.y <= h, "sample spans {lo}..{hi} in a {w}×{h} view");
    assert!((hi.x - lo.x) / w > 0.8 || (hi.y - lo.y) / h > 0.8, "sample spans only {lo}..{hi} in a {w}×{h} view");
    // Once the user moved the camera, a later size change (panel resized) keeps it; the same
    // rect changes nothing.
    s.apply([Command::Orbit { dx_px: 5.0, dy_px: 0.0 }]);
    let camera = s.camera;
    let changes = s.apply([Command::SetViewRect { origin_px: [300.0, 0.0], size_px: [600.0, h] }]);
    assert!(changes.camera);
    assert_eq!(s.camera, camera);
    assert_eq!(s.apply([Command::SetViewRect { origin_px: [300.0, 0.0], size_px: [600.0, h] }]), Changes::default());
}
