//! The lane kernel with explicit AVX2 (`std::arch`, detected at run time): eight orbits per
//! 256-bit vector, as structure of arrays. The portable lane kernel in `chaos_game.rs` stays the
//! fallback; both are bit-identical to [`CompiledIfs::map`](super::CompiledIfs::map) with the
//! same random streams, so the CPU chooses the speed and never the points.
//!
//! How one step of eight orbits goes, every operation the reference's, in its order (no FMA):
//! - the eight 32-bit PCGs advance as one vector (`vpmulld`, `vpsrlvd`);
//! - the function is the number of cumulative thresholds ≤ the 24-bit draw: one compare and
//!   one subtract per threshold (at most 7), exactly [`SelectionTable::select`];
//! - per-function values (clamp box, cell 0's start, strides) are 8-entry tables read with
//!   `vpermps` by the function index;
//! - the cell search along an axis counts the interior cell boundaries ≤ the clamped coordinate
//!   (boundaries past a function's last cell are +∞); for non-decreasing boundaries this is the
//!   reference's linear search, clamping included. Each boundary passed also switches the
//!   start and inverse width of the local coordinate and adds the axis's stride to the cell;
//! - the 24 coefficients of each lane's cell come from per-coefficient tables over the IFS's
//!   cells: one `vpermps` (≤ 8 cells), two and a blend (≤ 16), one AVX-512VL `vpermt2ps`
//!   (≤ 16, where the CPU has it), or a gather (more cells);
//! - Horner as in the scalar code.
//!
//! Everything here requires AVX2 (and `run_avx512vl` also AVX-512F/VL): the functions are
//! reached only through [`SimdKernel::run`] and the test entry points, which check the CPU
//! first. Hence the module-wide `unsafe_code` allowance: the intrinsics are `unsafe` to call
//! outside a `#[target_feature]` function; the memory accesses carry their own SAFETY notes.
#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{FastKernel, LANE_FUNCTIONS, ORBITS_PER_CHUNK, PointBatch, PointSink, SELECT_BITS, STEPS_PER_BATCH, SelectionTable};
use crate::rng::{PCG_INC, PCG_MUL, PCG_OUT_MUL};

/// Orbits per vector.
const LANES: usize = 8;
const GROUPS: usize = ORBITS_PER_CHUNK / LANES;
const _: () = assert!(ORBITS_PER_CHUNK % LANES == 0 && LANE_FUNCTIONS == LANES);
/// Most cells of one function along one axis that the kernel handles.
const MAX_AXIS_CELLS: usize = 8;
/// Coefficients per cell: a..h, xyz each.
const COEFS: usize = 24;

/// How the coefficients of each lane's cell are fetched (a const parameter of the kernel).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lookup {
    /// ≤ 8 cells: one `vpermps`.
    Permute8,
    /// ≤ 16 cells: two `vpermps` and a blend.
    Permute16,
    /// ≤ 16 cells with AVX-512VL: one `vpermt2ps`.
    Permute16Avx512,
    /// Any number of cells: `vgatherdps`.
    Gather,
}

const PERMUTE8: u8 = 0;
const PERMUTE16: u8 = 1;
const PERMUTE16_AVX512: u8 = 2;
const GATHER: u8 = 3;

impl Lookup {
    /// Whether this CPU can run the kernel with this lookup.
    pub(super) fn supported(self) -> bool {
        let avx2 = is_x86_feature_detected!("avx2");
        match self {
            Lookup::Permute16Avx512 => avx2 && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl"),
            _ => avx2,
        }
    }
}

/// Per-axis tables, each 8 entries indexed by function.
#[derive(Clone, Debug, PartialEq)]
struct SimdAxis {
    /// Interior boundaries to test: the most cells of any function along the axis, minus one.
    boundaries: usize,
    /// Boundary k: where cell k + 1 starts (+∞ past the function's last cell).
    next: [[f32; LANES]; MAX_AXIS_CELLS - 1],
    /// Start coordinate and inverse width of cell i (the last cell's past the function's).
    start: [[f32; LANES]; MAX_AXIS_CELLS],
    inv_width: [[f32; LANES]; MAX_AXIS_CELLS],
    /// Cell index step per cell along the axis.
    stride: [i32; LANES],
}

