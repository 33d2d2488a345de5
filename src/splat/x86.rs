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
//! - the accumulating modes with AVX-512F and AVX-512CD, into sums the target holds
//!   ([`Pixels::own_sums`]): on Intel, a vector whose lanes fall on distinct pixels gathers
//!   their sums, adds and scatters them back; on AMD each lane's sum is updated with one 16-byte
//!   load and store, a vector after its line's prefetch ([`splat_accumulate_avx512`],
//!   [`SumUpdates`]);
//! - otherwise each lane's pixel is updated by scalar code: closest keys through
//!   [`Pixels::min_key`], in the accumulating modes the portable splat's own colour arithmetic
//!   and a saturating add. Making a block of 256 updates first, their lines prefetched, and
//!   applying them after was tried and measured no faster.
//!
//! Everything here requires AVX2: [`splat`] checks the CPU before entering. Hence the
//! module-wide `unsafe_code` allowance: the intrinsics are `unsafe` to call outside a
//! `#[target_feature]` function; the memory accesses carry their own SAFETY notes.
#![expect(
    unsafe_code,
    reason = "intrinsics need unsafe outside #[target_feature] functions; callers check the CPU first"
)]

use std::arch::x86_64::*;

use super::{COLOR_SCALE, DEPTH_BITS, EMPTY, Pixels, SplatMode, SplatView, splat_portable};
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
    splat_with(view, colors, batch, out, SimdLevel::detect().avx512().then(SumUpdates::detect));
}

