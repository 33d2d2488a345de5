//! Where the viewer's jobs write, tested on its plain state and its job runner: "Ray-trace this
//! view" and "Record timeline" write next to the scene (the working folder for the built-in
//! scene, as `F12` does), numbered so that a run never replaces an earlier one, and the notice
//! a finished job leaves (the toast) names the file by its absolute path; *Show folder* finds
//! the desktop's opener on `PATH`. And the ray-trace form's default depth follows the scene's
//! contraction within the node budget.

mod common;

use std::path::{Path, PathBuf};

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::{Command, JobRequest};
use nlifs::viewer::job_plan::{self, DEFAULT_DEPTH_NODES, LEAF_TARGET_PX, MAX_DEPTH};
use nlifs::viewer::jobs::{Jobs, find_on_path};
use nlifs::viewer::state::ViewerState;

/// The shipped scene `name` copied into a fresh folder, opened from there.
fn opened_in(dir: &Path, name: &str) -> ViewerState {
    let path = dir.join(format!("{name}.toml"));
    std::fs::copy(common::scene_path(name), &path).unwrap();
    ViewerState::new(Scene::load(&path).unwrap(), Some(path), LiveSettings::default())
}

/// The folder as the viewer names it (`dir` may be reached through a link, as /tmp can be).
fn canonical(dir: &Path) -> PathBuf {
    std::fs::canonicalize(dir).unwrap()
}

