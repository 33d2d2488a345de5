//! Camera rays, shading and sampling: stratified (Latin hypercube) jittered samples per pixel
//! from the seeded PCG stream of that pixel, Lambert plus a little Blinn–Phong under
//! directional lights with shadow rays, an optional ground plane that fades into the
//! background, linear accumulation and one sRGB encode per pixel at the end.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::error::RaytraceError;
use super::geometry::{Hit, Ray};
use super::hierarchy::Hierarchy;
use super::search::Scratch;
use crate::camera::{OrbitCamera, Projection};
use crate::color::Srgb8Table;
use crate::rng::Pcg32;

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
    eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    half_height: f32,
    aspect: f32,
    parallel: bool,
    /// Parallel rays start this far behind the eye plane so nothing is behind them.
    back_off: f32,
    width: f32,
    height: f32,
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

/// Counts of rays traced.
#[derive(Clone, Copy, Debug, Default)]
pub struct TraceStats {
    pub primary_rays: u64,
    pub shadow_rays: u64,
    /// Primary rays that hit a leaf of W^n(A) (0: the camera saw none of it).
    pub leaf_hits: u64,
}

/// Samples of a pixel traced together (more are traced in batches of this many).
const BATCH: usize = 16;

/// Per-row state: traversal stacks and the last occluder per light.
struct RowScratch {
    stacks: Scratch,
    last_occluder: Vec<u32>,
    /// The leaf the previous primary ray hit (tried first by the next one).
    last_hit: u32,
}

struct Tracer<'a> {
    hierarchy: &'a Hierarchy,
    shading: &'a Shading,
    ground_y: f32,
    centre: Vec3,
    radius: f32,
    eps: f32,
}

/// A ramp from blue (shallow) through green to orange (deep).
fn depth_color(depth: u8, max_depth: u32) -> Vec3 {
    let s = if max_depth == 0 { 0.0 } else { depth as f32 / max_depth as f32 };
    let stops = [Vec3::new(0.05, 0.15, 0.8), Vec3::new(0.1, 0.6, 0.2), Vec3::new(0.95, 0.45, 0.05)];
    let x = s * 2.0;
    let k = (x as usize).min(1);
    stops[k].lerp(stops[k + 1], x - k as f32)
}

impl Tracer<'_> {
    fn albedo(&self, hit: &Hit) -> Vec3 {
        let node = &self.hierarchy.nodes[hit.node as usize];
        match self.shading.color_mode {
            ColorMode::Function => {
                self.shading.function_colors.get(node.function as usize).copied().unwrap_or(Vec3::splat(0.7))
            }
            ColorMode::Depth => depth_color(node.depth, self.hierarchy.max_depth),
        }
    }

    /// The summed radiance of a pixel's samples `rays` (at most [`BATCH`]), traced phase by
    /// phase: every ray's root test, then the nearest hits, then per light every shadow ray's
    /// root test and search. The root tests have no branches, so the rays' arithmetic
    /// overlaps; most rays of a still miss the root's bound and cost no more than that. Each
    /// sample's colour is the same sum in the same order as shading it alone.
    fn samples(&self, rays: &[Ray], stats: &mut TraceStats, scratch: &mut RowScratch) -> Vec3 {
        let count = rays.len();
        stats.primary_rays += count as u64;
        let mut t_ground = [f32::INFINITY; BATCH];
        let mut entry = [f32::INFINITY; BATCH];
        for (k, ray) in rays.iter().enumerate() {
            let t = if self.shading.ground && ray.dir.y < -1e-6 {
                (self.ground_y - ray.origin.y) / ray.dir.y
            } else {
                f32::INFINITY
            };
            t_ground[k] = if t > 0.0 { t } else { f32::INFINITY };
            entry[k] = self.hierarchy.root_entry(ray, 0.0, t_ground[k]);
        }
        // What each sample sees: a leaf (specular 0.25), the ground (no specular, faded into
        // the background) or the background.
        let mut point = [Vec3::ZERO; BATCH];
        let mut normal = [Vec3::ZERO; BATCH];
        let mut albedo = [Vec3::ZERO; BATCH];
        let mut specular = [0.0f32; BATCH];
        let mut lit: u32 = 0;
        let mut on_ground: u32 = 0;
        for (k, ray) in rays.iter().enumerate() {
            if entry[k] < f32::INFINITY
                && let Some(hit) = self.hierarchy.intersect_entered(
                    ray,
                    0.0,
                    t_ground[k],
                    entry[k],
                    scratch.last_hit,
                    &mut scratch.stacks,
                )
            {
                scratch.last_hit = hit.node;
                stats.leaf_hits += 1;
                (point[k], normal[k]) = self.hierarchy.surface(ray, &hit);
                albedo[k] = self.albedo(&hit);
                specular[k] = 0.25;
                lit |= 1 << k;
                continue;
            }
            if t_ground[k].is_finite() {
                point[k] = ray.origin + t_ground[k] * ray.dir;
                normal[k] = Vec3::Y;
                albedo[k] = Vec3::splat(0.55);
                lit |= 1 << k;
                on_ground |= 1 << k;
            }
        }
        let mut colour = [Vec3::ZERO; BATCH];
        for k in 0..count {
            colour[k] = albedo[k] * self.shading.ambient;
        }
        for (index, light) in self.shading.lights.iter().enumerate() {
            let mut facing: u32 = 0;
            let mut cos = [0.0f32; BATCH];
            for k in 0..count {
                cos[k] = normal[k].dot(light.to_light);
                facing |= ((cos[k] > 0.0) as u32) << k;
            }
            facing &= lit;
            let mut shaded = facing;
            if self.shading.shadows {
                stats.shadow_rays += facing.count_ones() as u64;
                let mut shadow = [Ray { origin: Vec3::ZERO, dir: light.to_light }; BATCH];
                let mut entry = [f32::INFINITY; BATCH];
                for k in 0..count {
                    shadow[k].origin = point[k] + normal[k] * self.eps;
                    entry[k] = self.hierarchy.root_entry(&shadow[k], 0.0, f32::INFINITY);
                }
                let mut search = facing;
                while search != 0 {
                    let k = search.trailing_zeros() as usize;
                    search &= search - 1;
                    if entry[k] == f32::INFINITY {
                        continue;
                    }
                    // Shadow cache (Haines & Greenberg): neighbouring shadow rays are often
                    // blocked by the same leaf, so it is tried before a full search.
                    let cached = scratch.last_occluder[index];
                    if let Some(leaf) =
                        self.hierarchy.occluder_entered(&shadow[k], 0.0, f32::INFINITY, cached, &mut scratch.stacks)
                    {
                        scratch.last_occluder[index] = leaf;
                        shaded &= !(1 << k);
                    }
                }
            }
            while shaded != 0 {
                let k = shaded.trailing_zeros() as usize;
                shaded &= shaded - 1;
                let mut light_k = albedo[k] * cos[k];
                if specular[k] > 0.0 {
                    let h = (light.to_light - rays[k].dir).normalize();
                    light_k += Vec3::splat(specular[k] * normal[k].dot(h).max(0.0).powi(32));
                }
                colour[k] += light.intensity * light_k;
            }
        }
        let mut sum = Vec3::ZERO;
        for k in 0..count {
            sum += if on_ground & (1 << k) != 0 {
                let d = (point[k] - self.centre).length() / (2.5 * self.radius);
                let fade = (-d * d).exp();
                self.shading.background.lerp(colour[k], fade)
            } else if lit & (1 << k) != 0 {
                colour[k]
            } else {
                self.shading.background
            };
        }
        sum
    }
}

