//! The closest-point splat with AVX2 (detected at run time): eight points projected per vector,
//! every operation that of [`SplatView::project`] and the portable splat in its order, then
//! each lane's key merged into its pixel with a scalar `min` (pixels are random, so there is
//! nothing to vectorize there, and `min` makes the order of the lanes irrelevant).
//!
//! Everything here requires AVX2: [`splat_closest`] checks the CPU before entering. Hence the
//! module-wide `unsafe_code` allowance: the intrinsics are `unsafe` to call outside a
//! `#[target_feature]` function; the memory accesses carry their own SAFETY notes.
#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{DEPTH_BITS, EMPTY, SplatView};
use crate::chaos_game::PointBatch;

const LANES: usize = 8;
/// Groups of 8 points between a pixel's prefetch and its update.
const AHEAD: usize = 8;

/// Whether [`splat_closest`] can run for this view and framebuffer length on this CPU.
pub(super) fn closest_supported(view: &SplatView, len: usize) -> bool {
    let (w, h) = (view.width as usize, view.height as usize);
    // Pixel indices are computed in i32; sizes up to 2^24 keep `width as f32` exact.
    is_x86_feature_detected!("avx2") && len == w * h && len > 0 && len <= i32::MAX as usize && w <= 1 << 24 && h <= 1 << 24
}

/// Splats `batch` into `closest` (one key per pixel of `view`), exactly as the portable
/// closest-mode splat does.
pub(super) fn splat_closest(view: &SplatView, closest: &mut [u32], batch: PointBatch<'_>) {
    assert!(closest_supported(view, closest.len()));
    assert!(batch.x.len() == batch.len() && batch.y.len() == batch.len() && batch.z.len() == batch.len());
    // SAFETY: the CPU has AVX2 and the framebuffer has width · height > 0 pixels (asserted);
    // the batch's slices have equal lengths (asserted).
    unsafe { splat_closest_avx2(view, closest, batch) }
}

#[target_feature(enable = "avx2")]
unsafe fn splat_closest_avx2(view: &SplatView, closest: &mut [u32], batch: PointBatch<'_>) {
    let n = batch.len();
    let m = view.pixel_from_world;
    let (c0, c1, c2, c3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
    let depth_range = view.far - view.near;
    let vectors = n / LANES;
    // Group g's pixels are prefetched when it is projected and updated AHEAD groups later,
    // so that many cache misses into the framebuffer are in flight at once.
    let mut ring_keys = [[0u32; LANES]; AHEAD];
    let mut ring_pixels = [[0u32; LANES]; AHEAD];
    for g in 0..vectors + AHEAD {
        let (keys, pixels) = (&mut ring_keys[g % AHEAD], &mut ring_pixels[g % AHEAD]);
        if g >= AHEAD {
            for l in 0..LANES {
                // SAFETY: an inside lane's pixel is iy · width + ix with 0 ≤ ix < width and
                // 0 ≤ iy < height (exact truncations of the checked coordinates), below
                // width · height = closest.len(); an outside lane's is 0 < closest.len().
                let slot = unsafe { closest.get_unchecked_mut(pixels[l] as usize) };
                *slot = (*slot).min(keys[l]);
            }
        }
        if g >= vectors {
            continue;
        }
        let o = g * LANES;
        // SAFETY: o + 8 ≤ n, the length of each of the batch's slices; stores into local arrays.
        unsafe {
            let x = _mm256_loadu_ps(batch.x.as_ptr().add(o));
            let y = _mm256_loadu_ps(batch.y.as_ptr().add(o));
            let z = _mm256_loadu_ps(batch.z.as_ptr().add(o));
            let fi = _mm256_cvtepu8_epi32(_mm_loadl_epi64(batch.functions.as_ptr().add(o).cast()));
            // glam's Mat4 · Vec4 with w = 1: ((c0 x + c1 y) + c2 z) + c3 · 1, and c3 · 1 = c3.
            // A macro, as closures would not inherit this function's target features.
            macro_rules! row {
                ($c:ident) => {
                    _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(c0.$c), x), _mm256_mul_ps(_mm256_set1_ps(c1.$c), y)), _mm256_mul_ps(_mm256_set1_ps(c2.$c), z)), _mm256_set1_ps(c3.$c))
                };
            }
            let (qx, qy, qz, qw) = (row!(x), row!(y), row!(z), row!(w));
            let inv_w = _mm256_div_ps(_mm256_set1_ps(1.0), qw);
            let (px, py) = (_mm256_mul_ps(qx, inv_w), _mm256_mul_ps(qy, inv_w));
            // q.w > 0, 0 ≤ x < width, 0 ≤ y < height; ordered compares, so NaN fails.
            let zero = _mm256_setzero_ps();
            let inside = _mm256_and_ps(
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(qw, zero), _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(px, zero), _mm256_cmp_ps::<_CMP_GE_OQ>(py, zero))),
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(px, _mm256_set1_ps(view.width as f32)), _mm256_cmp_ps::<_CMP_LT_OQ>(py, _mm256_set1_ps(view.height as f32))),
            );
            // t = clamp((q.z − near) / (far − near), 0, 1), then d = t · scale, and the portable
            // splat's `d > 0 ? d : 0`: a NaN t ends at 0 either way (maxps returns its second
            // operand on NaN), and −0 becomes +0, which truncates alike.
            let t = _mm256_div_ps(_mm256_sub_ps(qz, _mm256_set1_ps(view.near)), _mm256_set1_ps(depth_range));
            let t = _mm256_min_ps(_mm256_max_ps(t, zero), _mm256_set1_ps(1.0));
            let depth = _mm256_cvttps_epi32(_mm256_mul_ps(t, _mm256_set1_ps(scale)));
            let key = _mm256_or_si256(_mm256_slli_epi32::<8>(depth), fi);
            let pixel = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(py), _mm256_set1_epi32(view.width as i32)), _mm256_cvttps_epi32(px));
            // Outside lanes: the empty key (a no-op under min) on pixel 0.
            let inside = _mm256_castps_si256(inside);
            let key = _mm256_blendv_epi8(_mm256_set1_epi32(EMPTY as i32), key, inside);
            let pixel = _mm256_and_si256(pixel, inside);
            _mm256_storeu_si256(keys.as_mut_ptr().cast(), key);
            _mm256_storeu_si256(pixels.as_mut_ptr().cast(), pixel);
            for &pixel in pixels.iter() {
                // A prefetch of any address is harmless; this one is inside `closest` (above).
                _mm_prefetch::<_MM_HINT_T0>(closest.as_ptr().add(pixel as usize).cast());
            }
        }
    }
    for i in vectors * LANES..n {
        if let Some((idx, t)) = view.project(batch.point(i)) {
            let d = t * scale;
            let d = if d > 0.0 { d } else { 0.0 };
            let key = (d as u32) << 8 | batch.functions[i] as u32;
            closest[idx] = closest[idx].min(key);
        }
    }
}
