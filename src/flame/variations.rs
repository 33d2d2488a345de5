//! flam3's variations (its `variations.c`): each maps the affine image t = (tx, ty) of a point
//! to a new point; an xform sums them weighted. The table [`VARIATIONS`] gives each one's name
//! in the XML and its parameters with their defaults; [`CompiledXform`] applies a whole xform as
//! flam3's `apply_xform` does: pre-affine, `pre_blur` on the affine image, the point's shared
//! quantities (|t|², |t|, flam3's swapped angle atan2(tx, ty), its "sin" tx/|t| and "cos"
//! ty/|t|, and atan2(ty, tx)), the weighted variations in flam3's order, then the post-affine.
//!
//! The formulas live in `variations_basic.rs` (flam3's numbers 0–49: the original flame
//! variations and the early plugins) and `variations_plugins.rs` (50–98: Apophysis plugins,
//! cothe's complex functions, auger, flux, mobius, and the two 3D-era names files carry).
//! Everything that does not depend on the point (julian's |power| and exponent, radial_blur's
//! spin and zoom, waves' 1/(e² + 10⁻¹⁰), disc2's rotated sums, wedges' compensation factors…)
//! is computed once in [`CompiledXform::new`]; [`CompiledXform::apply`] allocates nothing and
//! dispatches on the variation's number.
//!
//! Random draws come from the chain's [`Pcg32`]: where flam3 draws `flam3_random_isaac_01`
//! (uniform in [0, 1]) these draw [`Pcg32::next_f64`] (uniform in [0, 1)), in the same order and
//! number; julia's branch bit is the low bit of [`Pcg32::next_u32`], as flam3 takes the low bit
//! of an isaac word. So the distributions are flam3's, not its bytes.
//!
//! Checked against flam3 3.1.1: its `variations.c` was compiled outside this repository into a
//! small C program whose random source was replaced by this crate's PCG32 (the same streams,
//! so flam3 and [`CompiledXform::apply`] draw the same numbers), which wrote 100 000 random
//! cases: every variation alone with random or default parameters, coefficients (some scaled by
//! up to 10^±4), post-affines, weights and points (some on the axes, at the origin or on
//! half-integers), and mixtures of two to four variations with `pre_blur`. All outputs agree
//! bit for bit, the random variations included, and where flam3 gives NaN or |v| > 1e10 so does
//! this code. That needed C's conversion to `int` as x86-64 does it (`basic::c_int`): fan2 and
//! rings2 with a parameter near 0, and cell of size 0, depend on it. (That was with libm's sin,
//! cos, tan, atan2, exp and pow throughout. The precalc's angles and the smooth variations of
//! `basic::eval_smooth` now take them from `flame::trig`, branch-free so that batches of
//! points run in vector registers: their results differ from libm's in the last bits (within 2
//! units for sin, cos, atan2, exp, ln, a few for tan, |y · ln x| for pow), which changes a
//! picture only as another seed would; `tests/flame_fidelity.rs` measures the pictures.)

#[path = "variations_basic.rs"]
mod basic;
#[path = "variations_batch.rs"]
mod batch;
#[path = "variations_plugins.rs"]
mod plugins;
#[cfg(test)]
#[path = "variations_tests.rs"]
mod tests;

pub use batch::{BATCH, BatchScratch, ChainNumber};

use super::{Coefs, Xform, apply_coefs, trig};
use crate::rng::Pcg32;

/// A variation: its index in [`VARIATIONS`] (flam3's numbering for the first 99).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Variation(pub u8);

/// A variation's name in flam3's XML and its parameters (XML attribute name, default).
#[derive(Debug)]
pub struct VariationInfo {
    pub name: &'static str,
    pub params: &'static [(&'static str, f64)],
}

const fn var(name: &'static str) -> VariationInfo {
    VariationInfo { name, params: &[] }
}

