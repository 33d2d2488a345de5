//! Long work the viewer starts and keeps running beside the UI: "ray-trace this view" and
//! "record timeline". Each job runs on its own thread with an atomic progress counter and an
//! atomic cancel flag; the event loop polls it once per frame ([`Jobs::poll`]) and the panel
//! reads a plain-data [`JobView`] with the fraction done and the time left ([`eta_secs`]).
//! Nothing here blocks the UI thread. A recording runs the plan the form checked
//! (`job_plan.rs`): its frames, their format, then the video through ffmpeg; another renderer
//! for the frames would be one more field of that plan, chosen where the frames are made below.

use crate::platform::Instant;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;

use crate::raytrace::{RaytraceSettings, Traced};
use crate::record::Recorder;

use super::command::JobRequest;
use super::job_plan::{self, RaytraceEstimate};

struct Running<T> {
    cancel: Arc<AtomicBool>,
    done: Arc<AtomicU64>,
    total: Arc<AtomicU64>,
    handle: JoinHandle<T>,
    /// When the first unit's total became known (a ray-trace builds its hierarchy first, with
    /// no units to count): the time left is reckoned from there.
    units_started: Option<Instant>,
}

impl<T: Send + 'static> Running<T> {
    fn spawn(work: impl FnOnce(&AtomicBool, &AtomicU64, &AtomicU64) -> T + Send + 'static) -> std::io::Result<Self> {
        let (cancel, done, total) =
            (Arc::new(AtomicBool::new(false)), Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
        let (c, d, t) = (cancel.clone(), done.clone(), total.clone());
        let handle = std::thread::Builder::new().name("nlifs-job".into()).spawn(move || work(&c, &d, &t))?;
        Ok(Self { cancel, done, total, handle, units_started: None })
    }

    fn progress(&mut self) -> JobProgress {
        let total = self.total.load(Ordering::Relaxed);
        if total > 0 && self.units_started.is_none() {
            self.units_started = Some(Instant::now());
        }
        JobProgress::new(
            self.done.load(Ordering::Relaxed),
            total,
            self.units_started.map_or(0.0, |t| t.elapsed().as_secs_f64()),
            self.cancel.load(Ordering::Relaxed),
        )
    }
}

/// How far a running job is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JobProgress {
    /// Units done (rows, frames) of `total` (0: not known yet, e.g. while a hierarchy builds).
    pub done: u64,
    pub total: u64,
    /// Seconds since the units started.
    pub elapsed_secs: f64,
    /// Time left at the rate so far (None until a unit is done).
    pub eta_secs: Option<f64>,
    /// Cancel was asked; the job stops at its next check.
    pub cancelling: bool,
}

impl JobProgress {
    pub fn new(done: u64, total: u64, elapsed_secs: f64, cancelling: bool) -> Self {
        Self { done, total, elapsed_secs, eta_secs: eta_secs(elapsed_secs, done, total), cancelling }
    }

    /// Done over total in [0, 1] (0 while the total is not known).
    pub fn fraction(&self) -> f32 {
        if self.total == 0 { 0.0 } else { (self.done.min(self.total) as f64 / self.total as f64) as f32 }
    }
}

/// Seconds left when `done` of `total` units took `elapsed_secs`, at the same rate; None before
/// the first unit (no rate yet) or without a total. Units of one job cost about the same (rows
/// of one image, frames of one timeline), so the average rate so far is the estimate.
pub fn eta_secs(elapsed_secs: f64, done: u64, total: u64) -> Option<f64> {
    if done == 0 || total == 0 || !elapsed_secs.is_finite() {
        return None;
    }
    let left = total.saturating_sub(done) as f64;
    Some(elapsed_secs.max(0.0) * left / done as f64)
}

/// A duration for people: `42 s`, `3 min 05 s`, `1 h 02 min`.
pub fn format_secs(secs: f64) -> String {
    let s = secs.max(0.0).round() as u64;
    if s < 60 {
        format!("{s} s")
    } else if s < 3600 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{} h {:02} min", s / 3600, (s % 3600) / 60)
    }
}

/// What the panel shows of the jobs.
#[derive(Clone, Debug, Default)]
pub struct JobView {
    /// Progress while a ray-trace runs.
    pub raytrace: Option<JobProgress>,
    pub record: Option<JobProgress>,
    /// The last ray-traced image shown in a window.
    pub raytrace_image: Option<(egui::TextureId, [usize; 2])>,
    pub raytrace_message: Option<String>,
    pub record_message: Option<String>,
    /// The folders the last finished ray-trace and recording wrote into (for *Show folder*).
    pub raytrace_folder: Option<PathBuf>,
    pub record_folder: Option<PathBuf>,
    /// Whether this desktop has a program that shows a folder ([`folder_opener`]).
    pub can_show_folder: bool,
}

