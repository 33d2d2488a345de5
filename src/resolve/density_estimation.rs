//! flam3's adaptive density estimation for the density mode, on the CPU: before the tone map,
//! each pixel's colour sums and count are spread over a disc whose radius shrinks with the
//! pixel's count, `max_radius_px / count^curve` clamped to [`min_radius_px`, `max_radius_px`]
//! ([`DensityEstimation`], after flam3's `filters.c` and `rect.c`). A pixel hit once spreads
//! over the widest disc, so sparse regions turn smooth; a dense pixel keeps its value (a disc
//! under one pixel is the pixel itself), so dense regions stay sharp.
//!
//! The kernel is flam3's Gaussian, exp(-2 (1.5 d)²) for d = distance / radius ≤ 1, normalised
//! to sum 1. Taps that fall outside the image are reflected back into it, so the spread keeps
//! the image's total exactly and a uniform field stays uniform up to the border. Kernels are
//! tabulated per radius in steps of 1/8 pixel. The pass scatters in bands of output rows in
//! parallel into a float copy of the accumulation ([`Estimated`]), which [`Estimated::fragment`]
//! resolves like the density branch of [`crate::resolve::resolve_fragment`] with float counts.
//!
//! The GPU twin is `shaders/density_estimation.wgsl` (host side `src/gpu/density_estimation.rs`),
//! run by the viewer and `render --backend gpu`: keep the two in sync. It gathers what this file
//! scatters (a GPU has no float atomics): for each output pixel, every source whose reflected
//! taps land on it, with the same kernels ([`KernelTables`], built here and uploaded, so the
//! weights are these bytes) and the same kernel choice per count (looked up in
//! [`KernelTables::first_count`] by [`kernel_index`], which a test holds equal to the
//! rounding of [`radius_px`] that [`estimate`] uses). Only the order of the f32 sums differs.

use rayon::prelude::*;

use super::{COLOR_SCALE, ResolveParams};
use crate::scene::spec::DensityEstimation;

/// Kernel radii are tabulated in steps of 1 / RADIUS_STEPS pixel (`shaders/density_estimation.wgsl`
/// receives the tables built with it).
pub const RADIUS_STEPS: f32 = 8.0;
/// Output rows one task scatters into.
const BAND_ROWS: usize = 32;

/// One tabulated kernel: its radius in whole pixels and (2r + 1)² normalised weights.
struct Kernel {
    reach: i32,
    weights: Vec<f32>,
}

/// flam3's Gaussian kernel of radius `radius_px`, normalised over its taps.
fn kernel(radius_px: f32) -> Kernel {
    if radius_px < 1.0 {
        // Only the centre lies within the disc.
        return Kernel { reach: 0, weights: vec![1.0] };
    }
    let reach = radius_px.floor() as i32;
    let side = 2 * reach + 1;
    let mut weights = Vec::with_capacity((side * side) as usize);
    for dy in -reach..=reach {
        for dx in -reach..=reach {
            let d = ((dx * dx + dy * dy) as f32).sqrt() / radius_px;
            let x = 1.5 * d;
            weights.push(if d <= 1.0 { (-2.0 * x * x).exp() } else { 0.0 });
        }
    }
    let total: f32 = weights.iter().sum();
    weights.iter_mut().for_each(|w| *w /= total);
    Kernel { reach, weights }
}

/// The kernel radius of a pixel with `count` points.
pub fn radius_px(de: &DensityEstimation, count: f32) -> f32 {
    (de.max_radius_px / count.powf(de.curve)).clamp(de.min_radius_px, de.max_radius_px)
}

/// The kernel table index of a pixel with `count` ≥ 1 points (the tabulated radius in steps
/// of 1 / [`RADIUS_STEPS`] pixel, at most `max_steps`).
fn kernel_step(de: &DensityEstimation, count: u32, max_steps: usize) -> usize {
    ((radius_px(de, count as f32) * RADIUS_STEPS).round() as usize).min(max_steps)
}

