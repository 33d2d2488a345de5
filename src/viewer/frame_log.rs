//! `--log-fps`: frame rate, process CPU per frame and the wall time of each stage of a frame,
//! printed to stderr once a second (measuring the viewer under Xvfb).

use crate::platform::Instant;

use crate::live::ChaosRoute;

/// Wall time of a frame's stages summed over the frames since the last report, and the process
/// CPU time since then (`--log-fps`).
/// The GPU work is asynchronous: on lavapipe its cost shows in `acquire` (waiting for a free
/// swapchain image, i.e. for the frame before last) and in `present`.
#[derive(Default)]
pub(super) struct FrameLog {
    pub(super) since: Option<Instant>,
    /// Process CPU seconds (all threads, lavapipe's included) at `since`.
    pub(super) cpu_since: f64,
    pub(super) frames: u32,
    pub(super) splats: u64,
    /// egui's `run_ui` (the panels' layout), plus applying commands.
    pub(super) ui_secs: f64,
    pub(super) acquire_secs: f64,
    /// Chaos game (on the CPU route: the whole CPU chaos game and its upload), resolve and egui
    /// recording: encoding, tessellation, buffer uploads, submit.
    pub(super) record_secs: f64,
    pub(super) present_secs: f64,
    /// Cached egui layer renders so far (total) and at the last report.
    pub(super) ui_renders: u64,
    pub(super) ui_renders_reported: u64,
    /// Where the chaos game ran (set every frame).
    pub(super) route: ChaosRoute,
}

impl FrameLog {
    /// Prints and restarts once a second has passed.
    pub(super) fn report(&mut self, now: Instant) {
        let Some(since) = self.since else {
            *self = Self { since: Some(now), cpu_since: crate::gpu::bench::process_cpu_secs(), ..Self::default() };
            return;
        };
        let secs = (now - since).as_secs_f64();
        if secs < 1.0 {
            return;
        }
        let n = self.frames.max(1) as f64;
        let cpu = crate::gpu::bench::process_cpu_secs();
        eprintln!(
            "viewer: {:.1} fps, {:.1} M points/s, chaos game on the {} ({}), process CPU {:.0} ms/frame, egui re-rendered in {} frames; wall ms/frame: ui {:.1}, acquire {:.1}, record+submit {:.1}, present {:.1}",
            self.frames as f64 / secs,
            self.splats as f64 / secs / 1e6,
            self.route.name(),
            self.route.reason,
            1e3 * (cpu - self.cpu_since) / n,
            self.ui_renders - self.ui_renders_reported,
            1e3 * self.ui_secs / n,
            1e3 * self.acquire_secs / n,
            1e3 * self.record_secs / n,
            1e3 * self.present_secs / n,
        );
        *self = Self {
            since: Some(now),
            cpu_since: cpu,
            ui_renders: self.ui_renders,
            ui_renders_reported: self.ui_renders,
            ..Self::default()
        };
    }
}
