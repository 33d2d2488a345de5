//! The key light's shadow map: the attractor's points splatted a second time, from the key
//! light, into a square map of closest depths (the same keys as the image's closest mode, 24 bits
//! of depth, merged with `min`, no function bits). The resolve (`src/resolve/shadow.rs`, and
//! `shaders/resolve.wgsl`) tests each visible pixel against it.
//!
//! The light is directional and fixed to the camera (`crate::resolve::KEY_LIGHT` by default),
//! so the map's projection is orthographic, looking along the light's direction, and fitted to
//! the attractor's bounds (the box the image's near and far come from): the bounds' eight
//! corners, seen along the light, span the map's square and its depth range. A camera orbit
//! moves the light with it, so the map changes whenever the image's view does.

use glam::{DVec3, Mat4, Vec3, Vec4};

use crate::camera::OrbitCamera;

/// Smallest and largest side of the shadow map, in texels ([`ShadowView::side_for_image`]).
pub const MIN_SIDE_PX: u32 = 256;
pub const MAX_SIDE_PX: u32 = 1024;

/// The shadow map's projection: everything the shadow splat and the shadow test need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowView {
    /// The map is `side_px`² texels.
    pub side_px: u32,
    /// Rows: texel x, texel y, depth fraction from the light (0 nearest), 1 (orthographic, so
    /// no division).
    pub map_from_world: Mat4,
    /// The same projection from the image's view space (the resolve reconstructs view-space
    /// positions from the image's keys).
    pub map_from_view: Mat4,
    /// World size of one texel.
    pub texel_world: f32,
    /// World length of the depth range (depth fraction 1).
    pub depth_world: f32,
}

impl ShadowView {
    /// The map side for an image of `width`×`height`: half the image's longer side, within
    /// [[`MIN_SIDE_PX`], [`MAX_SIDE_PX`]]. A texel then spans about two image pixels where the
    /// attractor fills map and image alike, so a still's 4 M points fill the map's texels four
    /// times as densely as the image's pixels (few holes for light to leak through), the map
    /// (≤ 4 MiB) stays in the last-level cache while points land on it at random (a map of the
    /// image's size cost three times the whole chaos game at 1920×1080: `nlifs bench look`), and
    /// the PCF's 3×3 taps give a soft edge of about six pixels. Below 256 the edge turns into a
    /// visible blur.
    pub fn side_for_image(width: u32, height: u32) -> u32 {
        (width.max(height) / 2).clamp(MIN_SIDE_PX, MAX_SIDE_PX)
    }

    /// The map of a key light in direction `to_light_view` (view space, towards the light) of
    /// `camera`, fitted to `bounds`, `side_px` texels square.
    pub fn new(camera: &OrbitCamera, bounds: (DVec3, DVec3), to_light_view: Vec3, side_px: u32) -> Self {
        let view_from_world = camera.view_from_world();
        let to_light = to_light_view.normalize();
        // The light's basis in view space: `right` and `up` across the map, `to_light` along its
        // depth (the helper axis is the view's up unless the light is nearly straight above).
        let helper = if to_light.y.abs() < 0.99 { Vec3::Y } else { Vec3::X };
        let right = helper.cross(to_light).normalize();
        let up = to_light.cross(right);
        let (lo, hi) = (bounds.0.as_vec3(), bounds.1.as_vec3());
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let v = view_from_world.transform_point3(c);
            let q = Vec3::new(v.dot(right), v.dot(up), v.dot(to_light));
            min = min.min(q);
            max = max.max(q);
        }
        // A square around the corners' span with a margin of one texel a side, and the depth
        // range padded like the image's (`OrbitCamera::depth_range`).
        let span = (max.x - min.x).max(max.y - min.y).max(1e-6);
        let texel_world = span / (side_px as f32 - 2.0);
        let half = 0.5 * side_px as f32 * texel_world;
        let centre = 0.5 * (min + max);
        let pad = 1e-3 * (max.z - min.z).max(1e-3);
        let (depth_lo, depth_hi) = (min.z - pad, max.z + pad);
        let depth_world = depth_hi - depth_lo;
        // Texel x grows along `right`, texel y against `up` (rows downwards, as in an image),
        // the depth fraction from the light's side (`depth_hi`) away from it.
        let r0 = (right / texel_world).extend((half - centre.x) / texel_world);
        let r1 = (-up / texel_world).extend((half + centre.y) / texel_world);
        let r2 = (-to_light / depth_world).extend(depth_hi / depth_world);
        let map_from_view = Mat4::from_cols(r0, r1, r2, Vec4::W).transpose();
        Self { side_px, map_from_world: map_from_view * view_from_world, map_from_view, texel_world, depth_world }
    }

    /// Texel index and depth fraction in [0, 1] of a world point, if it lands in the map.
    #[inline(always)]
    pub fn project(&self, p: Vec3) -> Option<(usize, f32)> {
        let q = self.map_from_world * p.extend(1.0);
        let side = self.side_px as f32;
        if !(q.x >= 0.0 && q.y >= 0.0 && q.x < side && q.y < side) {
            return None;
        }
        let t = q.z.clamp(0.0, 1.0);
        // 0 ≤ x, y < side (checked above; NaN fails the check): the truncations are exact.
        Some((q.y as u32 as usize * self.side_px as usize + q.x as u32 as usize, t))
    }

    /// Texels of the map.
    pub fn texels(&self) -> usize {
        self.side_px as usize * self.side_px as usize
    }
}

