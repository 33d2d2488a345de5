//! The vector kernels themselves: one step of eight orbits with AVX2 and of sixteen with
//! AVX-512F, twins kept side by side (see the parent module for how a step goes), the chunk
//! loop that runs them, and the entry points the parent's [`SimdKernel`] dispatches to.

use std::arch::x86_64::*;

use super::super::{ORBITS_PER_CHUNK, PointBatch, PointSink, SELECT_BITS, STEPS_PER_BATCH};
use super::{COEFS, LANES, PERMUTE8, PERMUTE16, SimdKernel, WIDE};
use crate::rng::{PCG_INC, PCG_MUL, PCG_OUT_MUL};

impl SimdKernel {
    #[inline(always)]
    unsafe fn select(&self, r: __m256i) -> __m256i {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            let r24 = _mm256_srli_epi32::<{ (32 - SELECT_BITS) as i32 }>(r);
            let mut fi = _mm256_setzero_si256();
            for &t in &self.thresholds {
                fi = _mm256_sub_epi32(fi, _mm256_cmpgt_epi32(r24, _mm256_set1_epi32(t)));
            }
            fi
        }
    }

    /// The map of 8 points by functions `fi` (each < the function count).
    #[inline(always)]
    unsafe fn map<const L: u8>(&self, fi: __m256i, p: [__m256; 3]) -> [__m256; 3] {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            // Closures would not inherit the caller's target features: a small macro instead.
            macro_rules! by_fn {
                ($table:expr) => {
                    _mm256_permutevar8x32_ps(_mm256_loadu_ps($table.as_ptr()), fi)
                };
            }
            let mut cell = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(self.cell_base.as_ptr().cast()), fi);
            let mut local = [_mm256_setzero_ps(); 3];
            for a in 0..3 {
                let axis = &self.axes[a];
                // x > lo ? x : lo, then x < hi ? x : hi (NaN goes to lo), as the lane kernel.
                let q = _mm256_min_ps(_mm256_max_ps(p[a], by_fn!(&self.lo[a])), by_fn!(&self.hi[a]));
                let mut start = by_fn!(&axis.start[0]);
                let mut inv_width = by_fn!(&axis.inv_width[0]);
                if axis.boundaries > 0 {
                    let stride = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(axis.stride.as_ptr().cast()), fi);
                    let b = axis.boundaries;
                    for ((next, next_start), next_inv_width) in
                        axis.next[..b].iter().zip(&axis.start[1..=b]).zip(&axis.inv_width[1..=b])
                    {
                        let passed = _mm256_cmp_ps::<_CMP_GE_OQ>(q, by_fn!(next));
                        start = _mm256_blendv_ps(start, by_fn!(next_start), passed);
                        inv_width = _mm256_blendv_ps(inv_width, by_fn!(next_inv_width), passed);
                        cell = _mm256_add_epi32(cell, _mm256_and_si256(_mm256_castps_si256(passed), stride));
                    }
                }
                local[a] = _mm256_mul_ps(_mm256_sub_ps(q, start), inv_width);
            }
            let [u, v, w] = local;
            // Bit 3 of the cell index as the sign, for the blend of the 16-entry lookup.
            let upper = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(cell));
            let cell_coefs = _mm256_mullo_epi32(cell, _mm256_set1_epi32(COEFS as i32));
            macro_rules! coef {
                ($j:expr) => {
                    self.coef::<L>($j, cell, upper, cell_coefs)
                };
            }
            let mut out = [_mm256_setzero_ps(); 3];
            for (i, out) in out.iter_mut().enumerate() {
                // a + u b + v (c + u e) + w (d + u f + v (g + u h)), as CompiledIfs::map.
                let inner = _mm256_add_ps(
                    _mm256_add_ps(coef!(9 + i), _mm256_mul_ps(u, coef!(15 + i))),
                    _mm256_mul_ps(v, _mm256_add_ps(coef!(18 + i), _mm256_mul_ps(u, coef!(21 + i)))),
                );
                let outer = _mm256_add_ps(
                    _mm256_add_ps(coef!(i), _mm256_mul_ps(u, coef!(3 + i))),
                    _mm256_mul_ps(v, _mm256_add_ps(coef!(6 + i), _mm256_mul_ps(u, coef!(12 + i)))),
                );
                *out = _mm256_add_ps(outer, _mm256_mul_ps(w, inner));
            }
            out
        }
    }

    /// Coefficient j of each lane's cell (see [`Lookup`]); `upper` has bit 3 of the cell
    /// index as its sign, `cell_coefs` is cell · 24.
    #[inline(always)]
    unsafe fn coef<const L: u8>(&self, j: usize, cell: __m256i, upper: __m256, cell_coefs: __m256i) -> __m256 {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            {
                match L {
                    PERMUTE8 => _mm256_permutevar8x32_ps(_mm256_loadu_ps(self.coef_tables[j].as_ptr()), cell),
                    PERMUTE16 => {
                        let t = &self.coef_tables[j];
                        let lo = _mm256_permutevar8x32_ps(_mm256_loadu_ps(t.as_ptr()), cell);
                        let hi = _mm256_permutevar8x32_ps(_mm256_loadu_ps(t[8..].as_ptr()), cell);
                        _mm256_blendv_ps(lo, hi, upper)
                    }
                    // SAFETY: every lane's cell is one of its function's cells (the boundary
                    // count stays below the function's cell count along each axis, because
                    // the clamped coordinate is finite and the padding boundaries are +∞;
                    // FastKernel::new checked base + cell count ≤ cells), so the offset
                    // cell · 24 + j < 24 · cells.len() stays inside `cells`.
                    _ => _mm256_i32gather_ps::<4>(self.cells.as_ptr().cast::<f32>().add(j), cell_coefs),
                }
            }
        }
    }

    /// One chaos-game step of 8 orbits: advance the generators, select, map.
    #[inline(always)]
    unsafe fn step<const L: u8>(&self, rng: &mut __m256i, p: [__m256; 3]) -> ([__m256; 3], __m256i) {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            let old = *rng;
            *rng = _mm256_add_epi32(
                _mm256_mullo_epi32(old, _mm256_set1_epi32(PCG_MUL as i32)),
                _mm256_set1_epi32(PCG_INC as i32),
            );
            let shift = _mm256_add_epi32(_mm256_srli_epi32::<28>(old), _mm256_set1_epi32(4));
            let word = _mm256_mullo_epi32(
                _mm256_xor_si256(_mm256_srlv_epi32(old, shift), old),
                _mm256_set1_epi32(PCG_OUT_MUL as i32),
            );
            let r = _mm256_xor_si256(_mm256_srli_epi32::<22>(word), word);
            let fi = self.select(r);
            (self.map::<L>(fi, p), fi)
        }
    }

    /// [`Self::select`], 16 lanes.
    #[inline(always)]
    unsafe fn select16(&self, r: __m512i) -> __m512i {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            let r24 = _mm512_srli_epi32::<{ 32 - SELECT_BITS }>(r);
            let mut fi = _mm512_setzero_si512();
            for &t in &self.thresholds {
                let passed = _mm512_cmpgt_epi32_mask(r24, _mm512_set1_epi32(t));
                fi = _mm512_mask_add_epi32(fi, passed, fi, _mm512_set1_epi32(1));
            }
            fi
        }
    }

    /// [`Self::map`], 16 lanes; `L` is PERMUTE16 or GATHER.
    #[inline(always)]
    unsafe fn map16<const L: u8>(&self, fi: __m512i, p: [__m512; 3]) -> [__m512; 3] {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            macro_rules! by_fn {
                ($table:expr) => {
                    _mm512_permutexvar_ps(fi, _mm512_loadu_ps($table.as_ptr()))
                };
            }
            let mut cell = _mm512_permutexvar_epi32(fi, _mm512_loadu_si512(self.cell_base.as_ptr().cast()));
            let mut local = [_mm512_setzero_ps(); 3];
            for a in 0..3 {
                let axis = &self.axes[a];
                // vmaxps / vminps as in the 8-wide map: NaN goes to lo.
                let q = _mm512_min_ps(_mm512_max_ps(p[a], by_fn!(&self.lo[a])), by_fn!(&self.hi[a]));
                let mut start = by_fn!(&axis.start[0]);
                let mut inv_width = by_fn!(&axis.inv_width[0]);
                if axis.boundaries > 0 {
                    let stride = _mm512_permutexvar_epi32(fi, _mm512_loadu_si512(axis.stride.as_ptr().cast()));
                    let b = axis.boundaries;
                    for ((next, next_start), next_inv_width) in
                        axis.next[..b].iter().zip(&axis.start[1..=b]).zip(&axis.inv_width[1..=b])
                    {
                        let passed = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(q, by_fn!(next));
                        start = _mm512_mask_permutexvar_ps(start, passed, fi, _mm512_loadu_ps(next_start.as_ptr()));
                        inv_width =
                            _mm512_mask_permutexvar_ps(inv_width, passed, fi, _mm512_loadu_ps(next_inv_width.as_ptr()));
                        cell = _mm512_mask_add_epi32(cell, passed, cell, stride);
                    }
                }
                local[a] = _mm512_mul_ps(_mm512_sub_ps(q, start), inv_width);
            }
            let [u, v, w] = local;
            let cell_coefs = _mm512_mullo_epi32(cell, _mm512_set1_epi32(COEFS as i32));
            macro_rules! coef {
                ($j:expr) => {
                    match L {
                        PERMUTE16 => _mm512_permutexvar_ps(cell, _mm512_loadu_ps(self.coef_tables[$j].as_ptr())),
                        // SAFETY: as in `coef`: cell · 24 + j < 24 · cells.len().
                        _ => _mm512_i32gather_ps::<4>(cell_coefs, self.cells.as_ptr().cast::<f32>().add($j)),
                    }
                };
            }
            let mut out = [_mm512_setzero_ps(); 3];
            for (i, out) in out.iter_mut().enumerate() {
                let inner = _mm512_add_ps(
                    _mm512_add_ps(coef!(9 + i), _mm512_mul_ps(u, coef!(15 + i))),
                    _mm512_mul_ps(v, _mm512_add_ps(coef!(18 + i), _mm512_mul_ps(u, coef!(21 + i)))),
                );
                let outer = _mm512_add_ps(
                    _mm512_add_ps(coef!(i), _mm512_mul_ps(u, coef!(3 + i))),
                    _mm512_mul_ps(v, _mm512_add_ps(coef!(6 + i), _mm512_mul_ps(u, coef!(12 + i)))),
                );
                *out = _mm512_add_ps(outer, _mm512_mul_ps(w, inner));
            }
            out
        }
    }

    /// [`Self::step`], 16 lanes.
    #[inline(always)]
    unsafe fn step16<const L: u8>(&self, rng: &mut __m512i, p: [__m512; 3]) -> ([__m512; 3], __m512i) {
        // SAFETY: the caller checked the CPU features (module doc); memory accesses carry their own notes.
        unsafe {
            let old = *rng;
            *rng = _mm512_add_epi32(
                _mm512_mullo_epi32(old, _mm512_set1_epi32(PCG_MUL as i32)),
                _mm512_set1_epi32(PCG_INC as i32),
            );
            let shift = _mm512_add_epi32(_mm512_srli_epi32::<28>(old), _mm512_set1_epi32(4));
            let word = _mm512_mullo_epi32(
                _mm512_xor_si512(_mm512_srlv_epi32(old, shift), old),
                _mm512_set1_epi32(PCG_OUT_MUL as i32),
            );
            let r = _mm512_xor_si512(_mm512_srli_epi32::<22>(word), word);
            let fi = self.select16(r);
            (self.map16::<L>(fi, p), fi)
        }
    }
}