/// [`splat`], with the 16-wide AVX-512 splats if `wide`, adding to sums as it says (for tests).
pub(super) fn splat_with(
    view: &SplatView,
    colors: &[[f32; 3]],
    batch: PointBatch<'_>,
    out: &mut impl Pixels,
    wide: Option<SumUpdates>,
) {
    assert!(supported(view) && (wide.is_none() || SimdLevel::detect().avx512()));
    assert!(batch.x.len() == batch.len() && batch.y.len() == batch.len() && batch.z.len() == batch.len());
    // SAFETY: the CPU has AVX2 (and AVX-512F and CD if wide: `SimdLevel::Avx512`), and the view has width · height > 0
    // pixels (asserted); the batch's slices have equal lengths (asserted).
    unsafe {
        match view.mode {
            SplatMode::Closest if wide.is_some() => splat_closest_avx512(view, out, batch),
            SplatMode::Closest => splat_closest_avx2(view, out, batch),
            SplatMode::Average | SplatMode::Density => match wide {
                Some(updates) => splat_accumulate_avx512(view, colors, out, batch, updates),
                None => splat_accumulate_avx2(view, colors, out, batch),
            },
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

#[target_feature(enable = "avx2")]
unsafe fn splat_accumulate_avx2(
    view: &SplatView,
    function_colors: &[[f32; 3]],
    out: &mut impl Pixels,
    batch: PointBatch<'_>,
) {
    let view = *view;
    let n = batch.len();
    let colors: Vec<[f32; 3]> = function_colors.iter().map(|c| c.map(|x| x * COLOR_SCALE)).collect();
    let bg = view.background.map(|x| x * COLOR_SCALE);
    // Per channel, the colours as an 8-entry table by function, looked up with a permute (up
    // to 8 colours), or as a column gathered by index (more: a palette's 256 entries; the
    // index clamped to the last colour, which every valid key is within). Either way each lane
    // gets the very colour the portable splat reads, so the arithmetic below is the same.
    let vector_colors = !colors.is_empty();
    let permuted = colors.len() <= LANES;
    let table: [[f32; LANES]; 3] = std::array::from_fn(|ch| {
        std::array::from_fn(|f| colors.get(f.min(colors.len().saturating_sub(1))).map_or(0.0, |c| c[ch]))
    });
    let columns: [Vec<f32>; 3] =
        std::array::from_fn(|ch| if permuted { Vec::new() } else { colors.iter().map(|c| c[ch]).collect() });
    let last_color = colors.len().saturating_sub(1).min(255) as i32;
    let vectors = n / LANES;
    for g in 0..vectors {
        let o = g * LANES;
        let mut pixels = [0u32; LANES];
        let mut ts = [0f32; LANES];
        // Per lane: r, g, b, 1 to add (when the vector colour arithmetic applies).
        let mut adds = [[0u32; 4]; LANES];
        // SAFETY: o + 8 ≤ n, the length of each of the batch's slices; stores into local arrays.
        let (mut inside, vector) = unsafe {
            let fi = _mm256_cvtepu8_epi32(_mm_loadl_epi64(batch.functions.as_ptr().add(o).cast()));
            let (inside, pixel, t) = project8(
                &view,
                _mm256_loadu_ps(batch.x.as_ptr().add(o)),
                _mm256_loadu_ps(batch.y.as_ptr().add(o)),
                _mm256_loadu_ps(batch.z.as_ptr().add(o)),
            );
            _mm256_storeu_si256(pixels.as_mut_ptr().cast(), pixel);
            _mm256_storeu_ps(ts.as_mut_ptr(), t);
            let inside = _mm256_movemask_ps(_mm256_castsi256_ps(inside)) as u32;
            // k = depth_cue · t; per channel (c + (bg − c) · k + 0.5) as u32, the saturating
            // cast: NaN and negatives → 0 (the mask), values ≥ 2^31 (beyond the signed
            // truncation) send the group to the scalar arithmetic.
            let k = _mm256_mul_ps(_mm256_set1_ps(view.depth_cue), t);
            let mut big = 0;
            let mut channel = [_mm256_setzero_si256(); 3];
            for ch in 0..3 {
                let c = if permuted {
                    _mm256_permutevar8x32_ps(_mm256_loadu_ps(table[ch].as_ptr()), fi)
                } else {
                    // SAFETY: the indices are clamped to 0..=last_color < columns[ch].len().
                    _mm256_i32gather_ps::<4>(columns[ch].as_ptr(), _mm256_min_epi32(fi, _mm256_set1_epi32(last_color)))
                };
                let v = _mm256_add_ps(
                    _mm256_add_ps(c, _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(bg[ch]), c), k)),
                    _mm256_set1_ps(0.5),
                );
                big |= _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(v, _mm256_set1_ps(2_147_483_648.0)));
                let nonneg = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OQ>(v, _mm256_setzero_ps()));
                channel[ch] = _mm256_and_si256(_mm256_cvttps_epi32(v), nonneg);
            }
            // Transpose to r, g, b, 1 per lane: lane l in half l / 4 of vector l % 4.
            let [r, gr, b] = channel;
            let one = _mm256_set1_epi32(1);
            let (rg_lo, rg_hi) = (_mm256_unpacklo_epi32(r, gr), _mm256_unpackhi_epi32(r, gr));
            let (b1_lo, b1_hi) = (_mm256_unpacklo_epi32(b, one), _mm256_unpackhi_epi32(b, one));
            let rows = [
                _mm256_unpacklo_epi64(rg_lo, b1_lo),
                _mm256_unpackhi_epi64(rg_lo, b1_lo),
                _mm256_unpacklo_epi64(rg_hi, b1_hi),
                _mm256_unpackhi_epi64(rg_hi, b1_hi),
            ];
            for (j, row) in rows.into_iter().enumerate() {
                _mm_storeu_si128(adds[j].as_mut_ptr().cast(), _mm256_castsi256_si128(row));
                _mm_storeu_si128(adds[j + 4].as_mut_ptr().cast(), _mm256_extracti128_si256::<1>(row));
            }
            (inside, vector_colors && big == 0)
        };
        while inside != 0 {
            let l = inside.trailing_zeros() as usize;
            inside &= inside - 1;
            if vector {
                out.add(pixels[l] as usize, adds[l]);
            } else {
                // The portable splat's arithmetic for one point.
                let c = colors[batch.functions[o + l] as usize];
                let k = view.depth_cue * ts[l];
                let add = [0, 1, 2].map(|ch| (c[ch] + (bg[ch] - c[ch]) * k + 0.5) as u32);
                out.add(pixels[l] as usize, [add[0], add[1], add[2], 1]);
            }
        }
    }
    let tail = PointBatch {
        x: &batch.x[vectors * LANES..],
        y: &batch.y[vectors * LANES..],
        z: &batch.z[vectors * LANES..],
        functions: &batch.functions[vectors * LANES..],
    };
    splat_portable(&view, function_colors, tail, out);
}