/// The lane kernel's data laid out for 8-wide vectors; see the module comment.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct SimdKernel {
    /// Inner cumulative thresholds minus one (r24 ≥ t ⇔ r24 > t − 1, a signed compare),
    /// padded with 2^24 − 1, which no 24-bit draw exceeds (a fixed count unrolls, branch-free).
    thresholds: [i32; LANES - 1],
    lo: [[f32; LANES]; 3],
    hi: [[f32; LANES]; 3],
    axes: [SimdAxis; 3],
    cell_base: [i32; LANES],
    /// Per coefficient j (3 · k + axis of coefficient k = a..h): its value in each cell, when
    /// there are at most 16 cells (padded with zeros; all zeros with more cells).
    coef_tables: Box<[[f32; 16]; COEFS]>,
    /// At most 16 cells: `coef_tables` holds them.
    small: bool,
    /// The cells' coefficients, 24 per cell (for the gather).
    cells: Vec<[f32; COEFS]>,
    /// The fastest lookup this CPU supports.
    pub(super) lookup: Lookup,
}

impl SimdKernel {
    /// The kernel for an IFS that takes the lane path (at most 8 multilinear or affine
    /// functions, global probabilities), or None when the CPU lacks AVX2 or the IFS has a
    /// function with more than [`MAX_AXIS_CELLS`] cells along an axis.
    pub(super) fn new(fast: &FastKernel, selection: &SelectionTable) -> Option<Self> {
        let n = fast.functions.len();
        if n == 0 || n > LANES || selection.cells != [1, 1, 1] || selection.thresholds.len() != n || fast.functions.iter().any(|f| f.julia) {
            return None;
        }
        if fast.cells.len() >= (i32::MAX as usize) / COEFS {
            return None;
        }
        let lane_fn = |k: usize| k.min(n - 1);
        let mut axes: [SimdAxis; 3] = std::array::from_fn(|_| SimdAxis {
            boundaries: 0,
            next: [[f32::INFINITY; LANES]; MAX_AXIS_CELLS - 1],
            start: [[0.0; LANES]; MAX_AXIS_CELLS],
            inv_width: [[0.0; LANES]; MAX_AXIS_CELLS],
            stride: [0; LANES],
        });
        for (a, axis) in axes.iter_mut().enumerate() {
            for l in 0..LANES {
                let f = &fast.functions[lane_fn(l)];
                let fa = &f.axes[a];
                let cells = fa.last_cell as usize + 1;
                if cells > MAX_AXIS_CELLS {
                    return None;
                }
                let coords = &fast.coords[fa.coord_offset as usize..=fa.coord_offset as usize + cells];
                // Counting boundaries is the linear search only if they do not decrease.
                if coords.windows(2).any(|w| !(w[0][0] <= w[1][0])) {
                    return None;
                }
                axis.boundaries = axis.boundaries.max(cells - 1);
                for i in 0..MAX_AXIS_CELLS {
                    let e = coords[i.min(cells - 1)];
                    axis.start[i][l] = e[0];
                    axis.inv_width[i][l] = e[1];
                }
                for k in 0..cells - 1 {
                    axis.next[k][l] = coords[k + 1][0];
                }
                axis.stride[l] = [f.stride_x, f.stride_y, 1][a] as i32;
            }
        }
        let per_fn = |g: &dyn Fn(&super::FastFunction) -> f32| -> [f32; LANES] { std::array::from_fn(|l| g(&fast.functions[lane_fn(l)])) };
        let cell_count = fast.cells.len();
        let lookup = if Lookup::Permute16Avx512.supported() && cell_count <= 16 {
            Lookup::Permute16Avx512
        } else if !Lookup::Permute8.supported() {
            return None;
        } else if cell_count <= 8 {
            Lookup::Permute8
        } else if cell_count <= 16 {
            Lookup::Permute16
        } else {
            Lookup::Gather
        };
        let small = cell_count <= 16;
        let coef_tables = Box::new(std::array::from_fn(|j| std::array::from_fn(|c| fast.cells.get(c).filter(|_| small).map_or(0.0, |cell| cell[j]))));
        let inner = &selection.thresholds[..n - 1];
        Some(Self {
            thresholds: std::array::from_fn(|k| inner.get(k).map_or((1 << SELECT_BITS) - 1, |&t| t as i32 - 1)),
            lo: std::array::from_fn(|a| per_fn(&|f| f.axes[a].lo)),
            hi: std::array::from_fn(|a| per_fn(&|f| f.axes[a].hi)),
            axes,
            cell_base: std::array::from_fn(|l| fast.functions[lane_fn(l)].cell_base as i32),
            coef_tables,
            small,
            cells: fast.cells.clone(),
            lookup,
        })
    }

