//! The tracer's loops: the image row by row on rayon's pool, and in a row the samples of a run
//! of pixels traced phase by phase as structure of arrays, so that everything but the searches
//! runs as vector loops.
//!
//! How it works. A run of up to [`RUN_PIXELS`] pixels of one row draws its samples (the seeded
//! PCG stream per pixel, Latin hypercube strata) into image-plane positions, then every phase
//! goes over all the run's samples at once: camera rays, the ground plane and the root bound's
//! entry (one branch-free loop); the nearest-hit search for the few rays that enter the root
//! bound (packets of up to 16 neighbouring samples, `packet`, each ray trying the previous
//! hit first); per light the shadow rays' origins and root entries (one loop), the packet
//! any-hit search for those that enter, and the shading (one loop); the ground's fade; the
//! per-pixel sums. The loops hold the same operations in the same order as shading one sample
//! alone (no fused multiply-add, glam's `normalize` as `1 / sqrt` then a product), so a sample's
//! colour is bit for bit that of tracing it alone, except where two leaves are hit at exactly
//! the same t and the packet search keeps the other one. They are compiled once per vector
//! width the CPU may run ([`Simd`]), so the compiler vectorises them for AVX-512 or AVX2.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::error::RaytraceError;
use super::geometry::{Hit, Ray};
use super::hierarchy::Hierarchy;
use super::packet::PACKET;
use super::search::Scratch;
use super::tracer::{CameraRays, ColorMode, Frame, Shading, TraceStats, depth_color};
#[cfg(target_arch = "x86_64")]
use super::wide::Avx512;
#[cfg(target_arch = "x86_64")]
use super::wide::Simd;
use super::wide::{Lanes, Portable};
use crate::camera::OrbitCamera;
use crate::color::Srgb8Table;
use crate::rng::Pcg32;

/// Pixels of a run: their samples' arrays (about 30 floats a sample) stay in the L1 and L2
/// caches.
pub const RUN_PIXELS: usize = 32;

/// Samples of a pixel summed together before they are added to the pixel's sum.
const BATCH: usize = 16;

/// Specular weight of a leaf surface (the ground has none).
const LEAF_SPECULAR: f32 = 0.25;
/// Albedo of the ground plane.
const GROUND_ALBEDO: f32 = 0.55;

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
    let frame = Frame::new(hierarchy);
    let rays = CameraRays::new(camera, w, h, frame.radius);
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
        let mut tracer = RowTracer::new(hierarchy, shading, &rays, frame, &srgb);
        tracer.row(y, row);
        let stats = tracer.stats;
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

/// One row's state: the run's sample arrays, traversal stacks, and the searches' hints.
struct RowTracer<'a> {
    hierarchy: &'a Hierarchy,
    shading: &'a Shading,
    rays: &'a CameraRays,
    frame: Frame,
    srgb: &'a Srgb8Table,
    stacks: Scratch,
    /// The last occluder per light (Haines & Greenberg's shadow cache).
    last_occluder: Vec<u32>,
    /// The leaf the previous primary ray hit (tried first by the next one).
    last_hit: u32,
    /// The y-strata permutation, shuffled again for each pixel of the row.
    strata: Vec<u32>,
    s: Samples,
    stats: TraceStats,
}

/// Per-sample arrays of a run (structure of arrays).
#[derive(Default)]
struct Samples {
    /// Image-plane position, pixels.
    x: Vec<f32>,
    y: Vec<f32>,
    origin: [Vec<f32>; 3],
    dir: [Vec<f32>; 3],
    t_ground: Vec<f32>,
    entry: Vec<f32>,
    point: [Vec<f32>; 3],
    normal: [Vec<f32>; 3],
    albedo: [Vec<f32>; 3],
    specular: Vec<f32>,
    lit: Vec<bool>,
    on_ground: Vec<bool>,
    colour: [Vec<f32>; 3],
    cos: Vec<f32>,
    facing: Vec<bool>,
    shadow_origin: [Vec<f32>; 3],
    shadow_entry: Vec<f32>,
    shaded: Vec<bool>,
    radiance: [Vec<f32>; 3],
}

fn resized<T: Copy + Default, const N: usize>(arrays: &mut [Vec<T>; N], n: usize) {
    for a in arrays {
        a.resize(n, T::default());
    }
}

