//! The solid look's light a row at a time on the CPU, the twin of the GPU's light pass
//! (`light_pass` in `shaders/resolve.wgsl`, whose light cache the live view reads): per pixel
//! the two light factors of its own key, the factor of its colour and the white added, which
//! the fragment then applies as the GPU's cached path does (`albedo · f.x + f.y`).
//!
//! Eight neighbouring pixels of a row go through [`solid::light`]'s arithmetic together, one
//! lane each: the same operations in the same order (no fused multiply-add, the same divisions
//! and square roots), empty neighbours left out by a select rather than a branch. So each lane's
//! factors are the scalar light's to the bit (`lanes_equal_the_scalar_light`) and every image
//! keeps its bytes, while the compiler turns the eight-float arrays into vector instructions
//! (AVX2 where the CPU has it, `light_row`; SSE2 otherwise). The shadow map's taps
//! stay per lane: their texels are scattered.

use std::ops::{Add, Div, Mul, RangeInclusive, Sub};

use glam::{Mat4, Vec4Swizzles};

use super::shadow::{SHADOW_BIAS_SLOPE, SHADOW_BIAS_TEXELS, SHADOW_PCF_RADIUS, SHADOW_SLOPE_MAX};
use super::solid::occlusion_offset;
use super::*;

/// Pixels lit together.
pub(super) const LANES: usize = 8;

/// Eight floats, one per pixel, with the scalar's operations lane by lane: the portable
/// [`F8`] and, on x86-64 with AVX2, one vector register (`x86::Avx8`). Each operation rounds as
/// the scalar one does (`max` and `min` return the other operand where one is NaN, as
/// `f32::max` does; the second operand is never NaN here).
pub(super) trait Lanes:
    Copy
    + Add<Output = Self>
    + Add<f32, Output = Self>
    + Sub<Output = Self>
    + Sub<f32, Output = Self>
    + Mul<Output = Self>
    + Mul<f32, Output = Self>
    + Div<Output = Self>
    + Div<f32, Output = Self>
{
    /// Which lanes a select takes from its first argument.
    type Mask: Copy;
    fn splat(v: f32) -> Self;
    fn from_array(v: [f32; LANES]) -> Self;
    fn to_array(self) -> [f32; LANES];
    /// `-self` (the sign flipped, zeros included).
    fn neg(self) -> Self;
    fn max(self, other: f32) -> Self;
    fn min(self, other: f32) -> Self;
    /// `f32::max` against lanes (`other` not NaN).
    fn max_lanes(self, other: Self) -> Self;
    fn sqrt(self) -> Self;
    /// `f32::clamp` (a NaN stays NaN).
    fn clamp(self, low: f32, high: f32) -> Self;
    /// `if mask { self } else { other }`, lane by lane.
    fn or(self, mask: Self::Mask, other: Self) -> Self;
    /// The lanes greater than 0.
    fn positive(self) -> Self::Mask;
    /// The lanes whose key is not [`EMPTY`].
    fn present(keys: [u32; LANES]) -> Self::Mask;
    /// `((keys >> 8) − depth0) as f32 · z_per_unit`: key depth differences from the lanes' own
    /// keys `own`, in footprints ([`solid::fitted_slopes`]'s z).
    fn depths(keys: [u32; LANES], own: [u32; LANES], z_per_unit: Self) -> Self;
    /// The shadowed fraction of the `active` lanes ([`shadow::shadow_at`]'s PCF): of the 3×3
    /// texels around (cx, cy) in the `side`² map, those holding a depth below the receiver's,
    /// which is t0 at the centre and changes by the gradients per texel step.
    fn shadow_taps(
        map: &[u32],
        side: i32,
        centre: ([i32; LANES], [i32; LANES]),
        receiver: (Self, Self, Self),
        active: Self::Mask,
    ) -> Self;
}

/// The portable lanes.
#[derive(Clone, Copy, Debug)]
pub(super) struct F8([f32; LANES]);

