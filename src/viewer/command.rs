//! What the viewer's UI and input can ask for: [`Command`], applied to the state once per frame
//! (`apply.rs`), and the background jobs that applying one may request ([`JobRequest`]) with
//! the forms that configure them. Plain data: nothing here reads or changes the state.

use std::path::PathBuf;

use glam::DVec3;

use crate::camera::{OrbitCamera, Projection};
use crate::live::LiveSettings;
use crate::model::builder::Step;
use crate::scene::Scene;
use crate::scene::timeline::{Ease, Interpolation, LoopMode};

/// Everything one change to the viewer can be.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    OpenScene(PathBuf),
    SetPathText(String),
    SetScreenshotText(String),
    /// Re-read the current scene file (it changed on disk); keeps the camera.
    ReloadScene,
    SetFunctionEnabled {
        function: usize,
        enabled: bool,
    },
    SetFunctionProbability {
        function: usize,
        probability: Option<f64>,
    },
    /// Linear RGB.
    SetFunctionColor {
        function: usize,
        color: [f32; 3],
    },
    SetBuilderStep {
        function: usize,
        step: usize,
        value: Step,
    },
    SetLiveSettings(LiveSettings),
    SetProjection(Projection),
    Orbit {
        dx_px: f32,
        dy_px: f32,
    },
    Pan {
        dx_px: f32,
        dy_px: f32,
    },
    Zoom {
        steps: f32,
    },
    FrameAttractor,
    SaveScreenshot(PathBuf),
    /// The part of the window the panels leave to the view (window pixels): the attractor is
    /// drawn and framed there. The first report re-frames the camera for its aspect.
    SetViewRect {
        origin_px: [f32; 2],
        size_px: [f32; 2],
    },

    // Grid display and editing.
    SetGridOverlay(bool),
    SelectFunction(Option<usize>),
    SelectPoint(Option<usize>),
    /// Moves along one world axis only (0 = x, 1 = y, 2 = z).
    SetAxisLock(Option<usize>),
    /// A press on grid point `point` of `function` in the view: selects it and starts a gesture.
    BeginPointDrag {
        function: usize,
        point: usize,
    },
    /// The cursor moved `delta_px` (window pixels) since the press of the running point drag.
    DragPoint {
        delta_px: [f32; 2],
    },
    /// Puts a grid point at `p` (numeric entry); part of the running gesture.
    SetPoint {
        function: usize,
        point: usize,
        p: DVec3,
    },
    /// Ends the running gesture: its edits become one undo step.
    EndGesture,
    Undo,
    Redo,
    SetSaveText(String),
    SaveScene(PathBuf),

    // Timeline.
    SetPlaying(bool),
    /// Advances scene time by `dt_secs` × speed while playing (the event loop's clock).
    Tick {
        dt_secs: f64,
    },
    /// Scrub: scene time.
    SetTime(f64),
    SetSpeed(f64),
    SetFollowCamera(bool),
    SetLoopMode(LoopMode),
    SetDuration(f64),
    /// Adds a key at the playhead holding every grid and builder function's current value,
    /// or, where a key is, pins every such function there.
    AddOrUpdateKey,
    DeleteKeyAtPlayhead,
    SetKeyShape {
        key: usize,
        interpolation: Interpolation,
        ease: Ease,
    },

    // Background jobs.
    SetRaytraceForm(RaytraceForm),
    StartRaytrace,
    CancelRaytrace,
    SetRecordForm(RecordForm),
    StartRecord,
    CancelRecord,
    CloseRaytraceImage,
}

/// A job for `jobs.rs` to start or stop, with everything it needs copied.
#[derive(Clone, Debug, PartialEq)]
pub enum JobRequest {
    Raytrace { scene: Box<Scene>, t_secs: f64, camera: OrbitCamera, form: RaytraceForm },
    CancelRaytrace,
    Record { scene: Box<Scene>, form: RecordForm },
    CancelRecord,
    CloseImage,
}

/// The "ray-trace this view" settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RaytraceForm {
    pub depth: u32,
    pub spp: u32,
    pub width: u32,
    pub height: u32,
    pub png_text: String,
}

impl Default for RaytraceForm {
    fn default() -> Self {
        Self { depth: 5, spp: 2, width: 640, height: 480, png_text: "nlifs-raytrace.png".into() }
    }
}

/// The "record timeline" settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordForm {
    pub width: u32,
    pub height: u32,
    pub fps: f64,
    pub points_per_frame: u64,
    pub dir_text: String,
}

impl Default for RecordForm {
    fn default() -> Self {
        Self { width: 480, height: 360, fps: 24.0, points_per_frame: 500_000, dir_text: "nlifs-record".into() }
    }
}
