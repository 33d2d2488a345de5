//! The IFS model: functions (grid distortions, affine maps, the Julia pair), their
//! contractivity and containment, and the choice of probabilities.
//!
//! An [`Ifs`] is resolved: builders and animation keys have been evaluated into plain maps. The
//! scene (`crate::scene`) keeps the editable parameters and produces an `Ifs` for a given time.

pub mod builder;
pub mod fit;
pub mod flame_map;
pub mod grid;
pub mod nesting;

pub use flame_map::FlameMap;
use glam::{DMat3, DVec3};
pub use grid::{GridMap, RectGrid};

/// w(p) = matrix * p + offset. A 2D map has zeros in the z row and column.
#[derive(Clone, Debug, PartialEq)]
pub struct AffineMap {
    pub matrix: DMat3,
    pub offset: DVec3,
}

/// One of the Julia pair w±(z) = ±√(z − c) in the complex plane (x + iy).
#[derive(Clone, Debug, PartialEq)]
pub struct JuliaMap {
    pub c: [f64; 2],
    /// +1 or −1.
    pub sign: f64,
}

impl JuliaMap {
    pub fn eval(&self, p: DVec3) -> DVec3 {
        let (re, im) = complex_sqrt(p.x - self.c[0], p.y - self.c[1]);
        DVec3::new(self.sign * re, self.sign * im, 0.0)
    }
}

/// Principal square root of re + i·im (non-negative real part).
pub fn complex_sqrt(re: f64, im: f64) -> (f64, f64) {
    let r = (re * re + im * im).sqrt();
    let a = ((r + re) * 0.5).max(0.0).sqrt();
    let b = ((r - re) * 0.5).max(0.0).sqrt();
    (a, if im < 0.0 { -b } else { b })
}

#[derive(Clone, Debug, PartialEq)]
pub enum Map {
    Grid(GridMap),
    Affine(AffineMap),
    Julia(JuliaMap),
    /// One of flam3's xforms (`flame_map.rs`).
    Flame(FlameMap),
}

impl Map {
    pub fn eval(&self, p: DVec3) -> DVec3 {
        match self {
            Map::Grid(g) => g.eval(p),
            Map::Affine(a) => a.matrix * p + a.offset,
            Map::Julia(j) => j.eval(p),
            Map::Flame(f) => f.eval(p),
        }
    }

    /// The function's `kind` as the scene file and `nlifs info` name it.
    pub fn kind(&self) -> &'static str {
        match self {
            Map::Grid(_) => "grid",
            Map::Affine(_) => "affine",
            Map::Julia(_) => "julia",
            Map::Flame(_) => "flame",
        }
    }

    /// Figure-8 measure (see [`GridMap::grid_ratio`]); for an affine map the same measure on
    /// any grid, the longest image of a unit axis vector. None for the Julia maps, whose
    /// derivative is unbounded near c, and for flames.
    pub fn grid_ratio(&self, dim: usize) -> Option<f64> {
        match self {
            Map::Grid(g) => Some(g.grid_ratio()),
            Map::Affine(a) => Some((0..dim).map(|k| a.matrix.col(k).length()).fold(0.0, f64::max)),
            Map::Julia(_) | Map::Flame(_) => None,
        }
    }

    /// Guaranteed upper bound of the Lipschitz constant, or None where the map has none.
    pub fn lipschitz_bound(&self) -> Option<f64> {
        match self {
            Map::Grid(g) => Some(g.lipschitz_bound()),
            Map::Affine(a) => Some(grid::spectral_norm_bound(a.matrix)),
            Map::Julia(_) | Map::Flame(_) => None,
        }
    }

    /// Upper bound of the Lipschitz constant on the box [lo, hi] (global for affine maps).
    pub fn lipschitz_bound_in_box(&self, lo: DVec3, hi: DVec3) -> Option<f64> {
        match self {
            Map::Grid(g) => Some(g.lipschitz_bound_in_box(lo, hi)),
            _ => self.lipschitz_bound(),
        }
    }

    /// Local volume (area in 2D) ratio |det J| at `p`.
    pub fn volume_ratio_at(&self, p: DVec3, dim: usize) -> f64 {
        match self {
            Map::Grid(g) => grid::volume_ratio(g.jacobian(p), dim),
            Map::Affine(a) => grid::volume_ratio(a.matrix, dim),
            Map::Julia(j) => {
                // |d/dz sqrt(z - c)|² = 1 / (4 |z - c|)
                let r = ((p.x - j.c[0]).powi(2) + (p.y - j.c[1]).powi(2)).sqrt();
                1.0 / (4.0 * r.max(1e-12))
            }
            Map::Flame(f) => f.volume_ratio_at(p),
        }
    }

    /// Mean volume ratio over the domain.
    pub fn mean_volume_ratio(&self, domain: &RectGrid) -> f64 {
        let dim = domain.dimension();
        match self {
            Map::Grid(g) => g.mean_volume_ratio(),
            Map::Affine(a) => grid::volume_ratio(a.matrix, dim),
            Map::Julia(_) => 0.5, // the pair splits the plane's measure evenly
            Map::Flame(f) => f.mean_volume_ratio(domain.min(), domain.max()),
        }
    }
}

