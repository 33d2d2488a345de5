//! Tests of the variations: the table against flam3 3.1.1's names, order and defaults, values
//! worked out by hand from the formulas, algebraic identities between variations, finiteness
//! on a grid away from singularities, and the random variations' distributions (seeded).

use super::*;
use crate::flame::{IDENTITY, VariationTerm};

fn xform(terms: &[(&str, f64, &[f64])], coefs: Coefs, post: Option<Coefs>) -> Xform {
    Xform {
        weight: 1.0,
        color: 0.0,
        color_speed: 0.5,
        opacity: 1.0,
        coefs,
        post,
        variation_coefs: None,
        variations: terms
            .iter()
            .map(|(name, weight, params)| {
                let variation = Variation::by_name(name).unwrap_or_else(|| panic!("no variation {name}"));
                let mut p = variation.default_params();
                p[..params.len()].copy_from_slice(params);
                VariationTerm { variation, weight: *weight, params: p }
            })
            .collect(),
        chaos: Vec::new(),
    }
}

/// The image of `p` under one variation of weight `w` with the identity pre-affine.
fn one(name: &str, w: f64, params: &[f64], p: [f64; 2], seed: u32) -> [f64; 2] {
    let x = CompiledXform::new(&xform(&[(name, w, params)], IDENTITY, None));
    x.apply(p, &mut Pcg32::for_stream(seed, 0, 0))
}

fn close(a: [f64; 2], b: [f64; 2], tol: f64) -> bool {
    (a[0] - b[0]).abs() <= tol * (1.0 + b[0].abs()) && (a[1] - b[1]).abs() <= tol * (1.0 + b[1].abs())
}

#[track_caller]
fn assert_close(a: [f64; 2], b: [f64; 2], tol: f64) {
    assert!(close(a, b, tol), "{a:?} != {b:?} (tolerance {tol})");
}

