//! Starting a background job from the viewer, tested on its plain state: a ray-trace or a
//! recording of a scene where a function may not be contractive first asks "Function fN may
//! not be contractive (bound X). Ray-trace anyway?" (Continue / Cancel, Esc cancels); a
//! contractive scene starts at once.

mod common;

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::{Command, JobKind, JobRequest};
use nlifs::viewer::state::ViewerState;

/// A 2D scene whose second function grows by 1.25 along x.
const GROWS: &str = r#"
version = 1
name = "grows"

[grid]
x = [0, 1]
y = [0, 1]

[[function]]
name = "f1"
kind = "affine"
matrix = [[0.5, 0], [0, 0.5]]
offset = [0, 0]

[[function]]
name = "f2"
kind = "affine"
matrix = [[1.25, 0], [0, 0.5]]
offset = [0, 0.5]
"#;

fn grows() -> ViewerState {
    ViewerState::new(Scene::parse(GROWS, "grows.toml").unwrap(), None, LiveSettings::default())
}

#[test]
fn a_job_on_a_scene_that_may_not_be_contractive_asks_first() {
    for (start, job, verb) in
        [(Command::StartRaytrace, JobKind::Raytrace, "Ray-trace"), (Command::StartRecord, JobKind::Record, "Record")]
    {
        let mut s = grows();
        let changes = s.apply([start.clone()]);
        assert!(changes.jobs.is_empty(), "nothing starts before the answer");
        let confirm = s.ui.job_confirm.clone().expect("a question");
        assert_eq!(confirm.job, job);
        assert_eq!(confirm.question, format!("Function f2 may not be contractive (bound 1.250). {verb} anyway?"));

        // Cancel: nothing starts, the question goes.
        let changes = s.apply([Command::ConfirmJob(false)]);
        assert!(changes.jobs.is_empty());
        assert!(s.ui.job_confirm.is_none());
        // Esc cancels too.
        s.apply([start.clone()]);
        let changes = s.apply([Command::Escape]);
        assert!(changes.jobs.is_empty() && s.ui.job_confirm.is_none());
        // Continue: the job starts, on the scene as it is.
        s.apply([start.clone()]);
        let changes = s.apply([Command::ConfirmJob(true)]);
        assert!(s.ui.job_confirm.is_none());
        assert_eq!(changes.jobs.len(), 1);
        match (&changes.jobs[0], job) {
            (JobRequest::Raytrace { scene, .. }, JobKind::Raytrace)
            | (JobRequest::Record { scene, .. }, JobKind::Record) => {
                assert_eq!(scene.functions, s.scene.functions)
            }
            (other, _) => panic!("{other:?} for {job:?}"),
        }
        // A second answer starts nothing more.
        assert!(s.apply([Command::ConfirmJob(true)]).jobs.is_empty());
    }
}

#[test]
fn a_contractive_scene_starts_at_once() {
    // The growing function switched off: no doubt left.
    let mut s = grows();
    s.apply([Command::SetFunctionEnabled { function: 1, enabled: false }]);
    assert!(s.contractivity_doubts().is_empty());
    let changes = s.apply([Command::StartRaytrace]);
    assert!(matches!(changes.jobs.as_slice(), [JobRequest::Raytrace { .. }]), "{:?}", changes.jobs);
    assert!(s.ui.job_confirm.is_none());

    let mut plant = ViewerState::new(common::load_scene("plant2"), None, LiveSettings::default());
    let changes = plant.apply([Command::StartRecord]);
    assert!(matches!(changes.jobs.as_slice(), [JobRequest::Record { .. }]), "{:?}", changes.jobs);
    assert!(plant.ui.job_confirm.is_none());
}

// The forms' checks (`job_plan.rs`) and the jobs' progress (`jobs.rs`).

use nlifs::output::Format;
use nlifs::viewer::job_plan::{self, NODE_BUDGET, RaytraceEstimate};
use nlifs::viewer::jobs::{eta_secs, format_secs};

