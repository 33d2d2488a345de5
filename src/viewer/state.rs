//! The viewer's state as plain data and the commands that change it. UI code (`ui.rs`) and
//! input handling read the state and emit [`Command`]s; [`ViewerState::apply`] applies them once
//! per frame and says what the renderer must refresh ([`Changes`]). Nothing here touches the
//! GPU or reads a clock, so it can be tested headless (playback advances by [`Command::Tick`],
//! whose `dt_secs` the event loop measures).
//!
//! Scene edits (grid points, builder steps, keys) go through `nlifs::edit`: while a gesture
//! (one drag in the view, one slider or number drag) runs, each change is applied at once so
//! the view follows, and its [`Edit`]s are collected; [`Command::EndGesture`] hands them to
//! [`History::record_applied`] as one undo step. With a timeline, edits go to the key at the
//! playhead (created there if needed).

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use glam::DVec3;

use crate::camera::{OrbitCamera, Projection};
use crate::chaos_game::{self, CompiledIfs};
use crate::edit::{Edit, History};
use crate::gpu::live::LiveSettings;
use crate::model::IfsReport;
use crate::model::builder::Step;
use crate::scene::Scene;
use crate::scene::spec::FunctionDef;
use crate::scene::timeline::{Ease, Interpolation, Key, LoopMode};

/// The scene shown when the viewer starts without one (the paper's plant, table 4).
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/plant2.toml");
pub const DEFAULT_SCENE_NAME: &str = "scenes/plant2.toml (built in)";

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

/// A drag of one grid point: where it was at the press, in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct PointDrag {
    pub function: usize,
    pub point: usize,
    pub start: DVec3,
}

/// The edits of the gesture in progress, already applied to the scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gesture {
    pub edits: Vec<Edit>,
    pub drag: Option<PointDrag>,
}

/// Grid display and editing state.
#[derive(Clone, Debug, PartialEq)]
pub struct EditState {
    pub grid_overlay: bool,
    pub selected_function: Option<usize>,
    pub selected_point: Option<usize>,
    pub axis_lock: Option<usize>,
    pub gesture: Option<Gesture>,
    pub save_text: String,
}

/// Playback of the timeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Playback {
    pub playing: bool,
    /// Scene seconds per wall-clock second (negative plays backwards).
    pub speed: f64,
    /// Take the camera from the scene's keys (fields they leave open from the attractor) at
    /// every new time.
    pub follow_camera: bool,
}

/// What the renderer must refresh after a batch of commands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Changes {
    /// A different scene: restart the points.
    pub scene_replaced: bool,
    /// The same scene edited: keep the points, clear the accumulation.
    pub scene_edited: bool,
    pub camera: bool,
    pub live_settings: bool,
    pub screenshot: Option<PathBuf>,
    /// Jobs to start or cancel.
    pub jobs: Vec<JobRequest>,
}

/// Smoothed frame statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub frame_secs: f64,
    pub points_per_sec: f64,
    pub frames: u64,
    /// Where the chaos game runs and why (the live view's [`crate::gpu::cpu_route::ChaosRoute`]).
    pub chaos_route: crate::gpu::cpu_route::ChaosRoute,
}

#[derive(Clone, Debug)]
pub struct ViewerState {
    /// The last scene that loaded; a bad file leaves it in place.
    pub scene: Scene,
    /// Where `scene` came from (None: the built-in default).
    pub scene_path: Option<PathBuf>,
    pub scene_mtime: Option<SystemTime>,
    /// The text of the "open" field.
    pub path_text: String,
    pub error: Option<String>,
    pub message: Option<String>,
    pub camera: OrbitCamera,
    pub bounds: (DVec3, DVec3),
    pub compiled: Option<CompiledIfs>,
    pub report: Option<IfsReport>,
    pub live: LiveSettings,
    pub t_secs: f64,
    pub stats: FrameStats,
    pub screenshot_text: String,
    /// The view's size in window pixels: the part of the window right of the side panel and
    /// above the timeline panel (1280×720, the default window, until the viewer reports it).
    pub width_px: f32,
    pub height_px: f32,
    /// The view's top left corner in window pixels.
    pub view_origin_px: [f32; 2],
    /// The viewer reported the view rectangle (`Command::SetViewRect`) at least once.
    pub view_rect_known: bool,
    pub edit: EditState,
    pub history: History,
    pub playback: Playback,
    pub raytrace_form: RaytraceForm,
    pub record_form: RecordForm,
}

fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl ViewerState {
    /// The state for `scene` (loaded from `path` when given).
    pub fn new(scene: Scene, path: Option<PathBuf>, live: LiveSettings) -> Self {
        let mut state = Self {
            scene,
            scene_mtime: path.as_deref().and_then(mtime),
            path_text: path.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
            scene_path: path,
            error: None,
            message: None,
            camera: OrbitCamera::framing((DVec3::ZERO, DVec3::ONE), 3),
            bounds: (DVec3::ZERO, DVec3::ONE),
            compiled: None,
            report: None,
            live,
            t_secs: 0.0,
            stats: FrameStats::default(),
            screenshot_text: "nlifs-screenshot.png".into(),
            width_px: 1280.0,
            height_px: 720.0,
            view_origin_px: [0.0, 0.0],
            view_rect_known: false,
            edit: EditState {
                grid_overlay: false,
                selected_function: None,
                selected_point: None,
                axis_lock: None,
                gesture: None,
                save_text: String::new(),
            },
            history: History::default(),
            playback: Playback { playing: false, speed: 1.0, follow_camera: false },
            raytrace_form: RaytraceForm::default(),
            record_form: RecordForm::default(),
        };
        state.edit.save_text = state.default_save_text();
        state.live.seed = state.scene.render.seed;
        state.live.mode = state.scene.render.mode;
        state.live.depth_cue = state.scene.render.depth_cue;
        state.live.background = state.scene.render.background;
        state.recompile();
        state.camera = state.framed_camera();
        state
    }

    /// The scene's camera at the current time, fitted to a sample of the attractor where the
    /// scene leaves target and distance open (the same framing as `nlifs render`).
    fn framed_camera(&self) -> OrbitCamera {
        let sample =
            self.compiled.as_ref().map(|c| chaos_game::attractor_sample(c, self.live.seed)).unwrap_or_default();
        crate::render::frame_camera(&self.scene, self.t_secs, self.bounds, &sample, self.view_aspect())
    }

    /// Width over height of the view.
    pub fn view_aspect(&self) -> f32 {
        self.width_px.max(1.0) / self.height_px.max(1.0)
    }

    /// The built-in default scene.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE, DEFAULT_SCENE_NAME).unwrap_or_else(|e| unreachable!("built-in scene: {e}"))
    }

    /// Recompiles the IFS at the current time (after an edit).
    fn recompile(&mut self) {
        let ifs = self.scene.at(self.t_secs);
        self.report = Some(ifs.report());
        self.compiled = CompiledIfs::new(&ifs);
        match &self.compiled {
            Some(c) => {
                self.bounds = chaos_game::attractor_bounds(c, self.live.seed);
                self.error = None;
            }
            None => self.error = Some("no function is enabled".into()),
        }
    }

    /// Loads `path`; on failure keeps the current scene and records the error.
    fn load(&mut self, path: &Path) -> bool {
        match Scene::load(path) {
            Ok(scene) => {
                self.scene = scene;
                self.scene_path = Some(path.to_path_buf());
                self.scene_mtime = mtime(path);
                self.path_text = path.display().to_string();
                // Edits made for the old file no longer apply.
                self.history = History::default();
                self.edit.gesture = None;
                self.edit.selected_function = self.edit.selected_function.filter(|&f| f < self.scene.functions.len());
                self.edit.selected_point = None;
                self.edit.save_text = self.default_save_text();
                self.playback.playing &= self.scene.timeline.is_some();
                self.recompile();
                true
            }
            Err(e) => {
                // Do not retry the same broken file every frame.
                self.scene_mtime = mtime(path).or(self.scene_mtime);
                self.error = Some(e.to_string());
                false
            }
        }
    }

    /// A reload command when the scene file changed on disk since it was read.
    pub fn poll_file(&self) -> Option<Command> {
        let path = self.scene_path.as_ref()?;
        let now = mtime(path)?;
        (Some(now) != self.scene_mtime).then_some(Command::ReloadScene)
    }

    /// Applies commands in order; returns what the renderer must refresh.
    pub fn apply(&mut self, commands: impl IntoIterator<Item = Command>) -> Changes {
        let mut changes = Changes::default();
        let mut edited = false;
        let mut time_moved = false;
        for command in commands {
            match command {
                Command::OpenScene(path) => {
                    if self.load(&path) {
                        let s = &self.scene.render;
                        self.live.seed = s.seed;
                        self.live.mode = s.mode;
                        self.live.depth_cue = s.depth_cue;
                        self.live.background = s.background;
                        self.camera = self.framed_camera();
                        changes.scene_replaced = true;
                        changes.camera = true;
                        changes.live_settings = true;
                        self.message = Some(format!("opened {}", path.display()));
                    }
                }
                Command::ReloadScene => {
                    if let Some(path) = self.scene_path.clone()
                        && self.load(&path)
                    {
                        changes.scene_edited = true;
                        self.message = Some(format!("reloaded {}", path.display()));
                    }
                }
                Command::SetFunctionEnabled { function, enabled } => {
                    if let Some(f) = self.scene.functions.get_mut(function) {
                        f.enabled = enabled;
                        edited = true;
                    }
                }
                Command::SetFunctionProbability { function, probability } => {
                    if let Some(f) = self.scene.functions.get_mut(function) {
                        f.probability = probability.map(|p| p.max(0.0));
                        edited = true;
                    }
                }
                Command::SetFunctionColor { function, color } => {
                    if let Some(f) = self.scene.functions.get_mut(function) {
                        f.color = color;
                        edited = true;
                    }
                }
                Command::SetBuilderStep { function, step, value } => {
                    edited |= self.set_builder_step(function, step, value);
                }
                Command::SetLiveSettings(live) => {
                    self.live = live;
                    changes.live_settings = true;
                }
                Command::SetProjection(projection) => {
                    self.camera.projection = projection;
                    changes.camera = true;
                }
                Command::Orbit { dx_px, dy_px } => {
                    self.camera.orbit(dx_px, dy_px);
                    changes.camera = true;
                }
                Command::Pan { dx_px, dy_px } => {
                    self.camera.pan(dx_px, dy_px, self.height_px);
                    changes.camera = true;
                }
                Command::Zoom { steps } => {
                    self.camera.zoom(steps);
                    changes.camera = true;
                }
                Command::FrameAttractor => {
                    // Keep the user's angles and projection; fit target and distance.
                    let sample = self
                        .compiled
                        .as_ref()
                        .map(|c| chaos_game::attractor_sample(c, self.live.seed))
                        .unwrap_or_default();
                    if sample.is_empty() {
                        let dim = self.scene.domain.dimension();
                        self.camera.target = OrbitCamera::framing(self.bounds, dim).target;
                        self.camera.distance = self.camera.framing_distance(self.bounds);
                    } else {
                        self.camera.fit_points(&sample, self.view_aspect());
                    }
                    changes.camera = true;
                }
                Command::SaveScreenshot(path) => changes.screenshot = Some(path),
                Command::SetViewRect { origin_px, size_px } => {
                    let size_px = size_px.map(|v| v.max(1.0));
                    self.view_origin_px = origin_px;
                    if size_px != [self.width_px, self.height_px] || !self.view_rect_known {
                        [self.width_px, self.height_px] = size_px;
                        changes.camera = true;
                        if !self.view_rect_known {
                            self.camera = self.framed_camera();
                        }
                    }
                    self.view_rect_known = true;
                }
                Command::SetPathText(text) => self.path_text = text,
                Command::SetScreenshotText(text) => self.screenshot_text = text,

                Command::SetGridOverlay(on) => self.edit.grid_overlay = on,
                Command::SelectFunction(function) => {
                    let function = function.filter(|&f| f < self.scene.functions.len());
                    if function != self.edit.selected_function {
                        self.edit.selected_point = None;
                    }
                    self.edit.selected_function = function;
                }
                Command::SelectPoint(point) => {
                    let count =
                        self.edit.selected_function.and_then(|f| self.function_grid(f)).map_or(0, |g| g.points.len());
                    self.edit.selected_point = point.filter(|&p| p < count);
                }
                Command::SetAxisLock(axis) => self.edit.axis_lock = axis.filter(|&a| a < self.scene.domain.dimension()),
                Command::BeginPointDrag { function, point } => {
                    self.end_gesture();
                    if let Some(start) =
                        self.function_grid(function).filter(|g| g.editable).and_then(|g| g.points.get(point).copied())
                    {
                        self.edit.selected_function = Some(function);
                        self.edit.selected_point = Some(point);
                        self.edit.gesture =
                            Some(Gesture { edits: Vec::new(), drag: Some(PointDrag { function, point, start }) });
                    }
                }
                Command::DragPoint { delta_px } => {
                    if let Some(drag) = self.edit.gesture.as_ref().and_then(|g| g.drag.clone()) {
                        let p = crate::viewer::grid_edit::dragged_position(self, drag.start, delta_px);
                        edited |= self.move_point(drag.function, drag.point, p);
                    }
                }
                Command::SetPoint { function, point, p } => {
                    if p.is_finite() {
                        edited |= self.move_point(function, point, p);
                    }
                }
                Command::EndGesture => self.end_gesture(),
                Command::Undo | Command::Redo => {
                    self.end_gesture();
                    let result = if command == Command::Undo {
                        self.history.undo(&mut self.scene)
                    } else {
                        self.history.redo(&mut self.scene)
                    };
                    match result {
                        Ok(true) => edited = true,
                        Ok(false) => {}
                        Err(e) => {
                            self.error =
                                Some(format!("cannot {}: {e}", if command == Command::Undo { "undo" } else { "redo" }))
                        }
                    }
                }
                Command::SetSaveText(text) => self.edit.save_text = text,
                Command::SaveScene(path) => {
                    self.end_gesture();
                    match self.scene.save(&path) {
                        Ok(()) => {
                            self.scene.path = Some(path.clone());
                            self.scene_path = Some(path.clone());
                            // Our own write is not a change to reload.
                            self.scene_mtime = mtime(&path);
                            self.path_text = path.display().to_string();
                            self.message = Some(format!("saved {}", path.display()));
                        }
                        Err(e) => self.error = Some(format!("cannot save {}: {e}", path.display())),
                    }
                }

                Command::SetPlaying(playing) => {
                    self.end_gesture();
                    let tl = self.scene.timeline.as_ref().filter(|tl| tl.duration_secs > 0.0);
                    self.playback.playing = playing && tl.is_some();
                    // Once: play from the start again when at the end.
                    if let Some(tl) = tl
                        && playing
                        && tl.loop_mode == LoopMode::Once
                        && self.t_secs >= tl.duration_secs
                    {
                        self.t_secs = 0.0;
                        edited = true;
                    }
                }
                Command::Tick { dt_secs } => {
                    let moved = self.tick(dt_secs);
                    edited |= moved;
                    time_moved |= moved;
                }
                Command::SetTime(t_secs) => {
                    if t_secs.is_finite() && t_secs != self.t_secs {
                        self.end_gesture();
                        self.t_secs = t_secs.max(0.0);
                        edited = true;
                        time_moved = true;
                    }
                }
                Command::SetFollowCamera(follow) => {
                    self.playback.follow_camera = follow;
                    time_moved = follow;
                }
                Command::SetSpeed(speed) => {
                    if speed.is_finite() {
                        self.playback.speed = speed.clamp(-8.0, 8.0);
                    }
                }
                Command::SetLoopMode(mode) => {
                    if let Some(tl) = &self.scene.timeline
                        && tl.loop_mode != mode
                    {
                        let mut after = tl.clone();
                        after.loop_mode = mode;
                        edited |= self.apply_edit(Edit::SetTimeline { before: Some(tl.clone()), after: Some(after) });
                    }
                }
                Command::SetDuration(d) => {
                    // Keys stay inside the timeline: once / ping-pong end at or after the last
                    // key; a loop's period ends after it (its end is the first key again).
                    let last = self.scene.timeline.as_ref().and_then(|tl| tl.keys.last()).map_or(0.0, |k| k.t_secs);
                    let looped = self.scene.timeline.as_ref().is_some_and(|tl| tl.loop_mode == LoopMode::Loop);
                    let d = if looped { d.max(last + 1e-3) } else { d.max(last) };
                    if let Some(tl) = &self.scene.timeline
                        && d.is_finite()
                        && d > 0.0
                        && d != tl.duration_secs
                    {
                        edited |= self.apply_edit(Edit::SetDuration { before: tl.duration_secs, after: d });
                    }
                }
                Command::AddOrUpdateKey => edited |= self.add_or_update_key(),
                Command::DeleteKeyAtPlayhead => {
                    if let Some(index) = self.key_at_playhead() {
                        match Edit::delete_key(&self.scene, index) {
                            Ok(e) => edited |= self.apply_edit(e),
                            Err(e) => self.error = Some(e.to_string()),
                        }
                    }
                }
                Command::SetKeyShape { key, interpolation, ease } => {
                    if let Some(before) = self.scene.timeline.as_ref().and_then(|tl| tl.keys.get(key)).cloned() {
                        let after = Key { interpolation, ease, ..before.clone() };
                        if after != before {
                            edited |= self.apply_edit(Edit::ReplaceKey { index: key, before, after });
                        }
                    }
                }

                Command::SetRaytraceForm(form) => self.raytrace_form = form,
                Command::StartRaytrace => changes.jobs.push(JobRequest::Raytrace {
                    scene: Box::new(self.scene.clone()),
                    t_secs: self.t_secs,
                    camera: self.camera,
                    form: self.raytrace_form.clone(),
                }),
                Command::CancelRaytrace => changes.jobs.push(JobRequest::CancelRaytrace),
                Command::SetRecordForm(form) => self.record_form = form,
                Command::StartRecord => {
                    // The current view: the viewer's camera (where keys leave it open) and splat settings.
                    let mut scene = self.scene.clone();
                    let c = &self.camera;
                    scene.camera = crate::scene::spec::CameraSpec {
                        target: Some(c.target.as_dvec3()),
                        yaw_deg: Some(c.yaw_deg as f64),
                        pitch_deg: Some(c.pitch_deg as f64),
                        distance: Some(c.distance as f64),
                        fov_y_deg: Some(c.fov_y_deg as f64),
                        projection: Some(c.projection),
                    };
                    scene.render.mode = self.live.mode;
                    scene.render.depth_cue = self.live.depth_cue;
                    scene.render.background = self.live.background;
                    changes.jobs.push(JobRequest::Record { scene: Box::new(scene), form: self.record_form.clone() });
                }
                Command::CancelRecord => changes.jobs.push(JobRequest::CancelRecord),
                Command::CloseRaytraceImage => changes.jobs.push(JobRequest::CloseImage),
            }
        }
        if edited {
            self.recompile();
            changes.scene_edited = true;
        }
        if time_moved && self.playback.follow_camera && self.scene.timeline.is_some() {
            self.camera = self.framed_camera();
            changes.camera = true;
        }
        changes
    }
}