macro_rules! lanewise {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for F8 {
            type Output = F8;
            #[inline(always)]
            fn $method(self, rhs: F8) -> F8 {
                self.zip(rhs, |a, b| a $op b)
            }
        }
        impl $trait<f32> for F8 {
            type Output = F8;
            #[inline(always)]
            fn $method(self, rhs: f32) -> F8 {
                self.map(|a| a $op rhs)
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl F8 {
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Self(self.0.map(f))
    }

    #[inline(always)]
    fn zip(self, other: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Self(std::array::from_fn(|i| f(self.0[i], other.0[i])))
    }
}

impl Lanes for F8 {
    type Mask = [bool; LANES];

    #[inline(always)]
    fn splat(v: f32) -> Self {
        Self([v; LANES])
    }
    #[inline(always)]
    fn from_array(v: [f32; LANES]) -> Self {
        Self(v)
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        self.0
    }
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|v| -v)
    }
    #[inline(always)]
    fn max(self, other: f32) -> Self {
        self.map(|v| v.max(other))
    }
    #[inline(always)]
    fn min(self, other: f32) -> Self {
        self.map(|v| v.min(other))
    }
    #[inline(always)]
    fn max_lanes(self, other: Self) -> Self {
        self.zip(other, f32::max)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }
    #[inline(always)]
    fn clamp(self, low: f32, high: f32) -> Self {
        self.map(|v| v.clamp(low, high))
    }
    #[inline(always)]
    fn or(self, mask: Self::Mask, other: Self) -> Self {
        Self(std::array::from_fn(|i| if mask[i] { self.0[i] } else { other.0[i] }))
    }
    #[inline(always)]
    fn positive(self) -> Self::Mask {
        self.0.map(|v| v > 0.0)
    }
    #[inline(always)]
    fn present(keys: [u32; LANES]) -> Self::Mask {
        keys.map(|k| k != EMPTY)
    }
    #[inline(always)]
    fn depths(keys: [u32; LANES], own: [u32; LANES], z_per_unit: Self) -> Self {
        Self(std::array::from_fn(|i| ((keys[i] >> 8) as i32 - (own[i] >> 8) as i32) as f32)) * z_per_unit
    }
    #[inline(always)]
    fn shadow_taps(
        map: &[u32],
        side: i32,
        centre: ([i32; LANES], [i32; LANES]),
        (t0, gradient_x, gradient_y): (Self, Self, Self),
        active: Self::Mask,
    ) -> Self {
        Self(shadow_taps_portable(map, side, centre, (t0.0, gradient_x.0, gradient_y.0), active))
    }
}

/// A view-space vector per lane, with glam's `Vec3` arithmetic (its order of operations).
#[derive(Clone, Copy)]
struct V8<L> {
    x: L,
    y: L,
    z: L,
}

impl<L: Lanes> V8<L> {
    #[inline(always)]
    fn splat(v: [f32; 3]) -> Self {
        Self { x: L::splat(v[0]), y: L::splat(v[1]), z: L::splat(v[2]) }
    }

    #[inline(always)]
    fn dot(self, o: Self) -> L {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Self { x: self.y * o.z - o.y * self.z, y: self.z * o.x - o.z * self.x, z: self.x * o.y - o.x * self.y }
    }

    #[inline(always)]
    fn normalize(self) -> Self {
        let recip = L::splat(1.0) / self.dot(self).sqrt();
        Self { x: self.x * recip, y: self.y * recip, z: self.z * recip }
    }
}

/// The keys of pixels (x .. x + 8, y), [`EMPTY`] outside the accumulation.
#[inline(always)]
fn keys8(p: &ResolveParams, accum: &[u32], x: i32, y: i32) -> [u32; LANES] {
    let (width, height) = (p.width as i32, p.height as i32);
    if y < 0 || y >= height {
        return [EMPTY; LANES];
    }
    let row = &accum[y as usize * width as usize..][..width as usize];
    if x >= 0 && x + LANES as i32 <= width {
        let mut keys = [EMPTY; LANES];
        keys.copy_from_slice(&row[x as usize..x as usize + LANES]);
        return keys;
    }
    std::array::from_fn(|i| {
        let xi = x + i as i32;
        if xi >= 0 && xi < width { row[xi as usize] } else { EMPTY }
    })
}

