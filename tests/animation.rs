//! Animation: timeline parsing and interpolation through `Scene::at`, camera and render at a
//! time, loop modes, parameter versus point interpolation, and recording determinism / resume.

mod common;

use glam::DVec3;
use nlifs::model::Map;
use nlifs::scene::Scene;
use nlifs::scene::timeline::{self, ChannelKey, Ease, Interpolation};

/// A 3D scene on the grid [-1, 0, 1]³ with one builder function `f1` (a twist about y over
/// the full height) and one grid function `f2` whose keys hold the same twist resolved to
/// points, so the two interpolations can be compared.
fn twist_scene(interpolation: &str, loop_mode: &str, duration: f64) -> String {
    let twist_points = |deg: f64| -> String {
        let mut s = String::from("[");
        for x in [-1.0, 0.0, 1.0] {
            for y in [-1.0f64, 0.0, 1.0] {
                for z in [-1.0, 0.0, 1.0] {
                    // The builder's twist: angle grows from 0 at y = -1 to `deg` at y = 1, about y
                    // with (z, x) rotating like (x, y).
                    let a = (deg * (y + 1.0) / 2.0).to_radians();
                    let (s_, c) = a.sin_cos();
                    let (zr, xr) = (c * z - s_ * x, s_ * z + c * x);
                    s += &format!("[{xr:?}, {y:?}, {zr:?}], ");
                }
            }
        }
        s + "]"
    };
    format!(
        r#"
version = 1
[grid]
x = [-1, 0, 1]
y = [-1, 0, 1]
z = [-1, 0, 1]

[[function]]
name = "f1"
kind = "builder"
resolution = [3, 3, 3]
steps = [{{ op = "twist", axis = "y", degrees = 0 }}, {{ op = "scale", by = 0.5 }}]

[[function]]
name = "f2"
kind = "grid"
points = {p0}

[timeline]
loop = "{loop_mode}"
duration_secs = {duration:?}

[[key]]
t_secs = 0.0
interpolation = "{interpolation}"
[[key.function]]
name = "f1"
steps = [{{ op = "twist", axis = "y", degrees = 0 }}, {{ op = "scale", by = 0.5 }}]
[[key.function]]
name = "f2"
points = {p0}
[key.camera]
yaw_deg = 10

[[key]]
t_secs = 1.0
interpolation = "{interpolation}"
[[key.function]]
name = "f1"
steps = [{{ op = "twist", axis = "y", degrees = 90 }}, {{ op = "scale", by = 0.5 }}]
[[key.function]]
name = "f2"
points = {p90}
[key.camera]
yaw_deg = 50
pitch_deg = 30
[key.render]
depth_cue = 0.2
"#,
        p0 = twist_points(0.0),
        p90 = twist_points(90.0),
    )
}

fn grid_points(scene: &Scene, i: usize, t: f64) -> Vec<DVec3> {
    match &scene.at(t).functions[i].map {
        Map::Grid(g) => g.points.clone(),
        other => panic!("expected a grid map, got {other:?}"),
    }
}

#[test]
fn keys_are_hit_exactly_through_scene_at() {
    for interp in ["hold", "linear", "catmull-rom"] {
        let scene = Scene::parse(&twist_scene(interp, "once", 1.0), "test.toml").unwrap();
        let tl = scene.timeline.as_ref().unwrap();
        for key in &tl.keys {
            let def = key.function(1).unwrap();
            let nlifs::scene::spec::FunctionDef::Grid { points } = def else { panic!() };
            assert_eq!(&grid_points(&scene, 1, key.t_secs), points, "{interp} at key t={}", key.t_secs);
        }
        assert_eq!(scene.camera_at(0.0).yaw_deg, Some(10.0));
        assert_eq!(scene.camera_at(1.0).yaw_deg, Some(50.0));
        // Only one key sets pitch and depth cue: they hold everywhere.
        assert_eq!(scene.camera_at(0.0).pitch_deg, Some(30.0));
        assert_eq!(scene.render_at(0.3).depth_cue, 0.2);
    }
}