const fn with(name: &'static str, params: &'static [(&'static str, f64)]) -> VariationInfo {
    VariationInfo { name, params }
}

/// The number of flam3 3.1.1's variations (`flam3_nvariations`); the entries after them are
/// names other programs write that have a meaning in the plane.
pub const FLAM3_VARIATIONS: usize = 99;

/// flam3's variations in its order (index = flam3's number), its defaults for their parameters
/// (`initialize_xforms` in flam3's `variations.c`), then `linear3D` and `flatten`.
pub static VARIATIONS: &[VariationInfo] = &[
    var("linear"),
    var("sinusoidal"),
    var("spherical"),
    var("swirl"),
    var("horseshoe"),
    var("polar"),
    var("handkerchief"),
    var("heart"),
    var("disc"),
    var("spiral"),
    var("hyperbolic"),
    var("diamond"),
    var("ex"),
    var("julia"),
    var("bent"),
    var("waves"),
    var("fisheye"),
    var("popcorn"),
    var("exponential"),
    var("power"),
    var("cosine"),
    var("rings"),
    var("fan"),
    with("blob", &[("blob_low", 0.0), ("blob_high", 1.0), ("blob_waves", 1.0)]),
    with("pdj", &[("pdj_a", 0.0), ("pdj_b", 0.0), ("pdj_c", 0.0), ("pdj_d", 0.0)]),
    with("fan2", &[("fan2_x", 0.0), ("fan2_y", 0.0)]),
    with("rings2", &[("rings2_val", 0.0)]),
    var("eyefish"),
    var("bubble"),
    var("cylinder"),
    with("perspective", &[("perspective_angle", 0.0), ("perspective_dist", 0.0)]),
    var("noise"),
    with("julian", &[("julian_power", 1.0), ("julian_dist", 1.0)]),
    with("juliascope", &[("juliascope_power", 1.0), ("juliascope_dist", 1.0)]),
    var("blur"),
    var("gaussian_blur"),
    with("radial_blur", &[("radial_blur_angle", 0.0)]),
    with("pie", &[("pie_slices", 6.0), ("pie_rotation", 0.0), ("pie_thickness", 0.5)]),
    with("ngon", &[("ngon_sides", 5.0), ("ngon_power", 3.0), ("ngon_circle", 1.0), ("ngon_corners", 2.0)]),
    with("curl", &[("curl_c1", 1.0), ("curl_c2", 0.0)]),
    with("rectangles", &[("rectangles_x", 1.0), ("rectangles_y", 1.0)]),
    var("arch"),
    var("tangent"),
    var("square"),
    var("rays"),
    var("blade"),
    var("secant2"),
    var("twintrian"),
    var("cross"),
    with("disc2", &[("disc2_rot", 0.0), ("disc2_twist", 0.0)]),
    with(
        "super_shape",
        &[
            ("super_shape_rnd", 0.0),
            ("super_shape_m", 0.0),
            ("super_shape_n1", 1.0),
            ("super_shape_n2", 1.0),
            ("super_shape_n3", 1.0),
            ("super_shape_holes", 0.0),
        ],
    ),
    with("flower", &[("flower_petals", 0.0), ("flower_holes", 0.0)]),
    with("conic", &[("conic_eccentricity", 1.0), ("conic_holes", 0.0)]),
    with("parabola", &[("parabola_height", 0.0), ("parabola_width", 0.0)]),
    with("bent2", &[("bent2_x", 1.0), ("bent2_y", 1.0)]),
    with("bipolar", &[("bipolar_shift", 0.0)]),
    var("boarders"),
    var("butterfly"),
    with("cell", &[("cell_size", 1.0)]),
    with("cpow", &[("cpow_r", 1.0), ("cpow_i", 0.0), ("cpow_power", 1.0)]),
    with("curve", &[("curve_xamp", 0.0), ("curve_yamp", 0.0), ("curve_xlength", 1.0), ("curve_ylength", 1.0)]),
    var("edisc"),
    var("elliptic"),
    with("escher", &[("escher_beta", 0.0)]),
    var("foci"),
    with(
        "lazysusan",
        &[
            ("lazysusan_spin", 0.0),
            ("lazysusan_space", 0.0),
            ("lazysusan_twist", 0.0),
            ("lazysusan_x", 0.0),
            ("lazysusan_y", 0.0),
        ],
    ),
    var("loonie"),
    var("pre_blur"),
    with("modulus", &[("modulus_x", 0.0), ("modulus_y", 0.0)]),
    with(
        "oscilloscope",
        &[
            ("oscilloscope_separation", 1.0),
            ("oscilloscope_frequency", std::f64::consts::PI),
            ("oscilloscope_amplitude", 1.0),
            ("oscilloscope_damping", 0.0),
        ],
    ),
    var("polar2"),
    with("popcorn2", &[("popcorn2_x", 0.0), ("popcorn2_y", 0.0), ("popcorn2_c", 0.0)]),
    var("scry"),
    with(
        "separation",
        &[("separation_x", 0.0), ("separation_xinside", 0.0), ("separation_y", 0.0), ("separation_yinside", 0.0)],
    ),
    with("split", &[("split_xsize", 0.0), ("split_ysize", 0.0)]),
    with("splits", &[("splits_x", 0.0), ("splits_y", 0.0)]),
    with("stripes", &[("stripes_space", 0.0), ("stripes_warp", 0.0)]),
    with("wedge", &[("wedge_angle", 0.0), ("wedge_hole", 0.0), ("wedge_count", 1.0), ("wedge_swirl", 0.0)]),
    with(
        "wedge_julia",
        &[
            ("wedge_julia_angle", 0.0),
            ("wedge_julia_count", 1.0),
            ("wedge_julia_power", 1.0),
            ("wedge_julia_dist", 0.0),
        ],
    ),
    with(
        "wedge_sph",
        &[("wedge_sph_angle", 0.0), ("wedge_sph_count", 1.0), ("wedge_sph_hole", 0.0), ("wedge_sph_swirl", 0.0)],
    ),
    with("whorl", &[("whorl_inside", 0.0), ("whorl_outside", 0.0)]),
    with("waves2", &[("waves2_scalex", 0.0), ("waves2_scaley", 0.0), ("waves2_freqx", 0.0), ("waves2_freqy", 0.0)]),
    var("exp"),
    var("log"),
    var("sin"),
    var("cos"),
    var("tan"),
    var("sec"),
    var("csc"),
    var("cot"),
    var("sinh"),
    var("cosh"),
    var("tanh"),
    var("sech"),
    var("csch"),
    var("coth"),
    with("auger", &[("auger_freq", 1.0), ("auger_weight", 0.5), ("auger_sym", 0.0), ("auger_scale", 1.0)]),
    with("flux", &[("flux_spread", 0.0)]),
    with(
        "mobius",
        &[
            ("mobius_re_a", 0.0),
            ("mobius_im_a", 0.0),
            ("mobius_re_b", 0.0),
            ("mobius_im_b", 0.0),
            ("mobius_re_c", 0.0),
            ("mobius_im_c", 0.0),
            ("mobius_re_d", 0.0),
            ("mobius_im_d", 0.0),
        ],
    ),
    // Apophysis 7X / JWildfire's 3D linear: in the plane, linear.
    var("linear3D"),
    // Apophysis 7X / JWildfire's flatten only zeroes the z coordinate; in the plane it adds
    // nothing to the sum (an xform of flatten alone maps every point to the origin, as an
    // xform of an unknown variation does in flam3).
    var("flatten"),
];

/// Other spellings flam3's reader accepts for parameters (alias, name in [`VARIATIONS`]).
pub static PARAM_ALIASES: &[(&str, &str)] = &[
    ("oscope_separation", "oscilloscope_separation"),
    ("oscope_frequency", "oscilloscope_frequency"),
    ("oscope_amplitude", "oscilloscope_amplitude"),
    ("oscope_damping", "oscilloscope_damping"),
    ("Re_A", "mobius_re_a"),
    ("Im_A", "mobius_im_a"),
    ("Re_B", "mobius_re_b"),
    ("Im_B", "mobius_im_b"),
    ("Re_C", "mobius_re_c"),
    ("Im_C", "mobius_im_c"),
    ("Re_D", "mobius_re_d"),
    ("Im_D", "mobius_im_d"),
];

impl Variation {
    pub const LINEAR: Variation = Variation(0);
    pub const PRE_BLUR: Variation = Variation(67);

    /// Every variation, in flam3's order (its number in `variations.c`), then the two of other
    /// programs.
    pub fn all() -> impl Iterator<Item = Self> {
        (0..VARIATIONS.len()).map(|i| Variation(i as u8))
    }

    pub fn by_name(name: &str) -> Option<Self> {
        VARIATIONS.iter().position(|v| v.name == name).map(|i| Variation(i as u8))
    }

    /// The variation and parameter index an xform attribute names (aliases included), if it is
    /// a variation's parameter.
    pub fn param_by_name(attribute: &str) -> Option<(Self, usize)> {
        let name = PARAM_ALIASES.iter().find(|(a, _)| *a == attribute).map_or(attribute, |(_, n)| n);
        VARIATIONS
            .iter()
            .enumerate()
            .find_map(|(i, v)| v.params.iter().position(|(p, _)| *p == name).map(|j| (Variation(i as u8), j)))
    }

    pub fn info(self) -> &'static VariationInfo {
        &VARIATIONS[self.0 as usize]
    }

    /// Whether the variation reads its xform's coefficients (waves: c, d, e, f; popcorn: e, f;
    /// rings: e; fan: e, f), not only its point and parameters (`basic::prepare`).
    pub fn reads_xform_coefs(self) -> bool {
        matches!(self.0, 15 | 17 | 21 | 22)
    }

    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The parameters' defaults, in the order of [`VariationInfo::params`].
    pub fn default_params(self) -> Vec<f64> {
        self.info().params.iter().map(|(_, d)| *d).collect()
    }
}

/// flam3's `EPS`, the guard added to denominators.
pub(crate) const EPS: f64 = 1e-10;

/// The most numbers a variation keeps precomputed (mobius' eight coefficients).
pub(crate) const MAX_CONSTS: usize = 8;

/// The quantities of the affine image that several variations share (flam3's `precalc_*`).
/// `atan_xy`, `sina`, `cosa` and `atan_yx` are computed only when a term of the xform reads them.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Point {
    pub tx: f64,
    pub ty: f64,
    /// tx² + ty².
    pub sumsq: f64,
    /// √(tx² + ty²).
    pub sqrt: f64,
    /// atan2(tx, ty): flam3's swapped angle.
    pub atan_xy: f64,
    /// tx / |t| (flam3's `precalc_sina`).
    pub sina: f64,
    /// ty / |t| (flam3's `precalc_cosa`).
    pub cosa: f64,
    /// atan2(ty, tx).
    pub atan_yx: f64,
}

