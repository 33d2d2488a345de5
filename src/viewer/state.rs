//! The viewer's state as plain data: the scene and what is derived from it (compiled IFS,
//! bounds, report), the camera, the live view's settings, grid editing, playback, the job forms
//! and the view's rectangle. UI code (the `ui/` folder) and input handling read
//! it and emit [`Command`]s; `apply.rs` applies them. Nothing here touches the GPU or reads a
//! clock, so it can be tested headless; the queries below (grids, playhead, picking) only read.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use glam::{DVec3, Vec2};

use crate::camera::OrbitCamera;
use crate::chaos_game::CompiledIfs;
use crate::edit::{Edit, History};
use crate::live::{ChaosRoute, LiveSettings};
use crate::model::IfsReport;
use crate::scene::Scene;
use crate::scene::spec::RenderSettings;
use crate::shot::{Framing, Shot};
use crate::splat::SplatView;

use super::command::{Command, JobConfirm, NestingView, RaytraceForm, RecordForm};
use super::framing;
use super::picking::{self, FunctionGrid};
use super::pointer::Button;

/// The scene shown when the viewer starts without one (the paper's plant, table 4).
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/plant2.toml");
pub const DEFAULT_SCENE_NAME: &str = "scenes/plant2.toml (built in)";

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

/// A recovery file found at start-up or on opening a scene, newer than the scene's file.
#[derive(Clone, Debug, PartialEq)]
pub struct RecoveryOffer {
    pub scene: Box<Scene>,
    /// When it was written ("12 s ago" in the dialog).
    pub written: SystemTime,
}

/// What the window shows besides the scene: panels, overlays, dialogs.
#[derive(Clone, Debug, PartialEq)]
pub struct UiState {
    /// The side panel (`Tab` hides it).
    pub panel_shown: bool,
    /// The shortcuts overlay (`F1`, `?`).
    pub shortcuts_shown: bool,
    /// Asking Save / Discard / Cancel before closing with unsaved edits.
    pub close_dialog: bool,
    /// The scene to open once the dialog is answered (None: the dialog is about closing).
    pub pending_open: Option<PendingOpen>,
    /// The window should close now (set once the user has decided).
    pub quit: bool,
    /// Full screen (`F11`).
    pub fullscreen: bool,
    /// A short notice over the view (a saved file); the event loop clears it after a while.
    pub toast: Option<String>,
    /// The scene file changed on disk while there were unsaved edits: not reloaded.
    pub file_changed_on_disk: bool,
    /// A job waiting for Continue / Cancel: a function may not be contractive.
    pub job_confirm: Option<JobConfirm>,
}

/// A scene waiting for the Save / Discard / Cancel dialog: opening it would drop unsaved edits.
#[derive(Clone, Debug, PartialEq)]
pub enum PendingOpen {
    /// A scene file (or the scene copied out of a PNG), read when the dialog is answered.
    File(PathBuf),
    /// A scene that came as bytes (the page's file chooser or a drop on the page), already read:
    /// one that does not read is an error at once, with no question asked.
    Read { name: String, scene: Box<Scene>, text: String },
    /// The scene inside a PNG that nlifs wrote, already read. It opens without a path, so that
    /// a save asks where to write it (beside the image, by default) and never writes over it.
    Image { png: PathBuf, scene: Box<Scene>, text: String },
}

impl PendingOpen {
    /// The file's name as the dialog says it: "Save them before opening …?".
    pub fn name(&self) -> String {
        match self {
            Self::File(path) => path.display().to_string(),
            Self::Read { name, .. } => name.clone(),
            Self::Image { png, .. } => png.display().to_string(),
        }
    }
}

