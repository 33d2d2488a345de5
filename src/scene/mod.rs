//! A scene: the IFS as editable definitions, its camera, render settings and timeline, and
//! what they are at a scene time ([`Scene::at`], [`Scene::camera_at`], [`Scene::render_at`]).
//!
//! The module is layered so that nothing here forms a cycle: `spec.rs` holds the plain types
//! (function definitions, camera and render settings) that everything else shares;
//! `timeline.rs` interpolates keys of those types without knowing `Scene`; this file puts them
//! together. Reading is two passes: serde reads the text into the span-keeping structs of
//! `file.rs`, then `check/` checks the meaning and reports any problem with the file, line,
//! column and field ([`Scene::load`], [`Scene::parse`]). `write.rs` writes a scene back
//! ([`Scene::to_toml`]), `rewrite.rs` over the file it was read from, keeping the file's form
//! ([`Scene::to_toml_over`]); `timeline_check.rs` checks contractivity along the timeline.

use std::path::PathBuf;

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::model::{Function, GridMap, Ifs, Map, ProbabilityMode, RectGrid};
use crate::scene::spec::{CameraSpec, FunctionDef, FunctionSpec, RenderSettings};
use crate::scene::timeline::Timeline;

pub mod blend;
mod check;
pub mod file;
pub mod flame_import;
mod rewrite;
pub mod spec;
pub mod timeline;
pub mod timeline_check;
pub mod url;
pub mod warnings;
mod write;

/// A problem in a scene file, located.
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}:{column}: {message}")]
pub struct SceneError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    /// The dotted path of the field at fault, when known (e.g. `function[2].points`).
    pub field: Option<String>,
    pub message: String,
}

/// Why a scene file could not be read. The operating system's reason is part of the message
/// and not a `source`, so that a printed error chain shows it once.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("cannot read scene file {path}: {cause}")]
    Io { path: String, cause: std::io::Error },
    #[error("{path} is larger than {limit_bytes} bytes, the most a scene file may have")]
    TooLarge { path: String, limit_bytes: u64 },
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A flame file (`.flame`, `.flam3`) that cannot be read or made a scene
    /// (`flame_import.rs`).
    #[error("{0}")]
    Flame(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub path: Option<PathBuf>,
    pub name: String,
    pub description: String,
    pub domain: RectGrid,
    pub functions: Vec<FunctionSpec>,
    pub probability_mode: ProbabilityMode,
    pub camera: CameraSpec,
    pub render: RenderSettings,
    /// Keys animating the functions, camera and render settings; None for a still scene.
    pub timeline: Option<Timeline>,
    /// flam3's final xform (`[final]`), applied to every drawn point; not keyed.
    pub final_xform: Option<spec::FinalXform>,
}

impl Scene {
    /// The resolved IFS at scene time `t_secs`: every function's definition interpolated
    /// between the keys around `t_secs`, then resolved (scenes without a timeline are static).
    pub fn at(&self, t_secs: f64) -> Ifs {
        let functions = self
            .functions
            .iter()
            .enumerate()
            .map(|(i, f)| Function {
                name: f.name.clone(),
                map: self.resolve(&self.function_def_at(i, t_secs)),
                color: f.color,
                weight: f.probability,
                enabled: f.enabled,
                xaos: f.xaos.clone(),
            })
            .collect();
        Ifs {
            domain: self.domain.clone(),
            functions,
            probability_mode: self.probability_mode,
            final_xform: self.final_xform.as_ref().map(spec::FinalXform::xform),
        }
    }

    /// Function `i`'s definition at scene time `t_secs` (interpolated, not yet resolved).
    pub fn function_def_at(&self, i: usize, t_secs: f64) -> FunctionDef {
        let base = &self.functions[i].def;
        let Some(tl) = &self.timeline else { return base.clone() };
        tl.channel_at(t_secs, |k| k.function(i).map(spec::flatten))
            .and_then(|v| spec::unflatten(base, &v))
            .unwrap_or_else(|| base.clone())
    }

    /// The camera settings at scene time `t_secs`: each orbit parameter interpolated over the
    /// keys that set it, else the scene's.
    pub fn camera_at(&self, t_secs: f64) -> CameraSpec {
        let mut out = self.camera.clone();
        let Some(tl) = &self.timeline else { return out };
        let scalar = |get: fn(&CameraSpec) -> Option<f64>| {
            tl.channel_at(t_secs, |k| get(&k.camera).map(|v| vec![v])).map(|v| v[0])
        };
        // Yaw is an angle: keys are joined the short way round (see `sample_channel_wrapped`).
        if let Some(v) = tl.angle_channel_at(t_secs, Some(360.0), |k| k.camera.yaw_deg.map(|v| vec![v])) {
            out.yaw_deg = Some(v[0]);
        }
        if let Some(v) = scalar(|c| c.pitch_deg) {
            out.pitch_deg = Some(v.clamp(-89.9, 89.9));
        }
        if let Some(v) = scalar(|c| c.distance) {
            out.distance = Some(v.max(1e-9));
        }
        if let Some(v) = scalar(|c| c.fov_y_deg) {
            out.fov_y_deg = Some(v.clamp(1.0, 170.0));
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.camera.target.map(|p| p.to_array().to_vec())) {
            out.target = Some(DVec3::new(v[0], v[1], v[2]));
        }
        if let Some(k) = tl.held_key(t_secs, |k| k.camera.projection.is_some()) {
            out.projection = k.camera.projection;
        }
        out
    }