/// The most random numbers a smooth variation draws per point (gaussian_blur's five).
pub(crate) const DRAWS: usize = 5;

/// `count` uniform numbers in [0, 1) from `rng`, in order, the rest of the array 0: what a
/// smooth variation draws (`basic::smooth_draw`, `plugins::smooth_draw`).
#[inline(always)]
fn uniform_draws(count: usize, rng: &mut Pcg32) -> [f64; DRAWS] {
    let mut draw = [0.0; DRAWS];
    for d in &mut draw[..count.min(DRAWS)] {
        *d = rng.next_f64();
    }
    draw
}

/// Which optional quantities of [`Point`] a variation reads.
pub(crate) const NEEDS_ATAN_XY: u8 = 1;
pub(crate) const NEEDS_ANGLES: u8 = 2;
pub(crate) const NEEDS_ATAN_YX: u8 = 4;
/// √(tx² + ty²): the point-by-point path always computes it; the batch path only where a term
/// reads it (`basic::needs` says which do not).
pub(crate) const NEEDS_SQRT: u8 = 8;

/// One weighted variation with its constants.
#[derive(Clone, Copy, Debug)]
struct Term {
    variation: u8,
    weight: f64,
    k: [f64; MAX_CONSTS],
}

/// A [`CompiledXform`]'s parts ([`CompiledXform::parts`]).
pub(crate) struct XformParts<'a> {
    pub coefs: &'a Coefs,
    /// The post-affine where flam3 applies one.
    pub post: Option<&'a Coefs>,
    /// The weight of `pre_blur` (0: none).
    pub pre_blur: f64,
    /// The [`Point`] quantities the terms read (`NEEDS_*`).
    pub needs: u8,
    /// The terms in flam3's order: variation, weight, prepared constants.
    pub terms: Vec<(u8, f64, [f64; MAX_CONSTS])>,
}

