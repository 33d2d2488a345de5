//! Rectilinear grids and the grid-distortion maps of the paper.
//!
//! A [`RectGrid`] is the initial grid: per-axis coordinates, any count ≥ 2 on the axes in use
//! (a 2D grid has a single z coordinate), spacing not necessarily uniform. A [`GridMap`] gives a
//! transformed point for every grid point and maps any point by locating its cell, computing the
//! local coordinates u, v, w and interpolating the transformed corners bilinearly (2D) or
//! trilinearly (3D), exactly the paper's formula. Points outside the grid are clamped onto it.
//!
//! Points are `DVec3` everywhere; a 2D map has z = 0 on input and output.

use glam::{DMat3, DVec3};

/// The initial grid: sorted coordinates along x, y and z. A 2D grid has `axes[2] == [0.0]`.
#[derive(Clone, Debug, PartialEq)]
pub struct RectGrid {
    pub axes: [Vec<f64>; 3],
}

/// Where a point lies in a grid: the cell's lower corner index per axis and the local
/// coordinates in [0, 1] (0 on an axis with a single coordinate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellCoords {
    pub cell: [usize; 3],
    pub local: DVec3,
}

impl RectGrid {
    /// A grid whose axis `a` has `counts[a]` evenly spaced coordinates from `lo[a]` to `hi[a]`.
    /// A count of 1 gives the single coordinate `lo[a]` (used for z in 2D).
    pub fn uniform(lo: DVec3, hi: DVec3, counts: [usize; 3]) -> Self {
        let axis = |a: usize| -> Vec<f64> {
            let n = counts[a];
            if n <= 1 {
                return vec![lo[a]];
            }
            let span = hi[a] - lo[a];
            (0..n)
                .map(|i| {
                    let t = i as f64 / (n - 1) as f64;
                    // A span past f64's range (`[-1e308, 1e308]`) is interpolated without
                    // forming it; finite spans keep the formula that earlier output came from.
                    if span.is_finite() { lo[a] + span * t } else { lo[a] * (1.0 - t) + hi[a] * t }
                })
                .collect()
        };
        Self { axes: [axis(0), axis(1), axis(2)] }
    }

    pub fn dims(&self) -> [usize; 3] {
        [self.axes[0].len(), self.axes[1].len(), self.axes[2].len()]
    }

    /// 2 for a grid with a single z coordinate, else 3.
    pub fn dimension(&self) -> usize {
        if self.axes[2].len() == 1 { 2 } else { 3 }
    }

    pub fn point_count(&self) -> usize {
        self.dims().iter().product()
    }

    /// Index of grid point (ix, iy, iz): x outermost, z fastest, as in the paper's tables.
    #[inline]
    pub fn index(&self, ix: usize, iy: usize, iz: usize) -> usize {
        let [_, ny, nz] = self.dims();
        (ix * ny + iy) * nz + iz
    }

    pub fn point(&self, ix: usize, iy: usize, iz: usize) -> DVec3 {
        DVec3::new(self.axes[0][ix], self.axes[1][iy], self.axes[2][iz])
    }

    /// All grid points in index order.
    pub fn points(&self) -> Vec<DVec3> {
        let [nx, ny, nz] = self.dims();
        let mut out = Vec::with_capacity(nx * ny * nz);
        for ix in 0..nx {
            for iy in 0..ny {
                for iz in 0..nz {
                    out.push(self.point(ix, iy, iz));
                }
            }
        }
        out
    }

    pub fn min(&self) -> DVec3 {
        DVec3::new(self.axes[0][0], self.axes[1][0], self.axes[2][0])
    }

    pub fn max(&self) -> DVec3 {
        DVec3::new(
            *self.axes[0].last().unwrap_or(&0.0),
            *self.axes[1].last().unwrap_or(&0.0),
            *self.axes[2].last().unwrap_or(&0.0),
        )
    }

