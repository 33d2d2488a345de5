//! The lane kernel with explicit AVX2 or AVX-512F (`std::arch`, detected at run time): eight
//! orbits per 256-bit vector or sixteen per 512-bit vector, as structure of arrays. This file
//! lays out the kernel's tables and dispatches; the vector code itself, the AVX2 and AVX-512
//! twins side by side, is in `x86/kernel.rs`. The portable lane kernel (`lanes.rs`) stays the
//! fallback; both are bit-identical to [`CompiledIfs::map`](super::CompiledIfs::map) with the
//! same random streams, so the CPU chooses the speed and never the points.
//!
//! How one step of eight (sixteen) orbits goes, every operation the reference's, in its order
//! (no FMA):
//! - the 32-bit PCGs advance as one vector (`vpmulld`, `vpsrlvd`);
//! - the function is the number of cumulative thresholds ≤ the 24-bit draw: one compare and
//!   one subtract per threshold (at most 7), exactly [`SelectionTable::select`];
//! - per-function values (clamp box, cell 0's start, strides) are tables read with `vpermps`
//!   by the function index;
//! - the cell search along an axis counts the interior cell boundaries ≤ the clamped coordinate
//!   (boundaries past a function's last cell are +∞); for non-decreasing boundaries this is the
//!   reference's linear search, clamping included. Each boundary passed also switches the
//!   start and inverse width of the local coordinate and adds the axis's stride to the cell;
//! - the 24 coefficients of each lane's cell come from per-coefficient tables over the IFS's
//!   cells: with AVX2 one `vpermps` (≤ 8 cells) or two and a blend (≤ 16), with AVX-512 one
//!   `vpermps` (≤ 16), or else a gather;
//! - Horner as in the scalar code.
//!
//! AVX-512 is preferred where present: 16 lanes halve the instructions per point, and the
//! 16-entry coefficient lookup is one instruction instead of three.
//!
//! Everything here requires AVX2 (the 16-wide code AVX-512F): the functions are reached only
//! through [`SimdKernel::run_kept`] and the test entry points, which check the CPU first. Hence the module-wide `unsafe_code` allowance: the intrinsics are `unsafe` to call
//! outside a `#[target_feature]` function; the memory accesses carry their own SAFETY notes.
#![expect(
    unsafe_code,
    reason = "intrinsics need unsafe outside #[target_feature] functions; callers check the CPU first"
)]

use super::fast::{FastFunction, FastKernel};
use super::lanes::LANE_FUNCTIONS;
use super::{ORBITS_PER_CHUNK, PointSink, SELECT_BITS, SelectionTable};
use crate::simd::SimdLevel;

mod kernel;

use kernel::{Lanes, run_avx2, run_avx512};
#[cfg(test)]
use kernel::{map_points_avx2, map_points_avx512, select_points_avx2, select_points_avx512};

/// Orbits per AVX2 vector.
const LANES: usize = 8;
/// Orbits per AVX-512 vector, and the length of the per-function tables (entries past the
/// function count repeat the last function, so that either width can load them whole).
const WIDE: usize = 16;
const _: () = assert!(ORBITS_PER_CHUNK.is_multiple_of(WIDE) && LANE_FUNCTIONS <= LANES);
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
    /// Any number of cells: `vgatherdps`.
    Gather,
    /// 16 lanes (AVX-512F), ≤ 16 cells: one `vpermps`.
    Wide16,
    /// 16 lanes (AVX-512F), any number of cells: `vgatherdps`.
    WideGather,
}

const PERMUTE8: u8 = 0;
const PERMUTE16: u8 = 1;
const GATHER: u8 = 2;

impl Lookup {
    /// Whether this CPU can run the kernel with this lookup.
    pub(super) fn supported(self) -> bool {
        let level = SimdLevel::detect();
        match self {
            Lookup::Wide16 | Lookup::WideGather => level.avx512(),
            _ => level.avx2(),
        }
    }
}

/// Per-axis tables, each 8 entries indexed by function.
#[derive(Clone, Debug, PartialEq)]
struct SimdAxis {
    /// Interior boundaries to test: the most cells of any function along the axis, minus one.
    boundaries: usize,
    /// Boundary k: where cell k + 1 starts (+∞ past the function's last cell).
    next: [[f32; WIDE]; MAX_AXIS_CELLS - 1],
    /// Start coordinate and inverse width of cell i (the last cell's past the function's).
    start: [[f32; WIDE]; MAX_AXIS_CELLS],
    inv_width: [[f32; WIDE]; MAX_AXIS_CELLS],
    /// Cell index step per cell along the axis.
    stride: [i32; WIDE],
}

