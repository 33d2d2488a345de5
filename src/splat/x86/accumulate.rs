//! The accumulating modes' vector splats (average and density): the colour arithmetic of the
//! portable splat per lane, then each point's (r, g, b, 1) added with saturation to its pixel's
//! sum, by the ways [`SumUpdates`] names.
#![expect(
    unsafe_code,
    reason = "intrinsics need unsafe outside #[target_feature] functions; callers check the CPU first"
)]

use std::arch::x86_64::*;

use super::{LANES, project8, project16};
use crate::chaos_game::PointBatch;
use crate::simd::SumUpdates;
use crate::splat::{COLOR_SCALE, Pixels, SplatView, splat_portable};

/// The accumulating modes' splat with 8 points per vector (AVX2): [`project8`], each lane's
/// colour from an 8-entry table by function (`vpermps`) or gathered from a palette's column,
/// and per channel (c + (bg − c) · k + 0.5) as u32 in the portable splat's order, so the same
/// updates. Into sums the target holds, as [`SumUpdates::Lanes`] in [`splat_accumulate_avx512`]
/// (whatever the CPU: AVX2 has no scatter; on an Intel Xeon the prefetch a vector ahead
/// measured neither faster nor slower, on a Zen 4 map + average went from 150 to 172 M points a
/// second, closest 193–200); otherwise lane by lane through [`Pixels::add`]. A vector with a
/// colour beyond a signed 32-bit truncation takes the portable arithmetic per lane.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn splat_accumulate_avx2(
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
    let pixel_count = view.width as usize * view.height as usize;
    let sums: Option<*mut [u32; 4]> =
        out.own_sums().filter(|s| s.len() == pixel_count && pixel_count <= 1 << 28).map(|s| s.as_mut_ptr());
    let mut ring = UpdateRing::<LANES>::NEW;
    let vectors = n / LANES;
    for g in 0..vectors {
        let o = g * LANES;
        // SAFETY: o + 8 ≤ n, the length of each of the batch's slices; stores into local arrays.
        // The ring's updates touch only inside lanes' pixels (and pixel 0), below width ·
        // height, the length of the target's own sums behind `sums` (checked above), which
        // nothing else touches while they are borrowed here.
        unsafe {
            let fi = _mm256_cvtepu8_epi32(_mm_loadl_epi64(batch.functions.as_ptr().add(o).cast()));
            let (inside, pixel, t) = project8(
                &view,
                _mm256_loadu_ps(batch.x.as_ptr().add(o)),
                _mm256_loadu_ps(batch.y.as_ptr().add(o)),
                _mm256_loadu_ps(batch.z.as_ptr().add(o)),
            );
            // k = depth_cue · t; per channel (c + (bg − c) · k + 0.5) as u32, the saturating
            // cast: NaN and negatives → 0 (the mask), values ≥ 2^31 (beyond the signed
            // truncation) send the vector to the scalar arithmetic.
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
            let vector = vector_colors && big == 0;
            match sums {
                Some(base) if vector => {
                    ring.next().fill8(inside, pixel, channel);
                    ring.push(base);
                }
                _ => {
                    let mut pixels = [0u32; LANES];
                    _mm256_storeu_si256(pixels.as_mut_ptr().cast(), pixel);
                    let mut lanes = _mm256_movemask_ps(_mm256_castsi256_ps(inside)) as u32;
                    if vector {
                        let mut updates = LaneUpdates::<LANES>::NONE;
                        updates.fill8(inside, pixel, channel);
                        updates.add_through(lanes, &pixels, out);
                    } else {
                        let mut ts = [0f32; LANES];
                        _mm256_storeu_ps(ts.as_mut_ptr(), t);
                        while lanes != 0 {
                            let l = lanes.trailing_zeros() as usize;
                            lanes &= lanes - 1;
                            // The portable splat's arithmetic for one point.
                            let c = colors[batch.functions[o + l] as usize];
                            let k = view.depth_cue * ts[l];
                            let add = [0, 1, 2].map(|ch| (c[ch] + (bg[ch] - c[ch]) * k + 0.5) as u32);
                            out.add(pixels[l] as usize, [add[0], add[1], add[2], 1]);
                        }
                    }
                }
            }
        }
    }
    if let Some(base) = sums {
        // SAFETY: as for the updates in the loop.
        unsafe { ring.finish(base) };
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
pub(super) unsafe fn splat_accumulate_avx512(
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
    let by_lanes = updates == SumUpdates::Lanes && pixel_count <= 1 << 28;
    let mut ring = UpdateRing::<WIDE>::NEW;
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
                    ring.next().fill16(inside, pixel, channel);
                    ring.push(base);
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
                    let mut updates = LaneUpdates::<WIDE>::NONE;
                    updates.fill16(inside, pixel, channel);
                    let mut pixels = [0u32; WIDE];
                    _mm512_storeu_si512(pixels.as_mut_ptr().cast(), pixel);
                    updates.add_through(u32::from(inside), &pixels, out);
                }
            }
        }
    }
    if by_lanes && let Some(base) = sums {
        // SAFETY: as for the updates in the loop.
        unsafe { ring.finish(base) };
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

/// One vector's updates of its pixels' sums, N lanes (8 or 16): `sums[j]` is the (r, g, b, 1)
/// of lane [`Self::lane_of`]`(j)`, (0, 0, 0, 0) for a lane outside the image, and `offsets[j]`
/// the byte offset of its pixel's sum, 16 · pixel (0 outside: adding nothing to pixel 0 leaves
/// it as it is; so the image has at most 2^28 pixels). In the transposition's order, so that
/// filling it is four vector stores.
#[derive(Clone, Copy)]
struct LaneUpdates<const N: usize> {
    offsets: [u32; N],
    sums: [__m128i; N],
}

impl<const N: usize> LaneUpdates<N> {
    const NONE: Self = {
        // SAFETY: a vector of integers may hold any bits, zeros too.
        let zero: __m128i = unsafe { std::mem::zeroed() };
        LaneUpdates { offsets: [0; N], sums: [zero; N] }
    };

    /// The lane whose update is `j`th: the transposition puts lane 4q + m in row m's 128-bit
    /// part q, and the rows are stored one after another (N / 4 parts each).
    const fn lane_of(j: usize) -> usize {
        4 * (j % (N / 4)) + j / (N / 4)
    }

    /// Adds the updates of the lanes in `inside` (bit l: lane l) to their `pixels` (by lane)
    /// through `out`'s [`Pixels::add`], for targets without their own sums.
    fn add_through(&self, inside: u32, pixels: &[u32; N], out: &mut impl Pixels) {
        for (j, &sum) in self.sums.iter().enumerate() {
            let l = Self::lane_of(j);
            if inside >> l & 1 != 0 {
                // SAFETY: an __m128i holds four u32s.
                out.add(pixels[l] as usize, unsafe { std::mem::transmute::<__m128i, [u32; 4]>(sum) });
            }
        }
    }

    /// Asks for the lines of the updates' sums.
    ///
    /// # Safety
    /// Every offset is within `sums`.
    #[inline(always)]
    unsafe fn prefetch(&self, sums: *mut [u32; 4]) {
        for &offset in &self.offsets {
            // SAFETY: the offset is within `sums` (the caller); a prefetch reads nothing.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(sums.byte_add(offset as usize).cast_const().cast()) };
        }
    }

    /// Adds the updates to `sums` with saturation (a + min(add, !a) per u32, as
    /// `OwnPixels::add`), one after another, so lanes on one pixel add up.
    ///
    /// # Safety
    /// SSE4.1; every offset is within `sums`, which the caller holds exclusively.
    #[inline(always)]
    unsafe fn apply(&self, sums: *mut [u32; 4]) {
        // SAFETY: as the caller guarantees; unaligned 16-byte loads and stores of one pixel.
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

impl LaneUpdates<16> {
    /// The updates of a vector's lanes (AVX-512F): those in `inside` add their `channel`s and 1
    /// to `pixel`.
    #[inline(always)]
    unsafe fn fill16(&mut self, inside: __mmask16, pixel: __m512i, channel: [__m512i; 3]) {
        // SAFETY: the caller checked the CPU features; stores into `self`.
        unsafe {
            let one = _mm512_maskz_set1_epi32(inside, 1);
            let [r, g, b] = channel.map(|c| _mm512_maskz_mov_epi32(inside, c));
            let (rg_lo, rg_hi) = (_mm512_unpacklo_epi32(r, g), _mm512_unpackhi_epi32(r, g));
            let (b1_lo, b1_hi) = (_mm512_unpacklo_epi32(b, one), _mm512_unpackhi_epi32(b, one));
            let rows = [
                _mm512_unpacklo_epi64(rg_lo, b1_lo),
                _mm512_unpackhi_epi64(rg_lo, b1_lo),
                _mm512_unpacklo_epi64(rg_hi, b1_hi),
                _mm512_unpackhi_epi64(rg_hi, b1_hi),
            ];
            for (m, row) in rows.into_iter().enumerate() {
                _mm512_storeu_si512(self.sums.as_mut_ptr().add(4 * m).cast(), row);
            }
            let order: [i32; 16] = std::array::from_fn(|j| Self::lane_of(j) as i32);
            let offset = _mm512_slli_epi32::<4>(_mm512_maskz_mov_epi32(inside, pixel));
            _mm512_storeu_si512(
                self.offsets.as_mut_ptr().cast(),
                _mm512_permutexvar_epi32(_mm512_loadu_si512(order.as_ptr().cast()), offset),
            );
        }
    }
}

impl LaneUpdates<8> {
    /// The updates of a vector's lanes (AVX2): those in `inside` (all bits set) add their
    /// `channel`s and 1 to `pixel`.
    #[inline(always)]
    unsafe fn fill8(&mut self, inside: __m256i, pixel: __m256i, channel: [__m256i; 3]) {
        // SAFETY: the caller checked the CPU features; stores into `self`.
        unsafe {
            let one = _mm256_and_si256(inside, _mm256_set1_epi32(1));
            let [r, g, b] = channel.map(|c| _mm256_and_si256(inside, c));
            let (rg_lo, rg_hi) = (_mm256_unpacklo_epi32(r, g), _mm256_unpackhi_epi32(r, g));
            let (b1_lo, b1_hi) = (_mm256_unpacklo_epi32(b, one), _mm256_unpackhi_epi32(b, one));
            let rows = [
                _mm256_unpacklo_epi64(rg_lo, b1_lo),
                _mm256_unpackhi_epi64(rg_lo, b1_lo),
                _mm256_unpacklo_epi64(rg_hi, b1_hi),
                _mm256_unpackhi_epi64(rg_hi, b1_hi),
            ];
            for (m, row) in rows.into_iter().enumerate() {
                _mm256_storeu_si256(self.sums.as_mut_ptr().add(2 * m).cast(), row);
            }
            let order: [i32; 8] = std::array::from_fn(|j| Self::lane_of(j) as i32);
            let offset = _mm256_slli_epi32::<4>(_mm256_and_si256(inside, pixel));
            _mm256_storeu_si256(
                self.offsets.as_mut_ptr().cast(),
                _mm256_permutevar8x32_epi32(offset, _mm256_loadu_si256(order.as_ptr().cast())),
            );
        }
    }
}

/// [`SumUpdates::Lanes`]'s updates of the last two vectors: the newer's lines are being
/// fetched while the older's updates are applied. (Three vectors ahead measured slower on a
/// Zen 4: map + average 218–225 against 226–238 M points a second.)
struct UpdateRing<const N: usize> {
    ring: [LaneUpdates<N>; 2],
    /// The updates to fill next.
    slot: usize,
    /// Whether the other slot holds updates not yet applied.
    waiting: bool,
}

impl<const N: usize> UpdateRing<N> {
    const NEW: Self = UpdateRing { ring: [LaneUpdates::NONE; 2], slot: 0, waiting: false };

    /// The updates to fill next; [`Self::push`] when they are filled.
    fn next(&mut self) -> &mut LaneUpdates<N> {
        &mut self.ring[self.slot]
    }

    /// Prefetches the lines of the updates just filled, and applies the ones before them.
    ///
    /// # Safety
    /// As for [`LaneUpdates::apply`], for every push with these `sums`.
    #[inline(always)]
    unsafe fn push(&mut self, sums: *mut [u32; 4]) {
        // SAFETY: as the caller guarantees.
        unsafe {
            self.ring[self.slot].prefetch(sums);
            self.slot ^= 1;
            if self.waiting {
                self.ring[self.slot].apply(sums);
            }
        }
        self.waiting = true;
    }

    /// Applies the updates still waiting.
    ///
    /// # Safety
    /// As for [`Self::push`].
    #[inline(always)]
    unsafe fn finish(&mut self, sums: *mut [u32; 4]) {
        if self.waiting {
            // SAFETY: as the caller guarantees.
            unsafe { self.ring[self.slot ^ 1].apply(sums) };
            self.waiting = false;
        }
    }
}
