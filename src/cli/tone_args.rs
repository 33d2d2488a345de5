//! The tone overrides `nlifs render` and `nlifs record` share: `--exposure`, `--gamma`,
//! `--gamma-threshold`, `--vibrancy`, `--highlight-power`, `--density-scale` and `--filter` over the
//! scene's `[render]` values (flam3's tone controls of the average and density modes,
//! `nlifs::resolve::Tone`), the numbers checked against the scene format's range
//! (`TONE_FIELDS`).

use clap::Args;

use nlifs::flame::FilterShape;
use nlifs::scene::Scene;
use nlifs::scene::spec::{DensityScale, PixelFilter, RenderSettings, TONE_FIELDS};

#[derive(Args, Clone, Debug, Default)]
pub struct ToneArgs {
    /// Brightness in stops (2^EXPOSURE), average and density modes: -10..10.
    #[arg(long, allow_hyphen_values = true, value_parser = |s: &str| in_range(s, 0))]
    exposure: Option<f32>,
    /// Gamma of the density's alpha (raised to 1 / GAMMA), average and density modes: 0.1..10.
    #[arg(long, value_parser = |s: &str| in_range(s, 1))]
    gamma: Option<f32>,
    /// Below this alpha the gamma curve blends into a straight line: 0..1.
    #[arg(long, value_parser = |s: &str| in_range(s, 2))]
    gamma_threshold: Option<f32>,
    /// 1: gamma on the alpha (saturated colours); 0: gamma per channel: 0..1.
    #[arg(long, value_parser = |s: &str| in_range(s, 3))]
    vibrancy: Option<f32>,
    /// Highlights past white: negative clips per channel, 0 keeps the hue, larger fades to
    /// white: -1..16.
    #[arg(long, allow_hyphen_values = true, value_parser = |s: &str| in_range(s, 4))]
    highlight_power: Option<f32>,
    /// Density mode's log density: relative (the densest pixel full) or absolute (flam3's: a
    /// pixel's points per point drawn and square unit; converges as points grow).
    #[arg(long, value_name = "SCALE", value_parser = density_scale)]
    density_scale: Option<DensityScale>,
    /// flam3's spatial filter, average and density modes: each pixel takes a share of its
    /// neighbours' light, RADIUS in pixels (0.5: flam3's default, 3×3 pixels; 0: off), SHAPE
    /// one of flam3's (gaussian, the default, hermite, box, triangle, bell, bspline, mitchell,
    /// blackman, catrom, hanning, hamming, lanczos3, lanczos2, quadratic).
    #[arg(long, value_name = "RADIUS[,SHAPE]", value_parser = filter)]
    filter: Option<FilterFlag>,
}

/// A parsed `--filter`: the filter, None for off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterFlag(Option<PixelFilter>);

impl ToneArgs {
    fn values(&self) -> [Option<f32>; 5] {
        [self.exposure, self.gamma, self.gamma_threshold, self.vibrancy, self.highlight_power]
    }

    /// Sets the given tone values and density scale in `settings`.
    pub fn apply(&self, settings: &mut RenderSettings) {
        for (value, slot) in self.values().into_iter().zip(settings.tone_mut()) {
            if let Some(v) = value {
                *slot = v;
            }
        }
        if let Some(scale) = self.density_scale {
            settings.density_scale = scale;
        }
        if let Some(FilterFlag(filter)) = self.filter {
            settings.filter = filter;
        }
    }

    /// Sets the given tone values in the scene's render settings and drops the keys' values of
    /// the same settings, so that the override holds over the whole animation.
    pub fn apply_to_scene(&self, scene: &mut Scene) {
        self.apply(&mut scene.render);
        if let Some(timeline) = &mut scene.timeline {
            for key in &mut timeline.keys {
                for (value, keyed) in self.values().into_iter().zip(key.render.tone.iter_mut()) {
                    if value.is_some() {
                        *keyed = None;
                    }
                }
            }
        }
    }
}

/// A number within the range of tone field `field` of [`TONE_FIELDS`].
fn in_range(s: &str, field: usize) -> Result<f32, String> {
    let (_, lo, hi) = TONE_FIELDS[field];
    let v: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number"))?;
    if !(lo..=hi).contains(&v) {
        return Err(format!("{v} is not in {lo}..={hi}"));
    }
    Ok(v as f32)
}

/// A density scale by its scene-file name.
fn density_scale(s: &str) -> Result<DensityScale, String> {
    DensityScale::parse(s.trim()).ok_or_else(|| format!("`{s}` is not a density scale; use relative or absolute"))
}

/// `--filter RADIUS[,SHAPE]`, checked as the scene's `filter` and `filter_shape` are.
fn filter(s: &str) -> Result<FilterFlag, String> {
    let (radius, shape) = s.split_once(',').map_or((s, None), |(r, shape)| (r, Some(shape.trim())));
    let radius: f64 = radius.trim().parse().map_err(|_| format!("`{radius}` is not a number"))?;
    let shape = match shape {
        Some(name) => FilterShape::parse(name)
            .ok_or_else(|| format!("`{name}` is not a filter shape; use one of {}", FilterShape::NAMES.join(", ")))?,
        None => FilterShape::Gaussian,
    };
    PixelFilter::checked(radius, shape).map(FilterFlag)
}
