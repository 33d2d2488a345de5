//! Applying commands to the viewer's state: [`ViewerState::apply`] runs a frame's commands in
//! order and reports what the renderer must refresh ([`Changes`]); it is the only place the
//! state changes after it is made. Playback advances by [`Command::Tick`], whose `dt_secs` the
//! event loop measures, so everything here is a function of the commands.
//!
//! Scene edits (grid points, builder steps, keys) go through `nlifs::edit`: while a gesture
//! (one drag in the view, one slider or number drag) runs, each change is applied at once so
//! the view follows, and its [`Edit`]s are collected; [`Command::EndGesture`] hands them to
//! [`History::record_applied`] as one undo step. With a timeline, edits go to the key at the
//! playhead (created there if needed).

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::edit::{Edit, History};
use crate::scene::Scene;
use crate::scene::spec::FunctionDef;
use crate::scene::timeline::{Key, LoopMode};

use super::command::{CloseChoice, Command, FileDialogKind, FileDialogRequest, JobKind, JobRequest};
use super::picking;
use super::recovery;
use super::state::{CameraFit, Gesture, PendingOpen, PointDrag, ViewerState, mtime};

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
    /// A native file dialog to show (`files.rs`).
    pub file_dialog: Option<FileDialogRequest>,
}

impl ViewerState {
    /// Applies commands in order; returns what the renderer must refresh.
    pub fn apply(&mut self, commands: impl IntoIterator<Item = Command>) -> Changes {
        let mut changes = Changes::default();
        let mut edited = false;
        let mut time_moved = false;
        for command in commands {
            match command {
                // The Open button with no path typed: the file dialog (the browser's file
                // chooser) instead of a question about opening nothing.
                Command::OpenScene(path) if path.as_os_str().is_empty() => {
                    self.show_file_dialog(FileDialogKind::Open, &mut changes)
                }
                // A PNG's scene opens as a dropped image's does (`nlifs view IMAGE.png`).
                Command::OpenScene(path) if crate::output::png::is_png(&path) => self.open_file(&path, &mut changes),
                // Opening over unsaved edits asks first, as closing does.
                Command::OpenScene(path) => self.request_open(PendingOpen::File(path), &mut changes),
                Command::ReloadScene => {
                    if let Some(path) = self.scene_path.clone()
                        && self.load(&path)
                    {
                        changes.scene_edited = true;
                        self.message = Some(format!("reloaded {}", path.display()));
                    }
                }
                Command::FileChangedOnDisk => {
                    self.ui.file_changed_on_disk = true;
                    self.scene_mtime = self.scene_path.as_deref().and_then(mtime).or(self.scene_mtime);
                }
                // Undoable, in `authoring.rs`.
                Command::SetFunctionEnabled { function, enabled } => {
                    edited |= self.set_function_enabled(function, enabled)
                }
                Command::SetFunctionProbability { function, probability } => {
                    edited |= self.set_function_probability(function, probability)
                }
                Command::SetFunctionXaos { function, to, value } => {
                    edited |= self.set_function_xaos(function, to, value)
                }
                Command::SetFunctionColor { function, color } => edited |= self.set_function_color(function, color),
                Command::SetBuilderStep { function, step, value } => {
                    edited |= self.set_builder_step(function, step, value);
                }
                Command::SetFlame { function, value } => edited |= self.set_flame(function, value),
                Command::SetFinalXform(value) => edited |= self.set_final_xform(value),
                Command::SetFlameVariations { function, variations } => {
                    edited |= self.set_flame_variations(function, variations)
                }
                Command::SetLiveSettings(live) => {
                    // The colour table is in the blend space of the live view's mode
                    // (`recompile`): with the sRGB blend, closest mode and the others differ.
                    let blend = |l: &crate::live::LiveSettings| l.draw.mode.blend_space(l.draw.tone.blend);
                    let recolor = blend(&live) != blend(&self.live);
                    self.live = live;
                    changes.live_settings = true;
                    if recolor {
                        self.recompile();
                        changes.scene_edited = true;
                    }
                }
                Command::SetProjection(projection) => {
                    self.camera.projection = projection;
                    self.camera_moved = true;
                    changes.camera = true;
                }
                Command::Orbit { dx_px, dy_px } => {
                    self.camera.orbit(dx_px, dy_px);
                    self.camera_moved = true;
                    changes.camera = true;
                }
                Command::Pan { dx_px, dy_px } => {
                    self.camera.pan(dx_px, dy_px, self.height_px);
                    self.camera_moved = true;
                    changes.camera = true;
                }
                Command::Zoom { steps } => {
                    self.camera.zoom(steps);
                    self.camera_moved = true;
                    changes.camera = true;
                }
                Command::ZoomAt { steps, cursor_px } => {
                    self.zoom_at(steps, cursor_px);
                    self.camera_moved = true;
                    changes.camera = true;
                }
                Command::SetCamera(camera) => {
                    self.camera = camera;
                    changes.camera = true;
                }
                Command::ViewAlong(axis) => {
                    // Framed from there as `F` frames: keeping the distance cropped a tall
                    // attractor seen from the top.
                    (self.camera.yaw_deg, self.camera.pitch_deg) = axis.angles_deg();
                    self.frame(false);
                    changes.camera = true;
                }
                Command::FrameAttractor => {
                    self.frame(false);
                    changes.camera = true;
                }
                Command::FrameAttractorAndGrid => {
                    self.frame(true);
                    changes.camera = true;
                }
                Command::SaveView => edited |= self.save_view(),
                Command::KeyCamera => edited |= self.key_camera(),
                Command::SaveScreenshot(path) => changes.screenshot = Some(path),
                Command::ScreenshotNextToScene => changes.screenshot = Some(self.screenshot_next_to_scene()),
                Command::SetViewRect { origin_px, size_px } => {
                    let size_px = size_px.map(|v| v.max(1.0));
                    self.view_origin_px = origin_px;
                    if size_px != [self.width_px, self.height_px] || !self.view_rect_known {
                        [self.width_px, self.height_px] = size_px;
                        changes.camera = true;
                        // The first report frames for the view's real aspect; later ones (a
                        // window resize, the panel resized or hidden) only while the user has
                        // not moved the camera since it was framed.
                        if !self.view_rect_known || !self.camera_moved {
                            match self.camera_fit {
                                CameraFit::Scene => self.camera = self.framed_camera(),
                                CameraFit::Attractor { with_grid } => self.frame(with_grid),
                            }
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
                        let p = picking::dragged_position(
                            &self.splat_view(),
                            &self.camera,
                            &self.scene.domain,
                            self.edit.axis_lock,
                            drag.start,
                            delta_px,
                        );
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
                Command::SaveScene(path) => self.save_scene(&path),

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
                            edited |= self.apply_edit(Edit::ReplaceKey {
                                index: key,
                                before: Box::new(before),
                                after: Box::new(after),
                            });
                        }
                    }
                }

                Command::Escape => edited |= self.escape(),
                Command::RequestClose => {
                    self.end_gesture();
                    if self.modified() {
                        self.ui.close_dialog = true;
                    } else {
                        self.ui.quit = true;
                    }
                }
                Command::CloseDialog(choice) => {
                    self.ui.close_dialog = false;
                    let proceed = match choice {
                        CloseChoice::Save => {
                            let path = PathBuf::from(self.edit.save_text.trim());
                            self.save_scene(&path);
                            // A failed save keeps the dialog up with the error shown.
                            self.ui.close_dialog = self.modified();
                            !self.modified()
                        }
                        CloseChoice::Discard => {
                            if let Some(file) = &self.recovery_file {
                                recovery::remove(file);
                            }
                            true
                        }
                        CloseChoice::Cancel => {
                            self.ui.pending_open = None;
                            false
                        }
                    };
                    if proceed {
                        // Then what the dialog interrupted: opening another scene, or quitting.
                        match self.ui.pending_open.take() {
                            Some(open) => self.open_pending(open, &mut changes),
                            None => self.ui.quit = true,
                        }
                    }
                }
                Command::SetRecoveryDir(dir) => {
                    self.recovery_dir = dir;
                    self.check_recovery();
                }
                Command::Recover(restore) => {
                    if let Some(offer) = self.recovery_offer.take() {
                        if restore {
                            self.end_gesture();
                            let mut scene = *offer.scene;
                            scene.path = self.scene.path.clone();
                            self.scene = scene;
                            self.history = History::default();
                            edited = true;
                            self.message = Some("restored unsaved edits".into());
                            self.ui.toast = Some("restored the unsaved edits from the recovery file".into());
                        } else if let Some(file) = &self.recovery_file {
                            recovery::remove(file);
                        }
                    }
                }
                Command::Autosave => self.autosave(),
                Command::SetPanelShown(shown) => self.ui.panel_shown = shown,
                Command::SetShortcutsShown(shown) => self.ui.shortcuts_shown = shown,
                Command::SetFullscreen(on) => self.ui.fullscreen = on,
                Command::SetToast(toast) => self.ui.toast = toast,
                Command::SetNestingView(nesting) => self.nesting = nesting,
                Command::AddFunction | Command::DuplicateFunction(_) | Command::DeleteFunction(_) => {
                    edited |= self.edit_functions(&command);
                }

                Command::SetRaytraceForm(form) => self.raytrace_form = form,
                Command::StartRaytrace => self.start_job(JobKind::Raytrace, &mut changes),
                Command::CancelRaytrace => changes.jobs.push(JobRequest::CancelRaytrace),
                Command::SetRecordForm(form) => self.record_form = form,
                Command::StartRecord => self.start_job(JobKind::Record, &mut changes),
                Command::ConfirmJob(go) => {
                    if let Some(confirm) = self.ui.job_confirm.take()
                        && go
                    {
                        self.push_job(confirm.job, &mut changes);
                    }
                }
                Command::CancelRecord => changes.jobs.push(JobRequest::CancelRecord),
                Command::CloseRaytraceImage => changes.jobs.push(JobRequest::CloseImage),
                Command::ShowFolder(folder) => changes.jobs.push(JobRequest::ShowFolder(folder)),

                // Authoring (`authoring.rs`).
                Command::SetFunctionKind { function, kind } => edited |= self.set_function_kind(function, kind),
                Command::SetProbabilityMode(mode) => edited |= self.set_probability_mode(mode),
                Command::InsertBuilderStep { function, index, step } => {
                    edited |= self.insert_builder_step(function, index, step)
                }
                Command::RemoveBuilderStep { function, step } => edited |= self.remove_builder_step(function, step),
                Command::MoveBuilderStep { function, from, to } => edited |= self.move_builder_step(function, from, to),
                Command::MoveKey { key, t_secs } => edited |= self.move_key(key, t_secs),
                Command::SetImaging(imaging) => {
                    // Another blend space recolours the points: recompiled, accumulation cleared.
                    edited |= imaging.tone.blend != self.live.draw.tone.blend;
                    self.set_imaging(imaging);
                }
                Command::Save
                | Command::ShowFileDialog(_)
                | Command::FileDialogDone { .. }
                | Command::OpenFile(_)
                | Command::OpenBytes { .. }
                | Command::SetConfigDir(_)
                | Command::SetToolSupport { .. }
                | Command::DismissViewError => self.file_command(command, &mut changes),
                Command::SetLens { aperture, focus_distance } => edited |= self.set_lens(aperture, focus_distance),
                // Palette colour, undoable, in `palette_edit.rs`.
                Command::SetPaletteIndex { .. } | Command::SetColorMode(_) | Command::SetPalette(_) => {
                    edited |= self.palette_command(command)
                }
            }
        }
        // Depth of field follows the scene at the playhead (`lens.rs`).
        if edited || time_moved || changes.scene_replaced || changes.scene_edited {
            changes.live_settings |= self.take_scene_lens();
        }
        if edited {
            self.recompile();
            changes.scene_edited = true;
        }
        // The tone and density estimation at the current time (after edits, undo, playback).
        changes.live_settings |= self.take_scene_imaging();
        if time_moved && self.playback.follow_camera && self.scene.timeline.is_some() {
            self.camera = self.framed_camera();
            changes.camera = true;
        }
        changes
    }

