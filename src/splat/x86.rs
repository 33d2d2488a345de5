//! The splat with AVX2 (detected at run time): eight points projected per vector (sixteen with
//! AVX-512F), every operation that of [`SplatView::project`] and the portable splat in its
//! order. Then the pixels:
//! - closest mode, into keys the target holds ([`Pixels::own_keys`], a framebuffer's own): the
//!   vector's present keys are gathered and compared with its new ones, and only lanes whose key
//!   falls are written (a `min`, lane after lane, so two lanes on one pixel keep the smaller).
//!   Once a picture has a few points per pixel almost no key falls (tapering, 50·10^6 points at
//!   1920×1080: 0.85 % of the points), so the splat mostly reads, the branch is rarely taken, and
//!   no cache line is dirtied for nothing; `min` is order-independent, so the keys are those of a
//!   `min` per point, byte for byte (`nlifs bench cpu`: map + closest 105 → 261 M points/s);
//! - the accumulating modes ([`accumulate`]), into sums the target holds
//!   ([`Pixels::own_sums`]): each lane's sum updated with one 16-byte load and store, a vector
//!   after its line's prefetch (8-wide; 16-wide on AMD), or, 16-wide on Intel, a vector whose
//!   lanes fall on distinct pixels gathers their sums, adds and scatters them back
//!   ([`SumUpdates`]);
//! - otherwise each lane's pixel is updated by scalar code: closest keys through
//!   [`Pixels::min_key`], in the accumulating modes the lanes' updates through [`Pixels::add`].
//!
//! Everything here requires AVX2: [`splat`] checks the CPU before entering. Hence the
//! module-wide `unsafe_code` allowance: the intrinsics are `unsafe` to call outside a
//! `#[target_feature]` function; the memory accesses carry their own SAFETY notes.
#![expect(
    unsafe_code,
    reason = "intrinsics need unsafe outside #[target_feature] functions; callers check the CPU first"
)]

use std::arch::x86_64::*;

mod accumulate;

use accumulate::{splat_accumulate_avx2, splat_accumulate_avx512};

use super::{DEPTH_BITS, EMPTY, Pixels, SplatMode, SplatView};
use crate::chaos_game::PointBatch;
use crate::simd::{SimdLevel, SumUpdates};

const LANES: usize = 8;

/// Whether [`splat`] can run for this view on this CPU.
pub(super) fn supported(view: &SplatView) -> bool {
    let (w, h) = (view.width as usize, view.height as usize);
    let len = w * h;
    // Pixel indices are computed in i32; sizes up to 2^24 keep `width as f32` exact.
    SimdLevel::detect().avx2() && len > 0 && len <= i32::MAX as usize && w <= 1 << 24 && h <= 1 << 24
}

/// Splats `batch` of `view` into `out`, exactly as the portable splat does. Outside lanes of
/// closest mode send the empty key (a no-op under min) to pixel 0.
pub(super) fn splat(view: &SplatView, colors: &[[f32; 3]], batch: PointBatch<'_>, out: &mut impl Pixels) {
    splat_with(view, colors, batch, out, SimdLevel::detect().avx512(), SumUpdates::detect());
}

/// [`splat`], with the 16-wide AVX-512 splats if `wide`, adding to sums as `updates` says (for
/// tests).
pub(super) fn splat_with(
    view: &SplatView,
    colors: &[[f32; 3]],
    batch: PointBatch<'_>,
    out: &mut impl Pixels,
    wide: bool,
    updates: SumUpdates,
) {
    assert!(supported(view) && (!wide || SimdLevel::detect().avx512()));
    assert!(batch.x.len() == batch.len() && batch.y.len() == batch.len() && batch.z.len() == batch.len());
    // SAFETY: the CPU has AVX2 (and AVX-512F and CD if wide: `SimdLevel::Avx512`), and the view has width · height > 0
    // pixels (asserted); the batch's slices have equal lengths (asserted).
    unsafe {
        match view.mode {
            SplatMode::Closest if wide => splat_closest_avx512(view, out, batch),
            SplatMode::Closest => splat_closest_avx2(view, out, batch),
            SplatMode::Average | SplatMode::Density if wide => {
                splat_accumulate_avx512(view, colors, out, batch, updates)
            }
            SplatMode::Average | SplatMode::Density => splat_accumulate_avx2(view, colors, out, batch),
        }
    }
}

