//! The least-squares affine fit of point pairs: the affine map w(p) = M p + o that comes
//! closest to sending each `from[i]` to `to[i]` (smallest sum of squared distances).
//!
//! How: with both point sets centred on their means p̄ and q̄, the sums A = Σ (p − p̄)(p − p̄)ᵀ
//! and B = Σ (q − q̄)(p − p̄)ᵀ give M = B A⁻¹ and o = q̄ − M p̄ (the normal equations of the
//! problem, solved per output coordinate at once). Centring keeps the solve well conditioned
//! for a grid far from the origin. When the pairs come from an affine map, q − q̄ = M (p − p̄)
//! holds exactly, so B = M A and the fit returns the map to rounding. In 2D only the x and y
//! rows and columns are fitted; the z row and column stay zero, as in every 2D affine map.

use glam::{DMat2, DMat3, DVec2, DVec3};

use super::AffineMap;

/// The least-squares affine map from `from` to `to` in `dim` (2 or 3) dimensions; None when
/// the pairs do not determine one (fewer than `dim + 1` points in general position, lengths
/// that differ, or numbers that are not finite).
pub fn fit_affine(from: &[DVec3], to: &[DVec3], dim: usize) -> Option<AffineMap> {
    if from.len() != to.len() || from.len() <= dim {
        return None;
    }
    let n = from.len() as f64;
    let p_mean = from.iter().copied().sum::<DVec3>() / n;
    let q_mean = to.iter().copied().sum::<DVec3>() / n;
    let (matrix, offset) = if dim == 2 {
        let (mut a, mut b) = (DMat2::ZERO, DMat2::ZERO);
        for (p, q) in from.iter().zip(to) {
            let dp = DVec2::new(p.x - p_mean.x, p.y - p_mean.y);
            let dq = DVec2::new(q.x - q_mean.x, q.y - q_mean.y);
            a += outer2(dp, dp);
            b += outer2(dq, dp);
        }
        let det = a.determinant();
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        let m = b * a.inverse();
        let matrix = DMat3::from_cols(m.x_axis.extend(0.0), m.y_axis.extend(0.0), DVec3::ZERO);
        let o = DVec2::new(q_mean.x, q_mean.y) - m * DVec2::new(p_mean.x, p_mean.y);
        (matrix, o.extend(0.0))
    } else {
        let (mut a, mut b) = (DMat3::ZERO, DMat3::ZERO);
        for (p, q) in from.iter().zip(to) {
            let (dp, dq) = (*p - p_mean, *q - q_mean);
            a += outer3(dp, dp);
            b += outer3(dq, dp);
        }
        let det = a.determinant();
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        let m = b * a.inverse();
        (m, q_mean - m * p_mean)
    };
    (matrix.is_finite() && offset.is_finite()).then_some(AffineMap { matrix, offset })
}

/// u vᵀ.
fn outer2(u: DVec2, v: DVec2) -> DMat2 {
    DMat2::from_cols(u * v.x, u * v.y)
}

/// u vᵀ.
fn outer3(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::RectGrid;

    /// A small deterministic generator for the test's numbers (seeded by the loop index).
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    #[test]
    fn an_affine_map_sampled_on_a_grid_is_recovered() {
        for seed in 0..20u64 {
            let mut r = numbers(seed);
            for dim in [2usize, 3] {
                let lo = DVec3::new(10.0 * r(), 10.0 * r(), if dim == 3 { 10.0 * r() } else { 0.0 });
                let hi = lo + DVec3::new(1.0 + r().abs() * 50.0, 1.0 + r().abs() * 50.0, 1.0 + r().abs() * 50.0);
                let counts = [3, 4, if dim == 3 { 3 } else { 1 }];
                let grid = RectGrid::uniform(lo, if dim == 3 { hi } else { hi.truncate().extend(0.0) }, counts);
                let mut m = DMat3::from_cols_array(&std::array::from_fn(|_| r()));
                let mut o = DVec3::new(r(), r(), r()) * 20.0;
                if dim == 2 {
                    m = DMat3::from_cols(m.x_axis.truncate().extend(0.0), m.y_axis.truncate().extend(0.0), DVec3::ZERO);
                    o.z = 0.0;
                }
                let from = grid.points();
                let to: Vec<DVec3> = from.iter().map(|&p| m * p + o).collect();
                let fit = fit_affine(&from, &to, dim).unwrap();
                // Rounding only: a few ulps of the largest entry times the grid's condition.
                let scale = to.iter().map(|q| q.abs().max_element()).fold(1.0, f64::max);
                for (p, q) in from.iter().zip(&to) {
                    let err = (fit.matrix * *p + fit.offset - *q).length();
                    assert!(err <= 1e-11 * scale, "seed {seed} dim {dim}: error {err:e}");
                }
                assert!((fit.matrix - m).to_cols_array().iter().all(|e| e.abs() < 1e-10), "seed {seed}");
            }
        }
    }

    #[test]
    fn the_fit_of_a_bent_grid_minimizes_the_squared_distance() {
        // Moving the fitted map's entries a little in any direction makes the squared error
        // larger: the fit is the minimum (the problem is convex, so a local test suffices).
        let grid = RectGrid::uniform(DVec3::ZERO, DVec3::ONE, [5, 5, 5]);
        let from = grid.points();
        let to: Vec<DVec3> = from.iter().map(|p| DVec3::new(p.x + 0.3 * p.y * p.y, p.y.sin(), p.z * p.x)).collect();
        let fit = fit_affine(&from, &to, 3).unwrap();
        let cost = |a: &AffineMap| {
            from.iter().zip(&to).map(|(p, q)| (a.matrix * *p + a.offset - *q).length_squared()).sum::<f64>()
        };
        let best = cost(&fit);
        let mut r = numbers(7);
        for _ in 0..50 {
            let nudged = AffineMap {
                matrix: fit.matrix + DMat3::from_cols_array(&std::array::from_fn(|_| 1e-3 * r())),
                offset: fit.offset + 1e-3 * DVec3::new(r(), r(), r()),
            };
            assert!(cost(&nudged) > best, "a nudge lowered the cost below the fit's");
        }
    }

    #[test]
    fn too_few_or_degenerate_points_give_none() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(fit_affine(&p, &p, 3), None);
        assert_eq!(fit_affine(&p[..2], &p[..2], 2), None);
        let line = [DVec3::ZERO, DVec3::X, 2.0 * DVec3::X, 3.0 * DVec3::X];
        assert_eq!(fit_affine(&line, &line, 2), None);
    }
}
