//! The side panel's "Flame functions" section: each `kind = "flame"` function's numbers at the
//! playhead (flam3's pre-affine coefs a b c d e f, the post-affine where it has one, each
//! variation's weight and parameters by flam3's names, the colour speed, the opacity), and the
//! final xform's, edited by dragging. Like every `*_ui` function it only reads the state and
//! emits [`Command::SetFlame`] (or [`Command::SetFinalXform`]); a drag is one undo step, keyed
//! at the playhead on an animated scene (`authoring.rs`; the final xform is not keyed).

use egui::RichText;

use crate::scene::spec::{FlameDef, FunctionDef};

use super::super::command::Command;
use super::super::state::ViewerState;
use super::widgets::slider;

/// flam3's names of the six coefficients, in its order.
const COEF_NAMES: [&str; 6] = ["a", "b", "c", "d", "e", "f"];

const COEFS_HELP: &str = "flam3's affine coefficients: x' = a·x + c·y + e, y' = b·x + d·y + f";

pub fn flame_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let flames: Vec<(usize, &str, FlameDef)> = state
        .scene
        .functions
        .iter()
        .enumerate()
        .filter_map(|(i, f)| match state.scene.function_def_at(i, state.t_secs) {
            FunctionDef::Flame(def) => Some((i, f.name.as_str(), def)),
            _ => None,
        })
        .collect();
    let final_xform = state.scene.final_xform.as_ref();
    if flames.is_empty() && final_xform.is_none() {
        return;
    }
    egui::CollapsingHeader::new("Flame functions").default_open(true).show(ui, |ui| {
        for (function, name, def) in flames {
            ui.label(RichText::new(name).strong());
            let mut value = def.clone();
            let mut changed = xform_ui(ui, function, &mut value);
            ui.horizontal(|ui| {
                ui.label("opacity").on_hover_text(
                    "flam3's opacity: each point of this function is drawn with chance 10^(log₂ opacity)",
                );
                changed |= ui.add(slider(&mut value.opacity, 0.0..=1.0)).changed();
            });
            if changed && value != def {
                commands.push(Command::SetFlame { function, value });
            }
            ui.separator();
        }
        if let Some(f) = final_xform {
            ui.label(RichText::new("final xform").strong())
                .on_hover_text("flam3's final xform: maps every point drawn, not the orbit (not keyed)");
            let mut value = f.clone();
            let mut changed = xform_ui(ui, usize::MAX, &mut value.def);
            ui.horizontal(|ui| {
                ui.label("colour index").on_hover_text("its colour coordinate c_f (flam3's color)");
                changed |= ui.add(slider(&mut value.palette_index, 0.0..=1.0)).changed();
            });
            if changed && value != *f {
                commands.push(Command::SetFinalXform(value));
            }
        }
    });
}

/// One xform's coefs, post-affine, variations and colour speed; `id` tells its widgets apart.
fn xform_ui(ui: &mut egui::Ui, id: usize, value: &mut FlameDef) -> bool {
    let mut changed = coefs_ui(ui, ("pre", id), "coefs", &mut value.coefs);
    if let Some(post) = &mut value.post {
        changed |= coefs_ui(ui, ("post", id), "post", post);
    }
    egui::Grid::new(("flame_variations", id)).num_columns(2).spacing([6.0, 2.0]).show(ui, |ui| {
        for t in &mut value.variations {
            ui.label(t.variation.name()).on_hover_text("this variation's weight in the sum");
            changed |= number(ui, &mut t.weight, 0.005);
            ui.end_row();
            for ((param, _), v) in t.variation.info().params.iter().zip(t.params.iter_mut()) {
                ui.small(format!("  {param}"));
                changed |= number(ui, v, 0.01);
                ui.end_row();
            }
        }
    });
    ui.horizontal(|ui| {
        ui.label("colour speed").on_hover_text("s in c' = s·c_i + (1 − s)·c (flam3's color_speed)");
        changed |= ui.add(slider(&mut value.color_speed, 0.0..=1.0)).changed();
    });
    changed
}

/// Six coefficients in two rows (a c e, then b d f: x' and y').
fn coefs_ui(ui: &mut egui::Ui, id: (&str, usize), label: &str, coefs: &mut [f64; 6]) -> bool {
    let mut changed = false;
    ui.label(label).on_hover_text(COEFS_HELP);
    egui::Grid::new(id).num_columns(3).spacing([4.0, 2.0]).show(ui, |ui| {
        for row in [[0, 2, 4], [1, 3, 5]] {
            for k in row {
                ui.horizontal(|ui| {
                    ui.small(COEF_NAMES[k]);
                    changed |= number(ui, &mut coefs[k], 0.005);
                });
            }
            ui.end_row();
        }
    });
    changed
}

/// A dragged number that stays finite.
fn number(ui: &mut egui::Ui, v: &mut f64, speed: f64) -> bool {
    let before = *v;
    let changed = ui.add(egui::DragValue::new(v).speed(speed).max_decimals(4)).changed();
    if !v.is_finite() {
        *v = before;
        return false;
    }
    changed && *v != before
}
