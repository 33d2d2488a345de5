//! The chaos game (the paper's stochastic algorithm, figure 7), CPU reference. The GPU twin is
//! This file is longer than 700 lines because its split by concept (tables, kernel, bounds, sinks) has not landed yet; it is the next structural step.
//! `shaders/chaos_game.wgsl` with the same data layout ([`KernelFunction`], the coordinate and
//! cell pools, the selection table) and the same loop shape.
//!
//! The IFS is compiled into a flat form for speed: every grid cell stores the coefficients of
//! its trilinear interpolant in local coordinates, p = a + u·b + v·c + w·d + uv·e + uw·f +
//! vw·g + uvw·h, evaluated in Horner form. An affine map is one unbounded cell with only a, b, c, d.
//! A 2D map has a single cell along z whose local coordinate is always 0.
//!
//! Work is split into chunks of [`ORBITS_PER_CHUNK`] orbits advanced together (independent
//! orbits give the CPU instruction-level parallelism); orbit `k` of chunk `c` is chain
//! `c · ORBITS_PER_CHUNK + k` and draws from the random stream (seed, frame, chain), as chain i
//! of the GPU does, so the points are a pure function of (IFS, seed, frame, count) whatever the
//! number of threads (the split is a [`ChunkPlan`]). Each orbit starts at a random point of the domain and its first
//! `transient` points are discarded.
//!
//! Three implementations of one step, bit-identical per point: [`CompiledIfs::map`] (the
//! reference the GPU mirrors, linear cell search), [`CompiledIfs::map_fast`] (cell search by
//! bins; any IFS), and the private lane kernel (the common case: few multilinear or affine
//! functions with global probabilities; bucketed selection, 4-wide arithmetic, and a variant
//! per set of axes that have more than one cell). On x86-64 CPUs with AVX2 (detected at run
//! time) the lane kernel's case runs eight orbits per vector instead, sixteen with AVX-512F
//! (`chaos_game/x86.rs`), again bit-identical. Measurements: docs/performance.md.

use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;

use crate::model::{Ifs, Map, ProbabilityMode};
use crate::rng::Pcg32;

pub mod plan;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use plan::{ChunkPlan, PlanError};

/// Orbits advanced together in one chunk.
pub const ORBITS_PER_CHUNK: usize = 64;
/// Steps mapped into the batch buffer before it is handed to the sink.
pub const STEPS_PER_BATCH: usize = 16;
/// Default steps per orbit in a chunk (after the transient).
pub const STEPS_PER_ORBIT: usize = 4096;
/// Random numbers are 24-bit for function selection: thresholds are in units of 2^-24.
pub const SELECT_BITS: u32 = 24;
/// Coarse cells per axis of the adaptive selection table.
pub const ADAPTIVE_CELLS_3D: u32 = 12;
pub const ADAPTIVE_CELLS_2D: u32 = 48;

pub const KIND_MULTILINEAR: u32 = 0;
pub const KIND_JULIA: u32 = 1;

/// Bounds used for unbounded (affine) maps.
const UNBOUNDED: f32 = 3.0e38;

/// One function of the compiled IFS. Mirrors `struct KernelFunction` in
/// `shaders/chaos_game.wgsl`: keep the two in sync.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct KernelFunction {
    /// Clamp box (xyz); w: unused.
    pub lo: [f32; 4],
    pub hi: [f32; 4],
    /// Bins per unit length per axis for the first guess of the cell (0 on a one-cell axis).
    pub inv_bin: [f32; 4],
    /// Cells per axis (xyz); w: offset of the first cell in the cell pool.
    pub cells: [u32; 4],
    /// Offset of each axis in the coordinate pool (xyz); w: the kind.
    pub coord_offset: [u32; 4],
    /// Julia: c.re, c.im, sign; w: unused.
    pub julia: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<KernelFunction>() == 96);

/// Per-cell interpolant coefficients a..h (xyz in each; w unused). Mirrors `struct Cell`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Cell {
    pub coef: [[f32; 4]; 8],
}
const _: () = assert!(std::mem::size_of::<Cell>() == 128);

/// The compiled IFS: what the CPU kernel reads and what is uploaded to the GPU.
#[derive(Clone, Debug, PartialEq)]
pub struct CompiledIfs {
    pub dimension: usize,
    pub functions: Vec<KernelFunction>,
    /// Per axis entry: (coordinate, 1 / width of the cell starting there); one extra entry
    /// closes each axis.
    pub coords: Vec<[f32; 2]>,
    pub cells: Vec<Cell>,
    /// Function-selection table, see [`SelectionTable`].
    pub selection: SelectionTable,
    /// Linear RGB per function (for the splat).
    pub colors: Vec<[f32; 3]>,
    /// Index into the IFS's functions of each compiled function (only enabled ones compile).
    pub source_index: Vec<usize>,
    pub domain_lo: Vec3,
    pub domain_hi: Vec3,
    /// Discarded points per orbit: enough for the worst contraction to shrink the domain
    /// below 1e-5 of its size.
    pub transient: u32,
    /// The CPU's packed copy of the kernel, see [`FastKernel`].
    fast: FastKernel,
    /// The CPU's fastest path, when the IFS allows it, see [`LaneKernel`].
    lanes: Option<LaneKernel>,
    /// The lane kernel's case as 8-wide AVX2 or 16-wide AVX-512F vectors, when the CPU has
    /// them (see `chaos_game/x86.rs`).
    #[cfg(target_arch = "x86_64")]
    simd: Option<x86::SimdKernel>,
}

/// Most functions the lane kernel handles.
const LANE_FUNCTIONS: usize = 8;
/// Buckets of the lane kernel's function selection: 2^SELECT_BUCKET_BITS.
const SELECT_BUCKET_BITS: u32 = 10;

