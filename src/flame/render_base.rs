//! What the stages of a flame's render share: its errors, the histogram's cell and flam3's
//! white level.

/// flam3's white level: palette colours are scaled to 0..255 in the histogram.
pub(super) const WHITE_LEVEL: f64 = 255.0;
/// One histogram cell: palette colour sums (R, G, B, A, each × 255) and the count × 255.
pub(super) type Bucket = [u32; 5];

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
