//! The timeline panel's scrubber, tested headless through the real panels with injected input:
//! a click on the scrubber seeks there, also one shorter than a frame (the egui slider it
//! replaced sensed drags only, and a press and release within one frame did nothing), scrubbed times snap to frame times at the record form's frame rate (Shift scrubs
//! freely; the slider's "smart aim" landed on times such as 2.010 s), and the playhead on the
//! key strip stands exactly under the scrubber's handle.

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::Command;
use nlifs::viewer::jobs::JobView;
use nlifs::viewer::state::ViewerState;
use nlifs::viewer::ui::timeline::{HANDLE_RADIUS, PLAYHEAD_COLOR, TimeTrack, snap_time};

fn twist_anim() -> ViewerState {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/twist-anim.toml");
    ViewerState::new(Scene::load(&path).unwrap(), Some(path), LiveSettings::default())
}

/// One frame of the panels with `events`; the commands they sent and what they painted.
fn frame(
    ctx: &egui::Context,
    state: &ViewerState,
    events: Vec<egui::Event>,
    shift: bool,
) -> (Vec<Command>, Vec<egui::Shape>) {
    let modifiers = egui::Event::ModifiersChanged(egui::Modifiers { shift, ..Default::default() });
    let input = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1280.0, 720.0))),
        events: std::iter::once(modifiers).chain(events).collect(),
        ..Default::default()
    };
    let mut commands = Vec::new();
    let output = ctx.run_ui(input, |ui| {
        nlifs::viewer::ui::panels_ui(ui, state, &JobView::default(), 1.0, &mut commands);
    });
    let mut shapes = Vec::new();
    fn flatten(shape: egui::Shape, out: &mut Vec<egui::Shape>) {
        match shape {
            egui::Shape::Vec(v) => v.into_iter().for_each(|s| flatten(s, out)),
            s => out.push(s),
        }
    }
    for clipped in output.shapes {
        flatten(clipped.shape, &mut shapes);
    }
    (commands, shapes)
}

/// The scrubber's handle (its centre) and the key strip's playhead line (x, top y, bottom y).
fn playhead_marks(shapes: &[egui::Shape]) -> (egui::Pos2, (f32, f32, f32)) {
    let handles: Vec<egui::Pos2> = shapes
        .iter()
        .filter_map(|s| match s {
            egui::Shape::Circle(c) if c.fill == PLAYHEAD_COLOR && c.radius == HANDLE_RADIUS => Some(c.center),
            _ => None,
        })
        .collect();
    let lines: Vec<(f32, f32, f32)> = shapes
        .iter()
        .filter_map(|s| match s {
            egui::Shape::LineSegment { points: [a, b], stroke } if stroke.color == PLAYHEAD_COLOR && a.x == b.x => {
                Some((a.x, a.y.min(b.y), a.y.max(b.y)))
            }
            _ => None,
        })
        .collect();
    assert_eq!((handles.len(), lines.len()), (1, 1), "one handle and one playhead: {handles:?} {lines:?}");
    (handles[0], lines[0])
}

/// The panels laid out at scene time `t` (twice, so that egui's layout has settled).
fn marks_at(ctx: &egui::Context, state: &mut ViewerState, t: f64) -> (egui::Pos2, (f32, f32, f32)) {
    state.apply([Command::SetTime(t)]);
    frame(ctx, state, Vec::new(), false);
    let (commands, shapes) = frame(ctx, state, Vec::new(), false);
    assert!(commands.iter().all(|c| matches!(c, Command::SetViewRect { .. })), "an idle panel sent {commands:?}");
    playhead_marks(&shapes)
}

/// A press and release of the primary button at `pos`, in frames of their own or, `quick`, in
/// one frame (a click shorter than a frame: the viewer's frames are slow on a software
/// renderer, and the slider this replaced missed such clicks); every command sent.
fn click(ctx: &egui::Context, state: &ViewerState, pos: egui::Pos2, shift: bool, quick: bool) -> Vec<Command> {
    let modifiers = egui::Modifiers { shift, ..Default::default() };
    let button = |pressed| egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed, modifiers };
    let frames = if quick {
        vec![vec![egui::Event::PointerMoved(pos)], vec![button(true), button(false)], vec![]]
    } else {
        vec![vec![egui::Event::PointerMoved(pos)], vec![button(true)], vec![button(false)]]
    };
    let mut sent = Vec::new();
    for events in frames {
        sent.extend(frame(ctx, state, events, shift).0);
    }
    sent.retain(|c| !matches!(c, Command::SetViewRect { .. }));
    sent
}

