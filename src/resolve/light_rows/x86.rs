//! The light's lanes in one AVX register ([`Avx8`]), for CPUs with AVX2: the operations of the
//! portable lanes ([`super::F8`]), each the same IEEE operation on eight floats, so the
//! factors keep their bits (`portable_lanes_equal_the_dispatched_ones`). The compiler's own
//! vectorization of the portable lanes left most of the arithmetic scalar or four wide.
//!
//! An [`Avx8`] is only made inside [`light_row_avx2`], after its CPU check: hence the module's
//! `unsafe_code` allowance (intrinsics are `unsafe` to call outside a `#[target_feature]`
//! function; the trait's methods inline into `light_row_avx2`'s AVX2 code).
#![expect(unsafe_code, reason = "intrinsics outside #[target_feature] functions; Avx8 exists only after the CPU check")]

use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Sub};

use super::{LANES, Lanes, light_row_lanes};
use crate::resolve::shadow::SHADOW_PCF_RADIUS;
use crate::resolve::{DEPTH_SCALE, EMPTY, ResolveInputs, ResolveParams};
use crate::simd::SimdLevel;

/// [`light_row_lanes`] with AVX2 (eight lanes to a register).
pub(super) fn light_row_avx2(p: &ResolveParams, inputs: &ResolveInputs<'_>, y: i32, out: &mut [[f32; 2]]) {
    #[target_feature(enable = "avx2")]
    fn run(p: &ResolveParams, inputs: &ResolveInputs<'_>, y: i32, out: &mut [[f32; 2]]) {
        light_row_lanes::<Avx8>(p, inputs, y, out);
    }
    assert!(SimdLevel::detect().avx2());
    // SAFETY: the CPU has AVX2 (asserted).
    unsafe { run(p, inputs, y, out) }
}

/// Eight lanes in an AVX register.
#[derive(Clone, Copy)]
struct Avx8(__m256);

/// Evaluates AVX intrinsics.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: an Avx8 is only made in light_row_avx2's AVX2 code, on a CPU with AVX2
        // (module doc); loads and stores go through whole arrays of eight lanes.
        unsafe { $e }
    };
}

macro_rules! lanewise {
    ($trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for Avx8 {
            type Output = Avx8;
            #[inline(always)]
            fn $method(self, rhs: Avx8) -> Avx8 {
                Avx8(avx!($intrinsic(self.0, rhs.0)))
            }
        }
        impl $trait<f32> for Avx8 {
            type Output = Avx8;
            #[inline(always)]
            fn $method(self, rhs: f32) -> Avx8 {
                Avx8(avx!($intrinsic(self.0, _mm256_set1_ps(rhs))))
            }
        }
    };
}
lanewise!(Add, add, _mm256_add_ps);
lanewise!(Sub, sub, _mm256_sub_ps);
lanewise!(Mul, mul, _mm256_mul_ps);
lanewise!(Div, div, _mm256_div_ps);

#[inline(always)]
fn load_keys(keys: [u32; LANES]) -> __m256i {
    avx!(_mm256_loadu_si256(keys.as_ptr().cast()))
}

impl Lanes for Avx8 {
    type Mask = __m256;

