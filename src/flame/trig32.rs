//! Elementary functions in f32 for the flame chaos game's lanes (`render_lanes.rs`): sin and cos,
//! tan, atan2 (and acos through it), exp, ln and pow as branch-free polynomial cores, so that a loop of them over the
//! lanes is a vector loop. Each core also says whether its argument was in its range; beyond it
//! the lanes are computed again by [`Exact32`] (in f64, rounded), which is what every core
//! approximates. Within range the cores are within a few f32 ulps (Cody and Waite's reduction
//! and Cephes's and fdlibm's polynomials, written anew here).

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Largest |x| the sin/cos reduction is exact for (three-part π/2, the quadrant below 2^13).
const REDUCE_LIMIT: f32 = 8192.0;
/// 1.5 · 2^23: added and subtracted, rounds a float below 2^22 to the nearest whole number.
const ROUND_MAGIC: f32 = 12_582_912.0;
/// π/2 in three parts, the first two short enough that q times them is exact for q < 2^13.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_79e-8;
/// The minimax odd polynomial of sin on [−π/2, π/2] past its first term (r³ … r⁹ coefficients;
/// within 3e-8 of sin there).
const SIN_HALF_PI: [f32; 4] = [-1.666_666_6e-1, 8.333_258e-3, -1.982_346_7e-4, 2.634_852_5e-6];

/// The elementary functions a variation's formula calls in f32 (`variations_lanes.rs`).
pub trait Elementary32 {
    fn sin_cos(&mut self, x: f32) -> (f32, f32);
    fn exp(&mut self, x: f32) -> f32;
    fn ln(&mut self, x: f32) -> f32;
    /// atan2(y, x), the angle of (x, y).
    fn atan2(&mut self, y: f32, x: f32) -> f32;
    /// acos x for |x| ≤ 1, as the angle of (x, √((1 − x)(1 + x))).
    #[inline(always)]
    fn acos(&mut self, x: f32) -> f32 {
        self.atan2(((1.0 - x) * (1.0 + x)).sqrt(), x)
    }
    #[inline(always)]
    fn sin(&mut self, x: f32) -> f32 {
        self.sin_cos(x).0
    }
    #[inline(always)]
    fn cos(&mut self, x: f32) -> f32 {
        self.sin_cos(x).1
    }
    #[inline(always)]
    fn tan(&mut self, x: f32) -> f32 {
        let (s, c) = self.sin_cos(x);
        s / c
    }
    /// x^y for x ≥ 0 (what the variations raise: radii and their squares).
    #[inline(always)]
    fn pow(&mut self, x: f32, y: f32) -> f32 {
        let l = self.ln(x);
        self.exp(y * l)
    }
    #[inline(always)]
    fn cosh(&mut self, x: f32) -> f32 {
        let e = self.exp(x);
        0.5 * (e + 1.0 / e)
    }
    #[inline(always)]
    fn sinh(&mut self, x: f32) -> f32 {
        let e = self.exp(x);
        0.5 * (e - 1.0 / e)
    }
}

/// The cores, noting in `in_range` whether every argument was within them.
pub struct Fast32 {
    pub in_range: bool,
}

impl Elementary32 for Fast32 {
    #[inline(always)]
    fn sin_cos(&mut self, x: f32) -> (f32, f32) {
        let (s, c, ok) = sin_cos_core(x);
        self.in_range &= ok;
        (s, c)
    }
    #[inline(always)]
    fn sin(&mut self, x: f32) -> f32 {
        let (s, ok) = sin_core::<false>(x);
        self.in_range &= ok;
        s
    }
    #[inline(always)]
    fn cos(&mut self, x: f32) -> f32 {
        let (c, ok) = sin_core::<true>(x);
        self.in_range &= ok;
        c
    }
    #[inline(always)]
    fn exp(&mut self, x: f32) -> f32 {
        let (e, ok) = exp_core(x);
        self.in_range &= ok;
        e
    }
    #[inline(always)]
    fn ln(&mut self, x: f32) -> f32 {
        let (l, ok) = ln_core(x);
        self.in_range &= ok;
        l
    }
    #[inline(always)]
    fn atan2(&mut self, y: f32, x: f32) -> f32 {
        let (a, ok) = atan2_core(y, x);
        self.in_range &= ok;
        a
    }
}

/// The functions in f64 (libm), rounded to f32: every argument, NaN and infinities included.
pub struct Exact32;

