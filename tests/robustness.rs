//! Every input works or says why: hostile scene files, numbers and paths must give a located
//! error (exit code 2 on the command line) and never a panic, a silent wrap-around, an unbounded
//! read or debris. One test (or a few) per family of problems found by fuzzing nlifs; the
//! property tests over the scene format and the command line live in `robustness_props.rs`.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use nlifs::scene::{LoadError, Scene, SceneError};

/// A scratch folder of this test binary, emptied first, removed when the test passes.
fn scratch(name: &str) -> common::TempDir {
    common::temp_dir(&format!("robustness-{name}"))
}

fn nlifs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nlifs")).args(args).output().expect("nlifs runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small 2D scene: the unit square, one builder function, the given extra text.
fn builder_scene(grid: &str, extra: &str) -> String {
    format!(
        "version = 1\n[grid]\n{grid}\n[[function]]\nkind = \"builder\"\nsteps = [{{ op = \"scale\", by = 0.5 }}]\n{extra}\n"
    )
}

const SIERPINSKI: &str = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n\
[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n\
[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]\n\
[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.25, 0.5]\n";

fn parse_err(text: &str) -> SceneError {
    match Scene::parse(text, "t.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

/// The message is located and in the user's words: it names the field, and no Rust type.
fn assert_user_words(e: &SceneError, field: &str) {
    let text = e.to_string();
    assert!(text.starts_with("t.toml:"), "{text}");
    assert_eq!(e.field.as_deref(), Some(field), "{text}");
    assert!(text.contains(&format!("`{field}`")), "{text}");
    for word in ["Toml", "untagged", "f64", "i64", "u32", "sequence", "struct "] {
        assert!(!text.contains(word), "`{word}` in: {text}");
    }
}

// Family 1: an axis whose width overflows f64 panicked in every command (clamp with NaN bounds).

#[test]
fn an_axis_past_f64_range_is_a_located_error() {
    let text = builder_scene("x = [0, 1]\ny = [-1e308, 1e308]", "");
    let e = parse_err(&text);
    assert_eq!(e.field.as_deref(), Some("grid.y"), "{e}");
    assert_eq!((e.line, e.column), (4, 5), "{e}");
}

#[test]
fn grid_code_does_not_panic_on_an_overflowing_or_nan_grid() {
    use glam::DVec3;
    use nlifs::model::{GridMap, RectGrid};
    let grid = RectGrid::uniform(DVec3::new(0.0, -1e308, 0.0), DVec3::new(1.0, 1e308, 0.0), [3, 3, 1]);
    assert!(grid.axes[1].iter().all(|y| y.is_finite()), "{:?}", grid.axes[1]);
    assert!(grid.validate().is_err(), "a span past f64 passes validation");
    let map = GridMap::from_fn(grid, |p| 0.5 * p);
    let _ = map.eval(DVec3::new(0.5, 0.0, 0.0));
    let _ = map.eval(DVec3::NAN);
    let nan_grid = RectGrid { axes: [vec![f64::NAN, 1.0], vec![0.0, f64::NAN], vec![0.0]] };
    let _ = GridMap::identity(nan_grid).eval(DVec3::new(0.5, 0.5, 0.0));
}

#[test]
fn builder_steps_that_overflow_are_a_located_error() {
    let text = "version = 1\n[grid]\nx = [0, 1e18]\ny = [0, 1]\n[[function]]\nkind = \"builder\"\n\
                steps = [{ op = \"scale\", by = 1e150 }, { op = \"scale\", by = 1e150 }, { op = \"scale\", by = 1e150 }]\n";
    let e = parse_err(text);
    assert_eq!(e.field.as_deref(), Some("function[0].steps"), "{e}");
}

// Family 8: messages in the user's words, located; exit codes.

#[test]
fn serde_messages_name_the_field_in_the_users_words() {
    let cases: [(&str, &str); 6] = [
        ("version = 1\n[grid]\nx = [0, \"1\"]\ny = [0, 1]\n", "grid.x"),
        ("version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[render]\nwidth = \"9\"\n", "render.width"),
        ("version = 1\ngrid = 5\n", "grid"),
        (
            "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[[function]]\nkind = \"affine\"\ncolor = 5\nmatrix = [[1, 0], [0, 1]]\n",
            "function[0].color",
        ),
        (
            "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[[function]]\nkind = \"builder\"\nsteps = [{ op = \"scale\", by = \"big\" }]\n",
            "function[0].steps.by",
        ),
        ("version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[camera]\nyaw_deg = \"1\"\n", "camera.yaw_deg"),
    ];
    for (text, field) in cases {
        assert_user_words(&parse_err(text), field);
    }
}

#[test]
fn invalid_utf8_has_a_line_and_column() {
    let dir = scratch("utf8");
    let path = dir.join("bad.toml");
    std::fs::write(&path, b"version = 1\n# caf\xe9\n").unwrap();
    match Scene::load(&path) {
        Err(LoadError::Scene(e)) => assert_eq!((e.line, e.column), (2, 6), "{e}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn os_errors_are_printed_once_and_exit_2() {
    let o = nlifs(&["info", "/nonexistent/scene.toml"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let text = stderr(&o);
    assert_eq!(text.matches("No such file").count(), 1, "{text}");
}

#[test]
fn output_path_errors_exit_2() {
    let dir = scratch("outputs");
    let scene = dir.join("s.toml");
    std::fs::write(&scene, SIERPINSKI).unwrap();
    std::fs::create_dir_all(dir.join("folder.png")).unwrap();
    std::fs::write(dir.join("file"), b"").unwrap();
    let folder = dir.join("folder.png");
    let under_file = dir.join("file/out.png");
    for out in [folder.to_str().unwrap(), under_file.to_str().unwrap(), "/proc/nlifs-out.png"] {
        let o = nlifs(&[
            "snapshot",
            scene.to_str().unwrap(),
            "-o",
            out,
            "--width",
            "16",
            "--height",
            "12",
            "--depth",
            "2",
            "--spp",
            "1",
        ]);
        assert_eq!(o.status.code(), Some(2), "{out}: {}", stderr(&o));
        assert!(stderr(&o).contains("cannot write"), "{out}: {}", stderr(&o));
    }
    // `render` writes through the image outputs: the same, and the reason said once.
    let o = nlifs(&["render", scene.to_str().unwrap(), "-o", "/proc/nlifs-out.png", "--points", "1000"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let reason = "no file can be created there";
    assert_eq!(stderr(&o).matches(reason).count(), 1, "{}", stderr(&o));
}

#[test]
fn a_read_only_folder_is_bad_input() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("readonly");
    let ro = dir.join("ro");
    std::fs::create_dir_all(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    let result = nlifs::io::write_atomic(&ro.join("out.png"), |w| w.write_all(b"x"));
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    // Root writes into read-only folders; then there is nothing to test.
    if let Err(e) = result {
        let w = nlifs::io::WriteError::of(&e).expect("a WriteError");
        assert!(w.is_bad_input(), "{w}");
    }
}

// Family 2: every number has a stated range.

#[test]
fn camera_angles_must_be_finite_and_bounded() {
    for value in ["nan", "inf", "-inf", "1e39"] {
        let text = format!("{SIERPINSKI}[camera]\nyaw_deg = {value}\n");
        let e = parse_err(&text);
        assert_eq!(e.field.as_deref(), Some("camera.yaw_deg"), "{value}: {e}");
        let text = format!("{SIERPINSKI}[[key]]\nt_secs = 0\n[key.camera]\nyaw_deg = {value}\n");
        let e = parse_err(&text);
        assert_eq!(e.field.as_deref(), Some("key[0].camera.yaw_deg"), "{value}: {e}");
    }
}

#[test]
fn cli_numbers_are_checked_by_their_parsers() {
    let dir = scratch("cli-numbers");
    let scene = dir.join("s.toml");
    std::fs::write(&scene, SIERPINSKI).unwrap();
    let s = scene.to_str().unwrap();
    let out = dir.join("o.png");
    let o = out.to_str().unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec!["info", s, "--time", "nan"],
        vec!["info", s, "--time", "inf"],
        vec!["info", s, "--time", "-1"],
        vec!["snapshot", s, "-o", o, "--stop-pixels", "nan"],
        vec!["snapshot", s, "-o", o, "--stop-pixels", "-1"],
        vec!["snapshot", s, "-o", o, "--background", "#+12345"],
        vec!["snapshot", s, "-o", o, "--time", "1e300"],
        vec!["render", s, "-o", o, "--points", "1125899906842624"],
        vec!["render", s, "-o", o, "--time", "nan"],
    ];
    for args in cases {
        let out = nlifs(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    }
    let o = nlifs(&["render", s, "-o", o, "--points", "1125899906842624"]);
    assert!(stderr(&o).contains("1099511627776"), "the limit is not named: {}", stderr(&o));
}

// Family 3: one point limit; probabilities that overflow their sum.

#[test]
fn the_scene_and_the_cli_share_the_point_limit() {
    use nlifs::scene::spec::MAX_POINTS;
    let text = format!("{SIERPINSKI}[render]\npoints = {}\n", MAX_POINTS + 1);
    let e = parse_err(&text);
    assert!(e.to_string().contains(&MAX_POINTS.to_string()), "{e}");
    let text = format!("{SIERPINSKI}[render]\npoints = {MAX_POINTS}\n");
    assert!(Scene::parse(&text, "t.toml").is_ok());
}

#[test]
fn huge_probabilities_normalise_without_overflow() {
    let text = SIERPINSKI.replace("kind = \"affine\"", "kind = \"affine\"\nprobability = 1e308");
    let scene = Scene::parse(&text, "t.toml").unwrap();
    let p = scene.at(0.0).probabilities();
    for x in &p {
        assert!((x - 1.0 / 3.0).abs() < 1e-12, "{p:?}");
    }
}

// Family 5: the same warnings everywhere, and a word when nothing was drawn.

#[test]
fn warnings_come_from_one_function() {
    let text = SIERPINSKI.replace("matrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]", "matrix = [[1.5, 0], [0, 0.5]]");
    let scene = Scene::parse(&text, "t.toml").unwrap();
    let warnings = nlifs::scene::warnings::scene_warnings(&scene, 0.0);
    assert!(warnings.iter().any(|w| w.contains("may not be contractive")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.contains("not contained")), "{warnings:?}");
    let blank = image::RgbImage::from_pixel(4, 4, image::Rgb([0, 0, 0]));
    assert!(nlifs::scene::warnings::coverage_warning(&blank, [0.0; 3]).is_some());
    let mut drawn = blank.clone();
    drawn.put_pixel(1, 1, image::Rgb([200, 0, 0]));
    assert!(nlifs::scene::warnings::coverage_warning(&drawn, [0.0; 3]).is_none());
}

#[test]
fn snapshot_says_when_no_ray_hit_the_attractor() {
    let dir = scratch("snapshot-away");
    let scene = dir.join("s.toml");
    let text = format!("{SIERPINSKI}[camera]\ntarget = [1000, 1000, 1000]\ndistance = 1\n");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("o.png");
    let o = nlifs(&[
        "snapshot",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "12",
        "--depth",
        "2",
        "--spp",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("no ray hit"), "{}", stderr(&o));
}

#[test]
fn render_and_record_say_when_no_point_landed() {
    let dir = scratch("render-away");
    let scene = dir.join("s.toml");
    let away = format!("{SIERPINSKI}[camera]\ntarget = [1000, 1000, 1000]\ndistance = 1\n");
    std::fs::write(&scene, format!("{away}[timeline]\nduration_secs = 1.0\n")).unwrap();
    let png = dir.join("o.png");
    let size = ["--width", "16", "--height", "12"];
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--points", "20000"];
    args.extend(size);
    let o = nlifs(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("the picture is empty"), "{}", stderr(&o));
    let frames = dir.join("frames");
    let mut args = vec!["record", scene.to_str().unwrap(), "-o", frames.to_str().unwrap(), "--fps", "2"];
    args.extend(size);
    args.extend(["--points-per-frame", "20000"]);
    let o = nlifs(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("3 of 3 frames are empty"), "{}", stderr(&o));
}

#[test]
fn a_closed_pipe_ends_quietly() {
    use std::io::Read;
    // `nlifs info scene | head -1`: the reader goes away after the first bytes; nlifs must end
    // as Unix tools do (SIGPIPE), not panic in println!. (info computes its report between
    // its first lines and the rest, so the later lines meet the closed pipe.)
    let mut child = Command::new(env!("CARGO_BIN_EXE_nlifs"))
        .args(["info", concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/plant2.toml")])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 1];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(out.status.code(), Some(101), "{err}");
}

// Family 9: no debris.

#[test]
fn writes_leave_no_temporary_files_and_clean_stale_ones() {
    let dir = scratch("debris");
    let out = dir.join("out.glb");
    // A temporary file of a process that no longer runs (no pid reaches 2^32 - 2).
    let stale = dir.join(".out.glb.4294967294.tmp");
    std::fs::write(&stale, vec![0u8; 1000]).unwrap();
    let listing = |dir: &Path| -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    let during = std::cell::RefCell::new(Vec::new());
    nlifs::io::write_atomic(&out, |w| {
        *during.borrow_mut() = listing(&dir);
        w.write_all(b"glTF")
    })
    .unwrap();
    assert!(!stale.exists(), "a stale temporary file stays");
    assert_eq!(listing(&dir), vec!["out.glb".to_string()]);
    if cfg!(target_os = "linux") {
        // The file being written has no name, so a kill at that moment leaves nothing.
        assert_eq!(*during.borrow(), Vec::<String>::new(), "a named temporary file while writing");
    }
    // A failed write leaves nothing either.
    let failed = nlifs::io::write_atomic(&dir.join("b.glb"), |_| Err(std::io::Error::other("stop")));
    assert!(failed.is_err());
    assert_eq!(listing(&dir), vec!["out.glb".to_string()]);
}

// Family 7: capped reads and sizes.

#[test]
fn reading_dev_zero_is_refused() {
    match Scene::load(Path::new("/dev/zero")) {
        Err(LoadError::TooLarge { .. }) => {}
        other => panic!("{other:?}"),
    }
}

#[test]
fn glb_lengths_past_32_bits_are_refused() {
    let e = nlifs::export::glb_lengths(100, 5 << 30).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::FileTooLarge);
    assert!(e.to_string().contains("4 GiB"), "{e}");
    assert!(nlifs::export::glb_lengths(100, 1000).is_ok());
}

/// A glTF with one triangle whose accessors are given by `index_count` and `uri`.
fn gltf_text(uri: &str, index_count: usize) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5125,"count":{index_count},"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":12}}],
"buffers":[{{"byteLength":48,"uri":"{uri}"}}]}}"#
    )
}

#[test]
fn gltf_buffers_are_capped_and_accessors_checked() {
    use glam::DVec3;
    let dir = scratch("gltf");
    let path = dir.join("zero.gltf");
    std::fs::write(&path, gltf_text("/dev/zero", 3)).unwrap();
    let e = nlifs::raytrace::mesh::load_gltf(&path, DVec3::ZERO, DVec3::ONE).unwrap_err();
    // Refused before it is opened: buffers lie in the model's folder (tests/gltf_input.rs).
    assert!(e.to_string().contains("not a path relative to the model's folder"), "{e}");
    // 3 positions and 3 indices, but the index accessor claims 6 (past its 12-byte view).
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u32, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("tri.bin"), &bin).unwrap();
    let good = dir.join("good.gltf");
    std::fs::write(&good, gltf_text("tri.bin", 3)).unwrap();
    assert!(nlifs::raytrace::mesh::load_gltf(&good, DVec3::ZERO, DVec3::ONE).is_ok());
    let bad = dir.join("bad.gltf");
    std::fs::write(&bad, gltf_text("tri.bin", 6)).unwrap();
    assert!(nlifs::raytrace::mesh::load_gltf(&bad, DVec3::ZERO, DVec3::ONE).is_err());
}

// Family 6: bounded time.

#[test]
fn the_timeline_check_reuses_unchanged_functions_and_caps_its_work() {
    use nlifs::scene::timeline_check::check_timeline;
    // Four 3D builders at the largest resolution and 20 keys that change only the camera:
    // the functions are checked once, not at every one of the 180 sampled times.
    let mut text = String::from("version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\nz = [0, 1]\n");
    for i in 0..4 {
        text += &format!(
            "[[function]]\nkind = \"builder\"\nresolution = [64, 64, 64]\nsteps = [{{ op = \"scale\", by = 0.5 }}, {{ op = \"translate\", by = [{}, 0, 0] }}]\n",
            0.05 * i as f64
        );
    }
    for k in 0..20 {
        text += &format!("[[key]]\nt_secs = {k}\n[key.camera]\nyaw_deg = {}\n", 10 * k);
    }
    let scene = Scene::parse(&text, "t.toml").unwrap();
    let start = std::time::Instant::now();
    let check = check_timeline(&scene, 8).unwrap();
    assert!(check.problems.is_empty(), "{:?}", check.problems);
    assert_eq!(check.samples_per_interval, 8);
    // 4 bounds of 16 M matrices each: seconds, not the 30 min of checking each time.
    assert!(start.elapsed().as_secs() < 120, "{:?}", start.elapsed());
}

#[test]
fn the_timeline_check_samples_more_thinly_past_its_cap() {
    use nlifs::scene::timeline_check::{MAX_CHECK_MATRICES, check_timeline_capped};
    // One 9×9 builder (64 cells of 4 matrices) changed by 5 keys: 7 stretches.
    let mut text = String::from("version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n");
    text += "[[function]]\nname = \"f\"\nkind = \"builder\"\nsteps = [{ op = \"scale\", by = 0.5 }]\n";
    for k in 0..5 {
        text += &format!(
            "[[key]]\nt_secs = {k}\n[[key.function]]\nname = \"f\"\nsteps = [{{ op = \"scale\", by = {} }}]\n",
            0.4 + 0.01 * k as f64
        );
    }
    let scene = Scene::parse(&text, "t.toml").unwrap();
    let per_time = 64 * 4;
    let full = check_timeline_capped(&scene, 8, MAX_CHECK_MATRICES, &mut |_, _| {}).unwrap();
    assert_eq!(full.samples_per_interval, 8);
    // A cap of three times per stretch: 8 → 4 → 2 sampled between keys.
    let capped = check_timeline_capped(&scene, 8, per_time * 7 * 3, &mut |_, _| {}).unwrap();
    assert_eq!(capped.samples_per_interval, 2);
    assert!(capped.samples < full.samples);
    let keys_only = check_timeline_capped(&scene, 8, 1, &mut |_, _| {}).unwrap();
    assert_eq!((keys_only.samples_per_interval, keys_only.samples), (0, 5));
}

#[test]
fn record_refuses_runs_past_its_frame_cap() {
    let dir = scratch("record-cap");
    let scene = dir.join("s.toml");
    let text = format!("{SIERPINSKI}[timeline]\nduration_secs = 1e8\n[[key]]\nt_secs = 0\n");
    std::fs::write(&scene, text).unwrap();
    let start = std::time::Instant::now();
    let o = nlifs(&["record", scene.to_str().unwrap(), "-o", dir.join("frames").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(&nlifs::record::MAX_FRAMES_PER_RUN.to_string()), "{}", stderr(&o));
    assert!(start.elapsed().as_secs() < 60, "{:?}", start.elapsed());
}

// Family 4: scale. The renderers work in f32; a grid too small, too large or too far from the
// origin for them is refused with the supported range instead of rendering blank.

#[test]
fn grid_extents_outside_the_supported_range_are_refused() {
    use nlifs::scene::spec::{GRID_EXTENT_RANGE, MAX_GRID_OFFSET_RATIO};
    let scene = |y: &str| {
        format!(
            "version = 1\n[grid]\nx = [0, 1]\ny = {y}\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n"
        )
    };
    for y in ["[0, 5e-324]", "[0, 1e-9]", "[0, 1e19]", "[1e6, 1000001]"] {
        let e = parse_err(&scene(y));
        assert_eq!(e.field.as_deref(), Some("grid.y"), "{y}: {e}");
    }
    let (lo, hi) = GRID_EXTENT_RANGE;
    for y in [
        format!("[0, {lo:e}]"),
        format!("[0, {hi:e}]"),
        format!("[{}, {MAX_GRID_OFFSET_RATIO:e}]", MAX_GRID_OFFSET_RATIO - 1.0),
    ] {
        assert!(Scene::parse(&scene(&y), "t.toml").is_ok(), "{y}");
    }
}
