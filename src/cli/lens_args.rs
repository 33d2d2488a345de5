//! The depth-of-field overrides `nlifs render` and `nlifs record` share: `--aperture`,
//! `--focus-distance` over the scene's `[render]` values (the thin lens of
//! `nlifs::splat::lens`), checked as the scene format checks them.

use clap::Args;

use nlifs::scene::Scene;
use nlifs::scene::spec::RenderSettings;

#[derive(Args, Clone, Debug, Default)]
pub struct LensArgs {
    /// Depth of field: the lens radius in scene units (0: none, the pinhole picture). Points
    /// off the focus plane spread into discs; default: the scene's `aperture`.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_aperture)]
    aperture: Option<f32>,
    /// Depth of field: the view distance in focus (> 0). Default: the scene's
    /// `focus_distance`, else the camera's distance to its target.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_focus_distance)]
    focus_distance: Option<f32>,
}

impl LensArgs {
    /// Sets the given lens values in `settings`.
    pub fn apply(&self, settings: &mut RenderSettings) {
        if let Some(a) = self.aperture {
            settings.aperture = a;
        }
        if let Some(f) = self.focus_distance {
            settings.focus_distance = Some(f);
        }
    }

    /// Sets the given lens values in the scene's render settings and drops the keys' values of
    /// the same settings, so that the override holds over the whole animation.
    pub fn apply_to_scene(&self, scene: &mut Scene) {
        self.apply(&mut scene.render);
        if let Some(timeline) = &mut scene.timeline {
            for key in &mut timeline.keys {
                if self.aperture.is_some() {
                    key.render.aperture = None;
                }
                if self.focus_distance.is_some() {
                    key.render.focus_distance = None;
                }
            }
        }
    }
}

fn number(s: &str) -> Result<f32, String> {
    s.trim().parse::<f32>().map_err(|_| format!("`{s}` is not a number"))
}

/// `--aperture`: a finite number ≥ 0.
fn parse_aperture(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    nlifs::splat::lens::check(v, None).map_err(|e| e.to_string())?;
    Ok(v)
}

/// `--focus-distance`: a finite number > 0.
fn parse_focus_distance(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    nlifs::splat::lens::check(0.0, Some(v)).map_err(|e| e.to_string())?;
    Ok(v)
}