impl Elementary32 for Exact32 {
    #[inline(always)]
    fn sin_cos(&mut self, x: f32) -> (f32, f32) {
        let (s, c) = f64::from(x).sin_cos();
        (s as f32, c as f32)
    }
    #[inline(always)]
    fn exp(&mut self, x: f32) -> f32 {
        f64::from(x).exp() as f32
    }
    #[inline(always)]
    fn ln(&mut self, x: f32) -> f32 {
        f64::from(x).ln() as f32
    }
    #[inline(always)]
    fn atan2(&mut self, y: f32, x: f32) -> f32 {
        f64::from(y).atan2(f64::from(x)) as f32
    }
}

/// (sin x, cos x, whether |x| ≤ 8192); outside that range the values are those of 0.
#[inline(always)]
pub fn sin_cos_core(x: f32) -> (f32, f32, bool) {
    let ok = x.abs() <= REDUCE_LIMIT;
    let x = if ok { x } else { 0.0 };
    let shifted = x * std::f32::consts::FRAC_2_PI + ROUND_MAGIC;
    let q = shifted - ROUND_MAGIC;
    let quadrant = shifted.to_bits();
    let r = ((x - q * PIO2_1) - q * PIO2_2) - q * PIO2_3;
    let z = r * r;
    let sin_r = r + r * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * -1.951_529_6e-4));
    let cos_r = (1.0 - 0.5 * z) + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
    let odd = quadrant & 1 != 0;
    let (s, c) = if odd { (cos_r, sin_r) } else { (sin_r, cos_r) };
    // sin is negated in quadrants 2 and 3, cos in 1 and 2.
    let s = f32::from_bits(s.to_bits() ^ ((quadrant & 2) << 30));
    let c = f32::from_bits(c.to_bits() ^ ((quadrant.wrapping_add(1) & 2) << 30));
    (s, c, ok)
}

/// (sin x, or cos x where `COS`, whether |x| ≤ 8192), one polynomial: x less the nearest n·π
/// (n whole for sin, half-odd for cos, as cos x = −sin(x − π/2)), the sign flipped for odd n.
/// Where only one of the two is wanted, it takes half [`sin_cos_core`]'s work.
#[inline(always)]
pub fn sin_core<const COS: bool>(x: f32) -> (f32, bool) {
    let ok = x.abs() <= REDUCE_LIMIT;
    let x = if ok { x } else { 0.0 };
    let half = if COS { 0.5 } else { 0.0 };
    let shifted = (x * std::f32::consts::FRAC_1_PI - half) + ROUND_MAGIC;
    let n = (shifted - ROUND_MAGIC) + half;
    // n · (π/2's parts doubled): 2n is below 2^13, as the quadrant of `sin_cos_core`.
    let r = ((x - n * (2.0 * PIO2_1)) - n * (2.0 * PIO2_2)) - n * (2.0 * PIO2_3);
    let z = r * r;
    let [s3, s5, s7, s9] = SIN_HALF_PI;
    let s = r + r * z * (s3 + z * (s5 + z * (s7 + z * s9)));
    // sin(r + kπ) = (−1)^k sin r, and cos(r + kπ + π/2) = −(−1)^k sin r: k's parity is the low
    // bit of `shifted`.
    let odd = shifted.to_bits() << 31;
    let sign = if COS { odd ^ 0x8000_0000 } else { odd };
    (f32::from_bits(s.to_bits() ^ sign), ok)
}