/// The accumulating modes' splat with 16 points per vector (AVX-512F and AVX-512CD) for up to
/// 16 function colours (more, a palette: [`splat_accumulate_avx2`]): [`project16`], each lane's
/// colour from a 16-entry table by function (`vpermps`), the colour arithmetic of
/// [`splat_accumulate_avx2`] in its order, so the same updates. Into sums the target holds
/// ([`Pixels::own_sums`]), as `updates` says:
/// - [`SumUpdates::Scatter`]: a vector whose lanes all fall on distinct pixels (`vpconflictd`)
///   gathers its pixels' sums as two 64-bit words each, (r, g) and (b, count), adds with
///   saturation and scatters them back: sixteen read-modify-writes in flight at once, where the
///   lane-by-lane updates waited on each other's cache misses (`nlifs bench cpu`, tapering, an
///   Intel Xeon: map + average 152–157 → 199–210 M points per CPU second; 16-wide with
///   lane-by-lane updates 177–188). (Scattering such a vector's distinct lanes and then
///   applying the others one by one measured 7–14 % slower, probably as a lane's load after the
///   scatter to its pixel waits for the scatter's stores.)
/// - [`SumUpdates::Lanes`]: the lanes' (r, g, b, 1) transposed into sixteen 16-byte updates
///   ([`LaneUpdates`]), their lines prefetched, and applied one load, add and store each a
///   vector later, when the lines are in ([`LaneUpdates::apply`]); lanes on one pixel simply
///   follow each other, so no conflict test (an AMD EPYC, Zen 4, whose scatters are
///   microcoded: map + average 166–168 M points a second with `Scatter`, 244–254 with `Lanes`,
///   closest 275–281 beside them).
///
/// A vector with two lanes on one pixel under `Scatter`, and every vector into a target without
/// its own sums, is applied lane by lane through [`Pixels::add`]. The sums are saturating sums
/// of non-negative terms, which no order changes.
#[target_feature(enable = "avx2,avx512f,avx512cd")]
unsafe fn splat_accumulate_avx512(
    view: &SplatView,
    function_colors: &[[f32; 3]],
    out: &mut impl Pixels,
    batch: PointBatch<'_>,
    updates: SumUpdates,
) {
    const WIDE: usize = 16;
    if function_colors.is_empty() || function_colors.len() > WIDE {
        // SAFETY: AVX2 is enabled here too.
        return unsafe { splat_accumulate_avx2(view, function_colors, out, batch) };
    }
    let view = *view;
    let n = batch.len();
    let last = function_colors.len() - 1;
    // Entries past the last colour repeat it, as the AVX2 table does.
    let table: [[f32; WIDE]; 3] =
        std::array::from_fn(|ch| std::array::from_fn(|f| function_colors[f.min(last)][ch] * COLOR_SCALE));
    let bg = view.background.map(|x| x * COLOR_SCALE);
    let pixel_count = view.width as usize * view.height as usize;
    // The gather's qword index 2 · pixel must fit in an i32.
    let sums: Option<*mut [u32; 4]> =
        out.own_sums().filter(|s| s.len() == pixel_count && pixel_count <= 1 << 30).map(|s| s.as_mut_ptr());
    // `Lanes`: the updates of the last vectors, waiting for their lines, in a ring (`filled`
    // of them, the newest before `slot`).
    let by_lanes = updates == SumUpdates::Lanes && pixel_count <= 1 << 28;
    let mut lane_updates = [LaneUpdates::NONE; LaneUpdates::RING];
    let (mut slot, mut filled) = (0, 0);
    let vectors = n / WIDE;
    for g in 0..vectors {
        let o = g * WIDE;
        // SAFETY: o + 16 ≤ n, the length of each of the batch's slices; stores into local arrays.
        // The updates touch only inside lanes' pixels (and pixel 0), iy · width + ix with
        // 0 ≤ ix < width and 0 ≤ iy < height, below width · height, the length of the sums
        // behind `sums` (checked above), which is the target's own and which nothing else
        // touches while it is borrowed here. The gathers and scatters read and write words
        // 2 · pixel and 2 · pixel + 1 of them as u64s, which the [u32; 4] of that pixel holds
        // (alignment 8 is not required by the gather or scatter).
        unsafe {
            let fi = _mm512_cvtepu8_epi32(_mm_loadu_si128(batch.functions.as_ptr().add(o).cast()));
            let (inside, pixel, t) = project16(
                &view,
                _mm512_loadu_ps(batch.x.as_ptr().add(o)),
                _mm512_loadu_ps(batch.y.as_ptr().add(o)),
                _mm512_loadu_ps(batch.z.as_ptr().add(o)),
            );
            // k = depth_cue · t; per channel (c + (bg − c) · k + 0.5) as u32 as in the AVX2
            // splat. `as u32` saturates: the unsigned truncation gives u32::MAX at 2^32 and
            // beyond, as it does, and its NaN and negatives (below −1 they would be u32::MAX
            // too) are zeroed.
            let k = _mm512_mul_ps(_mm512_set1_ps(view.depth_cue), t);
            let channel: [__m512i; 3] = std::array::from_fn(|ch| {
                let c = _mm512_permutexvar_ps(fi, _mm512_loadu_ps(table[ch].as_ptr()));
                let v = _mm512_add_ps(
                    _mm512_add_ps(c, _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(bg[ch]), c), k)),
                    _mm512_set1_ps(0.5),
                );
                _mm512_maskz_cvttps_epu32(_mm512_cmp_ps_mask::<_CMP_GE_OQ>(v, _mm512_setzero_ps()), v)
            });
            match sums {
                Some(base) if by_lanes => {
                    let next = &mut lane_updates[slot];
                    next.fill(inside, pixel, channel);
                    next.prefetch(base);
                    slot = (slot + 1) % LaneUpdates::RING;
                    if filled == LaneUpdates::AHEAD {
                        lane_updates[slot].apply(base);
                    } else {
                        filled += 1;
                    }
                }
                Some(base) if distinct(inside, pixel) => {
                    let all = _mm512_set1_epi32(-1);
                    let lo: *mut i64 = base.cast();
                    let hi = lo.wrapping_add(1);
                    for half in 0..2 {
                        let pick = |v: __m512i| {
                            if half == 0 { _mm512_castsi512_si256(v) } else { _mm512_extracti64x4_epi64::<1>(v) }
                        };
                        let lanes = (inside >> (8 * half)) as __mmask8;
                        let index = _mm256_slli_epi32::<1>(pick(pixel));
                        let rg_add = _mm512_or_si512(
                            _mm512_cvtepu32_epi64(pick(channel[0])),
                            _mm512_slli_epi64::<32>(_mm512_cvtepu32_epi64(pick(channel[1]))),
                        );
                        let b1_add = _mm512_or_si512(
                            _mm512_cvtepu32_epi64(pick(channel[2])),
                            _mm512_slli_epi64::<32>(_mm512_set1_epi64(1)),
                        );
                        let zero = _mm512_setzero_si512();
                        let rg = _mm512_mask_i32gather_epi64::<8>(zero, lanes, index, lo.cast_const().cast());
                        let b1 = _mm512_mask_i32gather_epi64::<8>(zero, lanes, index, hi.cast_const().cast());
                        // a + min(add, !a) per u32: the saturating add of `OwnPixels::add`.
                        let rg = _mm512_add_epi32(rg, _mm512_min_epu32(rg_add, _mm512_xor_si512(rg, all)));
                        let b1 = _mm512_add_epi32(b1, _mm512_min_epu32(b1_add, _mm512_xor_si512(b1, all)));
                        _mm512_mask_i32scatter_epi64::<8>(lo.cast(), lanes, index, rg);
                        _mm512_mask_i32scatter_epi64::<8>(hi.cast(), lanes, index, b1);
                    }
                }
                _ => {
                    // Lane by lane through the target.
                    let mut updates = LaneUpdates::NONE;
                    updates.fill(inside, pixel, channel);
                    let mut pixels = [0u32; WIDE];
                    _mm512_storeu_si512(pixels.as_mut_ptr().cast(), pixel);
                    let mut lanes = u32::from(inside);
                    while lanes != 0 {
                        let l = lanes.trailing_zeros() as usize;
                        lanes &= lanes - 1;
                        let mut add = [0u32; 4];
                        _mm_storeu_si128(add.as_mut_ptr().cast(), updates.sums[LaneUpdates::slot_of_lane(l)]);
                        out.add(pixels[l] as usize, add);
                    }
                }
            }
        }
    }
    if let Some(base) = sums {
        for k in (1..=filled).rev() {
            // SAFETY: as for the updates in the loop.
            unsafe { lane_updates[(slot + LaneUpdates::RING - k) % LaneUpdates::RING].apply(base) };
        }
    }
    let tail = PointBatch {
        x: &batch.x[vectors * WIDE..],
        y: &batch.y[vectors * WIDE..],
        z: &batch.z[vectors * WIDE..],
        functions: &batch.functions[vectors * WIDE..],
    };
    splat_portable(&view, function_colors, tail, out);
}