#[test]
fn scrubbed_times_snap_to_frames_unless_free() {
    for fps in [24.0, 30.0, 12.5, 59.94] {
        for k in 0..200 {
            let t = k as f64 * 0.0317 + 0.0049;
            let snapped = snap_time(t, fps, 10.0, false);
            let frame = snapped * fps;
            assert!((frame - frame.round()).abs() < 1e-9, "{t} at {fps} fps: {snapped} is not a frame time");
            assert!((snapped - t).abs() <= 0.5 / fps + 1e-12, "{t} at {fps} fps: {snapped} is not the nearest frame");
            assert_eq!(snap_time(t, fps, 10.0, true), t, "Shift: free");
        }
    }
    // Inside the timeline, and a rate that is no rate leaves the time free.
    assert_eq!(snap_time(4.2, 24.0, 4.0, false), 4.0);
    assert_eq!(snap_time(-0.3, 24.0, 4.0, true), 0.0);
    assert_eq!(snap_time(1.234, 0.0, 4.0, false), 1.234);
    // The mapping from x to time and back.
    let track = TimeTrack::new(egui::Rangef::new(100.0, 900.0), 4.0);
    for k in 0..=40 {
        let t = k as f64 * 0.1;
        assert!((track.time_of(track.x_of(t)) - t).abs() < 1e-5, "{t}");
    }
    assert_eq!((track.x_of(0.0), track.x_of(4.0)), (track.left, track.right));
    assert!(track.left > 100.0 && track.right < 900.0, "inset, so that a handle at either end is whole");
}

#[test]
fn the_key_strips_playhead_stands_under_the_scrubbers_handle() {
    let ctx = egui::Context::default();
    let mut s = twist_anim();
    let d = s.scene.timeline.as_ref().unwrap().duration_secs;
    let mut xs = Vec::new();
    for t in [0.0, 0.37 * d, 0.5 * d, 0.93 * d] {
        let (handle, (line_x, _, _)) = marks_at(&ctx, &mut s, t);
        assert!((handle.x - line_x).abs() < 1e-3, "t = {t}: handle at x {} but the playhead at {line_x}", handle.x);
        xs.push(handle.x);
    }
    // Linear in time along one track.
    let (x0, x_half) = (xs[0], xs[2]);
    let track = TimeTrack { left: x0, right: 2.0 * x_half - x0, duration_secs: d };
    assert!((track.x_of(0.37 * d) - xs[1]).abs() < 1e-2 && (track.x_of(0.93 * d) - xs[3]).abs() < 1e-2, "{xs:?}");
    // Playing (Pause in place of Play) moves neither.
    s.apply([Command::SetTime(0.37 * d), Command::SetPlaying(true)]);
    frame(&ctx, &s, Vec::new(), false);
    let (handle, _) = playhead_marks(&frame(&ctx, &s, Vec::new(), false).1);
    assert!((handle.x - xs[1]).abs() < 1e-3);
}

