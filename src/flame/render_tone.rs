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
use super::render_density::AccRows;
use super::render_layout::Layout;

/// flam3's `PREFILTER_WHITE`.
const PREFILTER_WHITE: f64 = 255.0;

/// Pixels the tone map takes at a time.
const BATCH: usize = 8;

/// The tone map of an image: its RGBA8 pixels, made row by row as the accumulation buffer's
/// rows under them become final ([`super::render_density::accumulate`]).
pub(super) struct ToneMap<'a> {
    tone: Tone,
    layout: &'a Layout,
    rgba: Vec<u8>,
    /// The first output row not made yet.
    next_row: usize,
}

impl<'a> ToneMap<'a> {
    pub fn new(flame: &Flame, layout: &'a Layout) -> Self {
        Self { tone: Tone::new(flame), layout, rgba: vec![0u8; layout.width * layout.height * 4], next_row: 0 }
    }

    /// The first accumulation row output row `j`'s filter reads.
    fn first_acc_row(&self, j: usize) -> usize {
        self.layout.filter_offset + j * self.layout.oversample
    }

    /// Makes the output rows whose filter reads only final rows of `acc`; returns the first
    /// accumulation row still to be read.
    pub fn take(&mut self, acc: &AccRows<'_>) -> usize {
        let (layout, tone) = (self.layout, &self.tone);
        let (start, mut end) = (self.next_row, self.next_row);
        while end < layout.height && self.first_acc_row(end) + layout.filter.width <= acc.final_end {
            end += 1;
        }
        let row_bytes = layout.width * 4;
        self.rgba[start * row_bytes..end * row_bytes].par_chunks_mut(row_bytes).enumerate().for_each_init(
            || vec![[0.0; 4]; layout.width],
            |filtered, (k, row)| {
                filter_row_dispatch(layout, acc, start + k, filtered);
                tone.row_dispatch(filtered, row);
            },
        );
        self.next_row = end;
        if end < layout.height { self.first_acc_row(end) } else { acc.final_end }
    }

    /// The pixels, once every row is made.
    pub fn finish(self) -> Vec<u8> {
        debug_assert_eq!(self.next_row, self.layout.height, "rows left out of the tone map");
        self.rgba
    }
}

/// [`filter_row`] compiled for AVX2 where the CPU has it (a pixel's four channels in one
/// vector; no FMA, so the sums are the same bits).
fn filter_row_dispatch(layout: &Layout, acc: &AccRows<'_>, j: usize, filtered: &mut [[f64; 4]]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::SimdLevel::detect().avx2() {
        #[expect(unsafe_code, reason = "an AVX2 function, entered after the CPU check")]
        // SAFETY: the CPU runs AVX2 (checked just above).
        return unsafe { filter_row_avx2(layout, acc, j, filtered) };
    }
    filter_row(layout, acc, j, filtered, [0.0; 4], |mut sum, coefs, line| {
        for (k, a) in coefs.iter().zip(line) {
            for c in 0..4 {
                sum[c] += k * a[c];
            }
        }
        sum
    });
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn filter_row_avx2(layout: &Layout, acc: &AccRows<'_>, j: usize, filtered: &mut [[f64; 4]]) {
    use std::arch::x86_64::*;
    #[derive(Clone, Copy)]
    struct Sum(__m256d);
    impl From<Sum> for [f64; 4] {
        fn from(sum: Sum) -> Self {
            let mut value = [0.0; 4];
            #[expect(unsafe_code, reason = "an unaligned vector store of four channels")]
            // SAFETY: `value` is a live `[f64; 4]`, 32 bytes, written whole.
            unsafe {
                _mm256_storeu_pd(value.as_mut_ptr(), sum.0)
            };
            value
        }
    }
    filter_row(layout, acc, j, filtered, Sum(_mm256_setzero_pd()), |sum, coefs, line| {
        let mut sum = sum.0;
        for (&k, a) in coefs.iter().zip(line) {
            #[expect(unsafe_code, reason = "an unaligned vector load of four channels")]
            // SAFETY: `a` is a live `[f64; 4]`, 32 bytes, read whole.
            let a = unsafe { _mm256_loadu_pd(a.as_ptr()) };
            sum = _mm256_add_pd(sum, _mm256_mul_pd(_mm256_set1_pd(k), a));
        }
        Sum(sum)
    });
}