    #[inline(always)]
    fn splat(v: f32) -> Self {
        Avx8(avx!(_mm256_set1_ps(v)))
    }
    #[inline(always)]
    fn from_array(v: [f32; LANES]) -> Self {
        Avx8(avx!(_mm256_loadu_ps(v.as_ptr())))
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        avx!(_mm256_storeu_ps(out.as_mut_ptr(), self.0));
        out
    }
    #[inline(always)]
    fn neg(self) -> Self {
        Avx8(avx!(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))))
    }
    /// maxps returns its second operand where either is NaN: `other`, as f32::max does.
    #[inline(always)]
    fn max(self, other: f32) -> Self {
        Avx8(avx!(_mm256_max_ps(self.0, _mm256_set1_ps(other))))
    }
    #[inline(always)]
    fn min(self, other: f32) -> Self {
        Avx8(avx!(_mm256_min_ps(self.0, _mm256_set1_ps(other))))
    }
    #[inline(always)]
    fn max_lanes(self, other: Self) -> Self {
        Avx8(avx!(_mm256_max_ps(self.0, other.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Avx8(avx!(_mm256_sqrt_ps(self.0)))
    }
    /// Ordered compares: a NaN lane is neither below nor above, and stays.
    #[inline(always)]
    fn clamp(self, low: f32, high: f32) -> Self {
        avx!({
            let (low, high) = (_mm256_set1_ps(low), _mm256_set1_ps(high));
            let v = _mm256_blendv_ps(self.0, low, _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, low));
            Avx8(_mm256_blendv_ps(v, high, _mm256_cmp_ps::<_CMP_GT_OQ>(v, high)))
        })
    }
    #[inline(always)]
    fn or(self, mask: __m256, other: Self) -> Self {
        Avx8(avx!(_mm256_blendv_ps(other.0, self.0, mask)))
    }
    #[inline(always)]
    fn positive(self) -> __m256 {
        avx!(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, _mm256_setzero_ps()))
    }
    #[inline(always)]
    fn present(keys: [u32; LANES]) -> __m256 {
        avx!({
            let empty = _mm256_set1_epi32(EMPTY as i32);
            let is_empty = _mm256_cmpeq_epi32(load_keys(keys), empty);
            _mm256_castsi256_ps(_mm256_xor_si256(is_empty, empty))
        })
    }
    /// Depths are 24 bits: the difference fits an i32 and converts exactly.
    #[inline(always)]
    fn depths(keys: [u32; LANES], own: [u32; LANES], z_per_unit: Self) -> Self {
        avx!({
            let difference =
                _mm256_sub_epi32(_mm256_srli_epi32::<8>(load_keys(keys)), _mm256_srli_epi32::<8>(load_keys(own)));
            Avx8(_mm256_mul_ps(_mm256_cvtepi32_ps(difference), z_per_unit.0))
        })
    }
    /// The taps gathered eight at a time, masked to the map (masked lanes read nothing);
    /// `occluded + 0` where a tap does not occlude leaves the count's bits (never −0).
    #[inline(always)]
    fn shadow_taps(
        map: &[u32],
        side: i32,
        (cx, cy): ([i32; LANES], [i32; LANES]),
        (t0, gradient_x, gradient_y): (Self, Self, Self),
        active: __m256,
    ) -> Self {
        assert!(map.len() >= side.max(0) as usize * side.max(0) as usize);
        avx!({
            let (cx, cy) = (_mm256_loadu_si256(cx.as_ptr().cast()), _mm256_loadu_si256(cy.as_ptr().cast()));
            let (minus_one, side_v) = (_mm256_set1_epi32(-1), _mm256_set1_epi32(side));
            let empty = _mm256_set1_epi32(EMPTY as i32);
            let mut occluded = _mm256_setzero_ps();
            let mut taps = 0.0f32;
            for j in -SHADOW_PCF_RADIUS..=SHADOW_PCF_RADIUS {
                for i in -SHADOW_PCF_RADIUS..=SHADOW_PCF_RADIUS {
                    let tx = _mm256_add_epi32(cx, _mm256_set1_epi32(i));
                    let ty = _mm256_add_epi32(cy, _mm256_set1_epi32(j));
                    let inside = _mm256_and_si256(
                        _mm256_and_si256(_mm256_cmpgt_epi32(tx, minus_one), _mm256_cmpgt_epi32(ty, minus_one)),
                        _mm256_and_si256(_mm256_cmpgt_epi32(side_v, tx), _mm256_cmpgt_epi32(side_v, ty)),
                    );
                    let read = _mm256_and_si256(inside, _mm256_castps_si256(active));
                    let index = _mm256_add_epi32(_mm256_mullo_epi32(ty, side_v), tx);
                    // Lanes outside `read` keep EMPTY and touch no memory; the others index
                    // texels inside the side² map (asserted above).
                    let k = _mm256_mask_i32gather_epi32::<4>(empty, map.as_ptr().cast(), index, read);
                    let t = _mm256_add_ps(
                        _mm256_add_ps(t0.0, _mm256_mul_ps(gradient_x.0, _mm256_set1_ps(i as f32))),
                        _mm256_mul_ps(gradient_y.0, _mm256_set1_ps(j as f32)),
                    );
                    let depth =
                        _mm256_div_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32::<8>(k)), _mm256_set1_ps(DEPTH_SCALE));
                    let present = _mm256_castsi256_ps(_mm256_xor_si256(_mm256_cmpeq_epi32(k, empty), empty));
                    let hit = _mm256_and_ps(present, _mm256_cmp_ps::<_CMP_LT_OQ>(depth, t));
                    occluded = _mm256_add_ps(occluded, _mm256_and_ps(hit, _mm256_set1_ps(1.0)));
                    taps += 1.0;
                }
            }
            Avx8(_mm256_div_ps(occluded, _mm256_set1_ps(taps)))
        })
    }
}