type RaytraceResult = (Result<Traced, String>, PathBuf);

#[derive(Default)]
pub struct Jobs {
    raytrace: Option<Running<RaytraceResult>>,
    /// What the recording said, with the folder that holds its output.
    record: Option<Running<Result<(String, PathBuf), String>>>,
    texture: Option<egui::TextureHandle>,
    notices: Vec<String>,
    pub view: JobView,
}

impl Jobs {
    /// Starts or cancels jobs.
    pub fn handle(&mut self, request: JobRequest) {
        match request {
            JobRequest::Raytrace { scene, t_secs, camera, form, png } => {
                if self.raytrace.is_some() {
                    return;
                }
                let settings = RaytraceSettings {
                    width: form.width.clamp(16, 4096),
                    height: form.height.clamp(16, 4096),
                    spp: form.spp.clamp(1, 64),
                    depth: job_plan::effective_depth(&form),
                    ..RaytraceSettings::default()
                };
                // The state refused this already (`job_plan.rs`); checked again so that no
                // request builds past the budget.
                let functions = scene.at(t_secs).active().len();
                if let Some(why) = RaytraceEstimate::new(functions, job_plan::effective_depth(&form)).refusal() {
                    self.view.raytrace_message = Some(why);
                    return;
                }
                let job = Running::spawn(move |cancel, done, total| {
                    let progress = |d: u64, t: u64| {
                        done.store(d, Ordering::Relaxed);
                        total.store(t, Ordering::Relaxed);
                    };
                    (
                        crate::raytrace::render(&scene, t_secs, Some(camera), &settings, &progress, cancel)
                            .map_err(|e| e.to_string()),
                        png,
                    )
                });
                match job {
                    Ok(job) => {
                        self.raytrace = Some(job);
                        self.view.raytrace_message = Some("ray-tracing…".into());
                    }
                    Err(e) => self.view.raytrace_message = Some(format!("cannot start a thread: {e}")),
                }
            }
            JobRequest::CancelRaytrace => {
                if let Some(r) = &self.raytrace {
                    r.cancel.store(true, Ordering::Relaxed);
                }
            }
            JobRequest::Record { scene, plan } => {
                if self.record.is_some() {
                    return;
                }
                // The state checked the plan (ffmpeg too; `encode_video` says so again if it
                // went).
                let job = Running::spawn(move |cancel, done, total| record_job(&scene, &plan, cancel, done, total));
                match job {
                    Ok(job) => {
                        self.record = Some(job);
                        self.view.record_message = Some("recording…".into());
                    }
                    Err(e) => self.view.record_message = Some(format!("cannot start a thread: {e}")),
                }
            }
            JobRequest::CloseImage => {
                self.view.raytrace_image = None;
                self.texture = None;
            }
            JobRequest::CancelRecord => {
                if let Some(r) = &self.record {
                    r.cancel.store(true, Ordering::Relaxed);
                }
            }
            JobRequest::ShowFolder(folder) => {
                if let Err(e) = open_folder(&folder) {
                    self.notices.push(format!("cannot show {}: {e}", folder.display()));
                }
            }
        }
    }

    /// Collects finished jobs (uploading a ray-traced image as a texture) and refreshes the
    /// view. True while a job runs. What a finished job says waits in [`Jobs::take_notices`].
    pub fn poll(&mut self, ctx: &egui::Context) -> bool {
        self.view.can_show_folder = folder_opener().is_some();
        self.view.raytrace = self.raytrace.as_mut().map(Running::progress);
        self.view.record = self.record.as_mut().map(Running::progress);
        if self.raytrace.as_ref().is_some_and(|r| r.handle.is_finished())
            && let Some(r) = self.raytrace.take()
        {
            self.view.raytrace = None;
            self.view.raytrace_message = Some(match r.handle.join() {
                Ok((Ok(traced), png)) => {
                    let (w, h) = traced.image.dimensions();
                    let image = egui::ColorImage::from_rgb([w as usize, h as usize], traced.image.as_raw());
                    let texture = ctx.load_texture("nlifs_raytrace", image, egui::TextureOptions::LINEAR);
                    self.view.raytrace_image = Some((texture.id(), [w as usize, h as usize]));
                    self.texture = Some(texture);
                    // The default name is free (numbered); a typed one may not be.
                    let replaced = if png.exists() { ", replacing the file there" } else { "" };
                    let saved = match crate::io::save_png(&png, &traced.image) {
                        Ok(()) => {
                            self.view.raytrace_folder = png.parent().map(Path::to_path_buf);
                            format!("saved {}{replaced}", png.display())
                        }
                        Err(e) => format!("cannot write {}: {e}", png.display()),
                    };
                    format!(
                        "{w}×{h}, {} leaves, {:.1} s; {saved}",
                        traced.leaf_count,
                        traced.build_secs + traced.trace_secs
                    )
                }
                Ok((Err(e), _)) => format!("ray-trace: {e}"),
                Err(_) => "ray-trace failed (the thread panicked)".into(),
            });
            self.notices.extend(self.view.raytrace_message.clone());
        }
        if self.record.as_ref().is_some_and(|r| r.handle.is_finished())
            && let Some(r) = self.record.take()
        {
            self.view.record = None;
            self.view.record_message = Some(match r.handle.join() {
                Ok(Ok((m, folder))) => {
                    self.view.record_folder = Some(folder);
                    m
                }
                Ok(Err(e)) => format!("record: {e}"),
                Err(_) => "record failed (the thread panicked)".into(),
            });
            self.notices.extend(self.view.record_message.clone());
        }
        self.raytrace.is_some() || self.record.is_some()
    }