/// The state of a chunk's orbits, lane-major.
pub(super) struct Lanes {
    pub(super) rng: [u32; ORBITS_PER_CHUNK],
    pub(super) x: [f32; ORBITS_PER_CHUNK],
    pub(super) y: [f32; ORBITS_PER_CHUNK],
    pub(super) z: [f32; ORBITS_PER_CHUNK],
}

/// Output buffers of one batch: STEPS_PER_BATCH rows of ORBITS_PER_CHUNK points.
struct Batch {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    functions: Vec<u8>,
}

impl Batch {
    fn new() -> Self {
        let n = ORBITS_PER_CHUNK * STEPS_PER_BATCH;
        Self { x: vec![0.0; n], y: vec![0.0; n], z: vec![0.0; n], functions: vec![0; n] }
    }

    fn consume(&self, rows: usize, sink: &mut impl PointSink) {
        let n = rows * ORBITS_PER_CHUNK;
        sink.consume(PointBatch { x: &self.x[..n], y: &self.y[..n], z: &self.z[..n], functions: &self.functions[..n] });
    }
}

/// The chunk loop of either width, as `Orbits::run`: `$step` advances vector `$g` of the
/// lanes and writes its points at the output offset in `$out`, if any. A macro, not a
/// function taking a closure, so that the step is inlined into the `#[target_feature]`
/// function that expands it.
macro_rules! run_chunk_loop {
    ($groups:expr, $transient:expr, $steps:expr, $sink:expr, |$g:ident, $out:ident| $step:expr) => {{
        for _ in 0..$transient {
            for $g in 0..$groups {
                let $out: Option<(&mut Batch, usize)> = None;
                $step;
            }
        }
        let mut batch = Batch::new();
        let mut done = 0;
        while done < $steps {
            let rows = STEPS_PER_BATCH.min($steps - done);
            for s in 0..rows {
                for $g in 0..$groups {
                    let $out = Some((&mut batch, s * ORBITS_PER_CHUNK));
                    $step;
                }
            }
            batch.consume(rows, $sink);
            done += rows;
        }
    }};
}

