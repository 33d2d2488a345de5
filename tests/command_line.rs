//! The command line's own behaviour, through the binary: every output is checked before the
//! work (an unwritable place fails at once with exit 2 and leaves nothing; a missing folder is
//! created and said), the usage lines name the required options, negative numbers reach their
//! option's range check, `record`'s two colour options, `export mesh`'s options, `info`'s
//! function kinds, and headless GPU runs without Wayland/X noise on stderr.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// Folders no output can be created in, inside `base`: a read-only folder (where the tests do
/// not run as root, who writes anyway) and a "folder" that is a regular file (which stops root
/// too).
fn unwritable_folders(base: &Path) -> Vec<PathBuf> {
    use std::os::unix::fs::PermissionsExt;
    let file = base.join("file.txt");
    std::fs::write(&file, b"not a folder").unwrap();
    let read_only = base.join("read-only");
    std::fs::create_dir(&read_only).unwrap();
    std::fs::set_permissions(&read_only, std::fs::Permissions::from_mode(0o555)).unwrap();
    let mut folders = vec![file];
    if std::fs::write(read_only.join("probe"), b"").is_err() {
        folders.push(read_only);
    } else {
        std::fs::remove_file(read_only.join("probe")).unwrap();
        eprintln!("running as root: a read-only folder takes files; only the file-as-folder case is checked");
    }
    folders
}

/// Every command that writes, given an output in `folder`, with work that takes far longer than
/// the time the failure is allowed (billions of points, deep trees, full-HD frames).
fn writers(folder: &Path, scratch: &Path) -> Vec<(String, Vec<String>)> {
    let plant2 = common::scene_path("plant2");
    let anim = common::scene_path("twist-anim");
    let out = |name: &str| s(&folder.join(name)).to_string();
    let args = |list: &[&str]| list.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    let (plant2, anim) = (s(&plant2), s(&anim));
    let missing_part = s(&scratch.join("missing.part")).to_string();
    let frames_dir = s(&scratch.join("frames")).to_string();
    vec![
        ("render".into(), args(&["render", plant2, "-o", &out("x.png"), "--points", "2000000000"])),
        (
            "render --part".into(),
            args(&["render", plant2, "--part", "1/1", "--raw", &out("x.part"), "--points", "2000000000"]),
        ),
        ("merge".into(), args(&["merge", &missing_part, "-o", &out("x.png")])),
        (
            "record -o".into(),
            args(&["record", anim, "-o", &out("frames"), "--width", "1920", "--height", "1080", "--backend", "cpu"]),
        ),
        (
            "record --video".into(),
            args(&[
                "record",
                anim,
                "-o",
                &frames_dir,
                "--width",
                "1920",
                "--height",
                "1080",
                "--backend",
                "cpu",
                "--video",
                &out("x.mp4"),
            ]),
        ),
        (
            "snapshot".into(),
            args(&["snapshot", plant2, "-o", &out("x.png"), "--depth", "12", "--width", "1920", "--height", "1080"]),
        ),
        ("export points".into(), args(&["export", "points", plant2, "-o", &out("x.ply"), "--points", "200000000"])),
        ("export mesh".into(), args(&["export", "mesh", plant2, "-o", &out("x.glb"), "--depth", "11"])),
        ("export pov".into(), args(&["export", "pov", plant2, "-o", &out("x.pov"), "--depth", "13"])),
    ]
}

