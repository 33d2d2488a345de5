//! Splatting chaos-game points into a framebuffer (CPU reference; on the GPU the chaos game
//! splats as it goes, in `shaders/chaos_game.wgsl`). The framebuffer becomes an image in
//! [`crate::resolve`].
//!
//! Three modes, as in the paper plus one from the fractal-flame tradition:
//! - `Closest`: per pixel the point nearest the viewer, its function's colour depth-cued
//!   (faded towards the background with distance between the attractor's near and far bounds).
//!   Stored as one u32 per pixel, (depth in 24 bits << 8) | function, merged with `min`.
//! - `Average`: the mean of the depth-cued colours of all points on the pixel.
//! - `Density`: the average colour scaled by log(1 + count) / log(1 + max count).
//!
//! Accumulators are integers, so merging per-thread framebuffers is order-independent and the
//! image is a pure function of the points.

use glam::{Mat4, Vec3, Vec4};

use crate::camera::OrbitCamera;
use crate::chaos_game::{PointBatch, PointSink};
use crate::scene::spec::SplatMode;

pub mod lens;
pub mod shadow;
pub mod shared;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use lens::Lens;
pub use shadow::ShadowView;
pub use shared::SharedFramebuffer;

/// Depth is quantized to this many bits in the closest-point key.
pub const DEPTH_BITS: u32 = 24;
/// Colour channels are accumulated as integers 0..=COLOR_SCALE.
pub const COLOR_SCALE: f32 = 255.0;
/// The empty closest-point key.
pub const EMPTY: u32 = u32::MAX;

/// Everything the splat needs about the view, derived once per image.
#[derive(Clone, Copy, Debug)]
pub struct SplatView {
    pub width: u32,
    pub height: u32,
    /// Rows: pixel x · w, pixel y · w, view distance, w.
    pub pixel_from_world: Mat4,
    pub near: f32,
    pub far: f32,
    pub mode: SplatMode,
    pub depth_cue: f32,
    pub background: [f32; 3],
    // Shadows (`splat/shadow.rs`).
    /// The key light's shadow map, splatted from the same points; None: no shadows.
    pub shadow: Option<ShadowView>,
    // Depth of field (`lens.rs`).
    /// The thin lens the points are seen through ([`Lens::NONE`]: a pinhole).
    pub lens: Lens,
}

impl SplatView {
    /// The view of `camera` on an image of `width`×`height` with depth range from `bounds`.
    pub fn new(
        camera: &OrbitCamera,
        width: u32,
        height: u32,
        bounds: (glam::DVec3, glam::DVec3),
        mode: SplatMode,
        depth_cue: f32,
        background: [f32; 3],
    ) -> Self {
        let (near, far) = camera.depth_range(bounds);
        let aspect = width as f32 / height as f32;
        let view_from_world = camera.view_from_world();
        let clip_from_world = camera.clip_from_view(aspect, near, far) * view_from_world;
        let row = |m: &Mat4, r: usize| -> Vec4 { m.row(r) };
        let (w, h) = (width as f32, height as f32);
        let r0 = 0.5 * w * (row(&clip_from_world, 0) + row(&clip_from_world, 3));
        let r1 = 0.5 * h * (row(&clip_from_world, 3) - row(&clip_from_world, 1));
        let r2 = -row(&view_from_world, 2);
        let r3 = row(&clip_from_world, 3);
        let pixel_from_world = Mat4::from_cols(r0, r1, r2, r3).transpose();
        Self { width, height, pixel_from_world, near, far, mode, depth_cue, background, shadow: None, lens: Lens::NONE }
    }

    /// This view with a shadow map of the key light in direction `to_light_view` (view space)
    /// of `camera`, fitted to `bounds` (closest mode only: the other modes have no depth to
    /// test against, so they keep none).
    pub fn with_shadow(self, camera: &OrbitCamera, bounds: (glam::DVec3, glam::DVec3), to_light_view: Vec3) -> Self {
        let side_px = ShadowView::side_for_image(self.width, self.height);
        self.with_shadow_side(camera, bounds, to_light_view, side_px)
    }

    /// [`Self::with_shadow`] with a map of `side_px`² texels.
    pub fn with_shadow_side(
        self,
        camera: &OrbitCamera,
        bounds: (glam::DVec3, glam::DVec3),
        to_light_view: Vec3,
        side_px: u32,
    ) -> Self {
        let shadow =
            (self.mode == SplatMode::Closest).then(|| ShadowView::new(camera, bounds, to_light_view, side_px.max(4)));
        Self { shadow, ..self }
    }

