//! The timeline panel, along the bottom of the whole window: play / pause, the time, speed,
//! loop mode, duration; the scrubber (press or drag anywhere on it to seek); the keys drawn on a
//! strip under it (click one to jump to it, drag one to move it in time); add / update / delete
//! the key at the playhead, and the interpolation and ease of the segment that starts at that
//! key. Like every `*_ui` function it only reads the state and emits commands.
//!
//! The scrubber and the key strip map time to x through one [`TimeTrack`] over the same span,
//! so that the playhead on the strip stands under the scrubber's handle. Scrubbed times snap to
//! frame times at the record form's frame rate ([`snap_time`]; Shift scrubs freely), so that
//! the playhead lands on frames a recording writes. (The scrubber was an egui slider: its
//! "smart aim" picked round-looking values such as 2.010 s, it sensed drags only, so that a
//! click whose press and release came within one frame did not seek, and its rail did not line
//! up with the strip below.)

use egui::{Color32, Sense, Stroke};

use crate::scene::timeline::{Ease, Interpolation, LoopMode};

use super::super::command::Command;
use super::super::state::ViewerState;

const INTERPOLATIONS: [Interpolation; 3] = [Interpolation::Hold, Interpolation::Linear, Interpolation::CatmullRom];
const EASES: [Ease; 4] = [Ease::None, Ease::In, Ease::Out, Ease::InOut];
const LOOP_MODES: [LoopMode; 3] = [LoopMode::Once, LoopMode::Loop, LoopMode::PingPong];

/// Space kept free at each end of a track (points), so that a handle or a key at either end
/// is drawn whole inside it.
pub const TRACK_INSET: f32 = 8.0;
/// The scrubber's height and its handle's radius (points).
pub const SCRUBBER_HEIGHT: f32 = 18.0;
pub const HANDLE_RADIUS: f32 = 6.0;
/// The scrubber's handle and the playhead line on the key strip.
pub const PLAYHEAD_COLOR: Color32 = Color32::from_rgb(255, 110, 90);
/// The Play / Pause button's width (points): one width for both words, so that what follows
/// it in the row does not move when playback starts or stops.
pub const PLAY_BUTTON_WIDTH: f32 = 56.0;

/// Where times of a `duration_secs` timeline lie along a track: time 0 at `left`, the end at
/// `right` (points). The scrubber and the key strip share it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeTrack {
    pub left: f32,
    pub right: f32,
    pub duration_secs: f64,
}

impl TimeTrack {
    /// The track inside a widget spanning `x` (points), [`TRACK_INSET`] from each end.
    pub fn new(x: egui::Rangef, duration_secs: f64) -> Self {
        let inner = x.shrink(TRACK_INSET.min(0.25 * x.span()));
        Self { left: inner.min, right: inner.max.max(inner.min + 1.0), duration_secs: duration_secs.max(1e-3) }
    }

    /// The x of time `t_secs` (clamped to the timeline).
    pub fn x_of(&self, t_secs: f64) -> f32 {
        let f = (t_secs / self.duration_secs).clamp(0.0, 1.0) as f32;
        self.left + (self.right - self.left) * f
    }

    /// The time at `x` (clamped to the timeline).
    pub fn time_of(&self, x: f32) -> f64 {
        ((x - self.left) / (self.right - self.left)).clamp(0.0, 1.0) as f64 * self.duration_secs
    }
}

/// The time a scrub at `t_secs` lands on: the nearest frame time k / `fps`, within
/// `0..=duration_secs`; with `free` (Shift held), `t_secs` itself. A frame rate that is not a
/// positive number leaves the time free.
pub fn snap_time(t_secs: f64, fps: f64, duration_secs: f64, free: bool) -> f64 {
    let t = if free || !(fps.is_finite() && fps > 0.0) { t_secs } else { (t_secs * fps).round() / fps };
    t.clamp(0.0, duration_secs.max(0.0))
}

/// The time a press or drag at `x` on `track` seeks to (snapped unless `free`), as
/// [`snap_time`] at the record form's frame rate.
pub fn seek_time(state: &ViewerState, track: &TimeTrack, x: f32, free: bool) -> f64 {
    snap_time(track.time_of(x), state.record_form.fps, track.duration_secs, free)
}

