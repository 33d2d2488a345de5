//! Depth of field: every splatted point seen through a random point of a thin lens at the eye,
//! as the flame renderers do (twin of `lens_offset_px` in `shaders/chaos_game.wgsl`).
//!
//! A lens of radius `aperture` (scene units) lies in the view plane at the eye, focused at view
//! distance f. A point at view depth d seen through lens point s (view-plane offset, x right,
//! y up) lands where the line from s through the point meets the focus plane; in screen units
//! (tangents) that is the pinhole position moved by s · (1/f − 1/d), in pixels that over the
//! pixel footprint at unit distance. Points on the focus plane stay where they were; a point at
//! depth d spreads, over many lens samples, into a disk of radius aperture · |1/f − 1/d| /
//! footprint pixels. The depth key stays the point's own depth.
//!
//! Parallel projection has no eye to put the lens at; its rule is the first-order term of the
//! perspective one: the image moves by s · (d − f) / f in scene units (pixels: over the pixel's
//! size), so the blur still grows linearly with the distance from the focus plane and vanishes
//! on it.
//!
//! The lens sample is a pure function of the point and the seed: a hash of the point's f32
//! coordinate bits seeds a PCG ([`crate::rng`]) that draws from the square [-1, 1)² until a
//! draw falls in the unit disk (rejection: only exact-in-f32 operations, no trigonometry or
//! square root whose rounding differs between CPU and GPU). So the picture does not depend on
//! the thread count or the batch order, and the CPU and GPU splats of the same points agree.
//! With aperture 0 the lens is off and the splat is the pinhole one, bit for bit (the lens
//! splat is not even entered).

use glam::Vec3;

use super::{COLOR_SCALE, DEPTH_BITS, Pixels, SplatMode, SplatView};
use crate::camera::{OrbitCamera, Projection};
use crate::chaos_game::PointBatch;
use crate::rng::{Pcg32, pcg_hash};

#[cfg(target_arch = "x86_64")]
mod x86;

/// Draws from the square before the lens sample falls back to the lens centre: the chance that
/// all miss the disk is (1 − π/4)^16 ≈ 2·10⁻¹¹.
pub const LENS_TRIES: u32 = 16;

/// A thin lens as the splat uses it (see the module comment). Mirrors the `lens` uniform of
/// `ChaosParams` in `shaders/chaos_game.wgsl` (x: `radius_px`, y: `inv_focus`, z: perspective,
/// w: the seed's bits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Aperture over the pixel footprint: pixels of offset per unit of lens sample and of
    /// defocus (1/f − 1/d in perspective, (d − f)/f in parallel projection). 0: no lens.
    pub radius_px: f32,
    /// 1 / focus distance.
    pub inv_focus: f32,
    pub perspective: bool,
    /// Seeds the lens samples' hash (the render's seed).
    pub seed: u32,
}

/// Bad lens settings (the scene check and the CLI report them located).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LensError {
    #[error("aperture {0} must be a finite number ≥ 0")]
    Aperture(f32),
    #[error("focus distance {0} must be a finite number > 0")]
    FocusDistance(f32),
}

impl Lens {
    /// No depth of field: the pinhole splat.
    pub const NONE: Lens = Lens { radius_px: 0.0, inv_focus: 0.0, perspective: true, seed: 0 };

    /// The lens of `camera` on an image `height_px` rows high: radius `aperture` (scene units),
    /// focused at view distance `focus_distance` (None: the camera's distance to its target),
    /// samples seeded with `seed`. Aperture 0 is [`Self::NONE`].
    pub fn new(
        camera: &OrbitCamera,
        height_px: u32,
        aperture: f32,
        focus_distance: Option<f32>,
        seed: u32,
    ) -> Result<Self, LensError> {
        check(aperture, focus_distance)?;
        if aperture == 0.0 {
            return Ok(Self::NONE);
        }
        let focus = focus_distance.unwrap_or(camera.distance).max(f32::MIN_POSITIVE);
        // The same footprint as `crate::resolve::pixel_footprint` (a test keeps them equal).
        let (footprint, perspective) = match camera.projection {
            Projection::Perspective => (2.0 * (0.5 * camera.fov_y_deg.to_radians()).tan() / height_px as f32, true),
            Projection::Parallel => (2.0 * camera.half_height_at_target() / height_px as f32, false),
        };
        Ok(Self { radius_px: aperture / footprint, inv_focus: 1.0 / focus, perspective, seed })
    }

