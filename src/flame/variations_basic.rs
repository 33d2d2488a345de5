//! flam3's variations 0–49 (linear … disc2): the original fractal-flame set, the 2006 blurs and
//! julias, and the first Z+ plugins. [`prepare`] turns a term's parameters (and, for waves,
//! popcorn, rings and fan, the xform's own coefficients, which flam3 reads there) into the
//! constants [`eval`] uses; [`eval`] returns the term's weighted contribution w·V(t).
//!
//! flam3's oddities are kept, as its pictures depend on them: `sina`/`cosa` are tx/|t| and
//! ty/|t| (the swapped angle), fisheye swaps its output axes, radial_blur's rotated part is not
//! scaled by the weight, arch, rays, blade, secant2 and twintrian use the weight inside as well.

use super::{DRAWS, EPS, NEEDS_ANGLES, NEEDS_ATAN_XY, NEEDS_ATAN_YX, NEEDS_SQRT, Point, uniform_draws};
use crate::flame::Coefs;
use crate::flame::trig::{Elementary, Exact};
use crate::rng::Pcg32;
use std::f64::consts::{FRAC_1_PI, LOG10_E, PI};

/// Which of [`Point`]'s optional quantities variation `v` reads.
pub(super) fn needs(v: u8) -> u8 {
    let angles = match v {
        5..=8 | 12 | 13 | 22 | 25 | 49 => NEEDS_ATAN_XY,
        23 => NEEDS_ATAN_XY | NEEDS_ANGLES,
        9..=11 | 19 | 21 | 26 => NEEDS_ANGLES,
        32 | 33 | 36 | 38 => NEEDS_ATAN_YX,
        _ => 0,
    };
    // Those that do not read r: linear, sinusoidal, spherical, swirl, bent, waves, popcorn,
    // exponential, cosine, bubble, cylinder.
    let sqrt = if matches!(v, 0..=3 | 14 | 15 | 17 | 18 | 20 | 28 | 29) { 0 } else { NEEDS_SQRT };
    angles | sqrt
}

/// The constants of variation `v` from its parameters `p` (in the table's order) and the
/// xform's coefficients `[a, b, c, d, e, f]`.
pub(super) fn prepare(v: u8, p: [f64; 8], c: &Coefs) -> [f64; 8] {
    let mut k = p;
    match v {
        // waves: c, d as amplitudes, 1 / (e² + EPS) and 1 / (f² + EPS) as frequencies.
        15 => {
            k[0] = c[2];
            k[1] = c[3];
            k[2] = 1.0 / (c[4] * c[4] + EPS);
            k[3] = 1.0 / (c[5] * c[5] + EPS);
        }
        // popcorn: e, f as amplitudes.
        17 => {
            k[0] = c[4];
            k[1] = c[5];
        }
        // rings: e² + EPS.
        21 => k[0] = c[4] * c[4] + EPS,
        // fan: π (e² + EPS), f.
        22 => {
            k[0] = PI * (c[4] * c[4] + EPS);
            k[1] = c[5];
        }
        // blob: low, high − low, waves.
        23 => k[1] = p[1] - p[0],
        // fan2: π (x² + EPS), y.
        25 => {
            k[0] = PI * (p[0] * p[0] + EPS);
            k[1] = p[1];
        }
        // rings2: val² + EPS.
        26 => k[0] = p[0] * p[0] + EPS,
        // perspective: dist, sin(angle π/2), dist cos(angle π/2).
        30 => {
            let ang = p[0] * PI / 2.0;
            k[0] = p[1];
            k[1] = ang.sin();
            k[2] = p[1] * ang.cos();
        }
        // julian, juliascope: power, |power|, dist / power / 2.
        32 | 33 => {
            k[0] = p[0];
            k[1] = p[0].abs();
            k[2] = p[1] / p[0] / 2.0;
        }
        // radial_blur: sin and cos of angle π/2 (spin and zoom).
        36 => {
            let (s, c) = (p[0] * PI / 2.0).sin_cos();
            k[0] = s;
            k[1] = c;
        }
        // ngon: 2π / sides, power / 2, circle, corners.
        38 => {
            k[0] = 2.0 * PI / p[0];
            k[1] = p[1] / 2.0;
        }
        // disc2: rot π, sin(twist) and cos(twist) − 1, stretched past ±2π.
        49 => {
            let add = p[1];
            let (mut s, mut c) = add.sin_cos();
            c -= 1.0;
            if add > 2.0 * PI {
                let f = 1.0 + add - 2.0 * PI;
                c *= f;
                s *= f;
            }
            if add < -2.0 * PI {
                let f = 1.0 + add + 2.0 * PI;
                c *= f;
                s *= f;
            }
            k[0] = p[0] * PI;
            k[1] = s;
            k[2] = c;
        }
        _ => {}
    }
    k
}