    /// The lookups this kernel can run with on this CPU (for tests).
    #[cfg(test)]
    pub(super) fn supported_lookups(&self) -> Vec<Lookup> {
        let small = self.small;
        [Lookup::Permute8, Lookup::Permute16, Lookup::Permute16Avx512, Lookup::Gather]
            .into_iter()
            .filter(|l| l.supported())
            .filter(|l| match l {
                Lookup::Permute8 => self.cells.len() <= 8,
                Lookup::Permute16 | Lookup::Permute16Avx512 => small,
                Lookup::Gather => true,
            })
            .collect()
    }

    /// Runs the orbits of one chunk (lane k: generator `rngs[k]`, position `pos[k]`) for
    /// `transient` discarded steps and `steps` kept ones into `sink`, as `Orbits::run` does.
    pub(super) fn run(&self, lookup: Lookup, rngs: &[u32; ORBITS_PER_CHUNK], pos: &[[f32; 3]; ORBITS_PER_CHUNK], transient: u32, steps: usize, sink: &mut impl PointSink) {
        assert!(lookup.supported() && (lookup == Lookup::Gather || self.small) && (lookup != Lookup::Permute8 || self.cells.len() <= 8));
        let mut state = Lanes { rng: *rngs, x: pos.map(|p| p[0]), y: pos.map(|p| p[1]), z: pos.map(|p| p[2]) };
        // SAFETY: the CPU has the features each entry point enables (asserted above), and the
        // lookup's tables exist (asserted above).
        unsafe {
            match lookup {
                Lookup::Permute8 => run_avx2::<PERMUTE8>(self, &mut state, transient, steps, sink),
                Lookup::Permute16 => run_avx2::<PERMUTE16>(self, &mut state, transient, steps, sink),
                Lookup::Gather => run_avx2::<GATHER>(self, &mut state, transient, steps, sink),
                Lookup::Permute16Avx512 => run_avx512vl(self, &mut state, transient, steps, sink),
            }
        }
    }

    /// Maps 8 points by functions `fi` with `lookup` (for tests).
    #[cfg(test)]
    pub(super) fn map8(&self, lookup: Lookup, fi: [u32; LANES], p: [[f32; 3]; LANES]) -> [[f32; 3]; LANES] {
        assert!(self.supported_lookups().contains(&lookup));
        // SAFETY: the CPU supports the lookup and its tables exist (asserted above).
        unsafe {
            match lookup {
                Lookup::Permute8 => map8_avx2::<PERMUTE8>(self, fi, p),
                Lookup::Permute16 => map8_avx2::<PERMUTE16>(self, fi, p),
                Lookup::Gather => map8_avx2::<GATHER>(self, fi, p),
                Lookup::Permute16Avx512 => map8_avx512vl(self, fi, p),
            }
        }
    }

    /// The functions chosen by 8 random words (for tests).
    #[cfg(test)]
    pub(super) fn select8(&self, r: [u32; LANES]) -> [u32; LANES] {
        assert!(Lookup::Permute8.supported());
        // SAFETY: the CPU has AVX2 (asserted above).
        unsafe { select8_avx2(self, r) }
    }

