//! Recording an animated scene to a numbered PNG sequence (and optionally a video).
//!
//! A frame is a pure function of (scene, frame index, settings): frame k shows scene time
//! k / fps; its chaos game draws from the random streams of frame k (`Pcg32::for_stream(seed,
//! k·S + s, chain)` for temporal sample s of S), and the camera is framed on bounds that depend
//! only on the scene (the union of the attractor's bounds sampled over the whole timeline). So
//! a frame has the same bytes whether it is rendered in one run, in a chunk `--frames 50..100`
//! on another machine, or again after `--resume`. Each temporal sample is a [`Shot`] as a still's,
//! but with these fixed bounds: a still frames each image on its own attractor, which would make
//! the depth cue (and an automatic camera distance) breathe from frame to frame.
//!
//! Every frame is written to a temporary file and renamed (`io::save_png`), so a killed run
//! leaves whole frames or none; `--resume` re-renders any frame that does not decode fully.

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::color;
use crate::output::{Format, ImageLayers, OutputOptions, Provenance};
use crate::resolve::resolve_image;
use crate::scene::Scene;
use crate::scene::spec::RenderSettings;
use crate::scene::timeline::LoopMode;
use crate::shot::{Framing, Shot, ShotError};
use crate::splat::Framebuffer;

/// The most frames one `record` run renders. Each frame takes at least milliseconds, so a
/// million is hours of work; a longer animation (a 1e8 s timeline has 2.4e9 frames at 24 fps)
/// is recorded in `--frames` ranges, and no list of all its frames is ever built.
pub const MAX_FRAMES_PER_RUN: u32 = 1_000_000;

#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error(transparent)]
    Shot(#[from] ShotError),
    #[error(
        "frames {start}..{end} are {count} frames, more than the {MAX_FRAMES_PER_RUN} one run records; record them in --frames ranges",
        count = end - start
    )]
    TooManyFrames { start: u32, end: u32 },
    #[error("frames {start}..{end} are not within the animation's {count} frames (0..{count})")]
    FrameRange { start: u32, end: u32, count: u32 },
    #[error("cannot write frame {path}")]
    Write { path: String, source: std::io::Error },
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    #[error(
        "ffmpeg was not found on PATH, so no video was made; the frames are in {dir} (install ffmpeg, or encode them with another tool)"
    )]
    NoFfmpeg { dir: String },
    #[error("ffmpeg failed ({status}): {stderr}")]
    Ffmpeg { status: String, stderr: String },
    #[error("cannot run ffmpeg: {0}")]
    FfmpegIo(std::io::Error),
}

/// How frames are made; everything a frame depends on besides the scene and its index.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordSettings {
    pub fps: f64,
    pub width: u32,
    pub height: u32,
    /// Points per frame (split over the temporal samples); None: the scene's (possibly keyed)
    /// `render.points` at the frame's time.
    pub points_per_frame: Option<u64>,
    /// Temporal samples averaged per frame; 1 is no motion blur.
    pub motion_blur_samples: u32,
    /// Open shutter as a fraction of the frame interval, centred on the frame's time.
    pub shutter: f64,
}

impl RecordSettings {
    pub fn for_scene(scene: &Scene) -> Self {
        Self {
            fps: 24.0,
            width: scene.render.width,
            height: scene.render.height,
            points_per_frame: None,
            motion_blur_samples: 1,
            shutter: 0.5,
        }
    }
}

/// Renders frames of one scene.
pub struct Recorder<'a> {
    scene: &'a Scene,
    settings: RecordSettings,
    /// The bounds every frame is framed and depth-cued on.
    bounds: (DVec3, DVec3),
}

/// Uniform samples per cycle when estimating the timeline's bounds (besides every key).
pub const BOUNDS_SAMPLES: usize = 48;

/// The union of the attractor's bounds over the timeline: at every key and at
/// [`BOUNDS_SAMPLES`] uniform times over one cycle. Depends only on the scene.
pub fn timeline_bounds(scene: &Scene) -> Result<(DVec3, DVec3), RecordError> {
    let mut times = vec![0.0];
    if let Some(tl) = &scene.timeline {
        times.extend(tl.keys.iter().map(|k| k.t_secs));
        let cycle = tl.cycle_secs();
        times.extend((0..BOUNDS_SAMPLES).map(|i| cycle * i as f64 / BOUNDS_SAMPLES as f64));
    }
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for t_secs in times {
        let (a, b) = Shot::prepare(scene, t_secs, &scene.render, Framing::Scene, None)?.bounds;
        lo = lo.min(a);
        hi = hi.max(b);
    }
    Ok((lo, hi))
}