/// The kernels of `de` laid out for the GPU (`shaders/density_estimation.wgsl`): per kernel
/// step its first weight's index and its reach, all weights in one array, and per step the
/// smallest count that takes that step or a smaller one.
pub struct KernelTables {
    /// Per step k: the smallest count whose kernel step is ≤ k (the step falls as the count
    /// grows, so this falls with k, and the last is 1); u32::MAX where no count reaches it
    /// (a count of u32::MAX would be misread there: GPU counts stay far below it).
    pub first_count: Vec<u32>,
    /// Per step: index of its first weight in `weights`, and its reach r ((2r + 1)² weights).
    pub kernels: Vec<[u32; 2]>,
    pub weights: Vec<f32>,
    /// The largest reach.
    pub reach_max: u32,
}

impl KernelTables {
    pub fn of(de: &DensityEstimation) -> Self {
        let max_steps = (de.max_radius_px * RADIUS_STEPS).round() as usize;
        let (mut kernels, mut weights) = (Vec::with_capacity(max_steps + 1), Vec::new());
        for s in 0..=max_steps {
            let k = kernel(s as f32 / RADIUS_STEPS);
            kernels.push([weights.len() as u32, k.reach as u32]);
            weights.extend_from_slice(&k.weights);
        }
        let reach_max = kernels.iter().map(|k| k[1]).max().unwrap_or(0);
        let first_count = (0..=max_steps)
            .map(|k| {
                if kernel_step(de, u32::MAX, max_steps) > k {
                    return u32::MAX;
                }
                // The step does not grow with the count: bisect for the first count at ≤ k.
                let (mut lo, mut hi) = (1u32, u32::MAX);
                while lo < hi {
                    let mid = lo + (hi - lo) / 2;
                    if kernel_step(de, mid, max_steps) <= k { hi = mid } else { lo = mid + 1 }
                }
                lo
            })
            .collect();
        Self { first_count, kernels, weights, reach_max }
    }
}

/// The kernel step of a pixel with `count` ≥ 1 points from [`KernelTables::first_count`]: the
/// smallest step whose first count is ≤ `count` (bisection; `kernel_index` in the shader).
pub fn kernel_index(first_count: &[u32], count: u32) -> usize {
    let (mut lo, mut hi) = (0, first_count.len() - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if first_count[mid] <= count { hi = mid } else { lo = mid + 1 }
    }
    lo
}

/// Index `i` reflected into 0..n (…, 1, 0 | 0, 1, …, n − 1 | n − 1, n − 2, …).
fn reflect(mut i: i64, n: i64) -> usize {
    loop {
        if i < 0 {
            i = -1 - i;
        } else if i >= n {
            i = 2 * n - 1 - i;
        } else {
            return i as usize;
        }
    }
}

/// An accumulation after density estimation: per pixel the spread r, g, b sums and count, and
/// the largest count (the density mode's normaliser).
pub struct Estimated {
    pub width: u32,
    pub height: u32,
    pub sums: Vec<[f32; 4]>,
    pub max_count: f32,
}

