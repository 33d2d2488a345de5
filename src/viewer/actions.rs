//! The larger actions [`ViewerState::apply`] dispatches to, kept out of `apply.rs` so that each
//! file stays readable: saving (and what a save clears), crash recovery (offer, autosave), Esc,
//! framing, zooming towards the cursor, the view's camera saved into the scene or keyed, the
//! screenshot name next to the scene, and adding, duplicating or deleting a function as one
//! undo step.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::edit::Edit;
use crate::scene::spec::{CameraSpec, FunctionDef};
use crate::scene::timeline::Key;

use super::apply::Changes;
use super::command::{Command, JobConfirm, JobKind, JobRequest, RaytraceForm};
use super::framing;
use super::job_plan;
use super::recovery;
use super::state::{CameraFit, RecoveryOffer, ViewerState, mtime};

impl ViewerState {
    /// Saves the scene to `path`; it becomes the scene's file, and its recovery file goes. A
    /// scene read from a file is saved as that file's text changed only where edited.
    pub(super) fn save_scene(&mut self, path: &Path) {
        self.end_gesture();
        if path.as_os_str().is_empty() {
            self.error = Some("cannot save: no file name".into());
            return;
        }
        if crate::flame::xml::is_flame_path(path) {
            self.error =
                Some(format!("cannot save over the flame file {}: save the scene as a .toml file", path.display()));
            return;
        }
        let mut saved = self.scene.clone();
        saved.path = Some(path.to_path_buf());
        // Over the text of the scene's file, so that its comments and spellings stay (also
        // under a new name: Save As copies the file's form).
        match saved.save_over(path, self.files.scene_text.as_deref()) {
            Ok(text) => {
                self.files.scene_text = Some(text);
                if let Some(file) = &self.recovery_file {
                    recovery::remove(file);
                }
                self.scene = saved;
                self.scene_as_saved = self.scene.clone();
                self.scene_path = Some(path.to_path_buf());
                // Our own write is not a change to reload.
                self.scene_mtime = mtime(path);
                self.ui.file_changed_on_disk = false;
                self.path_text = path.display().to_string();
                self.edit.save_text = self.default_save_text();
                self.message = Some(format!("saved {}", path.display()));
                self.ui.toast = self.message.clone();
                self.recovery_file = self.recovery_dir.as_deref().map(|d| recovery::recovery_path(d, Some(path)));
                self.recovery_written = None;
                self.remember_recent(path);
            }
            Err(e) => self.error = Some(format!("cannot save {}: {e}", path.display())),
        }
    }

    /// Works out this scene's recovery file (that of its file, or of the image whose scene it
    /// is) and offers it when it holds other edits than the scene's file.
    pub(super) fn check_recovery(&mut self) {
        self.recovery_written = None;
        self.recovery_offer = None;
        let origin = self.scene_path.as_deref().or(self.files.opened_image.as_deref());
        self.recovery_file = self.recovery_dir.as_deref().map(|d| recovery::recovery_path(d, origin));
        let Some(file) = &self.recovery_file else { return };
        if let Some((mut scene, written)) = recovery::read(file) {
            scene.path = self.scene.path.clone();
            if scene != self.scene {
                self.recovery_offer = Some(RecoveryOffer { scene: Box::new(scene), written });
            } else {
                recovery::remove(file);
            }
        }
    }

    /// Writes unsaved edits to the recovery file (when they changed since the last write);
    /// removes the file this run wrote once the edits are gone (undone back to the file).
    pub(super) fn autosave(&mut self) {
        // An offer not yet answered keeps its file as it is.
        let Some(file) = self.recovery_file.clone().filter(|_| self.recovery_offer.is_none()) else { return };
        if self.modified() {
            if self.recovery_written.as_ref() != Some(&self.scene) {
                match recovery::write(&file, &self.scene) {
                    Ok(()) => self.recovery_written = Some(self.scene.clone()),
                    Err(e) => {
                        self.error = Some(format!("cannot write the recovery file {}: {e}", file.display()));
                        // Do not retry every few seconds with the same error.
                        self.recovery_file = None;
                    }
                }
            }
        } else if self.recovery_written.take().is_some() {
            recovery::remove(&file);
        }
    }

