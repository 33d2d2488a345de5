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
