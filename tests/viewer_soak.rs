//! The viewer left open: `nlifs view scenes/plant1.toml` (the solid look) in a real window under
//! Xvfb, once on Vulkan and once on GL (Mesa's lavapipe and llvmpipe), for `NLIFS_SOAK_SECS`
//! seconds (default 600): a warm-up (the first minute, or the first sixth of a shorter run,
//! with one orbit in it), then orbits (xdotool drags on the view, a few seconds each) and idle
//! stretches (hands off) long enough for the view to converge, the run ending on one. Every
//! second the viewer's resident memory (VmRSS) and CPU time (utime + stime) are read from
//! /proc. Two figures are held to their bounds:
//!
//! - resident memory at the end minus at the end of the warm-up: under 30 MB (a leak of a
//!   fraction of a megabyte a frame, as lavapipe's specialized resolve shaders once were, adds
//!   hundreds in minutes);
//! - CPU over the last 10 s of the last idle stretch, once converged: under 3 % of a core (a
//!   converged, untouched view has nothing to draw).
//!
//! The samples go to stderr as a table and to `samples.csv` in the temporary directory the
//! test prints, with the viewer's `--log-fps` lines in `viewer.log` next to it (the frame
//! rates while orbiting come from them). `#[ignore]`d: ten minutes a backend; `.ci/run` runs
//! both with `NLIFS_SOAK_SECS=120`. `NLIFS_SOAK_BIN` runs another `nlifs` binary instead of
//! the one cargo built (to compare with an older one).
//!
//! Needs Xvfb, xdotool and a GPU adapter on the backend; without them it skips loudly, unless
//! NLIFS_REQUIRE_GPU=1, in which case it fails.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::window::{Guard, have, start_xvfb};

/// Resident memory may grow by less than this from the end of the warm-up to the end (MB,
/// 10^6 bytes).
const MAX_GROWTH_MB: f64 = 30.0;
/// A converged, untouched view may use less than this share of one core (percent).
const MAX_IDLE_CPU_PERCENT: f64 = 3.0;
/// The idle CPU is measured over this many last seconds of the last idle stretch.
const IDLE_MEASURE_SECS: u64 = 10;
/// One drag on the view.
const ORBIT_SECS: u64 = 6;
/// Shortest idle stretch: the view converges after 2^30 splats (`ProgressiveSettings::max_splats`),
/// about 20–35 s at the settings below on a 2-core machine on lavapipe (35–60 M points/s on
/// the CPU route), then [`IDLE_MEASURE_SECS`] are measured.
const MIN_IDLE_SECS: u64 = 60;
/// Warm-up: the first minute, or the first sixth of a shorter run.
const MAX_WARM_UP_SECS: u64 = 60;
/// 2^20 points × 8 steps a frame: the same points as the viewer's default, 8× the splats a
/// frame, so that the accumulation reaches its 2^30 splats in 128 frames instead of 1024.
const VIEW_ARGS: [&str; 4] = ["--points", "1048576", "--steps", "8"];

#[test]
#[ignore = "ten minutes a backend (NLIFS_SOAK_SECS to shorten); .ci/run runs it with a bound"]
fn viewer_on_vulkan_left_open_keeps_its_memory_and_rests() {
    soak("vulkan");
}

#[test]
#[ignore = "ten minutes a backend (NLIFS_SOAK_SECS to shorten); .ci/run runs it with a bound"]
fn viewer_on_gl_left_open_keeps_its_memory_and_rests() {
    soak("gl");
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    WarmUp,
    WarmUpOrbit,
    Orbit,
    Idle,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::WarmUp => "warm-up",
            Kind::WarmUpOrbit => "warm-up orbit",
            Kind::Orbit => "orbit",
            Kind::Idle => "idle",
        }
    }

    fn orbits(self) -> bool {
        matches!(self, Kind::WarmUpOrbit | Kind::Orbit)
    }
}

/// A stretch of the run: seconds `start_secs..end_secs` after the viewer started.
#[derive(Clone, Copy, Debug)]
struct Phase {
    kind: Kind,
    start_secs: u64,
    end_secs: u64,
}

