//! Grid editing, undo / redo, keys at the playhead, playback and saving in the viewer's plain
//! state: commands in, scene out, no window and no GPU.

mod common;

use glam::DVec3;
use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::scene::spec::FunctionDef;
use nlifs::scene::timeline::{Ease, Interpolation, LoopMode};
use nlifs::viewer::command::Command;
use nlifs::viewer::picking;
use nlifs::viewer::state::ViewerState;

fn state_for(file: &str) -> ViewerState {
    let path = common::repo_path("scenes").join(file);
    let scene = Scene::load(&path).unwrap();
    ViewerState::new(scene, Some(path), LiveSettings::default())
}

fn grid_points(s: &ViewerState, f: usize) -> Vec<DVec3> {
    s.function_grid(f).unwrap().points
}

/// The projected pixel position of a function's grid point in the state's view.
fn pixel_of(s: &ViewerState, f: usize, i: usize) -> glam::Vec2 {
    picking::project(&s.splat_view(), grid_points(s, f)[i]).unwrap()
}

#[test]
fn a_drag_gesture_is_one_undo_step_and_undo_redo_restore_exactly() {
    let mut s = state_for("plant1.toml");
    s.apply([Command::SetGridOverlay(true)]);
    let original = s.scene.clone();
    let (f, i) = (3, 2);
    let start = grid_points(&s, f)[i];
    let at = pixel_of(&s, f, i);
    // Picking at the point's projection finds it.
    assert_eq!(s.pick_point([at.x + 2.0, at.y - 1.0]), Some((f, i)));
    s.apply([Command::BeginPointDrag { function: f, point: i }]);
    let mut changes = Vec::new();
    for k in 1..=10 {
        changes.push(s.apply([Command::DragPoint { delta_px: [-10.0 * k as f32, -8.0 * k as f32] }]));
    }
    assert!(
        changes.iter().all(|c| c.scene_edited && !c.scene_replaced),
        "every drag step is a scene edit that keeps the points"
    );
    let moved = grid_points(&s, f)[i];
    // The point followed the cursor in the view plane: its projection moved by the cursor's
    // delta (to 0.05 px: f32 projection of coordinates ~100).
    let now = pixel_of(&s, f, i);
    assert!((now - (at + glam::Vec2::new(-100.0, -80.0))).length() < 0.05, "{at} -> {now}");
    assert_ne!(moved, start);
    // Other points did not move.
    let others: Vec<_> = grid_points(&s, f).into_iter().enumerate().filter(|&(k, _)| k != i).collect();
    let FunctionDef::Grid { points: orig } = &original.functions[f].def else { panic!() };
    assert!(others.iter().all(|&(k, p)| p == orig[k]));
    s.apply([Command::EndGesture]);
    let dragged = s.scene.clone();
    assert!(s.history.can_undo());
    s.apply([Command::Undo]);
    assert_eq!(s.scene, original, "one undo takes back the whole drag, exactly");
    assert!(!s.history.can_undo());
    s.apply([Command::Redo]);
    assert_eq!(s.scene, dragged);
    assert_eq!(grid_points(&s, f)[i], moved);
}

#[test]
fn axis_lock_moves_along_one_axis_and_numeric_entry_is_one_step() {
    let mut s = state_for("plant1.toml");
    s.apply([Command::SetGridOverlay(true), Command::SetAxisLock(Some(1))]);
    let start = grid_points(&s, 0)[5];
    s.apply([
        Command::BeginPointDrag { function: 0, point: 5 },
        Command::DragPoint { delta_px: [30.0, -40.0] },
        Command::EndGesture,
    ]);
    let p = grid_points(&s, 0)[5];
    assert_eq!((p.x, p.z), (start.x, start.z));
    assert!(p.y > start.y, "dragging up raises y: {start} -> {p}");
    let before = s.scene.clone();
    for k in 1..=5 {
        s.apply([Command::SetPoint { function: 0, point: 5, p: DVec3::new(1.0 * k as f64, 2.0, 3.0) }]);
    }
    s.apply([Command::EndGesture]);
    assert_eq!(grid_points(&s, 0)[5], DVec3::new(5.0, 2.0, 3.0));
    s.apply([Command::Undo]);
    assert_eq!(s.scene, before);
    // Builder grids are read-only; bad indices are ignored.
    s.apply([
        Command::SetPoint { function: 99, point: 0, p: DVec3::ZERO },
        Command::SetPoint { function: 0, point: 9999, p: DVec3::ZERO },
    ]);
    s.apply([Command::EndGesture]);
    assert_eq!(s.scene, before);
}