    /// Whether `p` lies in the grid's box, with an absolute slack of `tol`.
    pub fn contains(&self, p: DVec3, tol: f64) -> bool {
        let (lo, hi) = (self.min(), self.max());
        (0..self.dimension()).all(|a| p[a] >= lo[a] - tol && p[a] <= hi[a] + tol)
    }

    /// The cell containing `p` after clamping `p` onto the grid, with local coordinates.
    pub fn locate(&self, p: DVec3) -> CellCoords {
        let mut cell = [0usize; 3];
        let mut local = DVec3::ZERO;
        for a in 0..3 {
            let xs = &self.axes[a];
            if xs.len() < 2 {
                continue;
            }
            // max/min rather than clamp: clamp panics on NaN bounds, and a NaN point lands on
            // the grid's first corner instead of poisoning the cell search.
            let x = p[a].max(xs[0]).min(xs[xs.len() - 1]);
            // Largest i with xs[i] <= x, kept to a valid cell index.
            let i = xs.partition_point(|&c| c <= x).saturating_sub(1).min(xs.len() - 2);
            cell[a] = i;
            local[a] = ((x - xs[i]) / (xs[i + 1] - xs[i])).clamp(0.0, 1.0);
        }
        CellCoords { cell, local }
    }

    /// Number of cells per axis (0 on a single-coordinate axis, which has no extent).
    pub fn cell_counts(&self) -> [usize; 3] {
        self.dims().map(|n| n.saturating_sub(1))
    }

    /// Checks the invariants the model relies on; the message names the offending axis.
    pub fn validate(&self) -> Result<(), String> {
        for (a, name) in ["x", "y", "z"].iter().enumerate() {
            let xs = &self.axes[a];
            let need = if a == 2 { 1 } else { 2 };
            if xs.len() < need {
                return Err(format!("axis {name} needs at least {need} coordinates"));
            }
            if xs.iter().any(|x| !x.is_finite()) {
                return Err(format!("axis {name} has a non-finite coordinate"));
            }
            if let Some(w) = xs.windows(2).find(|w| w[1] <= w[0]) {
                return Err(format!("axis {name} must increase strictly, but {} is followed by {}", w[0], w[1]));
            }
            // Cell widths and the extent are divided by and interpolated over; past f64's range
            // they become infinite and every point built on them NaN.
            if xs.len() >= 2 && !(xs[xs.len() - 1] - xs[0]).is_finite() {
                return Err(format!(
                    "axis {name} spans {:e} to {:e}, a width past the largest number (about 1.8e308); use a smaller extent",
                    xs[0],
                    xs[xs.len() - 1]
                ));
            }
        }
        Ok(())
    }
}

/// A grid-distortion function: the initial grid and a transformed point per grid point.
#[derive(Clone, Debug, PartialEq)]
pub struct GridMap {
    pub grid: RectGrid,
    /// Transformed grid points, indexed like [`RectGrid::index`].
    pub points: Vec<DVec3>,
}

/// The corner offsets of a cell, in the order the interpolation visits them.
const CORNERS: [[usize; 3]; 8] =
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]];

impl GridMap {
    pub fn new(grid: RectGrid, points: Vec<DVec3>) -> Self {
        debug_assert_eq!(grid.point_count(), points.len());
        Self { grid, points }
    }

    /// The identity: every grid point maps to itself.
    pub fn identity(grid: RectGrid) -> Self {
        let points = grid.points();
        Self { grid, points }
    }

    /// Samples any point map onto the grid.
    pub fn from_fn(grid: RectGrid, f: impl FnMut(DVec3) -> DVec3) -> Self {
        let points = grid.points().into_iter().map(f).collect();
        Self { grid, points }
    }