/// The schedule of a run of `total_secs`, and the end of its warm-up: the warm-up (with one
/// orbit in its middle), then `n` cycles of an orbit and an idle stretch of at least
/// [`MIN_IDLE_SECS`], the last idle stretch ending the run.
fn schedule(total_secs: u64) -> (Vec<Phase>, u64) {
    let warm_up_secs = (total_secs / 6).min(MAX_WARM_UP_SECS);
    let rest_secs = total_secs - warm_up_secs;
    assert!(
        rest_secs >= ORBIT_SECS + MIN_IDLE_SECS,
        "NLIFS_SOAK_SECS={total_secs} leaves no room for an orbit and a {MIN_IDLE_SECS} s idle stretch after the warm-up"
    );
    let mut phases = Vec::new();
    let mut push = |kind, start_secs, end_secs| phases.push(Phase { kind, start_secs, end_secs });
    // The window takes a few seconds to open: the warm-up orbit starts at half of it.
    let orbit_at = warm_up_secs / 2;
    push(Kind::WarmUp, 0, orbit_at);
    push(Kind::WarmUpOrbit, orbit_at, (orbit_at + ORBIT_SECS).min(warm_up_secs));
    push(Kind::WarmUp, (orbit_at + ORBIT_SECS).min(warm_up_secs), warm_up_secs);
    let cycles = (rest_secs / (ORBIT_SECS + MIN_IDLE_SECS)).max(1);
    let mut t = warm_up_secs;
    for i in 0..cycles {
        let end = if i + 1 == cycles { total_secs } else { warm_up_secs + (i + 1) * rest_secs / cycles };
        push(Kind::Orbit, t, t + ORBIT_SECS);
        push(Kind::Idle, t + ORBIT_SECS, end);
        t = end;
    }
    phases.retain(|p| p.end_secs > p.start_secs);
    (phases, warm_up_secs)
}

/// One reading a second.
struct Sample {
    t_secs: u64,
    kind: Kind,
    rss_mb: f64,
    cpu_ticks: u64,
    /// The viewer's last `--log-fps` reading at the time: frames and M points per second.
    fps: Option<(f64, f64)>,
}

/// A `--log-fps` line: when it came, its fps and M points/s.
struct FpsLine {
    at: Instant,
    fps: f64,
    mpoints_per_sec: f64,
}

/// The viewer's stderr, collected by a thread.
#[derive(Default)]
struct ViewerLog {
    lines: Vec<String>,
    fps: Vec<FpsLine>,
}

/// "viewer: 25.3 fps, 0.0 M points/s, ..." → (25.3, 0.0).
fn parse_fps_line(line: &str) -> Option<(f64, f64)> {
    let rest = line.strip_prefix("viewer: ")?;
    let (fps, rest) = rest.split_once(" fps, ")?;
    let (mpoints, _) = rest.split_once(" M points/s")?;
    Some((fps.parse().ok()?, mpoints.parse().ok()?))
}

/// Resident memory (VmRSS) of process `pid` in MB (10^6 bytes).
fn rss_mb(pid: u32) -> Option<f64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0 / 1e6)
}

/// CPU time (utime + stime, all threads) of process `pid` in clock ticks.
fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces; fields 14 and 15
    // (utime, stime) are the 12th and 13th after it.
    let after = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = after.split_whitespace().collect();
    Some(fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?)
}

/// Clock ticks a second (`getconf CLK_TCK`; 100, Linux's USER_HZ everywhere, if that fails).
fn clock_ticks_per_sec() -> f64 {
    Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
        .unwrap_or(100.0)
}