/// The spatial filter over output row `j`: each pixel's RGBA, the filter's coefficients times
/// the accumulation buffer's values under it, summed from `zero` row by row of the filter, left
/// to right (`add_line(sum, coefs, line)` adds one row of the filter to `sum`), the sum kept
/// out of memory until the pixel is done.
#[inline(always)]
fn filter_row<S: Copy + Into<[f64; 4]>>(
    layout: &Layout,
    acc: &AccRows<'_>,
    j: usize,
    filtered: &mut [[f64; 4]],
    zero: S,
    add_line: impl Fn(S, &[f64], &[[f64; 4]]) -> S,
) {
    let filter = &layout.filter;
    let os = layout.oversample;
    let y = layout.filter_offset + j * os;
    for (i, t) in filtered.iter_mut().enumerate() {
        let x = layout.filter_offset + i * os;
        let mut sum = zero;
        for jj in 0..filter.width {
            let line = acc.line(y + jj, x, filter.width);
            sum = add_line(sum, &filter.coefs[jj * filter.width..(jj + 1) * filter.width], line);
        }
        *t = sum.into();
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

    /// The RGBA8 pixels of a row of filtered values, [`Self::row`] compiled for AVX2 where the
    /// CPU has it.
    fn row_dispatch(&self, filtered: &[[f64; 4]], rgba: &mut [u8]) {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::SimdLevel::detect().avx2() {
            #[expect(unsafe_code, reason = "an AVX2 function, entered after the CPU check")]
            // SAFETY: the CPU runs AVX2 (checked just above).
            return unsafe { self.row_avx2(filtered, rgba) };
        }
        self.row(filtered, rgba);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn row_avx2(&self, filtered: &[[f64; 4]], rgba: &mut [u8]) {
        self.row(filtered, rgba);
    }

    /// The RGBA8 pixels of a row: [`Self::pixels`] a batch at a time, [`Self::pixel`] for the
    /// rest.
    #[inline(always)]
    fn row(&self, filtered: &[[f64; 4]], rgba: &mut [u8]) {
        // Batches where nothing was drawn (all bits zero) take the empty pixel's colour.
        let empty = self.pixel([0.0; 4]);
        let mut batches = filtered.chunks_exact(BATCH);
        let mut out = rgba.chunks_exact_mut(4 * BATCH);
        for (batch, px) in (&mut batches).zip(&mut out) {
            let colours = if batch.iter().flatten().all(|v| v.to_bits() == 0) {
                [empty; BATCH]
            } else {
                self.pixels(batch.try_into().expect("a batch"))
            };
            for (px, [r, g, b]) in px.chunks_exact_mut(4).zip(colours) {
                px.copy_from_slice(&[r, g, b, 255]);
            }
        }
        for (px, &t) in out.into_remainder().chunks_exact_mut(4).zip(batches.remainder()) {
            let [r, g, b] = self.pixel(t);
            px.copy_from_slice(&[r, g, b, 255]);
        }
    }

    /// [`Self::pixel`] of `BATCH` pixels, each step an elementwise operation on the batch (the
    /// compiler makes them vector instructions: the same IEEE operations, so the same bits),
    /// the powers one pixel at a time, where they are needed; a pixel whose highlight needs
    /// its hue and saturation takes [`Self::pixel`].
    #[inline(always)]
    fn pixels(&self, t: &[[f64; 4]; BATCH]) -> [[u8; 3]; BATCH] {
        type Batch = [f64; BATCH];
        #[inline(always)]
        fn each(f: impl Fn(usize) -> f64) -> Batch {
            std::array::from_fn(f)
        }
        let channel: [Batch; 4] = std::array::from_fn(|c| each(|l| t[l][c] / PREFILTER_WHITE));
        let density = channel[3];
        // As in `pixel`, a NaN density is drawn (and its NaN carried on).
        let drawn: [bool; BATCH] = std::array::from_fn(|l| !(t[l][3] <= 0.0));
        let mut power = [0.0; BATCH];
        for l in 0..BATCH {
            if drawn[l] {
                power[l] = density[l].powf(self.alpha.gamma);
            }
        }
        let alpha = each(|l| if drawn[l] { self.alpha.of_with_power(density[l], power[l]) } else { 0.0 });
        let ls = each(|l| if drawn[l] { self.vibrancy * 256.0 * alpha[l] / density[l] } else { 0.0 });
        let alpha = alpha.map(|a| a.clamp(0.0, 1.0));
        // calc_newrgb's largest scaled channel, the first of equals, as its loop finds it.
        let mut max_scaled = [-1.0; BATCH];
        let mut max_channel = [0.0; BATCH];
        for values in &channel[..3] {
            for l in 0..BATCH {
                let a = ls[l] * values[l];
                if a > max_scaled[l] {
                    max_scaled[l] = a;
                    max_channel[l] = values[l];
                }
            }
        }
        let new_ls = each(|l| WHITE_LEVEL / max_channel[l]);
        let blend = each(|l| if max_scaled[l] <= 255.0 { 1.0 } else { (-self.highlight_power).min(1.0) });
        let black =
            each(|l| if ls[l] == 0.0 || (t[l][0] == 0.0 && t[l][1] == 0.0 && t[l][2] == 0.0) { 1.0 } else { 0.0 });
        let scaled = each(|l| (1.0 - blend[l]) * new_ls[l] + blend[l] * ls[l]);
        let mut vivid = [[0.0; BATCH]; 3];
        for (vivid, channel) in vivid.iter_mut().zip(&channel) {
            for l in 0..BATCH {
                vivid[l] = if black[l] == 1.0 { 0.0 } else { scaled[l] * channel[l] };
            }
        }
        // At vibrancy 1 the per-channel power adds +0 (see `pixel`), computed only where not.
        let mut per_channel = [[0.0; BATCH]; 3];
        for (c, per_channel) in per_channel.iter_mut().enumerate() {
            for l in 0..BATCH {
                if !(self.vibrancy == 1.0 && t[l][c] >= 0.0 && t[l][c].is_finite()) {
                    per_channel[l] = (1.0 - self.vibrancy) * 256.0 * channel[c][l].powf(self.inverse_gamma);
                }
            }
        }
        let mut colours = [[0u8; 3]; BATCH];
        for c in 0..3 {
            for l in 0..BATCH {
                let a = vivid[c][l] + per_channel[c][l] + (1.0 - alpha[l]) * self.background[c];
                colours[l][c] = if a.is_nan() { 255 } else { a.clamp(0.0, 255.0) as u8 };
            }
        }
        for (l, colour) in colours.iter_mut().enumerate() {
            if black[l] != 1.0 && max_scaled[l] > 255.0 && self.highlight_power >= 0.0 {
                *colour = self.pixel(t[l]);
            }
        }
        colours
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
        self.of_with_power(density, density.powf(self.gamma))
    }

    /// [`Self::of`] of a density > 0 whose power `gamma` is `power`.
    #[inline(always)]
    fn of_with_power(&self, density: f64, power: f64) -> f64 {
        if density < self.linear_range {
            let frac = density / self.linear_range;
            (1.0 - frac) * density * (self.at_threshold / self.linear_range) + frac * power
        } else {
            power
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

    /// The batch tone map gives each pixel the bytes of the one-pixel tone map: drawn and empty
    /// pixels, highlights past white, negative, NaN, infinite and subnormal channels, for tone
    /// maps with and without vibrancy, highlight power and gamma threshold, in both builds.
    #[test]
    fn a_batch_of_pixels_is_each_pixel_as_alone() {
        let specials = [0.0, -0.0, 1.0, 254.9, 255.0, 3e4, 1e9, -3.0, f64::NAN, f64::INFINITY, 5e-324, 1e-300];
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for (vibrancy, highlight_power, gamma, linear_range) in
            [(1.0, -1.0, 4.0, 0.01), (0.6, 1.0, 2.2, 0.3), (0.0, 0.0, 3.0, 0.0), (1.0, 2.0, 1.0, 1.5)]
        {
            let tone = Tone {
                inverse_gamma: 1.0 / gamma,
                alpha: AlphaCurve::new(1.0 / gamma, linear_range),
                vibrancy,
                highlight_power,
                background: [0.1, 0.5, 0.0].map(|c| c * 256.0),
            };
            for _ in 0..2000 {
                // Half the rows mostly empty: whole batches of them drawn from the empty pixel.
                let sparse = next() % 2 == 0;
                let row: Vec<[f64; 4]> = (0..3 * BATCH + 3)
                    .map(|_| {
                        let empty = sparse && next() % 8 != 0;
                        std::array::from_fn(|_| match if empty { 1 } else { next() % 4 } {
                            0 => specials[(next() % specials.len() as u64) as usize],
                            1 => 0.0,
                            _ => (next() % 1_000_000) as f64 * 10f64.powi((next() % 9) as i32 - 4),
                        })
                    })
                    .collect();
                let mut batch = vec![0u8; row.len() * 4];
                tone.row_dispatch(&row, &mut batch);
                let mut portable = vec![0u8; row.len() * 4];
                tone.row(&row, &mut portable);
                let alone: Vec<u8> = row.iter().flat_map(|&t| tone.pixel(t).into_iter().chain([255])).collect();
                assert_eq!(batch, alone, "{row:?}");
                assert_eq!(portable, alone, "{row:?}");
            }
        }
    }

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
