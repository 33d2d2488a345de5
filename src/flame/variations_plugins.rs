//! flam3's variations 50–98 (super_shape … mobius: the Apophysis plugin pack, cothe's complex
//! functions, auger, flux, mobius) and the names after flam3's 99 (`linear3D`, `flatten`).
//! [`prepare`] turns a term's parameters into the constants [`eval`] uses; [`eval`] returns the
//! term's weighted contribution w·V(t). `pre_blur` (67) is not evaluated here: it moves the
//! affine image before every term (`CompiledXform::apply`).
//!
//! flam3's oddities are kept: its coth is the conjugate of coth, cell and oscilloscope subtract
//! from y, loonie, scry and whorl use the weight inside, boarders rounds half to even (C's
//! `rint`), flux's weight shifts its poles.

use super::basic::{c_int, pseudo_gaussian};
use super::{DRAWS, EPS, NEEDS_ATAN_XY, NEEDS_ATAN_YX, NEEDS_SQRT, Point, uniform_draws};
use crate::flame::trig::{Elementary, Exact};
use crate::rng::Pcg32;
use std::f64::consts::{FRAC_1_PI, FRAC_2_PI, FRAC_PI_2, FRAC_PI_4, PI};

/// The first variation number this file evaluates.
pub(super) const FIRST: u8 = 50;

/// Which of [`Point`]'s optional quantities variation `v` reads.
pub(super) fn needs(v: u8) -> u8 {
    // Every one of these is taken to read r.
    NEEDS_SQRT
        | match v {
            70 => NEEDS_ATAN_XY,
            50 | 51 | 59 | 63 | 77..=80 | 83 => NEEDS_ATAN_YX,
            _ => 0,
        }
}

/// The constants of variation `v` from its parameters `p` (in the table's order).
pub(super) fn prepare(v: u8, p: [f64; 8]) -> [f64; 8] {
    let mut k = p;
    match v {
        // super_shape: rnd clamped to [0, 1] (as flam3's reader does), m / 4, −1 / n1.
        50 => {
            k[0] = p[0].clamp(0.0, 1.0);
            k[1] = p[1] / 4.0;
            k[2] = -1.0 / p[2];
        }
        // cpow: 2π / power, r / power, i / power, power.
        59 => {
            k[0] = 2.0 * PI / p[2];
            k[1] = p[0] / p[2];
            k[2] = p[1] / p[2];
            k[3] = p[2];
        }
        // curve: the squared lengths, at least 1e-20.
        60 => {
            k[2] = (p[2] * p[2]).max(1e-20);
            k[3] = (p[3] * p[3]).max(1e-20);
        }
        // escher: (1 + cos β) / 2, sin β / 2.
        63 => {
            let (s, c) = p[0].sin_cos();
            k[0] = 0.5 * (1.0 + c);
            k[1] = 0.5 * s;
        }
        // wedge: angle, hole, count, swirl, compensation 1 − angle·count / 2π.
        77 => k[4] = 1.0 - p[0] * p[2] * FRAC_1_PI * 0.5,
        // wedge_julia: angle, count, power, dist / power / 2, |power|, compensation.
        78 => {
            k[3] = p[3] / p[2] / 2.0;
            k[4] = p[2].abs();
            k[5] = 1.0 - p[0] * p[1] * FRAC_1_PI * 0.5;
        }
        // wedge_sph: angle, count, hole, swirl, compensation.
        79 => k[4] = 1.0 - p[0] * p[1] * FRAC_1_PI * 0.5,
        _ => {}
    }
    k
}

/// floor((count·a + π) / 2π): the wedge a point's angle falls in.
#[inline(always)]
fn wedge_index(count: f64, a: f64) -> f64 {
    ((count * a + PI) * FRAC_1_PI * 0.5).floor()
}

/// Whether [`eval_smooth`] holds variation `v`'s formula.
pub(super) fn smooth(v: u8) -> bool {
    matches!(v, 50..=54 | 60 | 63 | 64 | 66 | 69..=99)
}

/// The random numbers [`eval_smooth`] takes for variation `v`, drawn from `rng` in flam3's
/// order: super_shape, flower, conic and wedge_julia one uniform number in [0, 1), parabola
/// two; 0 where nothing is drawn.
#[inline(always)]
pub(super) fn smooth_draw(v: u8, rng: &mut Pcg32) -> [f64; DRAWS] {
    uniform_draws(smooth_draw_count(v), rng)
}

