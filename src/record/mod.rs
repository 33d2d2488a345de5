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
//! leaves whole frames or none; `--resume` re-renders any frame that does not decode fully
//! (`files`).
//!
//! The frame description ([`Recorder::samples`]) is drawn by one of three engines: the chaos
//! game on the CPU (the reference, the same bytes on every machine), the chaos game on the GPU
//! ([`Recorder::on_gpu`]: the same samples, cameras and streams, run in fixed batches by
//! `crate::gpu::batch`, so the same bytes on every run on one adapter, and the same densities
//! as the CPU's within sampling noise), or the ray tracer of `nlifs snapshot`
//! ([`Renderer::Raytrace`], `raytrace`). The PNG of a frame says which engine made it, so a
//! resumed sequence never mixes them.

pub mod files;
pub mod raytrace;

use std::sync::Mutex;

use glam::DVec3;

use crate::color;
use crate::gpu::batch::{BatchSizing, GpuSplatter};
use crate::gpu::{GpuContext, GpuError};
use crate::output::{ImageLayers, Provenance};
use crate::raytrace::RaytraceError;
use crate::resolve::density_estimation;
use crate::scene::Scene;
use crate::scene::spec::RenderSettings;
use crate::scene::timeline::LoopMode;
use crate::shot::{Framing, Shot, ShotError};
use crate::splat::Framebuffer;

pub use files::{
    RecordReport, encode_video, ffmpeg_available, frame_path, frame_path_as, frames_to_render, frames_to_render_as,
    is_complete_frame, parse_frame_range, record, record_as,
};
pub use raytrace::TraceOptions;

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
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Raytrace(#[from] RaytraceError),
    #[error(
        "ray-traced frames are 8-bit PNG only (the tracer makes no depth or count layers); leave out --format and --transparent"
    )]
    RaytraceLayers,
    #[error(
        "density estimation writes 8-bit PNG frames only; leave out --format and --transparent, or estimator_radius"
    )]
    EstimationLayers,
}

/// What draws a recording's frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Renderer {
    /// The chaos game's points, as `nlifs render` draws them.
    #[default]
    Chaos,
    /// The ray tracer of `nlifs snapshot`, with its options.
    Raytrace(TraceOptions),
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
    /// The chaos game (`points_per_frame` applies) or the ray tracer (its options apply).
    pub renderer: Renderer,
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
            renderer: Renderer::Chaos,
        }
    }
}

/// Renders frames of one scene.
pub struct Recorder<'a> {
    scene: &'a Scene,
    settings: RecordSettings,
    /// The bounds every frame is framed and depth-cued on.
    bounds: (DVec3, DVec3),
    /// Where the chaos game runs when not on the CPU.
    gpu: Option<Mutex<GpuFrames>>,
}

/// The GPU that a recorder's chaos game runs on, with its buffers kept from frame to frame.
struct GpuFrames {
    ctx: GpuContext,
    splatter: GpuSplatter,
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
        Ok(Self { scene, settings, bounds, gpu: None })
    }

    /// The recorder with its chaos game on `ctx`'s GPU, in fixed batches (reproducible bytes
    /// on one adapter). Fails where a frame's accumulation does not fit the device.
    pub fn on_gpu(mut self, ctx: GpuContext) -> Result<Self, RecordError> {
        let plan = crate::gpu::batch::BatchPlan::new(self.settings.points_per_frame.unwrap_or(1));
        crate::gpu::batch::check_fits(&ctx, self.settings.width, self.settings.height, plan.threads)?;
        self.gpu = Some(Mutex::new(GpuFrames { ctx, splatter: GpuSplatter::new(BatchSizing::Fixed) }));
        Ok(self)
    }

    /// The GPU adapter the chaos game runs on (None: the CPU).
    pub fn gpu_adapter(&self) -> Option<String> {
        self.gpu.as_ref().map(|g| g.lock().unwrap_or_else(|e| e.into_inner()).ctx.describe())
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

    /// Renders frame `frame` as an 8-bit image.
    pub fn frame(&self, frame: u32) -> Result<image::RgbImage, RecordError> {
        if let Renderer::Raytrace(options) = &self.settings.renderer {
            return raytrace::frame(self, options, frame);
        }
        let mut images = Vec::new();
        self.for_each_sample(frame, &mut |fb, shot| {
            let de = shot.settings.density_estimation.as_ref();
            images.push(density_estimation::resolve_image(fb, &shot.camera, &shot.style, de))
        })?;
        Ok(if images.len() == 1 { images.remove(0) } else { average_linear(&images) })
    }

    /// Renders frame `frame` as linear layers (for the float and alpha outputs): the temporal
    /// samples averaged in linear light ([`ImageLayers::average`]). Chaos game only.
    pub fn frame_layers(&self, frame: u32) -> Result<ImageLayers, RecordError> {
        if self.settings.renderer != Renderer::Chaos {
            return Err(RecordError::RaytraceLayers);
        }
        if density_estimation::applies(self.scene.render.density_estimation.as_ref(), self.scene.render.mode).is_some()
        {
            return Err(RecordError::EstimationLayers);
        }
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
        // The CPU chaos game's frames keep the settings (and the bytes) they always had; the
        // other engines say what they are, so their frames' fingerprints differ.
        let mut settings = settings;
        if let Some(obj) = settings.as_object_mut() {
            if let Some(adapter) = self.gpu_adapter() {
                obj.insert("backend".into(), "gpu".into());
                obj.insert("adapter".into(), adapter.into());
            }
            if let Renderer::Raytrace(options) = &s.renderer {
                obj.insert("renderer".into(), "raytrace".into());
                obj.insert("raytrace".into(), options.to_json());
                obj.remove("points_per_frame");
            }
        }
        Provenance::for_frame(self.scene, frame, self.time_of(frame), settings)
    }

    /// The accumulations of frame `frame`'s temporal samples, with their shots (tests compare
    /// the engines' densities on these).
    pub fn sample_framebuffers(&self, frame: u32) -> Result<Vec<(Framebuffer, Shot)>, RecordError> {
        let mut out = Vec::new();
        self.for_each_sample(frame, &mut |fb, shot| out.push((fb.clone(), shot.clone())))?;
        Ok(out)
    }

    /// Runs the chaos game of each temporal sample of frame `frame` (on the CPU or the GPU) and
    /// hands its framebuffer and shot to `each`.
    fn for_each_sample(&self, frame: u32, each: &mut dyn FnMut(&Framebuffer, &Shot)) -> Result<(), RecordError> {
        let (width, height) = (self.settings.width, self.settings.height);
        for sample in self.samples(frame) {
            let FrameSample { t_secs, camera, bounds, points, stream, render } = sample;
            let settings = RenderSettings { width, height, points, ..render };
            let shot =
                Shot::prepare(self.scene, t_secs, &settings, Framing::Given(camera), Some(bounds))?.with_stream(stream);
            let fb = match &self.gpu {
                None => shot.splat(|| {}),
                Some(gpu) => {
                    let mut guard = gpu.lock().unwrap_or_else(|e| e.into_inner());
                    let GpuFrames { ctx, splatter } = &mut *guard;
                    splatter.splat(ctx, &shot)?.0
                }
            };
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_average_of_black_and_white_is_mid_grey_in_light() {
        let black = image::RgbImage::from_pixel(1, 1, image::Rgb([0, 0, 0]));
        let white = image::RgbImage::from_pixel(1, 1, image::Rgb([255, 255, 255]));
        // Half of the light is sRGB 0.735 → 188.
        assert_eq!(average_linear(&[black, white]).get_pixel(0, 0).0, [188, 188, 188]);
    }
}