/// The light factors (colour factor, white added) of the keys `keys` of pixels
/// (x0 .. x0 + 8, y): [`solid::light`] lane by lane. Lanes with an empty key give garbage.
#[inline(always)]
fn light8<L: Lanes>(
    p: &ResolveParams,
    inputs: &ResolveInputs<'_>,
    x0: i32,
    y: i32,
    keys: [u32; LANES],
) -> ([f32; LANES], [f32; LANES]) {
    let accum = inputs.accum;
    let one = L::splat(1.0);
    // footprints_per_unit, and the view distance d.
    let depth = L::from_array(keys.map(|k| (k >> 8) as f32)) / DEPTH_SCALE;
    let d = L::splat(p.near) + depth * (p.far - p.near);
    let footprint = if p.perspective != 0 { L::splat(p.pixel_size) * d } else { L::splat(p.pixel_size) };
    let z_per_unit = L::splat((p.far - p.near) / DEPTH_SCALE) / footprint;

    // fitted_slopes.
    let zero = L::splat(0.0);
    let (mut sw, mut sx, mut sy, mut sz) = (one, zero, zero, zero);
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (zero, zero, zero, zero, zero);
    let r = p.normal_radius_px as i32;
    for dy in -r..=r {
        for dx in -r..=r {
            if dx == 0 && dy == 0 {
                continue;
            }
            let k = keys8(p, accum, x0 + dx, y + dy);
            let here = L::present(k);
            let z = L::depths(k, keys, z_per_unit);
            let (fx, fy) = (dx as f32, dy as f32);
            let (q, r2) = (z / SLOPE_SCALE, fx * fx + fy * fy);
            let w = L::splat(r2) / (q * q + r2);
            sw = (sw + w).or(here, sw);
            sx = (sx + w * fx).or(here, sx);
            sy = (sy + w * fy).or(here, sy);
            sz = (sz + w * z).or(here, sz);
            sxx = (sxx + w * fx * fx).or(here, sxx);
            sxy = (sxy + w * fx * fy).or(here, sxy);
            syy = (syy + w * fy * fy).or(here, syy);
            sxz = (sxz + w * fx * z).or(here, sxz);
            syz = (syz + w * fy * z).or(here, syz);
        }
    }
    let inv_sw = one / sw;
    let cxx = sxx - sx * sx * inv_sw + RIDGE;
    let cyy = syy - sy * sy * inv_sw + RIDGE;
    let cxy = sxy - sx * sy * inv_sw;
    let cxz = sxz - sx * sz * inv_sw;
    let cyz = syz - sy * sz * inv_sw;
    let inv_det = one / (cxx * cyy - cxy * cxy);
    // light adds the slope offset, 0 here.
    let slope_x = ((cyy * cxz - cxy * cyz) * inv_det).clamp(-SLOPE_MAX, SLOPE_MAX) + 0.0;
    let slope_y = ((cxx * cyz - cxy * cxz) * inv_det).clamp(-SLOPE_MAX, SLOPE_MAX) + 0.0;

    // normal_and_eye.
    let x = L::from_array(std::array::from_fn(|i| (x0 + i as i32) as f32));
    let sx_screen = (x + 0.5 - 0.5 * p.width as f32) * p.pixel_size;
    let sy_screen = L::splat((0.5 * p.height as f32 - (y as f32 + 0.5)) * p.pixel_size);
    let ray = if p.perspective != 0 {
        V8 { x: sx_screen, y: sy_screen, z: L::splat(-1.0) }
    } else {
        V8::splat([0.0, 0.0, -1.0])
    };
    let tangent_x = V8 { x: ray.x * slope_x + 1.0, y: ray.y * slope_x + 0.0, z: ray.z * slope_x + 0.0 };
    let tangent_y = V8 { x: ray.x * slope_y - 0.0, y: ray.y * slope_y - 1.0, z: ray.z * slope_y - 0.0 };
    let normal = tangent_y.cross(tangent_x).normalize();
    let to_eye = V8 { x: ray.x.neg(), y: ray.y.neg(), z: ray.z.neg() }.normalize();

    let mut key_visible = one;
    if p.shadows > 0.0 {
        let view = if p.perspective != 0 {
            V8 { x: sx_screen * d, y: sy_screen * d, z: d.neg() }
        } else {
            V8 { x: sx_screen, y: sy_screen, z: d.neg() }
        };
        let shadow = shadow8(p, inputs.shadow, view, normal, footprint, keys);
        key_visible = one - L::splat(p.shadows) * shadow;
    }

    // lit_by.
    let light = V8::splat([p.key_light[0], p.key_light[1], p.key_light[2]]);
    let key_diffuse = L::splat(KEY) * normal.dot(light).max(0.0) * key_visible;
    let diffuse = L::splat(AMBIENT) + key_diffuse + L::splat(FILL) * normal.dot(V8::splat(FILL_LIGHT)).max(0.0);
    let half = V8 { x: light.x + to_eye.x, y: light.y + to_eye.y, z: light.z + to_eye.z }.normalize();
    let s1 = normal.dot(half).max(0.0);
    let s2 = s1 * s1;
    let s4 = s2 * s2;
    let s8 = s4 * s4;
    let s16 = s8 * s8;
    let specular = L::splat(SPECULAR) * (s16 * s16) * key_visible;

    let mut visible = one;
    if p.occlusion > 0.0 {
        let occluded = occlusion8(p, accum, x0, y, keys, z_per_unit, (slope_x, slope_y));
        visible = one - L::splat(p.occlusion) * occluded;
    }
    let factor = L::splat(1.0 - p.shading) + diffuse * p.shading;
    ((factor * visible).to_array(), (specular * p.shading * visible).to_array())
}