/// How the camera was last framed, which decides how a resize of the view (a panel shown or
/// hidden, the timeline panel appearing) refits a camera the user has not moved since.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraFit {
    /// The scene's camera, framed on opening: a resize frames the scene's camera again.
    #[default]
    Scene,
    /// `F`, `Shift+F` (`with_grid`) or a view along an axis: a resize fits the attractor
    /// again from the user's angles. (It used to frame the scene's camera, so that a resize
    /// after `F` turned the view back to the scene's angles: *Animate* did so, its timeline
    /// panel shrinking the view.)
    Attractor { with_grid: bool },
}

/// Smoothed frame statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub frame_secs: f64,
    pub points_per_sec: f64,
    pub frames: u64,
    /// Where the chaos game runs and why.
    pub chaos_route: ChaosRoute,
    /// Points splatted since the accumulation was last cleared.
    pub accumulated: u64,
    /// Pixels hit by at least one of them (0: not known, on the GPU route).
    pub lit_pixels: u64,
}

impl FrameStats {
    /// How converged the picture is: accumulated points over lit pixels.
    pub fn points_per_lit_pixel(&self) -> f64 {
        self.accumulated as f64 / self.lit_pixels.max(1) as f64
    }
}

/// Everything the viewer shows and edits, besides the GPU objects and the window.
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
    /// The scene as its file holds it (as loaded or last saved): [`ViewerState::modified`]
    /// compares against it.
    pub scene_as_saved: Scene,
    /// The folder of recovery files (None: no recovery).
    pub recovery_dir: Option<PathBuf>,
    /// Where unsaved edits of this scene are written for crash recovery (None: nowhere).
    pub recovery_file: Option<PathBuf>,
    /// What this run last wrote there.
    pub recovery_written: Option<Scene>,
    /// Unsaved edits from an earlier run, offered for restoring.
    pub recovery_offer: Option<RecoveryOffer>,
    pub ui: UiState,
    /// The user moved the camera since it was last framed: a resize keeps it.
    pub camera_moved: bool,
    /// How it was last framed: what a resize refits while it is not moved.
    pub camera_fit: CameraFit,
    /// The W^k nesting view drawn over the points.
    pub nesting: NestingView,
    /// Recent files, file dialogs, the error shown over the view (`files.rs`).
    pub files: super::files_state::FilesState,
}