    #[inline(always)]
    unsafe fn select(&self, r: __m256i) -> __m256i {
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
                    for ((next, next_start), next_inv_width) in axis.next[..b].iter().zip(&axis.start[1..=b]).zip(&axis.inv_width[1..=b]) {
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
                    PERMUTE16_AVX512 => {
                        let t = &self.coef_tables[j];
                        _mm256_permutex2var_ps(_mm256_loadu_ps(t.as_ptr()), cell, _mm256_loadu_ps(t[8..].as_ptr()))
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
        unsafe {
            let old = *rng;
            *rng = _mm256_add_epi32(_mm256_mullo_epi32(old, _mm256_set1_epi32(PCG_MUL as i32)), _mm256_set1_epi32(PCG_INC as i32));
            let shift = _mm256_add_epi32(_mm256_srli_epi32::<28>(old), _mm256_set1_epi32(4));
            let word = _mm256_mullo_epi32(_mm256_xor_si256(_mm256_srlv_epi32(old, shift), old), _mm256_set1_epi32(PCG_OUT_MUL as i32));
            let r = _mm256_xor_si256(_mm256_srli_epi32::<22>(word), word);
            let fi = self.select(r);
            (self.map::<L>(fi, p), fi)
        }
    }
}

/// The state of a chunk's orbits, lane-major.
struct Lanes {
    rng: [u32; ORBITS_PER_CHUNK],
    x: [f32; ORBITS_PER_CHUNK],
    y: [f32; ORBITS_PER_CHUNK],
    z: [f32; ORBITS_PER_CHUNK],
}

impl Lanes {
    /// Advances group `g` (lanes 8g..8g + 8) one step; returns its new points and functions.
    #[inline(always)]
    unsafe fn step<const L: u8>(&mut self, k: &SimdKernel, g: usize) -> ([__m256; 3], __m256i) {
        let o = g * LANES;
        // SAFETY: g < GROUPS, so lanes o..o + 8 are inside each array; unaligned loads/stores.
        unsafe {
            let mut rng = _mm256_loadu_si256(self.rng.as_ptr().add(o).cast());
            let p = [_mm256_loadu_ps(self.x.as_ptr().add(o)), _mm256_loadu_ps(self.y.as_ptr().add(o)), _mm256_loadu_ps(self.z.as_ptr().add(o))];
            let (q, fi) = k.step::<L>(&mut rng, p);
            _mm256_storeu_si256(self.rng.as_mut_ptr().add(o).cast(), rng);
            _mm256_storeu_ps(self.x.as_mut_ptr().add(o), q[0]);
            _mm256_storeu_ps(self.y.as_mut_ptr().add(o), q[1]);
            _mm256_storeu_ps(self.z.as_mut_ptr().add(o), q[2]);
            (q, fi)
        }
    }
}

#[inline(always)]
unsafe fn run_body<const L: u8>(k: &SimdKernel, lanes: &mut Lanes, transient: u32, steps: usize, sink: &mut impl PointSink) {
    const K: usize = ORBITS_PER_CHUNK;
    for _ in 0..transient {
        for g in 0..GROUPS {
            // SAFETY: as for the caller.
            unsafe { lanes.step::<L>(k, g) };
        }
    }
    let mut xs = vec![0f32; K * STEPS_PER_BATCH];
    let mut ys = vec![0f32; K * STEPS_PER_BATCH];
    let mut zs = vec![0f32; K * STEPS_PER_BATCH];
    let mut fns = vec![0u8; K * STEPS_PER_BATCH];
    let mut done = 0;
    while done < steps {
        let batch = STEPS_PER_BATCH.min(steps - done);
        for s in 0..batch {
            for g in 0..GROUPS {
                let o = s * K + g * LANES;
                // SAFETY: s < STEPS_PER_BATCH and g < GROUPS, so o + 8 ≤ K · STEPS_PER_BATCH,
                // the length of each output buffer; the intrinsics need AVX2 (the caller's).
                unsafe {
                    let (q, fi) = lanes.step::<L>(k, g);
                    _mm256_storeu_ps(xs.as_mut_ptr().add(o), q[0]);
                    _mm256_storeu_ps(ys.as_mut_ptr().add(o), q[1]);
                    _mm256_storeu_ps(zs.as_mut_ptr().add(o), q[2]);
                    // fi < 8: pack to bytes (per 128-bit half: f0..f3, f4..f7).
                    let w16 = _mm256_packus_epi32(fi, fi);
                    let w8 = _mm256_packus_epi16(w16, w16);
                    let lo = _mm256_cvtsi256_si32(w8) as u32 as u64;
                    let hi = _mm256_extract_epi32::<4>(w8) as u32 as u64;
                    fns.as_mut_ptr().add(o).cast::<u64>().write_unaligned(lo | hi << 32);
                }
            }
        }
        let n = batch * K;
        sink.consume(PointBatch { x: &xs[..n], y: &ys[..n], z: &zs[..n], functions: &fns[..n] });
        done += batch;
    }
}

#[target_feature(enable = "avx2")]
unsafe fn run_avx2<const L: u8>(k: &SimdKernel, lanes: &mut Lanes, transient: u32, steps: usize, sink: &mut impl PointSink) {
    // SAFETY: AVX2 is enabled here; the caller checked the CPU.
    unsafe { run_body::<L>(k, lanes, transient, steps, sink) }
}

#[target_feature(enable = "avx2,avx512f,avx512vl")]
unsafe fn run_avx512vl(k: &SimdKernel, lanes: &mut Lanes, transient: u32, steps: usize, sink: &mut impl PointSink) {
    // SAFETY: AVX2 and AVX-512F/VL are enabled here; the caller checked the CPU.
    unsafe { run_body::<PERMUTE16_AVX512>(k, lanes, transient, steps, sink) }
}

#[cfg(test)]
#[inline(always)]
unsafe fn map8_body<const L: u8>(k: &SimdKernel, fi: [u32; LANES], p: [[f32; 3]; LANES]) -> [[f32; 3]; LANES] {
    // SAFETY: plain array loads and stores of 8 lanes; the caller has the features.
    unsafe {
        let fi = _mm256_loadu_si256(fi.as_ptr().cast());
        let axis = |a: usize| _mm256_loadu_ps(p.map(|q| q[a]).as_ptr());
        let q = k.map::<L>(fi, [axis(0), axis(1), axis(2)]);
        let mut out = [[0f32; LANES]; 3];
        for a in 0..3 {
            _mm256_storeu_ps(out[a].as_mut_ptr(), q[a]);
        }
        std::array::from_fn(|l| [out[0][l], out[1][l], out[2][l]])
    }
}

#[cfg(test)]
#[target_feature(enable = "avx2")]
unsafe fn map8_avx2<const L: u8>(k: &SimdKernel, fi: [u32; LANES], p: [[f32; 3]; LANES]) -> [[f32; 3]; LANES] {
    unsafe { map8_body::<L>(k, fi, p) }
}

#[cfg(test)]
#[target_feature(enable = "avx2,avx512f,avx512vl")]
unsafe fn map8_avx512vl(k: &SimdKernel, fi: [u32; LANES], p: [[f32; 3]; LANES]) -> [[f32; 3]; LANES] {
    unsafe { map8_body::<PERMUTE16_AVX512>(k, fi, p) }
}

#[cfg(test)]
#[target_feature(enable = "avx2")]
unsafe fn select8_avx2(k: &SimdKernel, r: [u32; LANES]) -> [u32; LANES] {
    // SAFETY: plain array loads and stores of 8 lanes.
    unsafe {
        let fi = k.select(_mm256_loadu_si256(r.as_ptr().cast()));
        let mut out = [0u32; LANES];
        _mm256_storeu_si256(out.as_mut_ptr().cast(), fi);
        out
    }
}