/// The closest key of a depth fraction `t` in [0, 1] (as the image's closest keys, function 0).
#[inline(always)]
pub fn key_of(t: f32) -> u32 {
    let d = t * ((1u32 << super::DEPTH_BITS) - 1) as f32;
    let d = if d > 0.0 { d } else { 0.0 };
    (d as u32) << 8
}

impl ShadowView {
    /// The map as a closest-mode image view: its projection has w = 1, near 0 and far 1, so
    /// [`SplatView::project`] gives exactly [`Self::project`]'s texel and depth fraction, and a
    /// splat of function 0 exactly [`key_of`]'s keys. So the map takes the image's vector splat.
    pub fn as_splat_view(&self) -> super::SplatView {
        super::SplatView {
            width: self.side_px,
            height: self.side_px,
            pixel_from_world: self.map_from_world,
            near: 0.0,
            far: 1.0,
            mode: crate::scene::spec::SplatMode::Closest,
            depth_cue: 0.0,
            background: [0.0; 3],
            shadow: None,
            lens: super::Lens::NONE,
        }
    }
}

/// Splats the points of `batch` into the shadow map `map` of `view` (keys merged with `min`)
/// with the image's splat ([`ShadowView::as_splat_view`]: the vector one where the CPU has it),
/// as function 0; the same keys as [`splat_shadow`].
pub(crate) fn splat_shadow_fast(view: &ShadowView, batch: crate::chaos_game::PointBatch<'_>, map: &mut [u32]) {
    // Function 0 for every point: a zeroed byte per point, reused by the thread.
    thread_local! {
        static FUNCTION_ZERO: std::cell::RefCell<Vec<u8>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    FUNCTION_ZERO.with_borrow_mut(|zeros| {
        if zeros.len() < batch.len() {
            zeros.resize(batch.len(), 0);
        }
        let points = crate::chaos_game::PointBatch { functions: &zeros[..batch.len()], ..batch };
        let mut pixels = super::OwnPixels { closest: map, accum: &mut [] };
        super::splat_into(&view.as_splat_view(), &[], points, &mut pixels);
    });
}

/// Splats the points `(x, y, z)` into `map` (keys of `view`, merged with `min`).
pub fn splat_shadow(view: &ShadowView, x: &[f32], y: &[f32], z: &[f32], mut min_key: impl FnMut(usize, u32)) {
    for ((&x, &y), &z) in x.iter().zip(y).zip(z) {
        if let Some((texel, t)) = view.project(Vec3::new(x, y, z)) {
            min_key(texel, key_of(t));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chaos_game::PointBatch;
    use crate::rng::Pcg32;
    use crate::splat::EMPTY;

    /// The shadow map splatted through the image's (vector) splat holds the keys of the scalar
    /// [`splat_shadow`], bit for bit, for points inside and outside the map, on its edges,
    /// behind the light and non-finite, in batches whose lengths are not multiples of 8 or 16.
    #[test]
    fn fast_shadow_splat_matches_the_scalar_one() {
        let bounds = (DVec3::ZERO, DVec3::ONE);
        let camera = OrbitCamera::framing(bounds, 3);
        let view = ShadowView::new(&camera, bounds, Vec3::new(-0.45, 0.55, 0.7), 64);
        let mut r = Pcg32::for_stream(9, 0, 0);
        let n = 5003;
        let mut p: Vec<Vec3> =
            (0..n).map(|_| Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.6 - 0.3).collect();
        p[3] = Vec3::new(f32::NAN, 0.5, 0.5);
        p[4] = Vec3::new(0.5, f32::INFINITY, 0.5);
        p[5] = Vec3::new(1e30, -1e30, 0.5);
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) =
            (p.iter().map(|p| p.x).collect(), p.iter().map(|p| p.y).collect(), p.iter().map(|p| p.z).collect());
        let functions = vec![3u8; n];
        let mut scalar = vec![EMPTY; view.texels()];
        let mut fast = scalar.clone();
        for start in (0..n).step_by(999) {
            let end = (start + 999).min(n);
            splat_shadow(&view, &x[start..end], &y[start..end], &z[start..end], |texel, key| {
                scalar[texel] = scalar[texel].min(key);
            });
            let batch = PointBatch {
                x: &x[start..end],
                y: &y[start..end],
                z: &z[start..end],
                functions: &functions[start..end],
            };
            splat_shadow_fast(&view, batch, &mut fast);
        }
        assert!(scalar.iter().filter(|&&k| k != EMPTY).count() > 1000);
        assert_eq!(scalar, fast);
    }
}
