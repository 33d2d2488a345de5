//! The accumulation buffer of a flame's histogram: flam3's log-density scale (k1, k2 of its
//! `rect.c`) per bucket, or the adaptive density estimator with the kernels of
//! `render_filter.rs` (see that file for flam3's index rule). The estimator runs on bands of
//! rows in parallel, each into its own buffer, and the bands are added in their order, so the
//! sums are the same whatever the thread count. Each kernel is spread out once to its whole
//! square, so a bucket's spread is a few contiguous row updates (the compiler vectorizes them).

use rayon::prelude::*;

use super::Flame;
use super::render_base::{HistogramCell, RenderError, WHITE_LEVEL};
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

/// Rows of no-estimate accumulation computed at a time.
const PLAIN_CHUNK_ROWS: usize = 64;

/// Rows of the accumulation buffer (RGBA, the histogram's width): `values` holds rows
/// `first_row..`, of which those below `final_end` have all their sums.
pub(super) struct AccRows<'a> {
    pub first_row: usize,
    pub final_end: usize,
    pub width: usize,
    values: &'a [[f64; 4]],
}

impl AccRows<'_> {
    /// `len` values of row `y` (final, and not dropped) from column `x`.
    #[inline(always)]
    pub fn line(&self, y: usize, x: usize, len: usize) -> &[[f64; 4]] {
        debug_assert!(y >= self.first_row && y < self.final_end, "row {y} outside the final rows");
        let at = (y - self.first_row) * self.width + x;
        &self.values[at..at + len]
    }
}

/// The rows of the accumulation buffer still in use: from `first_row`, zero where nothing has
/// been added yet.
struct Window {
    first_row: usize,
    width: usize,
    values: Vec<[f64; 4]>,
}

impl Window {
    /// Rows from `first_row` on up to `end` (new rows zero).
    fn extend_to(&mut self, end: usize) {
        let len = end.saturating_sub(self.first_row) * self.width;
        if len > self.values.len() {
            self.values.resize(len, [0.0; 4]);
        }
    }

    /// Rows `rows` (within the window).
    fn rows_mut(&mut self, rows: std::ops::Range<usize>) -> &mut [[f64; 4]] {
        let w = self.width;
        &mut self.values[(rows.start - self.first_row) * w..(rows.end - self.first_row) * w]
    }