/// [`solid::occlusion`] lane by lane.
#[inline(always)]
fn occlusion8<L: Lanes>(
    p: &ResolveParams,
    accum: &[u32],
    x0: i32,
    y: i32,
    keys: [u32; LANES],
    z_per_unit: L,
    (slope_x, slope_y): (L, L),
) -> L {
    let one = L::splat(1.0);
    let step = p.occlusion_step_px as i32;
    let inv_step = 1.0 / step as f32;
    let (mut occluded, mut samples) = (L::splat(0.0), L::splat(0.0));
    for ring in 0..OCCLUSION_RINGS {
        for i in 0..OCCLUSION_DIRECTIONS {
            let (ox, oy, inv_length) = occlusion_offset(ring, i);
            let k = keys8(p, accum, x0 + ox * step, y + oy * step);
            let here = L::present(k);
            let z = L::depths(k, keys, z_per_unit);
            let above = slope_x * (ox * step) as f32 + slope_y * (oy * step) as f32 - z;
            let e = (above * (inv_length * inv_step) - OCCLUSION_BIAS).max(0.0);
            let f = e * INV_OCCLUSION_FALLOFF;
            occluded = (occluded + e / ((one + e) * (one + f * f))).or(here, occluded);
            samples = (samples + 1.0).or(here, samples);
        }
    }
    (L::splat(OCCLUSION_GAIN) * occluded / samples).min(1.0).or(samples.positive(), L::splat(0.0))
}

