//! Camera rays, lights and shading settings of the tracer: stratified (Latin hypercube)
//! jittered samples per pixel from the seeded PCG stream of that pixel, Lambert plus a little
//! Blinn–Phong under directional lights with shadow rays, an optional ground plane that fades
//! into the background, linear accumulation and one sRGB encode per pixel at the end. The
//! image is traced by `stream`, row by row, a run of pixels at a time; this file also
//! writes what the tracer uses as text for a comparison program (`tools/embree/`).

use glam::Vec3;

use super::geometry::Ray;
use super::hierarchy::Hierarchy;
use crate::camera::{OrbitCamera, Projection};

/// How surfaces are coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColorMode {
    /// The colour of the outermost function w_i1 of the leaf w_i1∘…∘w_in(A): the part of the
    /// attractor it lies in, as the chaos game colours points and as the paper's plates do.
    #[default]
    Function,
    /// A ramp over the leaf's depth (useful with the adaptive stop).
    Depth,
}

/// A directional light: unit direction towards the light, linear RGB intensity.
#[derive(Clone, Copy, Debug)]
pub struct Light {
    pub to_light: Vec3,
    pub intensity: Vec3,
}

/// Everything the tracer needs besides the geometry.
#[derive(Clone, Debug)]
pub struct Shading {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u32,
    pub lights: Vec<Light>,
    pub shadows: bool,
    pub ground: bool,
    /// Linear RGB.
    pub background: Vec3,
    pub ambient: f32,
    pub color_mode: ColorMode,
    /// Linear RGB per function (in the order of the IFS's enabled functions).
    pub function_colors: Vec<Vec3>,
}

/// Lights placed relative to the camera: a key light above and to the left, a weaker fill
/// light from the right, both casting shadows onto the ground.
pub fn default_lights(camera: &OrbitCamera) -> Vec<Light> {
    let back = camera.eye_direction();
    let right = Vec3::Y.cross(back).try_normalize().unwrap_or(Vec3::X);
    vec![
        Light { to_light: (-0.45 * right + 1.0 * Vec3::Y + 0.55 * back).normalize(), intensity: Vec3::splat(0.85) },
        Light { to_light: (0.8 * right + 0.35 * Vec3::Y + 0.45 * back).normalize(), intensity: Vec3::splat(0.3) },
    ]
}

/// Primary rays of one camera: world-space origin and direction for a point of the image plane.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    pub(super) eye: Vec3,
    pub(super) right: Vec3,
    pub(super) up: Vec3,
    pub(super) forward: Vec3,
    pub(super) half_height: f32,
    pub(super) aspect: f32,
    pub(super) parallel: bool,
    /// Parallel rays start this far behind the eye plane so nothing is behind them.
    pub(super) back_off: f32,
    pub(super) width: f32,
    pub(super) height: f32,
}

impl CameraRays {
    pub fn new(camera: &OrbitCamera, width: u32, height: u32, scene_radius: f32) -> Self {
        let back = camera.eye_direction();
        let right = Vec3::Y.cross(back).try_normalize().unwrap_or(Vec3::X);
        let up = back.cross(right);
        let parallel = camera.projection == Projection::Parallel;
        Self {
            eye: camera.eye(),
            right,
            up,
            forward: -back,
            half_height: if parallel {
                camera.half_height_at_target()
            } else {
                (0.5 * camera.fov_y_deg.to_radians()).tan()
            },
            aspect: width as f32 / height as f32,
            parallel,
            back_off: 4.0 * scene_radius + camera.distance,
            width: width as f32,
            height: height as f32,
        }
    }

    /// The ray through image point (x, y) in pixels, y down.
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.half_height * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.half_height;
        if self.parallel {
            let origin = self.eye + sx * self.right + sy * self.up - self.back_off * self.forward;
            Ray { origin, dir: self.forward }
        } else {
            Ray { origin: self.eye, dir: (self.forward + sx * self.right + sy * self.up).normalize() }
        }
    }

    /// Radians per pixel (perspective) or world units per pixel (parallel), vertically.
    pub fn per_pixel(&self) -> f32 {
        if self.parallel { 2.0 * self.half_height / self.height } else { 2.0 * self.half_height.atan() / self.height }
    }
}