/// glam's `Mat4 · Vec4` with w = 1 for 8 points: ((c0 x + c1 y) + c2 z) + c3 · 1 (and
/// c3 · 1 = c3), the arithmetic of [`SplatView::project`]; the result's x, y, z and w rows.
/// Inlined into its callers, which carry the target features.
#[inline(always)]
pub(super) unsafe fn transform8(m: &glam::Mat4, x: __m256, y: __m256, z: __m256) -> [__m256; 4] {
    let (c0, c1, c2, c3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    // SAFETY: the caller checked the CPU features (module doc); no memory is accessed.
    unsafe {
        // A macro, as closures would not have the caller's target features.
        macro_rules! row {
            ($c:ident) => {
                _mm256_add_ps(
                    _mm256_add_ps(
                        _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(c0.$c), x), _mm256_mul_ps(_mm256_set1_ps(c1.$c), y)),
                        _mm256_mul_ps(_mm256_set1_ps(c2.$c), z),
                    ),
                    _mm256_set1_ps(c3.$c),
                )
            };
        }
        [row!(x), row!(y), row!(z), row!(w)]
    }
}

/// The projection of 8 points (as [`SplatView::project`]): a mask of the lanes that land in
/// the image, their pixel indices (0 elsewhere) and their depth fractions t (clamped as
/// `f32::clamp` does: a NaN stays NaN).
#[inline(always)]
unsafe fn project8(view: &SplatView, x: __m256, y: __m256, z: __m256) -> (__m256i, __m256i, __m256) {
    // SAFETY: the caller checked the CPU features (module doc); no memory is accessed.
    unsafe {
        let [qx, qy, qz, qw] = transform8(&view.pixel_from_world, x, y, z);
        let inv_w = _mm256_div_ps(_mm256_set1_ps(1.0), qw);
        let (px, py) = (_mm256_mul_ps(qx, inv_w), _mm256_mul_ps(qy, inv_w));
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
        let inside = _mm256_castps_si256(inside);
        let pixel = _mm256_add_epi32(
            _mm256_mullo_epi32(_mm256_cvttps_epi32(py), _mm256_set1_epi32(view.width as i32)),
            _mm256_cvttps_epi32(px),
        );
        // t = ((q.z − near) · (1 / (far − near))).clamp(0, 1): below 0 → 0, above 1 → 1, NaN kept.
        let t =
            _mm256_mul_ps(_mm256_sub_ps(qz, _mm256_set1_ps(view.near)), _mm256_set1_ps(1.0 / (view.far - view.near)));
        let t = _mm256_blendv_ps(t, zero, _mm256_cmp_ps::<_CMP_LT_OQ>(t, zero));
        let t = _mm256_blendv_ps(t, _mm256_set1_ps(1.0), _mm256_cmp_ps::<_CMP_GT_OQ>(t, _mm256_set1_ps(1.0)));
        (inside, _mm256_and_si256(pixel, inside), t)
    }
}

/// The closest-mode keys of 8 points from offset `o` of `batch` (o + 8 ≤ its length): a mask
/// of the lanes inside the image, their pixels (0 elsewhere) and their keys (the empty key
/// elsewhere, a no-op under min), as the portable splat computes them.
#[inline(always)]
unsafe fn closest_keys8(view: &SplatView, batch: &PointBatch<'_>, o: usize) -> (__m256i, __m256i, __m256i) {
    let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
    // SAFETY: the caller checked the CPU features (module doc) and that o + 8 ≤ the length of
    // each of the batch's slices.
    unsafe {
        let x = _mm256_loadu_ps(batch.x.as_ptr().add(o));
        let y = _mm256_loadu_ps(batch.y.as_ptr().add(o));
        let z = _mm256_loadu_ps(batch.z.as_ptr().add(o));
        let fi = _mm256_cvtepu8_epi32(_mm_loadl_epi64(batch.functions.as_ptr().add(o).cast()));
        let (inside, pixel, t) = project8(view, x, y, z);
        // d = t · scale, then the portable splat's `d > 0 ? d : 0` (maxps returns its
        // second operand on NaN, and −0 becomes +0, which truncates alike).
        let d = _mm256_max_ps(_mm256_mul_ps(t, _mm256_set1_ps(scale)), _mm256_setzero_ps());
        let key = _mm256_or_si256(_mm256_slli_epi32::<8>(_mm256_cvttps_epi32(d)), fi);
        let key = _mm256_blendv_epi8(_mm256_set1_epi32(EMPTY as i32), key, inside);
        (inside, pixel, key)
    }
}

