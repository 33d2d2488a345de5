//! Files in the viewer's real window under a virtual X display: the scene it opened is
//! remembered in the recent files (in a config folder the test chooses); when the scene file is
//! broken on disk, the failed reload is said over the view (a red banner with the located
//! error) while the attractor stays; fixing the file takes the banner away; and Ctrl+O, where
//! no file dialog can be shown, says in a toast to use the path fields instead of freezing or
//! failing.
//!
//! Needs Xvfb, xdotool, imagemagick and a GPU adapter (lavapipe will do); without them it skips
//! loudly, unless NLIFS_REQUIRE_GPU=1, in which case it fails. Screenshots are kept in the
//! temporary directory the test prints on failure.

mod common;

use std::process::{Command, Stdio};
use std::time::Duration;

use common::window::{Guard, VIEW_X0, have, screenshot, start_xvfb, wait_for, xdotool};

/// Pixels of the banner's red in the top band of the view: its fill (70, 20, 10 at 86 %
/// over a dark background) and the error text (255, 140, 120), each channel within 40 levels.
fn banner_pixels(img: &image::RgbImage) -> usize {
    let near = |p: [u8; 3], q: [i32; 3]| (0..3).all(|k| (p[k] as i32 - q[k]).abs() <= 40);
    let mut n = 0;
    for y in 0..80.min(img.height()) {
        for x in VIEW_X0..img.width() {
            let p = img.get_pixel(x, y).0;
            n += (near(p, [62, 18, 9]) || near(p, [255, 140, 120])) as usize;
        }
    }
    n
}

/// Pixels of a toast's fill (egui's popup grey, 27 in every channel, within 3 levels) in the
/// bottom band of the view, where toasts show; the view's own background is darker and bluer.
fn toast_pixels(img: &image::RgbImage) -> usize {
    let mut n = 0;
    for y in img.height().saturating_sub(120)..img.height() {
        for x in VIEW_X0..img.width() {
            n += img.get_pixel(x, y).0.iter().all(|&c| (c as i32 - 27).abs() <= 3) as usize;
        }
    }
    n
}

/// Pixels that are not the background's colour in the view (the attractor).
fn lit_pixels(img: &image::RgbImage) -> usize {
    let bg = img.get_pixel(img.width() - 2, img.height() / 2).0;
    let mut n = 0;
    for y in 100..img.height() - 40 {
        for x in VIEW_X0..img.width() {
            let p = img.get_pixel(x, y).0;
            n += (0..3).any(|k| (p[k] as i32 - bg[k] as i32).abs() > 30) as usize;
        }
    }
    n
}

#[test]
fn a_broken_reload_is_said_over_the_view_and_ctrl_o_without_a_dialog_explains() {
    for tool in ["Xvfb", "xdotool", "import"] {
        if !have(tool) {
            return common::skip(&format!("window test: {tool} is not installed"));
        }
    }
    if !nlifs::gpu::adapter_available() {
        return common::skip("window test: no GPU adapter");
    }
    let dir = common::temp_dir("window-files");
    let (display, runtime, _xvfb) = start_xvfb(&dir);

    let scene = dir.join("plant1.toml");
    std::fs::copy(common::scene_path("plant1"), &scene).unwrap();
    let config = dir.join("config");
    let mut viewer = Guard(
        common::nlifs_command()
            .arg("view")
            .arg(&scene)
            .args(["--points", "262144", "--exit-after-secs", "240"])
            .env("DISPLAY", &display)
            .env("XDG_RUNTIME_DIR", &runtime)
            .env("XDG_STATE_HOME", dir.join("state"))
            .env("NLIFS_CONFIG_DIR", &config)
            .env("NLIFS_NO_FILE_DIALOG", "1")
            .env("LIBGL_ALWAYS_SOFTWARE", "1")
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the viewer"),
    );
    let shot = |name: &str| dir.join(format!("{name}.png"));
    let up = wait_for(120, || {
        assert!(viewer.0.try_wait().unwrap().is_none(), "the viewer exited early");
        lit_pixels(&screenshot(&display, &shot("start")).expect("import -window root")) > 2000
    });
    assert!(up, "no attractor after 120 s; see {}", shot("start").display());
    let start = screenshot(&display, &shot("start")).expect("import -window root");
    assert!(banner_pixels(&start) < 50, "a banner before anything went wrong: {}", shot("start").display());

    // The scene it opened is the first recent file.
    let recent = nlifs::viewer::recent::RecentFiles::load(&config);
    assert_eq!(recent.paths.first(), Some(&std::fs::canonicalize(&scene).unwrap()));

    // Break the file on disk: the reload fails over the view, the attractor stays.
    let good = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, good.replacen("[grid]", "[grid\n", 1)).unwrap();
    let shown =
        wait_for(20, || banner_pixels(&screenshot(&display, &shot("broken")).expect("import -window root")) > 500);
    assert!(shown, "no error over the view after breaking the file; see {}", shot("broken").display());
    let broken = screenshot(&display, &shot("broken")).expect("import -window root");
    assert!(lit_pixels(&broken) > 2000, "the attractor went; see {}", shot("broken").display());
    assert!(viewer.0.try_wait().unwrap().is_none(), "the viewer exited");

    // Fix it: the banner goes.
    std::fs::write(&scene, &good).unwrap();
    let gone = wait_for(20, || banner_pixels(&screenshot(&display, &shot("fixed")).expect("import -window root")) < 50);
    assert!(gone, "the error stayed after the file was fixed; see {}", shot("fixed").display());
    // Whatever toast was up is gone after its 4 s.
    std::thread::sleep(Duration::from_secs(5));
    let before = toast_pixels(&screenshot(&display, &shot("fixed")).expect("import -window root"));

    // Ctrl+O with no dialog to show: a notice, the viewer keeps running.
    let focus = Command::new("xdotool")
        .args(["search", "--name", "nlifs", "windowfocus"])
        .env("DISPLAY", &display)
        .status()
        .is_ok_and(|s| s.success());
    assert!(focus, "cannot focus the viewer window");
    xdotool(&display, &["mousemove", "850", "360", "key", "ctrl+o"]);
    std::thread::sleep(Duration::from_secs(2));
    let notice = screenshot(&display, &shot("ctrl-o")).expect("import -window root");
    assert!(viewer.0.try_wait().unwrap().is_none(), "the viewer exited after Ctrl+O");
    assert!(lit_pixels(&notice) > 2000, "see {}", shot("ctrl-o").display());
    // The notice is a toast of some 500 × 40 pixels.
    let toast = toast_pixels(&notice);
    assert!(
        toast > before + 5000,
        "no notice after Ctrl+O ({toast} vs {before} grey pixels); see {}",
        shot("ctrl-o").display()
    );
    eprintln!("window files: screenshots in {}", dir.display());
}