    /// Esc: cancels a job waiting for its confirmation, else closes the close dialog, else the
    /// recovery offer (its file kept), else the shortcuts overlay, else the error over the view,
    /// else cancels a running point drag (the point goes back). True when the scene changed.
    pub(super) fn escape(&mut self) -> bool {
        if self.ui.job_confirm.is_some() {
            // Esc is Cancel.
            self.ui.job_confirm = None;
        } else if self.ui.close_dialog {
            self.ui.close_dialog = false;
            self.ui.pending_open = None;
        } else if self.recovery_offer.is_some() {
            self.recovery_offer = None;
        } else if self.ui.shortcuts_shown {
            self.ui.shortcuts_shown = false;
        } else if self.files.view_error.is_some() {
            self.files.view_error = None;
        } else if self.edit.gesture.as_ref().is_some_and(|g| g.drag.is_some()) {
            let gesture = self.edit.gesture.take().unwrap_or_default();
            for e in gesture.edits.iter().rev() {
                if let Err(e) = e.inverse().apply(&mut self.scene) {
                    self.error = Some(format!("cannot cancel the drag: {e}"));
                }
            }
            return !gesture.edits.is_empty();
        }
        false
    }

    /// Fits the camera around the attractor (and the grid box), keeping angles and projection.
    pub(super) fn frame(&mut self, with_grid: bool) {
        let mut points = self.framing_sample();
        if with_grid {
            points.extend(framing::box_corners((self.scene.domain.min(), self.scene.domain.max())));
            for f in 0..self.scene.functions.len() {
                if let Some(g) = self.function_grid(f).filter(|_| self.scene.functions[f].enabled) {
                    points.extend(g.points.iter().map(|p| p.as_vec3()));
                }
            }
        }
        if points.is_empty() {
            let dim = self.scene.domain.dimension();
            self.camera.target = OrbitCamera::framing(self.bounds, dim).target;
            self.camera.distance = self.camera.framing_distance(self.bounds);
        } else {
            let aspect = self.view_aspect();
            framing::fit(&mut self.camera, &points, aspect);
        }
        self.camera_moved = false;
        self.camera_fit = CameraFit::Attractor { with_grid };
    }

    /// Zooms by `steps` keeping the point under `cursor_px` (on the plane through the target)
    /// where it is on screen.
    pub(super) fn zoom_at(&mut self, steps: f32, cursor_px: [f32; 2]) {
        let before = self.camera.distance;
        self.camera.zoom(steps);
        let factor = self.camera.distance / before.max(1e-12);
        let (w, h) = (self.width_px.max(1.0), self.height_px.max(1.0));
        // The cursor in normalized view coordinates, x right and y up, in [-1, 1].
        let nx = 2.0 * (cursor_px[0] - self.view_origin_px[0]) / w - 1.0;
        let ny = 1.0 - 2.0 * (cursor_px[1] - self.view_origin_px[1]) / h;
        if !(nx.is_finite() && ny.is_finite()) || nx.abs() > 1.0 || ny.abs() > 1.0 {
            return;
        }
        // Half the view's height at the target before the zoom (the same for both
        // projections); the point under the cursor on the target's plane.
        let half_h = before * (0.5 * self.camera.fov_y_deg.to_radians()).tan();
        let back = self.camera.eye_direction();
        let right = glam::Vec3::Y.cross(back).try_normalize().unwrap_or(glam::Vec3::X);
        let up = back.cross(right);
        let under = self.camera.target + half_h * (nx * self.view_aspect() * right + ny * up);
        // Scaling about `under` by the zoom's factor keeps it fixed on screen.
        self.camera.target = under + (self.camera.target - under) * factor;
    }

    /// The view's camera as a scene's camera settings, every field set. Each value is the
    /// shortest decimal that reads back as the camera's `f32` (a yaw of 35.2, not
    /// 35.200000762939453, in a saved file).
    pub fn camera_spec(&self) -> CameraSpec {
        let short = |v: f32| v.to_string().parse::<f64>().unwrap_or(v as f64);
        let c = &self.camera;
        CameraSpec {
            target: Some(DVec3::new(short(c.target.x), short(c.target.y), short(c.target.z))),
            yaw_deg: Some(short(c.yaw_deg)),
            pitch_deg: Some(short(c.pitch_deg)),
            distance: Some(short(c.distance)),
            fov_y_deg: Some(short(c.fov_y_deg)),
            projection: Some(c.projection),
        }
    }

