//! The viewer's real window under a virtual X display, for the window suites: a private Xvfb on
//! a free display number with its runtime folder, screenshots of the whole screen
//! (`import -window root`), xdotool input, and a guard that kills and reaps what a test started.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The view area starts right of the egui side panel (window pixels).
pub const VIEW_X0: u32 = 420;

/// Whether `tool` is on the PATH.
pub fn have(tool: &str) -> bool {
    Command::new("sh")
        .arg("-c")
        .arg(format!("command -v {tool}"))
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Kills and reaps a child we started when dropped.
pub struct Guard(pub Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The whole screen of `display`, saved at `path`; None when `import` fails.
pub fn screenshot(display: &str, path: &Path) -> Option<image::RgbImage> {
    let ok =
        Command::new("import").args(["-window", "root"]).arg(path).env("DISPLAY", display).status().ok()?.success();
    if !ok {
        return None;
    }
    image::open(path).ok().map(|i| i.to_rgb8())
}

/// A virtual X display on a free number, its runtime folder, and its guard.
pub fn start_xvfb(dir: &Path) -> (String, PathBuf, Guard) {
    let runtime = dir.join("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    // Xvfb picks a free display and writes its number to stdout (-displayfd 1).
    let mut xvfb = Command::new("Xvfb")
        .args(["-displayfd", "1", "-screen", "0", "1280x720x24", "-nolisten", "tcp"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start Xvfb");
    let mut line = String::new();
    BufReader::new(xvfb.stdout.take().unwrap()).read_line(&mut line).unwrap();
    (format!(":{}", line.trim()), runtime, Guard(xvfb))
}

/// Runs xdotool on `display`; its output, trimmed.
pub fn xdotool(display: &str, args: &[&str]) -> String {
    let out = Command::new("xdotool").args(args).env("DISPLAY", display).output().expect("run xdotool");
    assert!(out.status.success(), "xdotool {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// Waits until `cond` holds (polling every half second) or `secs` pass.
pub fn wait_for(secs: u64, mut cond: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        if cond() {
            return true;
        }
        if Instant::now() > deadline {
            return false;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
}