    fn corners_used(&self) -> &'static [[usize; 3]] {
        if self.grid.dimension() == 2 { &CORNERS[..4] } else { &CORNERS[..] }
    }

    /// The transformed corner of cell `cell` at offset `o`.
    #[inline]
    fn corner(&self, cell: [usize; 3], o: [usize; 3]) -> DVec3 {
        let [nx, ny, nz] = self.grid.dims();
        let ix = (cell[0] + o[0]).min(nx - 1);
        let iy = (cell[1] + o[1]).min(ny - 1);
        let iz = (cell[2] + o[2]).min(nz - 1);
        self.points[self.grid.index(ix, iy, iz)]
    }

    /// The paper's interpolation: P' = Σ corners · Π (u or 1 − u).
    pub fn eval(&self, p: DVec3) -> DVec3 {
        let CellCoords { cell, local } = self.grid.locate(p);
        let mut out = DVec3::ZERO;
        for &o in self.corners_used() {
            let weight = (0..3).map(|a| if o[a] == 1 { local[a] } else { 1.0 - local[a] }).product::<f64>();
            out += weight * self.corner(cell, o);
        }
        out
    }

    /// Jacobian ∂P'/∂P at `p` (columns: derivatives along x, y, z). Inside a cell it is the
    /// derivative of the interpolant; on a face, that of the cell `locate` picks. The z column
    /// of a 2D map is zero.
    pub fn jacobian(&self, p: DVec3) -> DMat3 {
        let CellCoords { cell, local } = self.grid.locate(p);
        let mut cols = [DVec3::ZERO; 3];
        for (a, col) in cols.iter_mut().enumerate().take(self.grid.dimension()) {
            let width = self.grid.axes[a][cell[a] + 1] - self.grid.axes[a][cell[a]];
            for &o in self.corners_used() {
                let mut weight = if o[a] == 1 { 1.0 } else { -1.0 };
                for b in 0..3 {
                    if b != a {
                        weight *= if o[b] == 1 { local[b] } else { 1.0 - local[b] };
                    }
                }
                *col += weight * self.corner(cell, o) / width;
            }
        }
        DMat3::from_cols(cols[0], cols[1], cols[2])
    }

    /// The edge vectors of cell `cell` along axis `a`, each divided by the cell's width along
    /// `a`: 4 of them in 3D, 2 in 2D (the rest of the array is unused).
    fn scaled_edges(&self, cell: [usize; 3], a: usize) -> ([DVec3; 4], usize) {
        let width = self.grid.axes[a][cell[a] + 1] - self.grid.axes[a][cell[a]];
        let mut out = [DVec3::ZERO; 4];
        let mut n = 0;
        for &o in self.corners_used().iter().filter(|o| o[a] == 0) {
            let mut o1 = o;
            o1[a] = 1;
            out[n] = (self.corner(cell, o1) - self.corner(cell, o)) / width;
            n += 1;
        }
        (out, n)
    }

    /// A guaranteed upper bound of the Lipschitz constant (Euclidean norm) of this map on the
    /// cells whose index ranges are `cells[a]` (inclusive).
    ///
    /// Why it is an upper bound: inside a cell, column `a` of the Jacobian is a convex
    /// combination (weights from the other local coordinates) of the cell's edge vectors along
    /// `a` divided by the cell width. So every Jacobian of the cell lies in the convex hull of
    /// the matrices formed by picking one scaled edge per column (4³ = 64 in 3D, 2² = 4 in 2D).
    /// The spectral norm is convex, so its maximum over that hull is attained at one of those
    /// vertex matrices; we take the exact maximum over them (with a relative safety margin for
    /// rounding). The map is continuous and piecewise smooth on the convex grid box, so its
    /// Lipschitz constant there is the supremum of the Jacobian norm; clamping outside the box
    /// is a projection onto a convex set and does not increase distances. Hence the bound holds
    /// for all pairs of points in space.
    ///
    /// A 64³ grid has 250 000 cells of 64 matrices each, so the slabs of cells along x are
    /// spread over threads; the maximum does not depend on the order, so the result is the
    /// same on any number of threads.
    pub fn lipschitz_bound_cells(&self, cells: [std::ops::RangeInclusive<usize>; 3]) -> f64 {
        use rayon::prelude::*;
        let dim = self.grid.dimension();
        let slab = |cx: usize| {
            let mut best = 0.0f64;
            for cy in cells[1].clone() {
                for cz in cells[2].clone() {
                    let cell = [cx, cy, cz];
                    let (ex, nx) = self.scaled_edges(cell, 0);
                    let (ey, ny) = self.scaled_edges(cell, 1);
                    let (ez, nz) = if dim == 3 { self.scaled_edges(cell, 2) } else { ([DVec3::ZERO; 4], 1) };
                    for &a in &ex[..nx] {
                        for &b in &ey[..ny] {
                            for &c in &ez[..nz] {
                                best = best.max(spectral_norm_bound(DMat3::from_cols(a, b, c)));
                            }
                        }
                    }
                }
            }
            best
        };
        cells[0].clone().into_par_iter().map(slab).reduce(|| 0.0, f64::max)
    }

    /// [`Self::lipschitz_bound_cells`] over the whole grid.
    pub fn lipschitz_bound(&self) -> f64 {
        let cells = self.grid.cell_counts().map(|n| 0..=n.saturating_sub(1));
        self.lipschitz_bound_cells(cells)
    }

    /// The same bound restricted to the cells that the box [lo, hi] touches (after clamping).
    pub fn lipschitz_bound_in_box(&self, lo: DVec3, hi: DVec3) -> f64 {
        let a = self.grid.locate(lo).cell;
        let b = self.grid.locate(hi).cell;
        // A box face lying exactly on a cell face also touches the cell below it.
        let lo_cells = [0, 1, 2].map(|k| {
            let xs = &self.grid.axes[k];
            if xs.len() >= 2 && a[k] > 0 && lo[k] <= xs[a[k]] { a[k] - 1 } else { a[k] }
        });
        self.lipschitz_bound_cells([0, 1, 2].map(|k| lo_cells[k]..=b[k]))
    }

    /// The paper's figure-8 contractivity measure: the largest ratio of a transformed grid
    /// edge's length to the original edge's length, over all edges between neighbouring grid
    /// points.
    pub fn grid_ratio(&self) -> f64 {
        let [nx, ny, nz] = self.grid.dims();
        let mut best = 0.0f64;
        for ix in 0..nx {
            for iy in 0..ny {
                for iz in 0..nz {
                    let i = self.grid.index(ix, iy, iz);
                    for (jx, jy, jz) in [(ix + 1, iy, iz), (ix, iy + 1, iz), (ix, iy, iz + 1)] {
                        if jx >= nx || jy >= ny || jz >= nz {
                            continue;
                        }
                        let j = self.grid.index(jx, jy, jz);
                        let before = self.grid.point(ix, iy, iz).distance(self.grid.point(jx, jy, jz));
                        let after = self.points[i].distance(self.points[j]);
                        best = best.max(after / before);
                    }
                }
            }
        }
        best
    }

    /// Transformed grid points outside the initial grid's box (index and position). The image
    /// of the box lies in the convex hull of the transformed points, so an empty list means the
    /// whole image is contained.
    pub fn outside_points(&self, tol: f64) -> Vec<(usize, DVec3)> {
        self.points.iter().enumerate().filter(|(_, p)| !self.grid.contains(**p, tol)).map(|(i, p)| (i, *p)).collect()
    }

    /// Mean of |det J| over the cell centres, weighted by cell volume: the map's mean volume
    /// (area in 2D) ratio.
    pub fn mean_volume_ratio(&self) -> f64 {
        let dim = self.grid.dimension();
        let counts = self.grid.cell_counts();
        let (mut sum, mut total) = (0.0, 0.0);
        for cx in 0..counts[0] {
            for cy in 0..counts[1] {
                for cz in 0..counts[2].max(1) {
                    let c = [cx, cy, cz];
                    let mut centre = DVec3::ZERO;
                    let mut vol = 1.0;
                    for a in 0..dim {
                        let (x0, x1) = (self.grid.axes[a][c[a]], self.grid.axes[a][c[a] + 1]);
                        centre[a] = 0.5 * (x0 + x1);
                        vol *= x1 - x0;
                    }
                    sum += vol * volume_ratio(self.jacobian(centre), dim);
                    total += vol;
                }
            }
        }
        sum / total
    }
}

