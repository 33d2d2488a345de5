//! From flam3's histogram to its accumulation buffer: the log-density scale with flam3's k1 and
//! k2 (its `rect.c`), applied per bucket or through the adaptive density estimator (each
//! bucket's colour spread over a gaussian disc whose radius shrinks with the hits around it),
//! and the spatial filters (its `filters.c`) that later take the buffer down to the image.
//!
//! flam3's index rule is kept: the density of a bucket is the count summed over the
//! supersample's ss×ss neighbourhood (scaled by (ss/(ss+1))² for even ss), hits 1..=100 pick
//! kernels one by one and more hits go through `100 + (hits − 100)^curve`. The estimator runs on
//! bands of rows in parallel, each into its own buffer, and the bands are added in their order,
//! so the sums are the same whatever the thread count.

use rayon::prelude::*;

use super::render::{Bucket, Layout, RenderError, WHITE_LEVEL};
use super::{FilterShape, Flame};

/// flam3's `DE_THRESH`: up to this many hits, one kernel per hit count.
const DE_THRESHOLD: f64 = 100.0;
/// Rows of the histogram one estimator task handles.
const DE_BAND_ROWS: usize = 32;

/// A spatial filter shape's half-width in its own units (flam3's `flam3_spatial_support`).
fn support(shape: FilterShape) -> f64 {
    match shape {
        FilterShape::Gaussian | FilterShape::Bell | FilterShape::Quadratic => 1.5,
        FilterShape::Hermite
        | FilterShape::Triangle
        | FilterShape::Blackman
        | FilterShape::Hanning
        | FilterShape::Hamming => 1.0,
        FilterShape::Box => 0.5,
        FilterShape::BSpline | FilterShape::Mitchell | FilterShape::Catrom | FilterShape::Lanczos2 => 2.0,
        FilterShape::Lanczos3 => 3.0,
    }
}

fn sinc(x: f64) -> f64 {
    let x = x * std::f64::consts::PI;
    if x != 0.0 { x.sin() / x } else { 1.0 }
}

pub(super) fn gaussian(x: f64) -> f64 {
    (-2.0 * x * x).exp() * (2.0 / std::f64::consts::PI).sqrt()
}

/// The filter shape's value at `x` (Graphics Gems III and ImageMagick's kernels, as flam3).
fn kernel(shape: FilterShape, x: f64) -> f64 {
    use std::f64::consts::PI;
    let t = x.abs();
    match shape {
        FilterShape::Gaussian => gaussian(x),
        FilterShape::Hermite => {
            if t < 1.0 {
                (2.0 * t - 3.0) * t * t + 1.0
            } else {
                0.0
            }
        }
        FilterShape::Box => {
            if x > -0.5 && x <= 0.5 {
                1.0
            } else {
                0.0
            }
        }
        FilterShape::Triangle => (1.0 - t).max(0.0),
        FilterShape::Bell => {
            if t < 0.5 {
                0.75 - t * t
            } else if t < 1.5 {
                0.5 * (t - 1.5) * (t - 1.5)
            } else {
                0.0
            }
        }
        FilterShape::BSpline => {
            if t < 1.0 {
                0.5 * t * t * t - t * t + 2.0 / 3.0
            } else if t < 2.0 {
                (2.0 - t).powi(3) / 6.0
            } else {
                0.0
            }
        }
        FilterShape::Mitchell => {
            let (b, c) = (1.0 / 3.0, 1.0 / 3.0);
            let tt = t * t;
            if t < 1.0 {
                ((12.0 - 9.0 * b - 6.0 * c) * t * tt + (-18.0 + 12.0 * b + 6.0 * c) * tt + (6.0 - 2.0 * b)) / 6.0
            } else if t < 2.0 {
                ((-b - 6.0 * c) * t * tt
                    + (6.0 * b + 30.0 * c) * tt
                    + (-12.0 * b - 48.0 * c) * t
                    + (8.0 * b + 24.0 * c))
                    / 6.0
            } else {
                0.0
            }
        }
        FilterShape::Blackman => sinc(x) * (0.42 + 0.5 * (PI * x).cos() + 0.08 * (2.0 * PI * x).cos()),
        FilterShape::Catrom => {
            if t < 1.0 {
                0.5 * (2.0 + t * t * (-5.0 + 3.0 * t))
            } else if t < 2.0 {
                0.5 * (4.0 + t * (-8.0 + t * (5.0 - t)))
            } else {
                0.0
            }
        }
        FilterShape::Hanning => sinc(x) * (0.5 + 0.5 * (PI * x).cos()),
        FilterShape::Hamming => sinc(x) * (0.54 + 0.46 * (PI * x).cos()),
        FilterShape::Lanczos3 => {
            if t < 3.0 {
                sinc(x) * sinc(x / 3.0) * sinc(x / 3.0)
            } else {
                0.0
            }
        }
        FilterShape::Lanczos2 => {
            if t < 2.0 {
                sinc(x) * sinc(x / 2.0) * sinc(x / 2.0)
            } else {
                0.0
            }
        }
        FilterShape::Quadratic => {
            if t < 0.5 {
                0.75 - t * t
            } else if t < 1.5 {
                0.5 * (t - 1.5) * (t - 1.5)
            } else {
                0.0
            }
        }
    }
}