/// A function of the IFS with its presentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Function {
    pub name: String,
    pub map: Map,
    /// Linear RGB in [0, 1].
    pub color: [f32; 3],
    /// Explicit weight from the scene, if any.
    pub weight: Option<f64>,
    pub enabled: bool,
    /// Xaos: the multipliers of the next function's probability after this one, by function
    /// index (entries missing are 1; empty: none), as flam3's `chaos` row.
    pub xaos: Vec<f64>,
}

/// How the chaos game picks functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ProbabilityMode {
    /// The scene's `probability` per function, normalized.
    Explicit,
    /// From contractivity: p_i ∝ s_i^D with s_i the mean linear scale of function i and D the
    /// similarity dimension (Σ s_i^D = 1), so less contractive functions get more.
    #[default]
    Contractivity,
    /// Locally adaptive (after Peitgen and Saupe's modified inverse iteration): the same rule
    /// evaluated with the local scale at the current point, tabulated on a coarse grid.
    Adaptive,
}

impl ProbabilityMode {
    pub fn name(self) -> &'static str {
        match self {
            ProbabilityMode::Explicit => "explicit",
            ProbabilityMode::Contractivity => "contractivity",
            ProbabilityMode::Adaptive => "adaptive",
        }
    }
}

/// A resolved IFS.
#[derive(Clone, Debug, PartialEq)]
pub struct Ifs {
    /// The initial grid of the IFS; its box is the domain that contractive functions must map
    /// into themselves.
    pub domain: RectGrid,
    pub functions: Vec<Function>,
    pub probability_mode: ProbabilityMode,
    /// flam3's final xform: maps each drawn point, not the orbit (`chaos_game/flame.rs`); its
    /// `color` is its colour coordinate c_f.
    pub final_xform: Option<crate::flame::Xform>,
}

/// Per-function figures reported by `nlifs info`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FunctionReport {
    pub name: String,
    pub kind: &'static str,
    pub grid_ratio: Option<f64>,
    pub lipschitz_bound: Option<f64>,
    pub contained: Option<bool>,
    /// Transformed grid points (or box corners) outside the domain: index and position.
    pub outside: Vec<(usize, [f64; 3])>,
    pub probability: f64,
    /// The share of the points it draws in the long run ([`Ifs::long_run_shares`]; the
    /// probability without xaos).
    pub share: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct IfsReport {
    pub dimension: usize,
    pub probability_mode: &'static str,
    pub functions: Vec<FunctionReport>,
    pub max_grid_ratio: Option<f64>,
    pub max_lipschitz_bound: Option<f64>,
    pub all_contained: Option<bool>,
    /// Whether the functions are drawn by xaos rows (then `share` differs from `probability`).
    pub xaos: bool,
}

/// Relative slack of the containment test: the paper's tables are printed to 0.01.
pub const CONTAINMENT_TOL_REL: f64 = 1e-9;

