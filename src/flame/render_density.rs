//! The accumulation buffer of a flame's histogram: flam3's log-density scale (k1, k2 of its
//! `rect.c`) per bucket, or the adaptive density estimator with the kernels of
//! `render_filter.rs` (see that file for flam3's index rule). The estimator runs on bands of
//! rows in parallel, each into its own buffer, and the bands are added in their order, so the
//! sums are the same whatever the thread count.

use rayon::prelude::*;

use super::Flame;
use super::render_base::{Bucket, RenderError, WHITE_LEVEL};
use super::render_filter::DensityFilters;
use super::render_layout::Layout;

/// Rows of the histogram one estimator task handles.
const DE_BAND_ROWS: usize = 32;

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