#[test]
fn the_hierarchy_estimate_counts_every_level_and_the_budget_refuses_past_it() {
    // Oracle: the nodes of W^n(A) counted level by level in integers.
    for m in 1..=6usize {
        for depth in 0..=10u32 {
            let mut level = 1u64;
            let mut total = 0u64;
            for _ in 0..=depth {
                total += level;
                level *= m as u64;
            }
            assert_eq!(job_plan::hierarchy_nodes(m, depth), total as f64, "m = {m}, depth {depth}");
        }
        let deepest = job_plan::deepest_within_budget(m);
        if m > 1 {
            assert!(job_plan::hierarchy_nodes(m, deepest) <= NODE_BUDGET);
            assert!(job_plan::hierarchy_nodes(m, deepest + 1) > NODE_BUDGET, "m = {m}: {deepest} is not the deepest");
        }
    }
    // 4 functions: depth 11 is 5.6 million nodes, depth 12 22.4 million.
    assert_eq!(job_plan::deepest_within_budget(4), 11);
    assert!(RaytraceEstimate::new(4, 11).refusal().is_none());
    let refusal = RaytraceEstimate::new(4, 12).refusal().expect("past the budget");
    assert!(refusal.contains("at most depth 11"), "{refusal}");
    assert!(RaytraceEstimate::new(0, 3).refusal().is_some(), "no function, nothing to trace");

    // The viewer refuses to start it, and says why.
    let mut plant = ViewerState::new(common::load_scene("plant2"), None, LiveSettings::default());
    let m = plant.scene.functions.iter().filter(|f| f.enabled).count();
    let too_deep = job_plan::deepest_within_budget(m) + 1;
    assert!(too_deep <= 12, "plant2 has {m} functions: the form's depth 12 stays within the budget");
    let mut form = plant.raytrace_form.clone();
    form.depth = Some(too_deep);
    let changes = plant.apply([Command::SetRaytraceForm(form), Command::StartRaytrace]);
    assert!(changes.jobs.is_empty(), "{:?}", changes.jobs);
    assert!(plant.error.as_deref().is_some_and(|e| e.contains("budget")), "{:?}", plant.error);
    assert_eq!(plant.raytrace_estimate().nodes, job_plan::hierarchy_nodes(m, too_deep));
}

#[test]
fn the_form_counts_frames_as_the_recorder_does() {
    // Oracle: `Recorder::frame_count`, for each loop mode and a few frame rates.
    let base = common::load_scene("twist-anim");
    for mode in [
        nlifs::scene::timeline::LoopMode::Once,
        nlifs::scene::timeline::LoopMode::Loop,
        nlifs::scene::timeline::LoopMode::PingPong,
    ] {
        for fps in [1.0, 12.5, 24.0, 30.0, 59.94] {
            let mut scene = base.clone();
            scene.timeline.as_mut().unwrap().loop_mode = mode;
            let settings = nlifs::record::RecordSettings { fps, ..nlifs::record::RecordSettings::for_scene(&scene) };
            let rec = nlifs::record::Recorder::new(&scene, settings).unwrap();
            assert_eq!(job_plan::frame_count(&scene, fps), rec.frame_count(), "{mode:?} at {fps} fps");
        }
    }
    assert_eq!(job_plan::frame_count(&common::load_scene("plant2"), 24.0), 1, "a still scene is one frame");
}