/// Spreads the `width`×`height` accumulation `accum` (r, g, b sums and count per pixel) with
/// `de`. Memory: one float copy of the accumulation.
pub fn estimate(accum: &[[u32; 4]], width: u32, height: u32, de: &DensityEstimation) -> Estimated {
    let (w, h) = (width as usize, height as usize);
    let max_steps = (de.max_radius_px * RADIUS_STEPS).round() as usize;
    let kernels: Vec<Kernel> = (0..=max_steps).map(|s| kernel(s as f32 / RADIUS_STEPS)).collect();
    // Kernel index of every pixel (u16::MAX: empty).
    let index: Vec<u16> =
        accum.par_iter().map(|a| if a[3] == 0 { u16::MAX } else { kernel_step(de, a[3], max_steps) as u16 }).collect();
    let reach_max = kernels.iter().map(|k| k.reach).max().unwrap_or(0) as i64;
    let mut sums = vec![[0f32; 4]; w * h];
    sums.par_chunks_mut((BAND_ROWS * w).max(1)).enumerate().for_each(|(band, out)| {
        let y0 = (band * BAND_ROWS) as i64;
        let y1 = y0 + (out.len() / w.max(1)) as i64;
        // Sources within reach of the band, or whose reflected taps land in it (rows near an
        // edge reflect back): all rows within reach of the band or of its mirror images.
        let near_top = y0 <= reach_max;
        let near_bottom = y1 + reach_max >= h as i64;
        let lo = if near_top { 0 } else { y0 - reach_max };
        let hi = if near_bottom { h as i64 } else { y1 + reach_max };
        for sy in lo..hi {
            for sx in 0..w {
                let i = sy as usize * w + sx;
                if index[i] == u16::MAX {
                    continue;
                }
                let k = &kernels[index[i] as usize];
                let a = accum[i].map(|v| v as f32);
                let r = k.reach as i64;
                let side = 2 * r + 1;
                for dy in -r..=r {
                    let ty = reflect(sy + dy, h as i64) as i64;
                    if ty < y0 || ty >= y1 {
                        continue;
                    }
                    let row = &mut out[(ty - y0) as usize * w..(ty - y0 + 1) as usize * w];
                    let krow = &k.weights[((dy + r) * side) as usize..((dy + r + 1) * side) as usize];
                    for (dx, &wgt) in (-r..=r).zip(krow) {
                        if wgt == 0.0 {
                            continue;
                        }
                        let o = &mut row[reflect(sx as i64 + dx, w as i64)];
                        for c in 0..4 {
                            o[c] += wgt * a[c];
                        }
                    }
                }
            }
        }
    });
    let max_count = sums.par_iter().map(|s| s[3]).reduce(|| 0.0, f32::max);
    Estimated { width, height, sums, max_count }
}

impl Estimated {
    /// The density-mode colour of pixel (x, y) with `p` ([`crate::resolve::ResolveArgs::params`]):
    /// the average colour laid over the background with the log density
    /// ([`crate::resolve::log_density`]) through the tone map, as [`crate::resolve::resolve_fragment`] does with integer counts;
    /// as the target takes it ([`crate::resolve::output_color`]).
    pub fn fragment(&self, p: &ResolveParams, x: u32, y: u32) -> [f32; 3] {
        let mut c = [p.background[0], p.background[1], p.background[2]];
        let sample = |x: u32, y: u32| {
            let s = self.sums[(y * self.width + x) as usize];
            (s[3] > 0.0).then(|| {
                let n = s[3] * COLOR_SCALE;
                ([s[0] / n, s[1] / n, s[2] / n], crate::resolve::log_density(p, s[3], self.max_count.max(1.0)))
            })
        };
        let filtered = if p.filter_taps > 0 { super::filter::gather(p, x, y, sample) } else { sample(x, y) };
        if let Some((avg, a0)) = filtered {
            // The tone map of the unfiltered resolve (the neutral tone is the line above).
            let tone = crate::resolve::ToneUniforms {
                brightness: p.brightness,
                inv_gamma: p.inv_gamma,
                gamma_threshold: p.gamma_threshold,
                vibrancy: p.vibrancy,
                highlight_power: p.highlight_power,
            };
            c = crate::resolve::toned(&tone, avg, a0, c, true).0;
        }
        crate::resolve::output_color(p, c)
    }
}

/// [`crate::resolve::resolve_image`] with density estimation `de` where it applies (density
/// mode): the 8-bit sRGB image of `framebuffer` seen by `camera`, drawn with `style`.
pub fn resolve_image(
    framebuffer: &crate::splat::Framebuffer,
    camera: &crate::camera::OrbitCamera,
    style: &super::ResolveStyle,
    de: Option<&DensityEstimation>,
) -> image::RgbImage {
    let view = &framebuffer.view;
    let Some(de) = applies(de, view.mode) else { return super::resolve_image(framebuffer, camera, style) };
    image_of(&estimate(&framebuffer.accum, view.width, view.height, &de), framebuffer, camera, style)
}

