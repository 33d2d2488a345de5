//! What the viewer draws over the view rather than in the side panel: the warning banner (a
//! file that did not open or reload, with its error located; a function that may not be
//! contractive or leaves the grid; the file changed on disk while there are unsaved edits), the
//! toast (a saved file), the status line (accumulated points and
//! points per lit pixel), the shortcuts overlay (`F1`, `?`) and the dialogs: closing with
//! unsaved edits, restoring a recovery file, and starting a job on a scene that may not be
//! contractive. Like every `*_ui` file it only reads the state
//! and emits commands.

use egui::{Align2, Color32, RichText};

use super::super::command::{CloseChoice, Command, JobConfirm};
use super::super::state::ViewerState;

/// The mark in text that warns (the Statistics table): a glyph the bundled font draws. The
/// viewer's egui has no emoji font, so U+26A0 ⚠ drew as an empty box; the banner paints its
/// sign instead ([`warning_icon`]). `tests/viewer_overlays.rs` checks every text here for
/// glyphs the font lacks.
pub const WARNING_SIGN: char = '!';

/// The keys, as the shortcuts overlay and the README list them.
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("left drag", "orbit, pan in a 2D scene (a grid point with the grid overlay on: drag it)"),
    ("right / middle drag", "pan"),
    ("wheel", "zoom towards the cursor"),
    ("Ctrl+click", "focus depth of field on the point under the cursor"),
    ("F / Shift+F", "frame the attractor / the attractor and the grid box"),
    ("1 3 7 (numpad or row)", "front, side, top view; with Ctrl the opposite side"),
    ("5, P", "perspective / parallel"),
    ("X, Y, Z", "lock point drags to that axis (toggle)"),
    ("Space", "play / pause the timeline"),
    ("Ctrl+Z / Ctrl+Shift+Z, Ctrl+Y", "undo / redo"),
    ("Ctrl+O", "open a scene (or a PNG that nlifs wrote)"),
    ("Ctrl+S / Ctrl+Shift+S", "save the scene / save it as another file"),
    ("drop a file", "open a scene, or the scene inside a PNG that nlifs wrote"),
    ("Shift+A, Shift+D, Delete", "add a function; duplicate, delete the selected one"),
    ("F12", "screenshot next to the scene"),
    ("Tab", "hide / show the side panel"),
    ("F11", "full screen"),
    ("F1, ?", "this overlay"),
    ("Esc", "cancel a drag, close a dialog or this overlay (never quits)"),
    ("Ctrl+Q, close button", "quit (asks when there are unsaved edits)"),
];

const WARNING_FILL: Color32 = Color32::from_rgba_premultiplied(70, 20, 10, 220);

/// Everything over the view; `view_rect` is the part of the window the panels leave (points).
pub fn overlays_ui(ctx: &egui::Context, view_rect: egui::Rect, state: &ViewerState, commands: &mut Vec<Command>) {
    banner_ui(ctx, view_rect, state, commands);
    toast_ui(ctx, view_rect, state);
    status_ui(ctx, view_rect, state);
    if state.ui.shortcuts_shown {
        shortcuts_overlay_ui(ctx, commands);
    }
    if let Some(confirm) = &state.ui.job_confirm {
        job_confirm_ui(ctx, confirm, commands);
    } else if state.ui.close_dialog {
        close_dialog_ui(ctx, state, commands);
    } else if state.recovery_offer.is_some() {
        recovery_dialog_ui(ctx, state, commands);
    }
}

/// The warnings at the top of the view, where the eye is while editing.
fn banner_ui(ctx: &egui::Context, view_rect: egui::Rect, state: &ViewerState, commands: &mut Vec<Command>) {
    let warnings = state.warnings();
    let changed = state.ui.file_changed_on_disk;
    let error = state.files.view_error.as_deref();
    if warnings.is_empty() && !changed && error.is_none() {
        return;
    }
    egui::Area::new(egui::Id::unique("nlifs_banner"))
        .order(egui::Order::Foreground)
        .fixed_pos(view_rect.left_top() + egui::vec2(8.0, 8.0))
        .show(ctx, |ui| {
            ui.set_max_width((view_rect.width() - 16.0).max(100.0));
            egui::Frame::new().fill(WARNING_FILL).corner_radius(4.0).inner_margin(6.0).show(ui, |ui| {
                if let Some(error) = error {
                    ui.horizontal(|ui| {
                        warning_icon(ui);
                        // The button first: a long error wraps in what is left of the line.
                        if ui.small_button("×").on_hover_text("dismiss (Esc); the scene shown is kept").clicked() {
                            commands.push(Command::DismissViewError);
                        }
                        ui.add(
                            egui::Label::new(RichText::new(error).color(Color32::from_rgb(255, 140, 120)).strong())
                                .wrap(),
                        );
                    });
                }
                for line in &warnings {
                    ui.horizontal(|ui| {
                        warning_icon(ui);
                        ui.label(RichText::new(line).color(Color32::from_rgb(255, 200, 170)));
                    });
                }
                if changed {
                    ui.horizontal(|ui| {
                        warning_icon(ui);
                        ui.label(
                            RichText::new("the scene file changed on disk; your unsaved edits are kept")
                                .color(Color32::from_rgb(255, 200, 170)),
                        );
                        if ui.button("Reload (discard edits)").clicked() {
                            commands.push(Command::ReloadScene);
                        }
                    });
                }
            });
        });
}