    /// Whether the lens changes the splat (aperture > 0).
    #[inline(always)]
    pub fn is_on(&self) -> bool {
        self.radius_px > 0.0
    }

    /// The uniform `lens` of `shaders/chaos_game.wgsl`.
    pub fn uniform(&self) -> [f32; 4] {
        [self.radius_px, self.inv_focus, if self.perspective { 1.0 } else { 0.0 }, f32::from_bits(self.seed)]
    }

    /// Radius in pixels of the disk that a point at view depth `depth` spreads into.
    pub fn blur_radius_px(&self, depth: f32) -> f32 {
        let defocus = if self.perspective { self.inv_focus - 1.0 / depth } else { depth * self.inv_focus - 1.0 };
        self.radius_px * defocus.abs()
    }
}

/// Checks lens settings: aperture finite and ≥ 0, focus distance (when set) finite and > 0.
pub fn check(aperture: f32, focus_distance: Option<f32>) -> Result<(), LensError> {
    if !(aperture.is_finite() && aperture >= 0.0) {
        return Err(LensError::Aperture(aperture));
    }
    match focus_distance {
        Some(f) if !(f.is_finite() && f > 0.0) => Err(LensError::FocusDistance(f)),
        _ => Ok(()),
    }
}

/// The lens sample of point `p` under `seed`: a point of the unit disk (see the module comment;
/// `lens_sample` in `shaders/chaos_game.wgsl` is its twin).
#[inline(always)]
pub fn lens_sample(seed: u32, p: Vec3) -> [f32; 2] {
    let hash = pcg_hash(p.z.to_bits() ^ pcg_hash(p.y.to_bits() ^ pcg_hash(p.x.to_bits() ^ pcg_hash(seed))));
    let mut rng = Pcg32::from_state(hash);
    for _ in 0..LENS_TRIES {
        let u = 2.0 * rng.next_f32() - 1.0;
        let v = 2.0 * rng.next_f32() - 1.0;
        if u * u + v * v <= 1.0 {
            return [u, v];
        }
    }
    [0.0, 0.0]
}

/// Points per block of the lens splat: their projections are computed first, then the pixels
/// updated in a loop of independent framebuffer accesses (the projection's hash and rejection
/// loop between two accesses would otherwise keep the cache misses from overlapping).
const BLOCK: usize = 64;

/// The splat through the lens: per block of points their projections (8 at a time with
/// AVX2, `lens/x86.rs`), then the pixel updates (`splat_portable` in `src/splat.rs` is the
/// same arithmetic with the pinhole projection).
pub(crate) fn splat(view: &SplatView, colors: &[[f32; 3]], batch: PointBatch<'_>, out: &mut impl Pixels) {
    let v = *view;
    let mut hits = [None; BLOCK];
    let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
    let scaled: Vec<[f32; 3]> = colors.iter().map(|c| c.map(|x| x * COLOR_SCALE)).collect();
    let bg = v.background.map(|x| x * COLOR_SCALE);
    for start in (0..batch.len()).step_by(BLOCK) {
        let n = BLOCK.min(batch.len() - start);
        project_block(&v, batch, start, &mut hits[..n]);
        for (i, hit) in hits[..n].iter().enumerate() {
            let Some((idx, t)) = *hit else { continue };
            let fi = batch.functions[start + i];
            if v.mode == SplatMode::Closest {
                // As the portable splat: NaN and negatives to 0, an exact truncation.
                let d = t * scale;
                let d = if d > 0.0 { d } else { 0.0 };
                out.min_key(idx, (d as u32) << 8 | fi as u32);
            } else {
                let c = scaled[fi as usize];
                let k = v.depth_cue * t;
                let add = [0, 1, 2].map(|ch| (c[ch] + (bg[ch] - c[ch]) * k + 0.5) as u32);
                out.add(idx, [add[0], add[1], add[2], 1]);
            }
        }
    }
}