    /// Opens the scene at `path` in place of this one (its unsaved edits are gone).
    pub(super) fn open_scene(&mut self, path: &Path, changes: &mut Changes) {
        if self.load(path) {
            self.show_opened(changes);
            self.message = Some(format!("opened {}", path.display()));
            self.remember_recent(path);
            self.check_recovery();
        }
    }

    /// Takes the live settings and the camera of the scene just loaded.
    pub(super) fn show_opened(&mut self, changes: &mut Changes) {
        let s = &self.scene.render;
        // `load` compiled the colours in the blend space of the mode the view had.
        let recolor = s.mode.blend_space(s.blend_space) != self.live.draw.mode.blend_space(s.blend_space);
        self.live.draw.seed = s.seed;
        self.live.draw.mode = s.mode;
        self.live.draw.depth_cue = s.depth_cue;
        self.live.draw.background = s.background;
        if recolor {
            self.recompile();
        }
        self.take_scene_look();
        self.camera = self.framed_camera();
        self.camera_moved = false;
        self.camera_fit = CameraFit::Scene;
        changes.scene_replaced = true;
        changes.camera = true;
        changes.live_settings = true;
    }

    /// Loads `path`; on failure keeps the current scene and records the error.
    fn load(&mut self, path: &Path) -> bool {
        match Scene::load_with_text(path) {
            Ok((scene, text)) => {
                self.install_scene(scene, text, Some(path));
                true
            }
            Err(e) => {
                // Do not retry the same broken file every frame.
                self.scene_mtime = mtime(path).or(self.scene_mtime);
                // Over the view too, where the eye is (a dropped or reloaded file).
                self.set_view_error(e.to_string());
                false
            }
        }
    }

