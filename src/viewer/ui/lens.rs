//! Depth of field in the viewer, the UI side: the render panel's aperture slider and focus
//! distance field, and focus by click (Ctrl+click on the picture focuses on the nearest
//! splatted point under the cursor, as Blender's focus eyedropper picks an object). Both emit
//! [`Command::SetLens`] (one undo step, `lens.rs`); while a slider or field is dragged the live
//! view previews the value ([`Command::SetLiveSettings`]) and the release makes the edit.

use winit::event::MouseButton;

use crate::gpu::GpuContext;
use crate::live::LiveView;
use crate::scene::spec::SplatMode;
use crate::splat::SplatView;

use super::super::command::Command;
use super::super::lens::focus_depth_at;
use super::super::state::ViewerState;
use super::widgets::slider;

/// The render panel's depth-of-field controls.
pub fn lens_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let live = state.live;
    let (mut aperture, focus) = (live.draw.aperture, live.draw.focus_distance);
    // Apertures up to a fifth of the camera's distance (a strong blur); typed values may go past.
    let max_aperture = (0.2 * state.camera.distance).max(1e-6);
    let r = ui.add(slider(&mut aperture, 0.0..=max_aperture).logarithmic(true).text("aperture (depth of field)"));
    lens_edit(r, state, aperture, focus, commands);
    ui.horizontal(|ui| {
        let mut at_target = focus.is_none();
        if ui.checkbox(&mut at_target, "focus at target").changed() {
            let focus = if at_target { None } else { Some(state.camera.distance) };
            commands.push(Command::SetLens { aperture: live.draw.aperture, focus_distance: focus });
        }
        if let Some(mut f) = focus {
            let speed = 0.005 * state.camera.distance as f64;
            let r = ui.add(egui::DragValue::new(&mut f).speed(speed).range(1e-6..=f32::MAX).prefix("focus "));
            lens_edit(r, state, live.draw.aperture, Some(f), commands);
        }
    });
    ui.small("Ctrl+click the picture: focus on the point there (closest mode).");
}

/// The commands of a lens widget's response `r` showing `aperture`, `focus`: a preview while it
/// is dragged, the undoable edit when it is released or changed otherwise (typed, clicked).
fn lens_edit(r: egui::Response, state: &ViewerState, aperture: f32, focus: Option<f32>, commands: &mut Vec<Command>) {
    if r.changed() && r.dragged() {
        let mut live = state.live;
        (live.draw.aperture, live.draw.focus_distance) = (aperture, focus);
        commands.push(Command::SetLiveSettings(live));
    } else if r.changed() || r.drag_stopped() {
        commands.push(Command::SetLens { aperture, focus_distance: focus });
    }
}

/// A press of `button` with Ctrl held (`ctrl`) at `cursor` (window pixels) in the view: the
/// command focusing on the nearest splatted point there (the closest-mode keys of the live
/// view, read back from the GPU on its route), or a notice saying why not. None for any other
/// press (it stays the camera's).
pub fn focus_click(
    state: &ViewerState,
    live: &LiveView,
    ctx: &GpuContext,
    button: MouseButton,
    ctrl: bool,
    cursor: Option<(f64, f64)>,
) -> Option<Command> {
    let (x, y) = cursor.filter(|_| ctrl && button == MouseButton::Left)?;
    let notice = |m: &str| Some(Command::SetToast(Some(m.into())));
    if state.live.draw.mode != SplatMode::Closest {
        return notice("focus by click needs the closest splat mode (its keys hold the depth)");
    }
    let (w, h) = live.size();
    let view = SplatView::new(&state.camera, w, h, state.bounds, SplatMode::Closest, 0.0, [0.0; 3]);
    let keys = match live.cpu_accum() {
        Some(keys) => keys.to_vec(),
        None => match live.read_accum(ctx) {
            Ok(keys) => keys,
            Err(e) => return notice(&format!("focus by click: {e}")),
        },
    };
    let at = [x as f32 - state.view_origin_px[0], y as f32 - state.view_origin_px[1]];
    match focus_depth_at(&view, &keys, at) {
        Some(d) => Some(Command::SetLens { aperture: state.scene.render.aperture, focus_distance: Some(d) }),
        None => notice("no point under the cursor to focus on"),
    }
}
