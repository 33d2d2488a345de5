//! The viewer's egui panels. Each `*_ui` function reads the [`ViewerState`] and pushes
//! [`Command`]s; none of them changes the state directly. This file lays out the side panel
//! and holds its small sections (scene, render, statistics, screenshot); a section or overlay
//! with more to it has a file of its own here, and `layer.rs` draws egui on wgpu.

use egui::Color32;

use crate::camera::Projection;
use crate::live::ChaosBackend;
use crate::scene::spec::SplatMode;

use super::command::{Command, FileDialogKind};
use super::jobs::JobView;
use super::state::ViewerState;
use widgets::slider;

pub mod flame;
pub mod functions;
pub mod grid_edit;
pub mod jobs;
pub mod layer;
pub mod lens;
pub mod light;
pub mod nesting;
pub mod overlay;
pub mod palette;
pub mod timeline;
pub mod tone;
pub mod widgets;

/// The left side panel with every section, the timeline at the bottom, the grid overlay, the
/// ray-traced image window and the keyboard shortcuts. `ppp`: pixels per egui point. Returns
/// where the panels are (egui points).
pub fn panels_ui(
    ui: &mut egui::Ui,
    state: &ViewerState,
    jobs: &JobView,
    ppp: f32,
    commands: &mut Vec<Command>,
) -> PanelLayout {
    shortcuts_ui(ui.ctx(), state, commands);
    let timeline = state.scene.timeline.is_some().then(|| {
        egui::Panel::bottom("nlifs_timeline")
            .resizable(false)
            .show(ui, |ui| timeline::timeline_ui(ui, state, commands))
            .response
            .rect
    });
    // Tab hides the panel; it resizes by its right edge, and scrolls when its open sections
    // do not fit the window.
    let mut shown = state.ui.panel_shown;
    egui::Panel::left("nlifs_panel").default_size(310.0).resizable(true).show_collapsible(ui, &mut shown, |ui| {
        egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.heading("nlifs");
                file_menu_ui(ui, state, commands);
            });
            scene_ui(ui, state, commands);
            functions::functions_ui(ui, state, commands);
            grid_edit::grid_edit_ui(ui, state, commands);
            nesting::nesting_ui(ui, state, commands);
            functions::builder_ui(ui, state, commands);
            flame::flame_ui(ui, state, commands);
            render_ui(ui, state, commands);
            statistics_ui(ui, state);
            screenshot_ui(ui, state, commands);
            if crate::platform::DESKTOP {
                jobs::raytrace_ui(ui, state, jobs, commands);
                if state.scene.timeline.is_some() {
                    jobs::record_ui(ui, state, jobs, commands);
                }
            } else {
                jobs::desktop_only_ui(ui, state.scene.timeline.is_some());
            }
        });
    });
    if shown != state.ui.panel_shown {
        commands.push(Command::SetPanelShown(shown));
    }
    // The overlay is clipped to what the panels leave of the view.
    let view_rect = ui.available_rect_before_wrap();
    grid_edit::grid_overlay_ui(ui.ctx(), view_rect, state, ppp);
    nesting::nesting_overlay_ui(ui.ctx(), view_rect, state, ppp);
    jobs::raytrace_window_ui(ui.ctx(), jobs, commands);
    overlay::overlays_ui(ui.ctx(), view_rect, state, commands);
    PanelLayout { view: view_rect, timeline }
}

/// Where [`panels_ui`] put things, in egui points.
#[derive(Clone, Copy, Debug)]
pub struct PanelLayout {
    /// What the panels leave to the view of the attractor.
    pub view: egui::Rect,
    /// The timeline strip at the bottom, when the scene has a timeline (it changes every frame
    /// while playing: `ui/layer.rs` renders it apart from the other panels).
    pub timeline: Option<egui::Rect>,
}