/// The CPU's fastest chaos-game step, for the common case: at most [`LANE_FUNCTIONS`]
/// multilinear or affine functions, a global selection table and no capped bin table (no
/// Julia function, no adaptive probabilities). One step is branch-free: select by a
/// fixed-size threshold comparison, clamp and bin the point as one 4-wide vector, finish each
/// axis's cell search with one comparison against the boundary stored next to the bin's cell,
/// and evaluate the interpolant with 4-wide vectors (xyz, w unused). Every operation is the
/// one [`CompiledIfs::map`] performs, in the same order, so the result is bit-identical.
#[derive(Clone, Debug, PartialEq)]
struct LaneKernel {
    /// Function selection by the top [`SELECT_BUCKET_BITS`] bits of r: per bucket, the
    /// function chosen at the bucket's start and the one threshold inside the bucket (or
    /// u32::MAX); the chosen function is the first plus (r24 ≥ threshold). Exactly
    /// [`SelectionTable::select`]; built only when no bucket holds two thresholds.
    buckets: Vec<(u32, u32)>,
    functions: Vec<LaneFunction>,
    /// Per bin: the cell at the bin's start and the coordinate where the next cell begins
    /// (+inf for an axis's last cell), see [`FastAxis`].
    bins: Vec<(u32, f32)>,
    coords: Vec<[f32; 2]>,
    cells: Vec<[Vec3A; 8]>,
    /// Per axis: some function has more than one cell along it. Along the other axes every
    /// function's cell is cell 0 and the search is skipped (see [`LaneKernel::map`]).
    multi: [bool; 3],
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct LaneFunction {
    /// Start coordinate and inverse width of cell 0 per axis.
    origin: Vec3A,
    inv_width: Vec3A,
    lo: Vec3A,
    hi: Vec3A,
    inv_bin: Vec3A,
    last_bin: Vec3A,
    bin_offset: [u32; 3],
    coord_offset: [u32; 3],
    cell_base: u32,
    stride_x: u32,
    stride_y: u32,
}

/// The CPU's private, packed copy of the compiled IFS: the same data with the cell search by
/// bins and 24 tightly packed coefficients per cell. Private, and checked once when built, so
/// that its hot loop can index without bounds checks (see the SAFETY notes in `map_fast`).
#[derive(Clone, Debug, PartialEq)]
struct FastKernel {
    functions: Vec<FastFunction>,
    coords: Vec<[f32; 2]>,
    bin_cells: Vec<u32>,
    cells: Vec<[f32; 24]>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct FastFunction {
    axes: [FastAxis; 3],
    cell_base: u32,
    stride_x: u32,
    stride_y: u32,
    julia: bool,
}

/// The CPU's cell search along one axis of one function: the axis is cut into bins no wider
/// than its narrowest cell, so a bin overlaps at most two cells; `bin_cells` gives the cell at
/// the bin's start and one comparison with the next coordinate finishes the search. Same
/// result as the linear search of [`CompiledIfs::map`] (the GPU's), without its loops.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct FastAxis {
    lo: f32,
    hi: f32,
    inv_bin: f32,
    last_bin: f32,
    bin_offset: u32,
    coord_offset: u32,
    last_cell: u32,
    /// MAX_BINS limited the bins: a bin may overlap more than two cells.
    capped: bool,
}

/// At most this many bins per axis (finer grids fall back to a slightly larger bin; the search
/// then takes a second step in rare cases, see `locate_fast`).
const MAX_BINS: usize = 4096;

/// Function selection: a coarse grid over the domain (1×1×1 when probabilities are global);
/// each cell holds `n` cumulative thresholds t_0 ≤ … ≤ t_{n−1} = 2^24 and the function chosen
/// by a 24-bit random r is the number of thresholds ≤ r. Mirrors the `selection` buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectionTable {
    pub cells: [u32; 3],
    pub lo: Vec3,
    /// Cells per unit length per axis.
    pub inv_cell: Vec3,
    pub function_count: u32,
    pub thresholds: Vec<u32>,
}

impl SelectionTable {
    fn from_probabilities(cells: [u32; 3], lo: Vec3, inv_cell: Vec3, probs: &[Vec<f64>]) -> Self {
        let n = probs.first().map_or(0, |p| p.len());
        let mut thresholds = Vec::with_capacity(probs.len() * n);
        for p in probs {
            let mut acc = 0.0;
            for (k, &pk) in p.iter().enumerate() {
                acc += pk;
                let t = if k + 1 == n {
                    1u32 << SELECT_BITS
                } else {
                    ((acc * (1u64 << SELECT_BITS) as f64).round() as u32).min(1 << SELECT_BITS)
                };
                thresholds.push(t);
            }
        }
        Self { cells, lo, inv_cell, function_count: n as u32, thresholds }
    }

    /// Index of the coarse cell of `p` (0 for a global table).
    #[inline(always)]
    pub fn cell_of(&self, p: Vec3) -> usize {
        if self.cells == [1, 1, 1] {
            return 0;
        }
        let q = (p - self.lo) * self.inv_cell;
        let ix = (q.x.max(0.0) as u32).min(self.cells[0] - 1);
        let iy = (q.y.max(0.0) as u32).min(self.cells[1] - 1);
        let iz = (q.z.max(0.0) as u32).min(self.cells[2] - 1);
        ((ix * self.cells[1] + iy) * self.cells[2] + iz) as usize
    }

    /// The function chosen by random bits `r` (its top 24 bits are used) at coarse cell `cell`.
    #[inline(always)]
    pub fn select(&self, cell: usize, r: u32) -> usize {
        let n = self.function_count as usize;
        let t = &self.thresholds[cell * n..cell * n + n];
        let r24 = r >> (32 - SELECT_BITS);
        t[..n - 1].iter().map(|&x| (x <= r24) as usize).sum()
    }
}

impl CompiledIfs {
    /// Compiles the enabled functions of `ifs`. Returns None if no function is enabled.
    pub fn new(ifs: &Ifs) -> Option<Self> {
        let active = ifs.active();
        if active.is_empty() {
            return None;
        }
        let dim = ifs.dimension();
        let mut functions = Vec::new();
        let mut coords: Vec<[f32; 2]> = Vec::new();
        let mut cells: Vec<Cell> = Vec::new();
        for &i in &active {
            functions.push(compile_map(&ifs.functions[i].map, dim, &mut coords, &mut cells));
        }
        let domain_lo = ifs.domain.min().as_vec3();
        let domain_hi = ifs.domain.max().as_vec3();
        let selection = selection_table(ifs, &active, domain_lo, domain_hi);
        let fast = FastKernel::new(&functions, &coords, &cells);
        let lanes = LaneKernel::new(&fast, &selection, &cells);
        #[cfg(target_arch = "x86_64")]
        let simd = lanes.as_ref().and_then(|_| x86::SimdKernel::new(&fast, &selection));
        let worst = active
            .iter()
            .filter_map(|&i| ifs.functions[i].map.lipschitz_bound())
            .fold(0.0f64, f64::max)
            .clamp(0.3, 0.97);
        let transient = ((1e-5f64).ln() / worst.ln()).ceil().clamp(24.0, 400.0) as u32;
        Some(Self {
            dimension: dim,
            functions,
            coords,
            cells,
            selection,
            colors: active.iter().map(|&i| ifs.functions[i].color).collect(),
            source_index: active,
            domain_lo,
            domain_hi,
            transient,
            fast,
            lanes,
            #[cfg(target_arch = "x86_64")]
            simd,
        })
    }