    /// What jobs that finished since the last call said (for a toast each).
    pub fn take_notices(&mut self) -> Vec<String> {
        std::mem::take(&mut self.notices)
    }
}

/// Records `plan`'s frames of `scene` one by one (a cancel stops between frames, and every
/// written frame is whole: each is written atomically), then encodes the video.
fn record_job(
    scene: &crate::scene::Scene,
    plan: &job_plan::RecordPlan,
    cancel: &AtomicBool,
    done: &AtomicU64,
    total: &AtomicU64,
) -> Result<(String, PathBuf), String> {
    let rec = Recorder::new(scene, plan.settings.clone()).map_err(|e| e.to_string())?;
    let dir = &plan.dir;
    // The default folder is new (numbered); a typed one may hold an earlier run.
    let had_files = std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_some());
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let folder = dir.clone();
    let message = |text: String| (text, folder.clone());
    let frames = plan.frames.clone();
    let count = frames.len();
    // The video's encoding counts as one more unit.
    total.store(count as u64 + plan.video.is_some() as u64, Ordering::Relaxed);
    for (n, k) in frames.clone().enumerate() {
        if cancel.load(Ordering::Relaxed) {
            return Ok(message(format!("cancelled after {n} of {count} frames in {}", dir.display())));
        }
        crate::record::record_as(&rec, dir, k..k + 1, false, &plan.options, &mut |_, _| {})
            .map_err(|e| e.to_string())?;
        done.store(n as u64 + 1, Ordering::Relaxed);
    }
    let format = match plan.options.format {
        crate::output::Format::Png => String::new(),
        other => format!("{} ", other.name()),
    };
    let over = if had_files { " (the folder was not empty: frames of the same number were replaced)" } else { "" };
    let frames_text = format!("{count} {format}frames to {}{over}", dir.display());
    let Some(video) = &plan.video else { return Ok(message(format!("recorded {frames_text}"))) };
    if cancel.load(Ordering::Relaxed) {
        return Ok(message(format!("recorded {frames_text}; the video was cancelled")));
    }
    let replaced = if video.exists() { ", replacing the file there" } else { "" };
    crate::record::encode_video(dir, frames, plan.settings.fps, video).map_err(|e| e.to_string())?;
    done.store(count as u64 + 1, Ordering::Relaxed);
    Ok(message(format!("recorded {frames_text} and the video {}{replaced}", video.display())))
}

/// The program that shows a folder in the desktop's file manager, found on `PATH` once:
/// `xdg-open` (Linux and other Unix desktops), `open` (macOS), `explorer` (Windows). None
/// where there is none (a bare X server, a container): *Show folder* is then not offered.
pub fn folder_opener() -> Option<&'static Path> {
    static OPENER: OnceLock<Option<PathBuf>> = OnceLock::new();
    OPENER
        .get_or_init(|| {
            let name = if cfg!(target_os = "macos") {
                "open"
            } else if cfg!(windows) {
                "explorer.exe"
            } else {
                "xdg-open"
            };
            find_on_path(name, std::env::var_os("PATH").as_deref())
        })
        .as_deref()
}

/// `name` in one of the folders of `path` (a `PATH` value), as a file. (A few lines rather than
/// a crate: nlifs looks up only these three names, with their full file name.)
pub fn find_on_path(name: &str, path: Option<&std::ffi::OsStr>) -> Option<PathBuf> {
    std::env::split_paths(path?).map(|dir| dir.join(name)).find(|p| p.is_file())
}

/// Shows `folder` in the file manager: runs [`folder_opener`] on it without waiting (a thread
/// reaps it, so that nothing blocks the UI and no zombie stays).
pub fn open_folder(folder: &Path) -> std::io::Result<()> {
    use std::process::{Command, Stdio};
    let opener = folder_opener().ok_or_else(|| std::io::Error::other("no program shows folders here"))?;
    let mut child =
        Command::new(opener).arg(folder).stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::null()).spawn()?;
    std::thread::Builder::new().name("nlifs-open-folder".into()).spawn(move || child.wait())?;
    Ok(())
}
