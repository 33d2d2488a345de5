//! flam3's last step (the end of its `rect.c`, `flam3_calc_alpha` and `flam3_calc_newrgb` of
//! `palettes.c`): the spatial filter takes the accumulation buffer down to one value per output
//! pixel, then the tone map gives its 8-bit colour. The alpha is the filtered density raised to
//! 1/gamma (linear below gamma_threshold); vibrancy mixes the colour scaled by that alpha with
//! each channel raised to 1/gamma on its own; highlight_power ≥ 0 desaturates a channel past
//! white instead of clipping it; the background fills what the alpha leaves, and the PNG's
//! alpha is 255 as in flam3-render without `transparency`.

use rayon::prelude::*;

use super::Flame;
use super::palette::{hsv_to_rgb, rgb_to_hsv};
use super::render_base::WHITE_LEVEL;
use super::render_layout::Layout;

/// flam3's `PREFILTER_WHITE`.
const PREFILTER_WHITE: f64 = 255.0;

/// The RGBA8 pixels of the image from the accumulation buffer.
pub(super) fn tone_map(flame: &Flame, layout: &Layout, acc: &[[f64; 4]]) -> Vec<u8> {
    let tone = Tone::new(flame);
    let mut rgba = vec![0u8; layout.width * layout.height * 4];
    rgba.par_chunks_mut(layout.width * 4).enumerate().for_each_init(
        || vec![[0.0; 4]; layout.width],
        |filtered, (j, row)| {
            filter_row_dispatch(layout, acc, j, filtered);
            for (px, &t) in row.chunks_exact_mut(4).zip(filtered.iter()) {
                let [r, g, b] = tone.pixel(t);
                px.copy_from_slice(&[r, g, b, 255]);
            }
        },
    );
    rgba
}

