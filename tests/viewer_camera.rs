//! The viewer's camera as a daily tool, tested on its plain state: a left drag pans in a 2D
//! scene (orbits in 3D); "Save view" puts the view's camera into the scene (saved with it, one
//! undo step); "Key camera" keys it at the playhead.

mod common;

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::Command;
use nlifs::viewer::pointer::Button;
use nlifs::viewer::state::ViewerState;

fn opened(name: &str) -> ViewerState {
    let path = common::scene_path(name);
    let mut s = ViewerState::new(Scene::load(&path).unwrap(), Some(path), LiveSettings::default());
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 720.0] }]);
    s
}

#[test]
fn a_left_drag_pans_in_a_2d_scene_and_orbits_in_3d() {
    let mut flat = opened("sierpinski");
    assert_eq!(flat.scene.domain.dimension(), 2);
    let before = flat.camera;
    let drag = flat.camera_drag(Button::Left, 40.0, -25.0);
    assert_eq!(drag, Command::Pan { dx_px: 40.0, dy_px: -25.0 });
    flat.apply([drag]);
    assert_eq!((flat.camera.yaw_deg, flat.camera.pitch_deg), (before.yaw_deg, before.pitch_deg), "no orbit");
    assert!(flat.camera.target.distance(before.target) > 0.0, "the target moved: a pan");
    assert_eq!(flat.camera_drag(Button::Right, 1.0, 2.0), Command::Pan { dx_px: 1.0, dy_px: 2.0 });

    let deep = opened("plant1");
    assert_eq!(deep.scene.domain.dimension(), 3);
    assert_eq!(deep.camera_drag(Button::Left, 40.0, -25.0), Command::Orbit { dx_px: 40.0, dy_px: -25.0 });
    assert_eq!(deep.camera_drag(Button::Middle, 40.0, -25.0), Command::Pan { dx_px: 40.0, dy_px: -25.0 });
}

/// The scene's copy in a fresh folder (the test saves over it).
fn scratch(name: &str, scene: &str) -> (common::TempDir, std::path::PathBuf) {
    let dir = common::temp_dir(&format!("viewer-camera-{name}"));
    let path = dir.join(format!("{scene}.toml"));
    std::fs::copy(common::scene_path(scene), &path).unwrap();
    (dir, path)
}

fn close(a: nlifs::camera::OrbitCamera, b: nlifs::camera::OrbitCamera) -> bool {
    a.target.distance(b.target) < 1e-4 * (1.0 + a.distance)
        && (a.yaw_deg - b.yaw_deg).abs() < 1e-3
        && (a.pitch_deg - b.pitch_deg).abs() < 1e-3
        && (a.distance - b.distance).abs() < 1e-4 * a.distance
        && a.projection == b.projection
}

#[test]
fn save_view_puts_the_view_in_the_scene_file_as_one_undo_step() {
    let (_dir, path) = scratch("save-view", "plant1");
    let mut s = ViewerState::new(Scene::load(&path).unwrap(), Some(path.clone()), LiveSettings::default());
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 720.0] }]);
    let before = s.scene.camera.clone();
    s.apply([Command::Orbit { dx_px: 60.0, dy_px: 20.0 }, Command::Pan { dx_px: 15.0, dy_px: -8.0 }]);
    let view = s.camera;
    s.apply([Command::SaveView]);
    assert!(s.modified(), "the scene holds a new camera");
    assert_eq!(s.scene.camera, s.camera_spec());
    assert_eq!(s.camera, view, "saving the view does not move it");
    // One undo step, redone again.
    s.apply([Command::Undo]);
    assert_eq!(s.scene.camera, before);
    assert!(!s.modified());
    s.apply([Command::Redo]);
    assert_eq!(s.scene.camera, s.camera_spec());
    // Saving writes it; the file opens at that view.
    s.apply([Command::SaveScene(path.clone())]);
    assert!(!s.modified(), "{:?}", s.error);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(&format!("yaw_deg = {}", view.yaw_deg)), "short decimals in the file:\n{text}");
    let reopened = opened_at(&path);
    assert!(close(reopened.camera, view), "{:?} != {view:?}", reopened.camera);
}

fn opened_at(path: &std::path::Path) -> ViewerState {
    let mut s = ViewerState::new(Scene::load(path).unwrap(), Some(path.to_path_buf()), LiveSettings::default());
    s.apply([Command::SetViewRect { origin_px: [310.0, 0.0], size_px: [970.0, 720.0] }]);
    s
}

#[test]
fn key_camera_keys_the_view_at_the_playhead_as_one_undo_step() {
    let mut s = opened("twist-anim");
    let keys = s.scene.timeline.as_ref().unwrap().keys.clone();
    // Between two keys: a new key holding only the camera.
    s.apply([Command::SetTime(1.5), Command::Orbit { dx_px: 80.0, dy_px: 30.0 }]);
    let view = s.camera;
    s.apply([Command::KeyCamera]);
    assert!(s.error.is_none(), "{:?}", s.error);
    let tl = s.scene.timeline.as_ref().unwrap();
    assert_eq!(tl.keys.len(), keys.len() + 1);
    let k = s.key_at_playhead().expect("a key at the playhead");
    assert_eq!(tl.keys[k].t_secs, 1.5);
    assert_eq!(tl.keys[k].camera, s.camera_spec());
    assert!(tl.keys[k].functions.is_empty(), "a camera key only");
    // Following the keys' camera at the playhead gives the view back.
    s.apply([Command::SetFollowCamera(true)]);
    assert!(close(s.camera, view), "{:?} != {view:?}", s.camera);
    s.apply([Command::SetFollowCamera(false)]);
    s.apply([Command::Undo]);
    assert_eq!(s.scene.timeline.as_ref().unwrap().keys, keys, "one undo step removes it");

    // On a key: that key's camera changes, its functions stay.
    s.apply([Command::SetTime(keys[0].t_secs), Command::Orbit { dx_px: -50.0, dy_px: 10.0 }, Command::KeyCamera]);
    let tl = s.scene.timeline.as_ref().unwrap();
    assert_eq!(tl.keys.len(), keys.len());
    assert_eq!(tl.keys[0].camera, s.camera_spec());
    assert_eq!(tl.keys[0].functions, keys[0].functions);
    s.apply([Command::Undo]);
    assert_eq!(s.scene.timeline.as_ref().unwrap().keys, keys);

    // No timeline: refused with a message, nothing changed.
    let mut still = opened("plant1");
    still.apply([Command::KeyCamera]);
    assert!(!still.modified());
    assert!(still.error.as_deref().is_some_and(|e| e.contains("timeline")));
}
