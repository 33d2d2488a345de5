//! The viewer in a real window under a virtual X display: it starts on a paper scene, a
//! screenshot of the screen (`import -window root`) shows the attractor (not a blank or
//! uniform image), and a mouse drag (xdotool) on the view changes what is shown. Twice: with the
//! default chaos-game backend (auto, the CPU route on lavapipe) and with the GPU route forced.
//! A third run checks that work is not lost and input goes where the hand means it: the wheel
//! over the side panel leaves the view alone, a press in the view right after a panel click
//! orbits, Esc never quits, an added function marks the title, is written to the recovery file
//! and survives Ctrl+S (the file has it and `nlifs info` reads it), quitting with unsaved edits
//! asks instead of quitting, and quitting without them quits.
//!
//! Needs Xvfb, xdotool, imagemagick and a GPU adapter (lavapipe will do); without them it skips
//! loudly, unless NLIFS_REQUIRE_GPU=1, in which case it fails. Failing screenshots are kept in
//! the temporary directory printed by the test.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::window::{Guard, VIEW_X0, have, screenshot, start_xvfb, wait_for, xdotool};

/// A pixel "differs" when a channel moves by more than this (8-bit).
const DIFF: i32 = 30;

/// Fraction of view-area pixels that differ from the most common colour there.
fn non_background_fraction(img: &image::RgbImage) -> f64 {
    let mut counts = std::collections::BTreeMap::new();
    for y in 0..img.height() {
        for x in VIEW_X0..img.width() {
            *counts.entry(img.get_pixel(x, y).0).or_insert(0u64) += 1;
        }
    }
    let Some((bg, _)) = counts.iter().max_by_key(|(_, n)| **n) else { return 0.0 };
    let total: u64 = counts.values().sum();
    let differ: u64 =
        counts.iter().filter(|(c, _)| (0..3).any(|k| (c[k] as i32 - bg[k] as i32).abs() > DIFF)).map(|(_, n)| n).sum();
    differ as f64 / total as f64
}

fn changed_fraction(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    let mut changed = 0u64;
    let mut total = 0u64;
    for y in 0..a.height().min(b.height()) {
        for x in VIEW_X0..a.width().min(b.width()) {
            let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
            total += 1;
            changed += (0..3).any(|k| (p[k] as i32 - q[k] as i32).abs() > DIFF) as u64;
        }
    }
    changed as f64 / total.max(1) as f64
}

/// The viewer's default chaos-game backend (auto: the CPU route on lavapipe).
#[test]
fn viewer_shows_the_attractor_and_drag_orbits() {
    check_viewer(None);
}

/// The same with the chaos game forced onto the GPU (its route on every adapter).
#[test]
fn viewer_on_the_gpu_route_shows_the_attractor_and_drag_orbits() {
    check_viewer(Some("gpu"));
}

/// Gives the viewer window the keyboard (a virtual display has no window manager to do it).
fn focus(display: &str) {
    xdotool(display, &["search", "--name", "nlifs", "windowfocus"]);
}

/// The viewer window's title.
fn title(display: &str) -> String {
    let ids = xdotool(display, &["search", "--name", "nlifs"]);
    let id = ids.lines().last().expect("a viewer window");
    xdotool(display, &["getwindowname", id])
}

/// Waits for the attractor to show, then for one more frame of accumulation.
fn wait_for_attractor(viewer: &mut Guard, display: &str, shot: &Path) -> image::RgbImage {
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        std::thread::sleep(Duration::from_secs(2));
        if let Ok(Some(status)) = viewer.0.try_wait() {
            panic!("the viewer exited early: {status}");
        }
        if let Some(img) = screenshot(display, shot)
            && non_background_fraction(&img) > 0.01
        {
            std::thread::sleep(Duration::from_secs(2));
            return screenshot(display, shot).unwrap();
        }
        assert!(Instant::now() < deadline, "no attractor on screen after 120 s; last screenshot {}", shot.display());
    }
}