/// Whether the lanes in `inside` fall on distinct pixels.
#[inline(always)]
unsafe fn distinct(inside: __mmask16, pixel: __m512i) -> bool {
    // SAFETY: the caller checked the CPU features (AVX-512F and CD); no memory is accessed.
    unsafe {
        let conflicts = _mm512_maskz_conflict_epi32(inside, pixel);
        _mm512_mask_test_epi32_mask(inside, conflicts, conflicts) == 0
    }
}

/// One vector's sixteen updates of [`SumUpdates::Lanes`]: sum `j` is lane 4 (j % 4) + j / 4's
/// (r, g, b, 1), (0, 0, 0, 0) for a lane outside the image, and `offsets[j]` the byte offset
/// of its pixel's sum, 16 · pixel (0 outside: adding nothing to pixel 0 leaves it as it is;
/// so the image has at most 2^28 pixels).
#[derive(Clone, Copy)]
struct LaneUpdates {
    offsets: [u32; 16],
    sums: [__m128i; 16],
}

impl LaneUpdates {
    /// Vectors between a vector's prefetch and its updates.
    const AHEAD: usize = 1;
    const RING: usize = Self::AHEAD + 1;

    /// Where lane `l`'s sum is.
    fn slot_of_lane(l: usize) -> usize {
        4 * (l % 4) + l / 4
    }
    // SAFETY: a vector of integers may hold any bits, zeros too.
    const NONE: Self = LaneUpdates { offsets: [0; 16], sums: [unsafe { std::mem::zeroed() }; 16] };

