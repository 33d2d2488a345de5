//! flam3's filters: the spatial filters (its `filters.c`) that take the accumulation buffer
//! down to the image, and the density estimator's kernels with flam3's index rule (the density
//! of a bucket is the count summed over the supersample's ss×ss neighbourhood, scaled by
//! (ss/(ss+1))² for even ss; hits 1..=100 pick kernels one by one and more hits go through
//! `100 + (hits − 100)^curve`), which `render_density.rs` applies.

use super::render_base::RenderError;
use super::{FilterShape, Flame};

/// flam3's `DE_THRESH`: up to this many hits, one kernel per hit count.
const DE_THRESHOLD: f64 = 100.0;

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

/// The kernel values of flam3's spatial filter of `named` shape and `radius` (output pixels)
/// over a buffer of `oversample`² samples a pixel, along one axis: `width` values, the parity of
/// `oversample`, unnormalized (the square filter is their outer product, normalized).
fn filter_row(named: FilterShape, radius: f64, oversample: usize) -> Vec<f64> {
    let shape = as_flam3_evaluates(named);
    let supp = support(shape);
    let fw = 2.0 * supp * oversample as f64 * radius.max(0.0);
    let mut width = fw as usize + 1;
    if (width ^ oversample) & 1 == 1 {
        width += 1;
    }
    let adjust = if fw > 0.0 { supp * width as f64 / fw } else { 1.0 };
    (0..width).map(|i| kernel(shape, ((2.0 * i as f64 + 1.0) / width as f64 - 1.0) * adjust)).collect()
}

/// The width of flam3's spatial filter of `shape` and `radius` (pixels) at one sample a pixel:
/// the side of its square of taps, odd.
pub fn filter_width(shape: FilterShape, radius: f64) -> usize {
    let supp = support(as_flam3_evaluates(shape));
    let fw = 2.0 * supp * radius.max(0.0);
    // fw as usize + 1, made odd (the rule of `filter_row` for one sample a pixel).
    (fw as usize + 1) | 1
}

/// flam3's spatial filter (`[render] filter`, `filter_shape`): before the tone map each pixel
/// takes the weighted sum of the linear densities and colours of the pixels around it, with the
/// weights flam3 gives the shape at this radius ([`filter_weights`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFilter {
    /// flam3's `filter`: the radius in pixels (a Gaussian of radius 0.5 spans 3 × 3 pixels).
    pub radius_px: f32,
    pub shape: FilterShape,
}

impl PixelFilter {
    /// The widest filter, in pixels along each axis (the resolve's table of weights).
    pub const MAX_TAPS: usize = 15;

    /// The filter of `shape` and radius `radius_px` (0: off, None), or why there is none: a
    /// radius outside 0..=100, a filter wider than [`Self::MAX_TAPS`] pixels, or weights that
    /// sum to 0.
    pub fn checked(radius_px: f64, shape: FilterShape) -> Result<Option<Self>, String> {
        if !(0.0..=100.0).contains(&radius_px) {
            return Err(format!("the radius {radius_px} is not in 0..=100"));
        }
        if radius_px == 0.0 {
            return Ok(None);
        }
        let taps = filter_width(shape, radius_px);
        if taps > Self::MAX_TAPS {
            return Err(format!(
                "a {} filter of radius {radius_px} spans {taps} pixels; at most {} (a smaller radius)",
                shape.name(),
                Self::MAX_TAPS
            ));
        }
        if filter_weights(shape, radius_px).is_none() {
            return Err(format!("a {} filter of radius {radius_px} has weights that sum to 0", shape.name()));
        }
        Ok(Some(Self { radius_px: radius_px as f32, shape }))
    }
}

/// The widest radius (pixels) whose filter of `shape` spans at most `taps` pixels (odd).
pub fn max_radius(shape: FilterShape, taps: usize) -> f64 {
    // filter_width ≤ taps ⟺ 2 · support · radius < taps.
    let mut radius = taps as f64 / (2.0 * support(as_flam3_evaluates(shape)));
    while radius > 0.0 && filter_width(shape, radius) > taps {
        radius = radius.next_down();
    }
    radius
}

/// flam3's spatial filter of `shape` and `radius` (pixels) at one sample a pixel as the weights
/// of one axis, normalized to sum 1: the square filter is their outer product (flam3's
/// normalization of the product is the same up to rounding). None where the weights sum to 0.
pub fn filter_weights(shape: FilterShape, radius: f64) -> Option<Vec<f64>> {
    let row = filter_row(shape, radius, 1);
    let sum: f64 = row.iter().sum();
    (sum != 0.0 && sum.is_finite()).then(|| row.iter().map(|v| v / sum).collect())
}

impl SpatialFilter {
    pub fn new(named: FilterShape, radius: f64, oversample: usize) -> Result<Self, RenderError> {
        let row = filter_row(named, radius, oversample);
        let width = row.len();
        let mut coefs: Vec<f64> = (0..width * width).map(|k| row[k % width] * row[k / width]).collect();
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
    pub widths: Vec<f64>,
    /// `kernel_size` octant coefficients per kernel.
    pub coefs: Vec<f64>,
    pub kernel_size: usize,
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
    pub fn index(&self, hits: f64) -> usize {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The scene's one-axis weights are flam3's square filter at one sample a pixel: their outer
    /// product is [`SpatialFilter`]'s, shape by shape.
    #[test]
    fn one_axis_weights_multiply_to_the_square_filter() {
        for shape in FilterShape::ALL {
            for radius in [0.3, 0.5, 0.8, 1.3, 2.0] {
                let square = SpatialFilter::new(shape, radius, 1).expect("a filter");
                let row = filter_weights(shape, radius).expect("weights");
                assert_eq!(row.len(), square.width, "{shape:?} {radius}");
                assert_eq!(filter_width(shape, radius), square.width, "{shape:?} {radius}");
                let widest = max_radius(shape, 15);
                assert!(filter_width(shape, widest) <= 15 && filter_width(shape, widest * 1.0001) > 15, "{shape:?}");
                for (k, c) in square.coefs.iter().enumerate() {
                    let product = row[k % square.width] * row[k / square.width];
                    assert!((product - c).abs() < 1e-12, "{shape:?} {radius} tap {k}: {product} vs {c}");
                }
            }
        }
    }
}