    /// Puts `scene` (read from `text`, at `path` if it has one) in place of this one.
    pub(super) fn install_scene(&mut self, scene: Scene, text: String, path: Option<&Path>) {
        self.scene = scene;
        self.files.scene_text = Some(text);
        self.scene_as_saved = self.scene.clone();
        self.ui.file_changed_on_disk = false;
        self.scene_path = path.map(Path::to_path_buf);
        self.scene_mtime = path.and_then(mtime);
        self.path_text = path.map(|p| p.display().to_string()).unwrap_or_default();
        // Edits made for the old file no longer apply.
        self.history = History::default();
        self.edit.gesture = None;
        self.edit.selected_function = self.edit.selected_function.filter(|&f| f < self.scene.functions.len());
        self.edit.selected_point = None;
        self.edit.save_text = self.default_save_text();
        self.files.opened_name = None;
        self.files.opened_image = None;
        self.playback.playing &= self.scene.timeline.is_some();
        self.files.view_error = None;
        self.recompile();
    }

    /// Applies `edit` as a gesture of its own (one undo step).
    pub(super) fn apply_edit(&mut self, edit: Edit) -> bool {
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
    pub(super) fn preview(&mut self, edit: Edit) -> bool {
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
        } else if let (Some(Edit::ReplaceScene { after: a0, .. }), Edit::ReplaceScene { after, .. }) =
            (edits.last_mut(), &edit)
        {
            // Likewise a slider's many whole-scene steps (the render panel's imaging).
            *a0 = after.clone();
        } else {
            edits.push(edit);
        }
        true
    }

    /// Ends the running gesture: its edits become one undo step.
    pub(super) fn end_gesture(&mut self) {
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

    /// Sets flame function `function`'s numbers (at the playhead); its structure stays.
    fn set_flame(&mut self, function: usize, value: crate::scene::spec::FlameDef) -> bool {
        if function >= self.scene.functions.len() {
            return false;
        }
        let def = self.scene.function_def_at(function, self.t_secs);
        let value = FunctionDef::Flame(value);
        if def == value
            || !matches!(def, FunctionDef::Flame(_))
            || crate::scene::spec::same_structure(&def, &value).is_err()
        {
            return false;
        }
        self.set_definition(function, value)
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
