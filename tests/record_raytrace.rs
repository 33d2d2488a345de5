//! `nlifs record --renderer raytrace`: ray-traced sequences keep the chaos-game recorder's
//! guarantees (deterministic bytes, chunks, `--resume` that keeps complete frames of the same
//! settings only), and a frame is `nlifs snapshot` of its time seen by its camera. Also the
//! record flags that do not apply to the chosen renderer or backend, refused with exit 2.

mod common;

use std::path::{Path, PathBuf};

use nlifs::record;

/// twist-anim with its camera target fixed, so that the camera at any time depends on the
/// scene only (the recorder frames on the timeline's bounds, a snapshot on W^n(A)'s: with the
/// target and distance given, both give the scene's camera at t).
fn fixed_camera_scene(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(common::scene_path("twist-anim")).unwrap();
    assert!(text.contains("\n[camera]\n"));
    let path = dir.join("twist-fixed.toml");
    std::fs::write(&path, text.replacen("\n[camera]\n", "\n[camera]\ntarget = [0, 0, 0]\n", 1)).unwrap();
    path
}

/// Tiny traced frames: 48×36, 1 sample a pixel, W^3(A), 4 fps (frame k at k/4 s, exact).
const TRACE_ARGS: [&str; 12] =
    ["--renderer", "raytrace", "--fps", "4", "--width", "48", "--height", "36", "--spp", "1", "--depth", "3"];

fn record_traced(scene: &Path, dir: &Path, extra: &[&str]) -> String {
    let out = common::nlifs_command()
        .arg("record")
        .arg(scene)
        .arg("-o")
        .arg(dir)
        .args(TRACE_ARGS)
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "nlifs record --renderer raytrace failed: {stderr}");
    stderr
}

fn frame_bytes(dir: &Path, k: u32) -> Vec<u8> {
    std::fs::read(record::frame_path(dir, k)).unwrap()
}

#[test]
fn traced_recordings_are_deterministic_chunkable_and_resumable() {
    let (one, chunks) = (common::temp_dir("trace-one"), common::temp_dir("trace-chunks"));
    let scene = common::scene_path("twist-anim");
    let stderr = record_traced(&scene, &one, &["--frames", "0..3"]);
    assert!(stderr.contains("ray-traced") && stderr.contains("wrote 3 frames"), "{stderr}");
    // The same frames in two chunks, as a job array would make them.
    record_traced(&scene, &chunks, &["--frames", "0..1"]);
    record_traced(&scene, &chunks, &["--frames", "1..3"]);
    for k in 0..3 {
        assert!(frame_bytes(&one, k) == frame_bytes(&chunks, k), "frame {k} differs between one run and chunks");
    }
    // The frames show the attractor and change over time (the camera orbits, the pieces twist).
    let img = image::open(record::frame_path(&one, 1)).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (48, 36));
    assert_ne!(frame_bytes(&one, 0), frame_bytes(&one, 1));
    // --resume keeps complete frames and redoes a deleted and a truncated one, to the same bytes.
    let original: Vec<Vec<u8>> = (0..3).map(|k| frame_bytes(&one, k)).collect();
    std::fs::remove_file(record::frame_path(&one, 0)).unwrap();
    std::fs::write(record::frame_path(&one, 2), &original[2][..original[2].len() / 2]).unwrap();
    let stderr = record_traced(&scene, &one, &["--frames", "0..3", "--resume"]);
    assert!(stderr.contains("1 of 3 frames already complete"), "{stderr}");
    for (k, bytes) in original.iter().enumerate() {
        assert!(&frame_bytes(&one, k as u32) == bytes, "frame {k} after resume");
    }
    // Traced frames of other options (no shadows) are not kept by a resume; nor are chaos-game
    // frames kept by a traced resume.
    let stderr = record_traced(&scene, &one, &["--frames", "0..3", "--resume", "--no-shadows"]);
    assert!(stderr.contains("wrote 3 frames") && !stderr.contains("already complete"), "{stderr}");
    let chaos = common::temp_dir("trace-over-chaos");
    let out = common::run_nlifs(&[
        "record",
        scene.to_str().unwrap(),
        "-o",
        chaos.to_str().unwrap(),
        "--fps",
        "4",
        "--width",
        "48",
        "--height",
        "36",
        "--frames",
        "0..2",
        "--points-per-frame",
        "5000",
        "--backend",
        "cpu",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = record_traced(&scene, &chaos, &["--frames", "0..2", "--resume"]);
    assert!(!stderr.contains("already complete"), "{stderr}");
    for dir in [one, chunks, chaos] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Frame k of a traced recording has the pixels of `nlifs snapshot --time k/fps` with the same
/// size and options (the PNGs' text chunks differ: they name the command).
#[test]
fn a_traced_frame_is_the_snapshot_of_its_time() {
    let dir = common::temp_dir("trace-snapshot");
    let scene = fixed_camera_scene(&dir);
    let frames = dir.join("frames");
    record_traced(&scene, &frames, &["--frames", "1..3"]);
    for (k, t) in [(1u32, "0.25"), (2, "0.5")] {
        let still = dir.join(format!("snapshot_{k}.png"));
        let out = common::run_nlifs(&[
            "snapshot",
            scene.to_str().unwrap(),
            "-o",
            still.to_str().unwrap(),
            "--time",
            t,
            "--width",
            "48",
            "--height",
            "36",
            "--spp",
            "1",
            "--depth",
            "3",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let a = image::open(record::frame_path(&frames, k)).unwrap().to_rgb8();
        let b = image::open(&still).unwrap().to_rgb8();
        assert!(a == b, "frame {k} differs from the snapshot at t = {t} s");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Flags of the other renderer, a layered format for the tracer, and the GPU without an
/// adapter: exit 2 with a message naming the flag, nothing written.
#[test]
fn flags_that_do_not_apply_are_refused() {
    let dir = common::temp_dir("trace-bad");
    let out_dir = dir.join("frames");
    let scene = common::scene_path("twist-anim");
    let cases: [(&[&str], &str); 6] = [
        (&["--renderer", "raytrace", "--points-per-frame", "1000"], "--points-per-frame"),
        (&["--renderer", "raytrace", "--format", "exr"], "8-bit PNG"),
        (&["--renderer", "raytrace", "--transparent"], "8-bit PNG"),
        (&["--renderer", "raytrace", "--backend", "gpu"], "--backend gpu"),
        (&["--spp", "2"], "--spp applies to --renderer raytrace"),
        (&["--renderer", "chaos", "--no-ground"], "--no-ground applies to --renderer raytrace"),
    ];
    for (args, needle) in cases {
        let out = common::nlifs_command()
            .arg("record")
            .arg(&scene)
            .arg("-o")
            .arg(&out_dir)
            .args(["--frames", "0..1", "--width", "32", "--height", "24"])
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: expected {needle:?} in {stderr}");
        assert!(!out_dir.exists(), "{args:?} wrote {}", out_dir.display());
    }
    // No adapter: a backend that this platform does not have.
    let out = common::nlifs_command()
        .env("WGPU_BACKEND", "metal")
        .arg("record")
        .arg(&scene)
        .arg("-o")
        .arg(&out_dir)
        .args(["--frames", "0..1", "--width", "32", "--height", "24", "--backend", "gpu"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no GPU adapter"), "{stderr}");
    assert!(!out_dir.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