#[test]
fn viewer_keeps_unsaved_work_and_gives_the_camera_only_unused_input() {
    for tool in ["Xvfb", "xdotool", "import"] {
        if !have(tool) {
            return common::skip(&format!("window test: {tool} is not installed"));
        }
    }
    if !nlifs::gpu::adapter_available() {
        return common::skip("window test: no GPU adapter");
    }
    let dir = common::temp_dir("window-work");
    let (display, runtime, _xvfb) = start_xvfb(&dir);
    let scene = dir.join("plant2.toml");
    std::fs::copy(common::scene_path("plant2"), &scene).unwrap();
    let state_home = dir.join("state");
    let start = || {
        let child = common::nlifs_command()
            .arg("view")
            .arg(&scene)
            .args(["--points", "262144", "--exit-after-secs", "300"])
            .env("DISPLAY", &display)
            .env("XDG_RUNTIME_DIR", &runtime)
            .env("XDG_STATE_HOME", &state_home)
            .env("LIBGL_ALWAYS_SOFTWARE", "1")
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the viewer");
        Guard(child)
    };
    let mut viewer = start();
    let shot = |name: &str| dir.join(format!("{name}.png"));
    let before = wait_for_attractor(&mut viewer, &display, &shot("start"));
    let name = nlifs::scene::Scene::load(&scene).unwrap().name;
    assert_eq!(title(&display), format!("{name} — nlifs"));

    // How much the view changes by itself (accumulation noise) in 2 s.
    std::thread::sleep(Duration::from_secs(2));
    let still = screenshot(&display, &shot("still")).unwrap();
    let noise = changed_fraction(&before, &still);

    // 1. The wheel over the side panel does not zoom the view.
    xdotool(&display, &["mousemove", "150", "400"]);
    for _ in 0..5 {
        xdotool(&display, &["click", "5"]);
    }
    std::thread::sleep(Duration::from_secs(3));
    let after_wheel = screenshot(&display, &shot("after-wheel")).unwrap();
    let wheel_change = changed_fraction(&still, &after_wheel);
    assert!(
        wheel_change <= (3.0 * noise).max(0.003),
        "the wheel over the panel changed {wheel_change:.4} of the view (noise {noise:.4}); see {}",
        shot("after-wheel").display()
    );

    // 2. A press in the view right after a click on the panel orbits at once. (The panel
    // scrolls back to its top first, so that the click lands on its heading, not a button.)
    for _ in 0..10 {
        xdotool(&display, &["click", "4"]);
    }
    std::thread::sleep(Duration::from_secs(1));
    xdotool(
        &display,
        &[
            "mousemove",
            "20",
            "12",
            "click",
            "1",
            "mousemove",
            "850",
            "360",
            "mousedown",
            "1",
            "mousemove",
            "870",
            "362",
            "sleep",
            "0.2",
            "mousemove",
            "920",
            "365",
            "sleep",
            "0.2",
            "mousemove",
            "990",
            "370",
            "sleep",
            "0.2",
            "mouseup",
            "1",
        ],
    );
    let mut orbit_change = 0.0;
    wait_for(30, || {
        orbit_change = changed_fraction(&after_wheel, &screenshot(&display, &shot("after-orbit")).unwrap());
        orbit_change > 0.01
    });
    assert!(orbit_change > 0.01, "a drag right after a panel click changed only {orbit_change:.4} of the view");

    // 3. Esc does not quit, with or without unsaved edits.
    focus(&display);
    xdotool(&display, &["mousemove", "850", "360", "key", "Escape"]);
    std::thread::sleep(Duration::from_secs(2));
    assert!(viewer.0.try_wait().unwrap().is_none(), "Esc quit the viewer");
    xdotool(&display, &["key", "shift+a"]);
    assert!(wait_for(20, || title(&display).contains('*')), "no unsaved mark after Shift+A: {}", title(&display));
    assert_eq!(title(&display), format!("{name}* — nlifs"));
    xdotool(&display, &["key", "Escape"]);
    std::thread::sleep(Duration::from_secs(2));
    assert!(viewer.0.try_wait().unwrap().is_none(), "Esc with unsaved edits quit the viewer");

    // 4. The edit reaches the recovery file within a few seconds.
    let recovery = state_home.join("nlifs").join("recovery");
    let recovery_file = || std::fs::read_dir(&recovery).ok()?.flatten().map(|e| e.path()).next();
    assert!(wait_for(15, || recovery_file().is_some()), "no recovery file in {}", recovery.display());
    let functions = nlifs::scene::Scene::load(&scene).unwrap().functions.len();
    let recovered = nlifs::scene::Scene::load(&recovery_file().unwrap()).unwrap();
    assert_eq!(recovered.functions.len(), functions + 1);

    // 5. Quitting with unsaved edits asks (the dialog stays up; Esc closes it).
    xdotool(&display, &["key", "ctrl+q"]);
    std::thread::sleep(Duration::from_secs(3));
    screenshot(&display, &shot("close-dialog"));
    assert!(viewer.0.try_wait().unwrap().is_none(), "Ctrl+Q with unsaved edits quit without asking");
    xdotool(&display, &["key", "Escape"]);
    std::thread::sleep(Duration::from_secs(2));

    // 6. A kill keeps the edits for the next start, which offers them.
    let _ = viewer.0.kill();
    let _ = viewer.0.wait();
    assert!(recovery_file().is_some());
    let mut viewer = start();
    wait_for_attractor(&mut viewer, &display, &shot("restart"));
    screenshot(&display, &shot("recovery-offer"));
    // Esc answers nothing: the offer closes, the file stays.
    focus(&display);
    xdotool(&display, &["key", "Escape"]);
    std::thread::sleep(Duration::from_secs(1));
    assert!(recovery_file().is_some());

    // 7. Add a function in the view, save: the file has it, `nlifs info` reads it, the mark
    // and the recovery file go, and quitting no longer asks.
    xdotool(&display, &["mousemove", "850", "360", "key", "shift+a"]);
    assert!(wait_for(20, || title(&display).contains('*')), "no unsaved mark: {}", title(&display));
    xdotool(&display, &["key", "ctrl+s"]);
    assert!(wait_for(20, || !title(&display).contains('*')), "still marked after Ctrl+S: {}", title(&display));
    assert_eq!(nlifs::scene::Scene::load(&scene).unwrap().functions.len(), functions + 1);
    let info = common::run_nlifs(&["info", scene.to_str().unwrap()]);
    assert!(info.status.success(), "{}", String::from_utf8_lossy(&info.stderr));
    assert!(recovery_file().is_none(), "the recovery file outlived a save");
    xdotool(&display, &["key", "ctrl+q"]);
    assert!(wait_for(20, || viewer.0.try_wait().unwrap().is_some()), "Ctrl+Q without unsaved edits did not quit");
    assert!(viewer.0.try_wait().unwrap().unwrap().success());
    eprintln!(
        "window work: noise {noise:.4}, wheel over the panel {wheel_change:.4}, orbit after a panel click {orbit_change:.3}"
    );
    if std::env::var_os("NLIFS_KEEP_SCREENSHOTS").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    } else {
        eprintln!("screenshots in {}", dir.display());
    }
}

