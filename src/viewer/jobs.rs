//! Long work the viewer starts and keeps running beside the UI: "ray-trace this view" and
//! "record timeline". Each job runs on its own thread with an atomic progress counter and an
//! atomic cancel flag; the event loop polls it once per frame ([`Jobs::poll`]) and the panel
//! reads a plain-data [`JobView`]. Nothing here blocks the UI thread.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;

use crate::raytrace::{RaytraceSettings, Traced};
use crate::record::{RecordSettings, Recorder};

use super::command::JobRequest;

struct Running<T> {
    cancel: Arc<AtomicBool>,
    done: Arc<AtomicU64>,
    total: Arc<AtomicU64>,
    handle: JoinHandle<T>,
}

impl<T: Send + 'static> Running<T> {
    fn spawn(work: impl FnOnce(&AtomicBool, &AtomicU64, &AtomicU64) -> T + Send + 'static) -> std::io::Result<Self> {
        let (cancel, done, total) =
            (Arc::new(AtomicBool::new(false)), Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
        let (c, d, t) = (cancel.clone(), done.clone(), total.clone());
        let handle = std::thread::Builder::new().name("nlifs-job".into()).spawn(move || work(&c, &d, &t))?;
        Ok(Self { cancel, done, total, handle })
    }

    fn fraction(&self) -> f32 {
        let total = self.total.load(Ordering::Relaxed);
        if total == 0 { 0.0 } else { (self.done.load(Ordering::Relaxed) as f64 / total as f64) as f32 }
    }
}

/// What the panel shows of the jobs.
#[derive(Clone, Debug, Default)]
pub struct JobView {
    /// Progress in [0, 1] while a ray-trace runs.
    pub raytrace: Option<f32>,
    pub record: Option<f32>,
    /// The last ray-traced image shown in a window.
    pub raytrace_image: Option<(egui::TextureId, [usize; 2])>,
    pub raytrace_message: Option<String>,
    pub record_message: Option<String>,
}

/// The most leaves a ray-trace from the viewer may build (about 1 GB of hierarchy).
const MAX_LEAVES: f64 = 8.0e6;

type RaytraceResult = (Result<Traced, String>, PathBuf);

#[derive(Default)]
pub struct Jobs {
    raytrace: Option<Running<RaytraceResult>>,
    record: Option<Running<Result<String, String>>>,
    texture: Option<egui::TextureHandle>,
    pub view: JobView,
}

impl Jobs {
    /// Starts or cancels jobs.
    pub fn handle(&mut self, request: JobRequest) {
        match request {
            JobRequest::Raytrace { scene, t_secs, camera, form } => {
                if self.raytrace.is_some() {
                    return;
                }
                let settings = RaytraceSettings {
                    width: form.width.clamp(16, 4096),
                    height: form.height.clamp(16, 4096),
                    spp: form.spp.clamp(1, 64),
                    depth: form.depth.min(12),
                    ..RaytraceSettings::default()
                };
                let png = PathBuf::from(form.png_text.trim());
                // W^n(A) has m^n leaves: refuse what would not fit in memory rather than abort.
                let m = scene.at(t_secs).active().len().max(1) as f64;
                if m.powi(settings.depth as i32) > MAX_LEAVES {
                    let depth = (MAX_LEAVES.ln() / m.ln()).floor();
                    self.view.raytrace_message = Some(format!(
                        "depth {} gives {m}^{} leaves; at most depth {depth} here",
                        settings.depth, settings.depth
                    ));
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
            JobRequest::Record { scene, form } => {
                if self.record.is_some() {
                    return;
                }
                let dir = PathBuf::from(form.dir_text.trim());
                let job = Running::spawn(move |cancel, done, total| {
                    let settings = RecordSettings {
                        fps: form.fps.clamp(1.0, 240.0),
                        width: form.width.clamp(16, 4096),
                        height: form.height.clamp(16, 4096),
                        points_per_frame: Some(form.points_per_frame.max(1)),
                        motion_blur_samples: 1,
                        shutter: 0.5,
                        renderer: crate::record::Renderer::Chaos,
                    };
                    let rec = Recorder::new(&scene, settings).map_err(|e| e.to_string())?;
                    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
                    let count = rec.frame_count();
                    total.store(count as u64, Ordering::Relaxed);
                    // Frame by frame through `record`, so a cancel stops between frames and
                    // every written frame is whole (each is written atomically).
                    for k in 0..count {
                        if cancel.load(Ordering::Relaxed) {
                            return Ok(format!("cancelled after {k} of {count} frames in {}", dir.display()));
                        }
                        crate::record::record(&rec, &dir, k..k + 1, false, &mut |_, _| {})
                            .map_err(|e| e.to_string())?;
                        done.store(k as u64 + 1, Ordering::Relaxed);
                    }
                    Ok(format!("recorded {count} frames to {}", dir.display()))
                });
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
        }
    }

    /// Collects finished jobs (uploading a ray-traced image as a texture) and refreshes the
    /// view. True while a job runs (the event loop then keeps drawing for the progress bars).
    pub fn poll(&mut self, ctx: &egui::Context) -> bool {
        self.view.raytrace = self.raytrace.as_ref().map(Running::fraction);
        self.view.record = self.record.as_ref().map(Running::fraction);
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
                    let saved = if png.as_os_str().is_empty() {
                        "not saved (no path)".to_string()
                    } else {
                        match crate::io::save_png(&png, &traced.image) {
                            Ok(()) => format!("saved {}", png.display()),
                            Err(e) => format!("cannot write {}: {e}", png.display()),
                        }
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
        }
        if self.record.as_ref().is_some_and(|r| r.handle.is_finished())
            && let Some(r) = self.record.take()
        {
            self.view.record = None;
            self.view.record_message = Some(match r.handle.join() {
                Ok(Ok(m)) => m,
                Ok(Err(e)) => format!("record: {e}"),
                Err(_) => "record failed (the thread panicked)".into(),
            });
        }
        self.raytrace.is_some() || self.record.is_some()
    }
}
