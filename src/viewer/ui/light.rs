//! The render panel's key light controls: the cast shadows' strength and the key light's
//! direction relative to the camera (`crate::resolve::shadow`). Like the panel's other sliders
//! they edit a copy of the live settings; the panel turns a change into a
//! `Command::SetLiveSettings`, and the live view restarts its accumulation when the light moves
//! (the shadow map is part of the splat view, `crate::gpu::progressive`).

use crate::live::LiveSettings;
use crate::scene::spec::LIGHT_FIELDS;

use super::widgets::slider;

/// The shadows slider and the light's yaw and pitch, editing `live`; true when one changed.
pub fn light_ui(ui: &mut egui::Ui, live: &mut LiveSettings) -> bool {
    let [(_, shadows_lo, shadows_hi), (_, yaw_lo, yaw_hi), (_, pitch_lo, pitch_hi)] = LIGHT_FIELDS;
    let mut changed = false;
    changed |= ui
        .add(slider(&mut live.draw.shadows, shadows_lo as f32..=shadows_hi as f32).text("shadows (closest)"))
        .changed();
    // The direction only matters where something is lit.
    ui.add_enabled_ui(live.draw.shading > 0.0, |ui| {
        changed |= ui
            .add(slider(&mut live.draw.light_yaw_deg, yaw_lo as f32..=yaw_hi as f32).text("light yaw (°)"))
            .on_hover_text("the key light's direction from the view direction towards the right")
            .changed();
        changed |= ui
            .add(slider(&mut live.draw.light_pitch_deg, pitch_lo as f32..=pitch_hi as f32).text("light pitch (°)"))
            .on_hover_text("the key light's height above the view's horizontal plane")
            .changed();
    });
    changed
}