/// An xform ready to apply.
#[derive(Clone, Debug)]
pub struct CompiledXform {
    coefs: Coefs,
    post: Option<Coefs>,
    /// The weight of `pre_blur` (0: none), applied to the affine image before anything else.
    pre_blur: f64,
    needs: u8,
    /// In flam3's order (by variation number), `pre_blur` left out.
    terms: Vec<Term>,
    color: f64,
    color_speed: f64,
    /// [`super::Xform::plotted_weight`]: in the scene's chaos game, the chance that a point of
    /// this xform is drawn.
    plotted_weight: f64,
}

impl CompiledXform {
    pub fn new(x: &Xform) -> Self {
        let mut order: Vec<&super::VariationTerm> = x.variations.iter().collect();
        order.sort_by_key(|t| t.variation.0);
        let mut pre_blur = 0.0;
        let mut needs = 0;
        let mut terms = Vec::with_capacity(order.len());
        for t in order {
            let v = t.variation;
            if (v.0 as usize) >= VARIATIONS.len() || t.weight == 0.0 {
                continue;
            }
            if v == Variation::PRE_BLUR {
                pre_blur = t.weight;
                continue;
            }
            let mut p = [0.0; MAX_CONSTS];
            for (i, (_, default)) in v.info().params.iter().enumerate() {
                p[i] = t.params.get(i).copied().unwrap_or(*default);
            }
            let k = if v.0 < plugins::FIRST {
                basic::prepare(v.0, p, x.variation_coefs.as_ref().unwrap_or(&x.coefs))
            } else {
                plugins::prepare(v.0, p)
            };
            needs |= if v.0 < plugins::FIRST { basic::needs(v.0) } else { plugins::needs(v.0) };
            terms.push(Term { variation: v.0, weight: t.weight, k });
        }
        // flam3 applies the post-affine only when it differs from the identity.
        let post = x.post.filter(|p| *p != super::IDENTITY);
        let (color, color_speed, plotted_weight) = (x.color, x.color_speed, x.plotted_weight());
        Self { coefs: x.coefs, post, pre_blur, needs, terms, color, color_speed, plotted_weight }
    }