fn check_viewer(chaos_backend: Option<&str>) {
    for tool in ["Xvfb", "xdotool", "import"] {
        if !have(tool) {
            return common::skip(&format!("window test: {tool} is not installed"));
        }
    }
    if !nlifs::gpu::adapter_available() {
        return common::skip("window test: no GPU adapter");
    }
    let label = chaos_backend.unwrap_or("auto");
    let dir = common::temp_dir(&format!("window-smoke-{label}"));
    let (display, runtime, _xvfb) = start_xvfb(&dir);

    let scene = common::scene_path("plant2");
    let viewer = common::nlifs_command()
        .arg("view")
        .arg(&scene)
        .args(["--points", "262144", "--exit-after-secs", "240"])
        .args(chaos_backend.map(|b| ["--chaos-backend", b]).into_iter().flatten())
        .env("DISPLAY", &display)
        .env("XDG_RUNTIME_DIR", &runtime)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start the viewer");
    let mut viewer = Guard(viewer);

    // 1. The attractor appears (software rendering is slow: poll).
    let first = dir.join("before.png");
    let deadline = Instant::now() + Duration::from_secs(120);
    let before = loop {
        std::thread::sleep(Duration::from_secs(2));
        if let Ok(Some(status)) = viewer.0.try_wait() {
            panic!("the viewer exited early: {status}");
        }
        if let Some(img) = screenshot(&display, &first)
            && non_background_fraction(&img) > 0.01
        {
            // One more frame of accumulation so that the next comparison sees only the drag.
            std::thread::sleep(Duration::from_secs(2));
            break screenshot(&display, &first).unwrap();
        }
        assert!(Instant::now() < deadline, "no attractor on screen after 120 s; last screenshot {}", first.display());
    };
    let covered = non_background_fraction(&before);
    // The plant covers about a tenth of the view area; blank or uniform images give ~0.
    assert!(covered > 0.01, "attractor covers {covered:.4} of the view; see {}", first.display());

    // 2. A left drag on the view orbits the camera: the image changes.
    let drag = Command::new("xdotool")
        .args(["mousemove", "850", "360", "mousedown", "1"])
        .args([
            "mousemove",
            "870",
            "362",
            "sleep",
            "0.2",
            "mousemove",
            "920",
            "365",
            "sleep",
            "0.2",
            "mousemove",
            "990",
            "370",
            "sleep",
            "0.2",
        ])
        .args(["mouseup", "1"])
        .env("DISPLAY", &display)
        .status()
        .expect("run xdotool");
    assert!(drag.success());
    let second = dir.join("after.png");
    let deadline = Instant::now() + Duration::from_secs(60);
    let changed = loop {
        std::thread::sleep(Duration::from_secs(2));
        let after = screenshot(&display, &second).expect("screenshot");
        let changed = changed_fraction(&before, &after);
        // The orbit moves a plant covering ~10% of the area: well over 1% of pixels change.
        if changed > 0.01 || Instant::now() > deadline {
            break changed;
        }
    };
    assert!(
        changed > 0.01,
        "a drag changed only {changed:.4} of the view; see {} and {}",
        first.display(),
        second.display()
    );
    eprintln!("window smoke ({label}): attractor covers {covered:.3} of the view, a drag changed {changed:.3}");
    drop(viewer);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn viewer_screenshot_carries_the_scene_and_reopens() {
    if !have("Xvfb") {
        return common::skip("window test: Xvfb is not installed");
    }
    if !nlifs::gpu::adapter_available() {
        return common::skip("window test: no GPU adapter");
    }
    let dir = common::temp_dir("window-screenshot");
    let (display, runtime, _xvfb) = start_xvfb(&dir);
    let run = |scene: &Path, png: &Path| {
        let status = common::nlifs_command()
            .arg("view")
            .arg(scene)
            .args(["--points", "65536", "--exit-after-secs", "3", "--screenshot"])
            .arg(png)
            .env("DISPLAY", &display)
            .env("XDG_RUNTIME_DIR", &runtime)
            .env("XDG_STATE_HOME", dir.join("state"))
            // A PNG's scene is copied into the temporary folder: the test's own.
            .env("TMPDIR", dir.as_os_str())
            .env("LIBGL_ALWAYS_SOFTWARE", "1")
            .stdout(Stdio::null())
            .status()
            .expect("run the viewer");
        assert!(status.success(), "nlifs view {} exited with {status}", scene.display());
    };
    let first = dir.join("first.png");
    run(&common::scene_path("twisting"), &first);
    let inside = nlifs::output::png::scene_from_png(&first).expect("the screenshot carries its scene");
    assert_eq!(inside.scene("screenshot").unwrap().name, common::load_scene("twisting").name);
    // The screenshot opens as its scene, and shows the attractor again.
    let second = dir.join("second.png");
    run(&first, &second);
    let img = image::open(&second).unwrap().to_rgb8();
    assert!(non_background_fraction(&img) > 0.02, "reopened screenshot shows too little");
}
