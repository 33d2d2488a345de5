//! The render panel's imaging controls (average and density modes): flam3's tone map and, in
//! density mode, the density scale and density estimation. They read the live view's values (the scene's at the
//! current time) and send `Command::SetImaging` (`imaging.rs` turns it into a scene edit).

use crate::flame::FilterShape;
use crate::flame::render_filter::max_radius;
use crate::scene::spec::{BlendSpace, DensityEstimation, DensityScale, PixelFilter, SplatMode, TONE_FIELDS};

use super::super::command::Command;
use super::super::imaging::DEFAULT_DENSITY_ESTIMATION;
use super::super::state::ViewerState;
use super::widgets::slider;

/// The labels of the tone fields, in the order of `TONE_FIELDS`.
const TONE_LABELS: [&str; 5] = ["exposure (stops)", "gamma", "gamma threshold", "vibrancy", "highlight power (−1 off)"];

pub fn imaging_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let mode = state.live.draw.mode;
    if mode == SplatMode::Closest {
        return;
    }
    let before = state.imaging();
    let mut fields = before.tone_fields();
    let keyed = state.keyed_tone_fields();
    let at_key = state.key_at_playhead().is_some();
    let mut changed = false;
    ui.separator();
    ui.label("Tone (saved with the scene)");
    for (i, ((_, lo, hi), label)) in TONE_FIELDS.into_iter().zip(TONE_LABELS).enumerate() {
        let s = slider(&mut fields[i], lo as f32..=hi as f32).text(label).logarithmic(i == 1);
        let response = ui
            .add_enabled(!keyed[i] || at_key, s)
            .on_disabled_hover_text("keyed in the timeline: move the playhead onto a key to edit it there");
        changed |= response.changed();
    }
    let mut imaging = before.with_tone_fields(fields);
    ui.horizontal(|ui| {
        ui.label("blend");
        for (space, hint) in [
            (BlendSpace::Linear, "colours mixed and toned in linear light"),
            (BlendSpace::Srgb, "colours mixed and toned as sRGB values, as flam3 mixes its palette's bytes"),
        ] {
            changed |= ui.radio_value(&mut imaging.tone.blend, space, space.name()).on_hover_text(hint).changed();
        }
    });
    if mode == SplatMode::Density {
        ui.horizontal(|ui| {
            ui.label("density");
            for (scale, hint) in [
                (DensityScale::Relative, "log(1 + count) / log(1 + max count): the densest pixel is full"),
                (DensityScale::Absolute, "flam3's: points per point drawn and square unit; refines as points grow"),
            ] {
                let response = ui.radio_value(&mut imaging.tone.density_scale, scale, scale.name()).on_hover_text(hint);
                changed |= response.changed();
            }
        });
        let mut on = imaging.density_estimation.is_some();
        if ui
            .checkbox(&mut on, "density estimation")
            .on_hover_text("flam3's adaptive filter: sparse regions smooth, dense ones sharp")
            .changed()
        {
            imaging.density_estimation = on.then_some(DEFAULT_DENSITY_ESTIMATION);
            changed = true;
        }
        if let Some(de) = &mut imaging.density_estimation {
            let max = DensityEstimation::MAX_RADIUS_PX;
            changed |= ui.add(slider(&mut de.max_radius_px, 0.5..=max).text("estimator radius (px)")).changed();
            de.min_radius_px = de.min_radius_px.min(de.max_radius_px);
            let radius = de.max_radius_px;
            changed |= ui.add(slider(&mut de.min_radius_px, 0.0..=radius).text("estimator minimum (px)")).changed();
            changed |= ui.add(slider(&mut de.curve, 0.01..=10.0).logarithmic(true).text("estimator curve")).changed();
        }
    }
    // flam3's spatial filter, of the scene's shape (gaussian where it has none).
    let shape = imaging.tone.filter.map_or(FilterShape::Gaussian, |f| f.shape);
    let mut radius = imaging.tone.filter.map_or(0.0, |f| f.radius_px);
    let widest = (0.9999 * max_radius(shape, PixelFilter::MAX_TAPS)) as f32;
    let response =
        ui.add(slider(&mut radius, 0.0..=widest).text(format!("{} filter (px, 0 off)", shape.name()))).on_hover_text(
            "flam3's spatial filter: each pixel takes a share of its neighbours' light (flam3's default 0.5)",
        );
    if response.changed()
        && let Ok(filter) = PixelFilter::checked(f64::from(radius), shape)
    {
        imaging.tone.filter = filter;
        changed = true;
    }
    if changed && imaging != before {
        commands.push(Command::SetImaging(imaging));
    }
}
