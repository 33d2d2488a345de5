//! The common variations in f32, for the chaos game's lanes (`render_lanes.rs`): the same
//! formulas as `variations_basic.rs` and `variations_plugins.rs` (flam3's oddities kept) on the
//! constants `prepare` made there, rounded once. [`SUPPORTED`] lists them; a flame with any
//! other term takes the f64 chaos game.

use super::trig32::Elementary32;
use std::f32::consts::{FRAC_1_PI, PI};

/// flam3's `EPS`, the guard added to denominators.
const EPS: f32 = 1e-10;

/// The variations [`eval`] holds: linear … cosine (0–20), blob, pdj, eyefish … juliascope (27–30,
/// 32, 33), noise, the blurs, pie, curl … disc2 (39–49 but ngon), super_shape, flower, conic,
/// parabola, bent2, curve, wedge_julia.
pub const SUPPORTED: &[u8] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 23, 24, 27, 28, 29, 30, 31, 32, 33, 34,
    35, 36, 37, 39, 40, 41, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 60, 78,
];

/// Most random numbers a variation draws.
pub const DRAWS: usize = 5;

/// The point's quantities, one lane: as `variations::Point`, in f32.
#[derive(Clone, Copy, Debug, Default)]
pub struct Point32 {
    pub x: f32,
    pub y: f32,
    /// x² + y².
    pub r2: f32,
    /// √(x² + y²).
    pub r: f32,
    /// atan2(x, y): flam3's swapped angle.
    pub a: f32,
    /// x / r, y / r (flam3's `precalc_sina`, `precalc_cosa`).
    pub sa: f32,
    pub ca: f32,
    /// atan2(y, x).
    pub ayx: f32,
}

/// What variation `v` draws: none, one bit (julia) or uniform numbers in [0, 1), as many as
/// flam3 draws for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Draw {
    None,
    Bit,
    Uniform(usize),
}

/// What [`eval`] of variation `v` draws.
pub const fn draw_of(v: u8) -> Draw {
    match v {
        13 => Draw::Bit,
        32 | 33 | 41 | 44 | 45 | 47 | 50 | 51 | 52 | 78 => Draw::Uniform(1),
        31 | 34 | 43 | 53 => Draw::Uniform(2),
        37 => Draw::Uniform(3),
        36 => Draw::Uniform(4),
        35 => Draw::Uniform(5),
        _ => Draw::None,
    }
}