    /// What the f32 lane game (`flame/render_lanes.rs`) rebuilds the xform from.
    pub(crate) fn parts(&self) -> XformParts<'_> {
        XformParts {
            coefs: &self.coefs,
            post: self.post.as_ref(),
            pre_blur: self.pre_blur,
            needs: self.needs,
            terms: self.terms.iter().map(|t| (t.variation, t.weight, t.k)).collect(),
        }
    }

    /// flam3's weight of the xform's points ([`super::Xform::plotted_weight`]).
    pub fn plotted_weight(&self) -> f64 {
        self.plotted_weight
    }

    /// The xform's image of `p` (may be NaN or huge: the caller re-seeds such points, as flam3
    /// does).
    #[inline(always)]
    pub fn apply(&self, p: [f64; 2], rng: &mut Pcg32) -> [f64; 2] {
        let [mut tx, mut ty] = apply_coefs(&self.coefs, p);
        if self.pre_blur != 0.0 {
            let [dx, dy] = plugins::pre_blur_offset(self.pre_blur, rng);
            tx += dx;
            ty += dy;
        }
        let sumsq = tx * tx + ty * ty;
        let sqrt = sumsq.sqrt();
        let mut pt = Point { tx, ty, sumsq, sqrt, ..Point::default() };
        if self.needs & NEEDS_ATAN_XY != 0 {
            pt.atan_xy = trig::atan2(tx, ty);
        }
        if self.needs & NEEDS_ANGLES != 0 {
            pt.sina = tx / sqrt;
            pt.cosa = ty / sqrt;
        }
        if self.needs & NEEDS_ATAN_YX != 0 {
            pt.atan_yx = trig::atan2(ty, tx);
        }
        let mut out = [0.0, 0.0];
        for t in &self.terms {
            let d = if let Some(d) = basic::eval_arithmetic(t.variation, t.weight, &pt) {
                d
            } else if t.variation < plugins::FIRST {
                basic::eval(t.variation, t.weight, &t.k, &pt, rng)
            } else {
                plugins::eval(t.variation, t.weight, &t.k, &pt, rng)
            };
            out[0] += d[0];
            out[1] += d[1];
        }
        match &self.post {
            Some(post) => apply_coefs(post, out),
            None => out,
        }
    }

    /// The colour coordinate after this xform: s·c_f + (1 − s)·c (flam3's `apply_xform`).
    #[inline]
    pub fn apply_color(&self, c: f64) -> f64 {
        self.color_speed * self.color + (1.0 - self.color_speed) * c
    }

    /// This xform as records of the GPU's flame table (`shaders/variations.wgsl`): its header
    /// (pre-affine, `pre_blur` weight, colour speed, plotted weight; its `count` records start
    /// at `first`) and
    /// those records: the terms in flam3's order with the constants [`Self::new`] prepared,
    /// then the post-affine when there is one. The f64 constants are rounded to f32 here.
    pub fn gpu_ops(&self, first: u32) -> (FlameOp, Vec<FlameOp>) {
        let f = |v: &[f64]| -> [f32; 4] { std::array::from_fn(|i| v.get(i).map_or(0.0, |&x| x as f32)) };
        let mut records: Vec<FlameOp> = self
            .terms
            .iter()
            .map(|t| FlameOp {
                kind: t.variation as u32,
                weight: t.weight as f32,
                first: 0,
                count: 0,
                k: [f(&t.k[..4]), f(&t.k[4..])],
            })
            .collect();
        if let Some(post) = &self.post {
            records.push(FlameOp {
                kind: FLAME_OP_POST,
                weight: 0.0,
                first: 0,
                count: 0,
                k: [f(&post[..4]), f(&post[4..])],
            });
        }
        let c = &self.coefs;
        let header = FlameOp {
            kind: FLAME_OP_XFORM,
            weight: self.pre_blur as f32,
            first,
            count: records.len() as u32,
            k: [f(&c[..4]), f(&[c[4], c[5], self.color_speed, self.plotted_weight])],
        };
        (header, records)
    }
}