impl<'a> Recorder<'a> {
    pub fn new(scene: &'a Scene, settings: RecordSettings) -> Result<Self, RecordError> {
        let bounds = timeline_bounds(scene)?;
        Ok(Self { scene, settings, bounds })
    }

    pub fn settings(&self) -> &RecordSettings {
        &self.settings
    }

    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.bounds
    }

    /// Frames in the animation: once: 0..=duration; loop: one period (its end is frame 0 again);
    /// ping-pong: there and back. A still scene has one frame.
    pub fn frame_count(&self) -> u32 {
        let Some(tl) = &self.scene.timeline else { return 1 };
        let fps = self.settings.fps;
        // Slack so that 4 s at 24 fps is 96 frames and not 97 by rounding.
        let eps = 1e-9;
        let n = match tl.loop_mode {
            LoopMode::Once => (tl.duration_secs * fps + eps).floor() + 1.0,
            LoopMode::Loop | LoopMode::PingPong => (tl.cycle_secs() * fps - eps).ceil(),
        };
        n.clamp(1.0, u32::MAX as f64) as u32
    }

    /// Scene time of frame `frame`.
    pub fn time_of(&self, frame: u32) -> f64 {
        frame as f64 / self.settings.fps
    }

    /// What frame `frame` is made of: one [`FrameSample`] per temporal sample. A GPU recorder
    /// renders these same samples (and averages them with [`average_linear`]) to make the
    /// same frame.
    pub fn samples(&self, frame: u32) -> Vec<FrameSample> {
        let s = &self.settings;
        let samples = s.motion_blur_samples.max(1);
        let t_frame = self.time_of(frame);
        (0..samples)
            .map(|sample| {
                let offset =
                    if samples == 1 { 0.0 } else { ((sample as f64 + 0.5) / samples as f64 - 0.5) * s.shutter / s.fps };
                let t_secs = t_frame + offset;
                let render = self.scene.render_at(t_secs);
                FrameSample {
                    t_secs,
                    camera: self.scene.camera_for_at(t_secs, self.bounds),
                    bounds: self.bounds,
                    points: s.points_per_frame.unwrap_or(render.points).div_ceil(samples as u64).max(1),
                    stream: frame.wrapping_mul(samples).wrapping_add(sample),
                    render,
                }
            })
            .collect()
    }

    /// Renders frame `frame` on the CPU.
    pub fn frame(&self, frame: u32) -> Result<image::RgbImage, RecordError> {
        let mut images = Vec::new();
        self.for_each_sample(frame, &mut |fb, shot| images.push(resolve_image(fb, &shot.camera, &shot.style)))?;
        Ok(if images.len() == 1 { images.remove(0) } else { average_linear(&images) })
    }

    /// Renders frame `frame` on the CPU as linear layers (for the float and alpha outputs):
    /// the temporal samples averaged in linear light ([`ImageLayers::average`]).
    pub fn frame_layers(&self, frame: u32) -> Result<ImageLayers, RecordError> {
        let mut samples = Vec::new();
        self.for_each_sample(frame, &mut |fb, shot| samples.push(ImageLayers::of(fb, &shot.camera, &shot.style)))?;
        Ok(ImageLayers::average(samples))
    }

    /// What frame `frame` of this recording was made of, for the PNG's text chunks.
    pub fn provenance(&self, frame: u32) -> Provenance {
        let s = &self.settings;
        let settings = serde_json::json!({
            "fps": s.fps,
            "width": s.width,
            "height": s.height,
            "points_per_frame": s.points_per_frame,
            "motion_blur_samples": s.motion_blur_samples,
            "shutter": s.shutter,
        });
        Provenance::for_frame(self.scene, frame, self.time_of(frame), settings)
    }

    /// Runs the chaos game of each temporal sample of frame `frame` and hands its framebuffer
    /// and camera to `each`.
    fn for_each_sample(&self, frame: u32, each: &mut dyn FnMut(&Framebuffer, &Shot)) -> Result<(), RecordError> {
        let (width, height) = (self.settings.width, self.settings.height);
        for sample in self.samples(frame) {
            let FrameSample { t_secs, camera, bounds, points, stream, render } = sample;
            let settings = RenderSettings { width, height, points, ..render };
            let shot =
                Shot::prepare(self.scene, t_secs, &settings, Framing::Given(camera), Some(bounds))?.with_stream(stream);
            let fb = shot.splat(|| {});
            each(&fb, &shot);
        }
        Ok(())
    }
}

/// One temporal sample of a frame: the scene at `t_secs` seen by `camera`, `points` points from
/// random stream `stream` (the chaos game's `frame` argument) with `render`'s seed and splat
/// settings, depth-cued over `bounds`.
#[derive(Clone, Debug)]
pub struct FrameSample {
    pub t_secs: f64,
    pub camera: crate::camera::OrbitCamera,
    pub bounds: (DVec3, DVec3),
    pub points: u64,
    pub stream: u32,
    pub render: crate::scene::spec::RenderSettings,
}