/// The projection of 16 points with AVX-512F, [`project8`]'s operations in its order: a mask of
/// the lanes that land in the image, their pixel indices (0 elsewhere) and their depth
/// fractions t (clamped as `f32::clamp` does: a NaN stays NaN).
#[inline(always)]
unsafe fn project16(view: &SplatView, x: __m512, y: __m512, z: __m512) -> (__mmask16, __m512i, __m512) {
    let m = view.pixel_from_world;
    let (c0, c1, c2, c3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    // SAFETY: the caller checked the CPU features (module doc); no memory is accessed.
    unsafe {
        macro_rules! row {
            ($c:ident) => {
                _mm512_add_ps(
                    _mm512_add_ps(
                        _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(c0.$c), x), _mm512_mul_ps(_mm512_set1_ps(c1.$c), y)),
                        _mm512_mul_ps(_mm512_set1_ps(c2.$c), z),
                    ),
                    _mm512_set1_ps(c3.$c),
                )
            };
        }
        let (qx, qy, qz, qw) = (row!(x), row!(y), row!(z), row!(w));
        let inv_w = _mm512_div_ps(_mm512_set1_ps(1.0), qw);
        let (px, py) = (_mm512_mul_ps(qx, inv_w), _mm512_mul_ps(qy, inv_w));
        let zero = _mm512_setzero_ps();
        let inside = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(qw, zero)
            & _mm512_cmp_ps_mask::<_CMP_GE_OQ>(px, zero)
            & _mm512_cmp_ps_mask::<_CMP_GE_OQ>(py, zero)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(px, _mm512_set1_ps(view.width as f32))
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(py, _mm512_set1_ps(view.height as f32));
        let pixel = _mm512_add_epi32(
            _mm512_mullo_epi32(_mm512_cvttps_epi32(py), _mm512_set1_epi32(view.width as i32)),
            _mm512_cvttps_epi32(px),
        );
        let t =
            _mm512_mul_ps(_mm512_sub_ps(qz, _mm512_set1_ps(view.near)), _mm512_set1_ps(1.0 / (view.far - view.near)));
        let t = _mm512_mask_blend_ps(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, zero), t, zero);
        let t = _mm512_mask_blend_ps(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(t, _mm512_set1_ps(1.0)), t, _mm512_set1_ps(1.0));
        (inside, _mm512_maskz_mov_epi32(inside, pixel), t)
    }
}

/// The closest-mode keys of 16 points from offset `o` of `batch` (o + 16 ≤ its length): as
/// [`closest_keys8`] with AVX-512F, [`project16`] then the key.
#[inline(always)]
unsafe fn closest_keys16(view: &SplatView, batch: &PointBatch<'_>, o: usize) -> (__mmask16, __m512i, __m512i) {
    let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
    // SAFETY: the caller checked the CPU features (module doc) and that o + 16 ≤ the length of
    // each of the batch's slices.
    unsafe {
        let x = _mm512_loadu_ps(batch.x.as_ptr().add(o));
        let y = _mm512_loadu_ps(batch.y.as_ptr().add(o));
        let z = _mm512_loadu_ps(batch.z.as_ptr().add(o));
        let fi = _mm512_cvtepu8_epi32(_mm_loadu_si128(batch.functions.as_ptr().add(o).cast()));
        let (inside, pixel, t) = project16(view, x, y, z);
        let d = _mm512_max_ps(_mm512_mul_ps(t, _mm512_set1_ps(scale)), _mm512_setzero_ps());
        let key = _mm512_or_si512(_mm512_slli_epi32::<8>(_mm512_cvttps_epi32(d)), fi);
        let key = _mm512_mask_blend_epi32(inside, _mm512_set1_epi32(EMPTY as i32), key);
        (inside, pixel, key)
    }
}

/// Lowers `keys[pixels[l]]` to `new[l]` for each lane l set in `lanes`, one lane after the
/// other (two lanes on one pixel leave the smaller key).
#[inline(always)]
fn lower_lanes(keys: &mut [u32], pixels: &[u32], new: &[u32], mut lanes: u32) {
    while lanes != 0 {
        let l = lanes.trailing_zeros() as usize;
        lanes &= lanes - 1;
        let slot = &mut keys[pixels[l] as usize];
        *slot = (*slot).min(new[l]);
    }
}

