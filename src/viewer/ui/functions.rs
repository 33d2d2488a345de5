//! The side panel's authoring sections: "Functions" (each function on or off, its colour, its
//! probability, its kind; add, duplicate, delete; the scene's probability mode) and "Builder"
//! (each builder function's steps with their parameters, added, removed and reordered). Like
//! every `*_ui` function they only read the state and emit commands; `authoring.rs` applies them.

use egui::RichText;

use crate::edit::FunctionKind;
use crate::model::ProbabilityMode;
use crate::model::builder::{Step, StepKind};
use crate::scene::spec::FunctionDef;

use super::super::command::Command;
use super::super::state::ViewerState;
use super::widgets::slider;

// Here and not in `viewer/mod.rs`, which is at its length limit.

/// What the "p" of a function means here, shown when the pointer rests on it. (Only glyphs
/// that the bundled font draws: it has Σ and ≈ but no arrows and no ∝.)
pub const PROBABILITY_HELP: &str = "p: how often the chaos game applies this function.\n\
    Only ratios matter: the weights are normalized to shares that sum to 1 over the enabled \
    functions (the share is shown after the weight).\n\
    Automatic (the default): the shares follow from how much each function shrinks, \
    p proportional to s^D, with s its mean linear scale and D the similarity dimension (Σ s^D = 1); no function \
    gets less than a tenth of an equal share, so thin parts still fill. Adaptive: the same rule \
    with the scale at each point.\n\
    Changing a p makes the probabilities explicit, every other function keeping its current \
    share as its weight; choose an automatic mode (or \"auto\") to go back.";

const MODES: [(ProbabilityMode, &str); 3] = [
    (ProbabilityMode::Contractivity, "automatic (from contraction)"),
    (ProbabilityMode::Adaptive, "automatic, adaptive (per point)"),
    (ProbabilityMode::Explicit, "explicit weights"),
];

pub fn functions_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Functions").default_open(true).show(ui, |ui| {
        probability_mode_ui(ui, state, commands);
        let shares: Vec<f64> =
            state.report.as_ref().map(|r| r.functions.iter().map(|f| f.probability).collect()).unwrap_or_default();
        let explicit = state.scene.probability_mode == ProbabilityMode::Explicit;
        // A grid, so that the columns line up whatever the names' lengths.
        egui::Grid::new("functions").num_columns(5).spacing([6.0, 4.0]).show(ui, |ui| {
            for (i, f) in state.scene.functions.iter().enumerate() {
                let mut enabled = f.enabled;
                if ui
                    .checkbox(&mut enabled, &f.name)
                    .on_hover_text("draw this function (untick to leave it out)")
                    .changed()
                {
                    commands.push(Command::SetFunctionEnabled { function: i, enabled });
                }
                let mut color = f.color;
                if ui.color_edit_button_rgb(&mut color).on_hover_text("colour: click to pick").changed() {
                    commands.push(Command::SetFunctionColor { function: i, color });
                }
                let share = shares.get(i).copied().unwrap_or(0.0);
                ui.horizontal(|ui| {
                    // Explicit: the weight, then its share; automatic: the share, which a drag
                    // turns into a weight.
                    let mut p = if explicit { f.probability.unwrap_or(0.0) } else { share };
                    let drag = ui
                        .add(egui::DragValue::new(&mut p).speed(0.005).range(0.0..=1e6).max_decimals(3).prefix("p "))
                        .on_hover_text(PROBABILITY_HELP);
                    if drag.changed() && p.is_finite() {
                        commands.push(Command::SetFunctionProbability { function: i, probability: Some(p) });
                    }
                    if explicit {
                        ui.small(format!("{:.0} %", 100.0 * share)).on_hover_text(PROBABILITY_HELP);
                    }
                });
                kind_ui(ui, i, &f.def, commands);
                ui.horizontal(|ui| {
                    if ui.small_button("copy").on_hover_text("duplicate (Shift+D with it selected)").clicked() {
                        commands.push(Command::DuplicateFunction(i));
                    }
                    let deletable = state.scene.functions.len() > 1;
                    if ui
                        .add_enabled(deletable, egui::Button::new("×").small())
                        .on_hover_text("delete (Delete with it selected)")
                        .clicked()
                    {
                        commands.push(Command::DeleteFunction(i));
                    }
                });
                super::palette::palette_index_ui(ui, state, i, commands);
                ui.end_row();
            }
        });
        if ui.button("Add function").on_hover_text("an affine map halving the grid (Shift+A)").clicked() {
            commands.push(Command::AddFunction);
        }
        xaos_ui(ui, state, commands);
    });
}

const XAOS_HELP: &str = "Xaos (flam3's chaos): the row of a function multiplies the probabilities of the next \
function drawn after it (0: never next, 1: as usual). A row of all 0 is as if all 1.";

/// The most functions whose xaos table the panel shows.
const MAX_XAOS_TABLE: usize = 16;