/// Polls the jobs the way the event loop does until none runs (at most 120 s).
fn wait(jobs: &mut Jobs, ctx: &egui::Context) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while jobs.poll(ctx) {
        assert!(std::time::Instant::now() < deadline, "the job did not finish");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn the_default_outputs_go_next_to_the_scene_numbered() {
    let dir = common::temp_dir("viewer-outputs-next");
    let mut s = opened_in(&dir, "twist-anim");
    s.apply([Command::SetToolSupport { native_dialogs: false, ffmpeg: true }]);
    let here = canonical(&dir);
    assert_eq!(s.raytrace_png(), here.join("twist-anim-raytrace-1.png"));
    let mut form = s.record_form.clone();
    form.video = true;
    s.apply([Command::SetRecordForm(form)]);
    let plan = s.record_plan().unwrap();
    assert_eq!(plan.dir, here.join("twist-anim-record-1"));
    assert_eq!(plan.video, Some(here.join("twist-anim-record-1.mp4")));

    // A taken name moves on to the next number; the folder and its video keep one number, and
    // either being there skips it.
    std::fs::write(here.join("twist-anim-raytrace-1.png"), b"earlier").unwrap();
    assert_eq!(s.raytrace_png(), here.join("twist-anim-raytrace-2.png"));
    std::fs::write(here.join("twist-anim-record-1.mp4"), b"earlier").unwrap();
    let plan = s.record_plan().unwrap();
    assert_eq!((plan.dir, plan.video), (here.join("twist-anim-record-2"), Some(here.join("twist-anim-record-2.mp4"))));
    std::fs::create_dir(here.join("twist-anim-record-2")).unwrap();
    assert_eq!(s.record_plan().unwrap().dir, here.join("twist-anim-record-3"));

    // A typed relative name is taken from the scene's folder; a typed folder names its video.
    let mut form = s.record_form.clone();
    form.dir_text = "frames".into();
    s.apply([Command::SetRecordForm(form)]);
    let plan = s.record_plan().unwrap();
    assert_eq!((plan.dir, plan.video), (here.join("frames"), Some(here.join("frames.mp4"))));

    // F12 and the jobs share the folder, for a scene file and for the built-in scene.
    let shot = s.apply([Command::ScreenshotNextToScene]).screenshot.unwrap();
    assert_eq!(shot.parent(), s.raytrace_png().parent());
    let builtin = ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default());
    let mut b = builtin.clone();
    let shot = b.apply([Command::ScreenshotNextToScene]).screenshot.unwrap();
    let png = builtin.raytrace_png();
    assert_eq!(shot.parent(), png.parent());
    assert!(png.is_absolute(), "{}", png.display());
    assert_eq!(png.parent().unwrap(), canonical(&std::env::current_dir().unwrap()));
    assert!(png.file_name().unwrap().to_string_lossy().starts_with("nlifs-raytrace-"), "{}", png.display());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_second_ray_trace_does_not_overwrite_the_first_and_the_notice_names_the_absolute_path() {
    let dir = common::temp_dir("viewer-outputs-twice");
    let here = canonical(&dir);
    let mut s = opened_in(&dir, "tapering");
    let mut form = s.raytrace_form.clone();
    (form.depth, form.spp, form.width, form.height) = (Some(1), 1, 32, 24);
    s.apply([Command::SetRaytraceForm(form)]);
    let ctx = egui::Context::default();
    let mut jobs = Jobs::default();
    let mut notices = Vec::new();
    for _ in 0..2 {
        let changes = s.apply([Command::StartRaytrace]);
        assert_eq!(changes.jobs.len(), 1, "{:?} {:?}", changes.jobs, s.error);
        for r in changes.jobs {
            jobs.handle(r);
        }
        wait(&mut jobs, &ctx);
        notices.extend(jobs.take_notices());
    }
    let first = here.join("tapering-raytrace-1.png");
    let second = here.join("tapering-raytrace-2.png");
    assert!(first.is_file() && second.is_file(), "{notices:?}");
    assert_eq!(notices.len(), 2, "{notices:?}");
    for (notice, png) in notices.iter().zip([&first, &second]) {
        assert!(notice.contains(&format!("saved {}", png.display())), "{notice:?} does not name {}", png.display());
        assert!(!notice.contains("replacing"), "{notice:?}");
    }
    // The panel's Show folder names the folder.
    assert_eq!(jobs.view.raytrace_folder.as_deref(), Some(here.as_path()));

    // A typed name that is there is replaced, and the notice says so.
    let mut form = s.raytrace_form.clone();
    form.png_text = "tapering-raytrace-1.png".into();
    s.apply([Command::SetRaytraceForm(form)]);
    for r in s.apply([Command::StartRaytrace]).jobs {
        jobs.handle(r);
    }
    wait(&mut jobs, &ctx);
    let notice = jobs.take_notices().join(" ");
    assert!(notice.contains(&format!("saved {}, replacing", first.display())), "{notice:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_recording_goes_next_to_the_scene_and_a_second_one_beside_it() {
    let dir = common::temp_dir("viewer-outputs-record");
    let here = canonical(&dir);
    let mut s = opened_in(&dir, "twist-anim");
    let mut form = s.record_form.clone();
    (form.width, form.height, form.fps, form.points_per_frame, form.frame_range) = (16, 16, 2.0, 500, Some((0, 2)));
    s.apply([Command::SetRecordForm(form)]);
    let ctx = egui::Context::default();
    let mut jobs = Jobs::default();
    let mut notices = Vec::new();
    for _ in 0..2 {
        for r in s.apply([Command::StartRecord]).jobs {
            jobs.handle(r);
        }
        wait(&mut jobs, &ctx);
        notices.extend(jobs.take_notices());
    }
    for (n, notice) in notices.iter().enumerate() {
        let folder = here.join(format!("twist-anim-record-{}", n + 1));
        assert_eq!(notice, &format!("recorded 2 frames to {}", folder.display()));
        assert!(nlifs::record::is_complete_frame(&nlifs::record::frame_path(&folder, 1), 16, 16));
    }
    assert_eq!(jobs.view.record_folder, Some(here.join("twist-anim-record-2")));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn show_folder_finds_the_opener_on_path_and_is_a_job_request() {
    let dir = common::temp_dir("viewer-outputs-opener");
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let path = std::env::join_paths([dir.join("missing"), bin.clone()]).unwrap();
    assert_eq!(find_on_path("xdg-open", Some(&path)), None, "not there yet");
    std::fs::write(bin.join("xdg-open"), b"#!/bin/sh\n").unwrap();
    assert_eq!(find_on_path("xdg-open", Some(&path)), Some(bin.join("xdg-open")));
    assert_eq!(find_on_path("xdg-open", None), None, "no PATH, no opener");
    // A folder of that name is not a program.
    std::fs::create_dir_all(dir.join("missing").join("open")).unwrap();
    assert_eq!(find_on_path("open", Some(&path)), None);

    let mut s = ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default());
    let changes = s.apply([Command::ShowFolder(dir.to_path_buf())]);
    assert_eq!(changes.jobs, vec![JobRequest::ShowFolder(dir.to_path_buf())]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The oracle of the default depth: the deepest n within the default node budget, but not past
/// the first n whose largest leaf (c^n of A's size in pixels) is below the target.
fn oracle_depth(functions: usize, c: f64, initial_px: f64) -> u32 {
    let budget = (0..=MAX_DEPTH).filter(|&n| job_plan::hierarchy_nodes(functions, n) <= DEFAULT_DEPTH_NODES).max();
    let sub_pixel = (0..=MAX_DEPTH).find(|&n| c.powi(n as i32) * initial_px <= LEAF_TARGET_PX).unwrap_or(MAX_DEPTH);
    budget.unwrap().min(sub_pixel).max(1)
}

/// The largest Lipschitz bound of `s`'s enabled functions.
fn contraction(s: &ViewerState) -> f64 {
    let report = s.report.as_ref().unwrap();
    report.functions.iter().map(|f| f.lipschitz_bound.unwrap()).fold(0.0, f64::max)
}

#[test]
fn the_default_depth_follows_the_contraction_within_the_budget() {
    for (functions, c, px) in [(4, 0.5, 640.0), (4, 0.9, 640.0), (5, 0.3, 900.0), (2, 0.99, 1920.0), (3, 0.6, 64.0)] {
        assert_eq!(job_plan::default_depth(functions, Some(c), px), oracle_depth(functions, c, px), "{functions} {c}");
    }
    // Not contractive, or no bound: the budget decides.
    assert_eq!(job_plan::default_depth(4, Some(1.2), 640.0), job_plan::default_depth(4, None, 640.0));
    assert_eq!(job_plan::default_depth(4, None, 640.0), oracle_depth(4, 1.0, 640.0));

    // A's sphere spans more than the image: it encloses the grid's box, the view the attractor.
    let twist = ViewerState::new(common::load_scene("twist-anim"), None, LiveSettings::default());
    let form = &twist.raytrace_form;
    let px = twist.initial_sphere_px();
    assert!(px >= form.width.max(form.height) as f64, "{px}");
    // tapering contracts weakly (c = 0.63): the old fixed depth 5 left leaves of about 100 px,
    // blobs; the budget decides its depth.
    let taper = ViewerState::new(common::load_scene("tapering"), None, LiveSettings::default());
    let (c, px) = (contraction(&taper), taper.initial_sphere_px());
    let depth = taper.default_raytrace_depth();
    eprintln!("tapering: c = {c:.3}, A {px:.0} px, depth {depth}, largest leaf {:.1} px", c.powi(depth as i32) * px);
    assert!(c.powi(5) * px > 20.0, "depth 5 left leaves of {:.1} px", c.powi(5) * px);
    assert_eq!(depth, oracle_depth(4, c, px));
    assert!(depth > 5, "{depth}");
    assert!(job_plan::hierarchy_nodes(4, depth) <= DEFAULT_DEPTH_NODES);
    assert!(job_plan::hierarchy_nodes(4, depth + 1) > DEFAULT_DEPTH_NODES, "the budget's depth: {depth}");
    assert_eq!(taper.raytrace_depth(), depth, "auto is the default");
    assert!(taper.raytrace_estimate().refusal().is_none());

    // twist-anim and the Sierpinski triangle contract more: the leaf size stops them short of
    // the budget, once the largest leaf is below the target.
    for (name, functions) in [("twist-anim", 4), ("sierpinski", 3)] {
        let s = ViewerState::new(common::load_scene(name), None, LiveSettings::default());
        let (c, px) = (contraction(&s), s.initial_sphere_px());
        let depth = s.default_raytrace_depth();
        eprintln!("{name}: c = {c:.3}, A {px:.0} px, depth {depth}, largest leaf {:.2} px", c.powi(depth as i32) * px);
        assert_eq!(depth, oracle_depth(functions, c, px), "{name}");
        let leaf = |n: u32| c.powi(n as i32) * px;
        assert!(leaf(depth) <= LEAF_TARGET_PX && leaf(depth - 1) > LEAF_TARGET_PX, "{name}: {depth}");
        assert!(job_plan::hierarchy_nodes(functions, depth + 1) <= DEFAULT_DEPTH_NODES, "{name}: within the budget");
        assert!(depth > 5, "{name}: {depth}");
    }
    // A depth the user sets is kept.
    let mut s = taper.clone();
    let mut form = s.raytrace_form.clone();
    form.depth = Some(3);
    s.apply([Command::SetRaytraceForm(form)]);
    assert_eq!(s.raytrace_depth(), 3);
    // The request runs at the depth the form showed, never "auto".
    let mut s = taper;
    match s.apply([Command::StartRaytrace]).jobs.as_slice() {
        [JobRequest::Raytrace { form, .. }] => assert_eq!(form.depth, Some(depth)),
        other => panic!("{other:?}"),
    }
}