    /// This view seen through `lens` (depth of field, `lens.rs`).
    pub fn with_lens(self, lens: Lens) -> Self {
        Self { lens, ..self }
    }

    /// Pixel index and depth fraction t in [0, 1] of a world point, if it lands in the image.
    #[inline(always)]
    pub fn project(&self, p: Vec3) -> Option<(usize, f32)> {
        let q = self.pixel_from_world * p.extend(1.0);
        if !(q.w > 0.0) {
            return None;
        }
        let inv_w = 1.0 / q.w;
        let (x, y) = (q.x * inv_w, q.y * inv_w);
        if !(x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32) {
            return None;
        }
        // A multiplication by the inverse range (one division per view, not per point); the
        // vector splats (`x86.rs`) and the GPU do the same.
        let t = ((q.z - self.near) * (1.0 / (self.far - self.near))).clamp(0.0, 1.0);
        // 0 ≤ x < width and 0 ≤ y < height (checked above, NaN fails the check), so the
        // truncations are exact. The reference splat stays safe: the vector splats are tested
        // against it.
        let (ix, iy) = (x as u32 as usize, y as u32 as usize);
        Some((iy * self.width as usize + ix, t))
    }

    /// Bytes of one framebuffer of this view: 4 per pixel in closest mode (one key), 16 in the
    /// accumulating modes (r, g, b sums and the count), and 4 per texel of the shadow map.
    pub fn accumulation_bytes(&self) -> u64 {
        let per_pixel = if self.mode == SplatMode::Closest { 4 } else { 16 };
        let shadow = self.shadow.map_or(0, |s| 4 * s.texels() as u64);
        self.width as u64 * self.height as u64 * per_pixel + shadow
    }

    /// A colour faded towards the background by depth fraction t.
    #[inline(always)]
    pub fn cue(&self, color: [f32; 3], t: f32) -> [f32; 3] {
        let k = self.depth_cue * t;
        [0, 1, 2].map(|c| color[c] + (self.background[c] - color[c]) * k)
    }
}

/// A CPU framebuffer for one mode.
#[derive(Clone, Debug)]
pub struct Framebuffer {
    pub view: SplatView,
    /// Closest mode: one key per pixel.
    pub closest: Vec<u32>,
    /// Average and density modes: r, g, b sums and the count per pixel.
    pub accum: Vec<[u32; 4]>,
    /// Function colours (linear RGB), indexed by compiled function.
    pub colors: Vec<[f32; 3]>,
    /// The shadow map's keys (`view.shadow`'s texels; empty without shadows).
    pub shadow: Vec<u32>,
    /// The points drawn into it, those outside the view included (the absolute density's
    /// normalisation, `resolve::ResolveArgs::points_drawn`); set by whoever runs the chaos game.
    pub points_drawn: u64,
}

impl Framebuffer {
    pub fn new(view: SplatView, colors: Vec<[f32; 3]>) -> Self {
        let n = view.width as usize * view.height as usize;
        let (closest, accum) = match view.mode {
            SplatMode::Closest => (vec![EMPTY; n], Vec::new()),
            _ => (Vec::new(), vec![[0; 4]; n]),
        };
        let shadow = view.shadow.map_or_else(Vec::new, |s| vec![EMPTY; s.texels()]);
        Self { view, closest, accum, colors, shadow, points_drawn: 0 }
    }

    /// Writes a zero into every page of the accumulating modes' sums, for a framebuffer that
    /// several threads' splats will update ([`crate::platform::write_every_page`]). Closest
    /// mode's keys start as `EMPTY`, written at allocation.
    pub fn touch_pages(&mut self) {
        crate::platform::write_every_page(&mut self.accum, [0; 4]);
    }

    /// Elementwise merge (min of keys, sum of accumulators): order-independent.
    pub fn merge(mut self, other: Self) -> Self {
        if self.closest.is_empty() && self.accum.is_empty() {
            return other;
        }
        for (a, b) in self.closest.iter_mut().zip(&other.closest) {
            *a = (*a).min(*b);
        }
        for (a, b) in self.accum.iter_mut().zip(&other.accum) {
            for c in 0..4 {
                a[c] = a[c].saturating_add(b[c]);
            }
        }
        for (a, b) in self.shadow.iter_mut().zip(&other.shadow) {
            *a = (*a).min(*b);
        }
        self.points_drawn += other.points_drawn;
        self
    }