/// The square spatial filter over the supersampled buffer, normalized to sum 1; its width has
/// the parity of the supersample so that it centres on each output pixel.
pub(super) struct SpatialFilter {
    pub width: usize,
    /// `coefs[i + j·width]`.
    pub coefs: Vec<f64>,
}

/// The kernel flam3 evaluates for a `filter_shape` name. Its parser gives the names numbers
/// from `flam3.h` (lanczos3 6, lanczos2 7, mitchell 8, blackman 9, catrom 10, hamming 11,
/// hanning 12) while `filters.c` numbers its kernels and supports in another order (mitchell 6,
/// blackman 7, catrom 8, hanning 9, hamming 10, lanczos3 11, lanczos2 12): `mitchell` in a file
/// is rendered with the Catmull-Rom kernel, `catrom` with sinc·Hamming, and so on. flam3-render
/// 3.1.1's pictures are made so, so these are too.
fn as_flam3_evaluates(shape: FilterShape) -> FilterShape {
    match shape {
        FilterShape::Lanczos3 => FilterShape::Mitchell,
        FilterShape::Lanczos2 => FilterShape::Blackman,
        FilterShape::Mitchell => FilterShape::Catrom,
        FilterShape::Blackman => FilterShape::Hanning,
        FilterShape::Catrom => FilterShape::Hamming,
        FilterShape::Hamming => FilterShape::Lanczos3,
        FilterShape::Hanning => FilterShape::Lanczos2,
        other => other,
    }
}

impl SpatialFilter {
    pub fn new(named: FilterShape, radius: f64, oversample: usize) -> Result<Self, RenderError> {
        let shape = as_flam3_evaluates(named);
        let supp = support(shape);
        let fw = 2.0 * supp * oversample as f64 * radius.max(0.0);
        let mut width = fw as usize + 1;
        if (width ^ oversample) & 1 == 1 {
            width += 1;
        }
        let adjust = if fw > 0.0 { supp * width as f64 / fw } else { 1.0 };
        let at = |i: usize| ((2.0 * i as f64 + 1.0) / width as f64 - 1.0) * adjust;
        let mut coefs: Vec<f64> =
            (0..width * width).map(|k| kernel(shape, at(k % width)) * kernel(shape, at(k / width))).collect();
        let sum: f64 = coefs.iter().sum();
        if sum == 0.0 || !sum.is_finite() {
            return Err(RenderError::BadFilter(radius));
        }
        coefs.iter_mut().for_each(|c| *c /= sum);
        Ok(Self { width, coefs })
    }
}

/// flam3's density estimation kernels: one gaussian disc per hit count, from the widest
/// (estimator_radius) down to estimator_minimum, each stored as the octant `0 ≤ dx ≤ dy`.
pub(super) struct DensityFilters {
    /// Radius in buckets of each kernel.
    widths: Vec<f64>,
    /// `kernel_size` octant coefficients per kernel.
    coefs: Vec<f64>,
    kernel_size: usize,
    max_index: usize,
    max_counts: f64,
    curve: f64,
    /// The widest kernel's reach in buckets.
    pub reach: usize,
}