/// [`shadow::shadow_at`] lane by lane, for view-space positions `view` and unit normals
/// `normal`: the plane and bias in lanes, the 3×3 taps per lane (their texels are scattered).
#[inline(always)]
fn shadow8<L: Lanes>(
    p: &ResolveParams,
    map: &[u32],
    view: V8<L>,
    normal: V8<L>,
    footprint: L,
    keys: [u32; LANES],
) -> L {
    let map_from_view = Mat4::from_cols_array_2d(&p.shadow_from_view);
    let (qx, qy, qz) = (map_row(p, view, 0), map_row(p, view, 1), map_row(p, view, 2));
    let to_light = V8::splat([p.key_light[0], p.key_light[1], p.key_light[2]]);
    let cos = normal.dot(to_light).max(1.0 / SHADOW_SLOPE_MAX);
    let tan = ((L::splat(1.0) - cos * cos).max(0.0).sqrt() / cos).min(SHADOW_SLOPE_MAX);
    let texel_depth = p.shadow_texel_world * p.shadow_inv_depth_world;
    let row0 = (map_from_view.row(0).xyz() * p.shadow_texel_world).to_array();
    let row1 = (map_from_view.row(1).xyz() * p.shadow_texel_world).to_array();
    let gradient_x = (normal.dot(V8::splat(row0)) / cos).clamp(-SHADOW_SLOPE_MAX, SHADOW_SLOPE_MAX) * texel_depth;
    let gradient_y = (normal.dot(V8::splat(row1)) / cos).clamp(-SHADOW_SLOPE_MAX, SHADOW_SLOPE_MAX) * texel_depth;
    let bias = (L::splat(SHADOW_BIAS_TEXELS) + L::splat(SHADOW_BIAS_SLOPE) * tan)
        * footprint.max_lanes(L::splat(p.shadow_texel_world))
        * p.shadow_inv_depth_world;
    // The receiver's texel per lane (the scalar's float-to-int conversion), its depth there.
    let (cx, cy) = (qx.to_array().map(|v| v.floor() as i32), qy.to_array().map(|v| v.floor() as i32));
    let t0 = qz
        + gradient_x * (L::from_array(cx.map(|c| c as f32)) + 0.5 - qx)
        + gradient_y * (L::from_array(cy.map(|c| c as f32)) + 0.5 - qy)
        - bias;
    let side = p.shadow_side_px as i32;
    assert!(map.len() >= side.max(0) as usize * side.max(0) as usize, "a shadow map of side² keys");
    L::shadow_taps(map, side, (cx, cy), (t0, gradient_x, gradient_y), L::present(keys))
}

/// Row `r` of the shadow map's projection of `view` (glam's Mat4 · Vec4 with w = 1:
/// ((c0 x + c1 y) + c2 z) + c3).
#[inline(always)]
fn map_row<L: Lanes>(p: &ResolveParams, view: V8<L>, r: usize) -> L {
    let c = p.shadow_from_view;
    L::splat(c[0][r]) * view.x + L::splat(c[1][r]) * view.y + L::splat(c[2][r]) * view.z + c[3][r]
}

/// The portable lanes' [`Lanes::shadow_taps`]: [`shadow::shadow_at`]'s loop, lane by lane.
#[inline(always)]
fn shadow_taps_portable(
    map: &[u32],
    side: i32,
    (cx, cy): ([i32; LANES], [i32; LANES]),
    (t0, gradient_x, gradient_y): ([f32; LANES], [f32; LANES], [f32; LANES]),
    active: [bool; LANES],
) -> [f32; LANES] {
    let mut shadow = [0.0f32; LANES];
    for lane in 0..LANES {
        if !active[lane] {
            continue;
        }
        let (mut occluded, mut taps) = (0.0f32, 0.0f32);
        for j in -SHADOW_PCF_RADIUS..=SHADOW_PCF_RADIUS {
            for i in -SHADOW_PCF_RADIUS..=SHADOW_PCF_RADIUS {
                let (tx, ty) = (cx[lane] + i, cy[lane] + j);
                if tx >= 0 && ty >= 0 && tx < side && ty < side {
                    let k = map[(ty * side + tx) as usize];
                    let t = t0[lane] + gradient_x[lane] * i as f32 + gradient_y[lane] * j as f32;
                    if k != EMPTY && depth_of(k) < t {
                        occluded += 1.0;
                    }
                }
                taps += 1.0;
            }
        }
        shadow[lane] = occluded / taps;
    }
    shadow
}

