//! What the viewer's UI and input can ask for: [`Command`], applied to the state once per frame
//! (`apply.rs`), and the background jobs that applying one may request ([`JobRequest`]) with
//! the forms that configure them. Plain data: nothing here reads or changes the state.

use std::path::PathBuf;

use glam::DVec3;

use crate::camera::{OrbitCamera, Projection};
use crate::edit::FunctionKind;
use crate::live::LiveSettings;
use crate::model::ProbabilityMode;
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
    /// Function `function`'s xaos multiplier (≥ 0) of the next function `to`.
    SetFunctionXaos {
        function: usize,
        to: usize,
        value: f64,
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
    /// A flame function's numbers (same variations, same post-affine or none).
    SetFlame {
        function: usize,
        value: crate::scene::spec::FlameDef,
    },
    /// The final xform's numbers (same variations, same post-affine or none).
    SetFinalXform(crate::scene::spec::FinalXform),
    /// A flame function's variations (`function`; None: the final xform's) with one added or
    /// removed: one undo step, refused on a function that a key of the timeline holds.
    SetFlameVariations {
        function: Option<usize>,
        variations: Vec<crate::flame::VariationTerm>,
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
    /// Frames the attractor and the grid box (the domain and every transformed grid).
    FrameAttractorAndGrid,
    /// Zooms by wheel `steps` towards the point under `cursor_px` (window pixels).
    ZoomAt {
        steps: f32,
        cursor_px: [f32; 2],
    },
    /// Puts the camera back (Esc during an orbit or pan restores the camera at its press).
    SetCamera(OrbitCamera),
    /// Blender's numpad views: look along an axis, the attractor framed from there as `F`
    /// frames it.
    ViewAlong(ViewAxis),
    /// "Save view": the view's camera becomes the scene's camera (saved with the scene; one
    /// undo step).
    SaveView,
    /// "Key camera": the view's camera keyed at the playhead (in the key there, else a new
    /// key; one undo step). Only with a timeline.
    KeyCamera,
    SaveScreenshot(PathBuf),
    /// `F12`: a screenshot next to the scene file (or in the working folder for the built-in
    /// scene), named after the scene and numbered so that none is overwritten.
    ScreenshotNextToScene,
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

    // The window: closing, recovery, overlays.
    /// Esc: cancels a point drag, closes a dialog or an overlay; never quits.
    Escape,
    /// The window's close button or `Ctrl+Q`: closes at once without unsaved edits, else asks
    /// Save / Discard / Cancel.
    RequestClose,
    CloseDialog(CloseChoice),
    /// Where recovery files go (None: no recovery). Checks for one to offer.
    SetRecoveryDir(Option<PathBuf>),
    /// Restore (true) or discard (false) the offered recovery file.
    Recover(bool),
    /// Every few seconds: writes unsaved edits to the recovery file.
    Autosave,
    /// The scene file changed on disk while there were unsaved edits: say so, do not reload.
    FileChangedOnDisk,
    SetPanelShown(bool),
    SetShortcutsShown(bool),
    SetFullscreen(bool),
    SetToast(Option<String>),
    /// Shows or hides the W^k nesting view, its level and its fill.
    SetNestingView(NestingView),

    // Functions.
    /// Adds an affine function (a copy of the domain scaled by ½ about its centre).
    AddFunction,
    DuplicateFunction(usize),
    DeleteFunction(usize),

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
    /// Starts the ray-trace, or first asks when a function may not be contractive.
    StartRaytrace,
    CancelRaytrace,
    SetRecordForm(RecordForm),
    /// Starts the recording, or first asks when a function may not be contractive.
    StartRecord,
    /// The answer to "may not be contractive … anyway?": start the job (true) or not.
    ConfirmJob(bool),
    CancelRecord,
    CloseRaytraceImage,
    /// *Show folder*: opens a folder a job wrote into in the desktop's file manager.
    ShowFolder(PathBuf),

    // Authoring: a function's kind and probabilities, a builder's steps, key times. Each is one
    // undo step (a drag of a key is one gesture).
    /// Changes a function's kind, keeping the map as close as the kind allows (the message
    /// says when the change was only approximate).
    SetFunctionKind {
        function: usize,
        kind: FunctionKind,
    },
    /// How the chaos game picks functions. Explicit fills every function's weight with its
    /// current share; back to an automatic mode clears the weights.
    SetProbabilityMode(ProbabilityMode),
    /// Inserts `step` at position `index` of a builder's steps (the panel offers identity
    /// steps, [`Step::identity`], which change nothing until their parameters are set). A step
    /// whose axes the scene's dimension does not allow is refused.
    InsertBuilderStep {
        function: usize,
        index: usize,
        step: Step,
    },
    RemoveBuilderStep {
        function: usize,
        step: usize,
    },
    /// Moves a builder's step `from` to position `to`.
    MoveBuilderStep {
        function: usize,
        from: usize,
        to: usize,
    },
    /// Drags key `key` towards `t_secs` (clamped between its neighbours and inside the
    /// timeline); part of the running gesture, so that a whole drag is one undo step.
    MoveKey {
        key: usize,
        t_secs: f64,
    },
    // Files: dialogs, recent files, drops (`files.rs`).
    /// Ctrl+S: saves to the save field's file, or asks where (Save As) for a scene without a
    /// file of its own.
    Save,
    /// Opens the native Open or Save As dialog, or, where none can be shown, says how to do
    /// without one (the path fields).
    ShowFileDialog(FileDialogKind),
    /// What the native dialog returned (None: cancelled, or no dialog could be shown).
    FileDialogDone {
        kind: FileDialogKind,
        path: Option<PathBuf>,
    },
    /// A file dropped onto the window, picked in Open or in the recent files: a scene, or a
    /// PNG that nlifs wrote (its scene opens). Anything else is an error shown in the view.
    OpenFile(PathBuf),
    /// A file's contents, without a path (the browser's file input and drops): a scene's TOML
    /// or a PNG that nlifs wrote; `name` names it in messages and errors.
    OpenBytes {
        name: String,
        bytes: Vec<u8>,
    },
    /// Where the recent files list lives (None: nowhere); reads it.
    SetConfigDir(Option<PathBuf>),
    /// What this machine offers: native file dialogs, ffmpeg (the event loop finds out).
    SetToolSupport {
        native_dialogs: bool,
        ffmpeg: bool,
    },
    /// Closes the error shown over the view.
    DismissViewError,

    // Depth of field (`lens.rs`).
    /// The scene's lens: aperture (scene units, 0: none) and focus distance (None: the
    /// camera's distance to its target); one undo step.
    SetLens {
        aperture: f32,
        focus_distance: Option<f32>,
    },
    // Palette colour (`ui/palette.rs`, applied in `palette_edit.rs`).
    /// Function `function`'s colour coordinate c_i (None: the default spread); part of the
    /// running gesture, so that a slider drag is one undo step.
    SetPaletteIndex {
        function: usize,
        index: Option<f64>,
    },
    /// `[render] color` (one undo step).
    SetColorMode(crate::scene::spec::ColorMode),
    /// `[render] palette`: a built-in palette's name (one undo step).
    SetPalette(String),
    /// The render panel's tone and density estimation: a scene edit (`imaging.rs`), part of
    /// the running gesture; the accumulation is kept.
    SetImaging(crate::live::Imaging),
}

/// What the user answered when closing with unsaved edits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CloseChoice {
    Save,
    Discard,
    Cancel,
}