#[target_feature(enable = "avx2")]
pub(super) unsafe fn run_avx2<const L: u8>(
    k: &SimdKernel,
    lanes: &mut Lanes,
    transient: u32,
    steps: usize,
    sink: &mut impl PointSink,
) {
    // SAFETY: AVX2 is enabled here; g < ORBITS_PER_CHUNK / 8 and the offsets are rows.
    run_chunk_loop!(ORBITS_PER_CHUNK / LANES, transient, steps, sink, |g, out| unsafe {
        group_avx2::<L>(k, lanes, g, out)
    })
}

#[target_feature(enable = "avx2,avx512f")]
pub(super) unsafe fn run_avx512<const L: u8>(
    k: &SimdKernel,
    lanes: &mut Lanes,
    transient: u32,
    steps: usize,
    sink: &mut impl PointSink,
) {
    // SAFETY: AVX-512F is enabled here; g < ORBITS_PER_CHUNK / 16 and the offsets are rows.
    run_chunk_loop!(ORBITS_PER_CHUNK / WIDE, transient, steps, sink, |g, out| unsafe {
        group_avx512::<L>(k, lanes, g, out)
    })
}

/// Advances lanes 8g..8g + 8 one step; writes their points at offset `row` of `out`, if any.
/// Requires AVX2, g < ORBITS_PER_CHUNK / 8 and row a multiple of ORBITS_PER_CHUNK below
/// ORBITS_PER_CHUNK · STEPS_PER_BATCH.
#[inline(always)]
unsafe fn group_avx2<const L: u8>(k: &SimdKernel, lanes: &mut Lanes, g: usize, out: Option<(&mut Batch, usize)>) {
    let o = g * LANES;
    // SAFETY: lanes o..o + 8 are inside each lane array, and row + o + 8 ≤ ORBITS_PER_CHUNK ·
    // STEPS_PER_BATCH, the length of each output buffer (the caller's bounds on g and row).
    unsafe {
        let mut rng = _mm256_loadu_si256(lanes.rng.as_ptr().add(o).cast());
        let p = [
            _mm256_loadu_ps(lanes.x.as_ptr().add(o)),
            _mm256_loadu_ps(lanes.y.as_ptr().add(o)),
            _mm256_loadu_ps(lanes.z.as_ptr().add(o)),
        ];
        let (q, fi) = k.step::<L>(&mut rng, p);
        _mm256_storeu_si256(lanes.rng.as_mut_ptr().add(o).cast(), rng);
        _mm256_storeu_ps(lanes.x.as_mut_ptr().add(o), q[0]);
        _mm256_storeu_ps(lanes.y.as_mut_ptr().add(o), q[1]);
        _mm256_storeu_ps(lanes.z.as_mut_ptr().add(o), q[2]);
        if let Some((out, row)) = out {
            let o = row + o;
            _mm256_storeu_ps(out.x.as_mut_ptr().add(o), q[0]);
            _mm256_storeu_ps(out.y.as_mut_ptr().add(o), q[1]);
            _mm256_storeu_ps(out.z.as_mut_ptr().add(o), q[2]);
            // fi < 8: pack to bytes (per 128-bit half: f0..f3, f4..f7).
            let w16 = _mm256_packus_epi32(fi, fi);
            let w8 = _mm256_packus_epi16(w16, w16);
            let lo = _mm256_cvtsi256_si32(w8) as u32 as u64;
            let hi = _mm256_extract_epi32::<4>(w8) as u32 as u64;
            out.functions.as_mut_ptr().add(o).cast::<u64>().write_unaligned(lo | hi << 32);
        }
    }
}

