//! Ray-traced frames (`record --renderer raytrace`): each temporal sample of a frame
//! ([`Recorder::samples`]: its time and camera) traced by `nlifs snapshot`'s tracer with the
//! snapshot's options, the samples averaged in linear light as the chaos game's are. The tracer
//! is deterministic (its sample pattern is seeded by the scene's seed), so a frame has the same
//! bytes in any run or chunk, and equals the snapshot of its time seen by its camera.

use std::sync::atomic::AtomicBool;

use crate::raytrace::{self, ColorMode, Initial, RaytraceSettings};

use super::{RecordError, Recorder, average_linear};

/// The snapshot options a ray-traced recording takes (`nlifs snapshot`'s flags; its defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct TraceOptions {
    /// Samples per pixel (stratified).
    pub spp: u32,
    /// n of W^n(A); with `adaptive`, the cap.
    pub depth: u32,
    pub adaptive: bool,
    pub stop_pixels: f32,
    pub initial: Initial,
    pub color_mode: ColorMode,
    pub shadows: bool,
    pub ground: bool,
    /// Linear RGB; None: the scene's background.
    pub background: Option<[f32; 3]>,
}

impl Default for TraceOptions {
    fn default() -> Self {
        let d = RaytraceSettings::default();
        Self {
            spp: d.spp,
            depth: d.depth,
            adaptive: d.adaptive,
            stop_pixels: d.stop_pixels,
            initial: d.initial,
            color_mode: d.color_mode,
            shadows: d.shadows,
            ground: d.ground,
            background: d.background,
        }
    }
}

impl TraceOptions {
    /// The tracer's settings for a `width`×`height` image seeded with `seed`.
    pub fn settings(&self, width: u32, height: u32, seed: u32) -> RaytraceSettings {
        RaytraceSettings {
            width,
            height,
            spp: self.spp,
            depth: self.depth,
            adaptive: self.adaptive,
            stop_pixels: self.stop_pixels,
            initial: self.initial.clone(),
            color_mode: self.color_mode,
            shadows: self.shadows,
            ground: self.ground,
            seed,
            background: self.background,
        }
    }

    /// The options as the frames' text chunks carry them.
    pub fn to_json(&self) -> serde_json::Value {
        let initial = match &self.initial {
            Initial::Sphere => "sphere".to_string(),
            Initial::Grid => "grid".to_string(),
            Initial::Gltf(path) => path.display().to_string(),
        };
        serde_json::json!({
            "spp": self.spp,
            "depth": self.depth,
            "adaptive": self.adaptive,
            "stop_pixels": self.stop_pixels,
            "initial": initial,
            "color": format!("{:?}", self.color_mode).to_lowercase(),
            "shadows": self.shadows,
            "ground": self.ground,
            "background": self.background,
        })
    }
}

/// Frame `frame` of `rec`, traced with `options`: every temporal sample at its time and camera,
/// averaged in linear light.
pub fn frame(rec: &Recorder, options: &TraceOptions, frame: u32) -> Result<image::RgbImage, RecordError> {
    let s = rec.settings();
    // The scene's seed, as `nlifs snapshot` takes it: a frame equals the snapshot of its time.
    let settings = options.settings(s.width, s.height, rec.scene.render.seed);
    let cancel = AtomicBool::new(false);
    let mut images = Vec::new();
    for sample in rec.samples(frame) {
        let traced = raytrace::render(rec.scene, sample.t_secs, Some(sample.camera), &settings, &|_, _| {}, &cancel)?;
        images.push(traced.image);
    }
    Ok(if images.len() == 1 { images.remove(0) } else { average_linear(&images) })
}