impl DensityFilters {
    /// The kernels of `flame`, or `None` without density estimation (estimator_radius 0, or a
    /// minimum as wide as the radius, where flam3 keeps one kernel and skips the estimator).
    pub fn for_flame(flame: &Flame, oversample: usize) -> Result<Option<Self>, RenderError> {
        let (max_radius, min_radius, curve) = (flame.estimator_radius, flame.estimator_minimum, flame.estimator_curve);
        if max_radius < 0.0 || min_radius < 0.0 {
            return Err(RenderError::BadEstimator(format!(
                "estimator_radius {max_radius} and estimator_minimum {min_radius} must be ≥ 0"
            )));
        }
        if max_radius <= 0.0 {
            return Ok(None);
        }
        if !(curve > 0.0) {
            return Err(RenderError::BadEstimator(format!("estimator_curve {curve} must be greater than 0")));
        }
        if max_radius < min_radius {
            return Err(RenderError::BadEstimator(format!(
                "estimator_radius {max_radius} must be at least estimator_minimum {min_radius}"
            )));
        }
        let os = oversample as f64;
        let comp_max = max_radius * os + 1.0;
        let comp_min = min_radius * os + 1.0;
        let count_f = (comp_max / comp_min).powf(1.0 / curve);
        if count_f > 1e7 {
            return Err(RenderError::BadEstimator(format!(
                "the estimator needs {count_f:.3e} kernels (estimator_radius / estimator_minimum too large for the curve)"
            )));
        }
        let count = count_f.ceil() as usize;
        let keep = 100usize;
        let (max_ind, max_counts) = if count > keep {
            let ind = (DE_THRESHOLD + ((count as f64) - DE_THRESHOLD).powf(curve)).ceil() as usize + 1;
            (ind, (((ind as f64) - DE_THRESHOLD).powf(1.0 / curve) as usize) as f64 + DE_THRESHOLD)
        } else {
            (count, count as f64)
        };
        let row_size = (2.0 * comp_max.ceil() - 1.0) as usize;
        let half = (row_size - 1) / 2;
        let kernel_size = (half + 1) * (2 + half) / 2;
        let mut widths = Vec::new();
        let mut coefs = Vec::new();
        let mut max_index = 0;
        for k in 0..max_ind {
            let mut h = if k < keep {
                comp_max / ((k + 1) as f64).powf(curve)
            } else {
                let adj = ((k - keep) as f64).powf(1.0 / curve) + keep as f64;
                comp_max / (adj + 1.0).powf(curve)
            };
            if h <= comp_min {
                h = comp_min;
                max_index = k;
            }
            widths.push(h);
            let value = |dx: i64, dy: i64| {
                let d = (((dx * dx + dy * dy) as f64).sqrt()) / h;
                if d <= 1.0 { gaussian(1.5 * d) } else { 0.0 }
            };
            let r = half as i64;
            let sum: f64 = (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| (dx, dy))).map(|(dx, dy)| value(dx, dy)).sum();
            for dy in 0..=r {
                for dx in 0..=dy {
                    coefs.push(value(dx, dy) / sum);
                }
            }
            if max_index > 0 {
                break;
            }
        }
        if max_index == 0 {
            max_index = max_ind - 1;
        }
        if max_index == 0 {
            return Ok(None);
        }
        Ok(Some(Self { widths, coefs, kernel_size, max_index, max_counts, curve, reach: half }))
    }

    /// The kernel for `hits` (the neighbourhood's count).
    fn index(&self, hits: f64) -> usize {
        let k = if hits > self.max_counts {
            self.max_index
        } else if hits <= DE_THRESHOLD {
            (hits.ceil() as usize).saturating_sub(1)
        } else {
            DE_THRESHOLD as usize + (hits - DE_THRESHOLD).powf(self.curve).floor() as usize
        };
        k.min(self.max_index)
    }
}

/// flam3's log-density scale: k1 · ln(1 + a·k2) / a for a bucket of alpha sum a.
pub(super) struct LogScale {
    k1: f64,
    k2: f64,
}

impl LogScale {
    pub fn new(flame: &Flame, layout: &Layout) -> Self {
        let ppu = flame.scale * 2f64.powf(flame.zoom);
        let sample_density = flame.quality * 4f64.powf(flame.zoom);
        let k1 = flame.brightness * WHITE_LEVEL * 268.0 / 256.0;
        let area = (layout.width * layout.height) as f64 / (ppu * ppu);
        let os = layout.oversample as f64;
        let k2 = os * os / (area * WHITE_LEVEL * sample_density);
        Self { k1, k2 }
    }

    #[inline(always)]
    fn of(&self, alpha_sum: f64) -> f64 {
        self.k1 * (alpha_sum * self.k2).ln_1p() / alpha_sum
    }
}