/// How many numbers [`smooth_draw`] draws for variation `v`.
pub(super) const fn smooth_draw_count(v: u8) -> usize {
    match v {
        50 | 51 | 52 | 78 => 1,
        53 => 2,
        _ => 0,
    }
}

/// w · V(t) for the variations 50 and up that draw a fixed count of random numbers (`draw`,
/// from [`smooth_draw`]) and need only arithmetic, square roots, `floor` and `m`'s elementary
/// functions (as `basic::eval_smooth`); `None` for the others. Inlined into a loop over points
/// with a constant `v`, each is a vector loop (`CompiledXform::apply_batch`).
#[inline(always)]
pub(super) fn eval_smooth(
    v: u8,
    w: f64,
    k: &[f64; 8],
    pt: &Point,
    draw: [f64; DRAWS],
    m: &mut impl Elementary,
) -> Option<[f64; 2]> {
    let Point { tx: x, ty: y, sumsq: r2, sqrt: r, atan_xy: a, atan_yx: ayx, .. } = *pt;
    Some(match v {
        // super_shape: rnd, m/4, −1/n1, n2, n3, holes
        50 => {
            let (st, ct) = m.sin_cos(k[1] * ayx + FRAC_PI_4);
            let t1 = m.pow(ct.abs(), k[3]);
            let t2 = m.pow(st.abs(), k[4]);
            let rnd = k[0];
            let f = w * ((rnd * draw[0] + (1.0 - rnd) * r) - k[5]) * m.pow(t1 + t2, k[2]) / r;
            [f * x, f * y]
        }
        // parabola: height, width
        53 => {
            let (s, c) = m.sin_cos(r);
            let nx = k[0] * w * s * s * draw[0];
            let ny = k[1] * w * c * draw[1];
            [nx, ny]
        }
        // flower: petals, holes
        51 => {
            let f = w * (draw[0] - k[1]) * m.cos(k[0] * ayx) / r;
            [f * x, f * y]
        }
        // conic: eccentricity, holes
        52 => {
            let ct = x / r;
            let f = w * (draw[0] - k[1]) * k[0] / (1.0 + k[0] * ct) / r;
            [f * x, f * y]
        }
        // bent2: x, y
        54 => {
            let nx = if x < 0.0 { x * k[0] } else { x };
            let ny = if y < 0.0 { y * k[1] } else { y };
            [w * nx, w * ny]
        }
        // curve: xamp, yamp, xlength², ylength²
        60 => [w * (x + k[0] * m.exp(-y * y / k[2])), w * (y + k[1] * m.exp(-x * x / k[3]))],
        // escher: vc, vd
        63 => {
            let lnr = 0.5 * m.ln(r2);
            let mag = w * m.exp(k[0] * lnr - k[1] * ayx);
            let (s, c) = m.sin_cos(k[0] * ayx + k[1] * lnr);
            [mag * c, mag * s]
        }
        // foci
        64 => {
            let expx = m.exp(x) * 0.5;
            let expnx = 0.25 / expx;
            let (s, c) = m.sin_cos(y);
            let t = w / (expx + expnx - c);
            [t * (expx - expnx), t * s]
        }
        // loonie
        66 => {
            let w2 = w * w;
            if r2 < w2 {
                let f = w * (w2 / r2 - 1.0).sqrt();
                [f * x, f * y]
            } else {
                [w * x, w * y]
            }
        }
        // oscilloscope: separation, frequency, amplitude, damping
        69 => {
            let tpf = 2.0 * PI * k[1];
            let t = if k[3] == 0.0 {
                k[2] * m.cos(tpf * x) + k[0]
            } else {
                k[2] * m.exp(-x.abs() * k[3]) * m.cos(tpf * x) + k[0]
            };
            if y.abs() <= t { [w * x, -(w * y)] } else { [w * x, w * y] }
        }
        // polar2
        70 => {
            let p2v = w / PI;
            [p2v * a, p2v / 2.0 * m.ln(r2)]
        }
        // popcorn2: x, y, c
        71 => {
            let (tx, ty) = (m.tan(y * k[2]), m.tan(x * k[2]));
            [w * (x + k[0] * m.sin(tx)), w * (y + k[1] * m.sin(ty))]
        }
        // scry
        72 => {
            let f = 1.0 / (r * (r2 + 1.0 / (w + EPS)));
            [x * f, y * f]
        }
        // separation: x, xinside, y, yinside
        73 => {
            let nx = if x > 0.0 {
                w * ((x * x + k[0] * k[0]).sqrt() - x * k[1])
            } else {
                -(w * ((x * x + k[0] * k[0]).sqrt() + x * k[1]))
            };
            let ny = if y > 0.0 {
                w * ((y * y + k[2] * k[2]).sqrt() - y * k[3])
            } else {
                -(w * ((y * y + k[2] * k[2]).sqrt() + y * k[3]))
            };
            [nx, ny]
        }
        // split: xsize, ysize
        74 => {
            let ny = if m.cos(x * k[0] * PI) >= 0.0 { w * y } else { -(w * y) };
            let nx = if m.cos(y * k[1] * PI) >= 0.0 { w * x } else { -(w * x) };
            [nx, ny]
        }
        // splits: x, y
        75 => [
            if x >= 0.0 { w * (x + k[0]) } else { w * (x - k[0]) },
            if y >= 0.0 { w * (y + k[1]) } else { w * (y - k[1]) },
        ],
        // stripes: space, warp
        76 => {
            let rx = (x + 0.5).floor();
            let ox = x - rx;
            [w * (ox * (1.0 - k[0]) + rx), w * (y + ox * ox * k[1])]
        }
        // wedge: angle, hole, count, swirl, compensation
        77 => {
            let aa = ayx + k[3] * r;
            let c = wedge_index(k[2], aa);
            let aa = aa * k[4] + c * k[0];
            let (s, co) = m.sin_cos(aa);
            let f = w * (r + k[1]);
            [f * co, f * s]
        }
        // wedge_julia: angle, count, power, cn, |power|, compensation
        78 => {
            let f = w * m.pow(r2, k[3]);
            let branch = c_int(k[4] * draw[0]) as f64;
            let aa = (ayx + 2.0 * PI * branch) / k[2];
            let c = wedge_index(k[1], aa);
            let aa = aa * k[5] + c * k[0];
            let (s, co) = m.sin_cos(aa);
            [f * co, f * s]
        }
        // wedge_sph: angle, count, hole, swirl, compensation
        79 => {
            let rr = 1.0 / (r + EPS);
            let aa = ayx + k[3] * rr;
            let c = wedge_index(k[1], aa);
            let aa = aa * k[4] + c * k[0];
            let (s, co) = m.sin_cos(aa);
            let f = w * (rr + k[2]);
            [f * co, f * s]
        }
        // whorl: inside, outside
        80 => {
            let aa = if r < w { ayx + k[0] / (w - r) } else { ayx + k[1] / (w - r) };
            let (s, c) = m.sin_cos(aa);
            [w * r * c, w * r * s]
        }
        // waves2: scalex, scaley, freqx, freqy
        81 => [w * (x + k[0] * m.sin(y * k[2])), w * (y + k[1] * m.sin(x * k[3]))],
        // exp
        82 => {
            let e = m.exp(x);
            let (s, c) = m.sin_cos(y);
            [w * e * c, w * e * s]
        }
        // log
        83 => [w * 0.5 * m.ln(r2), w * ayx],
        // sin
        84 => {
            let (s, c) = m.sin_cos(x);
            [w * s * m.cosh(y), w * c * m.sinh(y)]
        }
        // cos
        85 => {
            let (s, c) = m.sin_cos(x);
            [w * c * m.cosh(y), -(w * s * m.sinh(y))]
        }
        // tan
        86 => {
            let (s, c) = m.sin_cos(2.0 * x);
            let den = 1.0 / (c + m.cosh(2.0 * y));
            [w * den * s, w * den * m.sinh(2.0 * y)]
        }
        // sec
        87 => {
            let (s, c) = m.sin_cos(x);
            let den = 2.0 / (m.cos(2.0 * x) + m.cosh(2.0 * y));
            [w * den * c * m.cosh(y), w * den * s * m.sinh(y)]
        }
        // csc
        88 => {
            let (s, c) = m.sin_cos(x);
            let den = 2.0 / (m.cosh(2.0 * y) - m.cos(2.0 * x));
            [w * den * s * m.cosh(y), -(w * den * c * m.sinh(y))]
        }
        // cot
        89 => {
            let (s, c) = m.sin_cos(2.0 * x);
            let den = 1.0 / (m.cosh(2.0 * y) - c);
            [w * den * s, -(w * den) * m.sinh(2.0 * y)]
        }
        // sinh
        90 => {
            let (s, c) = m.sin_cos(y);
            [w * m.sinh(x) * c, w * m.cosh(x) * s]
        }
        // cosh
        91 => {
            let (s, c) = m.sin_cos(y);
            [w * m.cosh(x) * c, w * m.sinh(x) * s]
        }
        // tanh
        92 => {
            let (s, c) = m.sin_cos(2.0 * y);
            let den = 1.0 / (c + m.cosh(2.0 * x));
            [w * den * m.sinh(2.0 * x), w * den * s]
        }
        // sech
        93 => {
            let (s, c) = m.sin_cos(y);
            let den = 2.0 / (m.cos(2.0 * y) + m.cosh(2.0 * x));
            [w * den * c * m.cosh(x), -(w * den * s * m.sinh(x))]
        }
        // csch
        94 => {
            let (s, c) = m.sin_cos(y);
            let den = 2.0 / (m.cosh(2.0 * x) - m.cos(2.0 * y));
            [w * den * m.sinh(x) * c, -(w * den * m.cosh(x) * s)]
        }
        // coth
        95 => {
            let (s, c) = m.sin_cos(2.0 * y);
            let den = 1.0 / (m.cosh(2.0 * x) - c);
            [w * den * m.sinh(2.0 * x), w * den * s]
        }
        // auger: freq, weight, sym, scale
        96 => {
            let s = m.sin(k[0] * x);
            let t = m.sin(k[0] * y);
            let dy = y + k[1] * (k[3] * s / 2.0 + y.abs() * s);
            let dx = x + k[1] * (k[3] * t / 2.0 + x.abs() * t);
            [w * (x + k[2] * (dx - x)), w * dy]
        }
        // flux: spread
        97 => {
            let xpw = x + w;
            let xmw = x - w;
            let avgr = w * (2.0 + k[0]) * ((y * y + xpw * xpw).sqrt() / (y * y + xmw * xmw).sqrt()).sqrt();
            let avga = (m.atan2(y, xmw) - m.atan2(y, xpw)) * 0.5;
            [avgr * m.cos(avga), avgr * m.sin(avga)]
        }
        // mobius: (a t + b) / (c t + d) in complex numbers
        98 => {
            let (re_a, im_a, re_b, im_b, re_c, im_c, re_d, im_d) = (k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7]);
            let re_u = re_a * x - im_a * y + re_b;
            let im_u = re_a * y + im_a * x + im_b;
            let re_v = re_c * x - im_c * y + re_d;
            let im_v = re_c * y + im_c * x + im_d;
            let rad_v = w / (re_v * re_v + im_v * im_v);
            [rad_v * (re_u * re_v + im_u * im_v), rad_v * (im_u * re_v - re_u * im_v)]
        }
        // linear3D
        99 => [w * x, w * y],
        _ => return None,
    })
}