/// [`filter_row`] compiled for AVX2 where the CPU has it (a pixel's four channels in one
/// vector; no FMA, so the sums are the same bits).
fn filter_row_dispatch(layout: &Layout, acc: &[[f64; 4]], j: usize, filtered: &mut [[f64; 4]]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::SimdLevel::detect().avx2() {
        #[expect(unsafe_code, reason = "an AVX2 function, entered after the CPU check")]
        // SAFETY: the CPU runs AVX2 (checked just above).
        return unsafe { filter_row_avx2(layout, acc, j, filtered) };
    }
    filter_row(layout, acc, j, filtered, |t, coefs, line| {
        for (k, a) in coefs.iter().zip(line) {
            for c in 0..4 {
                t[c] += k * a[c];
            }
        }
    });
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn filter_row_avx2(layout: &Layout, acc: &[[f64; 4]], j: usize, filtered: &mut [[f64; 4]]) {
    use std::arch::x86_64::*;
    filter_row(layout, acc, j, filtered, |t, coefs, line| {
        #[expect(unsafe_code, reason = "unaligned vector loads and a store of four channels")]
        // SAFETY: `t` and each `a` are live `[f64; 4]`s, 32 bytes, read (and `t` written) whole.
        unsafe {
            let mut sum = _mm256_loadu_pd(t.as_ptr());
            for (&k, a) in coefs.iter().zip(line) {
                sum = _mm256_add_pd(sum, _mm256_mul_pd(_mm256_set1_pd(k), _mm256_loadu_pd(a.as_ptr())));
            }
            _mm256_storeu_pd(t.as_mut_ptr(), sum);
        }
    });
}

/// The spatial filter over output row `j`: each pixel's RGBA, the filter's coefficients times
/// the accumulation buffer's values under it, summed row by row of the filter, left to right
/// (`add_line(t, coefs, line)` adds one row of the filter to `t`).
#[inline(always)]
fn filter_row(
    layout: &Layout,
    acc: &[[f64; 4]],
    j: usize,
    filtered: &mut [[f64; 4]],
    add_line: impl Fn(&mut [f64; 4], &[f64], &[[f64; 4]]),
) {
    let filter = &layout.filter;
    let (w, os) = (layout.hist_width, layout.oversample);
    let y = layout.filter_offset + j * os;
    for (i, t) in filtered.iter_mut().enumerate() {
        let x = layout.filter_offset + i * os;
        *t = [0.0; 4];
        for jj in 0..filter.width {
            let line = &acc[x + (y + jj) * w..x + (y + jj) * w + filter.width];
            add_line(t, &filter.coefs[jj * filter.width..(jj + 1) * filter.width], line);
        }
    }
}

/// The tone map's constants.
struct Tone {
    inverse_gamma: f64,
    alpha: AlphaCurve,
    vibrancy: f64,
    highlight_power: f64,
    /// The background × 256, as flam3 scales it.
    background: [f64; 3],
}

impl Tone {
    fn new(flame: &Flame) -> Self {
        Self {
            inverse_gamma: 1.0 / flame.gamma,
            alpha: AlphaCurve::new(1.0 / flame.gamma, flame.gamma_threshold),
            vibrancy: flame.vibrancy,
            highlight_power: flame.highlight_power,
            background: flame.background.map(|c| c * 256.0),
        }
    }

    fn pixel(&self, t: [f64; 4]) -> [u8; 3] {
        let density = t[3] / PREFILTER_WHITE;
        let (alpha, ls) = if t[3] <= 0.0 {
            (0.0, 0.0)
        } else {
            let alpha = self.alpha.of(density);
            (alpha.clamp(0.0, 1.0), self.vibrancy * 256.0 * alpha / density)
        };
        let vivid = calc_newrgb(t, ls, self.highlight_power);
        std::array::from_fn(|c| {
            // At vibrancy 1 the per-channel power is multiplied by 0: it adds +0 (no power to
            // compute) unless the channel is negative, where it is NaN and makes the byte 255.
            let per_channel = if self.vibrancy == 1.0 && t[c] >= 0.0 && t[c].is_finite() {
                0.0
            } else {
                (1.0 - self.vibrancy) * 256.0 * (t[c] / PREFILTER_WHITE).powf(self.inverse_gamma)
            };
            let a = vivid[c] + per_channel + (1.0 - alpha) * self.background[c];
            // A channel a filter's negative lobe took below 0 is NaN here (its power 1/gamma);
            // flam3-render's clamps (compiled to minsd/maxsd) turn NaN into 255, the white
            // fringe of its Mitchell and Lanczos pictures, and so does this.
            if a.is_nan() { 255 } else { a.clamp(0.0, 255.0) as u8 }
        })
    }
}

/// flam3's `flam3_calc_alpha`: the density raised to `gamma` (here 1/gamma), blended linearly
/// below `linear_range`.
struct AlphaCurve {
    gamma: f64,
    linear_range: f64,
    /// `linear_range` raised to `gamma`, the same for every pixel (flam3 computes it for each).
    at_threshold: f64,
}

impl AlphaCurve {
    fn new(gamma: f64, linear_range: f64) -> Self {
        Self { gamma, linear_range, at_threshold: linear_range.powf(gamma) }
    }

    fn of(&self, density: f64) -> f64 {
        if density <= 0.0 {
            return 0.0;
        }
        if density < self.linear_range {
            let frac = density / self.linear_range;
            (1.0 - frac) * density * (self.at_threshold / self.linear_range) + frac * density.powf(self.gamma)
        } else {
            density.powf(self.gamma)
        }
    }
}

/// The colour scaled by `ls`, with flam3's highlight handling of a channel past 255.
fn calc_newrgb(t: [f64; 4], ls: f64, highlight_power: f64) -> [f64; 3] {
    if ls == 0.0 || (t[0] == 0.0 && t[1] == 0.0 && t[2] == 0.0) {
        return [0.0; 3];
    }
    let mut max_scaled = -1.0;
    let mut max_channel = 0.0;
    for c in t.iter().take(3) {
        let a = ls * (c / PREFILTER_WHITE);
        if a > max_scaled {
            max_scaled = a;
            max_channel = c / PREFILTER_WHITE;
        }
    }
    let new_ls = WHITE_LEVEL / max_channel;
    if max_scaled > 255.0 && highlight_power >= 0.0 {
        let ratio = (new_ls / ls).powf(highlight_power);
        let rgb: [f64; 3] = std::array::from_fn(|c| new_ls * (t[c] / PREFILTER_WHITE) / 255.0);
        let mut hsv = rgb_to_hsv(rgb);
        hsv[1] *= ratio;
        hsv_to_rgb(hsv).map(|v| v * 255.0)
    } else {
        let blend = if max_scaled <= 255.0 { 1.0 } else { (-highlight_power).min(1.0) };
        std::array::from_fn(|c| ((1.0 - blend) * new_ls + blend * ls) * (t[c] / PREFILTER_WHITE))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_is_linear_below_the_threshold_and_a_power_above() {
        let g = 1.0 / 4.0;
        let calc_alpha = |density: f64, gamma: f64, linear_range: f64| AlphaCurve::new(gamma, linear_range).of(density);
        assert!((calc_alpha(0.5, g, 0.01) - 0.5f64.powf(g)).abs() < 1e-15);
        // Below the threshold the curve runs from the line through 0 to the power at the threshold.
        // Near 0 its slope is the line's, 0.01^g / 0.01; at the threshold it meets the power.
        let slope = calc_alpha(1e-12, g, 0.01) / 1e-12;
        assert!((slope / (0.01f64.powf(g) / 0.01) - 1.0).abs() < 1e-2, "slope {slope}");
        assert!((calc_alpha(0.01 - 1e-12, g, 0.01) - 0.01f64.powf(g)).abs() < 1e-9);
        assert_eq!(calc_alpha(0.0, g, 0.01), 0.0);
    }
}