/// The accumulation buffer (RGBA, the histogram's size) of `histogram`.
pub(super) fn accumulate(flame: &Flame, layout: &Layout, histogram: &[Bucket]) -> Result<Vec<[f64; 4]>, RenderError> {
    let scale = LogScale::new(flame, layout);
    let Some(de) = &layout.density else {
        return Ok(histogram
            .par_iter()
            .map(|b| {
                if b[3] == 0 {
                    return [0.0; 4];
                }
                let ls = scale.of(f64::from(b[3]));
                [0, 1, 2, 3].map(|c| f64::from(b[c]) * ls)
            })
            .collect());
    };
    let (w, h) = (layout.hist_width, layout.hist_height);
    let os = layout.oversample;
    let mut acc = vec![[0.0; 4]; w * h];
    // flam3's rows and columns: os − 1 from each edge (the last row past the end is empty).
    let rows = (os - 1)..((os - 1) + (h + 1).saturating_sub(2 * (os - 1))).min(h);
    let bands: Vec<std::ops::Range<usize>> =
        rows.clone().step_by(DE_BAND_ROWS).map(|start| start..(start + DE_BAND_ROWS).min(rows.end)).collect();
    let group = 2 * rayon::current_num_threads().max(1);
    for chunk in bands.chunks(group) {
        let parts: Vec<(usize, Vec<[f64; 4]>)> =
            chunk.par_iter().map(|band| estimate_band(de, &scale, layout, histogram, band.clone())).collect();
        for (first_row, part) in parts {
            let start = first_row * w;
            acc[start..start + part.len()].iter_mut().zip(&part).for_each(|(a, p)| {
                for c in 0..4 {
                    a[c] += p[c];
                }
            });
        }
    }
    Ok(acc)
}

/// The estimator over the rows `band`: the first row of its buffer and the buffer (the band's
/// rows and the kernels' reach above and below, clipped to the histogram).
fn estimate_band(
    de: &DensityFilters,
    scale: &LogScale,
    layout: &Layout,
    histogram: &[Bucket],
    band: std::ops::Range<usize>,
) -> (usize, Vec<[f64; 4]>) {
    let (w, h) = (layout.hist_width, layout.hist_height);
    let os = layout.oversample;
    let ss = (os / 2) as i64;
    let neighbourhood_scale = if os.is_multiple_of(2) { (os as f64 / (os as f64 + 1.0)).powi(2) } else { 1.0 };
    let first_row = band.start.saturating_sub(de.reach);
    let last_row = (band.end + de.reach).min(h);
    let mut buf = vec![[0.0; 4]; (last_row - first_row) * w];
    let mut add = |x: i64, y: i64, c: &[f64; 4]| {
        if x >= 0 && (x as usize) < w && y >= first_row as i64 && (y as usize) < last_row {
            let a = &mut buf[(y as usize - first_row) * w + x as usize];
            for k in 0..4 {
                a[k] += c[k];
            }
        }
    };
    for j in band {
        for i in (os - 1)..w.saturating_sub(os - 1) {
            let b = &histogram[i + j * w];
            if b[4] == 0 || b[3] == 0 {
                continue;
            }
            let mut hits = 0.0;
            for dy in -ss..=ss {
                let y = j as i64 + dy;
                if y < 0 || y as usize >= h {
                    continue;
                }
                for dx in -ss..=ss {
                    hits += f64::from(histogram[(i as i64 + dx) as usize + y as usize * w][4]) / WHITE_LEVEL;
                }
            }
            hits *= neighbourhood_scale;
            let k = de.index(hits);
            let coefs = &de.coefs[k * de.kernel_size..(k + 1) * de.kernel_size];
            let reach = (de.widths[k].ceil() as i64 - 1).max(0);
            let alpha = f64::from(b[3]);
            let ls = scale.of(alpha);
            let colour = [f64::from(b[0]), f64::from(b[1]), f64::from(b[2]), alpha];
            let (x, y) = (i as i64, j as i64);
            let mut idx = 0;
            for dy in 0..=reach {
                for dx in 0..=dy {
                    let coef = coefs[idx];
                    idx += 1;
                    if coef == 0.0 {
                        continue;
                    }
                    let c = colour.map(|v| v * coef * ls);
                    if dy == 0 {
                        add(x, y, &c);
                    } else if dx == 0 {
                        add(x + dy, y, &c);
                        add(x - dy, y, &c);
                        add(x, y + dy, &c);
                        add(x, y - dy, &c);
                    } else if dx == dy {
                        add(x + dx, y + dy, &c);
                        add(x - dx, y + dy, &c);
                        add(x + dx, y - dy, &c);
                        add(x - dx, y - dy, &c);
                    } else {
                        for (u, v) in [(dx, dy), (dy, dx)] {
                            add(x + u, y + v, &c);
                            add(x - u, y + v, &c);
                            add(x + u, y - v, &c);
                            add(x - u, y - v, &c);
                        }
                    }
                }
            }
        }
    }
    (first_row, buf)
}