/// |det J| of the block that a `dim`-dimensional map uses.
pub fn volume_ratio(j: DMat3, dim: usize) -> f64 {
    if dim == 2 { (j.x_axis.x * j.y_axis.y - j.y_axis.x * j.x_axis.y).abs() } else { j.determinant().abs() }
}

/// An upper bound of the spectral norm of `m`: the exact largest eigenvalue of mᵀm from the
/// closed form for symmetric 3×3 matrices, never above the Gershgorin bound (which is itself an
/// upper bound), square-rooted and raised by a relative margin far above f64 rounding.
pub fn spectral_norm_bound(m: DMat3) -> f64 {
    let a = m.transpose() * m;
    let gershgorin = (0..3).map(|r| (0..3).map(|c| a.col(c)[r].abs()).sum::<f64>()).fold(0.0, f64::max);
    let lambda = symmetric_max_eigenvalue(a).min(gershgorin);
    lambda.max(0.0).sqrt() * (1.0 + 1e-9) + 1e-300
}

/// Largest eigenvalue of a symmetric 3×3 matrix (trigonometric closed form).
fn symmetric_max_eigenvalue(a: DMat3) -> f64 {
    let (a11, a22, a33) = (a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let (a12, a13, a23) = (a.y_axis.x, a.z_axis.x, a.z_axis.y);
    let p1 = a12 * a12 + a13 * a13 + a23 * a23;
    if p1 == 0.0 {
        return a11.max(a22).max(a33);
    }
    let q = (a11 + a22 + a33) / 3.0;
    let p2 = (a11 - q).powi(2) + (a22 - q).powi(2) + (a33 - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = (a - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    q + 2.0 * p * phi.cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    fn random_in(r: &mut Pcg32, lo: DVec3, hi: DVec3) -> DVec3 {
        DVec3::new(
            lo.x + (hi.x - lo.x) * r.next_f32() as f64,
            lo.y + (hi.y - lo.y) * r.next_f32() as f64,
            lo.z + (hi.z - lo.z) * r.next_f32() as f64,
        )
    }

    /// A non-uniform 3D grid used by several tests.
    fn skew_grid() -> RectGrid {
        RectGrid { axes: [vec![-1.0, 0.2, 3.0], vec![0.0, 1.0, 1.5, 4.0], vec![2.0, 2.5, 5.0]] }
    }

    fn warped(grid: RectGrid, seed: u32) -> GridMap {
        let mut r = Pcg32::for_stream(seed, 0, 0);
        GridMap::from_fn(grid, |p| 0.4 * p + DVec3::new(r.next_f32() as f64, r.next_f32() as f64, r.next_f32() as f64))
    }

    #[test]
    fn undistorted_grid_is_identity() {
        let map = GridMap::identity(skew_grid());
        let mut r = Pcg32::for_stream(1, 0, 0);
        for _ in 0..1000 {
            let p = random_in(&mut r, map.grid.min(), map.grid.max());
            assert!(map.eval(p).distance(p) < 1e-12);
        }
    }

    #[test]
    fn affine_grid_reproduces_affine_map() {
        let m = DMat3::from_cols_array(&[0.3, 0.1, -0.2, 0.05, 0.5, 0.1, 0.2, -0.1, 0.4]);
        let t = DVec3::new(1.0, -2.0, 0.5);
        let map = GridMap::from_fn(skew_grid(), |p| m * p + t);
        let mut r = Pcg32::for_stream(2, 0, 0);
        for _ in 0..1000 {
            let p = random_in(&mut r, map.grid.min(), map.grid.max());
            assert!(map.eval(p).distance(m * p + t) < 1e-12, "at {p}");
            // The Jacobian of an affine map is its matrix.
            assert!((map.jacobian(p) - m).abs_diff_eq(DMat3::ZERO, 1e-12));
        }
        // And its Lipschitz bound is the matrix's spectral norm.
        let norm = spectral_norm_bound(m);
        assert!((map.lipschitz_bound() - norm).abs() < 1e-9 * norm);
    }

    #[test]
    fn grid_points_map_exactly() {
        let map = warped(skew_grid(), 3);
        for (i, p) in map.grid.points().into_iter().enumerate() {
            assert_eq!(map.eval(p), map.points[i], "grid point {i}");
        }
    }

    #[test]
    fn continuous_across_cell_faces() {
        let map = warped(skew_grid(), 4);
        let mut r = Pcg32::for_stream(4, 0, 0);
        for a in 0..3 {
            for &face in &map.grid.axes[a][1..map.grid.axes[a].len() - 1] {
                for _ in 0..100 {
                    let mut p = random_in(&mut r, map.grid.min(), map.grid.max());
                    p[a] = face;
                    let (mut below, mut above) = (p, p);
                    below[a] -= 1e-9;
                    above[a] += 1e-9;
                    // Lipschitz: the two sides differ by at most L * 2e-9.
                    let gap = map.eval(below).distance(map.eval(above));
                    assert!(gap <= map.lipschitz_bound() * 2e-9 + 1e-12, "axis {a} gap {gap}");
                }
            }
        }
    }

    #[test]
    fn lipschitz_bound_never_exceeded() {
        for seed in 0..20u32 {
            let map = warped(skew_grid(), 100 + seed);
            let bound = map.lipschitz_bound();
            let mut r = Pcg32::for_stream(seed, 1, 0);
            let (lo, hi) = (map.grid.min() - 1.0, map.grid.max() + 1.0);
            for _ in 0..2000 {
                let p = random_in(&mut r, lo, hi);
                // Near pairs probe the local Jacobian; far pairs the global behaviour.
                let q = if r.next_u32().is_multiple_of(2) {
                    p + (random_in(&mut r, DVec3::splat(-1.0), DVec3::splat(1.0)) * 1e-3)
                } else {
                    random_in(&mut r, lo, hi)
                };
                let ratio = map.eval(p).distance(map.eval(q)) / p.distance(q);
                assert!(ratio <= bound, "seed {seed}: ratio {ratio} > bound {bound}");
            }
        }
    }

    #[test]
    fn lipschitz_bound_is_attained_by_an_affine_cell() {
        // For a single-cell affine map the bound is exact, not just an upper bound.
        let grid = RectGrid::uniform(DVec3::ZERO, DVec3::ONE, [2, 2, 2]);
        let map = GridMap::from_fn(grid, |p| DVec3::new(0.5 * p.x, 0.25 * p.y, 0.1 * p.z));
        assert!((map.lipschitz_bound() - 0.5).abs() < 1e-8);
    }

    #[test]
    fn bilinear_2d() {
        let grid = RectGrid { axes: [vec![0.0, 1.0], vec![0.0, 2.0], vec![0.0]] };
        let map = GridMap::new(
            grid,
            vec![DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(2.0, 2.0, 0.0)],
        );
        // u = 0.5, v = 0.5: the mean of the four corners.
        assert!(map.eval(DVec3::new(0.5, 1.0, 0.0)).distance(DVec3::new(0.75, 0.75, 0.0)) < 1e-12);
        assert_eq!(map.grid.dimension(), 2);
    }

    #[test]
    fn clamps_outside_points() {
        let map = warped(skew_grid(), 5);
        let inside = map.grid.max();
        assert_eq!(map.eval(inside + 10.0), map.eval(inside));
    }
}
