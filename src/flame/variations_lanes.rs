//! The common variations in f32, for the chaos game's lanes (`render_lanes.rs`): the same
//! formulas as `variations_basic.rs` and `variations_plugins.rs` (flam3's oddities kept) on the
//! constants `prepare` made there, rounded once. [`SUPPORTED`] lists them; a flame with any
//! other term takes the f64 chaos game.

use super::trig32::Elementary32;
use std::f32::consts::{FRAC_1_PI, PI};

/// flam3's `EPS`, the guard added to denominators.
const EPS: f32 = 1e-10;

/// The variations [`eval`] holds: linear … cosine (0–20), blob, pdj, eyefish, bubble, cylinder,
/// perspective, julian, juliascope, curl, tangent, flower, wedge_julia.
pub const SUPPORTED: &[u8] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 23, 24, 27, 28, 29, 30, 32, 33, 39, 42,
    51, 78,
];

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

/// What variation `v` draws: none, one bit (julia) or one uniform number in [0, 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Draw {
    None,
    Bit,
    Uniform,
}

/// What [`eval`] of variation `v` draws.
pub const fn draw_of(v: u8) -> Draw {
    match v {
        13 => Draw::Bit,
        32 | 33 | 51 | 78 => Draw::Uniform,
        _ => Draw::None,
    }
}

/// w · V(t) of variation `V` with constants `k`, `draw` its random number ([`draw_of`]).
#[inline(always)]
pub fn eval<const V: u8>(w: f32, k: &[f32; 8], p: &Point32, draw: f32, m: &mut impl Elementary32) -> [f32; 2] {
    let Point32 { x, y, r2, r, a, sa, ca, ayx } = *p;
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
        _ => [0.0, 0.0],
    }
}
