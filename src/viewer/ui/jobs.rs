//! Panels for the background jobs (ray-trace this view, record the timeline) with their
//! progress bars, time left and Cancel, and the window showing the last ray-traced image. The
//! forms show what `job_plan.rs` makes of them (the hierarchy's size, the frames to record, why
//! a job cannot start, with its button disabled). They only read the state and the jobs'
//! progress and emit commands; `jobs.rs` runs the jobs.

use egui::{Color32, RichText};

use crate::output::Format;

use super::super::command::{Command, RaytraceForm, RecordForm};
use super::super::job_plan::{self, NODE_BUDGET};
use super::super::jobs::{JobProgress, JobView, format_secs};
use super::super::state::ViewerState;

const ERROR_COLOR: Color32 = Color32::from_rgb(255, 110, 90);

/// *Show folder* for the folder a finished job wrote into, where the desktop can show one.
fn show_folder_ui(ui: &mut egui::Ui, jobs: &JobView, folder: &Option<std::path::PathBuf>, commands: &mut Vec<Command>) {
    if let Some(folder) = folder.as_ref().filter(|_| jobs.can_show_folder)
        && ui.button("Show folder").on_hover_text(folder.display().to_string()).clicked()
    {
        commands.push(Command::ShowFolder(folder.clone()));
    }
}

/// "37 % · 12 s left" with a Cancel button, while a job runs (`preparing` before its units are
/// counted); then its last message.
fn progress_ui(
    ui: &mut egui::Ui,
    progress: Option<JobProgress>,
    preparing: &str,
    message: &Option<String>,
    cancel: Command,
    commands: &mut Vec<Command>,
) {
    if let Some(p) = progress {
        ui.horizontal(|ui| {
            let text = match (p.cancelling, p.eta_secs) {
                (true, _) => "cancelling…".to_string(),
                (false, _) if p.total == 0 => preparing.to_string(),
                (false, Some(eta)) => {
                    format!("{:.0} % · {} left", 100.0 * p.fraction(), format_secs(eta))
                }
                (false, None) => format!("{:.0} %", 100.0 * p.fraction()),
            };
            ui.add(egui::ProgressBar::new(p.fraction()).text(text).desired_width(190.0));
            if ui.add_enabled(!p.cancelling, egui::Button::new("Cancel")).clicked() {
                commands.push(cancel);
            }
        });
    }
    if let Some(m) = message {
        ui.small(m);
    }
}

/// Where the job panels were, in a build without threads, files or ffmpeg (the browser).
pub fn desktop_only_ui(ui: &mut egui::Ui, has_timeline: bool) {
    let jobs = if has_timeline { "Ray-trace this view and Record timeline" } else { "Ray-trace this view" };
    ui.separator();
    ui.label(format!("{jobs}: in the desktop viewer only (`nlifs view`)."));
}

