//! The variations in f32, for the chaos game's lanes (`render_lanes.rs`): the same formulas as
//! `variations_basic.rs` and `variations_plugins.rs` (flam3's oddities kept) on the constants
//! `prepare` made there, rounded once; 50 and up in `variations_lanes_plugins.rs`.
//! [`SUPPORTED`] lists them.

use super::trig32::Elementary32;
use std::f32::consts::{FRAC_1_PI, PI};

/// flam3's `EPS`, the guard added to denominators.
const EPS: f32 = 1e-10;

/// The variations [`eval`] holds: every one of the table but `pre_blur` (which `render_lanes.rs`
/// applies to the affine image), that is flam3's 98 others, `linear3D`, and `flatten` (which adds
/// nothing in the plane).
pub const SUPPORTED: &[u8] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30,
    31, 32, 33, 34, 35, 36, 37, 38, 39, 40, 41, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59,
    60, 61, 62, 63, 64, 65, 66, 68, 69, 70, 71, 72, 73, 74, 75, 76, 77, 78, 79, 80, 81, 82, 83, 84, 85, 86, 87, 88, 89,
    90, 91, 92, 93, 94, 95, 96, 97, 98, 99, 100,
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
        32 | 33 | 41 | 44 | 45 | 47 | 50 | 51 | 52 | 56 | 59 | 78 => Draw::Uniform(1),
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
    if V >= 50 {
        return plugins::eval::<V>(w, k, p, [draws[0][l], draws[1][l]], m);
    }
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
        // rings: dx² + EPS
        21 => {
            let dx = k[0];
            let f = w * (fmod(r + dx, 2.0 * dx) - dx + r * (1.0 - dx));
            [f * ca, f * sa]
        }
        // fan: π (e² + EPS), f
        22 => {
            let (dx, dy) = (k[0], k[1]);
            let dx2 = 0.5 * dx;
            let aa = a + if fmod(a + dy, dx) > dx2 { -dx2 } else { dx2 };
            let (s, c) = m.sin_cos(aa);
            [w * r * c, w * r * s]
        }
        // fan2: π (x² + EPS), y
        25 => {
            let (dx, dy) = (k[0], k[1]);
            let dx2 = 0.5 * dx;
            let t = a + dy - dx * c_int((a + dy) / dx);
            let (s, c) = m.sin_cos(if t > dx2 { a - dx2 } else { a + dx2 });
            [w * r * s, w * r * c]
        }
        // rings2: val² + EPS
        26 => {
            let dx = k[0];
            let f = r + (-2.0 * dx * c_int((r + dx) / (2.0 * dx)) + r * (1.0 - dx));
            [w * sa * f, w * ca * f]
        }
        // ngon: 2π / sides, power / 2, circle, corners
        38 => {
            let r_factor = m.pow(r2, k[1]);
            let b = k[0];
            let mut phi = ayx - b * (ayx / b).floor();
            if phi > b / 2.0 {
                phi -= b;
            }
            let amp = (k[3] * (1.0 / (m.cos(phi) + EPS) - 1.0) + k[2]) / (r_factor + EPS);
            [w * x * amp, w * y * amp]
        }
        _ => [0.0, 0.0],
    }
}

/// C's conversion of `v` to `int` as flam3's x86-64 builds do it (`variations_basic::c_int`),
/// as a float: toward zero, and −2^31 for NaN and anything out of range.
#[inline(always)]
fn c_int(v: f32) -> f32 {
    const LIMIT: f32 = 2_147_483_648.0;
    #[expect(clippy::manual_range_contains, reason = "`contains` is two branches, not a vector compare")]
    let inside = (v >= -LIMIT) & (v < LIMIT);
    if inside { v.trunc() } else { -LIMIT }
}

/// C's `fmod` as vector operations: a − b·trunc(a / b), kept within ±|b| (where the quotient is
/// past f32's whole numbers; the exact remainder of such an f32 is no nearer flam3's f64 one).
/// (Rust's `%` on f32 is a call to libm's `fmodf` for each lane.)
#[inline(always)]
fn fmod(a: f32, b: f32) -> f32 {
    let r = a - b * (a / b).trunc();
    let limit = b.abs();
    if r.abs() > limit { limit.copysign(r) } else { r }
}

#[path = "variations_lanes_plugins.rs"]
mod plugins;