/// A background job the viewer starts on the user's word.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobKind {
    Raytrace,
    Record,
}

/// A job held back until the user answers whether to run it on a scene that may not be
/// contractive (such a scene ray-traced for 40 s into two flat colour fields).
#[derive(Clone, Debug, PartialEq)]
pub struct JobConfirm {
    pub job: JobKind,
    /// The question, naming each doubtful function and its bound.
    pub question: String,
}

/// A view along a world axis (Blender's numpad 1, 3, 7 and, with Ctrl, the opposite side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewAxis {
    /// From +z (numpad 1).
    Front,
    Back,
    /// From +x (numpad 3).
    Right,
    Left,
    /// From +y (numpad 7).
    Top,
    Bottom,
}

impl ViewAxis {
    /// Yaw and pitch in degrees (`OrbitCamera`'s convention; the poles stop short of ±90° so
    /// that the up vector stays defined).
    pub fn angles_deg(self) -> (f32, f32) {
        match self {
            ViewAxis::Front => (0.0, 0.0),
            ViewAxis::Back => (180.0, 0.0),
            ViewAxis::Right => (90.0, 0.0),
            ViewAxis::Left => (-90.0, 0.0),
            ViewAxis::Top => (0.0, 89.9),
            ViewAxis::Bottom => (0.0, -89.9),
        }
    }
}

