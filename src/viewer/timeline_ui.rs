//! The timeline panel, along the bottom of the whole window: play / pause, scrub, speed, loop
//! mode, duration, the keys drawn on a strip under the scrubber (click one to jump to it, drag
//! one to move it in time), add / update / delete the key at the playhead, and the
//! interpolation and ease of the segment that starts at that key. Like every `*_ui` function
//! it only reads the state and emits commands.

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
        // Only the user moves time from here: a slider that wrote back its (clamped, rounded
        // to 3 decimals) value every frame sent the previous frame's time after each playback
        // tick, and playback ran at about half speed.
        // The scrubber takes the rest of the row: the panel spans the window.
        ui.spacing_mut().slider_width = (ui.available_width() - 110.0).max(120.0);
        let mut t = playhead;
        let scrub = ui.add(super::widgets::slider(&mut t, 0.0..=d).suffix(" s").max_decimals(3).text("t"));
        let by_user = scrub.dragged() || scrub.is_pointer_button_down_on() || scrub.has_focus() || scrub.clicked();
        if scrub.changed() && by_user && t != playhead {
            commands.push(Command::SetTime(t));
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

/// The keys as diamonds on a strip the width of the timeline panel. A click jumps to a key (or
/// to the time under the cursor); a drag that starts on a key moves it along the strip (one
/// undo step, kept between its neighbours); a drag elsewhere scrubs.
fn keys_strip_ui(ui: &mut egui::Ui, state: &ViewerState, d: f64, playhead: f64, commands: &mut Vec<Command>) {
    let Some(tl) = &state.scene.timeline else { return };
    let width = ui.available_width().max(50.0);
    let (rect, response) = ui.allocate_exact_size(egui::vec2(width, 22.0), Sense::click_and_drag());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(30));
    let x_of = |t: f64| rect.left() + 8.0 + (rect.width() - 16.0) * (t / d).clamp(0.0, 1.0) as f32;
    let t_of = |x: f32| (((x - rect.left() - 8.0) / (rect.width() - 16.0)).clamp(0.0, 1.0) as f64) * d;
    // The nearest key within 8 px of `x`.
    let key_near = |x: f32| {
        tl.keys
            .iter()
            .enumerate()
            .map(|(k, key)| ((x_of(key.t_secs) - x).abs(), k))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .filter(|(dx, _)| *dx <= 8.0)
            .map(|(_, k)| k)
    };
    // Which key the running drag holds (None: it scrubs), kept by egui between frames.
    let held_id = response.id.with("held_key");
    if response.drag_started()
        && let Some(pos) = response.interact_pointer_pos()
    {
        let press_x = ui.input(|i| i.pointer.press_origin()).map_or(pos.x, |p| p.x);
        let held: Option<usize> = key_near(press_x);
        ui.data_mut(|m| m.insert_temp(held_id, held));
    }
    let held: Option<usize> = ui.data(|m| m.get_temp(held_id)).flatten();
    if response.dragged()
        && let Some(pos) = response.interact_pointer_pos()
    {
        match held {
            Some(key) => commands.push(Command::MoveKey { key, t_secs: t_of(pos.x) }),
            None => commands.push(Command::SetTime(t_of(pos.x))),
        }
    }
    if response.drag_stopped() {
        ui.data_mut(|m| m.remove::<Option<usize>>(held_id));
        if held.is_some() {
            commands.push(Command::EndGesture);
        }
    }
    for (k, key) in tl.keys.iter().enumerate() {
        let c = egui::pos2(x_of(key.t_secs), rect.center().y);
        let r = if held == Some(k) { 7.0 } else { 5.0 };
        let at = (key.t_secs - playhead).abs() <= crate::scene::timeline::KEY_TIME_TOL_SECS;
        let fill = if held == Some(k) {
            Color32::WHITE
        } else if at {
            Color32::from_rgb(255, 200, 80)
        } else {
            Color32::from_rgb(170, 170, 190)
        };
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
    if let Some(key) = held {
        let t = tl.keys.get(key).map_or(0.0, |k| k.t_secs);
        painter.text(
            egui::pos2(x_of(t) + 10.0, rect.top()),
            egui::Align2::LEFT_TOP,
            format!("{t:.3} s"),
            egui::FontId::proportional(11.0),
            Color32::WHITE,
        );
    }
    let response =
        response.on_hover_text("click: jump to a key or a time · drag a key: move it · drag elsewhere: scrub");
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        let t = key_near(pos.x).map_or_else(|| t_of(pos.x), |k| tl.keys[k].t_secs);
        commands.push(Command::SetTime(t));
    }
}