/// A function's grid as the overlay shows it: the grid's dimensions and the transformed points
/// (at the playhead), and whether its points can be edited (`kind = "grid"`).
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionGrid {
    pub dims: [usize; 3],
    pub points: Vec<DVec3>,
    pub editable: bool,
}

/// The grid of a definition: grid and builder functions (resolved); None for the others.
pub fn definition_grid(scene: &Scene, def: &FunctionDef) -> Option<FunctionGrid> {
    match (def, scene.resolve(def)) {
        (FunctionDef::Grid { points }, _) => {
            Some(FunctionGrid { dims: scene.domain.dims(), points: points.clone(), editable: true })
        }
        (FunctionDef::Builder { .. }, crate::model::Map::Grid(g)) => {
            Some(FunctionGrid { dims: g.grid.dims(), points: g.points, editable: false })
        }
        _ => None,
    }
}

impl ViewerState {
    /// The default path the scene is saved to: its file, else a new file.
    fn default_save_text(&self) -> String {
        self.scene_path.as_ref().map_or_else(|| "nlifs-scene.toml".into(), |p| p.display().to_string())
    }

    /// Time on the timeline at the current scene time (where keys are added and edited).
    pub fn playhead_secs(&self) -> f64 {
        self.scene.timeline.as_ref().map_or(self.t_secs, |tl| tl.local_time(self.t_secs))
    }