/// A job for `jobs.rs` to start or stop, with everything it needs copied.
#[derive(Clone, Debug, PartialEq)]
pub enum JobRequest {
    /// `form.depth` is filled in (never *auto*); `png` is where the image goes, absolute.
    Raytrace {
        scene: Box<Scene>,
        t_secs: f64,
        camera: OrbitCamera,
        form: RaytraceForm,
        png: PathBuf,
    },
    CancelRaytrace,
    /// The plan the form checked, with its folder and video resolved (`job_plan.rs`).
    Record {
        scene: Box<Scene>,
        plan: Box<RecordPlan>,
    },
    CancelRecord,
    CloseImage,
    /// Opens `folder` in the desktop's file manager, detached (`jobs::open_folder`).
    ShowFolder(PathBuf),
}

/// The "ray-trace this view" settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RaytraceForm {
    /// n of W^n(A); None: *auto*, from the scene's contraction and the node budget
    /// (`job_plan::default_depth`).
    pub depth: Option<u32>,
    pub spp: u32,
    pub width: u32,
    pub height: u32,
    /// Where the PNG goes; empty: next to the scene, numbered (`job_plan::raytrace_png`).
    pub png_text: String,
}

impl Default for RaytraceForm {
    fn default() -> Self {
        Self { depth: None, spp: 2, width: 640, height: 480, png_text: String::new() }
    }
}

/// A recording the record form asks for, checked and with its folder and video resolved
/// (`job_plan::plan_record` makes it).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordPlan {
    pub settings: crate::record::RecordSettings,
    /// The frames to write.
    pub frames: std::ops::Range<u32>,
    /// Frames in the whole timeline at this frame rate.
    pub frame_count: u32,
    pub dir: PathBuf,
    pub options: crate::output::OutputOptions,
    /// Where the video goes (None: frames only).
    pub video: Option<PathBuf>,
}

/// The "record timeline" settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordForm {
    pub width: u32,
    pub height: u32,
    pub fps: f64,
    pub points_per_frame: u64,
    /// The frames' folder; empty: next to the scene, numbered (`job_plan::record_outputs`).
    pub dir_text: String,
    /// Frames `first..end` (end exclusive); None: every frame of the timeline.
    pub frame_range: Option<(u32, u32)>,
    /// The frames' image format (a video needs PNG frames).
    pub format: crate::output::Format,
    /// Encode the frames into a video with ffmpeg afterwards.
    pub video: bool,
    /// The video's file; empty: beside the frames' folder, named after it.
    pub video_text: String,
    /// Frames ray-traced (the snapshot's tracer at `trace_depth` and `trace_spp`) instead of
    /// splatted by the chaos game.
    pub ray_traced: bool,
    /// n of W^n(A) for traced frames.
    pub trace_depth: u32,
    /// Samples per pixel for traced frames.
    pub trace_spp: u32,
}

impl Default for RecordForm {
    fn default() -> Self {
        Self {
            width: 480,
            height: 360,
            fps: 24.0,
            points_per_frame: 500_000,
            dir_text: String::new(),
            frame_range: None,
            format: crate::output::Format::Png,
            video: false,
            video_text: String::new(),
            ray_traced: false,
            trace_depth: 5,
            trace_spp: 2,
        }
    }
}

/// The nesting view of the paper's plates 5 and 7: W^k of the grid box over the points
/// (`crate::model::nesting`), as outlines or translucent faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct NestingView {
    pub shown: bool,
    /// k in W^k (0: the grid box itself).
    pub level: u32,
    /// Faces filled faintly, not only outlined.
    pub translucent: bool,
}

/// The viewer's file dialogs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileDialogKind {
    /// Open a scene (or a PNG that nlifs wrote).
    Open,
    /// Save the scene to a file chosen in the dialog; it becomes the scene's file.
    SaveAs,
}

/// A native dialog for the event loop to show, off its thread.
#[derive(Clone, Debug, PartialEq)]
pub struct FileDialogRequest {
    pub kind: FileDialogKind,
    /// The folder it starts in (the scene's).
    pub directory: Option<PathBuf>,
    /// Save As: the file name it proposes.
    pub file_name: Option<String>,
}
