//! Panels for the background jobs (ray-trace this view, record the timeline) with their
//! progress bars, and the window showing the last ray-traced image. They only read the state and
//! the jobs' progress and emit commands; `jobs.rs` runs the jobs.

use egui::{Color32, RichText};

use super::command::{Command, RaytraceForm, RecordForm};
use super::jobs::JobView;
use super::state::ViewerState;

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