/// [`group_avx2`] for lanes 16g..16g + 16; requires AVX-512F and g < ORBITS_PER_CHUNK / 16.
#[inline(always)]
unsafe fn group_avx512<const L: u8>(k: &SimdKernel, lanes: &mut Lanes, g: usize, out: Option<(&mut Batch, usize)>) {
    let o = g * WIDE;
    // SAFETY: as in group_avx2, with 16 lanes.
    unsafe {
        let mut rng = _mm512_loadu_si512(lanes.rng.as_ptr().add(o).cast());
        let p = [
            _mm512_loadu_ps(lanes.x.as_ptr().add(o)),
            _mm512_loadu_ps(lanes.y.as_ptr().add(o)),
            _mm512_loadu_ps(lanes.z.as_ptr().add(o)),
        ];
        let (q, fi) = k.step16::<L>(&mut rng, p);
        _mm512_storeu_si512(lanes.rng.as_mut_ptr().add(o).cast(), rng);
        _mm512_storeu_ps(lanes.x.as_mut_ptr().add(o), q[0]);
        _mm512_storeu_ps(lanes.y.as_mut_ptr().add(o), q[1]);
        _mm512_storeu_ps(lanes.z.as_mut_ptr().add(o), q[2]);
        if let Some((out, row)) = out {
            let o = row + o;
            _mm512_storeu_ps(out.x.as_mut_ptr().add(o), q[0]);
            _mm512_storeu_ps(out.y.as_mut_ptr().add(o), q[1]);
            _mm512_storeu_ps(out.z.as_mut_ptr().add(o), q[2]);
            _mm_storeu_si128(out.functions.as_mut_ptr().add(o).cast(), _mm512_cvtepi32_epi8(fi));
        }
    }
}

