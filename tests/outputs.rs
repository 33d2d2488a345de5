//! Image outputs, checked through the command line: EXR layers and 16-bit PNG read back by an
//! independent reader (OpenImageIO's `oiiotool`), transparent backgrounds, the scene carried in
//! PNGs, recorded frames in the float formats, and still split into parts and merged to the
//! same bytes as one render.
//!
//! `oiiotool` (Debian's openimageio-tools) is optional on a developer's machine: without it the
//! reader checks skip with a loud message, unless `CI` or `NLIFS_REQUIRE_TOOLS=1` is set, where
//! `.ci/run` installs it and a missing reader fails.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use nlifs::output::png::{SCENE_KEYWORD, scene_from_png, text_chunks};

/// `oiiotool --info -v PATH` (stdout), or None after a loud skip where oiiotool is missing.
fn oiio_info(path: &Path) -> Option<String> {
    match Command::new("oiiotool").arg("--info").arg("-v").arg(path).output() {
        Ok(out) => {
            assert!(
                out.status.success(),
                "oiiotool --info failed on {}: {}",
                path.display(),
                String::from_utf8_lossy(&out.stderr)
            );
            Some(String::from_utf8_lossy(&out.stdout).into_owned())
        }
        Err(e) => {
            let why = format!(
                "oiiotool (Debian: openimageio-tools) cannot run ({e}), so {} is not checked by an independent reader",
                path.display()
            );
            assert!(!common::tools_required(), "CI or NLIFS_REQUIRE_TOOLS=1 but {why}");
            eprintln!("\n*** SKIPPED: {why} ***\n");
            None
        }
    }
}

