//! When the viewer draws: every frame while the picture changes, and otherwise only when input,
//! a timer or a wake-up asks for a frame, so that a converged, untouched view costs nothing
//! (docs/viewer.md, "Drawing, memory and idle"). The event loop (`mod.rs`) asks [`App::redraw`]
//! after each batch of events and sleeps until the instant it gives or [`App::next_wake`];
//! [`App::wake`] does between frames what needs no frame.

use std::time::Duration;

use crate::platform::Instant;

use super::{App, Command, Gfx, TOAST_SECS, recovery};
use crate::viewer::clock::Clock;

/// When the window needs its next frame ([`App::redraw`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Redraw {
    /// Every frame: the picture changes (accumulating, playing, dragging, commands to apply).
    Continuous,
    /// At this instant (a job's progress, a toast's end, an egui animation); then again asks.
    At(Instant),
    /// Only on input or what a wake-up finds (the file changed, a dialog answered).
    OnEvent,
}

/// How often a running job's progress is redrawn, and how often a wake-up looks for a file
/// dialog's answer and a changed scene file.
const JOB_REDRAW: Duration = Duration::from_millis(100);
const DIALOG_POLL: Duration = Duration::from_millis(100);
const FILE_POLL: Duration = Duration::from_millis(500);

impl App {
    /// What the event loop does between frames, drawing nothing: looks for a changed scene file
    /// and a file dialog's answer (commands for the next frame) and writes the recovery file
    /// when it is due.
    pub(super) fn wake(&mut self) {
        if self.last_poll.elapsed() >= FILE_POLL {
            self.last_poll = Instant::now();
            if let Some(c) = self.state.poll_file() {
                self.commands.push(c);
            }
        }
        self.commands.extend(self.dialogs.poll());
        let now_secs = self.clock.now_secs();
        if now_secs - self.last_autosave_secs >= recovery::AUTOSAVE_SECS {
            self.last_autosave_secs = now_secs;
            // Writes a file when there are unsaved edits; nothing on screen changes.
            self.state.apply([Command::Autosave]);
        }
    }

    /// When the next frame is needed: a converged, untouched view is not redrawn (the last
    /// frame stays on screen) until input, a timer or a wake-up asks for one.
    pub(super) fn redraw(&self, gfx: &Gfx, now: Instant) -> Redraw {
        let changing = self.state.playback.playing
            || self.state.edit.gesture.is_some()
            || self.drag.is_some()
            || !self.commands.is_empty()
            || !gfx.live.at_rest();
        if changing {
            return Redraw::Continuous;
        }
        let jobs = self.jobs.view.raytrace.is_some() || self.jobs.view.record.is_some();
        let job_frame = jobs.then(|| self.last_frame.map_or(now, |t| t + JOB_REDRAW));
        let toast_end = self
            .toast_shown
            .as_ref()
            .map(|(_, since)| now + Duration::from_secs_f64((since + TOAST_SECS - self.clock.now_secs()).max(0.0)));
        match [job_frame, toast_end, self.egui_repaint_at].into_iter().flatten().min() {
            Some(at) => Redraw::At(at),
            None => Redraw::OnEvent,
        }
    }

    /// The next wake-up (file and dialog polling, the autosave timer).
    pub(super) fn next_wake(&self, now: Instant) -> Instant {
        let poll = if self.dialogs.pending() { DIALOG_POLL } else { FILE_POLL };
        let autosave_secs = (self.last_autosave_secs + recovery::AUTOSAVE_SECS - self.clock.now_secs()).max(0.0);
        (self.last_poll + FILE_POLL).min(now + poll).min(now + Duration::from_secs_f64(autosave_secs))
    }
}