    /// The index of the key at the playhead, if there is one.
    pub fn key_at_playhead(&self) -> Option<usize> {
        self.scene.timeline.as_ref()?.key_index_at(self.playhead_secs())
    }

    /// Function `function`'s grid at the current time.
    pub fn function_grid(&self, function: usize) -> Option<FunctionGrid> {
        if function >= self.scene.functions.len() {
            return None;
        }
        definition_grid(&self.scene, &self.scene.function_def_at(function, self.t_secs))
    }

    /// Applies `edit` as a gesture of its own (one undo step).
    fn apply_edit(&mut self, edit: Edit) -> bool {
        self.end_gesture();
        match self.history.apply(&mut self.scene, edit) {
            Ok(()) => true,
            Err(e) => {
                self.error = Some(format!("edit refused: {e}"));
                false
            }
        }
    }

    /// Applies `edit` now as part of the running gesture (opening one if none runs).
    fn preview(&mut self, edit: Edit) -> bool {
        if let Err(e) = edit.apply(&mut self.scene) {
            self.error = Some(format!("edit refused: {e}"));
            return false;
        }
        let edits = &mut self.edit.gesture.get_or_insert_with(Gesture::default).edits;
        // A drag's many small moves of one definition fold into one edit (before of the first,
        // after of the last), so a long drag stays one small undo step.
        if let (
            Some(Edit::SetFunction { function: f0, key: k0, after: a0, .. }),
            Edit::SetFunction { function, key, after, .. },
        ) = (edits.last_mut(), &edit)
            && f0 == function
            && k0 == key
        {
            *a0 = after.clone();
        } else {
            edits.push(edit);
        }
        true
    }