#[test]
fn a_press_on_the_scrubber_or_the_strip_seeks_there() {
    let ctx = egui::Context::default();
    let mut s = twist_anim();
    let d = s.scene.timeline.as_ref().unwrap().duration_secs;
    let (h0, _) = marks_at(&ctx, &mut s, 0.0);
    let (h_half, (_, strip_top, strip_bottom)) = marks_at(&ctx, &mut s, 0.5 * d);
    let track = TimeTrack { left: h0.x, right: 2.0 * h_half.x - h0.x, duration_secs: d };
    let fps = s.record_form.fps;
    // A time between frames, away from the keys (twist-anim keys whole seconds).
    let target = 0.7 * d + 0.2 / fps;
    let x = track.x_of(target);
    let expected = snap_time(track.time_of(x), fps, d, false);
    for quick in [false, true] {
        let sent = click(&ctx, &s, egui::pos2(x, h0.y), false, quick);
        assert!(sent.contains(&Command::SetTime(expected)), "a click at x {x} (quick: {quick}) sent {sent:?}");
    }
    assert!((expected * fps - (expected * fps).round()).abs() < 1e-9);
    // With Shift: the time under the pointer itself.
    let sent = click(&ctx, &s, egui::pos2(x, h0.y), true, false);
    let free = sent
        .iter()
        .find_map(|c| if let Command::SetTime(t) = c { Some(*t) } else { None })
        .unwrap_or_else(|| panic!("{sent:?}"));
    assert!((free - target).abs() < 2e-3 * d && free != expected, "{free} for {target}");
    // A click on the key strip, off the keys, seeks to the same snapped time.
    let sent = click(&ctx, &s, egui::pos2(x, 0.5 * (strip_top + strip_bottom)), false, true);
    assert!(sent.contains(&Command::SetTime(expected)), "{sent:?}");
}

/// The panels' egui output at scene time `t` split as the viewer's cached layers split it.
fn layers_at(
    ctx: &egui::Context,
    state: &mut ViewerState,
    t: f64,
) -> (Vec<egui::epaint::ClippedShape>, Vec<egui::epaint::ClippedShape>) {
    state.apply([Command::SetTime(t)]);
    let mut out = None;
    for _ in 0..2 {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1280.0, 720.0))),
            ..Default::default()
        };
        let mut commands = Vec::new();
        let mut layout = None;
        let output = ctx.run_ui(input, |ui| {
            layout = Some(nlifs::viewer::ui::panels_ui(ui, state, &JobView::default(), 1.0, &mut commands));
        });
        let strip = layout.and_then(|l| l.timeline).expect("twist-anim has a timeline strip");
        out = Some(nlifs::viewer::ui::layer::split_strip(output.shapes, strip));
    }
    out.unwrap()
}

/// The timeline strip gets a cached layer of its own, which holds what playing changes every
/// frame (the time field, the scrubber's handle and the key strip's playhead), so that the
/// viewer re-renders the side panel only a few times a second while playing.
#[test]
fn the_strip_has_a_layer_of_its_own() {
    let ctx = egui::Context::default();
    let mut state = twist_anim();
    let (_, strip_1) = layers_at(&ctx, &mut state, 1.0);
    let (panels_2, strip_2) = layers_at(&ctx, &mut state, 2.0);
    assert!(!strip_1.is_empty(), "the strip got a layer of its own");
    assert!(strip_1 != strip_2, "the strip shows the time");
    let flat = |shapes: Vec<egui::epaint::ClippedShape>| {
        let mut out = Vec::new();
        fn flatten(shape: egui::Shape, out: &mut Vec<egui::Shape>) {
            match shape {
                egui::Shape::Vec(v) => v.into_iter().for_each(|s| flatten(s, out)),
                s => out.push(s),
            }
        }
        shapes.into_iter().for_each(|c| flatten(c.shape, &mut out));
        out
    };
    // Both marks of the playhead are in the strip's layer, none in the panels'.
    playhead_marks(&flat(strip_2));
    let in_panels = flat(panels_2).into_iter().filter(|s| match s {
        egui::Shape::Circle(c) => c.fill == PLAYHEAD_COLOR,
        egui::Shape::LineSegment { stroke, .. } => stroke.color == PLAYHEAD_COLOR,
        _ => false,
    });
    assert_eq!(in_panels.count(), 0, "the playhead is painted in the strip's layer only");
    // The time field is in the strip.
    let texts = |shapes: &[egui::Shape]| -> Vec<String> {
        shapes
            .iter()
            .filter_map(|s| match s {
                egui::Shape::Text(t) => Some(t.galley.text().to_string()),
                _ => None,
            })
            .collect()
    };
    let (_, strip_t) = layers_at(&ctx, &mut state, 2.5);
    assert!(texts(&flat(strip_t)).iter().any(|t| t.contains("2.5")), "the strip shows t = 2.5 s");
}