#[test]
fn keys_at_the_playhead_add_edit_delete_and_undo() {
    let mut s = state_for("twist-anim.toml");
    let original = s.scene.clone();
    let n = s.scene.timeline.as_ref().unwrap().keys.len();
    s.apply([Command::SetTime(0.7)]);
    assert_eq!(s.key_at_playhead(), None);
    s.apply([Command::AddOrUpdateKey]);
    let tl = s.scene.timeline.as_ref().unwrap();
    assert_eq!(tl.keys.len(), n + 1);
    let k = s.key_at_playhead().unwrap();
    assert_eq!(tl.keys[k].t_secs, 0.7);
    // The new key holds the values the animation had there: the scene at 0.7 is unchanged.
    let at =
        |s: &ViewerState| (0..s.scene.functions.len()).map(|f| s.scene.function_def_at(f, 0.7)).collect::<Vec<_>>();
    assert_eq!(at(&s), (0..original.functions.len()).map(|f| original.function_def_at(f, 0.7)).collect::<Vec<_>>());
    s.apply([Command::SetKeyShape { key: k, interpolation: Interpolation::Linear, ease: Ease::InOut }]);
    let key = &s.scene.timeline.as_ref().unwrap().keys[k];
    assert_eq!((key.interpolation, key.ease), (Interpolation::Linear, Ease::InOut));
    s.apply([Command::DeleteKeyAtPlayhead]);
    assert_eq!(s.scene.timeline.as_ref().unwrap().keys.len(), n);
    s.apply([Command::Undo, Command::Undo, Command::Undo]);
    assert_eq!(s.scene, original);
}

#[test]
fn grid_edits_on_an_animated_scene_go_to_a_key_at_the_playhead() {
    let mut s = state_for("plant1.toml");
    let original = s.scene.clone();
    // Make plant1 animated by adding a key at t = 0, then edit at t = 2 (a new key).
    s.apply([Command::AddOrUpdateKey, Command::SetDuration(4.0), Command::SetTime(2.0)]);
    let keys = s.scene.timeline.as_ref().unwrap().keys.len();
    s.apply([Command::SetPoint { function: 1, point: 0, p: DVec3::new(1.0, 2.0, 3.0) }, Command::EndGesture]);
    let tl = s.scene.timeline.as_ref().unwrap();
    assert_eq!(tl.keys.len(), keys + 1);
    assert_eq!(s.key_at_playhead().map(|k| tl.keys[k].t_secs), Some(2.0));
    assert_eq!(s.scene.function_def_at(1, 2.0), {
        let FunctionDef::Grid { points } = &original.functions[1].def else { panic!() };
        let mut p = points.clone();
        p[0] = DVec3::new(1.0, 2.0, 3.0);
        FunctionDef::Grid { points: p }
    });
    // The base scene is untouched.
    assert_eq!(s.scene.functions[1].def, original.functions[1].def);
    s.apply([Command::Undo]);
    assert_eq!(s.scene.timeline.as_ref().unwrap().keys.len(), keys);
}