impl Samples {
    fn resize(&mut self, n: usize) {
        for a in [&mut self.x, &mut self.y, &mut self.t_ground, &mut self.entry, &mut self.specular, &mut self.cos] {
            a.resize(n, 0.0);
        }
        self.shadow_entry.resize(n, 0.0);
        for a in [&mut self.lit, &mut self.on_ground, &mut self.facing, &mut self.shaded] {
            a.resize(n, false);
        }
        resized(&mut self.origin, n);
        resized(&mut self.dir, n);
        resized(&mut self.point, n);
        resized(&mut self.normal, n);
        resized(&mut self.albedo, n);
        resized(&mut self.colour, n);
        resized(&mut self.shadow_origin, n);
        resized(&mut self.radiance, n);
    }
}

/// Where a ray enters a sphere of `centre`, `radius` within (t_min, t_max), clamped to t_min;
/// infinity where it does not. The operations of `Hierarchy::root_entry`.
#[inline(always)]
fn sphere_entry(o: [f32; 3], d: [f32; 3], centre: [f32; 3], radius: f32, t_min: f32, t_max: f32) -> f32 {
    let oc = [o[0] - centre[0], o[1] - centre[1], o[2] - centre[2]];
    let b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
    let l = [oc[0] - b * d[0], oc[1] - b * d[1], oc[2] - b * d[2]];
    let s = (radius * radius - (l[0] * l[0] + l[1] * l[1] + l[2] * l[2])).sqrt();
    let (t0, t1) = (-b - s, -b + s);
    if (t1 > t_min) & (t0 < t_max) { t0.max(t_min) } else { f32::INFINITY }
}

impl<'a> RowTracer<'a> {
    fn new(
        hierarchy: &'a Hierarchy,
        shading: &'a Shading,
        rays: &'a CameraRays,
        frame: Frame,
        srgb: &'a Srgb8Table,
    ) -> Self {
        Self {
            hierarchy,
            shading,
            rays,
            frame,
            srgb,
            stacks: Scratch::default(),
            last_occluder: vec![u32::MAX; shading.lights.len()],
            last_hit: u32::MAX,
            strata: (0..shading.spp.max(1)).collect(),
            s: Samples::default(),
            stats: TraceStats::default(),
        }
    }

    /// Traces row `y` into `row` (RGB bytes), run by run.
    fn row(&mut self, y: usize, row: &mut [u8]) {
        let width = self.shading.width as usize;
        for first in (0..width).step_by(RUN_PIXELS) {
            let pixels = first..(first + RUN_PIXELS).min(width);
            self.run(y, pixels, row);
        }
    }