/// The lane kernel's data laid out for 8-wide vectors; see the module comment.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct SimdKernel {
    /// Inner cumulative thresholds minus one (r24 ≥ t ⇔ r24 > t − 1, a signed compare),
    /// padded with 2^24 − 1, which no 24-bit draw exceeds (a fixed count unrolls, branch-free).
    thresholds: [i32; LANES - 1],
    lo: [[f32; WIDE]; 3],
    hi: [[f32; WIDE]; 3],
    axes: [SimdAxis; 3],
    cell_base: [i32; WIDE],
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
        if n == 0
            || n > LANES
            || selection.cells != [1, 1, 1]
            || selection.thresholds.len() != n
            || fast.functions.iter().any(|f| f.julia)
        {
            return None;
        }
        if fast.cells.len() >= (i32::MAX as usize) / COEFS {
            return None;
        }
        let lane_fn = |k: usize| k.min(n - 1);
        let mut axes: [SimdAxis; 3] = std::array::from_fn(|_| SimdAxis {
            boundaries: 0,
            next: [[f32::INFINITY; WIDE]; MAX_AXIS_CELLS - 1],
            start: [[0.0; WIDE]; MAX_AXIS_CELLS],
            inv_width: [[0.0; WIDE]; MAX_AXIS_CELLS],
            stride: [0; WIDE],
        });
        for (a, axis) in axes.iter_mut().enumerate() {
            for l in 0..WIDE {
                let f = &fast.functions[lane_fn(l)];
                let fa = &f.axes[a];
                let cells = fa.last_cell as usize + 1;
                if cells > MAX_AXIS_CELLS {
                    return None;
                }
                let coords = &fast.coords[fa.coord_offset as usize..=fa.coord_offset as usize + cells];
                // Counting boundaries is the linear search only if they do not decrease.
                if coords.windows(2).any(|w| w[0][0].partial_cmp(&w[1][0]).is_none_or(std::cmp::Ordering::is_gt)) {
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
        let per_fn = |g: &dyn Fn(&FastFunction) -> f32| -> [f32; WIDE] {
            std::array::from_fn(|l| g(&fast.functions[lane_fn(l)]))
        };
        let cell_count = fast.cells.len();
        let lookup = if Lookup::Wide16.supported() {
            if cell_count <= 16 { Lookup::Wide16 } else { Lookup::WideGather }
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
        let coef_tables = Box::new(std::array::from_fn(|j| {
            std::array::from_fn(|c| fast.cells.get(c).filter(|_| small).map_or(0.0, |cell| cell[j]))
        }));
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
        [Lookup::Permute8, Lookup::Permute16, Lookup::Gather, Lookup::Wide16, Lookup::WideGather]
            .into_iter()
            .filter(|l| l.supported() && self.has_tables(*l))
            .collect()
    }

    /// Whether the lookup's tables exist.
    fn has_tables(&self, lookup: Lookup) -> bool {
        match lookup {
            Lookup::Permute8 => self.cells.len() <= 8,
            Lookup::Permute16 | Lookup::Wide16 => self.small,
            Lookup::Gather | Lookup::WideGather => true,
        }
    }

    /// Runs the orbits of one chunk (lane k: generator `rngs[k]`, position `pos[k]`) for
    /// `transient` discarded steps and `steps` kept ones into `sink`, as `Orbits::run` does,
    /// and leaves the generators and positions where the orbits end.
    pub(super) fn run_kept(
        &self,
        lookup: Lookup,
        rngs: &mut [u32; ORBITS_PER_CHUNK],
        pos: &mut [[f32; 3]; ORBITS_PER_CHUNK],
        transient: u32,
        steps: usize,
        sink: &mut impl PointSink,
    ) {
        assert!(lookup.supported() && self.has_tables(lookup));
        let mut state = Lanes { rng: *rngs, x: pos.map(|p| p[0]), y: pos.map(|p| p[1]), z: pos.map(|p| p[2]) };
        // SAFETY: the CPU has the features each entry point enables (asserted above), and the
        // lookup's tables exist (asserted above).
        unsafe {
            match lookup {
                Lookup::Permute8 => run_avx2::<PERMUTE8>(self, &mut state, transient, steps, sink),
                Lookup::Permute16 => run_avx2::<PERMUTE16>(self, &mut state, transient, steps, sink),
                Lookup::Gather => run_avx2::<GATHER>(self, &mut state, transient, steps, sink),
                Lookup::Wide16 => run_avx512::<PERMUTE16>(self, &mut state, transient, steps, sink),
                Lookup::WideGather => run_avx512::<GATHER>(self, &mut state, transient, steps, sink),
            }
        }
        *rngs = state.rng;
        *pos = std::array::from_fn(|k| [state.x[k], state.y[k], state.z[k]]);
    }

    /// Maps points `p[i]` by functions `fi[i]` with `lookup` (for tests); the count must be a
    /// multiple of 16.
    #[cfg(test)]
    pub(super) fn map_points(&self, lookup: Lookup, fi: &[u32], p: &[[f32; 3]]) -> Vec<[f32; 3]> {
        assert!(self.supported_lookups().contains(&lookup) && fi.len() == p.len() && p.len().is_multiple_of(WIDE));
        let mut out = vec![[0f32; 3]; p.len()];
        // SAFETY: the CPU supports the lookup and its tables exist (asserted above); the
        // slices hold whole vectors (asserted above).
        unsafe {
            match lookup {
                Lookup::Permute8 => map_points_avx2::<PERMUTE8>(self, fi, p, &mut out),
                Lookup::Permute16 => map_points_avx2::<PERMUTE16>(self, fi, p, &mut out),
                Lookup::Gather => map_points_avx2::<GATHER>(self, fi, p, &mut out),
                Lookup::Wide16 => map_points_avx512::<PERMUTE16>(self, fi, p, &mut out),
                Lookup::WideGather => map_points_avx512::<GATHER>(self, fi, p, &mut out),
            }
        }
        out
    }

    /// The functions chosen by random words `r`, by the 8-wide and by the 16-wide selection
    /// where the CPU has them (for tests); the count must be a multiple of 16.
    #[cfg(test)]
    pub(super) fn select_points(&self, r: &[u32]) -> Vec<Vec<u32>> {
        assert!(r.len().is_multiple_of(WIDE));
        let mut out = Vec::new();
        // SAFETY: each runs only where the CPU has its features; whole vectors (asserted).
        unsafe {
            if Lookup::Permute8.supported() {
                out.push(select_points_avx2(self, r));
            }
            if Lookup::Wide16.supported() {
                out.push(select_points_avx512(self, r));
            }
        }
        out
    }
}
