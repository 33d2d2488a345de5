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