    /// The same map as [`Self::map`] (bit for bit) with the cell search by bins.
    #[inline(always)]
    pub fn map_fast(&self, fi: usize, p: Vec3) -> Vec3 {
        let k = &self.fast;
        let f = &k.functions[fi];
        if f.julia {
            return self.map(fi, p);
        }
        let (ix, u) = k.locate(&f.axes[0], p.x);
        let (iy, v) = k.locate(&f.axes[1], p.y);
        let (iz, w) = k.locate(&f.axes[2], p.z);
        let cell = f.cell_base as usize + ix * f.stride_x as usize + iy * f.stride_y as usize + iz;
        debug_assert!(cell < k.cells.len());
        #[expect(unsafe_code, reason = "tables bounds-checked once when compiled")]
        // SAFETY: `locate` returns ix, iy, iz within the function's cell counts (FastKernel::new
        // checked that every bin maps to a valid cell and that the counts, strides and bases
        // stay inside `cells`), so `cell` indexes the function's own cells.
        let c = unsafe { k.cells.get_unchecked(cell) };
        let v3 = |i: usize| Vec3::new(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
        let inner = v3(3) + u * v3(5) + v * (v3(6) + u * v3(7));
        v3(0) + u * v3(1) + v * (v3(2) + u * v3(4)) + w * inner
    }
    /// Maps `p` by compiled function `fi` (f32; the twin of `map_point` in the shader).
    #[inline(always)]
    pub fn map(&self, fi: usize, p: Vec3) -> Vec3 {
        let f = &self.functions[fi];
        if f.coord_offset[3] == KIND_JULIA {
            let (re, im) = complex_sqrt_f32(p.x - f.julia[0], p.y - f.julia[1]);
            return Vec3::new(f.julia[2] * re, f.julia[2] * im, 0.0);
        }
        let q = p.clamp(Vec3::from_slice(&f.lo[..3]), Vec3::from_slice(&f.hi[..3]));
        let (ix, u) = self.locate_axis(f, 0, q.x);
        let (iy, v) = self.locate_axis(f, 1, q.y);
        let (iz, w) = self.locate_axis(f, 2, q.z);
        let cell_index = f.cells[3] as usize + (ix * f.cells[1] as usize + iy) * f.cells[2] as usize + iz;
        let c = &self.cells[cell_index].coef;
        let v3 = |k: usize| Vec3::new(c[k][0], c[k][1], c[k][2]);
        // a + u b + v (c + u e) + w (d + u f + v (g + u h))
        let inner = v3(3) + u * v3(5) + v * (v3(6) + u * v3(7));
        v3(0) + u * v3(1) + v * (v3(2) + u * v3(4)) + w * inner
    }

    /// Cell index and local coordinate along axis `a` of a clamped coordinate `x`.
    #[inline(always)]
    fn locate_axis(&self, f: &KernelFunction, a: usize, x: f32) -> (usize, f32) {
        let n = f.cells[a] as usize;
        let base = f.coord_offset[a] as usize;
        let axis = &self.coords[base..base + n + 1];
        let guess = ((x - f.lo[a]) * f.inv_bin[a]).max(0.0) as usize;
        let mut i = guess.min(n - 1);
        while i > 0 && x < axis[i][0] {
            i -= 1;
        }
        while i + 1 < n && x >= axis[i + 1][0] {
            i += 1;
        }
        (i, (x - axis[i][0]) * axis[i][1])
    }

    /// Random start point in the domain box.
    fn start_point(&self, rng: &mut Pcg32) -> Vec3 {
        let t = Vec3::new(rng.next_f32(), rng.next_f32(), if self.dimension == 3 { rng.next_f32() } else { 0.0 });
        self.domain_lo + t * (self.domain_hi - self.domain_lo)
    }
}

impl FastKernel {
    fn new(functions: &[KernelFunction], coords: &[[f32; 2]], cells: &[Cell]) -> Self {
        let mut bin_cells = Vec::new();
        let mut fast_functions = Vec::new();
        for f in functions {
            let julia = f.coord_offset[3] == KIND_JULIA;
            let mut axes = [FastAxis::default(); 3];
            if !julia {
                for (a, fa) in axes.iter_mut().enumerate() {
                    *fa = fast_axis(f, a, coords, &mut bin_cells);
                }
            }
            let [cx, cy, cz] = [f.cells[0], f.cells[1], f.cells[2]];
            let base = f.cells[3];
            // The checks that the unchecked indexing in `map_fast` and `locate` relies on.
            if !julia {
                assert!(base as usize + (cx * cy * cz) as usize <= cells.len(), "cell pool too short");
                for (a, fa) in axes.iter().enumerate() {
                    assert_eq!(fa.last_cell + 1, f.cells[a], "cell count");
                    assert!(
                        fa.coord_offset as usize + fa.last_cell as usize + 2 <= coords.len(),
                        "coordinate pool too short"
                    );
                    let bins = fa.last_bin as usize + 1;
                    assert!(fa.bin_offset as usize + bins <= bin_cells.len(), "bin table too short");
                    let table = &bin_cells[fa.bin_offset as usize..fa.bin_offset as usize + bins];
                    assert!(table.iter().all(|&c| c <= fa.last_cell), "bin table out of range");
                }
            }
            fast_functions.push(FastFunction { axes, cell_base: base, stride_x: cy * cz, stride_y: cz, julia });
        }
        Self {
            functions: fast_functions,
            coords: coords.to_vec(),
            bin_cells,
            cells: cells.iter().map(|c| std::array::from_fn(|i| c.coef[i / 3][i % 3])).collect(),
        }
    }

    /// Cell index and local coordinate of `x` along one axis: clamp, bin, one comparison.
    #[inline(always)]
    fn locate(&self, a: &FastAxis, x: f32) -> (usize, f32) {
        // Strict comparisons, the exact semantics of x86's maxss/minss (one instruction each),
        // rather than f32::max/min, which treat NaN with extra instructions; these map NaN to a
        // bound all the same.
        let x = if x > a.lo { x } else { a.lo };
        let x = if x < a.hi { x } else { a.hi };
        // x ≥ lo, so this is ≥ 0, or NaN for an unbounded one-cell axis (inf · 0), which the
        // comparison maps to last_bin = 0.
        let b = (x - a.lo) * a.inv_bin;
        let b = if b < a.last_bin { b } else { a.last_bin };
        #[expect(unsafe_code, reason = "tables bounds-checked once when compiled")]
        // SAFETY: b is finite and in [0, last_bin] (see above), so the conversion is exact, and
        // FastKernel::new checked that last_bin + 1 table entries at bin_offset hold cells
        // ≤ last_cell and that last_cell + 2 coordinates follow coord_offset; i stays ≤ last_cell.
        unsafe {
            let bin = b.to_int_unchecked::<u32>() as usize;
            let mut i = *self.bin_cells.get_unchecked(a.bin_offset as usize + bin) as usize;
            let axis = self.coords.get_unchecked(a.coord_offset as usize..);
            let last = a.last_cell as usize;
            // The bin overlaps cells i and i + 1 at most.
            i += (i < last && x >= axis.get_unchecked(i + 1)[0]) as usize;
            if a.capped {
                while i < last && x >= axis.get_unchecked(i + 1)[0] {
                    i += 1;
                }
            }
            let e = axis.get_unchecked(i);
            (i, (x - e[0]) * e[1])
        }
    }
}

impl LaneKernel {
    /// The lane kernel of `fast`, or None when the IFS needs the general path.
    fn new(fast: &FastKernel, selection: &SelectionTable, cells: &[Cell]) -> Option<Self> {
        let n = fast.functions.len();
        if n == 0 || n > LANE_FUNCTIONS || selection.cells != [1, 1, 1] || selection.thresholds.len() != n {
            return None;
        }
        if fast.functions.iter().any(|f| f.julia || f.axes.iter().any(|a| a.capped)) {
            return None;
        }
        let inner = &selection.thresholds[..n - 1];
        let width = 1u32 << (SELECT_BITS - SELECT_BUCKET_BITS);
        let mut buckets = Vec::with_capacity(1 << SELECT_BUCKET_BITS);
        for b in 0..1u32 << SELECT_BUCKET_BITS {
            let start = b * width;
            let first = inner.iter().filter(|&&t| t <= start).count() as u32;
            let mut within = inner.iter().filter(|&&t| t > start && t < start + width);
            let next = within.next().copied().unwrap_or(u32::MAX);
            if within.next().is_some() {
                return None;
            }
            buckets.push((first, next));
        }
        let mut bins = Vec::new();
        let mut functions = Vec::new();
        for f in &fast.functions {
            let mut bin_offset = [0u32; 3];
            for (a, axis) in f.axes.iter().enumerate() {
                bin_offset[a] = bins.len() as u32;
                let table =
                    &fast.bin_cells[axis.bin_offset as usize..=axis.bin_offset as usize + axis.last_bin as usize];
                for &cell in table {
                    let next = if cell < axis.last_cell {
                        fast.coords[(axis.coord_offset + cell + 1) as usize][0]
                    } else {
                        f32::INFINITY
                    };
                    bins.push((cell, next));
                }
            }
            let v = |g: fn(&FastAxis) -> f32| Vec3A::new(g(&f.axes[0]), g(&f.axes[1]), g(&f.axes[2]));
            let cell0 = |a: &FastAxis| fast.coords[a.coord_offset as usize];
            functions.push(LaneFunction {
                origin: Vec3A::from_array(f.axes.map(|a| cell0(&a)[0])),
                inv_width: Vec3A::from_array(f.axes.map(|a| cell0(&a)[1])),
                lo: v(|a| a.lo),
                hi: v(|a| a.hi),
                inv_bin: v(|a| a.inv_bin),
                last_bin: v(|a| a.last_bin),
                bin_offset,
                coord_offset: f.axes.map(|a| a.coord_offset),
                cell_base: f.cell_base,
                stride_x: f.stride_x,
                stride_y: f.stride_y,
            });
        }
        Some(Self {
            buckets,
            functions,
            bins,
            coords: fast.coords.clone(),
            cells: cells.iter().map(|c| c.coef.map(|k| Vec3A::new(k[0], k[1], k[2]))).collect(),
            multi: std::array::from_fn(|a| fast.functions.iter().any(|f| f.axes[a].last_cell > 0)),
        })
    }