    /// Number of pixels hit by at least one point.
    pub fn covered_pixels(&self) -> usize {
        match self.view.mode {
            SplatMode::Closest => self.closest.iter().filter(|&&k| k != EMPTY).count(),
            _ => self.accum.iter().filter(|a| a[3] > 0).count(),
        }
    }
}

impl PointSink for Framebuffer {
    fn consume(&mut self, batch: PointBatch<'_>) {
        let view = self.view;
        let mut pixels = OwnPixels { closest: &mut self.closest, accum: &mut self.accum };
        splat_into(&view, &self.colors, batch, &mut pixels);
        if let Some(shadow_view) = &view.shadow {
            shadow::splat_shadow_fast(shadow_view, batch, &mut self.shadow);
        }
    }
}

/// Where a splat's per-pixel updates go: a framebuffer's own pixels ([`OwnPixels`]) or the
/// buffers of a shared one ([`shared::BandWriter`]). Both updates are order-independent.
pub(crate) trait Pixels {
    /// Closest mode: keep the smaller of the pixel's key and `key`.
    fn min_key(&mut self, pixel: usize, key: u32);
    /// Accumulating modes: add r, g, b and the count (saturating) to the pixel's sums.
    fn add(&mut self, pixel: usize, add: [u32; 4]);
    /// Closest mode: the keys themselves, one per pixel, where this target holds them (the
    /// vector splat then reads them a vector at a time and writes only the keys that fall);
    /// None: updates go through [`Self::min_key`] only.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code, reason = "used by the x86-64 vector splat only"))]
    fn own_keys(&mut self) -> Option<&mut [u32]> {
        None
    }
    /// Accumulating modes: the sums themselves, one [r, g, b, count] per pixel, where this
    /// target holds them (the vector splat then gathers, adds and scatters back the sums of a
    /// vector whose pixels are distinct); None: updates go through [`Self::add`] only.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code, reason = "used by the x86-64 vector splat only"))]
    fn own_sums(&mut self) -> Option<&mut [[u32; 4]]> {
        None
    }
}

/// A framebuffer's own pixels as a [`Pixels`] target.
pub(crate) struct OwnPixels<'a> {
    pub closest: &'a mut [u32],
    pub accum: &'a mut [[u32; 4]],
}

impl Pixels for OwnPixels<'_> {
    #[inline(always)]
    fn min_key(&mut self, pixel: usize, key: u32) {
        // A store whatever the comparison says (a conditional move, not a branch): the branch
        // on a key just loaded from a random pixel mispredicts often, and each miss discards
        // the loads of the pixels after it; without it the splat keeps several cache misses in
        // flight (`nlifs bench look`: image and shadow splat 71 → 56 ms CPU, plant2 1920×1080,
        // 4·10^6 points).
        let slot = &mut self.closest[pixel];
        *slot = (*slot).min(key);
    }

    #[inline(always)]
    fn add(&mut self, pixel: usize, add: [u32; 4]) {
        let a = &mut self.accum[pixel];
        // a + min(add, !a) is a.saturating_add(add), in a form that vectorizes.
        for c in 0..4 {
            a[c] += add[c].min(!a[c]);
        }
    }

    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code, reason = "used by the x86-64 vector splat only"))]
    fn own_keys(&mut self) -> Option<&mut [u32]> {
        Some(self.closest)
    }

    fn own_sums(&mut self) -> Option<&mut [[u32; 4]]> {
        Some(self.accum)
    }
}