    /// "Save view": the scene's camera becomes the view's (one undo step; the scene is then
    /// modified, and a save writes it to the file). True when the scene changed.
    pub(super) fn save_view(&mut self) -> bool {
        let camera = self.camera_spec();
        if self.scene.camera == camera {
            return false;
        }
        let mut after = self.scene.clone();
        after.camera = camera;
        let done = self.apply_edit(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) });
        if done {
            let notice = "the view is the scene's camera now (Ctrl+S writes it to the file)";
            self.message = Some(notice.into());
            self.ui.toast = Some(notice.into());
        }
        done
    }

    /// "Key camera": the view's camera in the key at the playhead, or in a new key there holding
    /// only the camera (one undo step). Needs a timeline. True when the scene changed.
    pub(super) fn key_camera(&mut self) -> bool {
        if self.scene.timeline.is_none() {
            self.error = Some("cannot key the camera: the scene has no timeline".into());
            return false;
        }
        // Keying belongs to one playhead, as other edits do.
        self.playback.playing = false;
        let t = self.playhead_secs();
        let mut key = self
            .key_at_playhead()
            .and_then(|k| self.scene.timeline.as_ref().map(|tl| tl.keys[k].clone()))
            .unwrap_or_else(|| Key::new(t));
        let camera = self.camera_spec();
        if key.camera == camera {
            return false;
        }
        key.camera = camera;
        match Edit::add_key(&self.scene, key) {
            Ok(e) => self.apply_edit(e),
            Err(e) => {
                self.error = Some(format!("cannot key the camera: {e}"));
                false
            }
        }
    }

    /// Starts `job`, or, when a function may not be contractive, holds it and asks first. A
    /// ray-trace past the node budget or a recording the form cannot make does not start (the
    /// form says why; so does the panel's error line).
    pub(super) fn start_job(&mut self, job: JobKind, changes: &mut Changes) {
        let refusal = match job {
            JobKind::Raytrace => self.raytrace_estimate().refusal(),
            JobKind::Record => self.record_plan().err(),
        };
        if let Some(why) = refusal {
            self.error = Some(format!("cannot start: {why}"));
            return;
        }
        let doubts = self.contractivity_doubts();
        if doubts.is_empty() {
            self.push_job(job, changes);
            return;
        }
        let verb = match job {
            JobKind::Raytrace => "Ray-trace",
            JobKind::Record => "Record",
        };
        self.ui.job_confirm = Some(JobConfirm { job, question: format!("{} {verb} anyway?", doubts.join(" ")) });
    }

    /// What `jobs.rs` needs to run `job` on the scene as it is now (a recording the form
    /// cannot make: why not).
    pub(super) fn job_request(&self, job: JobKind) -> Result<JobRequest, String> {
        Ok(match job {
            JobKind::Raytrace => JobRequest::Raytrace {
                scene: Box::new(self.scene.clone()),
                t_secs: self.t_secs,
                camera: self.camera,
                form: RaytraceForm { depth: Some(self.raytrace_depth()), ..self.raytrace_form.clone() },
                png: self.raytrace_png(),
            },
            JobKind::Record => {
                // The current view: the viewer's camera (where keys leave it open) and splat settings.
                let mut scene = self.scene.clone();
                let c = &self.camera;
                scene.camera = CameraSpec {
                    target: Some(c.target.as_dvec3()),
                    yaw_deg: Some(c.yaw_deg as f64),
                    pitch_deg: Some(c.pitch_deg as f64),
                    distance: Some(c.distance as f64),
                    fov_y_deg: Some(c.fov_y_deg as f64),
                    projection: Some(c.projection),
                };
                scene.render.mode = self.live.draw.mode;
                scene.render.depth_cue = self.live.draw.depth_cue;
                scene.render.background = self.live.draw.background;
                // The plan as the form showed it (`start_job` refused a bad one), with its
                // numbered folder taken now.
                JobRequest::Record { scene: Box::new(scene), plan: Box::new(self.record_plan()?) }
            }
        })
    }

    /// Starts `job` now, or says why it cannot.
    pub(super) fn push_job(&mut self, job: JobKind, changes: &mut Changes) {
        match self.job_request(job) {
            Ok(request) => changes.jobs.push(request),
            Err(why) => self.error = Some(format!("cannot start: {why}")),
        }
    }

    /// The next free `<scene>-<n>.png` next to the scene file (the working folder for the
    /// built-in scene), where the jobs write too (`job_plan::output_place`).
    pub(super) fn screenshot_next_to_scene(&self) -> PathBuf {
        let (dir, stem) = job_plan::output_place(self.scene_path.as_deref());
        let [png] = job_plan::first_free(|n| [dir.join(format!("{stem}-{n}.png"))]);
        png
    }

    /// Adds, duplicates or deletes a function: one undo step (the whole scene, since keys refer
    /// to functions by index). A new function goes last and is selected.
    pub(super) fn edit_functions(&mut self, command: &Command) -> bool {
        let mut after = self.scene.clone();
        let n = after.functions.len();
        let selected = match *command {
            Command::AddFunction => {
                // An affine map halving the domain about its centre: contractive, inside the
                // grid, and visible at once as a smaller copy of the attractor.
                let (lo, hi) = (after.domain.min(), after.domain.max());
                let centre = 0.5 * (lo + hi);
                let dim = after.domain.dimension();
                let scale = if dim == 2 { DVec3::new(0.5, 0.5, 1.0) } else { DVec3::splat(0.5) };
                let matrix = glam::DMat3::from_diagonal(scale);
                let offset = centre - matrix * centre;
                let offset = if dim == 2 { DVec3::new(offset.x, offset.y, 0.0) } else { offset };
                let name =
                    (n + 1..).map(|k| format!("f{k}")).find(|name| after.functions.iter().all(|f| &f.name != name));
                // Explicit probabilities need a weight on every function: the mean of the others.
                let explicit = after.probability_mode == crate::model::ProbabilityMode::Explicit;
                let mean_weight = after.functions.iter().filter_map(|f| f.probability).sum::<f64>() / n.max(1) as f64;
                after.functions.push(crate::scene::spec::FunctionSpec {
                    name: name.unwrap_or_default(),
                    color: crate::color::palette_color(n),
                    probability: explicit.then_some(mean_weight),
                    enabled: true,
                    def: FunctionDef::Affine(crate::model::AffineMap { matrix, offset }),
                    palette_index: None,
                    xaos: Vec::new(),
                });
                Some(n)
            }
            Command::DuplicateFunction(f) if f < n => {
                let mut copy = after.functions[f].clone();
                copy.name = format!("{} copy", copy.name);
                copy.color = crate::color::palette_color(n);
                after.functions.push(copy);
                // Xaos: every function goes to the copy as it goes to the original.
                for g in &mut after.functions {
                    if let Some(&to_original) = g.xaos.get(f) {
                        g.xaos.resize(n, 1.0);
                        g.xaos.push(to_original);
                    }
                }
                // Keys animate the copy as they animate the original.
                if let Some(tl) = &mut after.timeline {
                    for key in &mut tl.keys {
                        if let Some(def) = key.function(f).cloned() {
                            key.set_function(n, Some(def));
                        }
                    }
                }
                Some(n)
            }
            Command::DeleteFunction(f) if f < n && n > 1 => {
                after.functions.remove(f);
                for g in &mut after.functions {
                    if f < g.xaos.len() {
                        g.xaos.remove(f);
                    }
                }
                if let Some(tl) = &mut after.timeline {
                    for key in &mut tl.keys {
                        key.functions.retain(|k| k.function != f);
                        for k in &mut key.functions {
                            if k.function > f {
                                k.function -= 1;
                            }
                        }
                    }
                }
                None
            }
            Command::DeleteFunction(_) => {
                self.error = Some("a scene keeps at least one function".into());
                return false;
            }
            _ => return false,
        };
        let edit = Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) };
        let done = self.apply_edit(edit);
        if done {
            self.edit.selected_function = selected;
            self.edit.selected_point = None;
        }
        done
    }
}
