//! The side panel's "Flame functions" section: each `kind = "flame"` function's numbers at the
//! playhead (flam3's pre-affine coefs a b c d e f, the post-affine where it has one, each
//! variation's weight and parameters by flam3's names, the colour speed, the opacity), and the
//! final xform's (with its colour index and opacity), edited by dragging; a variation removed by its × or added from the list
//! below them. Like every `*_ui` function it only reads the state and emits
//! [`Command::SetFlame`] (or [`Command::SetFinalXform`]; [`Command::SetFlameVariations`] for a
//! variation added or removed); a drag is one undo step, keyed at the playhead on an animated
//! scene (`authoring.rs`; the final xform is not keyed). A function that a key holds keeps its
//! variations (the keys hold the numbers of its list).

use egui::RichText;

use crate::flame::{Variation, VariationTerm};
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
            let keyed = state.scene.is_keyed(function);
            let (mut changed, variations) = xform_ui(ui, function, &mut value, !keyed);
            if let Some(variations) = variations {
                commands.push(Command::SetFlameVariations { function: Some(function), variations });
            }
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
            let (mut changed, variations) = xform_ui(ui, usize::MAX, &mut value.def, true);
            if let Some(variations) = variations {
                commands.push(Command::SetFlameVariations { function: None, variations });
            }
            ui.horizontal(|ui| {
                ui.label("colour index").on_hover_text("its colour coordinate c_f (flam3's color)");
                changed |= ui.add(slider(&mut value.palette_index, 0.0..=1.0)).changed();
            });
            ui.horizontal(|ui| {
                ui.label("opacity").on_hover_text(
                    "flam3's final opacity: the chance that the final xform maps a drawn point (the others are drawn as they are)",
                );
                changed |= ui.add(slider(&mut value.def.opacity, 0.0..=1.0)).changed();
            });
            if changed && value != *f {
                commands.push(Command::SetFinalXform(value));
            }
        }
    });
}

/// One xform's coefs, post-affine, variations and colour speed; `id` tells its widgets apart.
/// Returns whether a number changed, and the xform's variations with one removed or added
/// (where `restructure` allows it).
fn xform_ui(
    ui: &mut egui::Ui,
    id: usize,
    value: &mut FlameDef,
    restructure: bool,
) -> (bool, Option<Vec<VariationTerm>>) {
    let mut changed = coefs_ui(ui, ("pre", id), "coefs", &mut value.coefs);
    if let Some(post) = &mut value.post {
        changed |= coefs_ui(ui, ("post", id), "post", post);
    }
    let mut removed = None;
    let removable = restructure && value.variations.len() > 1;
    egui::Grid::new(("flame_variations", id)).num_columns(3).spacing([6.0, 2.0]).show(ui, |ui| {
        for (i, t) in value.variations.iter_mut().enumerate() {
            ui.label(t.variation.name()).on_hover_text("this variation's weight in the sum");
            changed |= number(ui, &mut t.weight, 0.005);
            if removable && ui.small_button("×").on_hover_text("remove this variation").clicked() {
                removed = Some(i);
            }
            ui.end_row();
            for ((param, _), v) in t.variation.info().params.iter().zip(t.params.iter_mut()) {
                ui.small(format!("  {param}"));
                changed |= number(ui, v, 0.01);
                ui.end_row();
            }
        }
    });
    let mut variations = removed.map(|i| {
        let mut v = value.variations.clone();
        v.remove(i);
        v
    });
    let add = ui.add_enabled_ui(restructure, |ui| {
        let mut added = None;
        let list = egui::ComboBox::from_id_salt(("add_variation", id))
            .selected_text("add variation")
            .height(320.0)
            // A click on the search field keeps the list open; a pick closes it.
            .close_behavior(egui::PopupCloseBehavior::CloseOnClickOutside)
            .show_ui(ui, |ui| added = variation_list_ui(ui, id, &value.variations));
        if list.inner.is_none() {
            // Closed: the next opening starts with an empty search.
            ui.data_mut(|d| d.remove::<String>(variation_search_id(id)));
        }
        added
    });
    add.response.on_disabled_hover_text("keyed on the timeline: remove its keys to add or remove a variation");
    if let Some(v) = add.inner {
        let mut list = value.variations.clone();
        // Added at weight 0, so that the picture changes only as its weight is dragged up.
        list.push(VariationTerm { variation: v, weight: 0.0, params: v.default_params() });
        variations = Some(list);
    }
    ui.horizontal(|ui| {
        ui.label("colour speed").on_hover_text("s in c' = s·c_i + (1 − s)·c (flam3's color_speed)");
        changed |= ui.add(slider(&mut value.color_speed, 0.0..=1.0)).changed();
    });
    (changed, variations)
}

/// The list of the variations an xform does not use, under a search field (flam3 has 99: the
/// field has the keyboard as the list opens, and a name typed there narrows the list to the
/// names that contain it; Enter takes the first). The typed text is the list's own, in egui's
/// memory while it is open. Returns the variation picked.
fn variation_list_ui(ui: &mut egui::Ui, id: usize, used: &[VariationTerm]) -> Option<Variation> {
    let search_id = variation_search_id(id);
    let mut search: String = ui.data_mut(|d| d.get_temp(search_id)).unwrap_or_default();
    let field = ui.add(egui::TextEdit::singleline(&mut search).hint_text("search").desired_width(150.0));
    if !field.has_focus() && search.is_empty() {
        field.request_focus();
    }
    let needle = search.trim().to_lowercase();
    let mut shown =
        Variation::all().filter(|v| used.iter().all(|t| t.variation != *v) && v.name().contains(needle.as_str()));
    let mut picked = None;
    if field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
        picked = shown.next();
    }
    let mut any = picked.is_some();
    for v in shown {
        any = true;
        if ui.selectable_label(false, v.name()).clicked() {
            picked = Some(v);
        }
    }
    if !any {
        ui.weak("no variation of that name");
    }
    if picked.is_some() {
        ui.close();
    }
    ui.data_mut(|d| d.insert_temp(search_id, search));
    picked
}

/// Where the text typed over xform `id`'s variation list is kept.
fn variation_search_id(id: usize) -> egui::Id {
    egui::Id::unique(("variation_search", id))
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