    /// Hands the rows below `final_end` to `take`, then drops those it will not read again.
    fn hand_over(&mut self, final_end: usize, take: &mut dyn FnMut(&AccRows<'_>) -> usize) {
        self.extend_to(final_end);
        let rows = AccRows { first_row: self.first_row, final_end, width: self.width, values: &self.values };
        let keep = take(&rows).min(final_end).max(self.first_row);
        self.values.drain(..(keep - self.first_row) * self.width);
        self.first_row = keep;
    }
}

/// The accumulation buffer of `histogram` (its log-density scale, or the density estimate),
/// handed to `take` a few rows at a time, top to bottom (all of them by the last call, whose
/// `final_end` is the histogram's height); `take` returns the first row it will read again.
/// Only the rows between are kept: the whole buffer (32 bytes a histogram cell) never exists.
pub(super) fn accumulate<C: HistogramCell>(
    flame: &Flame,
    layout: &Layout,
    histogram: &[C],
    take: &mut dyn FnMut(&AccRows<'_>) -> usize,
) -> Result<(), RenderError> {
    let scale = LogScale::new(flame, layout);
    let (w, h) = (layout.hist_width, layout.hist_height);
    let mut window = Window { first_row: 0, width: w, values: Vec::new() };
    let Some(de) = &layout.density else {
        for start in (0..h).step_by(PLAIN_CHUNK_ROWS) {
            let end = (start + PLAIN_CHUNK_ROWS).min(h);
            window.extend_to(end);
            window.rows_mut(start..end).par_iter_mut().zip(&histogram[start * w..end * w]).for_each(|(a, b)| {
                let b = b.bucket();
                if b[3] != 0 {
                    let ls = scale.of(f64::from(b[3]));
                    *a = [0, 1, 2, 3].map(|c| f64::from(b[c]) * ls);
                }
            });
            window.hand_over(end, take);
        }
        return Ok(());
    };
    let os = layout.oversample;
    // flam3's rows and columns: os − 1 from each edge (the last row past the end is empty).
    let rows = (os - 1)..((os - 1) + (h + 1).saturating_sub(2 * (os - 1))).min(h);
    let bands: Vec<std::ops::Range<usize>> =
        rows.clone().step_by(DE_BAND_ROWS).map(|start| start..(start + DE_BAND_ROWS).min(rows.end)).collect();
    let estimator = Estimator { squares: kernel_squares(de), de, scale, layout, histogram };
    let group = 2 * rayon::current_num_threads().max(1);
    // One buffer a band of a group, kept from group to group: memory is asked of the system
    // (and its pages first written) once, not once a band.
    let mut buffers: Vec<Vec<[f64; 4]>> = vec![Vec::new(); group];
    let mut groups = bands.chunks(group).peekable();
    while let Some(chunk) = groups.next() {
        let first_rows: Vec<usize> = chunk
            .par_iter()
            .zip(buffers.par_iter_mut())
            .map(|(band, buffer)| estimator.band_dispatch(band.clone(), buffer))
            .collect();
        for (first_row, part) in first_rows.into_iter().zip(&buffers) {
            let end = first_row + part.len() / w;
            window.extend_to(end);
            window.rows_mut(first_row..end).iter_mut().zip(part).for_each(|(a, p)| {
                for c in 0..4 {
                    a[c] += p[c];
                }
            });
        }
        // The rows no later band reaches are final.
        let final_end = groups.peek().map_or(h, |next| next[0].start.saturating_sub(de.reach));
        window.hand_over(final_end, take);
    }
    if bands.is_empty() {
        window.hand_over(h, take);
    }
    Ok(())
}

/// A density kernel spread out to its whole square (side 2·reach + 1, rows top to bottom), so
/// that a bucket's spread is a few contiguous row updates.
struct KernelSquare {
    reach: usize,
    coefs: Vec<f64>,
}

/// The squares of `de`'s kernels, each to the reach flam3 spreads it (⌈width⌉ − 1).
fn kernel_squares(de: &DensityFilters) -> Vec<KernelSquare> {
    (0..de.widths.len())
        .map(|k| {
            let octant = &de.coefs[k * de.kernel_size..(k + 1) * de.kernel_size];
            let reach = ((de.widths[k].ceil() as i64 - 1).max(0) as usize).min(de.reach);
            let side = 2 * reach + 1;
            let coefs = (0..side * side)
                .map(|n| {
                    let (u, v) = ((n % side).abs_diff(reach), (n / side).abs_diff(reach));
                    let (dy, dx) = (u.max(v), u.min(v));
                    octant[dy * (dy + 1) / 2 + dx]
                })
                .collect();
            KernelSquare { reach, coefs }
        })
        .collect()
}

/// What the estimator reads: the kernels spread to squares, the index rule, the log scale, the
/// histogram and its geometry.
struct Estimator<'a, C> {
    squares: Vec<KernelSquare>,
    de: &'a DensityFilters,
    scale: LogScale,
    layout: &'a Layout,
    histogram: &'a [C],
}

impl<C: HistogramCell> Estimator<'_, C> {
    /// [`Self::band`] compiled for AVX2 when the CPU has it (four channels in one vector; no
    /// FMA, so the sums are the same bits).
    fn band_dispatch(&self, band: std::ops::Range<usize>, buffer: &mut Vec<[f64; 4]>) -> usize {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::SimdLevel::detect().avx2() {
            #[expect(unsafe_code, reason = "an AVX2 function, entered after the CPU check")]
            // SAFETY: the CPU runs AVX2 (checked just above).
            return unsafe { self.band_avx2(band, buffer) };
        }
        self.band(band, buffer, spread)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn band_avx2(&self, band: std::ops::Range<usize>, buffer: &mut Vec<[f64; 4]>) -> usize {
        self.band(band, buffer, |buf, bucket| spread_avx2(buf, bucket))
    }

    /// The estimator over the rows `band` into `buffer` (made the band's rows and the kernels'
    /// reach above and below, clipped to the histogram, all zero at first); returns the buffer's
    /// first row. Each bucket adds
    /// its colour × kernel × log scale to the buckets of its kernel's square; a target's sum takes
    /// the buckets in row order, one term each, as flam3's octant-by-octant spread does (a zero
    /// coefficient adds +0, which changes no sum of non-negative terms).
    #[inline(always)]
    fn band(
        &self,
        band: std::ops::Range<usize>,
        buffer: &mut Vec<[f64; 4]>,
        spread: impl Fn(&mut [[f64; 4]], Spread),
    ) -> usize {
        let Self { squares, de, scale, layout, histogram } = self;
        let (w, h) = (layout.hist_width, layout.hist_height);
        let os = layout.oversample;
        let ss = os / 2;
        let neighbourhood_scale = if os.is_multiple_of(2) { (os as f64 / (os as f64 + 1.0)).powi(2) } else { 1.0 };
        let first_row = band.start.saturating_sub(de.reach);
        let last_row = (band.end + de.reach).min(h);
        buffer.clear();
        buffer.resize((last_row - first_row) * w, [0.0; 4]);
        let buf = buffer.as_mut_slice();
        for j in band {
            let rows_hit = j.saturating_sub(ss)..(j + ss + 1).min(h);
            for i in (os - 1)..w.saturating_sub(os - 1) {
                let b = histogram[i + j * w].bucket();
                if b[4] == 0 || b[3] == 0 {
                    continue;
                }
                let mut hits = 0.0;
                for y in rows_hit.clone() {
                    for cell in &histogram[i - ss + y * w..=i + ss + y * w] {
                        hits += f64::from(cell.bucket()[4]) / WHITE_LEVEL;
                    }
                }
                hits *= neighbourhood_scale;
                let square = &squares[de.index(hits)];
                let reach = square.reach;
                let side = 2 * reach + 1;
                let alpha = f64::from(b[3]);
                let ls = scale.of(alpha);
                let colour = [f64::from(b[0]), f64::from(b[1]), f64::from(b[2]), alpha];
                // The square's columns and rows inside the buffer.
                let (u0, u1) = (reach.saturating_sub(i), side.min(w + reach - i));
                let (v0, v1) = (reach.saturating_sub(j - first_row), side.min(last_row + reach - j));
                let x0 = i + u0 - reach;
                let bucket = Spread {
                    targets: Strided { start: (j + v0 - reach - first_row) * w + x0, stride: w },
                    coefs: &square.coefs,
                    square: Strided { start: v0 * side + u0, stride: side },
                    block: Block { rows: v1 - v0, columns: u1 - u0 },
                    colour,
                    ls,
                };
                spread(buf, bucket);
            }
        }
        first_row
    }
}

/// Where rows lie in a slice: the first from `start`, each `stride` after the one before.
#[derive(Clone, Copy)]
struct Strided {
    start: usize,
    stride: usize,
}

/// The size of a bucket's spread: `rows` rows of `columns` targets.
#[derive(Clone, Copy)]
struct Block {
    rows: usize,
    columns: usize,
}

impl Strided {
    /// The range of row `n` of `block`.
    fn row(&self, n: usize, block: Block) -> std::ops::Range<usize> {
        let at = self.start + n * self.stride;
        at..at + block.columns
    }