    /// Ends the running gesture: its edits become one undo step.
    fn end_gesture(&mut self) {
        if let Some(mut gesture) = self.edit.gesture.take()
            && !gesture.edits.is_empty()
        {
            self.history.record_applied(if gesture.edits.len() == 1 {
                gesture.edits.remove(0)
            } else {
                Edit::Batch(gesture.edits)
            });
        }
    }

    /// Sets function `function`'s definition: at the playhead if the scene has a timeline (in the
    /// key there, created if needed), else in the base scene. Part of the running gesture.
    fn set_definition(&mut self, function: usize, def: FunctionDef) -> bool {
        // Editing pauses playback: the edit belongs to one playhead.
        self.playback.playing = false;
        let edit = if self.scene.timeline.is_some() {
            Edit::set_function_at_playhead(&self.scene, self.playhead_secs(), function, def)
        } else {
            Edit::set_function(&self.scene, function, None, def)
        };
        match edit {
            Ok(e) => self.preview(e),
            Err(e) => {
                self.error = Some(format!("edit refused: {e}"));
                false
            }
        }
    }

    /// Moves grid point `point` of grid function `function` to `p` (at the playhead).
    fn move_point(&mut self, function: usize, point: usize, p: DVec3) -> bool {
        if function >= self.scene.functions.len() {
            return false;
        }
        let mut def = self.scene.function_def_at(function, self.t_secs);
        let FunctionDef::Grid { points } = &mut def else { return false };
        let Some(q) = points.get_mut(point) else { return false };
        if *q == p {
            return false;
        }
        *q = p;
        self.set_definition(function, def)
    }