/// The mean of equally sized sRGB images, taken in linear light.
pub fn average_linear(images: &[image::RgbImage]) -> image::RgbImage {
    let (w, h) = images[0].dimensions();
    let to_linear: Vec<f32> = (0..=255).map(color::srgb8_to_linear).collect();
    let mut out = image::RgbImage::new(w, h);
    let n = images.len() as f32;
    for (i, px) in out.as_mut().iter_mut().enumerate() {
        let sum: f32 = images.iter().map(|img| to_linear[img.as_raw()[i] as usize]).sum();
        *px = color::linear_to_srgb8(sum / n);
    }
    out
}

/// `dir/frame_00042.png`.
pub fn frame_path(dir: &Path, frame: u32) -> PathBuf {
    frame_path_as(dir, frame, Format::Png)
}

/// `dir/frame_00042.png` or `.exr`, by `format`.
pub fn frame_path_as(dir: &Path, frame: u32, format: Format) -> PathBuf {
    dir.join(format!("frame_{frame:05}.{}", format.extension()))
}

/// Whether `path` is a PNG (or by its extension an EXR) of `width`×`height` that decodes
/// completely.
pub fn is_complete_frame(path: &Path, width: u32, height: u32) -> bool {
    if Format::for_path(path) == Some(Format::Exr) {
        return crate::output::exr::is_complete(path, width, height);
    }
    match image::open(path) {
        Ok(img) => img.width() == width && img.height() == height,
        Err(_) => false,
    }
}

/// What a recording run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordReport {
    pub rendered: Vec<u32>,
    /// Complete frames left as they were (with `resume`).
    pub skipped: Vec<u32>,
    /// Rendered 8-bit frames in which no point landed (all background).
    pub empty: Vec<u32>,
}

/// The frames of `frames` that still need rendering (all of them unless `resume`).
pub fn frames_to_render(rec: &Recorder, dir: &Path, frames: Range<u32>, resume: bool) -> Vec<u32> {
    frames_to_render_as(rec, dir, frames, resume, Format::Png)
}

/// [`frames_to_render`] for frames in `format`. A PNG frame is kept only when it is complete
/// and was made of what would make it now: the fingerprint of the scene and settings in its
/// text chunks ([`Recorder::provenance`]) equals this recording's, so a resumed sequence never
/// mixes settings. (EXR frames carry no scene; they are checked for completeness only.)
pub fn frames_to_render_as(rec: &Recorder, dir: &Path, frames: Range<u32>, resume: bool, format: Format) -> Vec<u32> {
    let s = rec.settings();
    let keep = |k: u32| {
        let path = frame_path_as(dir, k, format);
        is_complete_frame(&path, s.width, s.height) && (format == Format::Exr || made_by(&path, &rec.provenance(k)))
    };
    frames.filter(|&k| !(resume && keep(k))).collect()
}

/// The PNG at `path` carries `provenance`'s fingerprint (a frame of older nlifs, with no scene
/// inside, does not).
fn made_by(path: &Path, provenance: &Provenance) -> bool {
    crate::output::png::scene_from_png(path).is_ok_and(|found| found.fingerprint() == provenance.fingerprint())
}

