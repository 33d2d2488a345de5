//! The palette-colour controls (`[render] color = "palette"`, `src/palette.rs`): in the Render
//! section the colour menu (function / palette) and the palette picker, in each function's row
//! of the Functions section its colour coordinate c_i (shown in palette colour only). Like every
//! `*_ui` function they only read the state and emit commands; `palette_edit.rs` applies them.

use crate::palette::{self, BUILTIN};
use crate::scene::spec::ColorMode;

use super::super::command::Command;
use super::super::state::ViewerState;
use super::widgets::slider;

/// What the colour coordinate is, shown when the pointer rests on a control.
const COLOR_HELP: &str = "palette colour: every function has a colour coordinate c_i in 0..1; \
    each point carries c, which becomes (c + c_i) / 2 at every step, and is drawn with the \
    palette's colour at c. Function colour: each point takes its function's colour.";

/// The colour menu and, in palette colour, the palette picker.
pub fn color_mode_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let render = &state.scene.render;
    let mut mode = render.color;
    egui::ComboBox::from_label("colour").selected_text(mode.name()).show_ui(ui, |ui| {
        for m in [ColorMode::Function, ColorMode::Palette] {
            if ui.selectable_value(&mut mode, m, m.name()).on_hover_text(COLOR_HELP).changed() {
                commands.push(Command::SetColorMode(m));
            }
        }
    });
    if mode != ColorMode::Palette {
        return;
    }
    let current = render.palette.as_ref().map_or(palette::DEFAULT, |p| p.source.as_str());
    egui::ComboBox::from_label("palette")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for (name, _) in BUILTIN {
                if ui.selectable_label(current == *name, *name).clicked() && current != *name {
                    commands.push(Command::SetPalette(name.to_string()));
                }
            }
        })
        .response
        .on_hover_text("a built-in palette; an image strip is set with `palette = \"FILE\"` in the scene");
}

/// Function `function`'s colour coordinate c_i (palette colour only; a cell of the functions
/// grid).
pub fn palette_index_ui(ui: &mut egui::Ui, state: &ViewerState, function: usize, commands: &mut Vec<Command>) {
    if state.scene.render.color != ColorMode::Palette {
        return;
    }
    let n = state.scene.functions.len();
    let Some(f) = state.scene.functions.get(function) else { return };
    let mut c = f.palette_index.unwrap_or(palette::default_index(function, n));
    if ui.add(slider(&mut c, 0.0..=1.0).text("c")).on_hover_text(COLOR_HELP).changed() {
        commands.push(Command::SetPaletteIndex { function, index: Some(c) });
    }
}