/// Splats `batch` of a view `view` with function colours `colors` into `out`: the vector
/// splat where the CPU has it, else the portable one; both give the same updates.
#[inline]
pub(crate) fn splat_into(view: &SplatView, colors: &[[f32; 3]], batch: PointBatch<'_>, out: &mut impl Pixels) {
    // Depth of field (aperture > 0): the lens splat (`lens.rs`); otherwise untouched.
    if view.lens.is_on() {
        lens::splat(view, colors, batch, out);
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if x86::supported(view) {
        x86::splat(view, colors, batch, out);
        return;
    }
    splat_portable(view, colors, batch, out);
}

/// The splat without vector code (the reference for the vector path, which must give the
/// same updates).
pub(crate) fn splat_portable(view: &SplatView, colors: &[[f32; 3]], batch: PointBatch<'_>, out: &mut impl Pixels) {
    let v = *view;
    match v.mode {
        SplatMode::Closest => {
            let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
            for (p, &fi) in batch.points().zip(batch.functions) {
                if let Some((idx, t)) = v.project(p) {
                    // t is in [0, 1] or NaN (a non-finite point); NaN goes to 0 as
                    // with a saturating `as u32`.
                    let d = t * scale;
                    let d = if d > 0.0 { d } else { 0.0 };
                    // 0 ≤ d ≤ scale < 2^24, so the truncation is exact.
                    out.min_key(idx, (d as u32) << 8 | fi as u32);
                }
            }
        }
        _ => {
            let colors: Vec<[f32; 3]> = colors.iter().map(|c| c.map(|x| x * COLOR_SCALE)).collect();
            let bg = v.background.map(|x| x * COLOR_SCALE);
            for (p, &fi) in batch.points().zip(batch.functions) {
                if let Some((idx, t)) = v.project(p) {
                    let c = colors[fi as usize];
                    let k = v.depth_cue * t;
                    let add = [0, 1, 2].map(|ch| (c[ch] + (bg[ch] - c[ch]) * k + 0.5) as u32);
                    out.add(idx, [add[0], add[1], add[2], 1]);
                }
            }
        }
    }
}

impl Framebuffer {
    /// The splat of [`PointSink::consume`] without vector code.
    #[cfg(test)]
    fn consume_portable(&mut self, batch: PointBatch<'_>) {
        let view = self.view;
        let mut pixels = OwnPixels { closest: &mut self.closest, accum: &mut self.accum };
        splat_portable(&view, &self.colors, batch, &mut pixels);
    }

    /// Bytes of this view's accumulation (see [`SplatView::accumulation_bytes`]).
    pub fn bytes(&self) -> u64 {
        self.view.accumulation_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use glam::DVec3;

    /// The vector splat (where the CPU has it) leaves the same framebuffer as the portable
    /// one in every mode, for points inside, outside, behind the camera, beyond the depth
    /// range and non-finite, with batch lengths that are not multiples of 8. 4003 points on
    /// 64×48 pixels put two lanes of many a vector on one pixel, so the 16-wide accumulating
    /// splat runs both its gather-add-scatter and its lane-by-lane updates.
    #[test]
    fn vector_splat_matches_portable() {
        for mode in SplatMode::ALL {
            check_vector_splat(mode);
        }
    }

    /// With more colours than the vector table holds (a palette's 256), the vector splat
    /// gathers them and still leaves the portable splat's sums.
    #[test]
    fn vector_splat_matches_portable_with_a_palette() {
        for mode in [SplatMode::Average, SplatMode::Density] {
            let bounds = (DVec3::ZERO, DVec3::ONE);
            let camera = OrbitCamera::framing(bounds, 3);
            let view = SplatView::new(&camera, 64, 48, bounds, mode, 0.75, [0.1, 0.2, 0.3]);
            let mut r = Pcg32::for_stream(23, 0, 0);
            let n = 6007;
            let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
                (0..n).map(|_| r.next_f32() * 1.4 - 0.2).collect(),
                (0..n).map(|_| r.next_f32() * 1.4 - 0.2).collect(),
                (0..n).map(|_| r.next_f32() * 1.4 - 0.2).collect(),
            );
            let functions: Vec<u8> = (0..n).map(|_| (r.next_u32() >> 24) as u8).collect();
            let colors: Vec<[f32; 3]> =
                (0..256).map(|i| [i as f32 / 255.0, 1.0 - i as f32 / 255.0, (i % 7) as f32 / 6.0]).collect();
            let mut portable = Framebuffer::new(view, colors);
            let mut fastest = portable.clone();
            for start in (0..n).step_by(1000) {
                let end = (start + 1000).min(n);
                let batch = PointBatch {
                    x: &x[start..end],
                    y: &y[start..end],
                    z: &z[start..end],
                    functions: &functions[start..end],
                };
                portable.consume_portable(batch);
                fastest.consume(batch);
            }
            assert!(portable.covered_pixels() > 1000, "{}", portable.covered_pixels());
            assert_eq!(portable.accum, fastest.accum, "{mode:?}");
        }
    }

    fn check_vector_splat(mode: SplatMode) {
        let bounds = (DVec3::ZERO, DVec3::ONE);
        let camera = OrbitCamera::framing(bounds, 3);
        let view = SplatView::new(&camera, 64, 48, bounds, mode, 0.75, [0.1, 0.2, 0.3]);
        let mut r = Pcg32::for_stream(21, 0, 0);
        let n = 4003;
        let mut p: Vec<Vec3> =
            (0..n).map(|_| Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 3.0 - 1.0).collect();
        p[5] = Vec3::new(f32::NAN, 0.5, 0.5);
        p[6] = Vec3::new(0.5, f32::INFINITY, 0.5);
        p[7] = camera.eye();
        p[8] = camera.eye() + (camera.eye() - camera.target);
        // Function 4 (whose colour needs the scalar arithmetic) only in every fourth run of 64.
        let functions: Vec<u8> = (0..n).map(|i| if i / 64 % 4 == 3 { 4 } else { (i % 4) as u8 }).collect();
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) =
            (p.iter().map(|p| p.x).collect(), p.iter().map(|p| p.y).collect(), p.iter().map(|p| p.z).collect());
        // Function 4's red is beyond what a signed 32-bit truncation holds once scaled, its
        // green beyond an unsigned one, its blue below −1.
        let mut portable = Framebuffer::new(
            view,
            (0..5).map(|i| if i == 4 { [1e7, 1e8, -10.0] } else { [0.2 * i as f32, 1.0, 0.5] }).collect(),
        );
        let mut fastest = portable.clone();
        let mut forwarded = portable.clone();
        // Each x86 kernel the CPU runs, 8-wide and 16-wide, with either way of adding to sums.
        #[cfg(target_arch = "x86_64")]
        let kernels: Vec<(bool, crate::simd::SumUpdates)> = {
            use crate::simd::{SimdLevel, SumUpdates};
            let widths: &[bool] = match (x86::supported(&portable.view), SimdLevel::detect().avx512()) {
                (false, _) => &[],
                (true, false) => &[false],
                (true, true) => &[false, true],
            };
            // (The 8-wide kernel adds to sums one way only.)
            widths
                .iter()
                .flat_map(|&w| {
                    if w {
                        vec![(w, SumUpdates::Scatter), (w, SumUpdates::Lanes)]
                    } else {
                        vec![(w, SumUpdates::Lanes)]
                    }
                })
                .collect()
        };
        #[cfg(target_arch = "x86_64")]
        let mut by_kernel = vec![portable.clone(); kernels.len()];
        for start in (0..n).step_by(1000) {
            let end = (start + 1000).min(n);
            let batch = PointBatch {
                x: &x[start..end],
                y: &y[start..end],
                z: &z[start..end],
                functions: &functions[start..end],
            };
            portable.consume_portable(batch);
            fastest.consume(batch);
            let (view, colors) = (forwarded.view, forwarded.colors.clone());
            let own = OwnPixels { closest: &mut forwarded.closest, accum: &mut forwarded.accum };
            splat_into(&view, &colors, batch, &mut Forward(own));
            #[cfg(target_arch = "x86_64")]
            for (&(wide, updates), fb) in kernels.iter().zip(&mut by_kernel) {
                let view = fb.view;
                let mut pixels = OwnPixels { closest: &mut fb.closest, accum: &mut fb.accum };
                x86::splat_with(&view, &portable.colors, batch, &mut pixels, wide, updates);
            }
        }
        #[cfg(target_arch = "x86_64")]
        for (kernel, fb) in kernels.iter().zip(&by_kernel) {
            assert_eq!(portable.closest, fb.closest, "{mode:?}, {kernel:?}");
            assert_eq!(portable.accum, fb.accum, "{mode:?}, {kernel:?}");
        }
        assert!(portable.covered_pixels() > 500, "{}", portable.covered_pixels());
        assert_eq!(portable.closest, fastest.closest, "{mode:?}");
        assert_eq!(portable.accum, fastest.accum, "{mode:?}");
        assert_eq!(portable.closest, forwarded.closest, "{mode:?}: through min_key");
        assert_eq!(portable.accum, forwarded.accum, "{mode:?}: through add");
    }

    /// A target that takes updates one by one only (as the shared framebuffer's writers do):
    /// the vector splat's path without the keys at hand.
    struct Forward<'a>(OwnPixels<'a>);

    impl Pixels for Forward<'_> {
        fn min_key(&mut self, pixel: usize, key: u32) {
            self.0.min_key(pixel, key);
        }

        fn add(&mut self, pixel: usize, add: [u32; 4]) {
            self.0.add(pixel, add);
        }
    }
}
