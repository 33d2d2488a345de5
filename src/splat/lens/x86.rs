//! The lens projection with AVX2 (detected at run time): eight points at a time, every
//! operation that of [`super::project_through_lens`] in its order (the hash, the rejection loop
//! drawing the lens sample, the projection), so the two give the same pixels bit for bit
//! (`tests/depth_of_field.rs` and the unit test below compare them). The rejection loop runs
//! until every lane has its sample (at most [`LENS_TRIES`] rounds).
//!
//! Everything here requires AVX2: [`project_block`] checks the CPU before entering. Hence the
//! module-wide `unsafe_code` allowance: the intrinsics are `unsafe` to call outside a
//! `#[target_feature]` function; the memory accesses carry their own SAFETY notes.
#![expect(
    unsafe_code,
    reason = "intrinsics need unsafe outside #[target_feature] functions; callers check the CPU first"
)]

use std::arch::x86_64::*;

use super::{LENS_TRIES, SplatView, project_through_lens};
use crate::chaos_game::PointBatch;
use crate::rng::{PCG_INC, PCG_MUL, PCG_OUT_MUL, pcg_hash};
use crate::simd::SimdLevel;

const LANES: usize = 8;

/// Whether [`project_block`] runs vector code for this view on this CPU.
pub(super) fn supported(view: &SplatView) -> bool {
    let (w, h) = (view.width as usize, view.height as usize);
    // Pixel indices are computed in i32; sizes up to 2^24 keep `width as f32` exact.
    SimdLevel::detect().avx2() && w * h > 0 && w * h <= i32::MAX as usize && w <= 1 << 24 && h <= 1 << 24
}

/// `out[i]` = [`project_through_lens`] of point `start + i` of `batch`, for i < `out.len()`.
pub(super) fn project_block(view: &SplatView, batch: PointBatch<'_>, start: usize, out: &mut [Option<(usize, f32)>]) {
    assert!(supported(view));
    let n = out.len();
    assert!(start + n <= batch.x.len() && start + n <= batch.y.len() && start + n <= batch.z.len());
    // SAFETY: the CPU has AVX2 and the view at least one pixel; the batch's slices hold the
    // block (both asserted above).
    unsafe { project_block_avx2(view, batch, start, out) }
}

/// [`project_block`] compiled with AVX2, so that the loads, stores and [`project8`] inline
/// into the loop (from a function without the feature each intrinsic was an out-of-line call).
#[target_feature(enable = "avx2")]
unsafe fn project_block_avx2(view: &SplatView, batch: PointBatch<'_>, start: usize, out: &mut [Option<(usize, f32)>]) {
    let n = out.len();
    let vectors = n / LANES;
    for g in 0..vectors {
        let o = start + g * LANES;
        let mut pixels = [0u32; LANES];
        let mut ts = [0f32; LANES];
        // SAFETY: the CPU has AVX2 and the view at least one pixel (the caller asserted); o + 8
        // ≤ start + n ≤ each slice's length (asserted there), and the stores go to local arrays.
        let inside = unsafe {
            let (x, y, z) = (
                _mm256_loadu_ps(batch.x.as_ptr().add(o)),
                _mm256_loadu_ps(batch.y.as_ptr().add(o)),
                _mm256_loadu_ps(batch.z.as_ptr().add(o)),
            );
            let (inside, pixel, t) = project8(view, x, y, z);
            _mm256_storeu_si256(pixels.as_mut_ptr().cast(), pixel);
            _mm256_storeu_ps(ts.as_mut_ptr(), t);
            _mm256_movemask_ps(inside)
        };
        for l in 0..LANES {
            out[g * LANES + l] = (inside >> l & 1 == 1).then_some((pixels[l] as usize, ts[l]));
        }
    }
    for (i, slot) in out.iter_mut().enumerate().skip(vectors * LANES) {
        *slot = project_through_lens(view, batch.point(start + i));
    }
}

