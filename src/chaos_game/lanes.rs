//! The lane kernel: the CPU's fastest portable chaos-game step, for the common case (few
//! multilinear or affine functions with global probabilities), specialized per set of axes with
//! more than one cell. Bit-identical to [`CompiledIfs::map`].

use glam::Vec3A;

#[cfg(doc)]
use super::CompiledIfs;
use super::compile::SelectionTable;
use super::fast::{FastAxis, FastKernel};
use super::{Cell, SELECT_BITS};

/// Most functions the lane kernel handles.
pub(super) const LANE_FUNCTIONS: usize = 8;
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
pub(super) struct LaneKernel {
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
    pub(super) multi: [bool; 3],
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

impl LaneKernel {
    /// The lane kernel of `fast`, or None when the IFS needs the general path.
    pub(super) fn new(fast: &FastKernel, selection: &SelectionTable, cells: &[Cell]) -> Option<Self> {
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
    pub(super) fn select(&self, r: u32) -> usize {
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
    pub(super) fn map<const MX: bool, const MY: bool, const MZ: bool>(&self, fi: usize, p: Vec3A) -> Vec3A {
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
    pub(super) fn map_any(&self, fi: usize, p: Vec3A) -> Vec3A {
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