#[test]
fn twist_parameters_interpolate_on_the_circle_not_the_chord() {
    let scene = Scene::parse(&twist_scene("linear", "once", 1.0), "test.toml").unwrap();
    let ifs = scene.at(0.5);
    // The grid node (1, 1, 0) sits at the top of the twist, radius 1 from the y axis.
    let p = DVec3::new(1.0, 1.0, 0.0);
    let by_parameter = ifs.eval(0, p) / 0.5;
    let by_points = ifs.eval(1, p);
    // Parameter interpolation: a 45° rotation, exact up to rounding.
    // About y, (z, x) rotate like (x, y): x → −z.
    let expect = DVec3::new(45f64.to_radians().cos(), 1.0, -45f64.to_radians().sin());
    assert!(by_parameter.distance(expect) < 1e-12, "builder midpoint {by_parameter}, want {expect}");
    // Point interpolation: the chord's midpoint between (1, 1, 0) and (0, 1, −1).
    assert!(by_points.distance(DVec3::new(0.5, 1.0, -0.5)) < 1e-12, "grid midpoint {by_points}");
    let radius = |q: DVec3| (q.x * q.x + q.z * q.z).sqrt();
    assert!((radius(by_parameter) - 1.0).abs() < 1e-12);
    assert!((radius(by_points) - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
}

/// Value of a one-number channel at `t`.
fn channel(keys: &[(f64, f64)], interp: Interpolation, ease: Ease, t: f64, period: Option<f64>) -> f64 {
    let values: Vec<[f64; 1]> = keys.iter().map(|k| [k.1]).collect();
    let ck: Vec<ChannelKey> = keys
        .iter()
        .zip(&values)
        .map(|(k, v)| ChannelKey { t_secs: k.0, interpolation: interp, ease, value: v })
        .collect();
    timeline::sample_channel(&ck, t, period).unwrap()[0]
}

/// Bound on |f''| of the Catmull-Rom spline through `keys`: on a segment of length H with end
/// values p0, p1 and tangents m0, m1, f'' = ((12u−6)(p0−p1) + (6u−4)H m0 + (6u−2)H m1) / H²,
/// so |f''| ≤ (6|p1−p0| + 4H|m0| + 4H|m1|) / H². Tangents are bounded by the largest
/// difference quotient over two segments.
fn second_derivative_bound(keys: &[(f64, f64)]) -> f64 {
    let max_slope = keys
        .windows(3)
        .map(|w| ((w[2].1 - w[0].1) / (w[2].0 - w[0].0)).abs())
        .chain(keys.windows(2).map(|w| ((w[1].1 - w[0].1) / (w[1].0 - w[0].0)).abs()))
        .fold(0.0, f64::max);
    keys.windows(2)
        .map(|w| {
            let h = w[1].0 - w[0].0;
            (6.0 * (w[1].1 - w[0].1).abs() + 8.0 * h * max_slope) / (h * h)
        })
        .fold(0.0, f64::max)
}

#[test]
fn catmull_rom_is_c1_across_keys() {
    // Non-uniform keys, seeded by index so a failure can be replayed.
    for case in 0..8u32 {
        let mut rng = nlifs::rng::Pcg32::for_stream(case, 0, 0);
        let mut t = 0.0;
        let keys: Vec<(f64, f64)> = (0..6)
            .map(|_| {
                let k = (t, 4.0 * rng.next_f32() as f64 - 2.0);
                t += 0.2 + 1.5 * rng.next_f32() as f64;
                k
            })
            .collect();
        let m = second_derivative_bound(&keys);
        let h = 1e-5;
        // One-sided differences each err by at most h/2·|f''|; rounding adds ~4ε·|f|/h.
        let tol = h * m + 4.0 * f64::EPSILON * 4.0 / h;
        let period = keys.last().unwrap().0 + 0.7;
        for periodic in [None, Some(period)] {
            // The timeline maps scene time into [0, period) before sampling; do the same here.
            let f = |t: f64| {
                channel(&keys, Interpolation::CatmullRom, Ease::None, periodic.map_or(t, |p| t.rem_euclid(p)), periodic)
            };
            for k in &keys {
                let (left, right) = ((f(k.0) - f(k.0 - h)) / h, (f(k.0 + h) - f(k.0)) / h);
                assert!(
                    (left - right).abs() <= tol,
                    "case {case} {periodic:?} key t={}: slopes {left} vs {right}, tol {tol}",
                    k.0
                );
            }
            // Across the loop's wrap, too.
            if let Some(p) = periodic {
                let (left, right) = ((f(p) - f(p - h)) / h, (f(p + h) - f(p)) / h);
                assert!((left - right).abs() <= tol, "case {case} wrap: {left} vs {right}");
            }
        }
        // The check can fail: linear interpolation has a kink at an interior key.
        let g = |t: f64| channel(&keys, Interpolation::Linear, Ease::None, t, None);
        let k = keys[2].0;
        let kink = ((g(k + h) - g(k)) / h - (g(k) - g(k - h)) / h).abs();
        let slopes = ((keys[3].1 - keys[2].1) / (keys[3].0 - keys[2].0)
            - (keys[2].1 - keys[1].1) / (keys[2].0 - keys[1].0))
            .abs();
        assert!((kink - slopes).abs() < 1e-4 * slopes.max(1.0), "linear kink {kink} vs {slopes}");
    }
}

#[test]
fn catmull_rom_end_keys_do_not_overshoot() {
    // Monotone keys: with zero end tangents the first and last segments stay between their keys.
    let keys = [(0.0, 0.0), (1.0, 1.0), (2.0, 3.0)];
    for i in 0..=200 {
        let t = i as f64 / 100.0;
        let v = channel(&keys, Interpolation::CatmullRom, Ease::None, t, None);
        assert!((0.0..=3.0).contains(&v), "t={t}: {v}");
    }
    assert_eq!(channel(&keys, Interpolation::CatmullRom, Ease::None, -1.0, None), 0.0);
    assert_eq!(channel(&keys, Interpolation::CatmullRom, Ease::None, 5.0, None), 3.0);
}

#[test]
fn easing_keeps_endpoints_and_shapes_the_segment() {
    let keys = [(0.0, 2.0), (2.0, 6.0)];
    for ease in [Ease::None, Ease::In, Ease::Out, Ease::InOut] {
        for interp in [Interpolation::Linear, Interpolation::CatmullRom] {
            assert_eq!(channel(&keys, interp, ease, 0.0, None), 2.0);
            assert_eq!(channel(&keys, interp, ease, 2.0, None), 6.0);
        }
    }
    // Linear with ease-in at a quarter: u = 1/4 → u² = 1/16 of the way.
    let v = channel(&keys, Interpolation::Linear, Ease::In, 0.5, None);
    assert!((v - (2.0 + 4.0 / 16.0)).abs() < 1e-12, "{v}");
    let v = channel(&keys, Interpolation::Linear, Ease::Out, 0.5, None);
    assert!((v - (2.0 + 4.0 * (1.0 - 9.0 / 16.0))).abs() < 1e-12, "{v}");
    // In-out is symmetric about the segment's middle.
    let mid = channel(&keys, Interpolation::Linear, Ease::InOut, 1.0, None);
    assert!((mid - 4.0).abs() < 1e-12);
    // Hold keeps the first value until the next key.
    assert_eq!(channel(&keys, Interpolation::Hold, Ease::None, 1.999, None), 2.0);
}

#[test]
fn loop_and_ping_pong_wrap() {
    let d = 2.0;
    let lp = Scene::parse(&twist_scene("catmull-rom", "loop", d), "t.toml").unwrap();
    let pp = Scene::parse(&twist_scene("catmull-rom", "ping-pong", d), "t.toml").unwrap();
    let once = Scene::parse(&twist_scene("catmull-rom", "once", 1.0), "t.toml").unwrap();
    let close = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
    // t + k·d wraps back to t up to a few ulps of t (~1e-15 s); points move at O(1) units/s, so
    // the only difference is rounding, far below this bound.
    let tol = 1e-9;
    for i in 0..20 {
        let t = 0.1 * i as f64;
        assert!(close(&grid_points(&lp, 1, t), &grid_points(&lp, 1, t + d)) < tol, "loop t={t}");
        assert!(close(&grid_points(&lp, 1, t), &grid_points(&lp, 1, t + 3.0 * d)) < tol, "loop t={t}");
        assert!(close(&grid_points(&pp, 1, d - t), &grid_points(&pp, 1, d + t)) < tol, "ping-pong t={t}");
        assert!(close(&grid_points(&pp, 1, t), &grid_points(&pp, 1, t + 2.0 * d)) < tol, "ping-pong t={t}");
    }
    // Loop: seamless — the segment after the last key runs back into the first key.
    assert!(close(&grid_points(&lp, 1, d), &grid_points(&lp, 1, 0.0)) < tol);
    let mid_wrap = grid_points(&lp, 1, 1.5);
    assert!(close(&mid_wrap, &grid_points(&lp, 1, 1.0)) > 0.1, "the loop should be moving back between 1 s and 2 s");
    // Once: holds after the end.
    assert_eq!(grid_points(&once, 1, 7.0), grid_points(&once, 1, 1.0));
}

#[test]
fn yaw_takes_the_short_way_round() {
    let text = twist_scene("linear", "once", 1.0)
        .replace("yaw_deg = 10", "yaw_deg = 350")
        .replace("yaw_deg = 50", "yaw_deg = 30");
    let scene = Scene::parse(&text, "t.toml").unwrap();
    let yaw = scene.camera_at(0.5).yaw_deg.unwrap();
    assert!((yaw.rem_euclid(360.0) - 10.0).abs() < 1e-9, "yaw {yaw}");
}

#[test]
fn timeline_errors_are_located() {
    let base = twist_scene("linear", "once", 1.0);
    let cases: &[(&str, &str, &str)] = &[
        (
            "interpolation = \"linear\"\n[[key.function]]\nname = \"f1\"",
            "interpolation = \"linear\"\nwobble = 3\n[[key.function]]\nname = \"f1\"",
            "wobble",
        ),
        (
            "name = \"f1\"\nsteps = [{ op = \"twist\", axis = \"y\", degrees = 90 }",
            "name = \"nope\"\nsteps = [{ op = \"twist\", axis = \"y\", degrees = 90 }",
            "key[1].function[0].name",
        ),
        ("degrees = 90 }, { op = \"scale\"", "degrees = 90 }, { op = \"translate\"", "key[1].function[0].steps"),
        ("t_secs = 1.0", "t_secs = -1.0", "key[1].t_secs"),
        ("loop = \"once\"", "loop = \"sometimes\"", "timeline.loop"),
        (
            "interpolation = \"linear\"\n[[key.function]]\nname = \"f1\"",
            "interpolation = \"cubic\"\n[[key.function]]\nname = \"f1\"",
            "interpolation",
        ),
    ];
    for (from, to, field) in cases {
        assert!(base.contains(from), "test setup: {from}");
        let text = base.replacen(from, to, 1);
        let err = Scene::parse(&text, "t.toml").expect_err(field);
        let msg = err.to_string();
        assert!(msg.starts_with("t.toml:") && msg.contains(field), "{field}: {msg}");
        // The line named is the line where the offending text is.
        let offending = to.lines().find(|l| !from.contains(*l)).unwrap_or(to);
        let line = text.lines().position(|l| l.contains(offending.trim())).map(|n| n + 1);
        if *field != "key[1].function[0].steps" {
            assert_eq!(Some(err.line), line, "{field}: {msg}");
        }
    }
    // Loop mode needs its period.
    let text = base.replacen("loop = \"once\"\nduration_secs = 1.0", "loop = \"loop\"", 1);
    let msg = Scene::parse(&text, "t.toml").unwrap_err().to_string();
    assert!(msg.contains("timeline.duration_secs"), "{msg}");
}

#[test]
fn example_scene_loads_and_loops() {
    let path = common::scene_path("twist-anim");
    let scene = Scene::load(&path).unwrap();
    let tl = scene.timeline.as_ref().unwrap();
    assert_eq!(tl.loop_mode, timeline::LoopMode::Loop);
    // The camera orbits once per cycle: yaw at the quarter points of the cycle.
    for (t, want) in [(0.0, 0.0), (1.0, 90.0), (2.0, 180.0), (3.0, 270.0), (4.0, 0.0)] {
        let yaw = scene.camera_at(t).yaw_deg.unwrap().rem_euclid(360.0);
        assert!((yaw - want).abs() < 1e-9 || (yaw - want).abs() > 360.0 - 1e-9, "t={t}: {yaw}");
    }
}

// ---------------------------------------------------------------------------------------------
// Recording.

use nlifs::record::{self, RecordSettings, Recorder};

fn example_scene() -> Scene {
    common::load_scene("twist-anim")
}

/// Small, fast frames: 64×48, 20 000 points.
fn small_settings(scene: &Scene, motion_blur_samples: u32) -> RecordSettings {
    RecordSettings {
        fps: 3.0,
        width: 64,
        height: 48,
        points_per_frame: Some(20_000),
        motion_blur_samples,
        ..RecordSettings::for_scene(scene)
    }
}

fn temp_dir(name: &str) -> common::TempDir {
    common::temp_dir(&format!("anim-{name}"))
}

fn frame_bytes(dir: &std::path::Path, k: u32) -> Vec<u8> {
    std::fs::read(record::frame_path(dir, k)).unwrap()
}

#[test]
fn frame_count_follows_loop_mode() {
    let scene = example_scene();
    // 4 s loop at 3 fps: frames at 0, 1/3, ..., 11/3 s; 4 s is frame 0 again.
    assert_eq!(Recorder::new(&scene, small_settings(&scene, 1)).unwrap().frame_count(), 12);
    let once = Scene::parse(&twist_scene("linear", "once", 1.0), "t.toml").unwrap();
    assert_eq!(Recorder::new(&once, small_settings(&once, 1)).unwrap().frame_count(), 4);
    let pp = Scene::parse(&twist_scene("linear", "ping-pong", 1.0), "t.toml").unwrap();
    assert_eq!(Recorder::new(&pp, small_settings(&pp, 1)).unwrap().frame_count(), 6);
}

#[test]
fn chunked_recording_equals_one_run() {
    let scene = example_scene();
    let (one, chunks) = (temp_dir("one"), temp_dir("chunks"));
    let n = 6;
    let whole = Recorder::new(&scene, small_settings(&scene, 1)).unwrap();
    record::record(&whole, &one, 0..n, false, &mut |_, _| {}).unwrap();
    // Each chunk as a separate recorder, as separate processes would make them.
    for range in [0..2, 2..n] {
        let rec = Recorder::new(&scene, small_settings(&scene, 1)).unwrap();
        record::record(&rec, &chunks, range, false, &mut |_, _| {}).unwrap();
    }
    for k in 0..n {
        assert_eq!(frame_bytes(&one, k), frame_bytes(&chunks, k), "frame {k} differs between one run and chunks");
    }
    // The frames show something and change over time.
    let img = image::open(record::frame_path(&one, 1)).unwrap().to_rgb8();
    let bg = *img.get_pixel(0, 0);
    let covered = img.pixels().filter(|p| **p != bg).count();
    assert!(covered > 64 * 48 / 20, "frame 1 covers only {covered} pixels");
    assert_ne!(frame_bytes(&one, 0), frame_bytes(&one, 1));
    let _ = std::fs::remove_dir_all(&one);
    let _ = std::fs::remove_dir_all(&chunks);
}

#[test]
fn resume_restores_deleted_and_truncated_frames() {
    let dir = temp_dir("resume");
    let scene_path = common::scene_path("twist-anim");
    let run_with = |points: &str, extra: &[&str]| {
        let out = common::nlifs_command()
            .arg("record")
            .arg(&scene_path)
            .arg("-o")
            .arg(&dir)
            .args([
                "--frames",
                "0..4",
                "--fps",
                "3",
                "--width",
                "64",
                "--height",
                "48",
                "--points-per-frame",
                points,
                "--backend",
                "cpu",
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "nlifs record failed: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let run = |extra: &[&str]| run_with("20000", extra);
    run(&[]);
    let original: Vec<Vec<u8>> = (0..4).map(|k| frame_bytes(&dir, k)).collect();
    std::fs::remove_file(record::frame_path(&dir, 1)).unwrap();
    let truncated = &original[2][..original[2].len() / 2];
    std::fs::write(record::frame_path(&dir, 2), truncated).unwrap();
    let stderr = run(&["--resume"]);
    assert!(stderr.contains("2 of 4 frames already complete"), "{stderr}");
    for (k, bytes) in original.iter().enumerate() {
        assert_eq!(&frame_bytes(&dir, k as u32), bytes, "frame {k} after resume");
    }
    // A complete frame made with other settings is redone, not kept: the frames' fingerprints
    // (scene and settings, in their text chunks) differ.
    run_with("30000", &[]);
    let denser: Vec<Vec<u8>> = (0..4).map(|k| frame_bytes(&dir, k)).collect();
    let stderr = run(&["--resume"]);
    assert!(stderr.contains("wrote 4 frames") && !stderr.contains("already complete"), "{stderr}");
    for (k, bytes) in original.iter().enumerate() {
        assert_eq!(&frame_bytes(&dir, k as u32), bytes, "frame {k} after resuming over other settings");
        assert_ne!(&denser[k], bytes, "frame {k}: 30000 points should differ from 20000");
    }
    // No temporary files are left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn motion_blur_is_deterministic_and_blurs() {
    let scene = example_scene();
    let sharp = Recorder::new(&scene, small_settings(&scene, 1)).unwrap();
    let blur = Recorder::new(&scene, RecordSettings { shutter: 1.0, ..small_settings(&scene, 4) }).unwrap();
    let a = blur.frame(2).unwrap();
    assert_eq!(a, blur.frame(2).unwrap());
    assert_ne!(a, sharp.frame(2).unwrap());
    // Averaging in light gives intermediate values: more distinct colours than the sharp frame,
    // whose closest-point pixels take one of few depth-cued function colours.
    let distinct = |img: &image::RgbImage| img.pixels().map(|p| p.0).collect::<std::collections::BTreeSet<_>>().len();
    assert!(distinct(&a) > distinct(&sharp.frame(2).unwrap()));
}

#[test]
fn killing_a_recording_leaves_only_whole_frames() {
    let dir = temp_dir("kill");
    let scene_path = common::scene_path("twist-anim");
    let mut child = common::nlifs_command()
        .arg("record")
        .arg(&scene_path)
        .arg("-o")
        .arg(&dir)
        .args(["--fps", "3", "--width", "96", "--height", "72", "--points-per-frame", "300000", "--backend", "cpu"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Kill it somewhere in the middle (wherever that is, the invariant below must hold).
    std::thread::sleep(std::time::Duration::from_millis(250));
    let _ = child.kill();
    let _ = child.wait();
    for entry in std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()) {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("frame_") {
            assert!(record::is_complete_frame(&entry.path(), 96, 72), "{name} is not a whole frame");
        } else {
            // Only the temporary file of the frame being written when killed may remain.
            assert!(name.starts_with(".frame_") && name.ends_with(".tmp"), "unexpected file {name}");
        }
    }
    // A resumed run cleans up the killed run's temporary file (faked here in case the kill
    // landed between frames) and completes the sequence.
    std::fs::write(dir.join(".frame_00003.png.999999.tmp"), b"partial").unwrap();
    let status = common::nlifs_command()
        .arg("record")
        .arg(&scene_path)
        .arg("-o")
        .arg(&dir)
        .args([
            "--fps",
            "3",
            "--width",
            "96",
            "--height",
            "72",
            "--points-per-frame",
            "20000",
            "--backend",
            "cpu",
            "--resume",
            "--frames",
            "0..5",
        ])
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    // Only the resumed range's temporary files are its to remove (job-array chunks own
    // disjoint ranges); a fast killed run may have been writing a later frame.
    let in_range = |n: &String| (0..5).any(|k| n.starts_with(&format!(".frame_{k:05}.png.")));
    assert!(names.iter().all(|n| !(n.ends_with(".tmp") && in_range(n))), "{names:?}");
    assert!((0..5).all(|k| record::is_complete_frame(&record::frame_path(&dir, k), 96, 72)));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn timeline_check_reports_the_key_and_interval_that_break_contractivity() {
    use nlifs::scene::timeline_check::{TimelineProblemKind as K, TimelineSpan as S, check_timeline};
    let text = r#"
version = 1
[grid]
x = [0, 1]
y = [0, 1]
[[function]]
name = "shrink"
kind = "affine"
matrix = [[0.5, 0], [0, 0.5]]
[[function]]
name = "grow"
kind = "affine"
matrix = [[0.5, 0], [0, 0.5]]
[[key]]
t_secs = 0
interpolation = "linear"
[[key]]
t_secs = 1
interpolation = "linear"
[[key.function]]
name = "grow"
matrix = [[0.5, 0], [0, 0.5]]
[[key]]
t_secs = 2
[[key.function]]
name = "grow"
matrix = [[1.2, 0], [0, 1.2]]
"#;
    let scene = Scene::parse(text, "t.toml").unwrap();
    let check = check_timeline(&scene, 8).unwrap();
    assert_eq!(check.samples, 3 + 2 * 8);
    let found: Vec<(S, &str, bool)> = check
        .problems
        .iter()
        .map(|p| (p.span.clone(), p.function.as_str(), matches!(p.kind, K::NotContractive { .. })))
        .collect();
    let interval = S::Interval { from_key: Some(1), to_key: Some(2), from_secs: 1.0, to_secs: 2.0 };
    let key2 = S::Key { index: 2, t_secs: 2.0 };
    // The scale passes 1 at t = 1 + 0.5/0.7 ≈ 1.71 s, so the samples at 1.78 and 1.89 s see it.
    assert_eq!(
        found,
        vec![
            (interval.clone(), "grow", true),
            (interval, "grow", false),
            (key2.clone(), "grow", true),
            (key2, "grow", false)
        ],
        "{:#?}",
        check.problems
    );
    match &check.problems[2].kind {
        // The bound is a guaranteed upper bound of the norm 1.2, padded by a relative 1e-9.
        K::NotContractive { max_bound, .. } => assert!((1.2..=1.2 * (1.0 + 1e-8)).contains(max_bound), "{max_bound}"),
        other => panic!("{other:?}"),
    }
    // The example scene stays contractive and contained all along.
    assert_eq!(check_timeline(&example_scene(), 8).unwrap().problems, vec![]);
}

// ---------------------------------------------------------------------------------------------
// Saving.

#[test]
fn to_toml_round_trips_every_scene() {
    let dir = common::repo_path("scenes");
    let mut scenes: Vec<(String, Scene)> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| (p.display().to_string(), Scene::load(&p).unwrap()))
        .collect();
    scenes.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(scenes.len() >= 6, "found {} scenes", scenes.len());
    for interp in ["hold", "linear", "catmull-rom"] {
        for mode in ["once", "ping-pong"] {
            scenes.push((
                format!("twist_scene {interp} {mode}"),
                Scene::parse(&twist_scene(interp, mode, 1.0), "t.toml").unwrap(),
            ));
        }
    }
    for (name, mut scene) in scenes {
        scene.path = None;
        let text = scene.to_toml();
        let back = Scene::parse(&text, "saved.toml").unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
        assert_eq!(back, scene, "{name} does not read back equal:\n{text}");
        assert_eq!(back.to_toml(), text, "{name}: writing is not a fixpoint");
    }
    // Saving goes through the atomic writer and loads back.
    let dir = temp_dir("save");
    let mut scene = example_scene();
    let path = dir.join("saved.toml");
    scene.save(&path).unwrap();
    let loaded = Scene::load(&path).unwrap();
    scene.path = Some(path);
    assert_eq!(loaded, scene);
    let _ = std::fs::remove_dir_all(&dir);
}