#[cfg(test)]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn map_points_avx2<const L: u8>(k: &SimdKernel, fi: &[u32], p: &[[f32; 3]], out: &mut [[f32; 3]]) {
    for ((fi, p), out) in fi.chunks_exact(LANES).zip(p.chunks_exact(LANES)).zip(out.chunks_exact_mut(LANES)) {
        let axis = |a: usize| -> [f32; LANES] { std::array::from_fn(|l| p[l][a]) };
        let mut q = [[0f32; LANES]; 3];
        // SAFETY: loads and stores of whole 8-lane arrays.
        unsafe {
            let fi = _mm256_loadu_si256(fi.as_ptr().cast());
            let r = k.map::<L>(
                fi,
                [
                    _mm256_loadu_ps(axis(0).as_ptr()),
                    _mm256_loadu_ps(axis(1).as_ptr()),
                    _mm256_loadu_ps(axis(2).as_ptr()),
                ],
            );
            for a in 0..3 {
                _mm256_storeu_ps(q[a].as_mut_ptr(), r[a]);
            }
        }
        for (l, out) in out.iter_mut().enumerate() {
            *out = [q[0][l], q[1][l], q[2][l]];
        }
    }
}

#[cfg(test)]
#[target_feature(enable = "avx2,avx512f")]
pub(super) unsafe fn map_points_avx512<const L: u8>(k: &SimdKernel, fi: &[u32], p: &[[f32; 3]], out: &mut [[f32; 3]]) {
    for ((fi, p), out) in fi.chunks_exact(WIDE).zip(p.chunks_exact(WIDE)).zip(out.chunks_exact_mut(WIDE)) {
        let axis = |a: usize| -> [f32; WIDE] { std::array::from_fn(|l| p[l][a]) };
        let mut q = [[0f32; WIDE]; 3];
        // SAFETY: loads and stores of whole 16-lane arrays.
        unsafe {
            let fi = _mm512_loadu_si512(fi.as_ptr().cast());
            let r = k.map16::<L>(
                fi,
                [
                    _mm512_loadu_ps(axis(0).as_ptr()),
                    _mm512_loadu_ps(axis(1).as_ptr()),
                    _mm512_loadu_ps(axis(2).as_ptr()),
                ],
            );
            for a in 0..3 {
                _mm512_storeu_ps(q[a].as_mut_ptr(), r[a]);
            }
        }
        for (l, out) in out.iter_mut().enumerate() {
            *out = [q[0][l], q[1][l], q[2][l]];
        }
    }
}

#[cfg(test)]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn select_points_avx2(k: &SimdKernel, r: &[u32]) -> Vec<u32> {
    let mut out = vec![0u32; r.len()];
    for (r, out) in r.chunks_exact(LANES).zip(out.chunks_exact_mut(LANES)) {
        // SAFETY: loads and stores of whole 8-lane chunks.
        unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), k.select(_mm256_loadu_si256(r.as_ptr().cast()))) };
    }
    out
}

#[cfg(test)]
#[target_feature(enable = "avx2,avx512f")]
pub(super) unsafe fn select_points_avx512(k: &SimdKernel, r: &[u32]) -> Vec<u32> {
    let mut out = vec![0u32; r.len()];
    for (r, out) in r.chunks_exact(WIDE).zip(out.chunks_exact_mut(WIDE)) {
        // SAFETY: loads and stores of whole 16-lane chunks.
        unsafe { _mm512_storeu_si512(out.as_mut_ptr().cast(), k.select16(_mm512_loadu_si512(r.as_ptr().cast()))) };
    }
    out
}
