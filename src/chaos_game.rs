//! The chaos game (the paper's stochastic algorithm, figure 7), CPU reference. The GPU twin is
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
//! number of threads (the split is a [`ChunkPlan`]). Each orbit starts at a random point of the
//! domain and its first `transient` points are discarded.
//!
//! Three implementations of one step, bit-identical per point: [`CompiledIfs::map`] (the
//! reference the GPU mirrors, linear cell search), [`CompiledIfs::map_fast`] (cell search by
//! bins; any IFS), and the private lane kernel (the common case: few multilinear or affine
//! functions with global probabilities; bucketed selection, 4-wide arithmetic, and a variant
//! per set of axes that have more than one cell). On x86-64 CPUs with AVX2 (detected at run
//! time) the lane kernel's case runs eight orbits per vector instead, sixteen with AVX-512F
//! (`chaos_game/x86.rs`), again bit-identical. Measurements: docs/performance.md.
//!
//! Where each part lives: this file holds the compiled IFS's data layout and the reference map;
//! `compile.rs` builds the tables and the selection table from an IFS, `fast.rs` the binned cell
//! search, `lanes.rs` the portable lane kernel, `x86.rs` the vector kernel, `sink.rs` the point
//! batches and sinks, `plan.rs` the chunk plan and `run.rs` the runs of chunks and plans.

use glam::Vec3;

use crate::model::Ifs;
use crate::rng::Pcg32;

mod color_coord;
mod compile;
mod fast;
mod flame;
mod lanes;
pub mod plan;
mod run;
mod sink;
#[cfg(test)]
mod tests;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use color_coord::{C_START, step_color, step_color_speed};
pub use compile::SelectionTable;
pub use flame::FlameTable;
pub use plan::{ChunkPlan, PlanError};
pub use run::{
    ChunkChains, attractor_bounds, attractor_sample, continue_chunk, run_chunk, run_parallel, run_per_thread,
};
pub use sink::{CollectSink, PointBatch, PointSink};

use compile::{compile_map, selection_table};
use fast::FastKernel;
use lanes::LaneKernel;

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
/// A flame function (`chaos_game/flame.rs`): the CPU maps it by its xform; the kernel table holds
/// its pre-affine as one affine cell.
pub const KIND_FLAME: u32 = 2;

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
    // Palette colour (`chaos_game/color_coord.rs`):
    /// Each compiled function's colour coordinate c_i in [0, 1]; None: function colour.
    pub color_coords: Option<Vec<f32>>,
    /// The palette entries interpolated as flam3's `palette_mode = "linear"` (dithered,
    /// `palette::index_linear`); false: the nearest step (`palette::index_of`).
    pub palette_linear: bool,
    /// Each compiled function's colour speed, when a flame function has one other than ½.
    pub color_speeds: Option<Vec<f32>>,
    /// The flame functions' xforms (`chaos_game/flame.rs`); None: the IFS has none.
    pub flames: Option<FlameTable>,
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
        let flames = FlameTable::new(
            active
                .iter()
                .map(|&i| match &ifs.functions[i].map {
                    crate::model::Map::Flame(f) => Some(f.xform.clone()),
                    _ => None,
                })
                .collect(),
            ifs.final_xform.as_ref(),
        );
        let color_speeds = flames.as_ref().map(FlameTable::color_speeds).filter(|s| s.iter().any(|&s| s != 0.5));
        let fast = FastKernel::new(&functions, &coords, &cells);
        let lanes = if flames.is_some() { None } else { LaneKernel::new(&fast, &selection, &cells) };
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
            color_coords: None,
            palette_linear: false,
            color_speeds,
            flames,
        })
    }

    /// The IFS coloured by a colour coordinate: `coords[i]` is compiled function i's c_i in
    /// [0, 1] (clamped), and the colour table becomes the palette's entries; the points then
    /// carry `palette::index_of(c)` where they carried their function.
    pub fn with_palette(self, coords: Vec<f32>, palette: &crate::palette::Palette) -> Self {
        assert_eq!(coords.len(), self.functions.len(), "one colour coordinate per compiled function");
        let coords = coords.into_iter().map(|c| if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.5 }).collect();
        Self { color_coords: Some(coords), colors: palette.samples.clone(), ..self }
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

fn complex_sqrt_f32(re: f32, im: f32) -> (f32, f32) {
    let r = (re * re + im * im).sqrt();
    let a = ((r + re) * 0.5).max(0.0).sqrt();
    let b = ((r - re) * 0.5).max(0.0).sqrt();
    (a, if im < 0.0 { -b } else { b })
}