    /// The function chosen by random bits `r`: the number of thresholds ≤ its top 24 bits.
    #[inline(always)]
    fn select(&self, r: u32) -> usize {
        let r24 = r >> (32 - SELECT_BITS);
        #[expect(unsafe_code, reason = "tables bounds-checked once when compiled")]
        // SAFETY: r >> (32 - SELECT_BUCKET_BITS) < 2^SELECT_BUCKET_BITS = buckets.len().
        let (first, next) = unsafe { *self.buckets.get_unchecked((r >> (32 - SELECT_BUCKET_BITS)) as usize) };
        (first + (r24 >= next) as u32) as usize
    }

    /// The same map as [`CompiledIfs::map`], bit for bit. `MX`, `MY`, `MZ` must equal
    /// `self.multi`: along an axis where every function has one cell, the cell is 0 and
    /// the local coordinate is (x − origin) · inv_width, what the bin search would give.
    #[inline(always)]
    fn map<const MX: bool, const MY: bool, const MZ: bool>(&self, fi: usize, p: Vec3A) -> Vec3A {
        debug_assert_eq!([MX, MY, MZ], self.multi);
        debug_assert!(fi < self.functions.len());
        #[expect(unsafe_code, reason = "tables bounds-checked once when compiled")]
        // SAFETY: fi comes from `select`, whose buckets hold at most n − 1 thresholds below
        // the bucket's start plus at most one inside it: fi ≤ n − 1 (n functions).
        let f = unsafe { self.functions.get_unchecked(fi) };
        // _mm_max_ps / _mm_min_ps: x > lo ? x : lo, then x < hi ? x : hi; NaN goes to lo,
        // as in FastKernel::locate.
        let q = p.max(f.lo).min(f.hi);
        // See FastKernel::locate: ≥ 0 and ≤ last_bin, NaN mapped to last_bin = 0.
        let b = ((q - f.lo) * f.inv_bin).min(f.last_bin);
        let locate = |a: usize, x: f32, b: f32| -> (usize, [f32; 2]) {
            #[expect(unsafe_code, reason = "tables bounds-checked once when compiled")]
            // SAFETY: b is finite and in [0, last_bin] (see above), so the conversion is
            // exact; LaneKernel::new copied last_bin + 1 bins at bin_offset from FastKernel's
            // checked table, whose cells are ≤ last_cell; the +1 step happens only below
            // last_cell (next is +inf there, and x ≤ hi is finite); FastKernel::new checked
            // that last_cell + 2 coordinates follow coord_offset.
            unsafe {
                let bin = b.to_int_unchecked::<u32>() as usize;
                let (cell, next) = *self.bins.get_unchecked(f.bin_offset[a] as usize + bin);
                let i = cell as usize + (x >= next) as usize;
                (i, *self.coords.get_unchecked(f.coord_offset[a] as usize + i))
            }
        };
        // The local coordinates along one-cell axes (the other lanes are replaced below).
        let uvw = (q - f.origin) * f.inv_width;
        let mut cell = f.cell_base as usize;
        let u = if MX {
            let (i, e) = locate(0, q.x, b.x);
            cell += i * f.stride_x as usize;
            (q.x - e[0]) * e[1]
        } else {
            uvw.x
        };
        let v = if MY {
            let (i, e) = locate(1, q.y, b.y);
            cell += i * f.stride_y as usize;
            (q.y - e[0]) * e[1]
        } else {
            uvw.y
        };
        let w = if MZ {
            let (i, e) = locate(2, q.z, b.z);
            cell += i;
            (q.z - e[0]) * e[1]
        } else {
            uvw.z
        };
        debug_assert!(cell < self.cells.len());
        #[expect(unsafe_code, reason = "tables bounds-checked once when compiled")]
        // SAFETY: as in CompiledIfs::map_fast, checked by FastKernel::new.
        let c = unsafe { self.cells.get_unchecked(cell) };
        let (u, v, w) = (Vec3A::splat(u), Vec3A::splat(v), Vec3A::splat(w));
        let inner = c[3] + u * c[5] + v * (c[6] + u * c[7]);
        c[0] + u * c[1] + v * (c[2] + u * c[4]) + w * inner
    }

