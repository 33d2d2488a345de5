//! Grid editing in the viewer's UI: the panel (overlay toggle, function and point selection,
//! axis lock, numeric entry, undo / redo, save) and the overlay drawn over the view (the initial
//! grid and every function's transformed grid as lines, the paper's plates 5 and 7, with the
//! selected function's points). Both only read the state and emit commands; the overlay projects
//! with the same [`SplatView`] as picking (`picking.rs`), so lines sit on the splatted points.

use glam::{DVec3, Vec2};

use crate::splat::SplatView;

use super::super::command::Command;
use super::super::picking::{FunctionGrid, definition_grid, grid_lines, project};
use super::super::state::ViewerState;

pub fn grid_edit_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Grid editing").default_open(true).show(ui, |ui| {
        let e = &state.edit;
        let mut overlay = e.grid_overlay;
        if ui.checkbox(&mut overlay, "show grids (initial and transformed)").changed() {
            commands.push(Command::SetGridOverlay(overlay));
        }
        let name = |f: usize| state.scene.functions.get(f).map_or("none".to_string(), |s| s.name.clone());
        let mut selected = e.selected_function;
        egui::ComboBox::from_label("function").selected_text(selected.map_or("none".into(), name)).show_ui(ui, |ui| {
            ui.selectable_value(&mut selected, None, "none");
            for f in 0..state.scene.functions.len() {
                if state.function_grid(f).is_some() {
                    ui.selectable_value(&mut selected, Some(f), name(f));
                }
            }
        });
        if selected != e.selected_function {
            commands.push(Command::SelectFunction(selected));
        }
        ui.horizontal(|ui| {
            ui.label("axis lock:");
            for (axis, label) in ["X", "Y", "Z"].iter().enumerate().take(state.scene.domain.dimension()) {
                let on = e.axis_lock == Some(axis);
                if ui.selectable_label(on, *label).clicked() {
                    commands.push(Command::SetAxisLock(if on { None } else { Some(axis) }));
                }
            }
            if ui.selectable_label(e.axis_lock.is_none(), "free").clicked() {
                commands.push(Command::SetAxisLock(None));
            }
        });
        if let Some(f) = e.selected_function
            && let Some(grid) = state.function_grid(f)
        {
            if !grid.editable {
                ui.small("builder function: its resolved grid is shown read-only; edit its parameters below.");
            } else {
                let count = grid.points.len();
                let mut point = e.selected_point.unwrap_or(0);
                ui.horizontal(|ui| {
                    ui.label("point");
                    if ui.add(egui::DragValue::new(&mut point).range(0..=count.saturating_sub(1))).changed()
                        || e.selected_point.is_none() && count > 0
                    {
                        commands.push(Command::SelectPoint(Some(point)));
                    }
                    let [nx, ny, nz] = grid.dims;
                    let (ix, iy, iz) = (point / (ny * nz), (point / nz) % ny, point % nz);
                    ui.small(format!("({ix}, {iy}, {iz}) of {nx}×{ny}×{nz}"));
                });
                if let Some(p) = e.selected_point.and_then(|i| grid.points.get(i)) {
                    let extent = (state.scene.domain.max() - state.scene.domain.min()).max_element().max(1e-9);
                    let mut q = *p;
                    ui.horizontal(|ui| {
                        for (a, label) in ["x ", "y ", "z "].iter().enumerate().take(state.scene.domain.dimension()) {
                            ui.add(egui::DragValue::new(&mut q[a]).speed(extent * 2e-3).max_decimals(4).prefix(*label));
                        }
                    });
                    if q != *p && q.is_finite() {
                        commands.push(Command::SetPoint {
                            function: f,
                            point: e.selected_point.unwrap_or(0),
                            p: DVec3::new(q.x, q.y, q.z),
                        });
                    }
                }
                ui.small("drag a point in the view (near its dot); X / Y / Z lock an axis.");
            }
        } else if e.grid_overlay {
            ui.small("click-drag a grid function's point in the view, or choose a function.");
        }
        if state.scene.timeline.is_none() {
            if ui
                .button("Animate (key at 0 s, 4 s long)")
                .on_hover_text("adds a timeline; edits at other times then create keys")
                .clicked()
            {
                commands.extend([Command::SetTime(0.0), Command::AddOrUpdateKey, Command::SetDuration(4.0)]);
            }
        } else {
            ui.small(format!(
                "edits go to the key at t = {:.3} s{}",
                state.playhead_secs(),
                if state.key_at_playhead().is_some() { "" } else { " (created on the first edit)" }
            ));
        }
        ui.horizontal(|ui| {
            if ui
                .add_enabled(state.history.can_undo() || e.gesture.is_some(), egui::Button::new("Undo"))
                .on_hover_text("Ctrl+Z")
                .clicked()
            {
                commands.push(Command::Undo);
            }
            if ui
                .add_enabled(state.history.can_redo(), egui::Button::new("Redo"))
                .on_hover_text("Ctrl+Shift+Z / Ctrl+Y")
                .clicked()
            {
                commands.push(Command::Redo);
            }
        });
        ui.horizontal(|ui| {
            let mut text = e.save_text.clone();
            if ui.text_edit_singleline(&mut text).changed() {
                commands.push(Command::SetSaveText(text.clone()));
            }
            if ui.button("Save").on_hover_text("Ctrl+S").clicked() {
                commands.push(Command::SaveScene(text.trim().into()));
            }
        });
    });
}