pub(super) fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl ViewerState {
    /// The state for `scene` (loaded from `path` when given).
    pub fn new(scene: Scene, path: Option<PathBuf>, live: LiveSettings) -> Self {
        let scene_as_saved = scene.clone();
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
            scene_as_saved: scene_as_saved.clone(),
            recovery_dir: None,
            recovery_file: None,
            recovery_written: None,
            recovery_offer: None,
            ui: UiState {
                panel_shown: true,
                shortcuts_shown: false,
                close_dialog: false,
                pending_open: None,
                quit: false,
                fullscreen: false,
                toast: None,
                file_changed_on_disk: false,
                job_confirm: None,
            },
            camera_moved: false,
            camera_fit: CameraFit::Scene,
            nesting: NestingView { shown: false, level: 1, translucent: false },
            files: super::files_state::FilesState::default(),
        };
        // What a save edits; a file that no longer reads as this scene is only a starting
        // point there (`Scene::to_toml_over` checks what it writes).
        state.files.scene_text = state.scene_path.as_deref().and_then(|p| std::fs::read_to_string(p).ok());
        state.edit.save_text = state.default_save_text();
        state.live.draw.seed = state.scene.render.seed;
        state.live.draw.mode = state.scene.render.mode;
        state.live.draw.depth_cue = state.scene.render.depth_cue;
        state.live.draw.background = state.scene.render.background;
        state.take_scene_look();
        state.take_scene_lens();
        state.take_scene_imaging();
        state.recompile();
        state.camera = state.framed_camera();
        state
    }

    /// The live view's shading and occlusion from the scene's look (`[render] look`, `shading`,
    /// `occlusion`), as `render` and `record` resolve it.
    pub fn take_scene_look(&mut self) {
        let style = crate::resolve::ResolveStyle::of(&self.scene.render, self.scene.domain.dimension());
        self.live.draw.shading = style.shading;
        self.live.draw.occlusion = style.occlusion;
        // Shadows (`crate::resolve::shadow`).
        self.live.draw.shadows = style.shadows;
        self.live.draw.light_yaw_deg = style.light_yaw_deg;
        self.live.draw.light_pitch_deg = style.light_pitch_deg;
    }

    /// The scene's camera at the current time, fitted to a sample of the attractor where the
    /// scene leaves target and distance open (the rule of `nlifs render`, the viewer's margin).
    pub fn framed_camera(&self) -> OrbitCamera {
        framing::scene_camera(&self.scene, self.t_secs, self.bounds, &self.framing_sample(), self.view_aspect())
    }

    /// The attractor sample framing fits (empty without an enabled function).
    pub fn framing_sample(&self) -> Vec<glam::Vec3> {
        self.compiled.as_ref().map(|c| framing::framing_sample(c, crate::shot::FRAMING_SEED)).unwrap_or_default()
    }

    /// The scene differs from its file (or, for the built-in scene, from how it started).
    pub fn modified(&self) -> bool {
        self.scene != self.scene_as_saved
    }

    /// The window's title: the scene's name, `*` when modified, the file's name where it is not
    /// the scene's (after Save As to another name), the program.
    pub fn window_title(&self) -> String {
        let file_name = self.scene_path.as_ref().and_then(|p| p.file_name()).map(|n| n.to_string_lossy().into_owned());
        let name = if self.scene.name.trim().is_empty() {
            file_name.clone().unwrap_or_else(|| "untitled".into())
        } else {
            self.scene.name.clone()
        };
        let stem = self.scene_path.as_ref().and_then(|p| p.file_stem()).map(|s| s.to_string_lossy().into_owned());
        let file = match file_name {
            Some(f) if stem.as_deref() != Some(name.as_str()) && f != name => format!(" ({f})"),
            _ => String::new(),
        };
        format!("{name}{}{file} — nlifs", if self.modified() { "*" } else { "" })
    }

    /// Functions that may not be contractive or that leave the grid, for the warning banner:
    /// one line each.
    pub fn warnings(&self) -> Vec<String> {
        let Some(report) = &self.report else { return Vec::new() };
        let mut lines = Vec::new();
        for (f, spec) in report.functions.iter().zip(&self.scene.functions) {
            if !spec.enabled {
                continue;
            }
            if let Some(l) = f.lipschitz_bound
                && l >= 1.0
            {
                lines.push(format!("{} may not be contractive: Lipschitz bound {l:.3} ≥ 1", f.name));
            }
            if f.contained == Some(false) {
                let total = self.function_grid_len(&spec.def);
                let of = total.map_or(String::new(), |n| format!(" of {n}"));
                lines.push(format!("{} leaves the grid: {}{of} transformed points outside", f.name, f.outside.len()));
            }
        }
        lines
    }

    /// "Function f2 may not be contractive (bound 1.250)." for every enabled function whose
    /// Lipschitz bound is 1 or more at the current time, one sentence each; empty when none.
    pub fn contractivity_doubts(&self) -> Vec<String> {
        let Some(report) = &self.report else { return Vec::new() };
        report
            .functions
            .iter()
            .zip(&self.scene.functions)
            .filter(|(_, spec)| spec.enabled)
            .filter_map(|(f, _)| f.lipschitz_bound.filter(|&l| l >= 1.0).map(|l| (f, l)))
            .map(|(f, l)| format!("Function {} may not be contractive (bound {l:.3}).", f.name))
            .collect()
    }

    /// The number of points a definition's containment is checked on (grid points, else the
    /// box corners).
    fn function_grid_len(&self, def: &crate::scene::spec::FunctionDef) -> Option<usize> {
        use crate::scene::spec::FunctionDef;
        match def {
            FunctionDef::Grid { points } => Some(points.len()),
            FunctionDef::Builder { .. } => Some(self.scene.domain.points().len()),
            // The domain box's corners.
            _ => Some(1 << self.scene.domain.dimension()),
        }
    }

    /// What a camera drag with `button` by (`dx_px`, `dy_px`) does: the left button orbits and
    /// the others pan, except in a 2D scene, where the left button pans too (orbiting would only
    /// tilt the plane away from the view).
    pub fn camera_drag(&self, button: Button, dx_px: f32, dy_px: f32) -> Command {
        if button == Button::Left && self.scene.domain.dimension() != 2 {
            Command::Orbit { dx_px, dy_px }
        } else {
            Command::Pan { dx_px, dy_px }
        }
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
    /// The tables and bounds come from the one shot setup that `render` and `record` use
    /// ([`Shot::prepare`]), with the live view's seed and mode (the colours are in the mode's
    /// blend space); the camera stays the viewer's.
    pub(super) fn recompile(&mut self) {
        let settings = RenderSettings {
            seed: self.live.draw.seed,
            mode: self.live.draw.mode,
            ..self.scene.render_at(self.t_secs)
        };
        match Shot::prepare(&self.scene, self.t_secs, &settings, Framing::Given(self.camera), None) {
            Ok(shot) => {
                self.report = Some(shot.ifs.report());
                self.compiled = Some(shot.compiled);
                self.bounds = shot.bounds;
                self.error = None;
            }
            Err(e) => {
                self.report = Some(self.scene.at(self.t_secs).report());
                self.compiled = None;
                self.error = Some(e.to_string());
            }
        }
    }

    /// A command when the scene file changed on disk since it was read: reload it, or, with
    /// unsaved edits, only say so (reloading would discard them without a word).
    pub fn poll_file(&self) -> Option<Command> {
        let path = self.scene_path.as_ref()?;
        let now = mtime(path)?;
        if Some(now) == self.scene_mtime {
            return None;
        }
        Some(if self.modified() { Command::FileChangedOnDisk } else { Command::ReloadScene })
    }

    /// The default path the scene is saved to: its file, else a new file.
    pub(super) fn default_save_text(&self) -> String {
        match &self.scene_path {
            None => "nlifs-scene.toml".into(),
            // A flame file opened as its scene is saved as a scene beside it, never over it.
            Some(p) if crate::flame::xml::is_flame_path(p) => p.with_extension("toml").display().to_string(),
            Some(p) => p.display().to_string(),
        }
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
        picking::definition_grid(&self.scene, &self.scene.function_def_at(function, self.t_secs))
    }

    /// The live view's projection for the current camera and view size (what picking and the
    /// grid overlay project with).
    pub fn splat_view(&self) -> SplatView {
        let (w, h) = (self.width_px.max(1.0) as u32, self.height_px.max(1.0) as u32);
        SplatView::new(
            &self.camera,
            w,
            h,
            self.bounds,
            self.live.draw.mode,
            self.live.draw.depth_cue,
            self.live.draw.splat_background(),
        )
    }

    /// The editable grid point nearest to `cursor_px` (window pixels) within
    /// [`picking::PICK_RADIUS_PX`], as (function, point): among the selected function's points,
    /// or every enabled grid function's when none is selected. None without the grid overlay.
    pub fn pick_point(&self, cursor_px: [f32; 2]) -> Option<(usize, usize)> {
        if !self.edit.grid_overlay {
            return None;
        }
        let candidates: Vec<usize> = match self.edit.selected_function {
            Some(f) => vec![f],
            None => (0..self.scene.functions.len()).filter(|&f| self.scene.functions[f].enabled).collect(),
        };
        let grids = candidates.into_iter().filter_map(|f| Some((f, self.function_grid(f)?)));
        picking::nearest_point(&self.splat_view(), grids, Vec2::from(cursor_px) - Vec2::from(self.view_origin_px))
    }
}