/// Writes everything [`trace`] uses for a sphere hierarchy as text, for a comparison program
/// outside nlifs (`tools/embree/`) to trace the same picture: every f32 as its bit pattern (a
/// decimal u32), so the other side reads the same values. One `name values…` line per item,
/// then one `sphere cx cy cz r function` line per leaf sphere, in node order.
pub fn write_trace_description(
    hierarchy: &Hierarchy,
    camera: &OrbitCamera,
    shading: &Shading,
    out: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let frame = Frame::new(hierarchy);
    let rays = CameraRays::new(camera, shading.width, shading.height, frame.radius);
    let bits = |values: &[f32]| values.iter().map(|v| v.to_bits().to_string()).collect::<Vec<_>>().join(" ");
    writeln!(out, "image {} {} {} {}", shading.width, shading.height, shading.spp.max(1), shading.seed)?;
    writeln!(out, "eye {}", bits(&rays.eye.to_array()))?;
    writeln!(out, "right {}", bits(&rays.right.to_array()))?;
    writeln!(out, "up {}", bits(&rays.up.to_array()))?;
    writeln!(out, "forward {}", bits(&rays.forward.to_array()))?;
    writeln!(out, "view {} {}", bits(&[rays.half_height, rays.aspect, rays.back_off]), rays.parallel as u32)?;
    writeln!(out, "flags {} {}", shading.shadows as u32, shading.ground as u32)?;
    writeln!(
        out,
        "frame {}",
        bits(&[frame.ground_y, frame.centre.x, frame.centre.y, frame.centre.z, frame.radius, frame.eps])
    )?;
    writeln!(out, "ambient {}", bits(&[shading.ambient]))?;
    writeln!(out, "background {}", bits(&shading.background.to_array()))?;
    let root = hierarchy.nodes.first().map_or([0.0; 4], |n| [n.centre.x, n.centre.y, n.centre.z, n.radius]);
    writeln!(out, "root {}", bits(&root))?;
    for light in &shading.lights {
        writeln!(out, "light {} {}", bits(&light.to_light.to_array()), bits(&light.intensity.to_array()))?;
    }
    for colour in &shading.function_colors {
        writeln!(out, "colour {}", bits(&colour.to_array()))?;
    }
    for n in hierarchy.leaf_spheres() {
        writeln!(out, "sphere {} {}", bits(&[n.centre.x, n.centre.y, n.centre.z, n.radius]), n.function)?;
    }
    Ok(())
}

/// Counts of rays traced.
#[derive(Clone, Copy, Debug, Default)]
pub struct TraceStats {
    pub primary_rays: u64,
    pub shadow_rays: u64,
    /// Primary rays that hit a leaf of W^n(A) (0: the camera saw none of it).
    pub leaf_hits: u64,
}

/// What the shading needs of the geometry's bounds: the ground plane just below the lowest
/// leaf, the centre and radius of the bounds (the ground's fade), the shadow rays' offset.
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame {
    pub ground_y: f32,
    pub centre: Vec3,
    pub radius: f32,
    pub eps: f32,
}

impl Frame {
    pub fn new(hierarchy: &Hierarchy) -> Self {
        let (lo, hi) = hierarchy.bounds;
        let (lo, hi) = if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (Vec3::ZERO, Vec3::ZERO) };
        let centre = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-6);
        Self { ground_y: lo.y - 1e-3 * radius, centre, radius, eps: 1e-4 * radius }
    }
}

/// A ramp from blue (shallow) through green to orange (deep).
pub(super) fn depth_color(depth: u8, max_depth: u32) -> Vec3 {
    let s = if max_depth == 0 { 0.0 } else { depth as f32 / max_depth as f32 };
    let stops = [Vec3::new(0.05, 0.15, 0.8), Vec3::new(0.1, 0.6, 0.2), Vec3::new(0.95, 0.45, 0.05)];
    let x = s * 2.0;
    let k = (x as usize).min(1);
    stops[k].lerp(stops[k + 1], x - k as f32)
}
