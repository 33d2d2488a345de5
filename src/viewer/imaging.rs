//! The scene's imaging in the viewer: flam3's tone map and density estimation (`[render]`
//! `exposure` … `highlight_power`, `estimator_*`). The live view takes them from the scene at
//! the current time (`ViewerState::take_scene_imaging` in `imaging_edit.rs`, keyed
//! `[key.render]` values included), so that it looks as `render` and `record` draw the same
//! scene; the render panel's edits
//! ([`Imaging`], sent as `Command::SetImaging`, UI in `tone_ui.rs`) are scene edits, undoable
//! and saved with the scene, that do not clear the accumulation (the resolve alone changes).

use crate::resolve::Tone;
use crate::scene::spec::DensityEstimation;

/// What the render panel's imaging controls edit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Imaging {
    pub tone: Tone,
    /// None: off.
    pub density_estimation: Option<DensityEstimation>,
}

impl Imaging {
    /// The tone fields in the order of `scene::spec::TONE_FIELDS`.
    pub fn tone_fields(&self) -> [f32; 5] {
        let t = &self.tone;
        [t.exposure, t.gamma, t.gamma_threshold, t.vibrancy, t.highlight_power]
    }

    pub fn with_tone_fields(self, v: [f32; 5]) -> Self {
        let tone = Tone { exposure: v[0], gamma: v[1], gamma_threshold: v[2], vibrancy: v[3], highlight_power: v[4] };
        Self { tone, ..self }
    }
}

/// flam3's density estimation defaults (`estimator_radius` 9, minimum 0, curve 0.4): what the
/// panel's switch turns on.
pub const DEFAULT_DENSITY_ESTIMATION: DensityEstimation =
    DensityEstimation { max_radius_px: 9.0, min_radius_px: 0.0, curve: DensityEstimation::DEFAULT_CURVE };