impl Ifs {
    pub fn dimension(&self) -> usize {
        self.domain.dimension()
    }

    /// Indices of the enabled functions.
    pub fn active(&self) -> Vec<usize> {
        (0..self.functions.len()).filter(|&i| self.functions[i].enabled).collect()
    }

    fn containment_tol(&self) -> f64 {
        CONTAINMENT_TOL_REL * (self.domain.max() - self.domain.min()).length().max(1.0)
    }

    /// Points of function `i`'s image that leave the domain box (grid points for grid maps, box
    /// corners for affine maps); None for the Julia maps and flames, which are not box-to-box
    /// maps.
    pub fn outside_points(&self, i: usize) -> Option<Vec<(usize, DVec3)>> {
        let tol = self.containment_tol();
        match &self.functions[i].map {
            Map::Grid(g) => {
                let mut out = g.outside_points(tol);
                out.retain(|(_, p)| !self.domain.contains(*p, tol));
                Some(out)
            }
            Map::Affine(a) => {
                let corners = RectGrid::uniform(
                    self.domain.min(),
                    self.domain.max(),
                    [2, 2, if self.dimension() == 3 { 2 } else { 1 }],
                );
                Some(
                    corners
                        .points()
                        .into_iter()
                        .enumerate()
                        .map(|(k, p)| (k, a.matrix * p + a.offset))
                        .filter(|(_, p)| !self.domain.contains(*p, tol))
                        .collect(),
                )
            }
            Map::Julia(_) | Map::Flame(_) => None,
        }
    }

    /// Normalized probabilities of the functions (0 for disabled ones) under the global rule of
    /// the probability mode (adaptive mode: the global rule, as the fallback and the report).
    pub fn probabilities(&self) -> Vec<f64> {
        let active = self.active();
        let mut p = vec![0.0; self.functions.len()];
        if active.is_empty() {
            return p;
        }
        let explicit = self.probability_mode == ProbabilityMode::Explicit;
        if explicit {
            for &i in &active {
                p[i] = self.functions[i].weight.unwrap_or(0.0).max(0.0);
            }
        } else {
            let dim = self.dimension() as f64;
            let scales: Vec<f64> =
                active.iter().map(|&i| self.functions[i].map.mean_volume_ratio(&self.domain).powf(1.0 / dim)).collect();
            let d = similarity_dimension(&scales, dim);
            for (k, &i) in active.iter().enumerate() {
                p[i] = scales[k].powf(d);
            }
            apply_floor(&mut p, &active);
        }
        normalize(&mut p, &active);
        p
    }

    /// Whether an enabled function's xaos row weights an enabled function by other than 1.
    pub fn has_xaos(&self) -> bool {
        let active = self.active();
        active
            .iter()
            .filter(|&&i| !self.functions[i].xaos.is_empty())
            .any(|&i| active.iter().any(|&j| (self.xaos_entry(i, j) - 1.0).abs() > 1e-10))
    }

    /// Function `i`'s xaos multiplier of function `j` (1 where its row has no entry; negative
    /// and NaN entries count as 0).
    pub fn xaos_entry(&self, i: usize, j: usize) -> f64 {
        self.functions[i].xaos.get(j).copied().unwrap_or(1.0).max(0.0)
    }

    /// Which functions may follow which (source indices): `[i][j]` where function j's xaos
    /// multiplier in i's row is above 0, or where i's row leaves nothing to draw (then drawn as
    /// without xaos, [`Self::xaos_rows`]). The probabilities aside, as W^n takes every function:
    /// the deterministic sets keep only such compositions. None without xaos: any may follow any.
    pub fn xaos_successors(&self) -> Option<Vec<Vec<bool>>> {
        if !self.has_xaos() {
            return None;
        }
        let n = self.functions.len();
        let (p, active) = (self.probabilities(), self.active());
        let successors = (0..n)
            .map(|i| {
                let falls_back = !self.xaos_row_draws(i, &p, &active);
                (0..n).map(|j| falls_back || self.xaos_entry(i, j) > 0.0).collect()
            })
            .collect();
        Some(successors)
    }