/// Undo (Ctrl+Z), redo (Ctrl+Shift+Z, Ctrl+Y), open (Ctrl+O), save (Ctrl+S), save as
/// (Ctrl+Shift+S), axis lock (X, Y, Z), play/pause (Space); not while a text field has the
/// keyboard (it has its own undo). The window's keys are in `input.rs`.
fn shortcuts_ui(ctx: &egui::Context, state: &ViewerState, commands: &mut Vec<Command>) {
    if ctx.egui_wants_keyboard_input() {
        return;
    }
    use egui::{Key, KeyboardShortcut, Modifiers};
    ctx.input_mut(|i| {
        if i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z))
            || i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND, Key::Y))
        {
            commands.push(Command::Redo);
        }
        if i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND, Key::Z)) {
            commands.push(Command::Undo);
        }
        if i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::S)) {
            commands.push(Command::ShowFileDialog(FileDialogKind::SaveAs));
        }
        if i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND, Key::S)) {
            commands.push(Command::Save);
        }
        if i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND, Key::O)) {
            commands.push(Command::ShowFileDialog(FileDialogKind::Open));
        }
        if i.modifiers.is_none() {
            for (key, axis) in [(Key::X, 0), (Key::Y, 1), (Key::Z, 2)] {
                if i.key_pressed(key) {
                    let lock = if state.edit.axis_lock == Some(axis) { None } else { Some(axis) };
                    commands.push(Command::SetAxisLock(lock));
                }
            }
            if i.key_pressed(Key::Space) && state.scene.timeline.is_some() {
                commands.push(Command::SetPlaying(!state.playback.playing));
            }
        }
    });
    // A gesture ends when nothing holds it any more (no button down, no widget focused):
    // covers sliders, number fields and drags that ended outside the window.
    if state.edit.gesture.is_some() && !ctx.input(|i| i.pointer.any_down()) && ctx.memory(|m| m.focused().is_none()) {
        commands.push(Command::EndGesture);
    }
}

/// The File menu: open, the recent files, save, save as, quit.
fn file_menu_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    ui.menu_button("File", |ui| {
        if ui.add(egui::Button::new("Open…").shortcut_text("Ctrl+O")).clicked() {
            commands.push(Command::ShowFileDialog(FileDialogKind::Open));
        }
        ui.menu_button("Open recent", |ui| {
            if state.files.recent.paths.is_empty() {
                ui.add_enabled(false, egui::Button::new("no recent files"));
            }
            for path in &state.files.recent.paths {
                let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
                if ui.button(name).on_hover_text(path.display().to_string()).clicked() {
                    commands.push(Command::OpenFile(path.clone()));
                }
            }
        });
        ui.separator();
        let save = ui.add(egui::Button::new("Save").shortcut_text("Ctrl+S"));
        if save.on_hover_text(format!("writes {}", state.edit.save_text.trim())).clicked() {
            commands.push(Command::Save);
        }
        if ui.add(egui::Button::new("Save as…").shortcut_text("Ctrl+Shift+S")).clicked() {
            commands.push(Command::ShowFileDialog(FileDialogKind::SaveAs));
        }
        ui.separator();
        if ui.add(egui::Button::new("Quit").shortcut_text("Ctrl+Q")).clicked() {
            commands.push(Command::RequestClose);
        }
    });
}

