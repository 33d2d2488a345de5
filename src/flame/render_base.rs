//! What the stages of a flame's render share: its errors, the histogram's cell, flam3's white
//! level and a conversion to integers that vector loops have.

/// flam3's white level: palette colours are scaled to 0..255 in the histogram.
pub(super) const WHITE_LEVEL: f64 = 255.0;
/// One histogram cell: palette colour sums (R, G, B, A, each × 255) and the count × 255.
pub(super) type Bucket = [u32; 5];

/// A histogram's cell as the density estimate and log scale read it: a [`Bucket`] (the f64
/// game's), or the lane game's 16-byte cell, read in place (no copy of the histogram made).
pub(super) trait HistogramCell: Copy + Send + Sync {
    fn bucket(self) -> Bucket;
}

impl HistogramCell for Bucket {
    #[inline(always)]
    fn bucket(self) -> Bucket {
        self
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RenderError {
    #[error("flame `{0}` has no xform with a positive weight: there is nothing to iterate")]
    Empty(String),
    #[error("xform {index} has the negative weight {weight}; weights must be ≥ 0")]
    NegativeWeight { index: usize, weight: f64 },
    #[error("size {0}×{1}: both must be at least 1 pixel")]
    BadSize(u32, u32),
    #[error("quality {0}: it must be greater than 0")]
    BadQuality(f64),
    #[error("supersample {0}: it must be at least 1")]
    BadSupersample(u32),
    #[error("scale {0}: pixels per unit must be greater than 0")]
    BadScale(f64),
    #[error("the palette has {0} entries; flam3's palettes have 256")]
    BadPalette(usize),
    #[error("{0}")]
    BadEstimator(String),
    #[error("the spatial filter of radius {0} is zero everywhere")]
    BadFilter(f64),
    #[error("the histogram ({width}×{height} buckets, {bytes} bytes) is too large")]
    TooLarge { width: usize, height: usize, bytes: u64 },
}

/// `v` truncated toward 0, as `v as u32` for 0 ≤ v < 2^32 (not NaN), with operations that
/// vector loops have: the truncation, then 2^52 added, which puts the integer in the low bits
/// (LLVM does not vectorize `as` from a double: the chaos game's buckets and palette entries
/// were computed lane by lane).
#[inline(always)]
pub(super) fn whole_u32(v: f64) -> u32 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    (v.trunc() + TWO_52).to_bits() as u32
}
