//! Panels for grid editing (overlay toggle, function and point selection, axis lock, numeric
//! entry, undo / redo, save) and for the background jobs (ray-trace this view, record the
//! timeline) with their progress bars. They only read the state and emit commands.

use egui::{Color32, RichText};
use glam::DVec3;

use super::jobs::JobView;
use super::state::{Command, RaytraceForm, RecordForm, ViewerState};

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

fn progress_ui(
    ui: &mut egui::Ui,
    fraction: Option<f32>,
    message: &Option<String>,
    cancel: Command,
    commands: &mut Vec<Command>,
) {
    if let Some(f) = fraction {
        ui.horizontal(|ui| {
            ui.add(egui::ProgressBar::new(f).show_percentage().desired_width(180.0));
            if ui.button("Cancel").clicked() {
                commands.push(cancel);
            }
        });
    }
    if let Some(m) = message {
        ui.small(m);
    }
}

pub fn raytrace_ui(ui: &mut egui::Ui, state: &ViewerState, jobs: &JobView, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Ray-trace this view").default_open(false).show(ui, |ui| {
        let mut form: RaytraceForm = state.raytrace_form.clone();
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut form.depth).range(0..=12).prefix("depth "));
            ui.add(egui::DragValue::new(&mut form.spp).range(1..=64).prefix("spp "));
        });
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut form.width).range(16..=4096).prefix("w "));
            ui.add(egui::DragValue::new(&mut form.height).range(16..=4096).prefix("h "));
        });
        ui.horizontal(|ui| {
            ui.label("PNG");
            ui.text_edit_singleline(&mut form.png_text);
        });
        if form != state.raytrace_form {
            commands.push(Command::SetRaytraceForm(form));
        }
        if ui.add_enabled(jobs.raytrace.is_none(), egui::Button::new("Ray-trace this view")).clicked() {
            commands.push(Command::StartRaytrace);
        }
        progress_ui(ui, jobs.raytrace, &jobs.raytrace_message, Command::CancelRaytrace, commands);
    });
}

pub fn record_ui(ui: &mut egui::Ui, state: &ViewerState, jobs: &JobView, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Record timeline").default_open(false).show(ui, |ui| {
        let mut form: RecordForm = state.record_form.clone();
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut form.width).range(16..=4096).prefix("w "));
            ui.add(egui::DragValue::new(&mut form.height).range(16..=4096).prefix("h "));
            ui.add(egui::DragValue::new(&mut form.fps).range(1.0..=240.0).prefix("fps "));
        });
        ui.add(
            egui::DragValue::new(&mut form.points_per_frame)
                .range(1000..=100_000_000)
                .speed(1000.0)
                .prefix("points / frame "),
        );
        ui.horizontal(|ui| {
            ui.label("directory");
            ui.text_edit_singleline(&mut form.dir_text);
        });
        if form != state.record_form {
            commands.push(Command::SetRecordForm(form));
        }
        ui.small("CPU, deterministic; the viewer's camera and splat settings.");
        if ui.add_enabled(jobs.record.is_none(), egui::Button::new("Record timeline")).clicked() {
            commands.push(Command::StartRecord);
        }
        progress_ui(ui, jobs.record, &jobs.record_message, Command::CancelRecord, commands);
    });
}

/// The last ray-traced image, in its own window.
pub fn raytrace_window_ui(ctx: &egui::Context, jobs: &JobView, commands: &mut Vec<Command>) {
    let Some((texture, [w, h])) = jobs.raytrace_image else { return };
    let mut open = true;
    egui::Window::new("Ray-traced view").open(&mut open).default_width(520.0).show(ctx, |ui| {
        let width = ui.available_width().min(w as f32).max(64.0);
        let size = egui::vec2(width, width * h as f32 / w as f32);
        ui.image((texture, size));
        if let Some(m) = &jobs.raytrace_message {
            ui.label(RichText::new(m).small().color(Color32::LIGHT_GRAY));
        }
    });
    if !open {
        commands.push(Command::CloseRaytraceImage);
    }
}