/// Renders frames `frames` into `dir`. With `resume`, frames already complete are kept; any
/// other file at a frame's path is replaced. `progress(done, total)` follows each written frame.
pub fn record(
    rec: &Recorder,
    dir: &Path,
    frames: Range<u32>,
    resume: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RecordReport, RecordError> {
    record_as(rec, dir, frames, resume, &OutputOptions::default(), progress)
}

/// [`record`] with frames written as `options` say (PNG frames carry the scene).
pub fn record_as(
    rec: &Recorder,
    dir: &Path,
    frames: Range<u32>,
    resume: bool,
    options: &OutputOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RecordReport, RecordError> {
    let count = rec.frame_count();
    if frames.start >= frames.end || frames.end > count {
        return Err(RecordError::FrameRange { start: frames.start, end: frames.end, count });
    }
    if frames.len() > MAX_FRAMES_PER_RUN as usize {
        return Err(RecordError::TooManyFrames { start: frames.start, end: frames.end });
    }
    let todo = frames_to_render_as(rec, dir, frames.clone(), resume, options.format);
    if resume {
        remove_stale_temp_files(dir, frames.clone(), options.format.extension());
    }
    // `todo` is in increasing order, so a binary search keeps this linear-logarithmic.
    let skipped = frames.filter(|k| todo.binary_search(k).is_err()).collect();
    let mut empty = Vec::new();
    for (n, &k) in todo.iter().enumerate() {
        let path = frame_path_as(dir, k, options.format);
        let provenance = rec.provenance(k);
        if options.is_plain_png() {
            let image = rec.frame(k)?;
            let background = rec.scene.render_at(rec.time_of(k)).background;
            if crate::scene::warnings::covered_pixels(&image, background) == 0 {
                empty.push(k);
            }
            crate::output::png::save_rgb8(&path, &image, Some(&provenance))?;
        } else {
            crate::output::write_image(&path, &rec.frame_layers(k)?, options, Some(&provenance))?;
        }
        progress(n + 1, todo.len());
    }
    Ok(RecordReport { rendered: todo, skipped, empty })
}

/// Removes temporary frame files (`.frame_00042.png.<pid>.tmp`) that a killed run left for
/// frames in `frames`. Chunks of a job array own disjoint frame ranges, so this never touches
/// a file another running chunk is writing.
fn remove_stale_temp_files(dir: &Path, frames: Range<u32>, extension: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.filter_map(|e| e.ok()) {
        let name = entry.file_name().to_string_lossy().into_owned();
        let frame = name
            .strip_prefix(".frame_")
            .filter(|_| name.ends_with(".tmp"))
            .and_then(|rest| rest.split_once(&format!(".{extension}.")))
            .and_then(|(digits, _)| digits.parse::<u32>().ok());
        if frame.is_some_and(|k| frames.contains(&k)) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether ffmpeg can be run.
pub fn ffmpeg_available() -> bool {
    std::process::Command::new("ffmpeg")
        .arg("-version")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok()
}

/// Encodes frames `frames` of `dir` into the video `out` with the system ffmpeg (H.264 in
/// .mp4/.mov/.mkv, ffmpeg's default codec for other containers), written atomically.
pub fn encode_video(dir: &Path, frames: Range<u32>, fps: f64, out: &Path) -> Result<(), RecordError> {
    if !ffmpeg_available() {
        return Err(RecordError::NoFfmpeg { dir: dir.display().to_string() });
    }
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("mp4").to_ascii_lowercase();
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    // The temporary file keeps the extension: ffmpeg picks the container from it.
    let tmp = out.with_file_name(format!(".{stem}.{}.tmp.{ext}", std::process::id()));
    if let Some(parent) = out.parent()
        && !parent.as_os_str().is_empty()
    {
        std::fs::create_dir_all(parent).map_err(RecordError::FfmpegIo)?;
    }
    let mut cmd = std::process::Command::new("ffmpeg");
    cmd.args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{fps}"))
        .arg("-start_number")
        .arg(frames.start.to_string())
        .arg("-i")
        .arg(dir.join("frame_%05d.png"))
        .arg("-frames:v")
        .arg((frames.end - frames.start).to_string())
        // H.264 in 4:2:0 needs even dimensions.
        .args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"]);
    if matches!(ext.as_str(), "mp4" | "mov" | "mkv") {
        cmd.args(["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"]);
    }
    let output = cmd.arg(&tmp).output().map_err(RecordError::FfmpegIo)?;
    if !output.status.success() {
        let _ = std::fs::remove_file(&tmp);
        return Err(RecordError::Ffmpeg {
            status: output.status.to_string(),
            stderr: String::from_utf8_lossy(&output.stderr).trim().to_string(),
        });
    }
    std::fs::rename(&tmp, out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        RecordError::FfmpegIo(e)
    })
}

/// Parses a frame range `A..B` (half-open).
pub fn parse_frame_range(s: &str) -> Result<Range<u32>, String> {
    let (a, b) = s.split_once("..").ok_or_else(|| format!("`{s}` is not a frame range; write A..B, e.g. 0..48"))?;
    let a: u32 = a.trim().parse().map_err(|_| format!("`{a}` in `{s}` is not a frame number"))?;
    let b: u32 = b.trim().parse().map_err(|_| format!("`{b}` in `{s}` is not a frame number"))?;
    if b <= a {
        return Err(format!("frame range `{s}` is empty; the end is exclusive"));
    }
    Ok(a..b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse() {
        assert_eq!(parse_frame_range("0..50"), Ok(0..50));
        assert!(parse_frame_range("5..5").is_err());
        assert!(parse_frame_range("5").is_err());
        assert!(parse_frame_range("a..3").is_err());
    }

    #[test]
    fn linear_average_of_black_and_white_is_mid_grey_in_light() {
        let black = image::RgbImage::from_pixel(1, 1, image::Rgb([0, 0, 0]));
        let white = image::RgbImage::from_pixel(1, 1, image::Rgb([255, 255, 255]));
        // Half of the light is sRGB 0.735 → 188.
        assert_eq!(average_linear(&[black, white]).get_pixel(0, 0).0, [188, 188, 188]);
    }
}