    /// The render settings at scene time `t_secs` (depth cue, background, point count and the
    /// tone controls may be keyed).
    pub fn render_at(&self, t_secs: f64) -> RenderSettings {
        let mut out = self.render.clone();
        let Some(tl) = &self.timeline else { return out };
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.depth_cue.map(|v| vec![v as f64])) {
            out.depth_cue = v[0].clamp(0.0, 1.0) as f32;
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.background.map(|c| c.iter().map(|&x| x as f64).collect())) {
            out.background = [0, 1, 2].map(|c| v[c].clamp(0.0, 1.0) as f32);
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.points.map(|n| vec![n as f64])) {
            out.points = v[0].round().max(1.0) as u64;
        }
        // The tone controls, each within its range.
        for (i, ((_, lo, hi), slot)) in spec::TONE_FIELDS.into_iter().zip(out.tone_mut()).enumerate() {
            if let Some(v) = tl.channel_at(t_secs, |k| k.render.tone[i].map(|v| vec![v as f64])) {
                *slot = v[0].clamp(lo, hi) as f32;
            }
        }
        // The key light, each within its range.
        let channel = |i: usize| tl.channel_at(t_secs, |k| k.render.light[i].map(|v| vec![v as f64]));
        let [(_, lo, hi), yaw_field, pitch_field] = spec::LIGHT_FIELDS;
        if let Some(v) = channel(0) {
            out.shadows = Some(v[0].clamp(lo, hi) as f32);
        }
        for (i, ((_, lo, hi), slot)) in [yaw_field, pitch_field].into_iter().zip(out.light_mut()).enumerate() {
            if let Some(v) = channel(i + 1) {
                *slot = v[0].clamp(lo, hi) as f32;
            }
        }
        // Depth of field: aperture ≥ 0, focus distance > 0.
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.aperture.map(|v| vec![v as f64])) {
            out.aperture = v[0].max(0.0) as f32;
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.focus_distance.map(|v| vec![v as f64])) {
            out.focus_distance = Some((v[0] as f32).max(f32::MIN_POSITIVE));
        }
        out
    }

    /// Whether a key of the timeline holds function `function`'s definition.
    pub fn is_keyed(&self, function: usize) -> bool {
        self.timeline.as_ref().is_some_and(|tl| tl.keys.iter().any(|k| k.function(function).is_some()))
    }

    /// Whether a function is a flame (`kind = "flame"`).
    pub fn has_flames(&self) -> bool {
        self.functions.iter().any(|f| matches!(f.def, FunctionDef::Flame(_)))
    }

    /// Turns one definition into a map over the scene's grid.
    pub fn resolve(&self, def: &FunctionDef) -> Map {
        match def {
            FunctionDef::Grid { points } => Map::Grid(GridMap::new(self.domain.clone(), points.clone())),
            FunctionDef::Builder { resolution, builder } => {
                let grid = RectGrid::uniform(self.domain.min(), self.domain.max(), *resolution);
                Map::Grid(GridMap::from_fn(grid, |p| builder.apply(p)))
            }
            FunctionDef::Affine(a) => Map::Affine(a.clone()),
            FunctionDef::Julia(j) => Map::Julia(j.clone()),
            FunctionDef::Flame(f) => Map::Flame(crate::model::FlameMap { xform: f.xform() }),
        }
    }

    /// The scene camera (at time 0) with unset fields filled in from `bounds` (the attractor's box).
    pub fn camera_for(&self, bounds: (DVec3, DVec3)) -> OrbitCamera {
        self.camera_for_at(0.0, bounds)
    }

    /// The camera at scene time `t_secs` with unset fields filled in from `bounds`.
    pub fn camera_for_at(&self, t_secs: f64, bounds: (DVec3, DVec3)) -> OrbitCamera {
        let dim = self.domain.dimension();
        let mut cam = OrbitCamera::framing(bounds, dim);
        let c = &self.camera_at(t_secs);
        if let Some(v) = c.yaw_deg {
            cam.yaw_deg = v as f32;
        }
        if let Some(v) = c.pitch_deg {
            cam.pitch_deg = v as f32;
        }
        if let Some(v) = c.fov_y_deg {
            cam.fov_y_deg = v as f32;
        }
        if let Some(v) = c.projection {
            cam.projection = v;
        }
        if let Some(v) = c.target {
            cam.target = v.as_vec3();
        }
        // Re-frame with the final angles unless the distance is given.
        cam.distance = match c.distance {
            Some(d) => d as f32,
            None => cam.framing_distance(bounds),
        };
        cam
    }
}
