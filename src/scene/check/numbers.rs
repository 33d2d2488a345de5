//! The ranges of the scene format's numbers, each checked with a located error that states
//! it: finite numbers, ranges, angles, coordinates and the grid extents the f32 renderers
//! draw faithfully (the limits themselves are named in `spec.rs`).

use std::ops::Range;

use toml::Spanned;

use crate::flame::FilterShape;
use crate::scene::file::RenderToml;
use crate::scene::spec::{
    DensityEstimation, GRID_EXTENT_RANGE, MAX_ANGLE_DEG, MAX_COORDINATE, MAX_GRID_OFFSET_RATIO, PixelFilter,
};

use super::{Checker, Res, words};

impl Checker<'_> {
    pub(super) fn finite(&self, v: &Spanned<f64>, field: &str) -> Res<f64> {
        if v.get_ref().is_finite() {
            Ok(*v.get_ref())
        } else {
            Err(self.err(v.span(), field, format!("must be a finite number, found {}", words::show(*v.get_ref()))))
        }
    }

    /// A number in `lo..=hi`; the message states the range.
    pub(super) fn in_range(&self, v: &Spanned<f64>, field: &str, lo: f64, hi: f64) -> Res<f64> {
        let x = self.finite(v, field)?;
        if !(lo..=hi).contains(&x) {
            return Err(self.err(
                v.span(),
                field,
                format!("must lie in {}..{}, found {}", words::show(lo), words::show(hi), words::show(x)),
            ));
        }
        Ok(x)
    }

    /// An angle in degrees, at most [`MAX_ANGLE_DEG`] either way.
    pub(super) fn angle(&self, v: &Spanned<f64>, field: &str) -> Res<f64> {
        self.in_range(v, field, -MAX_ANGLE_DEG, MAX_ANGLE_DEG)
    }

    /// Coordinates: finite numbers of magnitude at most [`MAX_COORDINATE`].
    pub(super) fn coordinates(&self, span: Range<usize>, xs: &[f64], field: &str) -> Res<()> {
        if let Some(x) = xs.iter().find(|x| !(x.abs() <= MAX_COORDINATE)) {
            return Err(self.err(
                span,
                field,
                format!("numbers must be finite and within ±{MAX_COORDINATE:e}, found {}", words::show(*x)),
            ));
        }
        Ok(())
    }

    /// A grid axis of a size and place the f32 renderers draw faithfully
    /// ([`GRID_EXTENT_RANGE`], [`MAX_GRID_OFFSET_RATIO`]).
    pub(super) fn supported_extent(&self, axis: &Spanned<Vec<f64>>, field: &str) -> Res<()> {
        let xs = axis.get_ref();
        let (Some(&first), Some(&last)) = (xs.first(), xs.last()) else { return Ok(()) };
        if xs.len() < 2 {
            return Ok(());
        }
        let extent = last - first;
        let (lo, hi) = GRID_EXTENT_RANGE;
        if !(lo..=hi).contains(&extent) {
            return Err(self.err(
                axis.span(),
                field,
                format!(
                    "spans {}, outside the supported extent {}..{} (the renderers work in f32); scale the scene",
                    words::show(extent),
                    words::show(lo),
                    words::show(hi)
                ),
            ));
        }
        let far = first.abs().max(last.abs());
        if far > MAX_GRID_OFFSET_RATIO * extent {
            return Err(self.err(
                axis.span(),
                field,
                format!(
                    "lies {} from the origin, more than {} times its extent {} (f32 would show its steps); move the scene nearer the origin",
                    words::show(far),
                    words::show(MAX_GRID_OFFSET_RATIO),
                    words::show(extent)
                ),
            ));
        }
        Ok(())
    }
}

impl Checker<'_> {
    /// flam3's density estimation fields: `estimator_radius` in 0..=32 (0 or absent: off),
    /// `estimator_minimum` in 0..=radius, `estimator_curve` in 0.01..=10; the last two only
    /// with a radius.
    pub(super) fn density_estimation(&self, r: &RenderToml) -> Res<Option<DensityEstimation>> {
        let max = DensityEstimation::MAX_RADIUS_PX as f64;
        let radius = match &r.estimator_radius {
            Some(v) => self.in_range(v, "render.estimator_radius", 0.0, max)?,
            None => 0.0,
        };
        if radius == 0.0 {
            for (v, field) in
                [(&r.estimator_minimum, "render.estimator_minimum"), (&r.estimator_curve, "render.estimator_curve")]
            {
                if let Some(v) = v {
                    return Err(self.err(
                        v.span(),
                        field,
                        "needs `estimator_radius` above 0 (density estimation is off)",
                    ));
                }
            }
            return Ok(None);
        }
        let min = match &r.estimator_minimum {
            Some(v) => self.in_range(v, "render.estimator_minimum", 0.0, radius)?,
            None => 0.0,
        };
        let curve = match &r.estimator_curve {
            Some(v) => self.in_range(v, "render.estimator_curve", 0.01, 10.0)?,
            None => DensityEstimation::DEFAULT_CURVE as f64,
        };
        Ok(Some(DensityEstimation { max_radius_px: radius as f32, min_radius_px: min as f32, curve: curve as f32 }))
    }

    /// flam3's spatial filter: `filter` (the radius in pixels, 0 or absent: off) at most as wide
    /// as [`PixelFilter::MAX_TAPS`] pixels, `filter_shape` one of flam3's names (default
    /// gaussian), only with a radius.
    pub(super) fn filter(&self, r: &RenderToml) -> Res<Option<PixelFilter>> {
        let shape = match &r.filter_shape {
            Some(name) => FilterShape::parse(name.get_ref()).ok_or_else(|| {
                self.err(
                    name.span(),
                    "render.filter_shape",
                    format!("`{}` is not a filter shape; use one of {}", name.get_ref(), FilterShape::NAMES.join(", ")),
                )
            })?,
            None => FilterShape::Gaussian,
        };
        let Some(v) = &r.filter else {
            if let Some(name) = &r.filter_shape {
                return Err(self.err(name.span(), "render.filter_shape", "needs `filter` above 0 (the filter is off)"));
            }
            return Ok(None);
        };
        let radius = self.finite(v, "render.filter")?;
        PixelFilter::checked(radius, shape).map_err(|why| self.err(v.span(), "render.filter", why))
    }
}