    /// Whether function i's xaos row leaves something to draw under the probabilities `p`.
    fn xaos_row_draws(&self, i: usize, p: &[f64], active: &[usize]) -> bool {
        active.iter().any(|&j| p[j] * self.xaos_entry(i, j) > 0.0)
    }

    /// The enabled functions an orbit keeps applying (source indices): those with an endless
    /// chain of enabled predecessors under `successors` ([`Self::xaos_successors`]). Without
    /// xaos every enabled function; a function that only the start can draw (no function may
    /// precede it, or only such functions) leaves no copy in the attractor.
    pub fn recurrent_functions(&self, successors: Option<&[Vec<bool>]>) -> Vec<usize> {
        let mut live = self.active();
        let Some(successors) = successors else { return live };
        loop {
            let before = live.len();
            let kept: Vec<usize> = live.iter().copied().filter(|&j| live.iter().any(|&i| successors[i][j])).collect();
            live = kept;
            if live.len() == before {
                return live;
            }
        }
    }

    /// The share of the points each function draws in the long run (source indices): with
    /// xaos the stationary distribution of the chain of functions an orbit runs through from
    /// its start (found by iterating the lazy chain, (P + I) / 2, which has the same one and
    /// settles even where the rows make the chain periodic); without, the probabilities.
    pub fn long_run_shares(&self) -> Vec<f64> {
        let start = self.probabilities();
        if !self.has_xaos() {
            return start;
        }
        let n = self.functions.len();
        let rows = self.xaos_rows();
        let mut share = start;
        // At most about 2·10^7 multiply-adds (a few milliseconds); a typical IFS settles to
        // 10⁻¹² in a few hundred rounds.
        for _ in 0..(20_000_000 / (n * n).max(1)).clamp(1, 20_000) {
            let next: Vec<f64> =
                (0..n).map(|j| 0.5 * share[j] + 0.5 * (0..n).map(|i| share[i] * rows[i][j]).sum::<f64>()).collect();
            let change = next.iter().zip(&share).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            share = next;
            if change < 1e-12 {
                break;
            }
        }
        share
    }

    /// The chaos game's rows (source indices): row i, entry j the chance that function j
    /// follows function i, `xaos_entry(i, j)` · p_j normalized; a row that leaves nothing to
    /// draw is the probabilities alone, as if function i had no xaos.
    pub fn xaos_rows(&self) -> Vec<Vec<f64>> {
        let (base, active) = (self.probabilities(), self.active());
        (0..self.functions.len())
            .map(|i| {
                if !self.xaos_row_draws(i, &base, &active) {
                    return base.clone();
                }
                let mut p: Vec<f64> = base.iter().enumerate().map(|(j, &pj)| pj * self.xaos_entry(i, j)).collect();
                normalize(&mut p, &active);
                p
            })
            .collect()
    }

    /// The adaptive rule at point `q`: p_i ∝ (|det J_i(q)|^(1/d))^D with the global D.
    pub fn local_probabilities(&self, q: DVec3, global_dimension: f64) -> Vec<f64> {
        let active = self.active();
        let dim = self.dimension();
        let mut p = vec![0.0; self.functions.len()];
        for &i in &active {
            let s = self.functions[i].map.volume_ratio_at(q, dim).powf(1.0 / dim as f64);
            p[i] = s.powf(global_dimension);
        }
        apply_floor(&mut p, &active);
        normalize(&mut p, &active);
        p
    }

    /// The similarity dimension D of the active functions' mean scales.
    pub fn similarity_dimension(&self) -> f64 {
        let dim = self.dimension() as f64;
        let scales: Vec<f64> = self
            .active()
            .iter()
            .map(|&i| self.functions[i].map.mean_volume_ratio(&self.domain).powf(1.0 / dim))
            .collect();
        similarity_dimension(&scales, dim)
    }

