//! The histogram's geometry for a flame: supersampled, with a gutter for the spatial filter
//! and the density estimator.

use super::Flame;
use super::render_base::{Bucket, RenderError};
use super::render_filter::{DensityFilters, SpatialFilter};

/// The largest histogram this renderer allocates per thread.
const MAX_HISTOGRAM_BYTES: u64 = 8 << 30;
const _: () = assert!(MAX_HISTOGRAM_BYTES / std::mem::size_of::<Bucket>() as u64 <= u32::MAX as u64);

/// The histogram's geometry: the image supersampled, with a gutter around it wide enough for
/// the spatial filter and the density estimator (flam3's `gutter_width`, `de_offset`).
pub(super) struct Layout {
    pub width: usize,
    pub height: usize,
    pub oversample: usize,
    pub filter: SpatialFilter,
    pub density: Option<DensityFilters>,
    pub gutter: usize,
    /// Where the spatial filter of the image's first pixel starts in the histogram.
    pub filter_offset: usize,
    pub hist_width: usize,
    pub hist_height: usize,
}

impl Layout {
    pub fn new(flame: &Flame) -> Result<Self, RenderError> {
        let [w, h] = flame.size;
        if w == 0 || h == 0 {
            return Err(RenderError::BadSize(w, h));
        }
        if !(flame.quality > 0.0) {
            return Err(RenderError::BadQuality(flame.quality));
        }
        if flame.supersample == 0 {
            return Err(RenderError::BadSupersample(flame.supersample));
        }
        if !(flame.scale > 0.0) || !flame.scale.is_finite() {
            return Err(RenderError::BadScale(flame.scale));
        }
        if flame.palette.len() != 256 {
            return Err(RenderError::BadPalette(flame.palette.len()));
        }
        let oversample = flame.supersample as usize;
        let filter = SpatialFilter::new(flame.filter_shape, flame.filter, oversample)?;
        let density = DensityFilters::for_flame(flame, oversample)?;
        let mut gutter = (filter.width - oversample) / 2;
        let mut de_width = (flame.estimator_radius.ceil() as usize) * oversample;
        if density.is_some() && de_width > 0 {
            de_width += oversample - 1;
        } else {
            de_width = 0;
        }
        let filter_offset = if de_width > gutter {
            let offset = de_width - gutter;
            gutter = de_width;
            offset
        } else {
            0
        };
        let hist_width = oversample * w as usize + 2 * gutter;
        let hist_height = oversample * h as usize + 2 * gutter;
        let bytes = (hist_width * hist_height) as u64 * std::mem::size_of::<Bucket>() as u64;
        // (Within the limit each side is below 2^31 and the buckets number below 2^32, which
        // the chaos game's bucket arithmetic takes for granted; the sides said here too, for a
        // histogram one bucket high.)
        if bytes > MAX_HISTOGRAM_BYTES || hist_width > i32::MAX as usize || hist_height > i32::MAX as usize {
            return Err(RenderError::TooLarge { width: hist_width, height: hist_height, bytes });
        }
        Ok(Self {
            width: w as usize,
            height: h as usize,
            oversample,
            filter,
            density,
            gutter,
            filter_offset,
            hist_width,
            hist_height,
        })
    }
}
