//! Who gets a pointer event, the camera or the panels: the camera gets exactly the input the
//! panels did not use. Every event also goes to egui (it must see releases and moves to end its
//! own interactions); [`PointerRouter::route`] decides whether the camera acts on it too.
//!
//! The rules: a press or a wheel step belongs to the camera when the cursor is inside the view
//! rectangle (what the panels leave) and no egui window, popup or dialog lies under it; a
//! button held since a press keeps the owner of that press until its release (an orbit that
//! leaves the view keeps orbiting; a slider dragged over the view keeps sliding), and while
//! egui holds a button the wheel is egui's too. The router keeps who pressed what itself rather
//! than asking egui whether it "wants" the pointer: egui answers from its last frame, which is
//! stale when events arrive between two frames (the viewer sleeps while the picture has
//! converged), and a press in the view right after a click on a panel was dropped that way.

/// A mouse button, as the router tells them apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Button {
    Left,
    Right,
    Middle,
    Other,
}

/// A pointer event from the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointerEvent {
    Press(Button),
    Release(Button),
    /// The cursor moved (to the position in the context).
    Move,
    /// Wheel steps (positive: away from the user).
    Wheel(f32),
}

/// Where the event happened, in window pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointerContext {
    /// The cursor (None: outside the window or not known yet).
    pub cursor_px: Option<[f32; 2]>,
    /// The view rectangle's top left corner and size.
    pub view_origin_px: [f32; 2],
    pub view_size_px: [f32; 2],
    /// An egui window, popup, menu or modal dialog lies under the cursor (or a modal dialog is
    /// open anywhere).
    pub over_egui_layer: bool,
}

impl PointerContext {
    /// The cursor is inside the view rectangle and nothing of egui's covers it there.
    pub fn in_free_view(&self) -> bool {
        let Some([x, y]) = self.cursor_px else { return false };
        let ([x0, y0], [w, h]) = (self.view_origin_px, self.view_size_px);
        !self.over_egui_layer && x >= x0 && y >= y0 && x < x0 + w && y < y0 + h
    }
}

/// Who acts on an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// The camera (or a grid point drag) acts on it; egui saw it too.
    Camera,
    /// Only egui.
    Egui,
}

/// The buttons held since their press and who got each press.
#[derive(Clone, Debug, Default)]
pub struct PointerRouter {
    held: Vec<(Button, Route)>,
}

impl PointerRouter {
    /// Who acts on `event` at `ctx`; remembers presses until their release.
    pub fn route(&mut self, event: PointerEvent, ctx: &PointerContext) -> Route {
        let egui_holds = self.held.iter().any(|&(_, r)| r == Route::Egui);
        match event {
            PointerEvent::Press(button) => {
                // A second press of a button already held (a lost release) starts afresh.
                self.held.retain(|&(b, _)| b != button);
                let route = if !egui_holds && ctx.in_free_view() { Route::Camera } else { Route::Egui };
                self.held.push((button, route));
                route
            }
            PointerEvent::Release(button) => match self.held.iter().position(|&(b, _)| b == button) {
                Some(i) => self.held.remove(i).1,
                None => Route::Egui,
            },
            PointerEvent::Move => {
                if self.camera_holds() {
                    Route::Camera
                } else {
                    Route::Egui
                }
            }
            PointerEvent::Wheel(_) => {
                if !egui_holds && ctx.in_free_view() {
                    Route::Camera
                } else {
                    Route::Egui
                }
            }
        }
    }

    /// A button pressed in the view is still held (an orbit, pan or point drag runs).
    pub fn camera_holds(&self) -> bool {
        self.held.iter().any(|&(_, r)| r == Route::Camera)
    }

    /// The camera's held buttons, oldest first.
    pub fn camera_buttons(&self) -> impl Iterator<Item = Button> + '_ {
        self.held.iter().filter(|&&(_, r)| r == Route::Camera).map(|&(b, _)| b)
    }

    /// Forgets every held button (the window lost focus: releases may never come).
    pub fn reset(&mut self) {
        self.held.clear();
    }
}