/// A warning sign painted as shapes (an amber triangle with a dark `!`), so that it never
/// depends on a font having U+26A0.
pub fn warning_icon(ui: &mut egui::Ui) {
    let size = ui.text_style_height(&egui::TextStyle::Body);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(size * 1.1, size), egui::Sense::hover());
    let p = ui.painter();
    p.add(egui::Shape::convex_polygon(
        vec![rect.center_top(), rect.right_bottom(), rect.left_bottom()],
        Color32::from_rgb(255, 190, 60),
        egui::Stroke::NONE,
    ));
    p.text(
        rect.center_bottom() - egui::vec2(0.0, 0.5),
        Align2::CENTER_BOTTOM,
        "!",
        egui::FontId::proportional(size * 0.75),
        Color32::from_rgb(40, 20, 0),
    );
}

/// A short notice at the bottom of the view.
fn toast_ui(ctx: &egui::Context, view_rect: egui::Rect, state: &ViewerState) {
    let Some(text) = &state.ui.toast else { return };
    egui::Area::new(egui::Id::unique("nlifs_toast"))
        .order(egui::Order::Foreground)
        .interactable(false)
        .pivot(Align2::CENTER_BOTTOM)
        .fixed_pos(view_rect.center_bottom() - egui::vec2(0.0, 36.0))
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                ui.label(text.as_str());
            });
        });
}

/// How converged the picture is, at the bottom left of the view.
fn status_ui(ctx: &egui::Context, view_rect: egui::Rect, state: &ViewerState) {
    let s = &state.stats;
    if s.frames == 0 {
        return;
    }
    let per_pixel =
        if s.lit_pixels > 0 { format!("{:.0} points per lit pixel", s.points_per_lit_pixel()) } else { String::new() };
    egui::Area::new(egui::Id::unique("nlifs_status"))
        .order(egui::Order::Middle)
        .interactable(false)
        .pivot(Align2::LEFT_BOTTOM)
        .fixed_pos(view_rect.left_bottom() + egui::vec2(8.0, -6.0))
        .show(ctx, |ui| {
            ui.add(
                egui::Label::new(
                    RichText::new(format!("{} points accumulated   {per_pixel}", group_thousands(s.accumulated)))
                        .small()
                        .color(Color32::from_gray(190)),
                )
                .extend(),
            );
        });
}

/// `1234567` as `1 234 567`.
fn group_thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

fn shortcuts_overlay_ui(ctx: &egui::Context, commands: &mut Vec<Command>) {
    let mut open = true;
    egui::Window::new("Keys and mouse")
        .id(egui::Id::unique("nlifs_shortcuts"))
        .collapsible(false)
        .resizable(false)
        .anchor(Align2::CENTER_CENTER, egui::vec2(0.0, 0.0))
        .open(&mut open)
        .show(ctx, |ui| {
            egui::Grid::new("nlifs_shortcuts_grid").striped(true).show(ui, |ui| {
                for (key, action) in SHORTCUTS {
                    ui.label(RichText::new(*key).strong());
                    ui.label(*action);
                    ui.end_row();
                }
            });
        });
    if !open {
        commands.push(Command::SetShortcutsShown(false));
    }
}

fn close_dialog_ui(ctx: &egui::Context, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::Modal::new(egui::Id::unique("nlifs_close_dialog")).show(ctx, |ui| {
        ui.heading("Unsaved changes");
        let before = match &state.ui.pending_open {
            Some(open) => format!("opening {}", open.name()),
            None => "closing".into(),
        };
        ui.label(format!("{} has unsaved edits. Save them before {before}?", state.scene.name));
        ui.small(format!("Save writes {}", state.edit.save_text.trim()));
        if let Some(e) = &state.error {
            ui.colored_label(Color32::from_rgb(255, 110, 90), e);
        }
        ui.horizontal(|ui| {
            if ui.button("Save").clicked() {
                commands.push(Command::CloseDialog(CloseChoice::Save));
            }
            if ui.button("Discard").clicked() {
                commands.push(Command::CloseDialog(CloseChoice::Discard));
            }
            if ui.button("Cancel").clicked() {
                commands.push(Command::CloseDialog(CloseChoice::Cancel));
            }
        });
    });
}

/// "Function f2 may not be contractive (bound 1.250). Ray-trace anyway?"
fn job_confirm_ui(ctx: &egui::Context, confirm: &JobConfirm, commands: &mut Vec<Command>) {
    egui::Modal::new(egui::Id::unique("nlifs_job_confirm")).show(ctx, |ui| {
        ui.heading("May not be contractive");
        ui.label(&confirm.question);
        ui.small("The attractor may not exist: the picture can come out as flat colour fields.");
        ui.horizontal(|ui| {
            if ui.button("Continue").clicked() {
                commands.push(Command::ConfirmJob(true));
            }
            if ui.button("Cancel").clicked() {
                commands.push(Command::ConfirmJob(false));
            }
        });
    });
}

fn recovery_dialog_ui(ctx: &egui::Context, state: &ViewerState, commands: &mut Vec<Command>) {
    let Some(offer) = &state.recovery_offer else { return };
    let age = offer.written.elapsed().map_or("earlier".into(), |d| format!("{} s ago", d.as_secs()));
    egui::Modal::new(egui::Id::unique("nlifs_recovery_dialog")).show(ctx, |ui| {
        ui.heading("Restore unsaved edits?");
        ui.label(format!(
            "{} was not saved when the viewer last stopped; its edits were kept ({age}).",
            state.scene.name
        ));
        ui.horizontal(|ui| {
            if ui.button("Restore").clicked() {
                commands.push(Command::Recover(true));
            }
            if ui.button("Discard").clicked() {
                commands.push(Command::Recover(false));
            }
        });
    });
}