/// An egui colour of linear RGB `color` with `alpha` (also the nesting view's).
pub(super) fn srgb(color: [f32; 3], alpha: f32) -> egui::Color32 {
    let c = color.map(|v| (crate::color::linear_to_srgb(v).clamp(0.0, 1.0) * 255.0).round() as u8);
    egui::Color32::from_rgba_unmultiplied(c[0], c[1], c[2], (alpha * 255.0).round() as u8)
}

/// egui position (points) of view pixel `q` in a view whose corner is at window pixel `origin`.
fn to_egui(q: Vec2, origin: [f32; 2], ppp: f32) -> egui::Pos2 {
    egui::pos2((q.x + origin[0]) / ppp, (q.y + origin[1]) / ppp)
}

fn draw_grid(
    painter: &egui::Painter,
    view: &SplatView,
    origin: [f32; 2],
    grid: &FunctionGrid,
    ppp: f32,
    stroke: egui::Stroke,
) {
    let projected: Vec<Option<egui::Pos2>> =
        grid.points.iter().map(|p| project(view, *p).map(|q| to_egui(q, origin, ppp))).collect();
    for (a, b) in grid_lines(grid.dims) {
        if let (Some(Some(pa)), Some(Some(pb))) = (projected.get(a), projected.get(b)) {
            painter.line_segment([*pa, *pb], stroke);
        }
    }
}

/// Draws the initial grid, every enabled function's grid, the selected function's points
/// (the selected one ringed) and, with a timeline, faint ghosts of the selected function's grid
/// at the neighbouring keys. `ppp`: egui points per window pixel inverse (pixels per point).
pub fn grid_overlay_ui(ctx: &egui::Context, clip: egui::Rect, state: &ViewerState, ppp: f32) {
    if !state.edit.grid_overlay {
        return;
    }
    let painter = ctx
        .layer_painter(egui::LayerId::new(egui::Order::Background, egui::Id::unique("nlifs_grid_overlay")))
        .with_clip_rect(clip);
    let view = state.splat_view();
    let initial =
        FunctionGrid { dims: state.scene.domain.dims(), points: state.scene.domain.points(), editable: false };
    draw_grid(
        &painter,
        &view,
        state.view_origin_px,
        &initial,
        ppp,
        egui::Stroke::new(1.0, egui::Color32::from_white_alpha(110)),
    );
    let selected = state.edit.selected_function;
    if let (Some(f), Some(tl)) = (selected, &state.scene.timeline) {
        let t = state.playhead_secs();
        let tol = crate::scene::timeline::KEY_TIME_TOL_SECS;
        let with_f: Vec<_> = tl.keys.iter().filter(|k| k.function(f).is_some()).collect();
        let before = with_f.iter().rev().find(|k| k.t_secs < t - tol);
        let after = with_f.iter().find(|k| k.t_secs > t + tol);
        for key in [before, after].into_iter().flatten() {
            if let Some(grid) = key.function(f).and_then(|d| definition_grid(&state.scene, d)) {
                draw_grid(
                    &painter,
                    &view,
                    state.view_origin_px,
                    &grid,
                    ppp,
                    egui::Stroke::new(1.0, srgb(state.scene.functions[f].color, 0.25)),
                );
            }
        }
    }
    for (f, spec) in state.scene.functions.iter().enumerate() {
        if !spec.enabled && selected != Some(f) {
            continue;
        }
        let Some(grid) = state.function_grid(f) else { continue };
        let (width, alpha) = if selected == Some(f) {
            (2.0, 1.0)
        } else if selected.is_some() {
            (1.0, 0.35)
        } else {
            (1.2, 0.8)
        };
        draw_grid(&painter, &view, state.view_origin_px, &grid, ppp, egui::Stroke::new(width, srgb(spec.color, alpha)));
        if selected == Some(f) || (selected.is_none() && grid.editable) {
            for (i, p) in grid.points.iter().enumerate() {
                let Some(q) = project(&view, *p) else { continue };
                let pos = to_egui(q, state.view_origin_px, ppp);
                let is_selected = selected == Some(f) && state.edit.selected_point == Some(i);
                if is_selected {
                    painter.circle_stroke(pos, 6.0, egui::Stroke::new(2.0, egui::Color32::WHITE));
                }
                let fill = if grid.editable { srgb(spec.color, 1.0) } else { egui::Color32::from_gray(150) };
                painter.circle_filled(pos, if is_selected { 4.0 } else { 2.5 }, fill);
            }
        }
    }
}
