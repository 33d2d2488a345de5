//! A flame function (`kind = "flame"`, one of flam3's xforms) as a map of the IFS: the plane's
//! point (x, y) goes through the xform (pre-affine, weighted variations, optional post-affine;
//! `crate::flame::variations`), and z passes through unchanged, so a flame function in a 2D
//! scene stays in the plane z = 0 and in a 3D scene maps every plane z = const into itself (a
//! grid function mixed with it can lift its points off the plane).
//!
//! Some variations draw random numbers. The chaos game gives them the orbit's own generator
//! (`crate::chaos_game`); the f64 evaluation here, for the checks and reports of the model,
//! draws from one fixed stream, so that it is a function of the point.
//!
//! A flame has no Lipschitz bound in general (spherical maps the origin to infinity), so
//! [`crate::model::Map::lipschitz_bound`] is None for it, as for the Julia maps; its volume
//! ratio (for the contractivity probabilities) is measured by central differences.

use glam::DVec3;

use crate::flame::Xform;
use crate::flame::variations::CompiledXform;
use crate::rng::Pcg32;

/// One flame function: the xform (its `weight` and `color` are the scene function's
/// `probability` and `palette_index`, kept there; here they are 1 and 0).
#[derive(Clone, Debug, PartialEq)]
pub struct FlameMap {
    pub xform: Xform,
}

/// The fixed stream of [`FlameMap::eval`]'s random draws.
fn fixed_stream() -> Pcg32 {
    Pcg32::for_stream(0x000f_1a3e, 0, 0)
}

/// Step of the central differences, relative to the point's magnitude (at least this much).
const DIFFERENCE_STEP: f64 = 1e-5;

impl FlameMap {
    /// The image of `p` (z unchanged); may be non-finite where the xform is (the chaos game
    /// re-seeds such points, as flam3 does).
    pub fn eval(&self, p: DVec3) -> DVec3 {
        let compiled = CompiledXform::new(&self.xform);
        let [x, y] = compiled.apply([p.x, p.y], &mut fixed_stream());
        DVec3::new(x, y, p.z)
    }

    /// |det J| at `p` in the plane, by central differences (each evaluation from the same
    /// random state, so that a random variation's noise does not enter the difference).
    pub fn volume_ratio_at(&self, p: DVec3) -> f64 {
        let compiled = CompiledXform::new(&self.xform);
        let h = DIFFERENCE_STEP * p.x.abs().max(p.y.abs()).max(1.0);
        let at = |x: f64, y: f64| compiled.apply([x, y], &mut fixed_stream());
        let (xp, xm) = (at(p.x + h, p.y), at(p.x - h, p.y));
        let (yp, ym) = (at(p.x, p.y + h), at(p.x, p.y - h));
        let j = [
            (xp[0] - xm[0]) / (2.0 * h),
            (xp[1] - xm[1]) / (2.0 * h),
            (yp[0] - ym[0]) / (2.0 * h),
            (yp[1] - ym[1]) / (2.0 * h),
        ];
        let det = (j[0] * j[3] - j[1] * j[2]).abs();
        if det.is_finite() { det } else { 0.0 }
    }

    /// The mean of [`Self::volume_ratio_at`] over a 16 × 16 lattice of cell centres of the box
    /// [lo, hi] in the plane.
    pub fn mean_volume_ratio(&self, lo: DVec3, hi: DVec3) -> f64 {
        const N: usize = 16;
        let mut sum = 0.0;
        for i in 0..N {
            for j in 0..N {
                let t = [(i as f64 + 0.5) / N as f64, (j as f64 + 0.5) / N as f64];
                let p = DVec3::new(lo.x + t[0] * (hi.x - lo.x), lo.y + t[1] * (hi.y - lo.y), 0.0);
                sum += self.volume_ratio_at(p);
            }
        }
        sum / (N * N) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flame::{Variation, VariationTerm};

    fn xform(coefs: [f64; 6], variation: &str) -> FlameMap {
        let v = Variation::by_name(variation).unwrap();
        FlameMap {
            xform: Xform {
                weight: 1.0,
                color: 0.0,
                color_speed: 0.5,
                opacity: 1.0,
                coefs,
                post: None,
                variation_coefs: None,
                variations: vec![VariationTerm { variation: v, weight: 1.0, params: v.default_params() }],
                chaos: Vec::new(),
            },
        }
    }

    #[test]
    fn linear_flame_is_its_affine_map_and_keeps_z() {
        // x' = a x + c y + e, y' = b x + d y + f.
        let f = xform([0.5, 0.25, -0.5, 1.0, 0.1, -0.2], "linear");
        let q = f.eval(DVec3::new(2.0, 3.0, 0.7));
        assert!((q - DVec3::new(0.5 * 2.0 - 0.5 * 3.0 + 0.1, 0.25 * 2.0 + 3.0 - 0.2, 0.7)).length() < 1e-12);
        assert!((f.volume_ratio_at(DVec3::new(0.3, -0.4, 0.0)) - (0.5 * 1.0 + 0.5 * 0.25)).abs() < 1e-6);
    }

    #[test]
    fn spherical_volume_ratio_is_its_closed_form() {
        // spherical: p / |p|²; |det J| = 1 / |p|⁴.
        let f = xform([1.0, 0.0, 0.0, 1.0, 0.0, 0.0], "spherical");
        let p = DVec3::new(0.6, 0.8, 0.0);
        let q = f.eval(p);
        assert!((q - DVec3::new(0.6, 0.8, 0.0)).length() < 1e-9);
        let p = DVec3::new(2.0, 0.0, 0.0);
        assert!((f.volume_ratio_at(p) - 1.0 / 16.0).abs() < 1e-6);
    }
}