/// The 8-bit sRGB image of the estimate `e` of `framebuffer` (made here or by the GPU twin)
/// seen by `camera`, drawn with `style`.
pub fn image_of(
    e: &Estimated,
    framebuffer: &crate::splat::Framebuffer,
    camera: &crate::camera::OrbitCamera,
    style: &super::ResolveStyle,
) -> image::RgbImage {
    let view = &framebuffer.view;
    let params = super::ResolveArgs::new(view, camera, style).drawn(framebuffer.points_drawn).params(
        view.width,
        view.height,
        true,
    );
    let width_px = view.width as usize;
    let mut bytes = vec![0u8; 3 * width_px * view.height as usize];
    bytes.par_chunks_mut(3 * width_px.max(1)).enumerate().for_each(|(y, row)| {
        for (x, pixel) in row.chunks_exact_mut(3).enumerate() {
            let c = e.fragment(&params, x as u32, y as u32).map(|v| (v * 255.0 + 0.5) as u8);
            pixel.copy_from_slice(&c);
        }
    });
    image::RgbImage::from_raw(view.width, view.height, bytes).expect("3 bytes for each of width × height pixels")
}

/// The CLI's `--density-estimation MAX_RADIUS[,MIN_RADIUS[,CURVE]]` (pixels, pixels, exponent),
/// checked as the scene's `estimator_*` fields are; `0` is off (None).
pub fn parse_flag(text: &str) -> Result<DensityFlag, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() > 3 {
        return Err(format!("`{text}`: give MAX_RADIUS[,MIN_RADIUS[,CURVE]]"));
    }
    let number = |s: &str, what: &str| -> Result<f32, String> {
        s.parse::<f32>().ok().filter(|v| v.is_finite()).ok_or_else(|| format!("{what} `{s}` is not a number"))
    };
    let max = number(parts[0], "MAX_RADIUS")?;
    if !(0.0..=DensityEstimation::MAX_RADIUS_PX).contains(&max) {
        return Err(format!("MAX_RADIUS {max} is not in 0..={}", DensityEstimation::MAX_RADIUS_PX));
    }
    let min = parts.get(1).map(|s| number(s, "MIN_RADIUS")).transpose()?.unwrap_or(0.0);
    if !(0.0..=max).contains(&min) {
        return Err(format!("MIN_RADIUS {min} is not in 0..={max}"));
    }
    let curve = parts.get(2).map(|s| number(s, "CURVE")).transpose()?.unwrap_or(DensityEstimation::DEFAULT_CURVE);
    if !(0.01..=10.0).contains(&curve) {
        return Err(format!("CURVE {curve} is not in 0.01..=10"));
    }
    Ok(DensityFlag((max > 0.0).then_some(DensityEstimation { max_radius_px: max, min_radius_px: min, curve })))
}

/// A parsed `--density-estimation`: the setting, None for off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensityFlag(pub Option<DensityEstimation>);

/// The estimate that spreads nothing (a kernel of one tap at every count: the sums as they are):
/// the live view filters on the estimate's schedule with it where density estimation is off.
pub const SPREADS_NOTHING: DensityEstimation =
    DensityEstimation { max_radius_px: 0.0, min_radius_px: 0.0, curve: DensityEstimation::DEFAULT_CURVE };

/// Whether `de` changes a render of `mode` (density mode only; other modes ignore it).
pub fn applies(de: Option<&DensityEstimation>, mode: crate::scene::spec::SplatMode) -> Option<DensityEstimation> {
    de.copied().filter(|_| mode == crate::scene::spec::SplatMode::Density)
}

#[cfg(test)]
#[path = "density_estimation_tests.rs"]
mod tests;
