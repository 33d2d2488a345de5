//! The viewer's state and commands, headless: a bad scene keeps the last good one with a
//! located error, edits recompile, camera moves do not, stale indices are ignored. (These sit
//! here rather than next to `src/viewer/state.rs` because the foundation's lib tests do not
//! compile at e5acdfd.)

use nlifs::gpu::live::LiveSettings;
use nlifs::viewer::state::{Changes, Command, ViewerState};

fn state() -> ViewerState {
    ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default())
}

#[test]
fn bad_scene_keeps_the_last_good_one() {
    let mut s = state();
    let before = s.scene.clone();
    let dir = std::env::temp_dir().join(format!("nlifs-viewer-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
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