/// Traces the image row by row on rayon's pool. `progress(rows_done, rows)`; `cancel` is
/// checked before each row.
pub fn trace(
    hierarchy: &Hierarchy,
    camera: &OrbitCamera,
    shading: &Shading,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<(image::RgbImage, TraceStats), RaytraceError> {
    let (w, h) = (shading.width, shading.height);
    let (lo, hi) = hierarchy.bounds;
    let (lo, hi) = if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (Vec3::ZERO, Vec3::ZERO) };
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-6);
    let rays = CameraRays::new(camera, w, h, radius);
    let tracer = Tracer { hierarchy, shading, ground_y: lo.y - 1e-3 * radius, centre, radius, eps: 1e-4 * radius };
    let spp = shading.spp.max(1);
    let done = AtomicU64::new(0);
    let primary = AtomicU64::new(0);
    let shadow = AtomicU64::new(0);
    let hits = AtomicU64::new(0);
    let srgb = Srgb8Table::new();
    let mut pixels = vec![0u8; w as usize * h as usize * 3];
    pixels.par_chunks_mut(w as usize * 3).enumerate().try_for_each(|(y, row)| {
        if cancel.load(Ordering::Relaxed) {
            return Err(RaytraceError::Cancelled);
        }
        let mut stats = TraceStats::default();
        let mut scratch = RowScratch {
            stacks: Scratch::default(),
            last_occluder: vec![u32::MAX; shading.lights.len()],
            last_hit: u32::MAX,
        };
        let mut strata: Vec<u32> = (0..spp).collect();
        for x in 0..w as usize {
            let mut rng = Pcg32::for_stream(shading.seed, 0, (y * w as usize + x) as u32);
            // Latin hypercube: sample i takes x-stratum i and a shuffled y-stratum.
            for i in (1..strata.len()).rev() {
                // Lemire's multiply-shift: an index in 0..=i without a division.
                let j = ((rng.next_u32() as u64 * (i as u64 + 1)) >> 32) as usize;
                strata.swap(i, j);
            }
            let mut sum = Vec3::ZERO;
            let mut batch = [Ray { origin: Vec3::ZERO, dir: Vec3::Z }; BATCH];
            for first in (0..spp).step_by(BATCH) {
                let count = (spp - first).min(BATCH as u32);
                for (k, ray) in batch[..count as usize].iter_mut().enumerate() {
                    let i = first + k as u32;
                    let sx = (i as f32 + rng.next_f32()) / spp as f32;
                    let sy = (strata[i as usize] as f32 + rng.next_f32()) / spp as f32;
                    *ray = rays.ray(x as f32 + sx, y as f32 + sy);
                }
                sum += tracer.samples(&batch[..count as usize], &mut stats, &mut scratch);
            }
            let c = sum / spp as f32;
            row[3 * x..3 * x + 3].copy_from_slice(&c.to_array().map(|v| srgb.encode(v)));
        }
        primary.fetch_add(stats.primary_rays, Ordering::Relaxed);
        shadow.fetch_add(stats.shadow_rays, Ordering::Relaxed);
        hits.fetch_add(stats.leaf_hits, Ordering::Relaxed);
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, h as u64);
        Ok(())
    })?;
    let image = image::RgbImage::from_raw(w, h, pixels).ok_or(RaytraceError::TooLarge("image buffer".into()))?;
    Ok((
        image,
        TraceStats {
            primary_rays: primary.into_inner(),
            shadow_rays: shadow.into_inner(),
            leaf_hits: hits.into_inner(),
        },
    ))
}