/// (e^x, whether −87 < x < 88, where the result is a normal float).
#[inline(always)]
pub fn exp_core(x: f32) -> (f32, bool) {
    let ok = (x > -87.0) & (x < 88.0);
    let x = if ok { x } else { 0.0 };
    let shifted = x * std::f32::consts::LOG2_E + ROUND_MAGIC;
    let n = shifted - ROUND_MAGIC;
    let r = (x - n * 0.693_359_4) - n * -2.121_944_4e-4;
    let p = (((((1.987_569_2e-4 * r + 1.398_2e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r + 1.666_666_5e-1) * r
        + 0.5)
        * (r * r)
        + r
        + 1.0;
    // 2^n from its exponent bits (n is within −126..=127 here).
    let scale = f32::from_bits((shifted.to_bits().wrapping_add(127) & 0xFF) << 23);
    (p * scale, ok)
}

/// (ln x, whether x is positive, normal and finite).
#[inline(always)]
pub fn ln_core(x: f32) -> (f32, bool) {
    #[expect(clippy::manual_range_contains, reason = "`contains` is two branches, not a vector compare")]
    let ok = (x >= f32::MIN_POSITIVE) & (x < f32::INFINITY);
    let x = if ok { x } else { 1.0 };
    let bits = x.to_bits();
    // x = 2^e · m with m in [1, 2), then moved to [√½, √2).
    let m = f32::from_bits((bits & 0x007F_FFFF) | 0x3F80_0000);
    let e = ((bits >> 23) as i32 - 127) as f32;
    let high = m > std::f32::consts::SQRT_2;
    let (m, e) = if high { (m * 0.5, e + 1.0) } else { (m, e) };
    let f = m - 1.0;
    let s = f / (2.0 + f);
    let z = s * s;
    let w = z * z;
    let r = z * (0.666_666_6 + w * 0.284_987_87) + w * (0.400_009_72 + w * 0.242_790_79);
    (e * 0.693_138_1 + ((f - s * (f - r)) + e * 9.058_001e-6), ok)
}

/// (atan2(y, x), whether both are finite).
#[inline(always)]
pub fn atan2_core(y: f32, x: f32) -> (f32, bool) {
    let (ax, ay) = (x.abs(), y.abs());
    let ok = (ax < f32::INFINITY) & (ay < f32::INFINITY);
    let swapped = ay > ax;
    let (small, large) = if swapped { (ax, ay) } else { (ay, ax) };
    let t = if large > 0.0 { small / large } else { 0.0 };
    // atan(t) for t in [0, 1]: t itself up to tan(π/8), else π/4 + atan((t − 1)/(t + 1)).
    let high = t > 0.414_213_57;
    let (u, base) = if high { ((t - 1.0) / (t + 1.0), FRAC_PI_4) } else { (t, 0.0) };
    let z = u * u;
    let a = base + (u + u * z * (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1));
    let a = if swapped { FRAC_PI_2 - a } else { a };
    let a = if x.is_sign_negative() { PI - a } else { a };
    (a.copysign(y), ok)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest difference from the f64 function, over a sweep, in units of `scale`.
    fn worst(f: impl Fn(f32) -> (f32, bool), exact: impl Fn(f64) -> f64, from: f32, to: f32) -> f64 {
        let mut worst: f64 = 0.0;
        for i in 0..=200_000 {
            let x = from + (to - from) * (i as f32 / 200_000.0);
            let (v, ok) = f(x);
            assert!(ok, "{x} is in range");
            let e = exact(f64::from(x));
            worst = worst.max((f64::from(v) - e).abs() / e.abs().max(1.0));
        }
        worst
    }

    #[test]
    fn cores_agree_with_f64_within_f32_rounding() {
        let eps = f64::from(f32::EPSILON);
        assert!(worst(|x| (sin_cos_core(x).0, sin_cos_core(x).2), f64::sin, -8192.0, 8192.0) < 4.0 * eps);
        assert!(worst(|x| (sin_cos_core(x).1, true), f64::cos, -20.0, 20.0) < 4.0 * eps);
        assert!(worst(sin_core::<false>, f64::sin, -8192.0, 8192.0) < 4.0 * eps);
        assert!(worst(sin_core::<true>, f64::cos, -8192.0, 8192.0) < 4.0 * eps);
        assert!(worst(sin_core::<false>, f64::sin, -4.0, 4.0) < 4.0 * eps);
        assert!(worst(sin_core::<true>, f64::cos, -4.0, 4.0) < 4.0 * eps);
        assert!(worst(exp_core, f64::exp, -80.0, 80.0) < 4.0 * eps);
        assert!(worst(ln_core, f64::ln, 1e-6, 1e6) < 4.0 * eps);
        assert!(worst(|t| atan2_core(t, 1.0 - t), |t| t.atan2(1.0 - t), -3.0, 3.0) < 4.0 * eps);
        assert!(worst(|t| atan2_core(-1.0, t), |t| (-1f64).atan2(t), -5.0, 5.0) < 4.0 * eps);
    }

    #[test]
    fn cores_say_when_out_of_range() {
        assert!(!sin_cos_core(1e5).2 && !sin_cos_core(f32::NAN).2);
        assert!(!sin_core::<false>(1e5).1 && !sin_core::<true>(f32::NAN).1 && sin_core::<true>(-8192.0).1);
        assert!(!exp_core(100.0).1 && !exp_core(f32::NAN).1);
        assert!(!ln_core(0.0).1 && !ln_core(-1.0).1 && !ln_core(f32::INFINITY).1);
        assert!(!atan2_core(f32::INFINITY, 1.0).1);
        assert_eq!(atan2_core(0.0, -1.0).0, PI);
        assert_eq!(atan2_core(-0.0, -1.0).0, -PI);
    }
}
