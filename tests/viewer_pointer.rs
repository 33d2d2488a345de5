//! Input routing between the camera and the panels (`viewer::pointer`): the camera gets exactly
//! the input egui did not use. The wheel over the side panel does not zoom; the first press in
//! the view right after a click on a panel widget orbits (it used to be dropped, because egui's
//! "wants the pointer" answer was a frame old); a drag keeps its owner until its release.

use nlifs::viewer::pointer::{Button, PointerContext, PointerEvent, PointerRouter, Route};

/// A 1280×720 window with a 310 px side panel on the left.
fn at(x: f32, y: f32) -> PointerContext {
    PointerContext {
        cursor_px: Some([x, y]),
        view_origin_px: [310.0, 0.0],
        view_size_px: [970.0, 720.0],
        over_egui_layer: false,
    }
}

const PANEL: (f32, f32) = (150.0, 300.0);
const VIEW: (f32, f32) = (800.0, 360.0);

#[test]
fn the_wheel_zooms_only_over_the_free_view() {
    let mut r = PointerRouter::default();
    assert_eq!(r.route(PointerEvent::Wheel(1.0), &at(PANEL.0, PANEL.1)), Route::Egui);
    assert_eq!(r.route(PointerEvent::Wheel(1.0), &at(VIEW.0, VIEW.1)), Route::Camera);
    // A window or popup over the view takes the wheel.
    let covered = PointerContext { over_egui_layer: true, ..at(VIEW.0, VIEW.1) };
    assert_eq!(r.route(PointerEvent::Wheel(1.0), &covered), Route::Egui);
    // Outside the window, or before the cursor is known: nobody zooms.
    let unknown = PointerContext { cursor_px: None, ..at(0.0, 0.0) };
    assert_eq!(r.route(PointerEvent::Wheel(1.0), &unknown), Route::Egui);
    // While a panel slider is dragged, the wheel stays with the panel.
    r.route(PointerEvent::Press(Button::Left), &at(PANEL.0, PANEL.1));
    assert_eq!(r.route(PointerEvent::Wheel(1.0), &at(VIEW.0, VIEW.1)), Route::Egui);
}

#[test]
fn a_press_in_the_view_right_after_a_panel_click_orbits() {
    let mut r = PointerRouter::default();
    // Click a panel widget.
    assert_eq!(r.route(PointerEvent::Press(Button::Left), &at(PANEL.0, PANEL.1)), Route::Egui);
    assert_eq!(r.route(PointerEvent::Release(Button::Left), &at(PANEL.0, PANEL.1)), Route::Egui);
    // At once (no frame in between) press in the view and drag: every event is the camera's.
    assert_eq!(r.route(PointerEvent::Move, &at(VIEW.0, VIEW.1)), Route::Egui, "a hover moves nothing");
    assert_eq!(r.route(PointerEvent::Press(Button::Left), &at(VIEW.0, VIEW.1)), Route::Camera);
    assert!(r.camera_holds());
    for k in 1..=10 {
        assert_eq!(r.route(PointerEvent::Move, &at(VIEW.0 + 10.0 * k as f32, VIEW.1)), Route::Camera);
    }
    assert_eq!(r.route(PointerEvent::Release(Button::Left), &at(VIEW.0 + 100.0, VIEW.1)), Route::Camera);
    assert!(!r.camera_holds());
}

#[test]
fn a_drag_keeps_its_owner_until_release() {
    let mut r = PointerRouter::default();
    // An orbit that leaves the view over the panel keeps orbiting.
    r.route(PointerEvent::Press(Button::Left), &at(VIEW.0, VIEW.1));
    assert_eq!(r.route(PointerEvent::Move, &at(PANEL.0, PANEL.1)), Route::Camera);
    assert_eq!(r.route(PointerEvent::Release(Button::Left), &at(PANEL.0, PANEL.1)), Route::Camera);
    // A slider dragged from the panel over the view keeps sliding: the camera never moves.
    r.route(PointerEvent::Press(Button::Left), &at(PANEL.0, PANEL.1));
    assert_eq!(r.route(PointerEvent::Move, &at(VIEW.0, VIEW.1)), Route::Egui);
    assert_eq!(r.route(PointerEvent::Press(Button::Right), &at(VIEW.0, VIEW.1)), Route::Egui);
    assert_eq!(r.route(PointerEvent::Release(Button::Right), &at(VIEW.0, VIEW.1)), Route::Egui);
    assert_eq!(r.route(PointerEvent::Release(Button::Left), &at(VIEW.0, VIEW.1)), Route::Egui);
    // A press on a dialog over the view is the dialog's.
    let covered = PointerContext { over_egui_layer: true, ..at(VIEW.0, VIEW.1) };
    assert_eq!(r.route(PointerEvent::Press(Button::Left), &covered), Route::Egui);
    assert_eq!(r.route(PointerEvent::Release(Button::Left), &at(VIEW.0, VIEW.1)), Route::Egui);
    // A release without its press (focus lost) belongs to nobody in particular.
    r.reset();
    assert_eq!(r.route(PointerEvent::Release(Button::Middle), &at(VIEW.0, VIEW.1)), Route::Egui);
}
