//! The timeline panel: play / pause, scrub, speed, loop mode, duration, the keys drawn on a
//! strip under the scrubber (click one to jump to it), add / update / delete the key at the
//! playhead, and the interpolation and ease of the segment that starts at that key. Like every
//! `*_ui` function it only reads the state and emits commands.

use egui::{Color32, Sense, Stroke};

use crate::scene::timeline::{Ease, Interpolation, LoopMode};

use super::command::Command;
use super::state::ViewerState;

const INTERPOLATIONS: [Interpolation; 3] = [Interpolation::Hold, Interpolation::Linear, Interpolation::CatmullRom];
const EASES: [Ease; 4] = [Ease::None, Ease::In, Ease::Out, Ease::InOut];
const LOOP_MODES: [LoopMode; 3] = [LoopMode::Once, LoopMode::Loop, LoopMode::PingPong];

pub fn timeline_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let Some(tl) = &state.scene.timeline else { return };
    let d = tl.duration_secs.max(1e-3);
    let playhead = state.playhead_secs();
    ui.horizontal(|ui| {
        let playing = state.playback.playing;
        if ui.button(if playing { "Pause" } else { "Play" }).on_hover_text("Space").clicked() {
            commands.push(Command::SetPlaying(!playing));
        }
        if ui.button("|<").on_hover_text("to the start").clicked() {
            commands.push(Command::SetTime(0.0));
        }
        // Only the user moves time from here: a slider that wrote back its (clamped, rounded
        // to 3 decimals) value every frame sent the previous frame's time after each playback
        // tick, and playback ran at about half speed.
        let mut t = playhead;
        let scrub = ui.add(super::widgets::slider(&mut t, 0.0..=d).suffix(" s").max_decimals(3).text("t"));
        let by_user = scrub.dragged() || scrub.is_pointer_button_down_on() || scrub.has_focus() || scrub.clicked();
        if scrub.changed() && by_user && t != playhead {
            commands.push(Command::SetTime(t));
        }
        let mut speed = state.playback.speed;
        if ui.add(egui::DragValue::new(&mut speed).speed(0.02).range(-8.0..=8.0).prefix("speed ×")).changed() {
            commands.push(Command::SetSpeed(speed));
        }
        let mut mode = tl.loop_mode;
        egui::ComboBox::from_id_salt("loop_mode").selected_text(mode.name()).show_ui(ui, |ui| {
            for m in LOOP_MODES {
                ui.selectable_value(&mut mode, m, m.name());
            }
        });
        if mode != tl.loop_mode {
            commands.push(Command::SetLoopMode(mode));
        }
        let mut follow = state.playback.follow_camera;
        if ui
            .checkbox(&mut follow, "keyed camera")
            .on_hover_text("take the camera from the scene's keys as time moves")
            .changed()
        {
            commands.push(Command::SetFollowCamera(follow));
        }
        let mut duration = tl.duration_secs;
        if ui
            .add(egui::DragValue::new(&mut duration).speed(0.05).range(0.01..=3600.0).prefix("duration ").suffix(" s"))
            .changed()
        {
            commands.push(Command::SetDuration(duration));
        }
    });
    keys_strip_ui(ui, state, d, playhead, commands);
    ui.horizontal(|ui| {
        let key = state.key_at_playhead();
        let label = if key.is_some() { "Update key (pin all functions)" } else { "Add key" };
        if ui.button(label).clicked() {
            commands.push(Command::AddOrUpdateKey);
        }
        if ui.add_enabled(key.is_some(), egui::Button::new("Delete key")).clicked() {
            commands.push(Command::DeleteKeyAtPlayhead);
        }
        match key {
            Some(k) => {
                let key_data = &tl.keys[k];
                let (mut interpolation, mut ease) = (key_data.interpolation, key_data.ease);
                egui::ComboBox::from_id_salt("key_interp").selected_text(interpolation.name()).show_ui(ui, |ui| {
                    for i in INTERPOLATIONS {
                        ui.selectable_value(&mut interpolation, i, i.name());
                    }
                });
                egui::ComboBox::from_id_salt("key_ease").selected_text(format!("ease {}", ease.name())).show_ui(
                    ui,
                    |ui| {
                        for e in EASES {
                            ui.selectable_value(&mut ease, e, e.name());
                        }
                    },
                );
                if (interpolation, ease) != (key_data.interpolation, key_data.ease) {
                    commands.push(Command::SetKeyShape { key: k, interpolation, ease });
                }
                ui.label(format!("key {} of {} at {:.3} s", k + 1, tl.keys.len(), key_data.t_secs));
            }
            None => {
                ui.label(format!("{} keys; edits at the playhead create a key", tl.keys.len()));
            }
        }
    });
}

/// The keys as diamonds on a strip the width of the scrubber; a click jumps to a key.
fn keys_strip_ui(ui: &mut egui::Ui, state: &ViewerState, d: f64, playhead: f64, commands: &mut Vec<Command>) {
    let Some(tl) = &state.scene.timeline else { return };
    let width = ui.available_width().max(50.0);
    let (rect, response) = ui.allocate_exact_size(egui::vec2(width, 18.0), Sense::click());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(30));
    let x_of = |t: f64| rect.left() + 8.0 + (rect.width() - 16.0) * (t / d).clamp(0.0, 1.0) as f32;
    for key in &tl.keys {
        let c = egui::pos2(x_of(key.t_secs), rect.center().y);
        let r = 5.0;
        let at = (key.t_secs - playhead).abs() <= crate::scene::timeline::KEY_TIME_TOL_SECS;
        let fill = if at { Color32::from_rgb(255, 200, 80) } else { Color32::from_rgb(170, 170, 190) };
        painter.add(egui::Shape::convex_polygon(
            vec![c + egui::vec2(0.0, -r), c + egui::vec2(r, 0.0), c + egui::vec2(0.0, r), c + egui::vec2(-r, 0.0)],
            fill,
            Stroke::NONE,
        ));
    }
    let x = x_of(playhead);
    painter.line_segment(
        [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
        Stroke::new(2.0, Color32::from_rgb(255, 110, 90)),
    );
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        // The nearest key within 8 px, else the time under the cursor.
        let nearest =
            tl.keys.iter().map(|k| ((x_of(k.t_secs) - pos.x).abs(), k.t_secs)).min_by(|a, b| a.0.total_cmp(&b.0));
        let t = match nearest {
            Some((dx, t)) if dx <= 8.0 => t,
            _ => (((pos.x - rect.left() - 8.0) / (rect.width() - 16.0)).clamp(0.0, 1.0) as f64) * d,
        };
        commands.push(Command::SetTime(t));
    }
}