/// C's conversion of a double to `int` as flam3's x86-64 builds do it: toward zero, and
/// 0x80000000 (i32::MIN) for NaN and anything out of range (where Rust's `as` saturates).
/// fan2 and rings2 with a parameter near 0 divide by ~1e−10 and land there, so their pictures
/// depend on it.
#[inline(always)]
pub(super) fn c_int(v: f64) -> i32 {
    if v > -2_147_483_649.0 && v < 2_147_483_648.0 { v as i32 } else { i32::MIN }
}

/// The sum of four uniform draws minus 2: flam3's pseudo-Gaussian in (−2, 2).
#[inline(always)]
pub(super) fn pseudo_gaussian(rng: &mut Pcg32) -> f64 {
    rng.next_f64() + rng.next_f64() + rng.next_f64() + rng.next_f64() - 2.0
}

/// w · V(t) for the variations that are a few arithmetic operations on [`Point`]'s
/// quantities (linear, spherical, horseshoe, polar, hyperbolic); `None` for the others.
/// Inlined into `CompiledXform::apply` (no transcendental function for LLVM to hoist), so
/// these cost no call; [`eval`] answers them through here too.
#[inline(always)]
pub(super) fn eval_arithmetic(v: u8, w: f64, pt: &Point) -> Option<[f64; 2]> {
    let Point { tx: x, ty: y, sumsq: r2, sqrt: r, atan_xy: a, sina: sa, cosa: ca, .. } = *pt;
    Some(match v {
        // linear
        0 => [w * x, w * y],
        // spherical
        2 => {
            let f = w / (r2 + EPS);
            [f * x, f * y]
        }
        // horseshoe
        4 => {
            let f = w / (r + EPS);
            [(x - y) * (x + y) * f, 2.0 * x * y * f]
        }
        // polar
        5 => [w * (a * FRAC_1_PI), w * (r - 1.0)],
        // hyperbolic
        10 => {
            let rr = r + EPS;
            [w * sa / rr, w * ca * rr]
        }
        _ => return None,
    })
}

/// Whether [`eval_smooth`] holds variation `v`'s formula.
pub(super) fn smooth(v: u8) -> bool {
    matches!(v, 1 | 3 | 6..=9 | 11..=20 | 23 | 24 | 27..=37 | 39..=49)
}

/// The random numbers [`eval_smooth`] takes for variation `v`, drawn from `rng` in flam3's
/// order and number: julia's bit (0 or 1), otherwise uniform numbers in [0, 1) (julian,
/// juliascope, arch, rays, blade and twintrian one; noise, blur and square two; pie three;
/// radial_blur four, gaussian_blur five); 0 where nothing is drawn.
#[inline(always)]
pub(super) fn smooth_draw(v: u8, rng: &mut Pcg32) -> [f64; DRAWS] {
    if v == 13 {
        return [(rng.next_u32() & 1) as f64, 0.0, 0.0, 0.0, 0.0];
    }
    uniform_draws(smooth_draw_count(v), rng)
}