/// w · V(t) for variation `v` (50 and up) with constants `k`.
// Not inlined into `CompiledXform::apply`: inlined, LLVM hoists the arms' transcendental
// functions of the point out of the loop over the terms and computes them all for every point
// (measured: 220 ns instead of 20 for one linear term).
#[inline(never)]
pub(super) fn eval(v: u8, w: f64, k: &[f64; 8], pt: &Point, rng: &mut Pcg32) -> [f64; 2] {
    if smooth(v) {
        let draw = smooth_draw(v, rng);
        return eval_smooth(v, w, k, pt, draw, &mut Exact).unwrap_or_default();
    }
    let Point { tx: x, ty: y, sumsq: r2, atan_yx: ayx, .. } = *pt;
    match v {
        // bipolar: shift
        55 => {
            let t = r2 + 1.0;
            let x2 = 2.0 * x;
            let ps = -FRAC_PI_2 * k[0];
            let mut yy = 0.5 * (2.0 * y).atan2(r2 - 1.0) + ps;
            if yy > FRAC_PI_2 {
                yy = -FRAC_PI_2 + (yy + FRAC_PI_2) % PI;
            } else if yy < -FRAC_PI_2 {
                yy = FRAC_PI_2 - (FRAC_PI_2 - yy) % PI;
            }
            [w * 0.25 * FRAC_2_PI * ((t + x2) / (t - x2)).ln(), w * FRAC_2_PI * yy]
        }
        // boarders
        56 => {
            let (rx, ry) = (x.round_ties_even(), y.round_ties_even());
            let (ox, oy) = (x - rx, y - ry);
            if rng.next_f64() >= 0.75 {
                [w * (ox * 0.5 + rx), w * (oy * 0.5 + ry)]
            } else if ox.abs() >= oy.abs() {
                if ox >= 0.0 {
                    [w * (ox * 0.5 + rx + 0.25), w * (oy * 0.5 + ry + 0.25 * oy / ox)]
                } else {
                    [w * (ox * 0.5 + rx - 0.25), w * (oy * 0.5 + ry - 0.25 * oy / ox)]
                }
            } else if oy >= 0.0 {
                [w * (ox * 0.5 + rx + ox / oy * 0.25), w * (oy * 0.5 + ry + 0.25)]
            } else {
                [w * (ox * 0.5 + rx - ox / oy * 0.25), w * (oy * 0.5 + ry - 0.25)]
            }
        }
        // butterfly: 4 / √(3π) · w
        57 => {
            let wx = w * 1.302_940_031_741_119_8;
            let y2 = y * 2.0;
            let f = wx * ((y * x).abs() / (EPS + x * x + y2 * y2)).sqrt();
            [f * x, f * y2]
        }
        // cell: size
        58 => {
            let size = k[0];
            let inv = 1.0 / size;
            // The cell's index as C's int (size 0 gives i32::MIN, times 0: flam3's (w·x, −w·y)).
            let cx = c_int((x * inv).floor());
            let cy = c_int((y * inv).floor());
            let dx = x - cx as f64 * size;
            let dy = y - cy as f64 * size;
            // Interleave the four quadrants' cells on the positive ones (C's int arithmetic).
            let fold =
                |c: i32| if c >= 0 { c.wrapping_mul(2) } else { c.wrapping_mul(2).wrapping_add(1).wrapping_neg() };
            [w * (dx + fold(cx) as f64 * size), -(w * (dy + fold(cy) as f64 * size))]
        }
        // cpow: 2π/power, r/power, i/power, power
        59 => {
            let lnr = 0.5 * r2.ln();
            let (va, vc, vd) = (k[0], k[1], k[2]);
            let ang = vc * ayx + vd * lnr + va * (k[3] * rng.next_f64()).floor();
            let m = w * (vc * lnr - vd * ayx).exp();
            let (s, c) = ang.sin_cos();
            [m * c, m * s]
        }
        // edisc
        61 => {
            let tmp = r2 + 1.0;
            let tmp2 = 2.0 * x;
            let xmax = ((tmp + tmp2).sqrt() + (tmp - tmp2).sqrt()) * 0.5;
            let a1 = (xmax + (xmax - 1.0).sqrt()).ln();
            let a2 = -(x / xmax).acos();
            let ww = w / 11.570_346_32;
            let (mut snv, csv) = a1.sin_cos();
            if y > 0.0 {
                snv = -snv;
            }
            [ww * a2.cosh() * csv, ww * a2.sinh() * snv]
        }
        // elliptic
        62 => {
            let tmp = r2 + 1.0;
            let x2 = 2.0 * x;
            let xmax = 0.5 * ((tmp + x2).sqrt() + (tmp - x2).sqrt());
            let aa = x / xmax;
            let b = 1.0 - aa * aa;
            let ssx = xmax - 1.0;
            let ww = w / FRAC_PI_2;
            let b = if b < 0.0 { 0.0 } else { b.sqrt() };
            let ssx = if ssx < 0.0 { 0.0 } else { ssx.sqrt() };
            let l = (xmax + ssx).ln();
            [ww * aa.atan2(b), if y > 0.0 { ww * l } else { -(ww * l) }]
        }
        // lazysusan: spin, space, twist, x, y
        65 => {
            let (spin, space, twist, lx, ly) = (k[0], k[1], k[2], k[3], k[4]);
            let xx = x - lx;
            let yy = y + ly;
            let rr = (xx * xx + yy * yy).sqrt();
            if rr < w {
                let ang = yy.atan2(xx) + spin + twist * (w - rr);
                let (s, c) = ang.sin_cos();
                let f = w * rr;
                [f * c + lx, f * s - ly]
            } else {
                let f = w * (1.0 + space / rr);
                [f * xx + lx, f * yy - ly]
            }
        }
        // modulus: x, y
        68 => [w * modulus(x, k[0]), w * modulus(y, k[1])],
        // flatten (z = 0 only) and anything unknown: nothing in the plane.
        _ => [0.0, 0.0],
    }
}

/// modulus' fold of one coordinate into [−m, m].
#[inline(always)]
fn modulus(t: f64, m: f64) -> f64 {
    if t > m {
        -m + (t + m) % (2.0 * m)
    } else if t < -m {
        m - (m - t) % (2.0 * m)
    } else {
        t
    }
}

/// `pre_blur`'s move of the affine image: a pseudo-Gaussian distance of scale w in a uniform
/// direction.
#[inline]
pub(super) fn pre_blur_offset(w: f64, rng: &mut Pcg32) -> [f64; 2] {
    let g = w * pseudo_gaussian(rng);
    let (s, c) = (rng.next_f64() * 2.0 * PI).sin_cos();
    [g * c, g * s]
}
