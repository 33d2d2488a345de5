//! The window's keys and the pointer's context for the event loop (`mod.rs`): what a key
//! pressed outside text fields does (frame, views, projection, panel, full screen, screenshot,
//! Esc, quit), and where the cursor is for the pointer router (`pointer.rs`).

use winit::event::MouseButton;
use winit::keyboard::{Key, NamedKey};

use crate::camera::Projection;

use super::command::ViewAxis;
use super::pointer;
use super::{App, Command, ViewerState};

impl App {
    /// A key pressed while no text field has the keyboard (egui's own shortcuts, undo, redo,
    /// save, axis lock and play, are in `ui/mod.rs`).
    pub(super) fn key(&mut self, event: &winit::event::KeyEvent) {
        use winit::keyboard::{KeyCode, PhysicalKey};
        let Some(gfx) = &self.gfx else { return };
        // Every key here is an action or a toggle: a held key (or a slow machine, where the
        // X server's auto-repeat starts before the release arrives) must not repeat it.
        if event.repeat {
            return;
        }
        let (ctrl, shift) = (self.modifiers.control_key(), self.modifiers.shift_key());
        let toggle_projection = |state: &ViewerState| {
            Command::SetProjection(match state.camera.projection {
                Projection::Perspective => Projection::Parallel,
                Projection::Parallel => Projection::Perspective,
            })
        };
        // Blender's numpad views, also on the number row (by physical key, so that numpad
        // digits work with Num Lock off too).
        if let PhysicalKey::Code(code) = event.physical_key {
            let axis = match code {
                KeyCode::Numpad1 | KeyCode::Digit1 => Some(if ctrl { ViewAxis::Back } else { ViewAxis::Front }),
                KeyCode::Numpad3 | KeyCode::Digit3 => Some(if ctrl { ViewAxis::Left } else { ViewAxis::Right }),
                KeyCode::Numpad7 | KeyCode::Digit7 => Some(if ctrl { ViewAxis::Bottom } else { ViewAxis::Top }),
                _ => None,
            };
            if let Some(axis) = axis {
                self.commands.push(Command::ViewAlong(axis));
                return;
            }
            if matches!(code, KeyCode::Numpad5 | KeyCode::Digit5) {
                self.commands.push(toggle_projection(&self.state));
                return;
            }
        }
        match event.logical_key.as_ref() {
            Key::Character(c) if c.eq_ignore_ascii_case("f") && !ctrl => {
                self.commands.push(if shift { Command::FrameAttractorAndGrid } else { Command::FrameAttractor })
            }
            Key::Character(c) if c.eq_ignore_ascii_case("p") && !ctrl => {
                self.commands.push(toggle_projection(&self.state))
            }
            Key::Character(c) if c.eq_ignore_ascii_case("q") && ctrl => self.commands.push(Command::RequestClose),
            Key::Character("?") => self.commands.push(Command::SetShortcutsShown(!self.state.ui.shortcuts_shown)),
            Key::Named(NamedKey::F1) => self.commands.push(Command::SetShortcutsShown(!self.state.ui.shortcuts_shown)),
            Key::Named(NamedKey::Tab) if !ctrl => {
                self.commands.push(Command::SetPanelShown(!self.state.ui.panel_shown))
            }
            Key::Named(NamedKey::F11) => {
                let on = gfx.window.fullscreen().is_none();
                gfx.window.set_fullscreen(on.then_some(winit::window::Fullscreen::Borderless(None)));
                self.commands.push(Command::SetFullscreen(on));
            }
            Key::Named(NamedKey::F12) => self.commands.push(Command::ScreenshotNextToScene),
            // Blender's add (Shift+A) and duplicate (Shift+D); Delete deletes.
            Key::Character(c) if c.eq_ignore_ascii_case("a") && shift && !ctrl => {
                self.commands.push(Command::AddFunction)
            }
            Key::Character(c) if c.eq_ignore_ascii_case("d") && shift && !ctrl => {
                if let Some(f) = self.state.edit.selected_function {
                    self.commands.push(Command::DuplicateFunction(f));
                }
            }
            Key::Named(NamedKey::Delete) => {
                if let Some(f) = self.state.edit.selected_function {
                    self.commands.push(Command::DeleteFunction(f));
                }
            }
            Key::Named(NamedKey::Escape) => {
                // An orbit or pan in progress goes back to where it started; else the state
                // decides (close a dialog or an overlay, cancel a point drag). Never quits.
                if self.drag.take().is_some() {
                    self.commands.push(Command::SetCamera(self.drag_start_camera));
                } else {
                    // A cancelled point drag takes no more moves; its release ends nothing.
                    self.point_drag = None;
                    self.commands.push(Command::Escape);
                }
            }
            _ => {}
        }
    }
}

pub(super) fn pointer_button(button: MouseButton) -> pointer::Button {
    match button {
        MouseButton::Left => pointer::Button::Left,
        MouseButton::Right => pointer::Button::Right,
        MouseButton::Middle => pointer::Button::Middle,
        _ => pointer::Button::Other,
    }
}

/// Where the cursor (window pixels) is for the pointer router: the view rectangle the panels
/// left at the last frame, and whether an egui window, popup or dialog is over the cursor.
pub(super) fn pointer_context(
    state: &ViewerState,
    egui_ctx: &egui::Context,
    cursor: Option<(f64, f64)>,
) -> pointer::PointerContext {
    let cursor_px = cursor.map(|(x, y)| [x as f32, y as f32]);
    let modal = state.ui.close_dialog || state.recovery_offer.is_some() || state.ui.job_confirm.is_some();
    let over_layer = cursor_px.is_some_and(|[x, y]| {
        let ppp = egui_ctx.pixels_per_point();
        egui_ctx.layer_id_at(egui::pos2(x / ppp, y / ppp)).is_some_and(|layer| layer.order != egui::Order::Background)
    });
    pointer::PointerContext {
        cursor_px,
        view_origin_px: state.view_origin_px,
        view_size_px: [state.width_px, state.height_px],
        over_egui_layer: modal || over_layer,
    }
}