/// `pcg_hash` of eight lanes.
#[inline(always)]
unsafe fn hash8(input: __m256i) -> __m256i {
    // SAFETY: the caller checked the CPU features (module doc); no memory is accessed.
    unsafe { output8(_mm256_add_epi32(_mm256_mullo_epi32(input, _mm256_set1_epi32(PCG_MUL as i32)), inc())) }
}

#[inline(always)]
unsafe fn inc() -> __m256i {
    // SAFETY: as `hash8`.
    unsafe { _mm256_set1_epi32(PCG_INC as i32) }
}

/// PCG's RXS-M-XS output of eight states (the step of `Pcg32::next_u32` before the update).
#[inline(always)]
unsafe fn output8(state: __m256i) -> __m256i {
    // SAFETY: as `hash8`.
    unsafe {
        let shift = _mm256_add_epi32(_mm256_srli_epi32::<28>(state), _mm256_set1_epi32(4));
        let word = _mm256_mullo_epi32(
            _mm256_xor_si256(_mm256_srlv_epi32(state, shift), state),
            _mm256_set1_epi32(PCG_OUT_MUL as i32),
        );
        _mm256_xor_si256(_mm256_srli_epi32::<22>(word), word)
    }
}

/// `2 · next_f32 − 1` of eight generators, which advance.
#[inline(always)]
unsafe fn next_signed8(state: &mut __m256i) -> __m256 {
    // SAFETY: as `hash8`.
    unsafe {
        let word = output8(*state);
        *state = _mm256_add_epi32(_mm256_mullo_epi32(*state, _mm256_set1_epi32(PCG_MUL as i32)), inc());
        // (word >> 8) < 2^24 converts exactly, as `as f32` does.
        let f = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32::<8>(word)), _mm256_set1_ps(1.0 / 16_777_216.0));
        _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(2.0), f), _mm256_set1_ps(1.0))
    }
}