/// An output that cannot be created fails before the work: exit 2 within seconds (the work
/// would take minutes), naming the path and why, with no progress or other output first, and
/// nothing left in the folder (nor a frames folder made for a video that cannot be written).
#[test]
fn unwritable_outputs_fail_before_the_work() {
    let base = common::temp_dir("unwritable");
    let scratch = base.join("scratch");
    std::fs::create_dir(&scratch).unwrap();
    // `--video` needs an ffmpeg on PATH before anything else; a stand-in that says it runs.
    let bin = base.join("bin");
    std::fs::create_dir(&bin).unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::write(bin.join("ffmpeg"), "#!/bin/sh\nexit 0\n").unwrap();
        std::fs::set_permissions(bin.join("ffmpeg"), std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let path = format!("{}:{}", s(&bin), std::env::var("PATH").unwrap_or_default());
    for folder in unwritable_folders(&base) {
        let before = names(&base);
        for (what, args) in writers(&folder, &scratch) {
            let start = Instant::now();
            let out = common::nlifs_command().args(&args).env("PATH", &path).output().unwrap();
            let secs = start.elapsed();
            let err = stderr(&out);
            assert_eq!(out.status.code(), Some(2), "{what} in {}: {err}", folder.display());
            // Loading and checking take milliseconds; 20 s is far below any of these works.
            assert!(secs < Duration::from_secs(20), "{what} took {secs:?} to fail: {err}");
            let output_arg = args.iter().find(|a| a.starts_with(s(&folder))).unwrap();
            assert!(err.contains("cannot write") && err.contains(output_arg.as_str()), "{what}: {err}");
            // Before the error at most the line saying where the chaos game runs: no progress,
            // no warnings, no folder said to be created.
            let first: Vec<&str> = err.lines().take_while(|l| !l.starts_with("error: ")).collect();
            assert!(first.iter().all(|l| l.starts_with("record: chaos game on")), "{what}: {err}");
            assert_eq!(names(&base), before, "{what} left something in {}", base.display());
            assert!(names(&scratch).is_empty(), "{what} left {:?} in the scratch folder", names(&scratch));
            if folder.is_dir() {
                assert!(names(&folder).is_empty(), "{what} left {:?} in {}", names(&folder), folder.display());
            }
        }
    }
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(base.join("read-only"), std::fs::Permissions::from_mode(0o755));
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// A missing folder above an output is created and said, with its absolute path, on stderr.
#[test]
fn a_missing_folder_is_created_and_said() {
    let base = common::temp_dir("created-folder");
    let png = base.join("new/deeper/x.png");
    let plant2 = common::scene_path("plant2");
    let size = ["--width", "32", "--height", "24", "--points", "1000", "--backend", "cpu"];
    let render = || common::run_nlifs(&[&["render", s(&plant2), "-o", s(&png)][..], &size].concat());
    let out = render();
    assert!(out.status.success(), "{}", stderr(&out));
    let said = format!("created folder {}\n", base.join("new/deeper").display());
    assert!(stderr(&out).contains(&said), "expected `{said}` in: {}", stderr(&out));
    assert!(png.is_file());
    // Once the folder exists, nothing is said.
    let again = render();
    assert!(again.status.success() && !stderr(&again).contains("created folder"), "{}", stderr(&again));
    let _ = std::fs::remove_dir_all(&base);
}

/// The usage line of every command that writes names its required output.
#[test]
fn usage_lines_name_the_required_output() {
    for command in [&["render"][..], &["merge"], &["record"], &["snapshot"], &["export", "points"], &["export", "mesh"]]
    {
        let mut args = command.to_vec();
        args.push("--help");
        let out = common::run_nlifs(&args);
        let help = String::from_utf8_lossy(&out.stdout).into_owned();
        let usage = help.split("\n\n").find(|p| p.starts_with("Usage:")).unwrap_or_else(|| panic!("{help}"));
        assert!(usage.contains("--output <OUTPUT>") || usage.contains("-o <OUTPUT>"), "{command:?}: {usage}");
        if command == ["render"] {
            assert!(usage.contains("--raw <RAW>") && usage.contains("--part"), "{usage}");
        }
    }
}

/// A negative number is a value: it reaches the option's range check instead of reading as an
/// unknown flag.
#[test]
fn negative_numbers_reach_the_range_check() {
    let plant2 = common::scene_path("plant2");
    let anim = common::scene_path("twist-anim");
    let dir = common::temp_dir("negative");
    let png = dir.join("x.png");
    for (args, expected) in [
        (vec!["render", s(&plant2), "-o", s(&png), "--width", "-100"], "-100 is not in 1..=16384"),
        (vec!["render", s(&plant2), "-o", s(&png), "--height", "-1"], "-1 is not in 1..=16384"),
        (vec!["render", s(&plant2), "-o", s(&png), "--seed", "-1"], "-1 is not in 0..=4294967295"),
        (vec!["render", s(&plant2), "-o", s(&png), "--points", "-5"], "`-5` is not a whole number"),
        (vec!["snapshot", s(&plant2), "-o", s(&png), "--spp", "-4"], "-4 is not in 1..=1024"),
        (vec!["record", s(&anim), "-o", s(&dir), "--fps", "-2"], "--fps must be a positive number, found -2"),
    ] {
        let out = common::run_nlifs(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expected) && !err.contains("unexpected argument"), "{args:?}: {err}");
    }
    assert!(names(&dir).is_empty(), "{:?}", names(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `record --color palette` colours the chaos game by the palette, `--raytrace-color depth`
/// the ray-traced frames by depth; each is refused, naming the other, with the other renderer.
#[test]
fn record_has_a_palette_colour_and_a_raytrace_colour() {
    let anim = common::scene_path("twist-anim");
    let dir = common::temp_dir("record-colours");
    let frame = |name: &str, extra: &[&str]| -> image::RgbImage {
        let out_dir = dir.join(name);
        let mut args =
            vec!["record", s(&anim), "-o", s(&out_dir), "--frames", "0..1", "--width", "48", "--height", "36"];
        args.extend(extra);
        let out = common::run_nlifs(&args);
        assert!(out.status.success(), "{extra:?}: {}", stderr(&out));
        image::open(out_dir.join("frame_00000.png")).unwrap().to_rgb8()
    };
    let chaos = ["--backend", "cpu", "--points-per-frame", "20000"];
    let by_function = frame("function", &[&chaos[..], &["--color", "function"]].concat());
    let by_palette = frame("palette", &[&chaos[..], &["--color", "palette"]].concat());
    assert_ne!(by_function, by_palette, "--color palette drew the function colours");
    let trace = ["--renderer", "raytrace", "--depth", "2", "--spp", "1"];
    let traced = frame("traced", &trace);
    let by_depth = frame("depth", &[&trace[..], &["--raytrace-color", "depth"]].concat());
    assert_ne!(traced, by_depth, "--raytrace-color depth drew the function colours");
    for (args, expected) in [
        (vec!["--raytrace-color", "depth"], "--raytrace-color applies to --renderer raytrace"),
        (vec!["--renderer", "raytrace", "--color", "palette"], "--color colours the chaos game's points"),
        (vec!["--renderer", "raytrace", "--palette", "ember"], "--palette colours the chaos game's points"),
    ] {
        let mut all = vec!["record", s(&anim), "-o", s(&dir), "--frames", "0..1"];
        all.extend(&args);
        let out = common::run_nlifs(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(expected), "{args:?}: {}", stderr(&out));
    }
    let help = String::from_utf8_lossy(&common::run_nlifs(&["record", "--help"]).stdout).into_owned();
    assert_eq!(help.matches("--color <").count(), 1, "{help}");
    assert!(help.contains("--raytrace-color <MODE>"), "{help}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `export mesh` lists only options it takes (no `--adaptive`, which is `snapshot`'s).
#[test]
fn export_mesh_help_lists_only_its_options() {
    let help = String::from_utf8_lossy(&common::run_nlifs(&["export", "mesh", "--help"]).stdout).into_owned();
    assert!(help.contains("--depth") && !help.contains("adaptive"), "{help}");
    let snapshot = String::from_utf8_lossy(&common::run_nlifs(&["snapshot", "--help"]).stdout).into_owned();
    assert!(snapshot.contains("--adaptive"), "{snapshot}");
}

/// `info` names each function's kind as the scene file does: builders are `builder`, in the
/// table and in JSON; grid functions stay `grid`.
#[test]
fn info_reports_the_kind_the_scene_gives() {
    for (scene, kind) in [("builders", "builder"), ("plant2", "grid")] {
        let path = common::scene_path(scene);
        let json = common::run_nlifs(&["info", s(&path), "--json"]);
        assert!(json.status.success(), "{}", stderr(&json));
        let value: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
        let kinds: Vec<&str> =
            value["functions"].as_array().unwrap().iter().map(|f| f["kind"].as_str().unwrap()).collect();
        let expected = nlifs::scene::Scene::load(&path).unwrap().functions.len();
        assert_eq!(kinds, vec![kind; expected], "{scene}");
        let text = String::from_utf8_lossy(&common::run_nlifs(&["info", s(&path)]).stdout).into_owned();
        // The table's rows: after its header, up to the summary; each names the kind.
        let rows: Vec<&str> = text
            .lines()
            .skip_while(|l| !l.starts_with("function "))
            .skip(1)
            .take_while(|l| !l.starts_with("IFS:") && !l.starts_with("warning:"))
            .filter(|l| !l.starts_with("    point"))
            .collect();
        assert_eq!(rows.len(), expected, "{scene}: {text}");
        assert!(rows.iter().all(|r| r.contains(&format!(" {kind} "))), "{scene}: {text}");
    }
}

/// A headless run that tries the GPU, without any display or runtime folder (ssh, cron),
/// prints no window-system noise about XDG_RUNTIME_DIR.
#[test]
fn headless_gpu_runs_print_no_display_noise() {
    let anim = common::scene_path("twist-anim");
    let plant2 = common::scene_path("plant2");
    let dir = common::temp_dir("headless-noise");
    let frames = dir.join("frames");
    let png = dir.join("x.png");
    let runs: [Vec<&str>; 2] = [
        vec![
            "record",
            s(&anim),
            "-o",
            s(&frames),
            "--frames",
            "0..2",
            "--width",
            "64",
            "--height",
            "48",
            "--backend",
            "auto",
        ],
        vec![
            "render",
            s(&plant2),
            "-o",
            s(&png),
            "--width",
            "64",
            "--height",
            "48",
            "--points",
            "10000",
            "--backend",
            "auto",
        ],
    ];
    for args in runs {
        let out = common::nlifs_command()
            .args(&args)
            .env_remove("XDG_RUNTIME_DIR")
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        assert!(!stderr(&out).contains("XDG_RUNTIME_DIR"), "{args:?}: {}", stderr(&out));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