#[test]
fn playing_advances_time_and_wraps_per_loop_mode() {
    let mut s = state_for("twist-anim.toml");
    let d = s.scene.timeline.as_ref().unwrap().duration_secs;
    assert_eq!(s.scene.timeline.as_ref().unwrap().loop_mode, LoopMode::Loop);
    // Not playing: ticks do nothing.
    assert!(!s.apply([Command::Tick { dt_secs: 0.5 }]).scene_edited);
    assert_eq!(s.t_secs, 0.0);
    s.apply([Command::SetPlaying(true), Command::SetSpeed(2.0)]);
    let c = s.apply([Command::Tick { dt_secs: 0.25 }]);
    assert!(c.scene_edited && !c.scene_replaced, "time moves the attractor as an edit (points kept)");
    assert_eq!(s.t_secs, 0.5);
    s.apply([Command::Tick { dt_secs: d / 2.0 }]);
    assert!((s.t_secs - 0.5).abs() < 1e-12, "loop wraps modulo the duration: {}", s.t_secs);
    s.apply([Command::SetLoopMode(LoopMode::PingPong), Command::SetSpeed(1.0), Command::SetTime(d - 0.5)]);
    s.apply([Command::Tick { dt_secs: 1.0 }]);
    assert!((s.t_secs - (d + 0.5)).abs() < 1e-12);
    assert!((s.playhead_secs() - (d - 0.5)).abs() < 1e-12, "ping-pong runs back");
    s.apply([Command::Tick { dt_secs: d }]);
    assert!((s.t_secs - 0.5).abs() < 1e-12, "and wraps after twice the duration: {}", s.t_secs);
    s.apply([Command::SetLoopMode(LoopMode::Once), Command::SetTime(d - 0.1)]);
    assert!(s.playback.playing);
    s.apply([Command::Tick { dt_secs: 1.0 }]);
    assert_eq!(s.t_secs, d);
    assert!(!s.playback.playing, "once stops at the end");
    // Playing again from the end starts over.
    s.apply([Command::SetPlaying(true)]);
    assert_eq!(s.t_secs, 0.0);
    // The compiled IFS follows time.
    s.apply([Command::SetLoopMode(LoopMode::Loop)]);
    let at0 = s.compiled.clone().unwrap();
    s.apply([Command::Tick { dt_secs: 1.0 }]);
    assert_ne!(s.compiled.as_ref().unwrap().cells.len(), 0);
    assert_ne!(format!("{:?}", s.compiled.as_ref().unwrap().cells), format!("{:?}", at0.cells));
}

#[test]
fn save_writes_a_file_that_loads_back_equal() {
    let mut s = state_for("plant1.toml");
    s.apply([Command::SetPoint { function: 2, point: 3, p: DVec3::new(0.125, 7.5, -3.25) }, Command::EndGesture]);
    let dir = common::temp_dir("viewer-editing");
    let path = dir.join("edited.toml");
    let c = s.apply([Command::SaveScene(path.clone())]);
    assert!(!c.scene_replaced && s.error.is_none(), "{:?}", s.error);
    let loaded = Scene::load(&path).unwrap();
    assert_eq!(loaded, s.scene);
    // Saving is not a change on disk to reload.
    assert_eq!(s.poll_file(), None);
    // An unwritable path is an error message, not a panic, and the scene stays.
    let before = s.scene.clone();
    // (its parent is a file)
    s.apply([Command::SaveScene(path.join("x.toml"))]);
    assert!(s.error.is_some());
    assert_eq!(s.scene, before);
}