pub fn timeline_ui(ui: &mut egui::Ui, state: &ViewerState, commands: &mut Vec<Command>) {
    let Some(tl) = &state.scene.timeline else { return };
    let d = tl.duration_secs.max(1e-3);
    let playhead = state.playhead_secs();
    ui.horizontal(|ui| {
        let playing = state.playback.playing;
        let play = egui::Button::new(if playing { "Pause" } else { "Play" });
        if ui.add_sized([PLAY_BUTTON_WIDTH, ui.spacing().interact_size.y], play).on_hover_text("Space").clicked() {
            commands.push(Command::SetPlaying(!playing));
        }
        if ui.button("|<").on_hover_text("to the start").clicked() {
            commands.push(Command::SetTime(0.0));
        }
        // The time as a number to type or drag. Only the user moves time from here: a widget
        // that wrote back its (clamped, rounded) value every frame sent the previous frame's
        // time after each playback tick, and playback ran at about half speed.
        let mut t = playhead;
        let field = ui.add(
            egui::DragValue::new(&mut t).range(0.0..=d).speed(d / 500.0).max_decimals(3).prefix("t ").suffix(" s"),
        );
        let by_user = field.dragged() || field.has_focus() || field.lost_focus();
        if field.changed() && by_user && t != playhead && t.is_finite() {
            commands.push(Command::SetTime(t.clamp(0.0, d)));
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
    // The scrubber and the key strip span the panel's width, one above the other, on one track.
    let width = ui.available_width().max(50.0);
    scrubber_ui(ui, state, width, d, playhead, commands);
    keys_strip_ui(ui, state, width, d, playhead, commands);
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

/// The scrubber: a rail with a handle at the playhead. A press anywhere on it seeks there, and
/// a drag scrubs, both to frame times unless Shift is held.
fn scrubber_ui(ui: &mut egui::Ui, state: &ViewerState, width: f32, d: f64, playhead: f64, commands: &mut Vec<Command>) {
    let (rect, response) = ui.allocate_exact_size(egui::vec2(width, SCRUBBER_HEIGHT), Sense::click_and_drag());
    let track = TimeTrack::new(rect.x_range(), d);
    // On the press itself (not only once a drag starts or the button is released), and only
    // while the pointer holds it: playback moves the handle otherwise.
    if (response.is_pointer_button_down_on() || response.clicked())
        && let Some(pos) = response.interact_pointer_pos()
    {
        let free = ui.input(|i| i.modifiers.shift);
        let t = seek_time(state, &track, pos.x, free);
        if t != playhead {
            commands.push(Command::SetTime(t));
        }
    }
    let painter = ui.painter_at(rect);
    let rail = egui::Rect::from_x_y_ranges(track.left..=track.right, rect.center().y - 2.0..=rect.center().y + 2.0);
    painter.rect_filled(rail, 2.0, Color32::from_gray(60));
    let x = track.x_of(playhead);
    painter.rect_filled(egui::Rect::from_x_y_ranges(track.left..=x, rail.y_range()), 2.0, Color32::from_gray(120));
    painter.circle_filled(egui::pos2(x, rect.center().y), HANDLE_RADIUS, PLAYHEAD_COLOR);
    response.on_hover_text("press or drag to seek (to frame times at the record form's rate; Shift: freely)");
}

/// The keys as diamonds on a strip under the scrubber. A click jumps to a key (or to the time
/// under the cursor); a drag that starts on a key moves it along the strip (one undo step, kept
/// between its neighbours); a drag elsewhere scrubs. Times snap to frames unless Shift is held.
fn keys_strip_ui(
    ui: &mut egui::Ui,
    state: &ViewerState,
    width: f32,
    d: f64,
    playhead: f64,
    commands: &mut Vec<Command>,
) {
    let Some(tl) = &state.scene.timeline else { return };
    let (rect, response) = ui.allocate_exact_size(egui::vec2(width, 22.0), Sense::click_and_drag());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(30));
    let track = TimeTrack::new(rect.x_range(), d);
    let x_of = |t: f64| track.x_of(t);
    let free = ui.input(|i| i.modifiers.shift);
    let t_of = |x: f32| seek_time(state, &track, x, free);
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
    painter.line_segment([egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())], Stroke::new(2.0, PLAYHEAD_COLOR));
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