    /// [`Self::map`] with the axis flags taken from `self.multi` (for tests).
    #[cfg(test)]
    fn map_any(&self, fi: usize, p: Vec3A) -> Vec3A {
        match self.multi {
            [false, false, false] => self.map::<false, false, false>(fi, p),
            [false, false, true] => self.map::<false, false, true>(fi, p),
            [false, true, false] => self.map::<false, true, false>(fi, p),
            [false, true, true] => self.map::<false, true, true>(fi, p),
            [true, false, false] => self.map::<true, false, false>(fi, p),
            [true, false, true] => self.map::<true, false, true>(fi, p),
            [true, true, false] => self.map::<true, true, false>(fi, p),
            [true, true, true] => self.map::<true, true, true>(fi, p),
        }
    }
}

/// Runs the orbits with the lane kernel, specialized for its multi-cell axes.
fn run_lanes(lanes: &LaneKernel, orbits: Orbits, sink: &mut impl PointSink) {
    match lanes.multi {
        [false, false, false] => run_lanes_for::<false, false, false>(lanes, orbits, sink),
        [false, false, true] => run_lanes_for::<false, false, true>(lanes, orbits, sink),
        [false, true, false] => run_lanes_for::<false, true, false>(lanes, orbits, sink),
        [false, true, true] => run_lanes_for::<false, true, true>(lanes, orbits, sink),
        [true, false, false] => run_lanes_for::<true, false, false>(lanes, orbits, sink),
        [true, false, true] => run_lanes_for::<true, false, true>(lanes, orbits, sink),
        [true, true, false] => run_lanes_for::<true, true, false>(lanes, orbits, sink),
        [true, true, true] => run_lanes_for::<true, true, true>(lanes, orbits, sink),
    }
}

fn run_lanes_for<const MX: bool, const MY: bool, const MZ: bool>(
    lanes: &LaneKernel,
    orbits: Orbits,
    sink: &mut impl PointSink,
) {
    orbits.run(sink, |rng, p| {
        let fi = lanes.select(rng.next_u32());
        (lanes.map::<MX, MY, MZ>(fi, p), fi)
    })
}

fn fast_axis(f: &KernelFunction, a: usize, coords: &[[f32; 2]], bin_cells: &mut Vec<u32>) -> FastAxis {
    let n = f.cells[a] as usize;
    let base = f.coord_offset[a] as usize;
    let axis = &coords[base..base + n + 1];
    let mut fa = FastAxis {
        lo: f.lo[a],
        hi: f.hi[a],
        coord_offset: base as u32,
        bin_offset: bin_cells.len() as u32,
        last_cell: n.saturating_sub(1) as u32,
        ..Default::default()
    };
    if n <= 1 || f.inv_bin[a] == 0.0 {
        // One cell (an affine map, or z in 2D): every coordinate is in cell 0.
        bin_cells.push(0);
        return fa;
    }
    let extent = axis[n][0] - axis[0][0];
    let narrowest = axis.windows(2).map(|w| w[1][0] - w[0][0]).fold(f32::INFINITY, f32::min);
    let wanted = (extent / narrowest).ceil() as usize * 2;
    let bins = wanted.clamp(n, MAX_BINS);
    fa.capped = wanted > MAX_BINS;
    fa.inv_bin = bins as f32 / extent;
    fa.last_bin = (bins - 1) as f32;
    for b in 0..bins {
        // A little before the bin's start, so that rounding in the runtime bin computation
        // can only leave a point above the tabulated cell, never below it.
        let x = axis[0][0] + (b as f32 - 0.01) / fa.inv_bin;
        // The cell containing it, found by the reference linear search.
        let mut i = 0;
        while i + 1 < n && x >= axis[i + 1][0] {
            i += 1;
        }
        bin_cells.push(i as u32);
    }
    fa
}

fn complex_sqrt_f32(re: f32, im: f32) -> (f32, f32) {
    let r = (re * re + im * im).sqrt();
    let a = ((r + re) * 0.5).max(0.0).sqrt();
    let b = ((r - re) * 0.5).max(0.0).sqrt();
    (a, if im < 0.0 { -b } else { b })
}

fn to4(v: DVec3) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, 0.0]
}

fn compile_map(map: &Map, dim: usize, coords: &mut Vec<[f32; 2]>, cells: &mut Vec<Cell>) -> KernelFunction {
    let cell_offset = cells.len() as u32;
    match map {
        Map::Grid(g) => {
            let mut coord_offset = [0u32; 4];
            let mut n_cells = [1u32; 4];
            let mut inv_bin = [0f32; 4];
            for a in 0..3 {
                coord_offset[a] = coords.len() as u32;
                let xs = &g.grid.axes[a];
                if xs.len() < 2 {
                    coords.push([xs[0] as f32, 0.0]);
                    coords.push([UNBOUNDED, 0.0]);
                    continue;
                }
                n_cells[a] = (xs.len() - 1) as u32;
                inv_bin[a] = (n_cells[a] as f64 / (xs[xs.len() - 1] - xs[0])) as f32;
                for k in 0..xs.len() {
                    let inv_w = if k + 1 < xs.len() { (1.0 / (xs[k + 1] - xs[k])) as f32 } else { 0.0 };
                    coords.push([xs[k] as f32, inv_w]);
                }
            }
            let counts = g.grid.cell_counts().map(|n| n.max(1));
            for cx in 0..counts[0] {
                for cy in 0..counts[1] {
                    for cz in 0..counts[2] {
                        let corner = |o: [usize; 3]| -> DVec3 {
                            let [nx, ny, nz] = g.grid.dims();
                            g.points[g.grid.index(
                                (cx + o[0]).min(nx - 1),
                                (cy + o[1]).min(ny - 1),
                                (cz + o[2]).min(nz - 1),
                            )]
                        };
                        let c000 = corner([0, 0, 0]);
                        let c100 = corner([1, 0, 0]);
                        let c010 = corner([0, 1, 0]);
                        let c110 = corner([1, 1, 0]);
                        let (c001, c101, c011, c111) = if dim == 3 {
                            (corner([0, 0, 1]), corner([1, 0, 1]), corner([0, 1, 1]), corner([1, 1, 1]))
                        } else {
                            (c000, c100, c010, c110)
                        };
                        let coef = [
                            c000,
                            c100 - c000,
                            c010 - c000,
                            c001 - c000,
                            c110 - c100 - c010 + c000,
                            c101 - c100 - c001 + c000,
                            c011 - c010 - c001 + c000,
                            c111 - c110 - c101 - c011 + c100 + c010 + c001 - c000,
                        ];
                        cells.push(Cell { coef: coef.map(to4) });
                    }
                }
            }
            coord_offset[3] = KIND_MULTILINEAR;
            n_cells[3] = cell_offset;
            KernelFunction {
                lo: to4(g.grid.min()),
                hi: to4(g.grid.max()),
                inv_bin,
                cells: n_cells,
                coord_offset,
                julia: [0.0; 4],
            }
        }
        Map::Affine(a) => {
            let mut coord_offset = [0u32; 4];
            for (k, off) in coord_offset.iter_mut().enumerate().take(3) {
                *off = coords.len() as u32;
                // u = x exactly (origin 0, inverse width 1); z unused in 2D.
                coords.push([0.0, if k < dim { 1.0 } else { 0.0 }]);
                coords.push([UNBOUNDED, 0.0]);
            }
            let m = a.matrix;
            let mut coef = [DVec3::ZERO; 8];
            coef[0] = a.offset;
            coef[1] = m.x_axis;
            coef[2] = m.y_axis;
            coef[3] = m.z_axis;
            cells.push(Cell { coef: coef.map(to4) });
            coord_offset[3] = KIND_MULTILINEAR;
            KernelFunction {
                lo: [-UNBOUNDED, -UNBOUNDED, -UNBOUNDED, 0.0],
                hi: [UNBOUNDED, UNBOUNDED, UNBOUNDED, 0.0],
                inv_bin: [0.0; 4],
                cells: [1, 1, 1, cell_offset],
                coord_offset,
                julia: [0.0; 4],
            }
        }
        Map::Julia(j) => KernelFunction {
            lo: [0.0; 4],
            hi: [0.0; 4],
            inv_bin: [0.0; 4],
            cells: [1, 1, 1, cell_offset],
            coord_offset: [0, 0, 0, KIND_JULIA],
            julia: [j.c[0] as f32, j.c[1] as f32, j.sign as f32, 0.0],
        },
    }
}