pub fn raytrace_ui(ui: &mut egui::Ui, state: &ViewerState, jobs: &JobView, commands: &mut Vec<Command>) {
    egui::CollapsingHeader::new("Ray-trace this view").default_open(false).show(ui, |ui| {
        let mut form: RaytraceForm = state.raytrace_form.clone();
        ui.horizontal(|ui| {
            let mut auto = form.depth.is_none();
            let mut depth = form.depth.unwrap_or_else(|| state.default_raytrace_depth());
            ui.add_enabled(!auto, egui::DragValue::new(&mut depth).range(0..=job_plan::MAX_DEPTH).prefix("depth "));
            ui.checkbox(&mut auto, "auto").on_hover_text(
                "deep enough that the largest leaf is below about 3 pixels (from the scene's contraction), within 2.5 million nodes",
            );
            form.depth = (!auto).then_some(depth);
            ui.add(egui::DragValue::new(&mut form.spp).range(1..=64).prefix("spp "));
        });
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut form.width).range(16..=4096).prefix("w "));
            ui.add(egui::DragValue::new(&mut form.height).range(16..=4096).prefix("h "));
        });
        ui.horizontal(|ui| {
            ui.label("PNG");
            ui.add(egui::TextEdit::singleline(&mut form.png_text).hint_text("next to the scene, numbered"));
        });
        ui.small(format!("writes {}", state.raytrace_png().display()));
        if form != state.raytrace_form {
            commands.push(Command::SetRaytraceForm(form));
        }
        let estimate = state.raytrace_estimate();
        let refusal = estimate.refusal();
        ui.small(format!(
            "hierarchy: about {} nodes ({} functions, depth {}; about {}); budget {} nodes",
            job_plan::format_count(estimate.nodes),
            estimate.functions,
            estimate.depth,
            job_plan::format_bytes(estimate.bytes),
            job_plan::format_count(NODE_BUDGET)
        ));
        if let Some(why) = &refusal {
            ui.colored_label(ERROR_COLOR, why);
        }
        let can_start = jobs.raytrace.is_none() && refusal.is_none();
        if ui.add_enabled(can_start, egui::Button::new("Ray-trace this view")).clicked() {
            commands.push(Command::StartRaytrace);
        }
        progress_ui(
            ui,
            jobs.raytrace,
            "building the hierarchy…",
            &jobs.raytrace_message,
            Command::CancelRaytrace,
            commands,
        );
        if jobs.raytrace.is_none() {
            show_folder_ui(ui, jobs, &jobs.raytrace_folder, commands);
        }
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
        ui.horizontal(|ui| {
            ui.selectable_value(&mut form.ray_traced, false, "chaos game");
            ui.selectable_value(&mut form.ray_traced, true, "ray-traced").on_hover_text(
                "each frame traced as \"Ray-trace this view\" traces a still: W^depth(A) of spheres, shadows, ground",
            );
        });
        if form.ray_traced {
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut form.trace_depth).range(0..=12).prefix("depth "));
                ui.add(egui::DragValue::new(&mut form.trace_spp).range(1..=64).prefix("spp "));
            });
        } else {
            ui.add(
                egui::DragValue::new(&mut form.points_per_frame)
                    .range(1000..=100_000_000)
                    .speed(1000.0)
                    .prefix("points / frame "),
            );
        }
        let count = job_plan::frame_count(&state.scene, form.fps);
        ui.horizontal(|ui| {
            let mut all = form.frame_range.is_none();
            if ui.checkbox(&mut all, format!("all {count} frames")).changed() {
                form.frame_range = if all { None } else { Some((0, count)) };
            }
            if let Some((first, end)) = &mut form.frame_range {
                ui.add(egui::DragValue::new(first).range(0..=count.saturating_sub(1)).prefix("from "));
                ui.add(egui::DragValue::new(end).range(1..=count).prefix("to "))
                    .on_hover_text("the end is exclusive: 0 to 24 is frames 0…23");
            }
        });
        ui.horizontal(|ui| {
            ui.label("frames as");
            for format in Format::ALL {
                ui.selectable_value(&mut form.format, format, format.name());
            }
        });
        ui.horizontal(|ui| {
            ui.label("folder");
            ui.add(egui::TextEdit::singleline(&mut form.dir_text).hint_text("next to the scene, numbered"));
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut form.video, "make a video");
            ui.add_enabled(
                form.video,
                egui::TextEdit::singleline(&mut form.video_text).hint_text("beside the frames' folder"),
            );
        });
        if form != state.record_form {
            commands.push(Command::SetRecordForm(form));
        }
        if !state.files.ffmpeg {
            ui.small("ffmpeg was not found: a video needs it (the frames do not).");
        }
        ui.small(if state.record_form.ray_traced {
            "CPU, deterministic; the viewer's camera, the scene's timeline."
        } else {
            "CPU, deterministic; the viewer's camera and splat settings."
        });
        let plan = state.record_plan();
        match &plan {
            Ok(plan) => {
                ui.small(format!("writes {}", plan.dir.display()));
                if let Some(video) = &plan.video {
                    ui.small(format!("and {}", video.display()));
                }
            }
            Err(why) => {
                ui.colored_label(ERROR_COLOR, why);
            }
        }
        let can_start = jobs.record.is_none() && plan.is_ok();
        if ui.add_enabled(can_start, egui::Button::new("Record timeline")).clicked() {
            commands.push(Command::StartRecord);
        }
        progress_ui(ui, jobs.record, "framing the timeline…", &jobs.record_message, Command::CancelRecord, commands);
        if jobs.record.is_none() {
            show_folder_ui(ui, jobs, &jobs.record_folder, commands);
        }
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
        show_folder_ui(ui, jobs, &jobs.raytrace_folder, commands);
    });
    if !open {
        commands.push(Command::CloseRaytraceImage);
    }
}