/// One record of the GPU's flame table (`shaders/variations.wgsl`, read by the chaos game).
/// Mirrors `struct FlameOp` there: keep the two in sync. Record i < the number of compiled
/// functions is function i's header ([`FLAME_OP_XFORM`] for a flame function, else
/// [`FLAME_OP_NONE`]); a header's `count` records from `first` on are its xform's terms (`kind`
/// = the variation's number, `k` its constants) and its post-affine ([`FLAME_OP_POST`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FlameOp {
    pub kind: u32,
    /// A term's weight; a header's `pre_blur` weight.
    pub weight: f32,
    pub first: u32,
    pub count: u32,
    /// A term's constants; an affine map's coefs a, b, c, d | e, f; a header's colour speed in
    /// `k[1][2]` and its plotted weight in `k[1][3]` (a final xform's: its colour coordinate).
    pub k: [[f32; 4]; 2],
}
const _: () = assert!(std::mem::size_of::<FlameOp>() == 48);

/// The header of a flame function's xform.
pub const FLAME_OP_XFORM: u32 = 1000;
/// The header of a function that is not a flame (colour speed ½ in `k[1][2]`).
pub const FLAME_OP_NONE: u32 = 1001;
/// An xform's post-affine.
pub const FLAME_OP_POST: u32 = 1002;
