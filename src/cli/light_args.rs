//! The key light overrides `nlifs render` and `nlifs record` share: `--shadows`,
//! `--light-yaw-deg`, `--light-pitch-deg` over the scene's `[render]` values (the solid look's
//! cast shadows and the key light's direction relative to the camera, `nlifs::resolve::shadow`),
//! each checked against the scene format's range (`LIGHT_FIELDS`).

use clap::Args;

use nlifs::scene::Scene;
use nlifs::scene::spec::{LIGHT_FIELDS, RenderSettings};

#[derive(Args, Clone, Debug, Default)]
pub struct LightArgs {
    /// Cast shadow strength of the key light, 0 (none) to 1, over the look's; closest mode.
    #[arg(long, value_parser = |s: &str| in_range(s, 0))]
    shadows: Option<f32>,
    /// The key light's direction: degrees from the view direction towards the right,
    /// -180..180 (default -32.7: up-left-front).
    #[arg(long, allow_hyphen_values = true, value_parser = |s: &str| in_range(s, 1))]
    light_yaw_deg: Option<f32>,
    /// The key light's height: degrees above the view's horizontal plane, -90..90 (default 33.5).
    #[arg(long, allow_hyphen_values = true, value_parser = |s: &str| in_range(s, 2))]
    light_pitch_deg: Option<f32>,
}

impl LightArgs {
    /// Sets the given values in `settings`.
    pub fn apply(&self, settings: &mut RenderSettings) {
        settings.shadows = self.shadows.or(settings.shadows);
        for (value, slot) in [self.light_yaw_deg, self.light_pitch_deg].into_iter().zip(settings.light_mut()) {
            if let Some(v) = value {
                *slot = v;
            }
        }
    }

    /// Sets the given values in the scene's render settings and drops the keys' values of the
    /// same settings, so that the override holds over the whole animation.
    pub fn apply_to_scene(&self, scene: &mut Scene) {
        self.apply(&mut scene.render);
        let values = [self.shadows, self.light_yaw_deg, self.light_pitch_deg];
        if let Some(timeline) = &mut scene.timeline {
            for key in &mut timeline.keys {
                for (value, keyed) in values.into_iter().zip(key.render.light.iter_mut()) {
                    if value.is_some() {
                        *keyed = None;
                    }
                }
            }
        }
    }
}

/// A number within the range of field `field` of [`LIGHT_FIELDS`].
fn in_range(s: &str, field: usize) -> Result<f32, String> {
    let (_, lo, hi) = LIGHT_FIELDS[field];
    let v: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number"))?;
    if !(lo..=hi).contains(&v) {
        return Err(format!("{v} is not in {lo}..={hi}"));
    }
    Ok(v as f32)
}