/// The xaos table: row i, column j is function i's multiplier of function j coming next.
fn xaos_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let functions = &state.scene.functions;
    let open = functions.iter().any(|f| !f.xaos.is_empty());
    egui::CollapsingHeader::new("Xaos (which function comes next)").default_open(open).show(ui, |ui| {
        if state.scene.probability_mode == ProbabilityMode::Adaptive {
            ui.small("Adaptive probabilities draw by the point's place; choose another mode for xaos.");
            return;
        }
        if functions.len() > MAX_XAOS_TABLE {
            // n² fields would take the panel (and every frame of it) over.
            ui.small(format!(
                "{} functions: the table is shown up to {MAX_XAOS_TABLE}; edit the rows (`xaos`) in the scene file.",
                functions.len()
            ));
            return;
        }
        egui::Grid::new("xaos").spacing([4.0, 2.0]).show(ui, |ui| {
            ui.small("after \\ next").on_hover_text(XAOS_HELP);
            for f in functions {
                ui.small(&f.name);
            }
            ui.end_row();
            for (i, f) in functions.iter().enumerate() {
                ui.small(&f.name);
                for j in 0..functions.len() {
                    let mut v = f.xaos.get(j).copied().unwrap_or(1.0);
                    let drag = ui
                        .add(egui::DragValue::new(&mut v).speed(0.01).range(0.0..=1e3).max_decimals(3))
                        .on_hover_text(XAOS_HELP);
                    if drag.changed() && v.is_finite() {
                        commands.push(Command::SetFunctionXaos { function: i, to: j, value: v.max(0.0) });
                    }
                }
                ui.end_row();
            }
            // What the rows make of the probabilities: each function's share of the points.
            if let Some(report) = state.report.as_ref().filter(|r| r.xaos) {
                ui.small("share").on_hover_text("each function's share of the points in the long run");
                for f in &report.functions {
                    ui.small(format!("{:.0} %", 100.0 * f.share));
                }
                ui.end_row();
            }
        });
    });
}

/// The scene's probability mode, with a one-click way back to automatic.
fn probability_mode_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let current = state.scene.probability_mode;
    let label = |m: ProbabilityMode| MODES.iter().find(|(mode, _)| *mode == m).map_or("", |(_, l)| *l);
    ui.horizontal(|ui| {
        let mut mode = current;
        ui.label("p:").on_hover_text(PROBABILITY_HELP);
        egui::ComboBox::from_id_salt("probability_mode").selected_text(label(current)).show_ui(ui, |ui| {
            for (m, text) in MODES {
                ui.selectable_value(&mut mode, m, text);
            }
        });
        if current == ProbabilityMode::Explicit
            && ui.small_button("auto").on_hover_text("back to automatic probabilities (clears the weights)").clicked()
        {
            mode = ProbabilityMode::Contractivity;
        }
        if mode != current {
            commands.push(Command::SetProbabilityMode(mode));
        }
    });
}

/// The function's kind, changeable between grid, builder and affine; each choice says how the
/// map is kept.
fn kind_ui(ui: &mut egui::Ui, function: usize, def: &FunctionDef, commands: &mut Vec<Command>) {
    let Some(current) = FunctionKind::of(def) else {
        // Julia and flame maps have no exact grid, builder or affine form: the kind is shown,
        // not offered for change.
        ui.small(def.kind()).on_hover_text(format!("a {} map has no grid, builder or affine form", def.kind()));
        return;
    };
    let mut kind = current;
    egui::ComboBox::from_id_salt(("function_kind", function)).width(64.0).selected_text(current.name()).show_ui(
        ui,
        |ui| {
            for k in FunctionKind::ALL {
                // Only an affine map converts exactly whatever it is; the others say how.
                let text = match (current, k) {
                    (c, k) if c == k || c == FunctionKind::Affine => k.name().to_string(),
                    (FunctionKind::Builder, FunctionKind::Grid) => "grid (sampled)".into(),
                    _ => format!("{} (fit)", k.name()),
                };
                ui.selectable_value(&mut kind, k, text).on_hover_text(current.conversion_note(k));
            }
        },
    );
    if kind != current {
        commands.push(Command::SetFunctionKind { function, kind });
    }
}

