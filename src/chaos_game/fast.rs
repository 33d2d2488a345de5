//! The CPU's packed copy of the compiled IFS ([`FastKernel`]) and its cell search by bins:
//! [`CompiledIfs::map_fast`], bit-identical to [`CompiledIfs::map`] for any IFS.

use glam::Vec3;

use super::{Cell, CompiledIfs, KIND_JULIA, KernelFunction};

/// The CPU's private, packed copy of the compiled IFS: the same data with the cell search by
/// bins and 24 tightly packed coefficients per cell. Private, and checked once when built, so
/// that its hot loop can index without bounds checks (see the SAFETY notes in `map_fast`).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FastKernel {
    pub(super) functions: Vec<FastFunction>,
    pub(super) coords: Vec<[f32; 2]>,
    pub(super) bin_cells: Vec<u32>,
    pub(super) cells: Vec<[f32; 24]>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct FastFunction {
    pub(super) axes: [FastAxis; 3],
    pub(super) cell_base: u32,
    pub(super) stride_x: u32,
    pub(super) stride_y: u32,
    pub(super) julia: bool,
}

/// The CPU's cell search along one axis of one function: the axis is cut into bins no wider
/// than its narrowest cell, so a bin overlaps at most two cells; `bin_cells` gives the cell at
/// the bin's start and one comparison with the next coordinate finishes the search. Same
/// result as the linear search of [`CompiledIfs::map`] (the GPU's), without its loops.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub(super) struct FastAxis {
    pub(super) lo: f32,
    pub(super) hi: f32,
    pub(super) inv_bin: f32,
    pub(super) last_bin: f32,
    pub(super) bin_offset: u32,
    pub(super) coord_offset: u32,
    pub(super) last_cell: u32,
    /// MAX_BINS limited the bins: a bin may overlap more than two cells.
    pub(super) capped: bool,
}

/// At most this many bins per axis (finer grids fall back to a slightly larger bin; the search
/// then takes a second step in rare cases, see `locate_fast`).
const MAX_BINS: usize = 4096;

impl CompiledIfs {
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
}

impl FastKernel {
    pub(super) fn new(functions: &[KernelFunction], coords: &[[f32; 2]], cells: &[Cell]) -> Self {
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
