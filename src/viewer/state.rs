//! The viewer's state as plain data and the commands that change it. UI code (`ui.rs`) and
//! input handling read the state and emit [`Command`]s; [`ViewerState::apply`] applies them once
//! per frame and says what the renderer must refresh ([`Changes`]). Nothing here touches the
//! GPU or reads a clock, so it can be tested headless. A timeline panel or grid editing plug in
//! as more commands.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use glam::DVec3;

use crate::camera::{OrbitCamera, Projection};
use crate::chaos_game::{self, CompiledIfs};
use crate::gpu::live::LiveSettings;
use crate::model::IfsReport;
use crate::model::builder::Step;
use crate::scene::{FunctionDef, Scene};

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
    SetFunctionEnabled { function: usize, enabled: bool },
    SetFunctionProbability { function: usize, probability: Option<f64> },
    /// Linear RGB.
    SetFunctionColor { function: usize, color: [f32; 3] },
    SetBuilderStep { function: usize, step: usize, value: Step },
    SetLiveSettings(LiveSettings),
    SetProjection(Projection),
    Orbit { dx_px: f32, dy_px: f32 },
    Pan { dx_px: f32, dy_px: f32 },
    Zoom { steps: f32 },
    FrameAttractor,
    SaveScreenshot(PathBuf),
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
}

/// Smoothed frame statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub frame_secs: f64,
    pub points_per_sec: f64,
    pub frames: u64,
}

/// Aspect ratio assumed when framing (the viewer's default window, 1280×720).
const VIEW_ASPECT: f32 = 16.0 / 9.0;

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
    pub height_px: f32,
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
            height_px: 720.0,
        };
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
        let sample = self.compiled.as_ref().map(|c| chaos_game::attractor_sample(c, self.live.seed)).unwrap_or_default();
        crate::render::frame_camera(&self.scene, self.t_secs, self.bounds, &sample, VIEW_ASPECT)
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
                    if let Some(FunctionDef::Builder { builder, .. }) = self.scene.functions.get_mut(function).map(|f| &mut f.def)
                        && let Some(s) = builder.steps.get_mut(step)
                    {
                        *s = value;
                        edited = true;
                    }
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
                    let sample = self.compiled.as_ref().map(|c| chaos_game::attractor_sample(c, self.live.seed)).unwrap_or_default();
                    if sample.is_empty() {
                        let dim = self.scene.domain.dimension();
                        self.camera.target = OrbitCamera::framing(self.bounds, dim).target;
                        self.camera.distance = self.camera.framing_distance(self.bounds);
                    } else {
                        self.camera.fit_points(&sample, VIEW_ASPECT);
                    }
                    changes.camera = true;
                }
                Command::SaveScreenshot(path) => changes.screenshot = Some(path),
                Command::SetPathText(text) => self.path_text = text,
                Command::SetScreenshotText(text) => self.screenshot_text = text,
            }
        }
        if edited {
            self.recompile();
            changes.scene_edited = true;
        }
        changes
    }
}