/// `out[i]` = [`project_through_lens`] of point `start + i` of `batch`.
fn project_block(view: &SplatView, batch: PointBatch<'_>, start: usize, out: &mut [Option<(usize, f32)>]) {
    #[cfg(target_arch = "x86_64")]
    if x86::supported(view) {
        x86::project_block(view, batch, start, out);
        return;
    }
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = project_through_lens(view, batch.point(start + i));
    }
}

/// [`SplatView::project`] through the view's lens: pixel index and depth fraction t of world
/// point `p`, if its image lands in the picture.
#[inline(always)]
pub fn project_through_lens(view: &SplatView, p: Vec3) -> Option<(usize, f32)> {
    let lens = view.lens;
    let q = view.pixel_from_world * p.extend(1.0);
    if !(q.w > 0.0) {
        return None;
    }
    let inv_w = 1.0 / q.w;
    // Perspective: q.w is the view depth d; parallel: q.w = 1 and q.z is d.
    let defocus = if lens.perspective { lens.inv_focus - inv_w } else { q.z * lens.inv_focus - 1.0 };
    let r = lens.radius_px * defocus;
    let [u, v] = lens_sample(lens.seed, p);
    // Pixel y grows downwards, the lens's v upwards.
    let (x, y) = (q.x * inv_w + u * r, q.y * inv_w - v * r);
    if !(x >= 0.0 && y >= 0.0 && x < view.width as f32 && y < view.height as f32) {
        return None;
    }
    let t = ((q.z - view.near) * (1.0 / (view.far - view.near))).clamp(0.0, 1.0);
    let (ix, iy) = (x as u32 as usize, y as u32 as usize);
    Some((iy * view.width as usize + ix, t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::spec::SplatMode;
    use glam::DVec3;

    /// Lens samples lie in the unit disc and fill it uniformly: the share within radius ½ is
    /// ¼, within 4 standard deviations of a binomial with n = 40 000 (σ ≈ 0.0022).
    #[test]
    fn lens_samples_fill_the_unit_disc_uniformly() {
        let n = 40_000;
        let mut inner = 0;
        let mut r = crate::rng::Pcg32::for_stream(1, 2, 3);
        for _ in 0..n {
            let p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            let [u, v] = lens_sample(9, p);
            assert!(u * u + v * v <= 1.0);
            assert_eq!(lens_sample(9, p), [u, v], "a pure function of the point");
            inner += (u * u + v * v <= 0.25) as u32;
        }
        let share = inner as f64 / n as f64;
        assert!((share - 0.25).abs() <= 4.0 * (0.25f64 * 0.75 / n as f64).sqrt(), "{share}");
    }

    /// With a zero radius the lens projection is the pinhole one, exactly, for points inside,
    /// outside, behind the eye and non-finite.
    #[test]
    fn zero_radius_projects_as_the_pinhole() {
        let bounds = (DVec3::ZERO, DVec3::ONE);
        let camera = OrbitCamera::framing(bounds, 3);
        let view = SplatView::new(&camera, 64, 48, bounds, SplatMode::Closest, 0.5, [0.0; 3]);
        let lens = Lens { radius_px: 0.0, ..Lens::new(&camera, 48, 0.1, None, 1).unwrap() };
        let view = view.with_lens(lens);
        let mut r = crate::rng::Pcg32::for_stream(4, 0, 0);
        let mut points: Vec<Vec3> =
            (0..5000).map(|_| Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 3.0 - 1.0).collect();
        points.extend([Vec3::NAN, camera.eye(), camera.eye() + (camera.eye() - camera.target)]);
        for p in points {
            assert_eq!(project_through_lens(&view, p), view.project(p), "{p}");
        }
    }

    #[test]
    fn bad_settings_are_refused() {
        assert_eq!(check(-1.0, None), Err(LensError::Aperture(-1.0)));
        assert!(check(f32::NAN, None).is_err());
        assert_eq!(check(0.5, Some(0.0)), Err(LensError::FocusDistance(0.0)));
        assert!(check(0.5, Some(f32::INFINITY)).is_err());
        assert_eq!(check(0.0, Some(2.0)), Ok(()));
    }
}
