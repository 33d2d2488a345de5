//! Compiling an IFS into the flat tables the kernels read: per function a [`KernelFunction`],
//! per grid cell its interpolant's coefficients ([`Cell`]), the coordinate pool, and the
//! function-selection table ([`SelectionTable`], global, adaptive over a coarse grid, or by the
//! previous function with xaos).

use glam::{DVec3, Vec3};

use super::{
    ADAPTIVE_CELLS_2D, ADAPTIVE_CELLS_3D, Cell, KIND_FLAME, KIND_JULIA, KIND_MULTILINEAR, KernelFunction, SELECT_BITS,
};
use crate::model::{AffineMap, Ifs, Map, ProbabilityMode};

/// Bounds used for unbounded (affine) maps.
const UNBOUNDED: f32 = 3.0e38;

/// Function selection: rows of `n` cumulative thresholds t_0 ≤ … ≤ t_{n−1} = 2^24, the
/// function chosen by a 24-bit random r being the number of thresholds ≤ r. One row when
/// probabilities are global; a row per cell of a coarse grid over the domain when adaptive
/// (found by [`Self::cell_of`]); with xaos a row per previous function: row 0 at an orbit's
/// start, row i + 1 after compiled function i (`cells` is then 1×1×1). Mirrors the `selection`
/// buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectionTable {
    pub cells: [u32; 3],
    pub lo: Vec3,
    /// Cells per unit length per axis.
    pub inv_cell: Vec3,
    pub function_count: u32,
    pub thresholds: Vec<u32>,
    /// Whether the rows are xaos rows (by the orbit's previous function).
    pub xaos: bool,
}

impl SelectionTable {
    pub(super) fn from_probabilities(cells: [u32; 3], lo: Vec3, inv_cell: Vec3, probs: &[Vec<f64>]) -> Self {
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
        Self { cells, lo, inv_cell, function_count: n as u32, thresholds, xaos: false }
    }

    /// The row an orbit at `p` draws from, `row` being its xaos row (its previous function + 1,
    /// 0 at the start).
    #[inline(always)]
    pub fn row_of(&self, p: Vec3, row: u16) -> usize {
        if self.xaos { row as usize } else { self.cell_of(p) }
    }

    /// An orbit's xaos row after it applied compiled function `fi` (unchanged without xaos, so
    /// that every path leaves the same chains).
    #[inline(always)]
    pub fn step_row(&self, row: &mut u16, fi: usize) {
        if self.xaos {
            *row = fi as u16 + 1;
        }
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

fn to4(v: DVec3) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, 0.0]
}

pub(super) fn compile_map(map: &Map, dim: usize, coords: &mut Vec<[f32; 2]>, cells: &mut Vec<Cell>) -> KernelFunction {
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
        Map::Flame(f) => {
            // The pre-affine as an affine cell (the CPU maps the xform itself, `flame.rs`).
            let [a, b, c, d, e, g] = f.xform.coefs;
            let matrix = glam::DMat3::from_cols(DVec3::new(a, b, 0.0), DVec3::new(c, d, 0.0), DVec3::Z);
            let affine = Map::Affine(AffineMap { matrix, offset: DVec3::new(e, g, 0.0) });
            let mut k = compile_map(&affine, dim, coords, cells);
            k.coord_offset[3] = KIND_FLAME;
            k
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

pub(super) fn selection_table(ifs: &Ifs, active: &[usize], lo: Vec3, hi: Vec3) -> SelectionTable {
    let pick = |p: Vec<f64>| -> Vec<f64> { active.iter().map(|&i| p[i]).collect() };
    if ifs.probability_mode != ProbabilityMode::Adaptive && ifs.has_xaos() {
        let after = ifs.xaos_rows();
        let rows: Vec<Vec<f64>> =
            std::iter::once(ifs.probabilities()).chain(active.iter().map(|&i| after[i].clone())).map(pick).collect();
        return SelectionTable { xaos: true, ..SelectionTable::from_probabilities([1, 1, 1], lo, Vec3::ZERO, &rows) };
    }
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