/// How many numbers [`smooth_draw`] draws for variation `v` (julia's bit counts one).
pub(super) const fn smooth_draw_count(v: u8) -> usize {
    match v {
        13 | 32 | 33 | 41 | 44 | 45 | 47 => 1,
        31 | 34 | 43 => 2,
        37 => 3,
        36 => 4,
        35 => 5,
        _ => 0,
    }
}

/// w · V(t) for the variations that draw a fixed count of random numbers (`draw`, from
/// [`smooth_draw`]) and need only arithmetic, square roots, `floor` and `m`'s elementary
/// functions: every one of 0–49 but rings, fan, fan2, rings2 (`%` or C's `int` of a quotient)
/// and ngon; `None` for the others. Inlined into a loop
/// over points with a constant `v`, each is a vector loop (`CompiledXform::apply_batch`).
#[inline(always)]
pub(super) fn eval_smooth(
    v: u8,
    w: f64,
    k: &[f64; 8],
    pt: &Point,
    draw: [f64; DRAWS],
    m: &mut impl Elementary,
) -> Option<[f64; 2]> {
    let Point { tx: x, ty: y, sumsq: r2, sqrt: r, atan_xy: a, sina: sa, cosa: ca, atan_yx: ayx } = *pt;
    Some(match v {
        // sinusoidal
        1 => [w * m.sin(x), w * m.sin(y)],
        // swirl
        3 => {
            let (s, c) = m.sin_cos(r2);
            [w * (s * x - c * y), w * (c * x + s * y)]
        }
        // handkerchief
        6 => [w * r * m.sin(a + r), w * r * m.cos(a - r)],
        // heart
        7 => {
            let (s, c) = m.sin_cos(r * a);
            let f = w * r;
            [f * s, -f * c]
        }
        // disc
        8 => {
            let aa = a * FRAC_1_PI;
            let (s, c) = m.sin_cos(PI * r);
            [w * s * aa, w * c * aa]
        }
        // spiral
        9 => {
            let rr = r + EPS;
            let f = w / rr;
            let (s, c) = m.sin_cos(rr);
            [f * (ca + s), f * (sa - c)]
        }
        // diamond
        11 => {
            let (s, c) = m.sin_cos(r);
            [w * sa * c, w * ca * s]
        }
        // ex
        12 => {
            let n0 = m.sin(a + r);
            let n1 = m.cos(a - r);
            let m0 = n0 * n0 * n0 * r;
            let m1 = n1 * n1 * n1 * r;
            [w * (m0 + m1), w * (m0 - m1)]
        }
        // julia: one of the two square roots, by a random bit.
        13 => {
            let mut aa = 0.5 * a;
            if draw[0] != 0.0 {
                aa += PI;
            }
            let f = w * r.sqrt();
            let (s, c) = m.sin_cos(aa);
            [f * c, f * s]
        }
        // bent
        14 => {
            let nx = if x < 0.0 { x * 2.0 } else { x };
            let ny = if y < 0.0 { y / 2.0 } else { y };
            [w * nx, w * ny]
        }
        // waves
        15 => [w * (x + k[0] * m.sin(y * k[2])), w * (y + k[1] * m.sin(x * k[3]))],
        // fisheye (flam3's, with the output axes swapped)
        16 => {
            let f = 2.0 * w / (r + 1.0);
            [f * y, f * x]
        }
        // popcorn
        17 => {
            let dx = m.tan(3.0 * y);
            let dy = m.tan(3.0 * x);
            [w * (x + k[0] * m.sin(dx)), w * (y + k[1] * m.sin(dy))]
        }
        // exponential
        18 => {
            let dx = w * m.exp(x - 1.0);
            let (s, c) = m.sin_cos(PI * y);
            [dx * c, dx * s]
        }
        // power
        19 => {
            let f = w * m.pow(r, sa);
            [f * ca, f * sa]
        }
        // cosine
        20 => {
            let (s, c) = m.sin_cos(x * PI);
            [w * (c * m.cosh(y)), w * (-s * m.sinh(y))]
        }
        // eyefish
        27 => {
            let f = (w * 2.0) / (r + 1.0);
            [f * x, f * y]
        }
        // bubble
        28 => {
            let f = w / (0.25 * r2 + 1.0);
            [f * x, f * y]
        }
        // cylinder
        29 => [w * m.sin(x), w * y],
        // blob
        23 => {
            let f = r * (k[0] + k[1] * (0.5 + 0.5 * m.sin(k[2] * a)));
            [w * sa * f, w * ca * f]
        }
        // pdj
        24 => {
            let nx1 = m.cos(k[1] * x);
            let nx2 = m.sin(k[2] * x);
            let ny1 = m.sin(k[0] * y);
            let ny2 = m.cos(k[3] * y);
            [w * (ny1 - nx1), w * (nx2 - ny2)]
        }
        // perspective
        30 => {
            let t = 1.0 / (k[0] - y * k[1]);
            [w * k[0] * x * t, w * k[2] * y * t]
        }
        // curl
        39 => {
            let (c1, c2) = (k[0], k[1]);
            let re = 1.0 + c1 * x + c2 * (x * x - y * y);
            let im = c1 * y + 2.0 * c2 * x * y;
            let f = w / (re * re + im * im);
            [(x * re + y * im) * f, (y * re - x * im) * f]
        }
        // rectangles
        40 => {
            let (rx, ry) = (k[0], k[1]);
            let nx = if rx == 0.0 { x } else { (2.0 * (x / rx).floor() + 1.0) * rx - x };
            let ny = if ry == 0.0 { y } else { (2.0 * (y / ry).floor() + 1.0) * ry - y };
            [w * nx, w * ny]
        }
        // tangent
        42 => [w * m.sin(x) / m.cos(y), w * m.tan(y)],
        // secant2
        46 => {
            let cr = m.cos(w * r);
            let icr = 1.0 / cr;
            [w * x, if cr < 0.0 { w * (icr + 1.0) } else { w * (icr - 1.0) }]
        }
        // julian: one of |power| branches of t^(dist/power), by a uniform draw.
        32 => {
            let branch = c_int(k[1] * draw[0]) as f64;
            let ang = (ayx + 2.0 * PI * branch) / k[0];
            let f = w * m.pow(r2, k[2]);
            let (s, c) = m.sin_cos(ang);
            [f * c, f * s]
        }
        // juliascope: as julian, the odd branches mirrored.
        33 => {
            let branch = (k[1] * draw[0]).trunc();
            // flam3's branch % 2 == 0 for a whole number: half of it is whole.
            let even = branch.is_finite() && (0.5 * branch).trunc() == 0.5 * branch;
            let ang = if even { (2.0 * PI * branch + ayx) / k[0] } else { (2.0 * PI * branch - ayx) / k[0] };
            let (s, c) = m.sin_cos(ang);
            let f = w * m.pow(r2, k[2]);
            [f * c, f * s]
        }
        // noise
        31 => {
            let (s, c) = m.sin_cos(draw[0] * 2.0 * PI);
            let f = w * draw[1];
            [x * f * c, y * f * s]
        }
        // blur
        34 => {
            let (s, c) = m.sin_cos(draw[0] * 2.0 * PI);
            let f = w * draw[1];
            [f * c, f * s]
        }
        // gaussian_blur
        35 => {
            let (s, c) = m.sin_cos(draw[0] * 2.0 * PI);
            let f = w * (draw[1] + draw[2] + draw[3] + draw[4] - 2.0);
            [f * c, f * s]
        }
        // radial_blur
        36 => {
            let g = w * (draw[0] + draw[1] + draw[2] + draw[3] - 2.0);
            let (s, c) = m.sin_cos(ayx + k[0] * g);
            let rz = k[1] * g - 1.0;
            [r * c + rz * x, r * s + rz * y]
        }
        // pie: slices, rotation, thickness
        37 => {
            let slice = c_int(draw[0] * k[0] + 0.5) as f64;
            let ang = k[1] + 2.0 * PI * (slice + draw[1] * k[2]) / k[0];
            let f = w * draw[2];
            let (s, c) = m.sin_cos(ang);
            [f * c, f * s]
        }
        // arch
        41 => {
            let (s, c) = m.sin_cos(draw[0] * w * PI);
            [w * s, w * (s * s) / c]
        }
        // square
        43 => [w * (draw[0] - 0.5), w * (draw[1] - 0.5)],
        // rays
        44 => {
            let ang = w * draw[0] * PI;
            let f = w / (r2 + EPS);
            let t = w * m.tan(ang) * f;
            [t * m.cos(x), t * m.sin(y)]
        }
        // blade
        45 => {
            let (s, c) = m.sin_cos(draw[0] * w * r);
            [w * x * (c + s), w * x * (c - s)]
        }
        // twintrian
        47 => {
            let (s, c) = m.sin_cos(draw[0] * w * r);
            let mut diff = m.ln(s * s) * LOG10_E + c;
            if !(diff.abs() <= 1e10) {
                diff = -30.0;
            }
            [w * x * diff, w * x * (diff - s * PI)]
        }
        // cross
        48 => {
            let s = x * x - y * y;
            let f = w * (1.0 / (s * s + EPS)).sqrt();
            [x * f, y * f]
        }
        // disc2: rot π, sin(twist)', cos(twist)' − 1
        49 => {
            let (s, c) = m.sin_cos(k[0] * (x + y));
            let f = w * a / PI;
            [(s + k[2]) * f, (c + k[1]) * f]
        }
        _ => return None,
    })
}