/// The lens projection of eight points: a mask of the lanes that land in the image, their
/// pixel indices (0 elsewhere) and depth fractions t.
#[target_feature(enable = "avx2")]
unsafe fn project8(view: &SplatView, x: __m256, y: __m256, z: __m256) -> (__m256, __m256i, __m256) {
    let lens = view.lens;
    // SAFETY: this function has AVX2 (the caller checked the CPU); no memory is accessed.
    unsafe {
        // As `SplatView::project` (the image splat's transform).
        let [qx, qy, qz, qw] = crate::splat::x86::transform8(&view.pixel_from_world, x, y, z);
        let inv_w = _mm256_div_ps(_mm256_set1_ps(1.0), qw);
        let defocus = if lens.perspective {
            _mm256_sub_ps(_mm256_set1_ps(lens.inv_focus), inv_w)
        } else {
            _mm256_sub_ps(_mm256_mul_ps(qz, _mm256_set1_ps(lens.inv_focus)), _mm256_set1_ps(1.0))
        };
        let r = _mm256_mul_ps(_mm256_set1_ps(lens.radius_px), defocus);

        // The lens sample: hash of (seed, x, y, z) bits, then the rejection loop.
        let bits = |v: __m256| _mm256_castps_si256(v);
        let seeded = _mm256_set1_epi32(pcg_hash(lens.seed) as i32);
        let h = hash8(_mm256_xor_si256(bits(x), seeded));
        let h = hash8(_mm256_xor_si256(bits(y), h));
        let mut state = hash8(_mm256_xor_si256(bits(z), h));
        let (mut u, mut v) = (_mm256_setzero_ps(), _mm256_setzero_ps());
        let mut pending = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        for _ in 0..LENS_TRIES {
            let du = next_signed8(&mut state);
            let dv = next_signed8(&mut state);
            let r2 = _mm256_add_ps(_mm256_mul_ps(du, du), _mm256_mul_ps(dv, dv));
            let take = _mm256_and_ps(pending, _mm256_cmp_ps::<_CMP_LE_OQ>(r2, _mm256_set1_ps(1.0)));
            u = _mm256_blendv_ps(u, du, take);
            v = _mm256_blendv_ps(v, dv, take);
            pending = _mm256_andnot_ps(take, pending);
            if _mm256_movemask_ps(pending) == 0 {
                break;
            }
        }

        let px = _mm256_add_ps(_mm256_mul_ps(qx, inv_w), _mm256_mul_ps(u, r));
        let py = _mm256_sub_ps(_mm256_mul_ps(qy, inv_w), _mm256_mul_ps(v, r));
        // q.w > 0, 0 ≤ x < width, 0 ≤ y < height; ordered compares, so NaN fails.
        let zero = _mm256_setzero_ps();
        let inside = _mm256_and_ps(
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(qw, zero),
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(px, zero), _mm256_cmp_ps::<_CMP_GE_OQ>(py, zero)),
            ),
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LT_OQ>(px, _mm256_set1_ps(view.width as f32)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(py, _mm256_set1_ps(view.height as f32)),
            ),
        );
        let pixel = _mm256_add_epi32(
            _mm256_mullo_epi32(_mm256_cvttps_epi32(py), _mm256_set1_epi32(view.width as i32)),
            _mm256_cvttps_epi32(px),
        );
        // t = ((q.z − near) · (1 / (far − near))).clamp(0, 1): below 0 → 0, above 1 → 1, NaN kept.
        let t =
            _mm256_mul_ps(_mm256_sub_ps(qz, _mm256_set1_ps(view.near)), _mm256_set1_ps(1.0 / (view.far - view.near)));
        let t = _mm256_blendv_ps(t, zero, _mm256_cmp_ps::<_CMP_LT_OQ>(t, zero));
        let t = _mm256_blendv_ps(t, _mm256_set1_ps(1.0), _mm256_cmp_ps::<_CMP_GT_OQ>(t, _mm256_set1_ps(1.0)));
        (inside, _mm256_and_si256(pixel, _mm256_castps_si256(inside)), t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{OrbitCamera, Projection};
    use crate::rng::Pcg32;
    use crate::scene::spec::SplatMode;
    use crate::splat::Lens;
    use glam::{DVec3, Vec3};

    /// The vector lens projection gives the scalar one's pixel and depth fraction, bit for bit
    /// (tolerance 0), for points inside, outside, behind the eye and non-finite, in both
    /// projections, with a block length that is not a multiple of 8.
    #[test]
    fn vector_lens_projection_matches_scalar() {
        let bounds = (DVec3::ZERO, DVec3::ONE);
        for projection in [Projection::Perspective, Projection::Parallel] {
            let camera = OrbitCamera { projection, ..OrbitCamera::framing(bounds, 3) };
            let lens = Lens::new(&camera, 48, 0.1 * camera.distance, Some(0.8 * camera.distance), 5).unwrap();
            let view = SplatView::new(&camera, 64, 48, bounds, SplatMode::Closest, 0.5, [0.0; 3]).with_lens(lens);
            if !supported(&view) {
                return;
            }
            let mut r = Pcg32::for_stream(8, 0, 0);
            let mut p: Vec<Vec3> =
                (0..4003).map(|_| Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 3.0 - 1.0).collect();
            (p[5], p[6], p[7], p[9]) =
                (Vec3::NAN, Vec3::new(0.5, f32::INFINITY, 0.5), camera.eye(), 2.0 * camera.eye() - camera.target);
            let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) =
                (p.iter().map(|p| p.x).collect(), p.iter().map(|p| p.y).collect(), p.iter().map(|p| p.z).collect());
            let functions = vec![0u8; p.len()];
            let batch = PointBatch { x: &x, y: &y, z: &z, functions: &functions };
            let mut out = vec![None; p.len() - 3];
            project_block(&view, batch, 3, &mut out);
            let mut hits = 0;
            for (i, got) in out.iter().enumerate() {
                let want = project_through_lens(&view, p[3 + i]);
                let same = match (got, want) {
                    (Some((a, s)), Some((b, t))) => *a == b && s.to_bits() == t.to_bits(),
                    (None, None) => true,
                    _ => false,
                };
                assert!(same, "{projection:?} point {}: {got:?} vs {want:?}", 3 + i);
                hits += got.is_some() as u32;
            }
            assert!(hits > 500, "{hits}");
        }
    }
}