/// The light factors of a band of rows: per pixel with a key, (colour factor, white added).
pub struct LightRows {
    rows: RangeInclusive<i32>,
    width: usize,
    factors: Vec<[f32; 2]>,
}

impl LightRows {
    /// The factors of rows `rows` (clipped to the accumulation) of `p`'s solid look.
    pub fn new(p: &ResolveParams, inputs: &ResolveInputs<'_>, rows: RangeInclusive<i32>) -> Self {
        let rows = (*rows.start()).max(0)..=(*rows.end()).min(p.height as i32 - 1);
        let width = p.width as usize;
        let mut factors = vec![[1.0, 0.0]; width * rows.clone().count()];
        for (y, out) in rows.clone().zip(factors.chunks_exact_mut(width.max(1))) {
            light_row(p, inputs, y, out);
        }
        Self { rows, width, factors }
    }

    /// A cache of every row of `p`'s accumulation, each pixel unlit (factor 1, nothing added)
    /// until [`Self::refresh`] computes its rows: the CPU twin of the GPU's light cache.
    pub fn whole(p: &ResolveParams) -> Self {
        let width = p.width as usize;
        Self { rows: 0..=p.height as i32 - 1, width, factors: vec![[1.0, 0.0]; width * p.height as usize] }
    }

    /// Computes rows `rows` (clipped to these rows) afresh, as [`Self::new`] would; the
    /// other rows keep their factors.
    pub fn refresh(&mut self, p: &ResolveParams, inputs: &ResolveInputs<'_>, rows: RangeInclusive<i32>) {
        debug_assert_eq!(self.width, p.width as usize);
        let rows = (*rows.start()).max(*self.rows.start())..=(*rows.end()).min(*self.rows.end());
        let first = (*rows.start() - *self.rows.start()).max(0) as usize;
        let out = self.factors[first * self.width..].chunks_exact_mut(self.width.max(1));
        for (y, out) in rows.zip(out) {
            out.fill([1.0, 0.0]);
            light_row(p, inputs, y, out);
        }
    }

    /// True when the cache holds every row of a `width`×`height` accumulation.
    pub fn covers(&self, width: u32, height: u32) -> bool {
        self.width == width as usize && self.rows == (0..=height as i32 - 1)
    }

    /// `albedo` lit at pixel (x, y) (a pixel of these rows).
    pub fn lit(&self, x: i32, y: i32, albedo: [f32; 3]) -> [f32; 3] {
        debug_assert!(self.rows.contains(&y));
        let [factor, white] = self.factors[(y - self.rows.start()) as usize * self.width + x as usize];
        albedo.map(|c| c * factor + white)
    }
}

/// The factors of row `y` into `out` (one per pixel), groups of eight pixels with a key.
#[inline(always)]
pub(super) fn light_row_lanes<L: Lanes>(p: &ResolveParams, inputs: &ResolveInputs<'_>, y: i32, out: &mut [[f32; 2]]) {
    let width = p.width as i32;
    let mut x0 = 0;
    while x0 < width {
        let keys = keys8(p, inputs.accum, x0, y);
        if keys.iter().any(|&k| k != EMPTY) {
            // Lanes past the row's end have no key (keys8 gives EMPTY there).
            let (factor, white) = light8::<L>(p, inputs, x0, y, keys);
            for lane in 0..LANES {
                let x = x0 as usize + lane;
                if x < out.len() && keys[lane] != EMPTY {
                    out[x] = [factor[lane], white[lane]];
                }
            }
        }
        x0 += LANES as i32;
    }
}

/// [`light_row_lanes`], compiled for AVX2 where the CPU has it.
fn light_row(p: &ResolveParams, inputs: &ResolveInputs<'_>, y: i32, out: &mut [[f32; 2]]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::SimdLevel::detect().avx2() {
        x86::light_row_avx2(p, inputs, y, out);
        return;
    }
    light_row_lanes::<F8>(p, inputs, y, out);
}

#[cfg(target_arch = "x86_64")]
mod x86;

#[cfg(test)]
#[path = "light_rows_tests.rs"]
mod tests;
