//! Ray-traced stills of the deterministic approximation W^n(A) of a scene's attractor, with the
//! nested W^k(A) as bounding hierarchy (Gröller's rendering section, after Hart & DeFanti).
//!
//! The split follows pbrt: `geometry` holds the node, ray and hit types and the ray–sphere
//! roots; `hierarchy` builds the nodes (it knows only spheres and triangles), `wide` collapses
//! them into the wide nodes that `search` traverses one ray at a time and `packet` up to 16
//! rays at a time; `tracer` makes camera rays and lights, `stream` traces the rows, each a
//! run of pixels' samples at a time, phase by phase (camera rays, searches, shading), `mesh` provides
//! the mesh initial objects (grid surface, glTF), `export` writes W^n(A) as glTF or as a
//! POV-Ray scene.
//! [`render`] is the entry point for the command line and for a viewer's background thread.

mod error;
pub mod export;
pub mod geometry;
mod gltf_input;
pub mod hierarchy;
pub mod mesh;
mod packet;
pub mod search;
mod stream;
pub mod tracer;
pub mod wide;

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use glam::{DVec3, Vec3};

use crate::camera::{OrbitCamera, Projection};
use crate::model::Ifs;
use crate::scene::Scene;
pub use error::RaytraceError;
use hierarchy::{Hierarchy, InitialObject, PixelFootprint, Stop};
use mesh::Mesh;
pub use tracer::{ColorMode, Light, Shading, TraceStats};

/// The initial object A.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Initial {
    /// The sphere bounding the initial grid.
    #[default]
    Sphere,
    /// The initial grid box's outer surface, tessellated.
    Grid,
    /// A glTF mesh, fitted into the grid's box.
    Gltf(PathBuf),
}

impl Initial {
    /// `sphere`, `grid`, or a path to a .glb/.gltf file.
    pub fn parse(text: &str) -> Self {
        match text {
            "sphere" => Initial::Sphere,
            "grid" => Initial::Grid,
            path => Initial::Gltf(PathBuf::from(path)),
        }
    }
}

/// Geometry and image settings of a ray-traced still.
#[derive(Clone, Debug)]
pub struct RaytraceSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (stratified).
    pub spp: u32,
    /// n of W^n(A); with `adaptive`, the cap.
    pub depth: u32,
    /// Stop refining where a node's sphere projects smaller than `stop_pixels` pixels.
    pub adaptive: bool,
    /// Projected diameter (pixels) below which the adaptive stop leaves a node unrefined.
    pub stop_pixels: f32,
    pub initial: Initial,
    pub color_mode: ColorMode,
    pub shadows: bool,
    pub ground: bool,
    pub seed: u32,
    /// Linear RGB; None: the scene's background.
    pub background: Option<[f32; 3]>,
}

impl Default for RaytraceSettings {
    fn default() -> Self {
        Self {
            width: 960,
            height: 720,
            spp: 4,
            depth: 6,
            adaptive: false,
            stop_pixels: 1.0,
            initial: Initial::Sphere,
            color_mode: ColorMode::Function,
            shadows: true,
            ground: true,
            seed: 1,
            background: None,
        }
    }
}

/// Triangle budget for the grid surface: the tessellation of each face is chosen so that all
/// leaves together stay near this many triangles (at least 1, at most 24 quads per face edge).
const GRID_TRIANGLE_BUDGET: f64 = 2.0e6;

/// The initial object for `ifs` (grid tessellation sized for about `leaves` leaves).
pub fn initial_object(ifs: &Ifs, initial: &Initial, leaves: f64) -> Result<InitialObject, RaytraceError> {
    let (lo, hi) = (ifs.domain.min(), ifs.domain.max());
    Ok(match initial {
        Initial::Sphere => InitialObject::Sphere,
        Initial::Grid => {
            let s = (GRID_TRIANGLE_BUDGET / (12.0 * leaves.max(1.0))).sqrt().floor().clamp(1.0, 24.0) as usize;
            InitialObject::Mesh(Mesh::box_surface(lo, hi, s))
        }
        Initial::Gltf(path) => InitialObject::Mesh(mesh::load_gltf(path, lo, hi)?),
    })
}

/// Builds W^depth(A) (fixed depth, no camera needed).
pub fn build_fixed(ifs: &Ifs, initial: &Initial, depth: u32) -> Result<Hierarchy, RaytraceError> {
    let m = ifs.active().len().max(1) as f64;
    let object = initial_object(ifs, initial, m.powi(depth as i32))?;
    Hierarchy::build(ifs, &object, Stop { max_depth: depth, pixel: None })
}