/// The closest-mode splat, 8 points per vector.
#[target_feature(enable = "avx2")]
unsafe fn splat_closest_avx2(view: &SplatView, out: &mut impl Pixels, batch: PointBatch<'_>) {
    let n = batch.len();
    let vectors = n / LANES;
    let pixel_count = view.width as usize * view.height as usize;
    match out.own_keys().filter(|k| k.len() == pixel_count) {
        Some(keys) => {
            for g in 0..vectors {
                // SAFETY: g · 8 + 8 ≤ n, the length of each of the batch's slices. The gather
                // reads only the inside lanes (the mask), whose pixels are iy · width + ix with
                // 0 ≤ ix < width and 0 ≤ iy < height (exact truncations of the checked
                // coordinates), below width · height = keys.len() (checked above).
                unsafe {
                    let (inside, pixel, key) = closest_keys8(view, &batch, g * LANES);
                    let empty = _mm256_set1_epi32(EMPTY as i32);
                    let old = _mm256_mask_i32gather_epi32::<4>(empty, keys.as_ptr().cast(), pixel, inside);
                    // key < old (unsigned) ⇔ max(key, old) ≠ key; outside lanes compare the
                    // empty key with itself.
                    let kept = _mm256_cmpeq_epi32(_mm256_max_epu32(key, old), key);
                    let lower = !(_mm256_movemask_ps(_mm256_castsi256_ps(kept)) as u32) & 0xff;
                    if lower != 0 {
                        let (mut new, mut pixels) = ([0u32; LANES], [0u32; LANES]);
                        _mm256_storeu_si256(new.as_mut_ptr().cast(), key);
                        _mm256_storeu_si256(pixels.as_mut_ptr().cast(), pixel);
                        lower_lanes(keys, &pixels, &new, lower);
                    }
                }
            }
        }
        None => {
            for g in 0..vectors {
                let (mut keys, mut pixels) = ([0u32; LANES], [0u32; LANES]);
                // SAFETY: g · 8 + 8 ≤ n, the length of each of the batch's slices; stores into
                // local arrays.
                unsafe {
                    let (_, pixel, key) = closest_keys8(view, &batch, g * LANES);
                    _mm256_storeu_si256(keys.as_mut_ptr().cast(), key);
                    _mm256_storeu_si256(pixels.as_mut_ptr().cast(), pixel);
                }
                for l in 0..LANES {
                    // An inside lane's pixel is iy · width + ix with 0 ≤ ix < width and
                    // 0 ≤ iy < height; an outside lane's is 0, with the empty key.
                    out.min_key(pixels[l] as usize, keys[l]);
                }
            }
        }
    }
    let scale = ((1u32 << DEPTH_BITS) - 1) as f32;
    for i in vectors * LANES..n {
        if let Some((idx, t)) = view.project(batch.point(i)) {
            let d = t * scale;
            let d = if d > 0.0 { d } else { 0.0 };
            out.min_key(idx, (d as u32) << 8 | batch.functions[i] as u32);
        }
    }
}

/// The closest-mode splat with 16 points per vector: [`closest_keys16`] and the loops of
/// [`splat_closest_avx2`] with AVX-512F.
#[target_feature(enable = "avx2,avx512f")]
unsafe fn splat_closest_avx512(view: &SplatView, out: &mut impl Pixels, batch: PointBatch<'_>) {
    const WIDE: usize = 16;
    let n = batch.len();
    let vectors = n / WIDE;
    let pixel_count = view.width as usize * view.height as usize;
    match out.own_keys().filter(|k| k.len() == pixel_count) {
        Some(keys) => {
            for g in 0..vectors {
                // SAFETY: as in splat_closest_avx2: whole vectors of the batch, and the gather
                // reads only inside lanes, whose pixels are below width · height = keys.len().
                unsafe {
                    let (inside, pixel, key) = closest_keys16(view, &batch, g * WIDE);
                    let old = _mm512_mask_i32gather_epi32::<4>(
                        _mm512_set1_epi32(EMPTY as i32),
                        inside,
                        pixel,
                        keys.as_ptr().cast(),
                    );
                    let lower = _mm512_mask_cmplt_epu32_mask(inside, key, old) as u32;
                    if lower != 0 {
                        let (mut new, mut pixels) = ([0u32; WIDE], [0u32; WIDE]);
                        _mm512_storeu_si512(new.as_mut_ptr().cast(), key);
                        _mm512_storeu_si512(pixels.as_mut_ptr().cast(), pixel);
                        lower_lanes(keys, &pixels, &new, lower);
                    }
                }
            }
        }
        None => {
            for g in 0..vectors {
                let (mut keys, mut pixels) = ([0u32; WIDE], [0u32; WIDE]);
                // SAFETY: whole vectors of the batch; stores into local arrays.
                unsafe {
                    let (_, pixel, key) = closest_keys16(view, &batch, g * WIDE);
                    _mm512_storeu_si512(keys.as_mut_ptr().cast(), key);
                    _mm512_storeu_si512(pixels.as_mut_ptr().cast(), pixel);
                }
                for l in 0..WIDE {
                    out.min_key(pixels[l] as usize, keys[l]);
                }
            }
        }
    }
    let rest = vectors * WIDE;
    // SAFETY: AVX2 is enabled here too.
    unsafe {
        splat_closest_avx2(
            view,
            out,
            PointBatch {
                x: &batch.x[rest..],
                y: &batch.y[rest..],
                z: &batch.z[rest..],
                functions: &batch.functions[rest..],
            },
        )
    };
}