#[test]
fn the_record_form_says_what_is_wrong_and_does_not_start() {
    let mut s = ViewerState::new(common::load_scene("twist-anim"), None, LiveSettings::default());
    // 4 s loop at 24 fps: 96 frames.
    let plan = s.record_plan().unwrap();
    assert_eq!((plan.frames.clone(), plan.frame_count, plan.video.clone()), (0..96, 96, None));
    let check = |s: &mut ViewerState, edit: &dyn Fn(&mut nlifs::viewer::command::RecordForm), words: &[&str]| {
        let mut form = s.record_form.clone();
        edit(&mut form);
        let changes = s.apply([Command::SetRecordForm(form), Command::StartRecord]);
        let error = s.record_plan().expect_err("the form is refused");
        assert!(words.iter().all(|w| error.contains(w)), "{error:?} lacks {words:?}");
        assert!(changes.jobs.is_empty(), "nothing starts");
        assert!(s.error.as_deref().is_some_and(|e| e.contains(&error)), "{:?}", s.error);
        s.apply([Command::SetRecordForm(Default::default())]);
    };
    check(&mut s, &|f| f.frame_range = Some((10, 10)), &["10..10", "exclusive"]);
    check(&mut s, &|f| f.frame_range = Some((90, 97)), &["past the end", "96 frames"]);
    check(&mut s, &|f| f.width = 8, &["width"]);
    // A video needs ffmpeg, and PNG frames.
    s.apply([Command::SetToolSupport { native_dialogs: false, ffmpeg: false }]);
    check(&mut s, &|f| f.video = true, &["ffmpeg was not found"]);
    s.apply([Command::SetToolSupport { native_dialogs: false, ffmpeg: true }]);
    check(
        &mut s,
        &|f| {
            f.video = true;
            f.format = Format::Exr;
        },
        &["PNG frames"],
    );

    // Ray-traced frames: PNG only, and each frame's hierarchy within the ray-trace budget.
    check(
        &mut s,
        &|f| {
            f.ray_traced = true;
            f.format = Format::Png16;
        },
        &["8-bit PNG"],
    );
    check(
        &mut s,
        &|f| {
            f.ray_traced = true;
            f.trace_depth = 12;
        },
        &["nodes"],
    );
    let mut form = s.record_form.clone();
    (form.ray_traced, form.trace_depth, form.trace_spp) = (true, 3, 4);
    s.apply([Command::SetRecordForm(form)]);
    match s.record_plan().unwrap().settings.renderer {
        nlifs::record::Renderer::Raytrace(trace) => assert_eq!((trace.depth, trace.spp), (3, 4)),
        other => panic!("the form asked for traced frames, the plan has {other:?}"),
    }
    s.apply([Command::SetRecordForm(Default::default())]);

    // A good form: frames 10..20 as 16-bit PNG, with a video; it starts.
    let mut form = s.record_form.clone();
    form.frame_range = Some((10, 20));
    form.format = Format::Png16;
    form.video = true;
    let changes = s.apply([Command::SetRecordForm(form), Command::StartRecord]);
    let plan = s.record_plan().unwrap();
    assert_eq!(plan.frames, 10..20);
    assert_eq!(plan.options.format, Format::Png16);
    // The video beside the frames' folder, named after it (the built-in scene's folder: the
    // working folder, as F12's).
    assert_eq!(plan.video, Some(plan.dir.with_extension("mp4")), "{plan:?}");
    assert!(plan.dir.is_absolute() && plan.dir.starts_with(std::env::current_dir().unwrap()), "{plan:?}");
    assert!(matches!(changes.jobs.as_slice(), [JobRequest::Record { .. }]), "{:?}", changes.jobs);
}

#[test]
fn time_left_is_the_rate_so_far_times_what_is_left() {
    // 25 of 100 rows in 10 s: 75 rows at 2.5 rows/s is 30 s.
    assert_eq!(eta_secs(10.0, 25, 100), Some(30.0));
    assert_eq!(eta_secs(3.0, 100, 100), Some(0.0));
    assert_eq!(eta_secs(3.0, 0, 100), None, "no rate before the first unit");
    assert_eq!(eta_secs(3.0, 5, 0), None, "no total yet (a hierarchy building)");
    assert_eq!(eta_secs(3.0, 120, 100), Some(0.0), "never negative");
    // A constant rate: the estimate plus the time spent is the whole job's time at each step.
    let secs_per_unit = 0.37;
    for done in 1..=50u64 {
        let eta = eta_secs(done as f64 * secs_per_unit, done, 50).unwrap();
        assert!((eta + done as f64 * secs_per_unit - 50.0 * secs_per_unit).abs() < 1e-9, "{done}: {eta}");
    }
    assert_eq!(format_secs(42.4), "42 s");
    assert_eq!(format_secs(185.0), "3 min 05 s");
    assert_eq!(format_secs(3725.0), "1 h 02 min");
    let p = nlifs::viewer::jobs::JobProgress::new(30, 120, 6.0, false);
    assert_eq!((p.fraction(), p.eta_secs), (0.25, Some(18.0)));
}
