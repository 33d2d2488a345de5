//! The scene's imaging in the viewer: flam3's tone map, the density scale and density
//! estimation (`[render]` `exposure` … `highlight_power`, `density_scale`, `estimator_*`). The live view takes them from the scene at
//! the current time ([`ViewerState::take_scene_imaging`], keyed `[key.render]` values included),
//! so that it looks as `render` and `record` draw the same scene; the render panel's edits
//! ([`Imaging`], sent as `Command::SetImaging`, UI in `ui/tone.rs`) are scene edits, undoable
//! and saved with the scene, that do not clear the accumulation (the resolve alone changes).

use crate::edit::Edit;
use crate::live::{Imaging, RenderDensity};
use crate::resolve::Tone;
use crate::scene::spec::DensityEstimation;

use super::state::ViewerState;

/// flam3's density estimation defaults (`estimator_radius` 9, minimum 0, curve 0.4): what the
/// panel's switch turns on.
pub const DEFAULT_DENSITY_ESTIMATION: DensityEstimation =
    DensityEstimation { max_radius_px: 9.0, min_radius_px: 0.0, curve: DensityEstimation::DEFAULT_CURVE };

impl ViewerState {
    /// The imaging the live view shows.
    pub fn imaging(&self) -> Imaging {
        Imaging { tone: self.live.draw.tone, density_estimation: self.live.draw.density_estimation }
    }

    /// Which tone fields (in the order of `TONE_FIELDS`) some key of the timeline sets: those
    /// are edited in the key at the playhead, not in `[render]`.
    pub fn keyed_tone_fields(&self) -> [bool; 5] {
        let keys = self.scene.timeline.as_ref().map_or(&[][..], |tl| &tl.keys[..]);
        [0, 1, 2, 3, 4].map(|i| keys.iter().any(|k| k.render.tone[i].is_some()))
    }

    /// The live view's tone and density estimation from the scene at the current time, as
    /// `render` takes them, and the render's points and size, where density mode stops
    /// accumulating ([`RenderDensity`]); true when they changed.
    pub fn take_scene_imaging(&mut self) -> bool {
        let render = self.scene.render_at(self.t_secs);
        let before = (self.imaging(), self.live.render_density);
        self.live.draw.tone = Tone::of(&render);
        self.live.draw.density_estimation = render.density_estimation;
        self.live.render_density =
            Some(RenderDensity { points: render.points, width_px: render.width, height_px: render.height });
        (self.imaging(), self.live.render_density) != before
    }

    /// The render panel's imaging edit: tone fields into `[render]`, or into the key at the
    /// playhead where the timeline keys them (a keyed field without a key there is left as
    /// it is; the panel does not offer it); the density scale and density estimation into
    /// `[render]`. Part of the
    /// running gesture (a slider's drag is one undo step).
    pub(super) fn set_imaging(&mut self, imaging: Imaging) {
        let mut after = self.scene.clone();
        let keyed = self.keyed_tone_fields();
        let key = self.key_at_playhead();
        let old = self.imaging().tone_fields();
        for (i, &value) in imaging.tone_fields().iter().enumerate() {
            if value == old[i] {
                continue;
            }
            match (keyed[i], key, after.timeline.as_mut()) {
                (false, _, _) => *after.render.tone_mut()[i] = value,
                (true, Some(k), Some(tl)) => {
                    tl.keys[k].render.tone[i] = Some(value);
                    // The edit belongs to one playhead.
                    self.playback.playing = false;
                }
                (true, _, _) => {}
            }
        }
        after.render.density_scale = imaging.tone.density_scale;
        after.render.blend_space = imaging.tone.blend;
        after.render.filter = imaging.tone.filter;
        after.render.density_estimation = imaging.density_estimation;
        if after != self.scene {
            self.preview(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) });
        }
    }
}