/// Starts a left drag on the view lasting about `secs`: back and forth across it, 10 moves a
/// second, released at the end. Runs while the test samples; reap the child when done.
fn start_orbit(display: &str, secs: u64) -> Child {
    let mut args: Vec<String> = ["mousemove", "850", "360", "mousedown", "1"].map(String::from).to_vec();
    let moves = 10 * secs;
    for i in 0..moves {
        // A triangle wave over 2 s: 700 → 1000 → 700 pixels, drifting a little up and down.
        let phase = (i % 20) as f64 / 20.0;
        let x = 700.0 + 300.0 * (1.0 - (2.0 * phase - 1.0).abs());
        let y = 360.0 + 40.0 * (i as f64 * 0.15).sin();
        args.extend(["mousemove".into(), format!("{x:.0}"), format!("{y:.0}"), "sleep".into(), "0.1".into()]);
    }
    args.extend(["mouseup".to_string(), "1".to_string()]);
    Command::new("xdotool").args(&args).env("DISPLAY", display).stdout(Stdio::null()).spawn().expect("run xdotool")
}

/// The binary under test: `NLIFS_SOAK_BIN` when set, else the one cargo built.
fn viewer_command() -> Command {
    match std::env::var_os("NLIFS_SOAK_BIN") {
        Some(bin) => {
            let mut command = Command::new(bin);
            command
                .env("NLIFS_CONFIG_DIR", common::scratch_root().join(format!("nlifs-config-{}", std::process::id())));
            command
        }
        None => common::nlifs_command(),
    }
}