/// Axis-aligned bounds of W^k(A) for the deepest k ≤ depth with at most 4,096 leaves; they
/// contain every deeper W^n(A) because W(A) ⊆ A. What the camera frames when the adaptive
/// build needs a camera first.
fn framing_bounds(ifs: &Ifs, initial: &Initial, depth: u32) -> Result<(DVec3, DVec3), RaytraceError> {
    let m = ifs.active().len().max(2) as f64;
    let k = (4096f64.ln() / m.ln()).floor() as u32;
    let h = build_fixed(ifs, initial, depth.min(k.max(1)))?;
    Ok((h.bounds.0.as_dvec3(), h.bounds.1.as_dvec3()))
}

/// What [`render`] produced.
pub struct Traced {
    pub image: image::RgbImage,
    pub camera: OrbitCamera,
    pub stats: TraceStats,
    pub leaf_count: usize,
    pub node_count: usize,
    pub max_depth: u32,
    pub build_secs: f64,
    pub trace_secs: f64,
}

/// W^n(A) of `ifs` (the scene at `t_secs`) as `settings` ask, and the camera that sees it:
/// `camera`, or else the scene's camera framed on the geometry. What [`render`] traces (the
/// adaptive stop needs the camera first); `nlifs bench record` times it alone.
pub fn build(
    scene: &Scene,
    ifs: &Ifs,
    t_secs: f64,
    camera: Option<OrbitCamera>,
    settings: &RaytraceSettings,
) -> Result<(Hierarchy, OrbitCamera), RaytraceError> {
    if settings.adaptive {
        let camera = match camera {
            Some(c) => c,
            None => scene.camera_for_at(t_secs, framing_bounds(ifs, &settings.initial, settings.depth)?),
        };
        let rays = tracer::CameraRays::new(&camera, settings.width, settings.height, 1.0);
        let pixel = PixelFootprint {
            eye: camera.eye(),
            perspective: camera.projection == Projection::Perspective,
            per_pixel: rays.per_pixel() * settings.stop_pixels.max(1e-3),
        };
        let m = ifs.active().len().max(1) as f64;
        let object = initial_object(ifs, &settings.initial, m.powi(settings.depth as i32))?;
        Ok((Hierarchy::build(ifs, &object, Stop { max_depth: settings.depth, pixel: Some(pixel) })?, camera))
    } else {
        let h = build_fixed(ifs, &settings.initial, settings.depth)?;
        let camera =
            camera.unwrap_or_else(|| scene.camera_for_at(t_secs, (h.bounds.0.as_dvec3(), h.bounds.1.as_dvec3())));
        Ok((h, camera))
    }
}

/// Ray-traces `scene` at `t_secs`. `camera` overrides the scene camera (which is otherwise
/// framed on the geometry). `progress(rows_done, rows)` is called from worker threads; setting
/// `cancel` makes it return [`RaytraceError::Cancelled`] within a row's time. Safe to run on a
/// background thread.
pub fn render(
    scene: &Scene,
    t_secs: f64,
    camera: Option<OrbitCamera>,
    settings: &RaytraceSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<Traced, RaytraceError> {
    let ifs = scene.at(t_secs);
    let start = crate::platform::Instant::now();
    let (hierarchy, camera) = build(scene, &ifs, t_secs, camera, settings)?;
    let build_secs = start.elapsed().as_secs_f64();
    let shading = shading_for(scene, &ifs, &camera, settings);
    let start = crate::platform::Instant::now();
    let (image, stats) = stream::trace(&hierarchy, &camera, &shading, progress, cancel)?;
    Ok(Traced {
        image,
        camera,
        stats,
        leaf_count: hierarchy.leaf_count,
        node_count: hierarchy.nodes.len(),
        max_depth: hierarchy.max_depth,
        build_secs,
        trace_secs: start.elapsed().as_secs_f64(),
    })
}

/// The tracer's settings for a scene and camera.
pub fn shading_for(scene: &Scene, ifs: &Ifs, camera: &OrbitCamera, settings: &RaytraceSettings) -> Shading {
    Shading {
        width: settings.width,
        height: settings.height,
        spp: settings.spp,
        seed: settings.seed,
        lights: tracer::default_lights(camera),
        shadows: settings.shadows,
        ground: settings.ground,
        background: Vec3::from(settings.background.unwrap_or(scene.render.background)),
        ambient: 0.15,
        color_mode: settings.color_mode,
        function_colors: ifs.active().iter().map(|&i| Vec3::from(ifs.functions[i].color)).collect(),
    }
}