/// w · V(t) of variation `V` with constants `k` in lane `l`, `draws` the lanes' random numbers
/// ([`draw_of`]).
#[inline(always)]
pub fn eval<const V: u8, const L: usize>(
    w: f32,
    k: &[f32; 8],
    p: &Point32,
    draws: &[[f32; L]; DRAWS],
    l: usize,
    m: &mut impl Elementary32,
) -> [f32; 2] {
    let Point32 { x, y, r2, r, a, sa, ca, ayx } = *p;
    let draws = |i: usize| draws[i][l];
    let draw = draws(0);
    match V {
        // linear
        0 => [w * x, w * y],
        // sinusoidal
        1 => [w * m.sin(x), w * m.sin(y)],
        // spherical
        2 => {
            let f = w / (r2 + EPS);
            [f * x, f * y]
        }
        // swirl
        3 => {
            let (s, c) = m.sin_cos(r2);
            [w * (s * x - c * y), w * (c * x + s * y)]
        }
        // horseshoe
        4 => {
            let f = w / (r + EPS);
            [(x - y) * (x + y) * f, 2.0 * x * y * f]
        }
        // polar
        5 => [w * (a * FRAC_1_PI), w * (r - 1.0)],
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
        // hyperbolic
        10 => {
            let rr = r + EPS;
            [w * sa / rr, w * ca * rr]
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
            let aa = 0.5 * a + if draw != 0.0 { PI } else { 0.0 };
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
        // perspective
        30 => {
            let t = 1.0 / (k[0] - y * k[1]);
            [w * k[0] * x * t, w * k[2] * y * t]
        }
        // julian: one of |power| branches of t^(dist/power), by a uniform draw.
        32 => {
            let branch = (k[1] * draw).trunc();
            let ang = (ayx + 2.0 * PI * branch) / k[0];
            let f = w * m.pow(r2, k[2]);
            let (s, c) = m.sin_cos(ang);
            [f * c, f * s]
        }
        // juliascope: as julian, the odd branches mirrored.
        33 => {
            let branch = (k[1] * draw).trunc();
            let even = (0.5 * branch).trunc() == 0.5 * branch;
            let ang = if even { (2.0 * PI * branch + ayx) / k[0] } else { (2.0 * PI * branch - ayx) / k[0] };
            let (s, c) = m.sin_cos(ang);
            let f = w * m.pow(r2, k[2]);
            [f * c, f * s]
        }
        // curl
        39 => {
            let (c1, c2) = (k[0], k[1]);
            let re = 1.0 + c1 * x + c2 * (x * x - y * y);
            let im = c1 * y + 2.0 * c2 * x * y;
            let f = w / (re * re + im * im);
            [(x * re + y * im) * f, (y * re - x * im) * f]
        }
        // tangent
        42 => [w * m.sin(x) / m.cos(y), w * m.tan(y)],
        // flower: petals, holes
        51 => {
            let f = w * (draw - k[1]) * m.cos(k[0] * ayx) / r;
            [f * x, f * y]
        }
        // wedge_julia: angle, count, power, cn, |power|, compensation
        78 => {
            let f = w * m.pow(r2, k[3]);
            let branch = (k[4] * draw).trunc();
            let aa = (ayx + 2.0 * PI * branch) / k[2];
            let c = ((k[1] * aa + PI) * FRAC_1_PI * 0.5).floor();
            let aa = aa * k[5] + c * k[0];
            let (s, co) = m.sin_cos(aa);
            [f * co, f * s]
        }
        // noise
        31 => {
            let (s, c) = m.sin_cos(draw * 2.0 * PI);
            let f = w * draws(1);
            [x * f * c, y * f * s]
        }
        // blur
        34 => {
            let (s, c) = m.sin_cos(draw * 2.0 * PI);
            let f = w * draws(1);
            [f * c, f * s]
        }
        // gaussian_blur
        35 => {
            let (s, c) = m.sin_cos(draw * 2.0 * PI);
            let f = w * (draws(1) + draws(2) + draws(3) + draws(4) - 2.0);
            [f * c, f * s]
        }
        // radial_blur
        36 => {
            let g = w * (draws(0) + draws(1) + draws(2) + draws(3) - 2.0);
            let (s, c) = m.sin_cos(ayx + k[0] * g);
            let rz = k[1] * g - 1.0;
            [r * c + rz * x, r * s + rz * y]
        }
        // pie: slices, rotation, thickness
        37 => {
            let slice = (draw * k[0] + 0.5).trunc();
            let ang = k[1] + 2.0 * PI * (slice + draws(1) * k[2]) / k[0];
            let f = w * draws(2);
            let (s, c) = m.sin_cos(ang);
            [f * c, f * s]
        }
        // rectangles
        40 => {
            let (rx, ry) = (k[0], k[1]);
            let nx = if rx == 0.0 { x } else { (2.0 * (x / rx).floor() + 1.0) * rx - x };
            let ny = if ry == 0.0 { y } else { (2.0 * (y / ry).floor() + 1.0) * ry - y };
            [w * nx, w * ny]
        }
        // arch
        41 => {
            let (s, c) = m.sin_cos(draw * w * PI);
            [w * s, w * (s * s) / c]
        }
        // square
        43 => [w * (draw - 0.5), w * (draws(1) - 0.5)],
        // rays
        44 => {
            let ang = w * draw * PI;
            let f = w / (r2 + EPS);
            let t = w * m.tan(ang) * f;
            [t * m.cos(x), t * m.sin(y)]
        }
        // blade
        45 => {
            let (s, c) = m.sin_cos(draw * w * r);
            [w * x * (c + s), w * x * (c - s)]
        }
        // secant2
        46 => {
            let cr = m.cos(w * r);
            let icr = 1.0 / cr;
            [w * x, if cr < 0.0 { w * (icr + 1.0) } else { w * (icr - 1.0) }]
        }
        // twintrian
        47 => {
            let (s, c) = m.sin_cos(draw * w * r);
            let mut diff = m.ln(s * s) * std::f32::consts::LOG10_E + c;
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
        // super_shape: rnd, m/4, −1/n1, n2, n3, holes
        50 => {
            let (st, ct) = m.sin_cos(k[1] * ayx + std::f32::consts::FRAC_PI_4);
            let t1 = m.pow(ct.abs(), k[3]);
            let t2 = m.pow(st.abs(), k[4]);
            let rnd = k[0];
            let f = w * ((rnd * draw + (1.0 - rnd) * r) - k[5]) * m.pow(t1 + t2, k[2]) / r;
            [f * x, f * y]
        }
        // conic: eccentricity, holes
        52 => {
            let ct = x / r;
            let f = w * (draw - k[1]) * k[0] / (1.0 + k[0] * ct) / r;
            [f * x, f * y]
        }
        // parabola: height, width
        53 => {
            let (s, c) = m.sin_cos(r);
            [k[0] * w * s * s * draw, k[1] * w * c * draws(1)]
        }
        // bent2: x, y
        54 => {
            let nx = if x < 0.0 { x * k[0] } else { x };
            let ny = if y < 0.0 { y * k[1] } else { y };
            [w * nx, w * ny]
        }
        // curve: xamp, yamp, xlength², ylength²
        60 => [w * (x + k[0] * m.exp(-y * y / k[2])), w * (y + k[1] * m.exp(-x * x / k[3]))],
        _ => [0.0, 0.0],
    }
}
