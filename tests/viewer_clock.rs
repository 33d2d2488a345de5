//! Playback speed: at ×1 scene time follows the clock within 2 % over 10 s at 5, 30 and 120
//! frames per second. Each frame runs as the viewer runs it, with an injected clock: the
//! playback clock turns the reading into a `Tick`, the real egui panels (timeline included) run
//! headless on the state and push their commands, and the state applies them all. (The
//! timeline slider used to write its rounded value back every frame, undoing the tick: scene
//! time advanced about half a second per wall second.)

use std::cell::Cell;

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::clock::{Clock, PlaybackClock};
use nlifs::viewer::command::Command;
use nlifs::viewer::jobs::JobView;
use nlifs::viewer::state::ViewerState;

/// A clock the test steps by hand.
#[derive(Default)]
struct ManualClock(Cell<f64>);

impl Clock for ManualClock {
    fn now_secs(&self) -> f64 {
        self.0.get()
    }
}

/// Plays twist-anim at ×1 for `wall_secs` at `fps` through the panels; returns scene seconds
/// played and every command the panels sent.
fn play(fps: f64, wall_secs: f64) -> (f64, Vec<Command>) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/twist-anim.toml");
    let mut state = ViewerState::new(Scene::load(&path).unwrap(), Some(path), LiveSettings::default());
    // A long timeline, so that 10 s do not wrap.
    state.apply([Command::SetDuration(60.0), Command::SetLoopMode(nlifs::scene::timeline::LoopMode::Once)]);
    state.apply([Command::SetPlaying(true)]);
    assert!(state.playback.playing);
    let t0 = state.t_secs;
    let ctx = egui::Context::default();
    let clock = ManualClock::default();
    let mut playback = PlaybackClock::default();
    let jobs = JobView::default();
    let mut sent = Vec::new();
    let frames = (wall_secs * fps).round() as usize;
    for k in 0..=frames {
        clock.0.set(k as f64 / fps);
        let mut commands = Vec::new();
        if let Some(dt_secs) = playback.advance(clock.now_secs(), state.playback.playing) {
            commands.push(Command::Tick { dt_secs });
        }
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1280.0, 720.0))),
            time: Some(clock.now_secs()),
            ..Default::default()
        };
        let mut panel_commands = Vec::new();
        let _ = ctx.run_ui(input, |ui| {
            nlifs::viewer::ui::panels_ui(ui, &state, &jobs, 1.0, &mut panel_commands);
        });
        sent.extend(panel_commands.iter().cloned());
        commands.extend(panel_commands);
        state.apply(commands);
    }
    (state.t_secs - t0, sent)
}

#[test]
fn playback_at_x1_follows_the_clock_at_5_30_and_120_fps() {
    for fps in [5.0, 30.0, 120.0] {
        let (played, sent) = play(fps, 10.0);
        let rate = played / 10.0;
        eprintln!("{fps} fps: {played:.4} scene s in 10 wall s (×{rate:.4})");
        assert!((rate - 1.0).abs() <= 0.02, "{fps} fps: scene time ran at ×{rate:.4}");
        // Idle panels send nothing that moves time or edits.
        assert!(
            sent.iter().all(|c| matches!(c, Command::SetViewRect { .. })),
            "{fps} fps: the panels sent {:?}",
            sent.iter().find(|c| !matches!(c, Command::SetViewRect { .. }))
        );
    }
}

#[test]
fn a_stall_is_not_played_through_and_a_pause_is_not_counted() {
    let mut p = PlaybackClock::default();
    assert_eq!(p.advance(0.0, true), Some(0.0));
    assert_eq!(p.advance(0.2, true), Some(0.2));
    // A 3 s stall advances at most the cap.
    assert_eq!(p.advance(3.2, true), Some(PlaybackClock::MAX_STEP_SECS));
    // Paused for 5 s: playing again starts from 0.
    assert_eq!(p.advance(4.0, false), None);
    assert_eq!(p.advance(9.0, true), Some(0.0));
    assert_eq!(p.advance(9.1, true).map(|d| (d * 1e9).round() / 1e9), Some(0.1));
}