    /// Whether the rows of `block` lie inside a slice of `len` items.
    #[cfg(target_arch = "x86_64")]
    fn fits(&self, block: Block, len: usize) -> bool {
        block.rows == 0 || block.columns == 0 || self.start + (block.rows - 1) * self.stride + block.columns <= len
    }
}

/// A bucket's spread: `buf[t][c] += colour[c] · coefs[k] · ls` for the targets `t` of
/// `block` at `targets` and the coefficients `k` of `block` at `square`, in that order (the
/// estimator's one sum).
struct Spread<'a> {
    targets: Strided,
    coefs: &'a [f64],
    square: Strided,
    block: Block,
    colour: [f64; 4],
    ls: f64,
}

/// `bucket`'s spread into `buf`.
#[inline(always)]
fn spread(buf: &mut [[f64; 4]], bucket: Spread) {
    let Spread { targets, coefs, square, block, colour, ls } = bucket;
    for v in 0..block.rows {
        for (t, &coef) in buf[targets.row(v, block)].iter_mut().zip(&coefs[square.row(v, block)]) {
            for c in 0..4 {
                t[c] += colour[c] * coef * ls;
            }
        }
    }
}

/// [`spread`] with a target's four channels in one AVX vector (left to itself, LLVM
/// vectorized across targets and spent its time transposing them): the same operations in the
/// same order, so the same bits. The bounds are checked once a bucket, and the rows walked with
/// pointers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn spread_avx2(buf: &mut [[f64; 4]], bucket: Spread) {
    use std::arch::x86_64::*;
    let Spread { targets, coefs, square, block, colour, ls } = bucket;
    let colour = _mm256_set_pd(colour[3], colour[2], colour[1], colour[0]);
    let ls = _mm256_set1_pd(ls);
    let Block { rows, columns } = block;
    assert!(targets.fits(block, buf.len()) && square.fits(block, coefs.len()), "a spread inside its buffers");
    if rows == 0 || columns == 0 {
        return;
    }
    #[expect(unsafe_code, reason = "pointer walks over two blocks whose bounds were checked")]
    // SAFETY: the rows of both rectangles lie inside their slices (asserted above); a target is
    // a live `[f64; 4]`, 32 bytes.
    unsafe {
        for v in 0..rows {
            let target_row = buf.as_mut_ptr().add(targets.start + v * targets.stride);
            let coef_row = coefs.as_ptr().add(square.start + v * square.stride);
            for n in 0..columns {
                let t = target_row.add(n).cast::<f64>();
                let term = _mm256_mul_pd(_mm256_mul_pd(colour, _mm256_set1_pd(*coef_row.add(n))), ls);
                _mm256_storeu_pd(t, _mm256_add_pd(_mm256_loadu_pd(t), term));
            }
        }
    }
}
