//! flam3's variations 50–99 in f32 for the chaos game's lanes: the formulas of
//! `variations_plugins.rs` (its oddities kept) on the constants its `prepare` made, rounded
//! once. Where f32's rounding takes a quantity a hair past its domain (an ellipse's half-axis
//! below 1, a cosine's argument past ±1), it is clamped back, as the exact value is inside.

use super::{EPS, Elementary32, Point32, c_int, fmod};
use std::f32::consts::{FRAC_1_PI, FRAC_2_PI, FRAC_PI_2, FRAC_PI_4, PI};

/// 4 / √(3π): butterfly's scale.
const BUTTERFLY: f32 = 1.302_940_1;

/// floor((count·a + π) / 2π): the wedge a point's angle falls in.
#[inline(always)]
fn wedge_index(count: f32, a: f32) -> f32 {
    ((count * a + PI) * FRAC_1_PI * 0.5).floor()
}

/// modulus' fold of one coordinate into [−m, m].
#[inline(always)]
fn modulus(t: f32, m: f32) -> f32 {
    if t > m {
        -m + fmod(t + m, 2.0 * m)
    } else if t < -m {
        m - fmod(m - t, 2.0 * m)
    } else {
        t
    }
}

/// cell's fold of the four quadrants' cells (index `c`, a whole number) on the positive ones, in
/// C's int arithmetic.
#[inline(always)]
fn fold(c: f32) -> f32 {
    let c = c as i32;
    (if c >= 0 { c.wrapping_mul(2) } else { c.wrapping_mul(2).wrapping_add(1).wrapping_neg() }) as f32
}

/// separation's move of one coordinate `t` by `s` (`inside`: its factor inside).
#[inline(always)]
fn separate(t: f32, s: f32, inside: f32) -> f32 {
    let root = (t * t + s * s).sqrt();
    if t > 0.0 { root - t * inside } else { -(root + t * inside) }
}

/// The elliptic coordinates' half-axis of (x, y) with foci ±1 (at least 1).
#[inline(always)]
fn ellipse_axis(x: f32, r2: f32) -> f32 {
    let t = r2 + 1.0;
    let x2 = 2.0 * x;
    (0.5 * ((t + x2).sqrt() + (t - x2).sqrt())).max(1.0)
}