fn soak(backend: &str) {
    for tool in ["Xvfb", "xdotool"] {
        if !have(tool) {
            return common::skip(&format!("soak test: {tool} is not installed"));
        }
    }
    if !nlifs::gpu::adapter_available() {
        return common::skip("soak test: no GPU adapter");
    }
    let total_secs: u64 = match std::env::var("NLIFS_SOAK_SECS") {
        Ok(s) => s.parse().unwrap_or_else(|_| panic!("NLIFS_SOAK_SECS={s} is not a number of seconds")),
        Err(_) => 600,
    };
    let (phases, warm_up_secs) = schedule(total_secs);
    let tck = clock_ticks_per_sec();
    // Kept after the test: the samples and the viewer's log are what it measured.
    let dir = common::temp_dir(&format!("soak-{backend}")).keep();
    let (display, runtime, _xvfb) = start_xvfb(&dir);

    let mut child = viewer_command()
        .arg("view")
        .arg(common::scene_path("plant1"))
        .args(VIEW_ARGS)
        .arg("--log-fps")
        // A bound in case the test dies without reaping it.
        .args(["--exit-after-secs", &(total_secs + 120).to_string()])
        .env("DISPLAY", &display)
        .env("XDG_RUNTIME_DIR", &runtime)
        .env("XDG_STATE_HOME", dir.join("state"))
        .env("WGPU_BACKEND", backend)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the viewer");
    let started = Instant::now();
    let pid = child.id();
    let stderr = child.stderr.take().unwrap();
    let mut viewer = Guard(child);
    let log = Arc::new(Mutex::new(ViewerLog::default()));
    let reader = {
        let log = Arc::clone(&log);
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let mut log = log.lock().unwrap();
                if let Some((fps, mpoints_per_sec)) = parse_fps_line(&line) {
                    log.fps.push(FpsLine { at: Instant::now(), fps, mpoints_per_sec });
                }
                log.lines.push(line);
            }
        })
    };
    let log_tail = |log: &Mutex<ViewerLog>| {
        let log = log.lock().unwrap();
        log.lines[log.lines.len().saturating_sub(20)..].join("\n")
    };
    let at = |secs: u64| started + Duration::from_secs(secs);

    eprintln!(
        "soak ({backend}): {total_secs} s, warm-up {warm_up_secs} s, {} orbits of {ORBIT_SECS} s; samples in {}",
        phases.iter().filter(|p| p.kind.orbits()).count(),
        dir.display()
    );
    let mut samples: Vec<Sample> = Vec::new();
    let first = Sample { t_secs: 0, kind: Kind::WarmUp, rss_mb: rss_mb(pid).unwrap_or(0.0), cpu_ticks: 0, fps: None };
    let first_ticks = cpu_ticks(pid).unwrap_or(0);
    samples.push(Sample { cpu_ticks: first_ticks, ..first });
    let mut drag: Option<Child> = None;
    for s in 0..total_secs {
        let phase = phases.iter().find(|p| (p.start_secs..p.end_secs).contains(&s)).unwrap();
        if phase.kind.orbits() && phase.start_secs == s {
            drag = Some(start_orbit(&display, phase.end_secs - phase.start_secs));
        }
        if phase.end_secs == s + 1
            && let Some(mut d) = drag.take()
        {
            let _ = d.wait();
        }
        let now = Instant::now();
        if at(s + 1) > now {
            std::thread::sleep(at(s + 1) - now);
        }
        if let Ok(Some(status)) = viewer.0.try_wait() {
            let _ = reader.join();
            let tail = log_tail(&log);
            if tail.contains("no GPU adapter") {
                return common::skip(&format!("soak test: no {backend} adapter: {tail}"));
            }
            panic!("the viewer exited after {s} s: {status}\n{tail}");
        }
        let (Some(rss), Some(ticks)) = (rss_mb(pid), cpu_ticks(pid)) else { panic!("cannot read /proc/{pid}") };
        let fps = log.lock().unwrap().fps.last().map(|l| (l.fps, l.mpoints_per_sec));
        samples.push(Sample { t_secs: s + 1, kind: phase.kind, rss_mb: rss, cpu_ticks: ticks, fps });
    }
    drop(viewer);
    let _ = reader.join();
    let log = log.lock().unwrap();
    std::fs::write(dir.join("viewer.log"), log.lines.join("\n") + "\n").unwrap();

    // The table, on stderr and as CSV.
    let mut csv = String::from("t_s,phase,rss_mb,cpu_percent,fps,mpoints_per_s\n");
    eprintln!("{:>6}  {:<14} {:>8} {:>7} {:>7} {:>9}", "t (s)", "phase", "RSS (MB)", "CPU %", "fps", "M pts/s");
    for w in samples.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let cpu_percent = 100.0 * (b.cpu_ticks - a.cpu_ticks) as f64 / tck;
        let (fps, mpoints) =
            b.fps.map_or((String::new(), String::new()), |(f, m)| (format!("{f:.1}"), format!("{m:.1}")));
        eprintln!(
            "{:>6}  {:<14} {:>8.1} {:>7.1} {:>7} {:>9}",
            b.t_secs,
            b.kind.name(),
            b.rss_mb,
            cpu_percent,
            fps,
            mpoints
        );
        csv += &format!("{},{},{:.2},{:.1},{fps},{mpoints}\n", b.t_secs, b.kind.name(), b.rss_mb, cpu_percent);
    }
    std::fs::write(dir.join("samples.csv"), csv).unwrap();

    // Each idle stretch: the CPU over its last seconds and when the view converged (the
    // first `--log-fps` line with no points splatted, or no line at all: no frames drawn).
    let sample_at = |t: u64| samples.iter().find(|x| x.t_secs == t).unwrap();
    let idle_cpu_percent = |end: u64| {
        let (a, b) = (sample_at(end - IDLE_MEASURE_SECS), sample_at(end));
        100.0 * (b.cpu_ticks - a.cpu_ticks) as f64 / tck / IDLE_MEASURE_SECS as f64
    };
    let lines_in = |from: u64, to: u64| log.fps.iter().filter(move |l| l.at > at(from) && l.at <= at(to));
    let mut last_idle = None;
    for p in phases.iter().filter(|p| p.kind == Kind::Idle) {
        let converged_after = lines_in(p.start_secs, p.end_secs)
            .find(|l| l.mpoints_per_sec == 0.0)
            .map(|l| format!("{:.0} s", (l.at - at(p.start_secs)).as_secs_f64()))
            // A view at rest draws nothing, so it logs nothing: the last line is when it stopped.
            .or_else(|| {
                lines_in(p.start_secs, p.end_secs)
                    .next_back()
                    .map(|l| format!("{:.0} s (drawing stopped)", (l.at - at(p.start_secs)).as_secs_f64()))
            })
            .unwrap_or_else(|| "— (no frame drawn)".into());
        let cpu = idle_cpu_percent(p.end_secs);
        eprintln!(
            "soak ({backend}): idle {}–{} s: converged after {converged_after}, CPU over its last {IDLE_MEASURE_SECS} s {cpu:.1} % of a core",
            p.start_secs, p.end_secs
        );
        last_idle = Some((*p, cpu));
    }
    let orbit_fps: Vec<f64> = phases
        .iter()
        .filter(|p| p.kind.orbits())
        .flat_map(|p| lines_in(p.start_secs + 1, p.end_secs).map(|l| l.fps))
        .collect();
    if !orbit_fps.is_empty() {
        let mean = orbit_fps.iter().sum::<f64>() / orbit_fps.len() as f64;
        let (lo, hi) = orbit_fps.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &f| (lo.min(f), hi.max(f)));
        eprintln!("soak ({backend}): orbiting {lo:.1}–{hi:.1} fps (mean {mean:.1} over {} readings)", orbit_fps.len());
    }
    let reference = sample_at(warm_up_secs).rss_mb;
    let end = sample_at(total_secs).rss_mb;
    let peak = samples.iter().map(|s| s.rss_mb).fold(0.0, f64::max);
    let growth = end - reference;
    let minutes = (total_secs - warm_up_secs) as f64 / 60.0;
    let (last, cpu) = last_idle.unwrap();
    eprintln!(
        "soak ({backend}): RSS {reference:.1} MB at the end of the warm-up ({warm_up_secs} s), {end:.1} MB at the end ({total_secs} s), peak {peak:.1} MB: growth {growth:+.1} MB ({:+.2} MB/min); idle CPU {cpu:.1} % of a core",
        growth / minutes
    );
    assert!(
        growth < MAX_GROWTH_MB,
        "{backend}: resident memory grew {growth:.1} MB (from {reference:.1} to {end:.1} MB) after the warm-up; samples in {}",
        dir.display()
    );
    let still_splatting: Vec<f64> = lines_in(last.end_secs - IDLE_MEASURE_SECS, last.end_secs)
        .map(|l| l.mpoints_per_sec)
        .filter(|&m| m > 0.0)
        .collect();
    assert!(
        cpu < MAX_IDLE_CPU_PERCENT,
        "{backend}: the untouched view used {cpu:.1} % of a core over the last {IDLE_MEASURE_SECS} s of a {} s idle stretch{}; samples in {}",
        last.end_secs - last.start_secs,
        if still_splatting.is_empty() {
            " (converged: nothing splatted)".to_string()
        } else {
            format!(" (not converged: still splatting {still_splatting:?} M points/s)")
        },
        dir.display()
    );
}

#[test]
fn the_schedule_ends_idle_and_fits_the_run() {
    for total in [120, 300, 600, 3600] {
        let (phases, warm_up) = schedule(total);
        assert_eq!(warm_up, (total / 6).min(MAX_WARM_UP_SECS));
        assert_eq!(phases.first().unwrap().start_secs, 0);
        assert_eq!(phases.last().unwrap().end_secs, total);
        for w in phases.windows(2) {
            assert_eq!(w[0].end_secs, w[1].start_secs, "{total} s: {phases:?}");
        }
        let last = phases.last().unwrap();
        assert_eq!(last.kind, Kind::Idle);
        for p in phases.iter().filter(|p| p.kind == Kind::Idle) {
            assert!(p.end_secs - p.start_secs >= MIN_IDLE_SECS, "{total} s: {p:?}");
        }
        assert!(phases.iter().any(|p| p.kind == Kind::WarmUpOrbit && p.end_secs <= warm_up));
    }
    assert_eq!(parse_fps_line("viewer: 25.3 fps, 0.0 M points/s, chaos game on the cpu"), Some((25.3, 0.0)));
    assert_eq!(parse_fps_line("viewer: 591 frames in 45.01 s (13.1 fps)"), None);
}
