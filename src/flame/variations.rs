//! flam3's variations (its `variations.c`): each maps the affine image t = (tx, ty) of a point
//! to a new point; an xform sums them weighted. The table [`VARIATIONS`] gives each one's name
//! in the XML and its parameters with their defaults; [`CompiledXform`] applies a whole xform
//! (pre-affine, the weighted sum, post-affine).

use super::{Coefs, Xform, apply_coefs};
use crate::rng::Pcg32;

/// A variation: its index in [`VARIATIONS`] (flam3's numbering).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Variation(pub u8);

/// A variation's name in flam3's XML and its parameters (XML attribute name, default).
#[derive(Debug)]
pub struct VariationInfo {
    pub name: &'static str,
    pub params: &'static [(&'static str, f64)],
}

/// flam3's variations in its order.
pub static VARIATIONS: &[VariationInfo] = &[
    VariationInfo { name: "linear", params: &[] },
    VariationInfo { name: "sinusoidal", params: &[] },
    VariationInfo { name: "spherical", params: &[] },
    VariationInfo { name: "swirl", params: &[] },
];

impl Variation {
    pub fn by_name(name: &str) -> Option<Self> {
        VARIATIONS.iter().position(|v| v.name == name).map(|i| Variation(i as u8))
    }

    pub fn info(self) -> &'static VariationInfo {
        &VARIATIONS[self.0 as usize]
    }

    pub fn name(self) -> &'static str {
        self.info().name
    }
}

/// An xform ready to apply.
#[derive(Clone, Debug)]
pub struct CompiledXform {
    coefs: Coefs,
    post: Option<Coefs>,
    terms: Vec<(Variation, f64, Vec<f64>)>,
}

impl CompiledXform {
    pub fn new(x: &Xform) -> Self {
        Self {
            coefs: x.coefs,
            post: x.post,
            terms: x.variations.iter().map(|t| (t.variation, t.weight, t.params.clone())).collect(),
        }
    }

    /// The xform's image of `p` (may be NaN or huge: the caller re-seeds such points, as flam3
    /// does).
    pub fn apply(&self, p: [f64; 2], rng: &mut Pcg32) -> [f64; 2] {
        let t = apply_coefs(&self.coefs, p);
        let mut out = [0.0, 0.0];
        for (v, w, _params) in &self.terms {
            let d = eval(*v, *w, t, rng);
            out[0] += d[0];
            out[1] += d[1];
        }
        match &self.post {
            Some(post) => apply_coefs(post, out),
            None => out,
        }
    }
}

/// w · V(t) for one variation.
fn eval(v: Variation, w: f64, t: [f64; 2], _rng: &mut Pcg32) -> [f64; 2] {
    let [x, y] = t;
    let r2 = x * x + y * y;
    match v.0 {
        0 => [w * x, w * y],
        1 => [w * x.sin(), w * y.sin()],
        2 => {
            let r = w / (r2 + 1e-10);
            [r * x, r * y]
        }
        3 => {
            let (s, c) = r2.sin_cos();
            [w * (s * x - c * y), w * (c * x + s * y)]
        }
        _ => [0.0, 0.0],
    }
}