    fn set_builder_step(&mut self, function: usize, step: usize, value: crate::model::builder::Step) -> bool {
        if function >= self.scene.functions.len() {
            return false;
        }
        let mut def = self.scene.function_def_at(function, self.t_secs);
        let FunctionDef::Builder { builder, .. } = &mut def else { return false };
        let Some(s) = builder.steps.get_mut(step) else { return false };
        *s = value;
        self.set_definition(function, def)
    }

    /// Adds a key at the playhead holding every grid and builder function's current value, or
    /// pins them all in the key that is there (one undo step).
    fn add_or_update_key(&mut self) -> bool {
        let t = self.playhead_secs();
        let mut key = self
            .key_at_playhead()
            .and_then(|k| self.scene.timeline.as_ref().map(|tl| tl.keys[k].clone()))
            .unwrap_or_else(|| Key::new(t));
        for (i, f) in self.scene.functions.iter().enumerate() {
            if matches!(f.def, FunctionDef::Grid { .. } | FunctionDef::Builder { .. }) {
                key.set_function(i, Some(self.scene.function_def_at(i, self.t_secs)));
            }
        }
        match Edit::add_key(&self.scene, key) {
            Ok(e) => self.apply_edit(e),
            Err(e) => {
                self.error = Some(e.to_string());
                false
            }
        }
    }

    /// Advances scene time while playing; true if it moved. Once: stops at either end; loop:
    /// wraps modulo the duration; ping-pong: wraps modulo twice the duration (the timeline
    /// maps the second half backwards).
    fn tick(&mut self, dt_secs: f64) -> bool {
        let Some(tl) = &self.scene.timeline else {
            self.playback.playing = false;
            return false;
        };
        let d = tl.duration_secs;
        if !self.playback.playing || !(d > 0.0) || !dt_secs.is_finite() || dt_secs <= 0.0 {
            return false;
        }
        let t = self.t_secs + dt_secs * self.playback.speed;
        self.t_secs = match tl.loop_mode {
            LoopMode::Once => {
                if !(0.0..d).contains(&t) {
                    self.playback.playing = false;
                }
                t.clamp(0.0, d)
            }
            LoopMode::Loop => t.rem_euclid(d),
            LoopMode::PingPong => t.rem_euclid(2.0 * d),
        };
        true
    }
}
