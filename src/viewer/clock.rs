//! How playback turns wall-clock time into scene time. The event loop reads a [`Clock`] once per
//! frame and [`PlaybackClock::advance`] says by how much scene time moves ([`Command::Tick`]),
//! so that ×1 is wall-clock time at any frame rate. The clock is injected: the viewer passes
//! [`WallClock`], the tests a clock they step by hand (`tests/viewer_clock.rs`).
//!
//! A frame interval is capped at [`PlaybackClock::MAX_STEP_SECS`] so that a stall (a window
//! drag, a debugger) does not jump the animation; the cap sits above the slowest frame rate the
//! viewer must keep up with (5 fps on a software adapter), so that it never slows normal play.
//!
//! [`Command::Tick`]: super::Command::Tick

use crate::platform::Instant;

/// A source of monotonic seconds.
pub trait Clock {
    fn now_secs(&self) -> f64;
}

/// The process's monotonic clock, in seconds since the clock was made.
#[derive(Clone, Copy, Debug)]
pub struct WallClock {
    start: Instant,
}

impl Default for WallClock {
    fn default() -> Self {
        Self { start: Instant::now() }
    }
}

impl Clock for WallClock {
    fn now_secs(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

/// Scene-time steps from clock readings while the timeline plays.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlaybackClock {
    /// The reading at the last frame that played.
    last_secs: Option<f64>,
}

impl PlaybackClock {
    /// The longest step one frame may advance (a stall beyond it is not played through).
    pub const MAX_STEP_SECS: f64 = 0.5;

    /// The wall-clock seconds to advance at this frame (`now_secs` from the clock): the time
    /// since the previous playing frame, capped; None while not playing (the next start then
    /// advances 0, not the time spent paused).
    pub fn advance(&mut self, now_secs: f64, playing: bool) -> Option<f64> {
        if !playing {
            self.last_secs = None;
            return None;
        }
        let dt_secs = self.last_secs.map_or(0.0, |t| (now_secs - t).clamp(0.0, Self::MAX_STEP_SECS));
        self.last_secs = Some(now_secs);
        Some(dt_secs)
    }
}