/// Complex product.
fn mul(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

#[test]
fn table_has_flam3s_names_in_its_order() {
    assert_eq!(VARIATIONS.len(), FLAM3_VARIATIONS + 2);
    let expect = [
        (0, "linear"),
        (1, "sinusoidal"),
        (2, "spherical"),
        (3, "swirl"),
        (13, "julia"),
        (22, "fan"),
        (31, "noise"),
        (32, "julian"),
        (33, "juliascope"),
        (35, "gaussian_blur"),
        (44, "rays"),
        (50, "super_shape"),
        (56, "boarders"),
        (67, "pre_blur"),
        (69, "oscilloscope"),
        (81, "waves2"),
        (82, "exp"),
        (95, "coth"),
        (96, "auger"),
        (97, "flux"),
        (98, "mobius"),
        (99, "linear3D"),
        (100, "flatten"),
    ];
    for (i, name) in expect {
        assert_eq!(VARIATIONS[i].name, name);
        assert_eq!(Variation::by_name(name), Some(Variation(i as u8)));
        assert_eq!(Variation(i as u8).name(), name);
    }
    for (i, a) in VARIATIONS.iter().enumerate() {
        for b in &VARIATIONS[i + 1..] {
            assert_ne!(a.name, b.name);
        }
    }
    assert_eq!(Variation::by_name("no_such_variation"), None);
}

#[test]
fn parameters_are_unique_and_have_flam3s_defaults() {
    let mut all = Vec::new();
    for (i, v) in VARIATIONS.iter().enumerate() {
        for (j, (p, _)) in v.params.iter().enumerate() {
            assert!(!all.contains(p), "{p} twice");
            all.push(*p);
            assert_eq!(Variation::param_by_name(p), Some((Variation(i as u8), j)));
            assert!(p.starts_with(v.name), "{p} is not named after {}", v.name);
        }
    }
    let defaults: &[(&str, &[f64])] = &[
        ("blob", &[0.0, 1.0, 1.0]),
        ("julian", &[1.0, 1.0]),
        ("juliascope", &[1.0, 1.0]),
        ("pie", &[6.0, 0.0, 0.5]),
        ("ngon", &[5.0, 3.0, 1.0, 2.0]),
        ("curl", &[1.0, 0.0]),
        ("rectangles", &[1.0, 1.0]),
        ("super_shape", &[0.0, 0.0, 1.0, 1.0, 1.0, 0.0]),
        ("conic", &[1.0, 0.0]),
        ("bent2", &[1.0, 1.0]),
        ("cell", &[1.0]),
        ("cpow", &[1.0, 0.0, 1.0]),
        ("curve", &[0.0, 0.0, 1.0, 1.0]),
        ("oscilloscope", &[1.0, std::f64::consts::PI, 1.0, 0.0]),
        ("wedge", &[0.0, 0.0, 1.0, 0.0]),
        ("wedge_julia", &[0.0, 1.0, 1.0, 0.0]),
        ("wedge_sph", &[0.0, 1.0, 0.0, 0.0]),
        ("auger", &[1.0, 0.5, 0.0, 1.0]),
        ("flux", &[0.0]),
        ("mobius", &[0.0; 8]),
    ];
    for (name, d) in defaults {
        assert_eq!(Variation::by_name(name).unwrap().default_params(), *d, "{name}");
    }
    assert_eq!(Variation::param_by_name("Re_A"), Some((Variation(98), 0)));
    assert_eq!(Variation::param_by_name("Im_D"), Some((Variation(98), 7)));
    assert_eq!(Variation::param_by_name("oscope_damping"), Some((Variation(69), 3)));
    assert_eq!(Variation::param_by_name("weight"), None);
}

#[test]
fn values_worked_out_by_hand() {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    assert_close(one("spherical", 1.0, &[], [1.0, 1.0], 0), [0.5, 0.5], 1e-9);
    assert_close(one("swirl", 2.0, &[], [1.0, 0.0], 0), [2.0 * 1f64.sin(), 2.0 * 1f64.cos()], 1e-12);
    // polar: θ = atan2(x, y) = π/2 at (1, 0), r − 1 = 0.
    assert_close(one("polar", 1.0, &[], [1.0, 0.0], 0), [0.5, 0.0], 1e-12);
    assert_close(one("exponential", 1.0, &[], [1.0, 0.5], 0), [0.0, 1.0], 1e-12);
    assert_close(one("bubble", 1.0, &[], [2.0, 0.0], 0), [1.0, 0.0], 1e-12);
    assert_close(one("horseshoe", 1.0, &[], [s, s], 0), [0.0, 1.0], 1e-9);
    assert_close(one("bent", 1.0, &[], [-1.0, -1.0], 0), [-2.0, -0.5], 1e-12);
    assert_close(one("fisheye", 1.0, &[], [3.0, 0.0], 0), [0.0, 1.5], 1e-12);
    assert_close(one("exp", 1.0, &[], [0.0, std::f64::consts::PI], 0), [-1.0, 0.0], 1e-12);
    assert_close(one("log", 1.0, &[], [std::f64::consts::E, 0.0], 0), [1.0, 0.0], 1e-12);
    assert_close(one("cylinder", 1.0, &[], [0.5, 3.0], 0), [0.5f64.sin(), 3.0], 1e-12);
    assert_close(one("linear3D", 0.5, &[], [2.0, 4.0], 0), [1.0, 2.0], 1e-12);
    assert_close(one("flatten", 1.0, &[], [2.0, 4.0], 0), [0.0, 0.0], 0.0);
    // mobius (z + 0) / (0 z + 1) is the identity; (0 z + 1) / (z + 0) is 1/z.
    let id = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    assert_close(one("mobius", 1.0, &id, [0.3, -0.7], 0), [0.3, -0.7], 1e-12);
    let inv = [0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0];
    assert_close(one("mobius", 1.0, &inv, [0.6, 0.8], 0), [0.6, -0.8], 1e-12);
    // waves reads the xform's c, d, e, f.
    let coefs = [1.0, 0.0, 0.3, 1.0, 0.5, 0.2];
    let x = CompiledXform::new(&xform(&[("waves", 1.0, &[])], coefs, None));
    let t = apply_coefs(&coefs, [0.4, 0.1]);
    let want = [t[0] + 0.3 * (t[1] / (0.25 + EPS)).sin(), t[1] + 1.0 * (t[0] / (0.04 + EPS)).sin()];
    assert_close(x.apply([0.4, 0.1], &mut Pcg32::for_stream(0, 0, 0)), want, 1e-12);
}

#[test]
fn julias_are_square_roots_and_julian_1_1_is_the_identity() {
    let mut rng = Pcg32::for_stream(7, 0, 0);
    let julia = CompiledXform::new(&xform(&[("julia", 1.0, &[])], IDENTITY, None));
    let julian = CompiledXform::new(&xform(&[("julian", 1.0, &[1.0, 1.0])], IDENTITY, None));
    let julian2 = CompiledXform::new(&xform(&[("julian", 1.0, &[2.0, 1.0])], IDENTITY, None));
    for i in 0..200 {
        let p = [rng.next_f64() * 4.0 - 2.0, rng.next_f64() * 4.0 - 2.0];
        let mut r = Pcg32::for_stream(i, 0, 0);
        // julia works in flam3's swapped frame: its square is (y, x).
        let q = julia.apply(p, &mut r);
        assert_close(mul(q, q), [p[1], p[0]], 1e-12);
        assert_close(julian.apply(p, &mut r), p, 1e-12);
        let q = julian2.apply(p, &mut r);
        assert_close(mul(q, q), p, 1e-12);
    }
}

#[test]
fn complex_functions_keep_their_identities() {
    let mut rng = Pcg32::for_stream(3, 0, 0);
    for _ in 0..200 {
        let p = [rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0];
        let f = |name| one(name, 1.0, &[], p, 0);
        let (sin, cos, tan) = (f("sin"), f("cos"), f("tan"));
        let one_c = [1.0, 0.0];
        let s2c2 = mul(sin, sin);
        let c2 = mul(cos, cos);
        assert_close([s2c2[0] + c2[0], s2c2[1] + c2[1]], one_c, 1e-12);
        assert_close(mul(tan, cos), sin, 1e-12);
        assert_close(mul(f("sec"), cos), one_c, 1e-12);
        assert_close(mul(f("csc"), sin), one_c, 1e-12);
        assert_close(mul(f("cot"), tan), one_c, 1e-12);
        let (sinh, cosh, tanh) = (f("sinh"), f("cosh"), f("tanh"));
        let ch2 = mul(cosh, cosh);
        let sh2 = mul(sinh, sinh);
        assert_close([ch2[0] - sh2[0], ch2[1] - sh2[1]], one_c, 1e-12);
        assert_close(mul(tanh, cosh), sinh, 1e-12);
        assert_close(mul(f("sech"), cosh), one_c, 1e-12);
        assert_close(mul(f("csch"), sinh), one_c, 1e-12);
        // flam3's coth is the conjugate of coth (the sign of its y).
        let coth = f("coth");
        assert_close(mul([coth[0], -coth[1]], tanh), one_c, 1e-12);
        // exp(log z) = z.
        assert_close(one("exp", 1.0, &[], f("log"), 0), p, 1e-12);
    }
}

/// Parameters with which every variation is defined on the grid of
/// [`every_variation_is_finite_on_a_grid`] (the defaults leave perspective, mobius and a few
/// others singular everywhere).
fn sample_params(v: Variation) -> Vec<f64> {
    let mut p = v.default_params();
    let set: &[f64] = match v.name() {
        "blob" => &[0.2, 1.1, 5.0],
        "pdj" => &[1.1, -0.7, 2.3, 0.4],
        "fan2" => &[0.6, 0.3],
        "rings2" => &[0.4],
        "perspective" => &[0.4, 2.5],
        "julian" => &[3.0, 0.7],
        "juliascope" => &[-3.0, 1.3],
        "radial_blur" => &[0.3],
        "disc2" => &[0.7, 7.1],
        "super_shape" => &[0.3, 5.0, 2.0, 1.5, 0.7, 0.1],
        "flower" => &[3.0, 0.2],
        "conic" => &[0.5, 0.1],
        "parabola" => &[1.2, 0.8],
        "bent2" => &[0.4, 1.7],
        "bipolar" => &[0.6],
        "cell" => &[0.37],
        "cpow" => &[1.3, 0.4, 3.0],
        "curve" => &[0.4, 0.7, 1.1, 0.6],
        "escher" => &[0.4],
        "lazysusan" => &[0.3, 0.2, 1.1, 0.15, -0.2],
        "modulus" => &[0.7, 0.4],
        "oscilloscope" => &[0.5, 1.3, 0.8, 0.2],
        "popcorn2" => &[0.3, 0.2, 1.7],
        "separation" => &[0.4, 0.2, 0.6, 0.1],
        "split" => &[0.7, 1.2],
        "splits" => &[0.2, 0.3],
        "stripes" => &[0.3, 0.6],
        "wedge" => &[0.4, 0.1, 3.0, 0.2],
        "wedge_julia" => &[0.3, 2.0, 3.0, 0.8],
        "wedge_sph" => &[0.3, 2.0, 0.1, 0.2],
        "whorl" => &[0.4, 0.6],
        "waves2" => &[0.3, 0.2, 2.0, 3.0],
        "auger" => &[2.0, 0.4, 0.5, 1.2],
        "flux" => &[0.3],
        "mobius" => &[1.0, 0.2, -0.3, 0.1, 0.4, -0.2, 1.5, 0.3],
        _ => &[],
    };
    p[..set.len()].copy_from_slice(set);
    p
}

#[test]
fn every_variation_is_finite_on_a_grid() {
    // Coordinates none of which is 0, ±π/2 or on a diagonal: the variations' singular places.
    let coords: Vec<f64> = (0..9).map(|i| -1.537 + 0.383 * i as f64).collect();
    let coefs = [0.9, 0.1, -0.2, 1.1, 0.3, 0.2];
    for i in 0..VARIATIONS.len() {
        let v = Variation(i as u8);
        let mut x = xform(&[], coefs, Some([1.0, 0.2, 0.0, 1.0, 0.1, 0.0]));
        x.variations.push(VariationTerm { variation: v, weight: 0.8, params: sample_params(v) });
        if v == Variation::PRE_BLUR {
            x.variations.push(VariationTerm { variation: Variation::LINEAR, weight: 1.0, params: vec![] });
        }
        let c = CompiledXform::new(&x);
        let mut rng = Pcg32::for_stream(11, 0, i as u32);
        for &px in &coords {
            for &py in &coords {
                // Each point twice, so that the random variations draw more than once.
                for _ in 0..2 {
                    let q = c.apply([px, py], &mut rng);
                    assert!(q[0].is_finite() && q[1].is_finite(), "{} at ({px}, {py}): {q:?}", v.name());
                }
            }
        }
    }
}

#[test]
fn terms_apply_in_flam3s_order_and_random_draws_repeat_with_the_seed() {
    let a = xform(&[("julia", 0.5, &[]), ("blur", 0.3, &[]), ("linear", 0.2, &[])], IDENTITY, None);
    let b = xform(&[("linear", 0.2, &[]), ("blur", 0.3, &[]), ("julia", 0.5, &[])], IDENTITY, None);
    let (ca, cb) = (CompiledXform::new(&a), CompiledXform::new(&b));
    let (mut ra, mut rb, mut rc) = (Pcg32::for_stream(5, 0, 0), Pcg32::for_stream(5, 0, 0), Pcg32::for_stream(6, 0, 0));
    let mut differ = 0;
    for i in 0..100 {
        let p = [0.01 * i as f64 - 0.5, 0.3];
        let qa = ca.apply(p, &mut ra);
        assert_eq!(qa, cb.apply(p, &mut rb));
        differ += (qa != ca.apply(p, &mut rc)) as u32;
    }
    assert!(differ > 90, "another seed gave the same points {} times in 100", 100 - differ);
}

#[test]
fn weights_of_zero_and_post_affine_as_flam3() {
    let post = [0.0, 1.0, -1.0, 0.0, 0.5, 0.25];
    let x = xform(&[("linear", 2.0, &[]), ("spherical", 0.0, &[])], [1.0, 0.0, 0.0, 1.0, 0.1, 0.0], Some(post));
    let q = CompiledXform::new(&x).apply([0.2, 0.3], &mut Pcg32::for_stream(0, 0, 0));
    assert_close(q, apply_coefs(&post, [0.6, 0.6]), 1e-12);
    let c = CompiledXform::new(&x);
    assert_close([c.apply_color(1.0), 0.0], [0.5, 0.0], 1e-15);
}

/// Mean and mean square of `f` over `n` seeded draws.
fn moments(n: u32, mut f: impl FnMut(&mut Pcg32) -> f64) -> (f64, f64) {
    let mut rng = Pcg32::for_stream(1234, 0, 0);
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let v = f(&mut rng);
        s += v;
        s2 += v * v;
    }
    (s / n as f64, s2 / n as f64)
}