/// w · V(t) for variation `v` (0–49) with constants `k`.
// Not inlined into `CompiledXform::apply`: inlined, LLVM hoists the arms' transcendental
// functions of the point out of the loop over the terms and computes them all for every point
// (measured: 220 ns instead of 20 for one linear term).
#[inline(never)]
pub(super) fn eval(v: u8, w: f64, k: &[f64; 8], pt: &Point, rng: &mut Pcg32) -> [f64; 2] {
    if let Some(d) = eval_arithmetic(v, w, pt) {
        return d;
    }
    if smooth(v) {
        let draw = smooth_draw(v, rng);
        return eval_smooth(v, w, k, pt, draw, &mut Exact).unwrap_or_default();
    }
    let Point { tx: x, ty: y, sumsq: r2, sqrt: r, atan_xy: a, sina: sa, cosa: ca, atan_yx: ayx } = *pt;
    match v {
        // rings
        21 => {
            let dx = k[0];
            let f = w * ((r + dx) % (2.0 * dx) - dx + r * (1.0 - dx));
            [f * ca, f * sa]
        }
        // fan
        22 => {
            let (dx, dy) = (k[0], k[1]);
            let dx2 = 0.5 * dx;
            let aa = a + if (a + dy) % dx > dx2 { -dx2 } else { dx2 };
            let f = w * r;
            let (s, c) = aa.sin_cos();
            [f * c, f * s]
        }
        // fan2
        25 => {
            let (dx, dy) = (k[0], k[1]);
            let dx2 = 0.5 * dx;
            let t = a + dy - dx * c_int((a + dy) / dx) as f64;
            let aa = if t > dx2 { a - dx2 } else { a + dx2 };
            let f = w * r;
            let (s, c) = aa.sin_cos();
            [f * s, f * c]
        }
        // rings2
        26 => {
            let dx = k[0];
            let f = r + (-2.0 * dx * c_int((r + dx) / (2.0 * dx)) as f64 + r * (1.0 - dx));
            [w * sa * f, w * ca * f]
        }
        // ngon: 2π / sides, power / 2, circle, corners
        38 => {
            let r_factor = r2.powf(k[1]);
            let b = k[0];
            let mut phi = ayx - b * (ayx / b).floor();
            if phi > b / 2.0 {
                phi -= b;
            }
            let amp = (k[3] * (1.0 / (phi.cos() + EPS) - 1.0) + k[2]) / (r_factor + EPS);
            [w * x * amp, w * y * amp]
        }
        _ => [0.0, 0.0],
    }
}