fn selection_table(ifs: &Ifs, active: &[usize], lo: Vec3, hi: Vec3) -> SelectionTable {
    let pick = |p: Vec<f64>| -> Vec<f64> { active.iter().map(|&i| p[i]).collect() };
    if ifs.probability_mode != ProbabilityMode::Adaptive {
        return SelectionTable::from_probabilities([1, 1, 1], lo, Vec3::ZERO, &[pick(ifs.probabilities())]);
    }
    let dim = ifs.dimension();
    let n = if dim == 3 { ADAPTIVE_CELLS_3D } else { ADAPTIVE_CELLS_2D };
    let cells = [n, n, if dim == 3 { n } else { 1 }];
    let size = (hi - lo).max(Vec3::splat(1e-20));
    let inv_cell = Vec3::new(n as f32 / size.x, n as f32 / size.y, if dim == 3 { n as f32 / size.z } else { 0.0 });
    let d = ifs.similarity_dimension();
    let mut probs = Vec::new();
    for ix in 0..cells[0] {
        for iy in 0..cells[1] {
            for iz in 0..cells[2] {
                let t = Vec3::new(
                    (ix as f32 + 0.5) / n as f32,
                    (iy as f32 + 0.5) / n as f32,
                    if dim == 3 { (iz as f32 + 0.5) / n as f32 } else { 0.0 },
                );
                let q = (lo + t * (hi - lo)).as_dvec3();
                probs.push(pick(ifs.local_probabilities(q, d)));
            }
        }
    }
    SelectionTable::from_probabilities(cells, lo, inv_cell, &probs)
}

/// A batch of mapped points as structure of arrays (what vector code reads and writes best):
/// point i is (x[i], y[i], z[i]), mapped by compiled function `functions[i]`. All four slices
/// have the same length.
#[derive(Clone, Copy, Debug)]
pub struct PointBatch<'a> {
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
    pub functions: &'a [u8],
}

impl PointBatch<'_> {
    pub fn len(&self) -> usize {
        self.functions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.functions.is_empty()
    }

    #[inline(always)]
    pub fn point(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.len()).map(|i| self.point(i))
    }
}

/// Receives mapped points in batches.
pub trait PointSink {
    fn consume(&mut self, batch: PointBatch<'_>);
}

/// Collects points (used by export and tests).
#[derive(Default)]
pub struct CollectSink {
    pub points: Vec<Vec3>,
    pub functions: Vec<u8>,
}

impl PointSink for CollectSink {
    fn consume(&mut self, batch: PointBatch<'_>) {
        self.points.extend(batch.points());
        self.functions.extend_from_slice(batch.functions);
    }
}

/// Runs chunk `chunk` of a chaos game: [`ORBITS_PER_CHUNK`] orbits, `steps` points each after
/// the transient, into `sink`. Orbit (lane) `k` of chunk `c` is chain `c · ORBITS_PER_CHUNK + k`
/// and draws from the random stream (seed, frame, chain), as chain i of the GPU does.
pub fn run_chunk(ifs: &CompiledIfs, seed: u32, frame: u32, chunk: u32, steps: usize, sink: &mut impl PointSink) {
    run_chunk_on(ifs, Path::Fastest, seed, frame, chunk, steps, sink)
}

/// Which implementation [`run_chunk_on`] takes; all give the same points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Path {
    /// The fastest the IFS and the CPU allow.
    Fastest,
    /// Not the vector kernel (for tests).
    #[cfg(test)]
    Portable,
    /// The vector kernel with this coefficient lookup (for tests).
    #[cfg(all(test, target_arch = "x86_64"))]
    Simd(x86::Lookup),
}

fn run_chunk_on(
    ifs: &CompiledIfs,
    path: Path,
    seed: u32,
    frame: u32,
    chunk: u32,
    steps: usize,
    sink: &mut impl PointSink,
) {
    let first_chain = chunk.wrapping_mul(ORBITS_PER_CHUNK as u32);
    let mut rngs: [Pcg32; ORBITS_PER_CHUNK] =
        std::array::from_fn(|k| Pcg32::for_stream(seed, frame, first_chain.wrapping_add(k as u32)));
    let mut pos: [Vec3A; ORBITS_PER_CHUNK] = std::array::from_fn(|k| ifs.start_point(&mut rngs[k]).into());
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = &ifs.simd {
        let lookup = match path {
            Path::Fastest => Some(simd.lookup),
            #[cfg(test)]
            Path::Portable => None,
            #[cfg(test)]
            Path::Simd(lookup) => Some(lookup),
        };
        if let Some(lookup) = lookup {
            let rngs = rngs.map(Pcg32::state);
            simd.run(lookup, &rngs, &pos.map(|p| p.to_array()), ifs.transient, steps, sink);
            return;
        }
    }
    #[cfg(all(test, target_arch = "x86_64"))]
    assert!(!matches!(path, Path::Simd(_)), "no vector kernel for this IFS");
    let _ = path;
    let orbits = Orbits { rngs: &mut rngs, pos: &mut pos, transient: ifs.transient, steps };
    match &ifs.lanes {
        Some(lanes) => run_lanes(lanes, orbits, sink),
        None => {
            let sel = &ifs.selection;
            let adaptive = sel.cells != [1, 1, 1];
            orbits.run(sink, |rng, p| {
                let cell = if adaptive { sel.cell_of(p.into()) } else { 0 };
                let fi = sel.select(cell, rng.next_u32());
                (ifs.map_fast(fi, p.into()).into(), fi)
            })
        }
    }
}

/// The orbits of one chunk, advanced one step at a time across all lanes (independent lanes
/// give the CPU instruction-level parallelism).
struct Orbits<'a> {
    rngs: &'a mut [Pcg32; ORBITS_PER_CHUNK],
    pos: &'a mut [Vec3A; ORBITS_PER_CHUNK],
    transient: u32,
    steps: usize,
}

impl Orbits<'_> {
    #[inline(always)]
    fn run(self, sink: &mut impl PointSink, step: impl Fn(&mut Pcg32, Vec3A) -> (Vec3A, usize)) {
        const K: usize = ORBITS_PER_CHUNK;
        for _ in 0..self.transient {
            for (rng, p) in self.rngs.iter_mut().zip(self.pos.iter_mut()) {
                *p = step(rng, *p).0;
            }
        }
        let mut out_x = vec![0f32; K * STEPS_PER_BATCH];
        let mut out_y = vec![0f32; K * STEPS_PER_BATCH];
        let mut out_z = vec![0f32; K * STEPS_PER_BATCH];
        let mut out_fn = vec![0u8; K * STEPS_PER_BATCH];
        let mut done = 0;
        while done < self.steps {
            let batch = STEPS_PER_BATCH.min(self.steps - done);
            for s in 0..batch {
                let row = s * K..s * K + K;
                let (xs, ys, zs, fs) =
                    (&mut out_x[row.clone()], &mut out_y[row.clone()], &mut out_z[row.clone()], &mut out_fn[row]);
                for (k, (rng, p)) in self.rngs.iter_mut().zip(self.pos.iter_mut()).enumerate() {
                    let (q, fi) = step(rng, *p);
                    *p = q;
                    (xs[k], ys[k], zs[k]) = (q.x, q.y, q.z);
                    fs[k] = fi as u8;
                }
            }
            let n = batch * K;
            sink.consume(PointBatch { x: &out_x[..n], y: &out_y[..n], z: &out_z[..n], functions: &out_fn[..n] });
            done += batch;
        }
    }
}