#[test]
fn random_variations_have_flam3s_distributions() {
    const N: u32 = 20_000;
    let p = [0.3, -0.4];
    let term = |name: &str, w: f64, params: &[f64]| CompiledXform::new(&xform(&[(name, w, params)], IDENTITY, None));
    // gaussian_blur and pre_blur: a distance w·(u1 + u2 + u3 + u4 − 2) of mean square w²/3
    // (standard error of the mean square ≈ 0.9 %; bound 4 %).
    let g = term("gaussian_blur", 2.0, &[]);
    let (m2, _) = moments(N, |r| {
        let q = g.apply(p, r);
        q[0] * q[0] + q[1] * q[1]
    });
    assert!((m2 / (4.0 / 3.0) - 1.0).abs() < 0.04, "gaussian_blur mean square {m2}");
    let pre = CompiledXform::new(&xform(&[("pre_blur", 2.0, &[]), ("linear", 1.0, &[])], IDENTITY, None));
    let (m2, _) = moments(N, |r| {
        let q = pre.apply(p, r);
        (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
    });
    assert!((m2 / (4.0 / 3.0) - 1.0).abs() < 0.04, "pre_blur mean square {m2}");
    // blur: radius uniform in [0, w) (mean w/2, standard error 0.2 % of w; bound 1 %).
    let b = term("blur", 1.0, &[]);
    let (m, _) = moments(N, |r| {
        let q = b.apply(p, r);
        q[0].hypot(q[1])
    });
    assert!((m - 0.5).abs() < 0.01, "blur mean radius {m}");
    // square: uniform in [−w/2, w/2)²: mean 0, mean square w²/12.
    let sq = term("square", 1.0, &[]);
    let (m, m2) = moments(N, |r| sq.apply(p, r)[0]);
    assert!(m.abs() < 0.01 && (m2 * 12.0 - 1.0).abs() < 0.04, "square x: mean {m}, mean square {m2}");
    // julia: each root half of the time (standard error 0.35 %; bound 2 %).
    let j = term("julia", 1.0, &[]);
    let (m, _) = moments(N, |r| (j.apply(p, r)[0] > 0.0) as u8 as f64);
    assert!((m - 0.5).abs() < 0.02, "julia's first root {m} of the time");
    // julian power 3: three branches, a third of the time each.
    let jn = term("julian", 1.0, &[3.0, 1.0]);
    let root = jn.apply(p, &mut Pcg32::for_stream(0, 0, 0));
    let mut counts = [0u32; 3];
    let mut rng = Pcg32::for_stream(99, 0, 0);
    for _ in 0..N {
        let q = jn.apply(p, &mut rng);
        // The branches differ by a rotation of 2π/3: which one is q, from root?
        let turn = (q[1].atan2(q[0]) - root[1].atan2(root[0])).rem_euclid(std::f64::consts::TAU);
        counts[((turn / (std::f64::consts::TAU / 3.0)).round() as usize) % 3] += 1;
    }
    for c in counts {
        assert!((c as f64 / N as f64 - 1.0 / 3.0).abs() < 0.02, "julian branches {counts:?}");
    }
    // pie: points on `slices` wedges of `thickness` of a turn each, radius uniform in [0, w).
    let pie = term("pie", 1.0, &[4.0, 0.0, 0.25]);
    let mut rng = Pcg32::for_stream(5, 0, 0);
    for _ in 0..1000 {
        let q = pie.apply(p, &mut rng);
        let turn = q[1].atan2(q[0]).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU * 4.0;
        assert!(turn.fract() <= 0.25 + 1e-9 && q[0].hypot(q[1]) < 1.0, "pie point {q:?}");
    }
}

#[test]
fn c_int_overflow_as_flam3_on_x86_64() {
    assert_eq!(basic::c_int(2.9), 2);
    assert_eq!(basic::c_int(-2.9), -2);
    assert_eq!(basic::c_int(3e9), i32::MIN);
    assert_eq!(basic::c_int(-3e9), i32::MIN);
    assert_eq!(basic::c_int(f64::NAN), i32::MIN);
    // rings2 with val 0: (r + EPS) / 2EPS overflows, so r' = r + 2³²·EPS + r (1 − EPS).
    let f = 1.0 + (4_294_967_296.0 * EPS + (1.0 - EPS));
    assert_close(one("rings2", 1.0, &[0.0], [0.6, 0.8], 0), [0.6 * f, 0.8 * f], 1e-12);
    // cell of size 0: the index overflows and is multiplied by 0, leaving (w·x, −w·y).
    assert_close(one("cell", 0.5, &[0.0], [0.3, 0.7], 0), [0.15, -0.35], 1e-12);
    // cell of size 1 at (1.5, −0.5): cells (1, −1) fold to (2, 1), offsets (0.5, 0.5).
    assert_close(one("cell", 1.0, &[1.0], [1.5, -0.5], 0), [2.5, -1.5], 1e-12);
}

#[test]
fn missing_parameters_take_defaults_and_unknown_variations_are_ignored() {
    let julian = Variation::by_name("julian").unwrap();
    let mut x = xform(&[], IDENTITY, None);
    // No parameters given: julian's defaults (power 1, dist 1) make it the identity.
    x.variations.push(VariationTerm { variation: julian, weight: 1.0, params: vec![] });
    x.variations.push(VariationTerm { variation: Variation(250), weight: 1.0, params: vec![] });
    let q = CompiledXform::new(&x).apply([0.3, -0.2], &mut Pcg32::for_stream(0, 0, 0));
    assert_close(q, [0.3, -0.2], 1e-12);
    // super_shape's rnd is clamped to [0, 1] as flam3's reader does: rnd 5 acts as rnd 1.
    let (a, b) =
        (one("super_shape", 1.0, &[5.0, 4.0], [0.3, 0.4], 9), one("super_shape", 1.0, &[1.0, 4.0], [0.3, 0.4], 9));
    assert_eq!(a, b);
}

/// `apply_batch` gives `apply`'s bits for every variation it maps in vector loops, with
/// `sample_params`, on points from 0 and tiny to 10^9 (where sin, cos and tan leave their
/// cores' range and the batch is redone with libm) and each point's own generator.
#[test]
fn batches_give_the_bits_of_one_point_at_a_time() {
    let mut batched = 0;
    for i in 0..VARIATIONS.len() {
        let v = Variation(i as u8);
        let mut x = xform(&[("linear", 0.3, &[])], [0.9, 0.1, -0.2, 1.1, 0.3, 0.2], Some(IDENTITY));
        x.variations.push(VariationTerm { variation: v, weight: 0.8, params: sample_params(v) });
        let c = CompiledXform::new(&x);
        if !c.batches() {
            continue;
        }
        batched += 1;
        let mut scratch = BatchScratch::default();
        let mut source = Pcg32::for_stream(3, 0, i as u32);
        for round in 0..8 {
            let scale = [1e-12, 1.0, 1.0, 1.0, 40.0, 1e4, 1e7, 1e9][round];
            let points: Vec<[f64; 2]> = (0..BATCH)
                .map(|j| match j {
                    0 => [0.0, 0.0],
                    _ => [(2.0 * source.next_f64() - 1.0) * scale, (2.0 * source.next_f64() - 1.0) * scale],
                })
                .collect();
            let chain: Vec<ChainNumber> = (0..BATCH as ChainNumber).rev().collect();
            let mut rngs: Vec<Pcg32> = (0..BATCH as u32).map(|k| Pcg32::for_stream(9, round as u32, k)).collect();
            let mut expected_rngs = rngs.clone();
            let expected: Vec<[f64; 2]> =
                points.iter().zip(&chain).map(|(&p, &k)| c.apply(p, &mut expected_rngs[k as usize])).collect();
            let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (p[0], p[1])).unzip();
            c.apply_batch(&mut xs, &mut ys, &chain, &mut rngs, &mut scratch);
            for j in 0..BATCH {
                let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan();
                assert!(
                    same(xs[j], expected[j][0]) && same(ys[j], expected[j][1]),
                    "{} round {round} point {j} {:?}: batch ({}, {}), alone {:?}",
                    v.name(),
                    points[j],
                    xs[j],
                    ys[j],
                    expected[j]
                );
            }
            for k in 0..BATCH {
                assert_eq!(rngs[k].next_u32(), expected_rngs[k].next_u32(), "{}: generator {k}", v.name());
            }
        }
    }
    assert!(batched >= 80, "only {batched} variations batch");
}