/// w · V(t) of variation `V` (50 and up) with constants `k`, `draw` (and `draw1`) the lane's
/// random numbers (`draw_of`).
#[inline(always)]
#[expect(clippy::too_many_lines, reason = "one arm per variation, as variations_plugins.rs")]
pub(super) fn eval<const V: u8>(
    w: f32,
    k: &[f32; 8],
    p: &Point32,
    [draw, draw1]: [f32; 2],
    m: &mut impl Elementary32,
) -> [f32; 2] {
    let Point32 { x, y, r2, r, a, ayx, .. } = *p;
    match V {
        // super_shape: rnd, m/4, −1/n1, n2, n3, holes
        50 => {
            let (st, ct) = m.sin_cos(k[1] * ayx + FRAC_PI_4);
            let t1 = m.pow(ct.abs(), k[3]);
            let t2 = m.pow(st.abs(), k[4]);
            let rnd = k[0];
            let f = w * ((rnd * draw + (1.0 - rnd) * r) - k[5]) * m.pow(t1 + t2, k[2]) / r;
            [f * x, f * y]
        }
        // flower: petals, holes
        51 => {
            let f = w * (draw - k[1]) * m.cos(k[0] * ayx) / r;
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
            [k[0] * w * s * s * draw, k[1] * w * c * draw1]
        }
        // bent2: x, y
        54 => {
            let nx = if x < 0.0 { x * k[0] } else { x };
            let ny = if y < 0.0 { y * k[1] } else { y };
            [w * nx, w * ny]
        }
        // bipolar: shift
        55 => {
            let t = r2 + 1.0;
            let x2 = 2.0 * x;
            let mut yy = 0.5 * m.atan2(2.0 * y, r2 - 1.0) - FRAC_PI_2 * k[0];
            if yy > FRAC_PI_2 {
                yy = -FRAC_PI_2 + fmod(yy + FRAC_PI_2, PI);
            } else if yy < -FRAC_PI_2 {
                yy = FRAC_PI_2 - fmod(FRAC_PI_2 - yy, PI);
            }
            [w * 0.25 * FRAC_2_PI * m.ln((t + x2) / (t - x2)), w * FRAC_2_PI * yy]
        }
        // boarders: C's rint rounds half to even
        56 => {
            let (rx, ry) = (x.round_ties_even(), y.round_ties_even());
            let (ox, oy) = (x - rx, y - ry);
            let (mut nx, mut ny) = (ox * 0.5 + rx, oy * 0.5 + ry);
            if draw < 0.75 {
                if ox.abs() >= oy.abs() {
                    let s = if ox >= 0.0 { 0.25 } else { -0.25 };
                    nx += s;
                    ny += s * oy / ox;
                } else {
                    let s = if oy >= 0.0 { 0.25 } else { -0.25 };
                    nx += s * ox / oy;
                    ny += s;
                }
            }
            [w * nx, w * ny]
        }
        // butterfly
        57 => {
            let y2 = y * 2.0;
            let f = w * BUTTERFLY * ((y * x).abs() / (EPS + x * x + y2 * y2)).sqrt();
            [f * x, f * y2]
        }
        // cell: size (C's int arithmetic folds the four quadrants' cells on the positive ones)
        58 => {
            let size = k[0];
            let inv = 1.0 / size;
            let (cx, cy) = (c_int((x * inv).floor()), c_int((y * inv).floor()));
            let (dx, dy) = (x - cx * size, y - cy * size);
            [w * (dx + fold(cx) * size), -(w * (dy + fold(cy) * size))]
        }
        // cpow: 2π/power, r/power, i/power, power
        59 => {
            let lnr = 0.5 * m.ln(r2);
            let ang = k[1] * ayx + k[2] * lnr + k[0] * (k[3] * draw).floor();
            let f = w * m.exp(k[1] * lnr - k[2] * ayx);
            let (s, c) = m.sin_cos(ang);
            [f * c, f * s]
        }
        // curve: xamp, yamp, xlength², ylength²
        60 => [w * (x + k[0] * m.exp(-y * y / k[2])), w * (y + k[1] * m.exp(-x * x / k[3]))],
        // edisc
        61 => {
            let xmax = ellipse_axis(x, r2);
            let a1 = m.ln(xmax + (xmax - 1.0).sqrt());
            let a2 = -m.acos((x / xmax).clamp(-1.0, 1.0));
            let ww = w / 11.570_346;
            let (s, c) = m.sin_cos(a1);
            let s = if y > 0.0 { -s } else { s };
            [ww * m.cosh(a2) * c, ww * m.sinh(a2) * s]
        }
        // elliptic
        62 => {
            let xmax = ellipse_axis(x, r2);
            let aa = (x / xmax).clamp(-1.0, 1.0);
            let b = ((1.0 - aa) * (1.0 + aa)).sqrt();
            let l = m.ln(xmax + (xmax - 1.0).sqrt());
            let ww = w / FRAC_PI_2;
            [ww * m.atan2(aa, b), if y > 0.0 { ww * l } else { -(ww * l) }]
        }
        // escher: (1 + cos β) / 2, sin β / 2
        63 => {
            let lnr = 0.5 * m.ln(r2);
            let f = w * m.exp(k[0] * lnr - k[1] * ayx);
            let (s, c) = m.sin_cos(k[0] * ayx + k[1] * lnr);
            [f * c, f * s]
        }
        // foci
        64 => {
            let expx = m.exp(x) * 0.5;
            let expnx = 0.25 / expx;
            let (s, c) = m.sin_cos(y);
            let t = w / (expx + expnx - c);
            [t * (expx - expnx), t * s]
        }
        // lazysusan: spin, space, twist, x, y
        65 => {
            let (xx, yy) = (x - k[3], y + k[4]);
            let rr = (xx * xx + yy * yy).sqrt();
            if rr < w {
                let ang = m.atan2(yy, xx) + k[0] + k[2] * (w - rr);
                let (s, c) = m.sin_cos(ang);
                [w * rr * c + k[3], w * rr * s - k[4]]
            } else {
                let f = w * (1.0 + k[1] / rr);
                [f * xx + k[3], f * yy - k[4]]
            }
        }
        // loonie
        66 => {
            let w2 = w * w;
            let f = if r2 < w2 { w * (w2 / r2 - 1.0).sqrt() } else { w };
            [f * x, f * y]
        }
        // modulus: x, y
        68 => [w * modulus(x, k[0]), w * modulus(y, k[1])],
        // oscilloscope: separation, frequency, amplitude, damping
        69 => {
            let wave = k[2] * m.cos(2.0 * PI * k[1] * x);
            let t = if k[3] == 0.0 { wave } else { wave * m.exp(-x.abs() * k[3]) } + k[0];
            [w * x, if y.abs() <= t { -(w * y) } else { w * y }]
        }
        // polar2
        70 => {
            let f = w * FRAC_1_PI;
            [f * a, f / 2.0 * m.ln(r2)]
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
        73 => [w * separate(x, k[0], k[1]), w * separate(y, k[2], k[3])],
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
            let aa = aa * k[4] + wedge_index(k[2], aa) * k[0];
            let (s, c) = m.sin_cos(aa);
            let f = w * (r + k[1]);
            [f * c, f * s]
        }
        // wedge_julia: angle, count, power, cn, |power|, compensation
        78 => {
            let f = w * m.pow(r2, k[3]);
            let branch = (k[4] * draw).trunc();
            let aa = (ayx + 2.0 * PI * branch) / k[2];
            let aa = aa * k[5] + wedge_index(k[1], aa) * k[0];
            let (s, c) = m.sin_cos(aa);
            [f * c, f * s]
        }
        // wedge_sph: angle, count, hole, swirl, compensation
        79 => {
            let rr = 1.0 / (r + EPS);
            let aa = ayx + k[3] * rr;
            let aa = aa * k[4] + wedge_index(k[1], aa) * k[0];
            let (s, c) = m.sin_cos(aa);
            let f = w * (rr + k[2]);
            [f * c, f * s]
        }
        // whorl: inside, outside
        80 => {
            let turn = if r < w { k[0] } else { k[1] };
            let (s, c) = m.sin_cos(ayx + turn / (w - r));
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
        // coth (flam3's: the conjugate)
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
            let (xpw, xmw) = (x + w, x - w);
            let avgr = w * (2.0 + k[0]) * ((y * y + xpw * xpw).sqrt() / (y * y + xmw * xmw).sqrt()).sqrt();
            let avga = (m.atan2(y, xmw) - m.atan2(y, xpw)) * 0.5;
            let (s, c) = m.sin_cos(avga);
            [avgr * c, avgr * s]
        }
        // mobius: (a t + b) / (c t + d) in complex numbers
        98 => {
            let re_u = k[0] * x - k[1] * y + k[2];
            let im_u = k[0] * y + k[1] * x + k[3];
            let re_v = k[4] * x - k[5] * y + k[6];
            let im_v = k[4] * y + k[5] * x + k[7];
            let f = w / (re_v * re_v + im_v * im_v);
            [f * (re_u * re_v + im_u * im_v), f * (im_u * re_v - re_u * im_v)]
        }
        // linear3D (in the plane)
        99 => [w * x, w * y],
        _ => [0.0, 0.0],
    }
}