fn scene_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Scene").default_open(true).show(ui, |ui| {
        ui.label(format!(
            "{} — {}",
            state.scene.name,
            match (&state.scene_path, &state.files.opened_name) {
                (Some(path), _) => path.display().to_string(),
                (None, Some(name)) => name.clone(),
                (None, None) => "built in".into(),
            }
        ));
        if crate::platform::DESKTOP {
            let mut text = state.path_text.clone();
            ui.horizontal(|ui| {
                let edit = ui.text_edit_singleline(&mut text);
                if edit.changed() {
                    commands.push(Command::SetPathText(text.clone()));
                }
                let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                if ui.button("Open").on_hover_text("opens the path typed here (none: the file dialog)").clicked()
                    || enter
                {
                    commands.push(Command::OpenScene(text.trim().into()));
                }
            });
        } else if ui.button("Open…").on_hover_text("a scene (.toml) or a PNG that nlifs wrote").clicked() {
            // The browser opens files from its file chooser, never by path.
            commands.push(Command::ShowFileDialog(FileDialogKind::Open));
        }
        let mut save_text = state.edit.save_text.clone();
        ui.horizontal(|ui| {
            if ui.text_edit_singleline(&mut save_text).changed() {
                commands.push(Command::SetSaveText(save_text.clone()));
            }
            if ui.button("Save as").on_hover_text("save the scene to this file; it becomes the scene's file").clicked()
            {
                commands.push(Command::SaveScene(save_text.trim().into()));
            }
        });
        ui.small(if crate::platform::DESKTOP {
            "…or drop a .toml or .flame file, or a PNG that nlifs wrote, onto the window. The file is reloaded when it \
             changes."
        } else {
            "…or drop a .toml file, or a PNG that nlifs wrote, onto the page. Save as downloads the scene under \
             this name."
        });
        if let Some(e) = &state.error {
            ui.colored_label(Color32::from_rgb(255, 110, 90), format!("error: {e}"));
        }
        if let Some(m) = &state.message {
            ui.small(m);
        }
    });
}

fn render_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Render").default_open(true).show(ui, |ui| {
        // Only a widget the user changed sends the settings: comparing them with the state
        // sent them every frame where a widget cannot show the value exactly (a point count
        // that is no power of two, a background colour that does not survive the colour
        // button's 8-bit round trip), and that cleared the accumulation every frame.
        let mut live = state.live;
        let mut changed = false;
        let mut log2_points = (live.draw.point_count as f32).log2().round() as u32;
        if ui.add(slider(&mut log2_points, 12..=24).text("points (log2)")).changed() {
            live.draw.point_count = 1 << log2_points;
            changed = true;
        }
        changed |= ui.add(slider(&mut live.draw.steps_per_frame, 1..=64).text("steps / frame")).changed();
        egui::ComboBox::from_label("splat").selected_text(live.draw.mode.name()).show_ui(ui, |ui| {
            for mode in SplatMode::ALL {
                changed |= ui.selectable_value(&mut live.draw.mode, mode, mode.name()).changed();
            }
        });
        egui::ComboBox::from_label("chaos game backend").selected_text(live.chaos_backend.name()).show_ui(ui, |ui| {
            for backend in ChaosBackend::ALL {
                changed |= ui.selectable_value(&mut live.chaos_backend, backend, backend.name()).changed();
            }
        });
        changed |= ui.add(slider(&mut live.draw.depth_cue, 0.0..=1.0).text("depth cue")).changed();
        changed |= ui.add(slider(&mut live.draw.point_radius_px, 0..=3).text("point size (radius px)")).changed();
        changed |= ui.add(slider(&mut live.draw.shading, 0.0..=1.0).text("shading (closest)")).changed();
        changed |= ui.add(slider(&mut live.draw.occlusion, 0.0..=1.0).text("occlusion (closest)")).changed();
        lens::lens_ui(ui, state, commands);
        changed |= light::light_ui(ui, &mut live);
        ui.horizontal(|ui| {
            changed |= ui.color_edit_button_rgb(&mut live.draw.background).changed();
            ui.label("background");
        });
        if changed && live != state.live {
            commands.push(Command::SetLiveSettings(live));
        }
        tone::imaging_ui(ui, state, commands);
        let mut perspective = state.camera.projection == Projection::Perspective;
        ui.horizontal(|ui| {
            if ui.checkbox(&mut perspective, "perspective (P)").changed() {
                commands.push(Command::SetProjection(if perspective {
                    Projection::Perspective
                } else {
                    Projection::Parallel
                }));
            }
            if ui.button("Frame (F)").clicked() {
                commands.push(Command::FrameAttractor);
            }
        });
        ui.horizontal(|ui| {
            if ui
                .button("Save view")
                .on_hover_text("make this view the scene's camera (saved with the scene)")
                .clicked()
            {
                commands.push(Command::SaveView);
            }
            let keyed = ui
                .add_enabled(state.scene.timeline.is_some(), egui::Button::new("Key camera"))
                .on_hover_text("key this view's camera at the playhead")
                .on_disabled_hover_text("the scene has no timeline (add a key first)");
            if keyed.clicked() {
                commands.push(Command::KeyCamera);
            }
        });
        palette::color_mode_ui(ui, state, commands);
        ui.small("left-drag: orbit (pan in 2D) · right/middle-drag: pan · wheel: zoom · F1: every key");
    });
}