    /// The updates of a vector's lanes: those in `inside` add their `channel`s and 1 to `pixel`.
    #[inline(always)]
    unsafe fn fill(&mut self, inside: __mmask16, pixel: __m512i, channel: [__m512i; 3]) {
        // SAFETY: the caller checked the CPU features (AVX-512F); stores into `self`.
        unsafe {
            let one = _mm512_maskz_set1_epi32(inside, 1);
            let [r, g, b] = channel.map(|c| _mm512_maskz_mov_epi32(inside, c));
            let (rg_lo, rg_hi) = (_mm512_unpacklo_epi32(r, g), _mm512_unpackhi_epi32(r, g));
            let (b1_lo, b1_hi) = (_mm512_unpacklo_epi32(b, one), _mm512_unpackhi_epi32(b, one));
            // Row m's 128-bit part q is lane 4q + m's sum.
            let rows = [
                _mm512_unpacklo_epi64(rg_lo, b1_lo),
                _mm512_unpackhi_epi64(rg_lo, b1_lo),
                _mm512_unpacklo_epi64(rg_hi, b1_hi),
                _mm512_unpackhi_epi64(rg_hi, b1_hi),
            ];
            for (m, row) in rows.into_iter().enumerate() {
                _mm512_storeu_si512(self.sums.as_mut_ptr().add(4 * m).cast(), row);
            }
            let order = _mm512_setr_epi32(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15);
            let offset = _mm512_slli_epi32::<4>(_mm512_maskz_mov_epi32(inside, pixel));
            _mm512_storeu_si512(self.offsets.as_mut_ptr().cast(), _mm512_permutexvar_epi32(order, offset));
        }
    }

    /// Asks for the lines of the updates' sums.
    #[inline(always)]
    unsafe fn prefetch(&self, sums: *mut [u32; 4]) {
        for &offset in &self.offsets {
            // SAFETY: the caller guarantees every pixel is within `sums`; a prefetch reads nothing.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(sums.byte_add(offset as usize).cast_const().cast()) };
        }
    }

    /// Adds the updates to `sums` with saturation (a + min(add, !a) per u32, as
    /// `OwnPixels::add`), one after another.
    #[inline(always)]
    unsafe fn apply(&self, sums: *mut [u32; 4]) {
        // SAFETY: the caller checked the CPU features and guarantees every pixel is within
        // `sums`, which it holds exclusively; unaligned 16-byte loads and stores of one pixel.
        unsafe {
            let all = _mm_set1_epi32(-1);
            for (&offset, &add) in self.offsets.iter().zip(&self.sums) {
                let at: *mut __m128i = sums.byte_add(offset as usize).cast();
                let a = _mm_loadu_si128(at);
                _mm_storeu_si128(at, _mm_add_epi32(a, _mm_min_epu32(add, _mm_xor_si128(a, all))));
            }
        }
    }
}