/// Runs nlifs; panics with its stderr unless it exits with `code`.
fn nlifs(args: &[&str], code: i32) -> String {
    let out = common::run_nlifs(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "nlifs {}: {stderr}", args.join(" "));
    stderr
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Small, fast render arguments for `scene`.
fn small(scene: &str) -> Vec<String> {
    let path = common::scene_path(scene);
    ["render", s(&path), "--width", "96", "--height", "72", "--points", "300000"].map(String::from).to_vec()
}

fn render(scene: &str, extra: &[&str]) {
    let mut args = small(scene);
    args.extend(extra.iter().map(|a| a.to_string()));
    nlifs(&args.iter().map(String::as_str).collect::<Vec<_>>(), 0);
}

/// `oiiotool --info -v` names `channels` (in its own order: R G B A first), the size and the
/// sample format.
fn assert_info(info: &str, channels: &[&str], size: &str, format: &str) {
    let head = info
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
        .find(|l| l.contains(size))
        .unwrap_or_else(|| panic!("expected {size} in:\n{info}"));
    assert!(head.contains(format), "expected {format} in `{head}`");
    let list =
        info.lines().find(|l| l.contains("channel list")).unwrap_or_else(|| panic!("no channel list in:\n{info}"));
    let names: Vec<&str> =
        list.split(':').nth(1).unwrap().split(',').map(|c| c.split_whitespace().next().unwrap()).collect();
    assert_eq!(names, channels, "in `{list}`");
}

#[test]
fn exr_has_the_layers_of_its_mode() {
    let dir = common::temp_dir("outputs-exr");
    let closest = dir.join("closest.exr");
    render("plant2", &["-o", s(&closest), "--transparent"]);
    let (names, size) = nlifs::output::exr::channels(&closest).unwrap();
    // plant2 is 3D, so the default look is the solid one and the shading normal is a layer.
    assert_eq!(
        (names.clone(), size),
        (["A", "B", "G", "N.x", "N.y", "N.z", "R", "Z", "id"].map(String::from).to_vec(), (96, 72))
    );
    let density = dir.join("density.exr");
    render("plant2", &["-o", s(&density), "--mode", "density", "--half"]);
    assert_eq!(nlifs::output::exr::channels(&density).unwrap().0, ["A", "B", "G", "R", "count"]);
    if let Some(info) = oiio_info(&closest) {
        assert_info(&info, &["R", "G", "B", "A", "Z", "id", "N.x", "N.y", "N.z"], "96 x 72", "float openexr");
        // A transparent background: the corner is empty, so alpha 0 and depth infinite.
        let out = Command::new("oiiotool").arg(&closest).args(["--ch", "A,Z", "--printinfo:stats=1"]).output().unwrap();
        let stats = String::from_utf8_lossy(&out.stdout);
        assert!(stats.contains("Min: 0.000") && stats.contains("Max: 1.000"), "alpha from 0 to 1 expected:\n{stats}");
        let infinite =
            stats.lines().find(|l| l.contains("InfCount")).unwrap_or_else(|| panic!("no InfCount in:\n{stats}"));
        assert!(infinite.split_whitespace().last() != Some("0"), "empty pixels have infinite depth: `{infinite}`");
    }
    if let Some(info) = oiio_info(&density) {
        assert_info(&info, &["R", "G", "B", "A", "count"], "96 x 72", "half/half/half/half/float openexr");
    }
}

#[test]
fn png16_has_16_bit_samples_close_to_the_8_bit_png() {
    let dir = common::temp_dir("outputs-png16");
    let (p8, p16) = (dir.join("p8.png"), dir.join("p16.png"));
    render("tapering", &["-o", s(&p8)]);
    render("tapering", &["-o", s(&p16), "--format", "png16"]);
    let wide = image::open(&p16).unwrap();
    assert_eq!(wide.color(), image::ColorType::Rgb16);
    let (wide, narrow) = (wide.to_rgb16(), image::open(&p8).unwrap().to_rgb8());
    // The same linear colour encoded to 16 bits: within half an 8-bit level of the 8-bit PNG
    // (which rounds the same value), and not a widened 8-bit image (some sample is off the
    // 257-multiples that widening gives).
    let mut fine = false;
    for (a, b) in wide.as_raw().iter().zip(narrow.as_raw()) {
        assert!((*a as f32 / 257.0 - *b as f32).abs() <= 0.5 + 1e-3, "{a} vs {b}");
        fine |= a % 257 != 0;
    }
    assert!(fine, "16-bit samples carry no more than 8 bits");
    if let Some(info) = oiio_info(&p16) {
        assert_info(&info, &["R", "G", "B"], "96 x 72", "uint16 png");
    }
    let rgba = dir.join("t.png");
    render("tapering", &["-o", s(&rgba), "--transparent", "--format", "png16"]);
    let img = image::open(&rgba).unwrap().to_rgba16();
    assert_eq!(img.get_pixel(0, 0).0[3], 0, "the background's corner is transparent");
    assert!(img.pixels().any(|p| p.0[3] == 65535), "the attractor is opaque");
}

#[test]
fn pngs_carry_their_scene() {
    let dir = common::temp_dir("outputs-scene");
    let png = dir.join("p.png");
    render("plant2", &["-o", s(&png), "--time", "0.25", "--seed", "7"]);
    let p = scene_from_png(&png).unwrap();
    assert_eq!(p.t_secs, 0.25);
    assert_eq!(p.settings["seed"], 7);
    assert_eq!(p.scene(s(&png)).unwrap(), {
        let mut scene = common::load_scene("plant2");
        scene.path = None;
        scene
    });
    let (scene, t_secs) = nlifs::output::png::load_scene_or_png(&png).unwrap();
    assert_eq!((scene.name, t_secs), (common::load_scene("plant2").name, 0.25));
    assert_eq!(p.scene(s(&png)).unwrap().to_toml(), common::load_scene("plant2").to_toml());
    // `nlifs info` reads the scene inside; a PNG without one is bad input.
    let out = common::run_nlifs(&["info", s(&png)]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("scene inside") && stdout.contains("t = 0.25 s"), "{stdout}");
    let bare = dir.join("bare.png");
    image::RgbImage::new(4, 4).save(&bare).unwrap();
    let err = nlifs(&["info", s(&bare)], 2);
    assert!(err.contains("no embedded scene"), "{err}");
    // nlifs's chunks come before the pixels.
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(text_chunks(&bytes, &png).unwrap()[0].0, SCENE_KEYWORD);
    // Recorded frames carry theirs, with the frame's time.
    let frames = dir.join("frames");
    let anim = common::scene_path("twist-anim");
    nlifs(
        &[
            "record",
            s(&anim),
            "-o",
            s(&frames),
            "--width",
            "32",
            "--height",
            "24",
            "--points-per-frame",
            "20000",
            "--frames",
            "2..3",
            "--fps",
            "4",
        ],
        0,
    );
    let p = scene_from_png(&frames.join("frame_00002.png")).unwrap();
    assert_eq!((p.t_secs, p.settings["frame"].as_u64()), (0.5, Some(2)));
}

#[test]
fn recorded_frames_in_exr_and_resume() {
    let dir = common::temp_dir("outputs-record");
    let anim = common::scene_path("twist-anim");
    let args = [
        "record",
        s(&anim),
        "-o",
        s(&dir),
        "--width",
        "32",
        "--height",
        "24",
        "--points-per-frame",
        "20000",
        "--frames",
        "0..2",
        "--fps",
        "4",
        "--format",
        "exr",
        "--motion-blur",
        "2",
    ];
    nlifs(&args, 0);
    for k in 0..2 {
        let path = dir.join(format!("frame_{k:05}.exr"));
        assert_eq!(nlifs::output::exr::channels(&path).unwrap().1, (32, 24));
    }
    let mut resume = args.to_vec();
    resume.push("--resume");
    let stderr = nlifs(&resume, 0);
    assert!(stderr.contains("2 of 2 frames already complete"), "{stderr}");
}

/// Renders part k/4 of a 4-chunk still (1.1 M points at 64 points × 4096 steps per chunk).
fn part_args(scene: &Path, k: u32, raw: &Path, seed: &str) -> Vec<String> {
    part_args_in(scene, k, raw, seed, "density")
}

fn part_args_in(scene: &Path, k: u32, raw: &Path, seed: &str, mode: &str) -> Vec<String> {
    ["render", s(scene), "--width", "80", "--height", "60", "--points", "1100000", "--seed", seed, "--mode", mode]
        .into_iter()
        .map(String::from)
        .chain(["--part".into(), format!("{k}/4"), "--raw".into(), s(raw).into()])
        .collect()
}

#[test]
fn four_parts_merge_to_the_bytes_of_one_render() {
    let dir = common::temp_dir("outputs-parts");
    let scene = common::scene_path("plant2");
    // Density, and closest mode in plant2's default (solid) look and in the paper look: the
    // merge resolves with the look the parts were rendered with.
    // And the command line's tone and density estimation.
    let cases: [(&str, &[&str]); 5] = [
        ("density", &[]),
        ("closest", &[]),
        ("closest", &["--look", "paper"]),
        ("density", &["--gamma", "2.2", "--exposure", "0.5"]),
        ("density", &["--density-estimation", "4"]),
    ];
    for (mode, look_args) in cases {
        let look_args = look_args.to_vec();
        // (EXR refuses density estimation.)
        let exts: &[&str] = if look_args.contains(&"--density-estimation") { &["png"] } else { &["png", "exr"] };
        let parts: Vec<PathBuf> = (1..=4).map(|k| dir.join(format!("p{k}.part"))).collect();
        for (k, part) in (1..=4).zip(&parts) {
            let args = part_args_in(&scene, k, part, "3", mode);
            nlifs(&[args.iter().map(String::as_str).collect::<Vec<_>>(), look_args.clone()].concat(), 0);
        }
        let full = [
            "render",
            s(&scene),
            "--width",
            "80",
            "--height",
            "60",
            "--points",
            "1100000",
            "--seed",
            "3",
            "--mode",
            mode,
        ];
        for ext in exts {
            let (one, merged) = (dir.join(format!("one.{ext}")), dir.join(format!("merged.{ext}")));
            nlifs(&[&full[..], &look_args, &["-o", s(&one)]].concat(), 0);
            // Any order of the parts.
            nlifs(&["merge", s(&parts[2]), s(&parts[0]), s(&parts[3]), s(&parts[1]), "-o", s(&merged)], 0);
            assert!(
                std::fs::read(&one).unwrap() == std::fs::read(&merged).unwrap(),
                "merged {ext} ({mode}, {look_args:?}) differs from one render"
            );
        }
    }
    let parts: Vec<PathBuf> = (1..=4).map(|k| dir.join(format!("p{k}.part"))).collect();
    for (k, part) in (1..=4).zip(&parts) {
        nlifs(&part_args(&scene, k, part, "3").iter().map(String::as_str).collect::<Vec<_>>(), 0);
    }

    // Bad input: exit 2 and nothing written.
    let out = dir.join("bad.png");
    let stderr = nlifs(&["render", s(&scene), "--part", "5/4", "--raw", s(&dir.join("x.part"))], 2);
    assert!(stderr.contains("out of range"), "{stderr}");
    let other = dir.join("other.part");
    nlifs(&part_args(&scene, 4, &other, "4").iter().map(String::as_str).collect::<Vec<_>>(), 0);
    let stderr = nlifs(&["merge", s(&parts[0]), s(&parts[1]), s(&parts[2]), s(&other), "-o", s(&out)], 2);
    assert!(stderr.contains("different stills"), "{stderr}");
    let stderr = nlifs(&["merge", s(&parts[0]), s(&parts[1]), s(&parts[2]), "-o", s(&out)], 2);
    assert!(stderr.contains("missing parts 4/4"), "{stderr}");
    let stderr =
        nlifs(&["merge", s(&parts[0]), s(&parts[0]), s(&parts[1]), s(&parts[2]), s(&parts[3]), "-o", s(&out)], 2);
    assert!(stderr.contains("given twice"), "{stderr}");
    let truncated = dir.join("truncated.part");
    let bytes = std::fs::read(&parts[3]).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    let stderr = nlifs(&["merge", s(&parts[0]), s(&parts[1]), s(&parts[2]), s(&truncated), "-o", s(&out)], 2);
    assert!(stderr.contains("truncated"), "{stderr}");
    let mut damaged = bytes.clone();
    let mid = damaged.len() - 1000;
    damaged[mid] ^= 0x40;
    std::fs::write(&truncated, &damaged).unwrap();
    let stderr = nlifs(&["merge", s(&parts[0]), s(&parts[1]), s(&parts[2]), s(&truncated), "-o", s(&out)], 2);
    assert!(stderr.contains("checksum"), "{stderr}");
    assert!(!out.exists(), "a failed merge wrote {}", out.display());
}

#[test]
fn format_and_extension_must_agree() {
    let dir = common::temp_dir("outputs-ext");
    let scene = common::scene_path("tapering");
    let stderr = nlifs(&["render", s(&scene), "-o", s(&dir.join("a.png")), "--format", "exr"], 2);
    assert!(stderr.contains(".exr"), "{stderr}");
    nlifs(&["render", s(&scene), "-o", s(&dir.join("a.jpg"))], 2);
    nlifs(&["render", s(&scene), "-o", s(&dir.join("a.png")), "--half"], 2);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing written");
}