/// Runs the chaos game of `plan` in parallel: every chunk into its own sink made by `make_sink`,
/// the sinks merged with `merge` (which must be order-independent for determinism). `progress`
/// is called once per finished chunk.
pub fn run_parallel<S: PointSink + Send>(
    ifs: &CompiledIfs,
    seed: u32,
    frame: u32,
    plan: &ChunkPlan,
    make_sink: impl Fn() -> S + Sync,
    merge: impl Fn(S, S) -> S + Sync + Send,
    progress: impl Fn() + Sync,
) -> S {
    (0..plan.chunks())
        .into_par_iter()
        .fold(&make_sink, |mut sink, c| {
            run_chunk(ifs, seed, frame, c, plan.steps(c), &mut sink);
            progress();
            sink
        })
        .reduce(&make_sink, &merge)
}

/// A short deterministic sample of the attractor (16,384 points), for framing and bounds.
pub fn attractor_sample(ifs: &CompiledIfs, seed: u32) -> Vec<Vec3> {
    let mut sink = CollectSink::default();
    for c in 0..4 {
        run_chunk(ifs, seed ^ 0x5eed_b0d5, 0, c, 64, &mut sink);
    }
    sink.points
}

/// Axis-aligned bounds of the attractor from a short deterministic run, or the domain's box if
/// the run gives nothing finite.
pub fn attractor_bounds(ifs: &CompiledIfs, seed: u32) -> (DVec3, DVec3) {
    let mut sink = CollectSink::default();
    for c in 0..4 {
        run_chunk(ifs, seed ^ 0x5eed_b0d5, 0, c, 256, &mut sink);
    }
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in sink.points.iter().filter(|p| p.is_finite()) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (ifs.domain_lo.as_dvec3(), ifs.domain_hi.as_dvec3());
    }
    // A short run can miss thin extremities: pad by 2% of the extent.
    let pad = 0.02 * (hi - lo);
    ((lo - pad).as_dvec3(), (hi + pad).as_dvec3())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{AffineMap, Function, GridMap, RectGrid};
    use glam::DMat3;

    fn warped_ifs() -> Ifs {
        let grid = RectGrid { axes: [vec![0.0, 0.3, 1.0], vec![0.0, 0.5, 0.8, 1.0], vec![0.0, 0.4, 1.0]] };
        let mut r = Pcg32::for_stream(9, 0, 0);
        let functions = (0..3)
            .map(|i| Function {
                name: format!("f{i}"),
                map: Map::Grid(GridMap::from_fn(grid.clone(), |p| {
                    0.45 * p
                        + DVec3::new(r.next_f32() as f64 * 0.5, r.next_f32() as f64 * 0.5, r.next_f32() as f64 * 0.5)
                })),
                color: [1.0; 3],
                weight: None,
                enabled: true,
            })
            .chain(std::iter::once(Function {
                name: "affine".into(),
                map: Map::Affine(AffineMap {
                    matrix: DMat3::from_diagonal(DVec3::splat(0.3)),
                    offset: DVec3::splat(0.1),
                }),
                color: [1.0; 3],
                weight: None,
                enabled: true,
            }))
            .collect();
        Ifs { domain: grid, functions, probability_mode: ProbabilityMode::Contractivity }
    }

    /// The compiled f32 kernel agrees with the f64 model within f32 rounding of the
    /// coordinates (relative 1e-6 of the domain size, with room for the ~20 operations).
    #[test]
    fn compiled_matches_model() {
        let ifs = warped_ifs();
        let c = CompiledIfs::new(&ifs).unwrap();
        let mut r = Pcg32::for_stream(3, 0, 0);
        for _ in 0..5000 {
            let p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.2 - 0.1;
            for fi in 0..4 {
                let want = ifs.eval(fi, p.as_dvec3());
                let got = c.map(fi, p).as_dvec3();
                assert!(got.distance(want) < 2e-5, "f{fi} at {p}: {got} vs {want}");
            }
        }
    }

    /// The CPU's binned cell search gives bit-identical results to the reference search that
    /// the GPU mirrors, including points on and near cell faces and outside the grid.
    #[test]
    fn fast_map_is_bit_identical() {
        let ifs = warped_ifs();
        let c = CompiledIfs::new(&ifs).unwrap();
        let mut r = Pcg32::for_stream(4, 0, 0);
        let faces = [0.0f32, 0.3, 0.5, 0.8, 0.4, 1.0];
        for k in 0..20_000 {
            let mut p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.4 - 0.2;
            if k % 4 == 0 {
                // Exactly on a face, or one ulp either side.
                let f = faces[k / 4 % faces.len()];
                p.y = match k % 3 {
                    0 => f,
                    1 => f.next_up(),
                    _ => f.next_down(),
                };
            }
            for fi in 0..4 {
                assert_eq!(c.map_fast(fi, p), c.map(fi, p), "f{fi} at {p:?}");
            }
        }
    }

    /// The lane kernel (the common case's fast path) is bit-identical to the reference map,
    /// on and near cell faces and outside the grid, and is the path the warped IFS takes.
    #[test]
    fn lane_map_is_bit_identical() {
        // The warped IFS has several cells along every axis; its variant on a 1×2×1 grid
        // (as the paper's tapering, 1×3×1) takes the kernel specialized for y alone.
        // With 2 cells along y the IFS has 7 cells (every vector lookup applies), with 3 it has
        // 10 (the 16-entry lookups and the gathers), the warped IFS 37 (the gathers).
        for (ifs, multi) in [
            (warped_ifs(), [true; 3]),
            (y_only_ifs(&[0.0, 0.3, 1.0]), [false, true, false]),
            (y_only_ifs(&[0.0, 0.3, 0.8, 1.0]), [false, true, false]),
        ] {
            check_lane_map(&ifs, multi);
        }
    }

    /// The warped IFS with its grid maps on a 1×n×1 grid with y coordinates `ys`.
    fn y_only_ifs(ys: &[f64]) -> Ifs {
        let mut y_only = warped_ifs();
        let grid = RectGrid { axes: [vec![0.0, 1.0], ys.to_vec(), vec![0.0, 1.0]] };
        for (i, f) in y_only.functions.iter_mut().enumerate().take(3) {
            let o = DVec3::new(0.1 * i as f64, 0.5, 0.2);
            f.map = Map::Grid(GridMap::from_fn(grid.clone(), |p| 0.4 * p + o + DVec3::new(0.0, 0.1 * p.x * p.y, 0.0)));
        }
        y_only.domain = grid;
        y_only
    }

    /// The vector kernel's lookups this CPU runs for `c` (none without AVX2 or off x86-64).
    fn simd_paths(c: &CompiledIfs) -> Vec<Path> {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = &c.simd {
            return simd.supported_lookups().into_iter().map(Path::Simd).collect();
        }
        let _ = c;
        Vec::new()
    }

    fn check_lane_map(ifs: &Ifs, multi: [bool; 3]) {
        let c = CompiledIfs::new(ifs).unwrap();
        let lanes = c.lanes.as_ref().expect("the IFS takes the lane path");
        assert_eq!(lanes.multi, multi);
        let mut r = Pcg32::for_stream(4, 0, 1);
        let faces = [0.0f32, 0.3, 0.5, 0.8, 0.4, 1.0];
        let mut points = Vec::new();
        for k in 0..20_000 {
            let mut p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.4 - 0.2;
            if k % 2 == 0 {
                let f = faces[k / 2 % faces.len()];
                let g = match k % 3 {
                    0 => f,
                    1 => f.next_up(),
                    _ => f.next_down(),
                };
                match k % 5 {
                    0 => p.x = g,
                    1 | 2 => p.y = g,
                    _ => p.z = g,
                }
            }
            if k % 97 == 0 {
                p = Vec3::new(f32::NAN, 1e30, -1e30);
            }
            for fi in 0..4 {
                let got = Vec3::from(lanes.map_any(fi, p.into()));
                let want = c.map(fi, p);
                assert_eq!(got.to_array().map(f32::to_bits), want.to_array().map(f32::to_bits), "f{fi} at {p:?}");
            }
            points.push(p);
        }
        // The vector kernel, a vector of points at a time with mixed functions, every lookup.
        let paths = simd_paths(&c);
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            assert!(paths.contains(&Path::Simd(x86::Lookup::Gather)), "{paths:?}");
        }
        for path in paths {
            #[cfg(target_arch = "x86_64")]
            if let Path::Simd(lookup) = path {
                let simd = c.simd.as_ref().unwrap();
                let fi: Vec<u32> = (0..points.len()).map(|i| ((i + i / 16) % 4) as u32).collect();
                let p: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
                let got = simd.map_points(lookup, &fi, &p);
                for i in 0..points.len() {
                    let want = c.map(fi[i] as usize, points[i]);
                    assert_eq!(
                        got[i].map(f32::to_bits),
                        want.to_array().map(f32::to_bits),
                        "{lookup:?} f{} at {:?}",
                        fi[i],
                        points[i]
                    );
                }
            }
            let _ = path;
        }
    }

    /// The lane kernel's bucketed selection equals the table's threshold count for every
    /// r near each threshold and at random.
    #[test]
    fn lane_select_matches_table() {
        let c = CompiledIfs::new(&warped_ifs()).unwrap();
        let lanes = c.lanes.as_ref().unwrap();
        let mut r = Pcg32::for_stream(6, 0, 0);
        let mut rs: Vec<u32> = (0..100_000).map(|_| r.next_u32()).collect();
        for &t in &c.selection.thresholds {
            for d in -3i64..=3 {
                let r24 = (t as i64 + d).clamp(0, (1 << 24) - 1) as u32;
                rs.extend([r24 << 8, r24 << 8 | 0xff]);
            }
        }
        for &r in &rs {
            assert_eq!(lanes.select(r), c.selection.select(0, r), "r = {r:#x}");
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = &c.simd {
            // Whole vectors: pad with a value already tested.
            rs.resize(rs.len().next_multiple_of(16), rs[0]);
            for got in simd.select_points(&rs) {
                for (&r, &fi) in rs.iter().zip(&got) {
                    assert_eq!(fi as usize, c.selection.select(0, r), "r = {r:#x}");
                }
            }
        }
    }

    /// `run_chunk` against a plain oracle: lane k of chunk c draws from stream (seed, frame,
    /// 64c + k), starts at a random domain point, selects with the table and maps with the
    /// reference `map`; every point must be bit-identical, on the lane path (global
    /// probabilities; the portable lane kernel and the vector kernel with each lookup the CPU
    /// has) and on the general path (adaptive probabilities).
    #[test]
    fn run_chunk_matches_reference_orbits() {
        let cases = [
            (warped_ifs(), ProbabilityMode::Contractivity),
            (warped_ifs(), ProbabilityMode::Adaptive),
            (y_only_ifs(&[0.0, 0.3, 1.0]), ProbabilityMode::Contractivity),
            (y_only_ifs(&[0.0, 0.3, 0.8, 1.0]), ProbabilityMode::Contractivity),
        ];
        for (mut ifs, mode) in cases {
            ifs.probability_mode = mode;
            let c = CompiledIfs::new(&ifs).unwrap();
            assert_eq!(c.lanes.is_some(), mode == ProbabilityMode::Contractivity);
            for path in [Path::Fastest, Path::Portable].into_iter().chain(simd_paths(&c)) {
                check_chunk(&c, path);
            }
        }
    }

    fn check_chunk(c: &CompiledIfs, path: Path) {
        let mode = (c.selection.cells, path);
        let (seed, frame, chunk, steps) = (11, 2, 5u32, 40);
        let mut got = CollectSink::default();
        run_chunk_on(c, path, seed, frame, chunk, steps, &mut got);
        let k_n = ORBITS_PER_CHUNK;
        let mut want = vec![Vec3::ZERO; k_n * steps];
        let mut want_fn = vec![0u8; k_n * steps];
        for k in 0..k_n {
            let mut rng = Pcg32::for_stream(seed, frame, chunk * k_n as u32 + k as u32);
            let mut p = c.start_point(&mut rng);
            for s in 0..c.transient as usize + steps {
                let fi = c.selection.select(c.selection.cell_of(p), rng.next_u32());
                p = c.map(fi, p);
                if s >= c.transient as usize {
                    let row = s - c.transient as usize;
                    want[row * k_n + k] = p;
                    want_fn[row * k_n + k] = fi as u8;
                }
            }
        }
        assert_eq!(got.functions, want_fn, "{mode:?}");
        let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&got.points), bits(&want), "{mode:?}");
    }

    #[test]
    fn grid_points_compile_exactly_enough() {
        let ifs = warped_ifs();
        let c = CompiledIfs::new(&ifs).unwrap();
        if let Map::Grid(g) = &ifs.functions[0].map {
            for (i, p) in g.grid.points().into_iter().enumerate() {
                assert!(c.map(0, p.as_vec3()).as_dvec3().distance(g.points[i]) < 1e-6);
            }
        }
    }

    #[test]
    fn selection_follows_probabilities() {
        let probs = vec![vec![0.2, 0.5, 0.3]];
        let t = SelectionTable::from_probabilities([1, 1, 1], Vec3::ZERO, Vec3::ZERO, &probs);
        let mut r = Pcg32::for_stream(5, 0, 0);
        let n = 300_000;
        let mut counts = [0usize; 3];
        for _ in 0..n {
            counts[t.select(0, r.next_u32())] += 1;
        }
        for k in 0..3 {
            let p = probs[0][k];
            let sigma = (p * (1.0 - p) / n as f64).sqrt();
            // 5 standard deviations of a binomial proportion.
            assert!((counts[k] as f64 / n as f64 - p).abs() < 5.0 * sigma, "{counts:?}");
        }
    }

    #[test]
    fn chunks_are_independent_of_threads() {
        let ifs = warped_ifs();
        let c = CompiledIfs::new(&ifs).unwrap();
        let run = || {
            run_parallel(
                &c,
                7,
                0,
                &ChunkPlan::new(600_000).unwrap(),
                CollectSink::default,
                |mut a, b| {
                    a.points.extend(b.points);
                    a
                },
                || {},
            )
            .points
            .len()
        };
        assert_eq!(run(), run());
        let mut a = CollectSink::default();
        let mut b = CollectSink::default();
        run_chunk(&c, 7, 0, 3, 100, &mut a);
        run_chunk(&c, 7, 0, 3, 100, &mut b);
        assert_eq!(a.points, b.points);
    }
}