fn statistics_ui(ui: &mut egui::Ui, state: &ViewerState) {
    egui::CollapsingHeader::new("Statistics").default_open(true).show(ui, |ui| {
        let s = &state.stats;
        ui.label(format!("frame {:.1} ms ({:.0} fps)", 1e3 * s.frame_secs, 1.0 / s.frame_secs.max(1e-6)));
        ui.label(format!("{:.1} M points/s", s.points_per_sec / 1e6));
        ui.label(format!("chaos game on the {} ({})", s.chaos_route.name(), s.chaos_route.reason));
        let Some(report) = &state.report else { return };
        egui::Grid::new("report").striped(true).show(ui, |ui| {
            ui.label("function");
            ui.label("Lipschitz");
            ui.label("contained");
            ui.end_row();
            for f in &report.functions {
                ui.label(&f.name);
                match f.lipschitz_bound {
                    Some(l) if l >= 1.0 => {
                        ui.colored_label(Color32::from_rgb(255, 110, 90), format!("{l:.3} {}", overlay::WARNING_SIGN))
                    }
                    Some(l) => ui.label(format!("{l:.3}")),
                    None => ui.label("—"),
                };
                match f.contained {
                    Some(false) => ui.colored_label(Color32::from_rgb(255, 180, 80), "no"),
                    Some(true) => ui.label("yes"),
                    None => ui.label("n/a"),
                };
                ui.end_row();
            }
        });
        for f in &report.functions {
            if let Some(l) = f.lipschitz_bound
                && l >= 1.0
            {
                ui.colored_label(
                    Color32::from_rgb(255, 110, 90),
                    format!("warning: {} may not be contractive (bound {l:.3} ≥ 1)", f.name),
                );
            }
        }
    });
}

fn screenshot_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Screenshot").default_open(false).show(ui, |ui| {
        let mut text = state.screenshot_text.clone();
        if ui.text_edit_singleline(&mut text).changed() {
            commands.push(Command::SetScreenshotText(text.clone()));
        }
        if ui.button("Save PNG").clicked() {
            commands.push(Command::SaveScreenshot(text.trim().into()));
        }
    });
}

/// The window pixels (origin, size) of `rect` (egui points at `ppp` pixels per point) inside a
/// window of `window_px`; at least one pixel wide and tall.
pub(super) fn view_pixels(rect: egui::Rect, ppp: f32, window_px: [u32; 2]) -> ([u32; 2], [u32; 2]) {
    let [w, h] = window_px.map(|v| v.max(1));
    if !rect.is_positive() || !rect.is_finite() {
        return ([0, 0], [w, h]);
    }
    let x0 = ((rect.min.x * ppp).round().max(0.0) as u32).min(w - 1);
    let y0 = ((rect.min.y * ppp).round().max(0.0) as u32).min(h - 1);
    let x1 = ((rect.max.x * ppp).round().max(0.0) as u32).clamp(x0 + 1, w);
    let y1 = ((rect.max.y * ppp).round().max(0.0) as u32).clamp(y0 + 1, h);
    ([x0, y0], [x1 - x0, y1 - y0])
}