/// Polls the jobs the way the event loop does until none runs (at most 120 s).
fn wait_jobs(jobs: &mut nlifs::viewer::jobs::Jobs, ctx: &egui::Context) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while jobs.poll(ctx) {
        assert!(std::time::Instant::now() < deadline, "job did not finish");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn ray_trace_and_record_jobs_run_in_the_background_and_cancel() {
    use nlifs::viewer::command::{RaytraceForm, RecordForm};
    let dir = common::temp_dir("viewer-jobs");
    let ctx = egui::Context::default();
    let mut jobs = nlifs::viewer::jobs::Jobs::default();

    // Ray-trace this view: the viewer's camera, a small image, written as PNG and shown.
    let mut s = state_for("tapering.toml");
    let png = dir.join("rt.png");
    let form = RaytraceForm { depth: Some(2), spp: 1, width: 64, height: 48, png_text: png.display().to_string() };
    let changes =
        s.apply([Command::SetRaytraceForm(form), Command::Orbit { dx_px: 30.0, dy_px: 0.0 }, Command::StartRaytrace]);
    for r in changes.jobs {
        jobs.handle(r);
    }
    wait_jobs(&mut jobs, &ctx);
    assert_eq!(jobs.view.raytrace_image.map(|(_, size)| size), Some([64, 48]), "{:?}", jobs.view.raytrace_message);
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // The same camera as the viewer's: identical to rendering with it directly.
    let direct = nlifs::raytrace::render(
        &s.scene,
        0.0,
        Some(s.camera),
        &nlifs::raytrace::RaytraceSettings { width: 64, height: 48, spp: 1, depth: 2, ..Default::default() },
        &|_, _| {},
        &std::sync::atomic::AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(img, direct.image);

    // A cancelled ray-trace ends with a message and no new image.
    let big = RaytraceForm {
        depth: Some(8),
        spp: 16,
        width: 1024,
        height: 768,
        png_text: dir.join("big.png").display().to_string(),
    };
    for r in s.apply([Command::SetRaytraceForm(big), Command::StartRaytrace, Command::CancelRaytrace]).jobs {
        jobs.handle(r);
    }
    wait_jobs(&mut jobs, &ctx);
    assert!(jobs.view.raytrace_message.as_deref().unwrap_or("").contains("ancel"), "{:?}", jobs.view.raytrace_message);
    assert!(!dir.join("big.png").exists());

    // Record the timeline (CPU): every frame written.
    let mut s = state_for("twist-anim.toml");
    let out = dir.join("frames");
    let form = RecordForm {
        width: 32,
        height: 24,
        fps: 2.0,
        points_per_frame: 2000,
        dir_text: out.display().to_string(),
        ..Default::default()
    };
    for r in s.apply([Command::SetRecordForm(form.clone()), Command::StartRecord]).jobs {
        jobs.handle(r);
    }
    wait_jobs(&mut jobs, &ctx);
    assert_eq!(jobs.view.record_message.as_deref(), Some(format!("recorded 8 frames to {}", out.display()).as_str()));
    assert!((0..8).all(|k| nlifs::record::is_complete_frame(&nlifs::record::frame_path(&out, k), 32, 24)));
    // Cancelled right away: stops between frames.
    let out2 = dir.join("frames2");
    let form = RecordForm { fps: 200.0, dir_text: out2.display().to_string(), ..form };
    for r in s.apply([Command::SetRecordForm(form), Command::StartRecord, Command::CancelRecord]).jobs {
        jobs.handle(r);
    }
    wait_jobs(&mut jobs, &ctx);
    assert!(
        jobs.view.record_message.as_deref().unwrap_or("").starts_with("cancelled after"),
        "{:?}",
        jobs.view.record_message
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_keyed_camera_is_followed_only_when_asked() {
    let mut s = state_for("twist-anim.toml");
    let yaw0 = s.camera.yaw_deg;
    s.apply([Command::SetTime(1.0)]);
    assert_eq!(s.camera.yaw_deg, yaw0, "the user's camera stays by default");
    let c = s.apply([Command::SetFollowCamera(true)]);
    assert!(c.camera);
    // twist-anim's keys turn the camera 90° a second.
    let expected = s.scene.camera_at(1.0).yaw_deg.unwrap() as f32;
    assert!((s.camera.yaw_deg - expected).abs() < 1e-3, "{} vs {expected}", s.camera.yaw_deg);
    assert!((s.camera.yaw_deg - yaw0).abs() > 45.0);
}