/// Every builder function's steps: each step's parameters (applied live, keyed at the playhead
/// on an animated scene), moved up or down, removed; steps added from a menu.
pub fn builder_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let builders: Vec<_> = state
        .scene
        .functions
        .iter()
        .enumerate()
        .filter_map(|(i, f)| match state.scene.function_def_at(i, state.t_secs) {
            FunctionDef::Builder { builder, .. } => Some((i, &f.name, builder)),
            _ => None,
        })
        .collect();
    if builders.is_empty() {
        return;
    }
    egui::CollapsingHeader::new("Builder steps").default_open(true).show(ui, |ui| {
        for (function, name, builder) in builders {
            ui.label(RichText::new(name.as_str()).strong());
            let count = builder.steps.len();
            for (k, step) in builder.steps.iter().enumerate() {
                ui.horizontal(|ui| {
                    ui.label(format!("{}. {}", k + 1, step_title(step)));
                    if ui.add_enabled(k > 0, egui::Button::new("up").small()).on_hover_text("move up").clicked() {
                        commands.push(Command::MoveBuilderStep { function, from: k, to: k - 1 });
                    }
                    if ui
                        .add_enabled(k + 1 < count, egui::Button::new("down").small())
                        .on_hover_text("move down")
                        .clicked()
                    {
                        commands.push(Command::MoveBuilderStep { function, from: k, to: k + 1 });
                    }
                    if ui.small_button("×").on_hover_text("remove this step").clicked() {
                        commands.push(Command::RemoveBuilderStep { function, step: k });
                    }
                });
                let mut value = step.clone();
                if step_params_ui(ui, state, &mut value) {
                    commands.push(Command::SetBuilderStep { function, step: k, value });
                }
            }
            ui.menu_button("Add step", |ui| add_step_menu_ui(ui, state, function, count, commands));
            ui.separator();
        }
    });
}

/// The kinds of step, each with its axes where it has a choice; the step goes last and
/// changes nothing until its numbers are set.
fn add_step_menu_ui(
    ui: &mut egui::Ui,
    state: &ViewerState,
    function: usize,
    index: usize,
    commands: &mut Vec<Command>,
) {
    let dim = state.scene.domain.dimension();
    let (lo, hi) = (state.scene.domain.min(), state.scene.domain.max());
    let mut add = |step: Step| commands.push(Command::InsertBuilderStep { function, index, step });
    for kind in StepKind::ALL {
        let identity = Step::identity(kind, dim, lo, hi);
        let choices = Step::axis_choices(kind, dim);
        if choices.len() <= 1 {
            if ui.button(kind.name()).on_hover_text("added last; it changes nothing until you set it").clicked() {
                add(identity);
            }
            continue;
        }
        ui.menu_button(kind.name(), |ui| {
            for axes in choices {
                let step = identity.clone().with_axes(axes, lo, hi);
                if ui.button(step_title(&step)).clicked() {
                    add(step);
                }
            }
        });
    }
}

/// "twist about y", "scale", …: the step's op and axes.
fn step_title(step: &Step) -> String {
    match step {
        Step::Rotate { axis, .. } => format!("rotate about {}", axis.name()),
        Step::Taper { axis, .. } => format!("taper along {}", axis.name()),
        Step::Twist { axis, along, .. } if axis == along => format!("twist about {}", axis.name()),
        Step::Twist { along, .. } => format!("twist along {}", along.name()),
        Step::Bend { axis, toward, .. } => format!("bend {} towards {}", axis.name(), toward.name()),
        _ => step.kind().name().to_string(),
    }
}

/// The step's parameters as sliders (a matrix of number fields for an affine step); true if
/// the user changed one.
fn step_params_ui(ui: &mut egui::Ui, state: &ViewerState, value: &mut Step) -> bool {
    let dim = state.scene.domain.dimension();
    let names = ["x", "y", "z"];
    match value {
        Step::Taper { amount, .. } => ui.add(slider(amount, -1.0..=1.0).text("amount")).changed(),
        Step::Twist { degrees, .. } => ui.add(slider(degrees, -360.0..=360.0).text("degrees")).changed(),
        Step::Bend { degrees, .. } => ui.add(slider(degrees, -180.0..=180.0).text("degrees")).changed(),
        Step::Rotate { degrees, .. } => ui.add(slider(degrees, -180.0..=180.0).text("degrees")).changed(),
        Step::Scale { by, .. } => {
            let mut c = false;
            for a in 0..dim {
                c |= ui.add(slider(&mut by[a], 0.0..=1.5).text(format!("scale {}", names[a]))).changed();
            }
            c
        }
        Step::Translate { by } => {
            let mut c = false;
            for a in 0..dim {
                let r = 2.0 * (state.scene.domain.max() - state.scene.domain.min())[a].abs().max(1.0);
                c |= ui.add(slider(&mut by[a], -r..=r).text(format!("move {}", names[a]))).changed();
            }
            c
        }
        Step::Affine { matrix, offset } => {
            let mut c = false;
            let extent = (state.scene.domain.max() - state.scene.domain.min()).max_element().max(1e-9);
            egui::Grid::new(ui.next_auto_id())
                .show(ui, |ui| {
                    for r in 0..dim {
                        for col in 0..dim {
                            let entry = &mut matrix.col_mut(col)[r];
                            c |= ui.add(egui::DragValue::new(entry).speed(0.005).max_decimals(4)).changed();
                        }
                        ui.label("+");
                        c |=
                            ui.add(egui::DragValue::new(&mut offset[r]).speed(extent * 2e-3).max_decimals(4)).changed();
                        ui.end_row();
                    }
                })
                .response
                .on_hover_text("p' = matrix · p + offset, rows as in the scene file");
            c
        }
    }
}