    fn run(&mut self, y: usize, pixels: std::ops::Range<usize>, row: &mut [u8]) {
        match self.hierarchy.simd() {
            #[cfg(target_arch = "x86_64")]
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: `simd` is only ever set to a form that `Simd::detect` found the CPU runs.
            Simd::Avx512 => unsafe { self.run_avx512(y, pixels, row) },
            #[cfg(target_arch = "x86_64")]
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: as above.
            Simd::Avx2 => unsafe { self.run_avx2(y, pixels, row) },
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: the portable lanes use only the baseline target's instructions.
            _ => unsafe { self.run_any::<Portable>(y, pixels, row) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn run_avx512(&mut self, y: usize, pixels: std::ops::Range<usize>, row: &mut [u8]) {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: this function only runs where AVX-512F is enabled.
        unsafe {
            self.run_any::<Avx512>(y, pixels, row)
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2(&mut self, y: usize, pixels: std::ops::Range<usize>, row: &mut [u8]) {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: the portable lanes need nothing beyond the baseline target.
        unsafe {
            self.run_any::<Portable>(y, pixels, row)
        }
    }

    /// One run, every phase (compiled into each vector width's copy).
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[inline(always)]
    unsafe fn run_any<L: Lanes>(&mut self, y: usize, pixels: std::ops::Range<usize>, row: &mut [u8]) {
        let spp = self.shading.spp.max(1) as usize;
        let n = pixels.len() * spp;
        self.s.resize(n);
        self.positions(y, pixels.clone(), spp);
        self.camera_rays(n);
        // SAFETY: the caller guarantees L's instructions.
        unsafe { self.primary::<L>(n) };
        for (index, light) in self.shading.lights.iter().enumerate() {
            self.shadow_rays(n, light.to_light);
            if self.shading.shadows {
                // SAFETY: as above.
                unsafe { self.occlusion::<L>(n, index, light.to_light) };
            } else {
                self.s.shaded[..n].copy_from_slice(&self.s.facing[..n]);
            }
            self.shade(n, light.to_light, light.intensity);
        }
        self.finish(n);
        let s = &self.s;
        for (p, x) in pixels.enumerate() {
            // Summed in batches of BATCH samples, then the batches, the order nlifs has always
            // summed in, so that pictures with any spp keep their bytes.
            let mut sum = Vec3::ZERO;
            for batch in (p * spp..(p + 1) * spp).step_by(BATCH) {
                let mut part = Vec3::ZERO;
                for k in batch..(batch + BATCH).min((p + 1) * spp) {
                    part += Vec3::new(s.radiance[0][k], s.radiance[1][k], s.radiance[2][k]);
                }
                sum += part;
            }
            let c = sum / spp as f32;
            row[3 * x..3 * x + 3].copy_from_slice(&c.to_array().map(|v| self.srgb.encode(v)));
        }
    }

    /// Image-plane positions of the samples: sample i of a pixel takes x-stratum i and a
    /// shuffled y-stratum (Latin hypercube), jittered by the pixel's PCG stream. The shuffle
    /// permutes the row's permutation further from pixel to pixel.
    #[inline(always)]
    fn positions(&mut self, y: usize, pixels: std::ops::Range<usize>, spp: usize) {
        let width = self.shading.width as usize;
        let strata = &mut self.strata;
        for (p, x) in pixels.enumerate() {
            let mut rng = Pcg32::for_stream(self.shading.seed, 0, (y * width + x) as u32);
            for i in (1..spp).rev() {
                // Lemire's multiply-shift: an index in 0..=i without a division.
                let j = ((rng.next_u32() as u64 * (i as u64 + 1)) >> 32) as usize;
                strata.swap(i, j);
            }
            for (i, &stratum) in strata.iter().enumerate() {
                let sx = (i as f32 + rng.next_f32()) / spp as f32;
                let sy = (stratum as f32 + rng.next_f32()) / spp as f32;
                self.s.x[p * spp + i] = x as f32 + sx;
                self.s.y[p * spp + i] = y as f32 + sy;
            }
        }
    }

    /// Camera rays, their ground-plane distance and root-bound entry (`CameraRays::ray`,
    /// `Hierarchy::root_entry`, operation for operation).
    #[inline(always)]
    fn camera_rays(&mut self, n: usize) {
        let c = self.rays;
        let s = &mut self.s;
        let (xs, ys) = (&s.x[..n], &s.y[..n]);
        let [ox, oy, oz] = &mut s.origin;
        let [dx, dy, dz] = &mut s.dir;
        let (ox, oy, oz, dx, dy, dz) =
            (&mut ox[..n], &mut oy[..n], &mut oz[..n], &mut dx[..n], &mut dy[..n], &mut dz[..n]);
        let (t_ground, entry) = (&mut s.t_ground[..n], &mut s.entry[..n]);
        let (ground, ground_y) = (self.shading.ground, self.frame.ground_y);
        let (root_centre, root_radius) =
            self.hierarchy.nodes.first().map_or(([0.0; 3], f32::NAN), |r| (r.centre.to_array(), r.radius));
        let (e, r, u, f) = (c.eye, c.right, c.up, c.forward);
        for k in 0..n {
            let sx = (2.0 * xs[k] / c.width - 1.0) * c.half_height * c.aspect;
            let sy = (1.0 - 2.0 * ys[k] / c.height) * c.half_height;
            let (o, d) = if c.parallel {
                let o = [
                    e.x + sx * r.x + sy * u.x - c.back_off * f.x,
                    e.y + sx * r.y + sy * u.y - c.back_off * f.y,
                    e.z + sx * r.z + sy * u.z - c.back_off * f.z,
                ];
                (o, [f.x, f.y, f.z])
            } else {
                let d = [f.x + sx * r.x + sy * u.x, f.y + sx * r.y + sy * u.y, f.z + sx * r.z + sy * u.z];
                let rcp = 1.0 / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                ([e.x, e.y, e.z], [d[0] * rcp, d[1] * rcp, d[2] * rcp])
            };
            let t = if ground && d[1] < -1e-6 { (ground_y - o[1]) / d[1] } else { f32::INFINITY };
            let tg = if t > 0.0 { t } else { f32::INFINITY };
            (ox[k], oy[k], oz[k], dx[k], dy[k], dz[k]) = (o[0], o[1], o[2], d[0], d[1], d[2]);
            t_ground[k] = tg;
            entry[k] = sphere_entry(o, d, root_centre, root_radius, 0.0, tg);
        }
    }

    fn ray(&self, k: usize) -> Ray {
        let s = &self.s;
        Ray {
            origin: Vec3::new(s.origin[0][k], s.origin[1][k], s.origin[2][k]),
            dir: Vec3::new(s.dir[0][k], s.dir[1][k], s.dir[2][k]),
        }
    }

    /// What each sample sees: the ground (one loop), then the nearest leaf for the rays that
    /// enter the root bound, in sample order.
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[inline(always)]
    unsafe fn primary<L: Lanes>(&mut self, n: usize) {
        self.stats.primary_rays += n as u64;
        {
            let s = &mut self.s;
            let [ox, oy, oz] = &s.origin;
            let [dx, dy, dz] = &s.dir;
            let (ox, oy, oz, dx, dy, dz) = (&ox[..n], &oy[..n], &oz[..n], &dx[..n], &dy[..n], &dz[..n]);
            let [px, py, pz] = &mut s.point;
            let (px, py, pz) = (&mut px[..n], &mut py[..n], &mut pz[..n]);
            let [nx, ny, nz] = &mut s.normal;
            let (nx, ny, nz) = (&mut nx[..n], &mut ny[..n], &mut nz[..n]);
            let [ar, ag, ab] = &mut s.albedo;
            let (ar, ag, ab) = (&mut ar[..n], &mut ag[..n], &mut ab[..n]);
            let (t_ground, specular) = (&s.t_ground[..n], &mut s.specular[..n]);
            let (lit, on_ground) = (&mut s.lit[..n], &mut s.on_ground[..n]);
            for k in 0..n {
                let tg = t_ground[k];
                let finite = tg.is_finite();
                px[k] = ox[k] + tg * dx[k];
                py[k] = oy[k] + tg * dy[k];
                pz[k] = oz[k] + tg * dz[k];
                (nx[k], ny[k], nz[k]) = (0.0, 1.0, 0.0);
                let a = if finite { GROUND_ALBEDO } else { 0.0 };
                (ar[k], ag[k], ab[k]) = (a, a, a);
                specular[k] = 0.0;
                lit[k] = finite;
                on_ground[k] = finite;
            }
        }
        // The rays that enter the root bound, a packet of neighbouring samples at a time.
        let mut k = 0;
        while k < n {
            let mut members = [0usize; PACKET];
            let mut rays = [Ray { origin: Vec3::ZERO, dir: Vec3::Z }; PACKET];
            let (mut t_max, mut entry) = ([0.0f32; PACKET], [0.0f32; PACKET]);
            let mut count = 0;
            while k < n && count < PACKET {
                if self.s.entry[k] != f32::INFINITY {
                    (members[count], rays[count]) = (k, self.ray(k));
                    (t_max[count], entry[count]) = (self.s.t_ground[k], self.s.entry[k]);
                    count += 1;
                }
                k += 1;
            }
            if count == 0 {
                break;
            }
            let mut hits = [Hit { t: 0.0, node: u32::MAX, triangle: u32::MAX, u: 0.0, v: 0.0 }; PACKET];
            // SAFETY: the caller guarantees L's instructions.
            unsafe {
                self.hierarchy.closest_packet::<L>(
                    &rays[..count],
                    0.0,
                    &t_max[..count],
                    &entry[..count],
                    self.last_hit,
                    &mut self.stacks,
                    &mut hits[..count],
                )
            };
            for j in 0..count {
                let hit = hits[j];
                if hit.node == u32::MAX {
                    continue;
                }
                let k = members[j];
                self.last_hit = hit.node;
                self.stats.leaf_hits += 1;
                let (p, normal) = self.hierarchy.surface(&rays[j], &hit);
                let a = self.albedo(&hit);
                let s = &mut self.s;
                (s.point[0][k], s.point[1][k], s.point[2][k]) = (p.x, p.y, p.z);
                (s.normal[0][k], s.normal[1][k], s.normal[2][k]) = (normal.x, normal.y, normal.z);
                (s.albedo[0][k], s.albedo[1][k], s.albedo[2][k]) = (a.x, a.y, a.z);
                s.specular[k] = LEAF_SPECULAR;
                s.lit[k] = true;
                s.on_ground[k] = false;
            }
        }
        let s = &mut self.s;
        let [ar, ag, ab] = &s.albedo;
        let (ar, ag, ab) = (&ar[..n], &ag[..n], &ab[..n]);
        let [cr, cg, cb] = &mut s.colour;
        let (cr, cg, cb) = (&mut cr[..n], &mut cg[..n], &mut cb[..n]);
        let ambient = self.shading.ambient;
        for k in 0..n {
            cr[k] = ar[k] * ambient;
            cg[k] = ag[k] * ambient;
            cb[k] = ab[k] * ambient;
        }
    }

    fn albedo(&self, hit: &Hit) -> Vec3 {
        let node = &self.hierarchy.nodes[hit.node as usize];
        match self.shading.color_mode {
            ColorMode::Function => {
                self.shading.function_colors.get(node.function as usize).copied().unwrap_or(Vec3::splat(0.7))
            }
            ColorMode::Depth => depth_color(node.depth, self.hierarchy.max_depth),
        }
    }

    /// Per sample for one light: the cosine, whether the surface faces the light, and the
    /// shadow ray's origin and root-bound entry.
    #[inline(always)]
    fn shadow_rays(&mut self, n: usize, to_light: Vec3) {
        let s = &mut self.s;
        let [px, py, pz] = &s.point;
        let (px, py, pz) = (&px[..n], &py[..n], &pz[..n]);
        let [nx, ny, nz] = &s.normal;
        let (nx, ny, nz) = (&nx[..n], &ny[..n], &nz[..n]);
        let [sx, sy, sz] = &mut s.shadow_origin;
        let (sx, sy, sz) = (&mut sx[..n], &mut sy[..n], &mut sz[..n]);
        let (cos_out, lit) = (&mut s.cos[..n], &s.lit[..n]);
        let (facing_out, shaded, shadow_entry) = (&mut s.facing[..n], &mut s.shaded[..n], &mut s.shadow_entry[..n]);
        let eps = self.frame.eps;
        let (root_centre, root_radius) =
            self.hierarchy.nodes.first().map_or(([0.0; 3], f32::NAN), |r| (r.centre.to_array(), r.radius));
        let l = to_light.to_array();
        for k in 0..n {
            let cos = nx[k] * l[0] + ny[k] * l[1] + nz[k] * l[2];
            cos_out[k] = cos;
            let facing = lit[k] & (cos > 0.0);
            facing_out[k] = facing;
            shaded[k] = facing;
            let o = [px[k] + nx[k] * eps, py[k] + ny[k] * eps, pz[k] + nz[k] * eps];
            (sx[k], sy[k], sz[k]) = (o[0], o[1], o[2]);
            let entry = sphere_entry(o, l, root_centre, root_radius, 0.0, f32::INFINITY);
            shadow_entry[k] = if facing { entry } else { f32::INFINITY };
        }
    }

    /// The any-hit search for the shadow rays that enter the root bound, a packet of
    /// neighbouring samples at a time.
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[inline(always)]
    unsafe fn occlusion<L: Lanes>(&mut self, n: usize, index: usize, to_light: Vec3) {
        self.stats.shadow_rays += self.s.facing[..n].iter().filter(|&&f| f).count() as u64;
        let mut k = 0;
        while k < n {
            let mut members = [0usize; PACKET];
            let mut rays = [Ray { origin: Vec3::ZERO, dir: to_light }; PACKET];
            let mut count = 0;
            while k < n && count < PACKET {
                if self.s.shadow_entry[k] != f32::INFINITY {
                    let s = &self.s;
                    members[count] = k;
                    rays[count].origin = Vec3::new(s.shadow_origin[0][k], s.shadow_origin[1][k], s.shadow_origin[2][k]);
                    count += 1;
                }
                k += 1;
            }
            if count == 0 {
                break;
            }
            let cached = self.last_occluder[index];
            let mut last = cached;
            // SAFETY: the caller guarantees L's instructions.
            let blocked = unsafe {
                self.hierarchy.occluded_packet::<L>(
                    &rays[..count],
                    0.0,
                    f32::INFINITY,
                    cached,
                    &mut self.stacks,
                    &mut last,
                )
            };
            self.last_occluder[index] = last;
            for (j, &k) in members[..count].iter().enumerate() {
                if blocked & (1 << j) != 0 {
                    self.s.shaded[k] = false;
                }
            }
        }
    }

    /// Adds one light's Lambert and Blinn–Phong terms where it reaches the surface.
    #[inline(always)]
    fn shade(&mut self, n: usize, to_light: Vec3, intensity: Vec3) {
        let s = &mut self.s;
        let [dx, dy, dz] = &s.dir;
        let (dx, dy, dz) = (&dx[..n], &dy[..n], &dz[..n]);
        let [nx, ny, nz] = &s.normal;
        let (nx, ny, nz) = (&nx[..n], &ny[..n], &nz[..n]);
        let [ar, ag, ab] = &s.albedo;
        let (ar, ag, ab) = (&ar[..n], &ag[..n], &ab[..n]);
        let [cr, cg, cb] = &mut s.colour;
        let (cr, cg, cb) = (&mut cr[..n], &mut cg[..n], &mut cb[..n]);
        let (cos, specular, shaded) = (&s.cos[..n], &s.specular[..n], &s.shaded[..n]);
        let l = to_light.to_array();
        let i = intensity.to_array();
        for k in 0..n {
            let cos = cos[k];
            let mut lk = [ar[k] * cos, ag[k] * cos, ab[k] * cos];
            let spec = specular[k];
            let h = [l[0] - dx[k], l[1] - dy[k], l[2] - dz[k]];
            let rcp = 1.0 / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            let h = [h[0] * rcp, h[1] * rcp, h[2] * rcp];
            let nh = (nx[k] * h[0] + ny[k] * h[1] + nz[k] * h[2]).max(0.0);
            // powi(32) as the compiler expands it: five squarings.
            let p2 = nh * nh;
            let p4 = p2 * p2;
            let p8 = p4 * p4;
            let p16 = p8 * p8;
            let add = spec * (p16 * p16);
            if spec > 0.0 {
                lk = [lk[0] + add, lk[1] + add, lk[2] + add];
            }
            if shaded[k] {
                cr[k] += i[0] * lk[0];
                cg[k] += i[1] * lk[1];
                cb[k] += i[2] * lk[2];
            }
        }
    }

    /// Each sample's radiance: the ground fades into the background away from the attractor.
    #[inline(always)]
    fn finish(&mut self, n: usize) {
        let s = &mut self.s;
        let [px, py, pz] = &s.point;
        let (px, py, pz) = (&px[..n], &py[..n], &pz[..n]);
        let [cr, cg, cb] = &s.colour;
        let (cr, cg, cb) = (&cr[..n], &cg[..n], &cb[..n]);
        let [rr, rg, rb] = &mut s.radiance;
        let (rr, rg, rb) = (&mut rr[..n], &mut rg[..n], &mut rb[..n]);
        let (lit, on_ground, fade) = (&s.lit[..n], &s.on_ground[..n], &mut s.cos[..n]);
        let bg = self.shading.background.to_array();
        let c = self.frame.centre.to_array();
        let scale = 2.5 * self.frame.radius;
        // The fade's distance (a vector loop), then its exp on the ground samples alone.
        for k in 0..n {
            let d = [px[k] - c[0], py[k] - c[1], pz[k] - c[2]];
            let d = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() / scale;
            fade[k] = -d * d;
        }
        for k in 0..n {
            if on_ground[k] {
                fade[k] = fade[k].exp();
            }
        }
        for k in 0..n {
            let f = fade[k];
            let ground = [bg[0] * (1.0 - f) + cr[k] * f, bg[1] * (1.0 - f) + cg[k] * f, bg[2] * (1.0 - f) + cb[k] * f];
            let v = if on_ground[k] {
                ground
            } else if lit[k] {
                [cr[k], cg[k], cb[k]]
            } else {
                bg
            };
            (rr[k], rg[k], rb[k]) = (v[0], v[1], v[2]);
        }
    }
}