    pub fn report(&self) -> IfsReport {
        let dim = self.dimension();
        let probabilities = self.probabilities();
        let shares = self.long_run_shares();
        let functions: Vec<FunctionReport> = self
            .functions
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let outside = self.outside_points(i);
                FunctionReport {
                    name: f.name.clone(),
                    kind: f.map.kind(),
                    grid_ratio: f.map.grid_ratio(dim),
                    lipschitz_bound: f.map.lipschitz_bound(),
                    contained: outside.as_ref().map(|o| o.is_empty()),
                    outside: outside.unwrap_or_default().into_iter().map(|(k, p)| (k, p.to_array())).collect(),
                    probability: probabilities[i],
                    share: shares[i],
                }
            })
            .collect();
        let max_opt =
            |v: Vec<Option<f64>>| -> Option<f64> { v.into_iter().try_fold(0.0f64, |m, x| x.map(|x| m.max(x))) };
        IfsReport {
            dimension: dim,
            probability_mode: self.probability_mode.name(),
            max_grid_ratio: max_opt(functions.iter().map(|f| f.grid_ratio).collect()),
            max_lipschitz_bound: max_opt(functions.iter().map(|f| f.lipschitz_bound).collect()),
            all_contained: functions.iter().map(|f| f.contained).try_fold(true, |a, c| c.map(|c| a && c)),
            xaos: self.has_xaos(),
            functions,
        }
    }

    /// Maps `p` by function `i` (f64 reference path).
    pub fn eval(&self, i: usize, p: DVec3) -> DVec3 {
        self.functions[i].map.eval(p)
    }
}

/// No active function falls below this share of the uniform probability, so that a thin stem
/// (tiny volume ratio) is still drawn.
const PROBABILITY_FLOOR: f64 = 0.1;

fn apply_floor(p: &mut [f64], active: &[usize]) {
    let total: f64 = active.iter().map(|&i| p[i]).sum();
    if !(total > 0.0) || !total.is_finite() {
        for &i in active {
            p[i] = 1.0;
        }
        return;
    }
    let floor = PROBABILITY_FLOOR * total / active.len() as f64;
    for &i in active {
        p[i] = p[i].max(floor);
    }
}

fn normalize(p: &mut [f64], active: &[usize]) {
    let mut total: f64 = active.iter().map(|&i| p[i]).sum();
    if total == f64::INFINITY {
        // Weights near f64's limit (1e308 each) overflow the sum; scaled by the largest first,
        // each is at most 1 and the sum at most the function count. Only then, so that ordinary
        // weights keep the exact quotients they always had.
        let largest = active.iter().map(|&i| p[i]).fold(0.0f64, f64::max);
        for &i in active {
            p[i] /= largest;
        }
        total = active.iter().map(|&i| p[i]).sum();
    }
    for &i in active {
        p[i] = if total > 0.0 { p[i] / total } else { 1.0 / active.len() as f64 };
    }
}

/// Solves Σ s_i^D = 1 for D in [0, `max_dim`] by bisection (Moran's equation); `max_dim` where
/// the scales are so large that the sum stays above 1.
pub fn similarity_dimension(scales: &[f64], max_dim: f64) -> f64 {
    let f = |d: f64| scales.iter().filter(|&&s| s > 0.0).map(|s| s.powf(d)).sum::<f64>() - 1.0;
    if f(max_dim) >= 0.0 {
        return max_dim;
    }
    if f(0.0) <= 0.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, max_dim);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn complex_sqrt_squares_back() {
        for &(re, im) in &[(1.0, 0.0), (-1.0, 0.0), (0.3, -0.7), (-2.0, 5.0), (0.0, -1.0)] {
            let (a, b) = complex_sqrt(re, im);
            assert!((a * a - b * b - re).abs() < 1e-12 && (2.0 * a * b - im).abs() < 1e-12);
            assert!(a >= 0.0);
        }
    }

    #[test]
    fn sierpinski_dimension() {
        let d = similarity_dimension(&[0.5, 0.5, 0.5], 2.0);
        assert!((d - 3f64.ln() / 2f64.ln()).abs() < 1e-9);
    }
}
