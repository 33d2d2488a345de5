//! Small golden images of `nlifs render` on the deterministic CPU path, compared pixel for pixel
//! with `tests/golden/<name>.png`. The CPU chaos game and its splat are pure functions of the
//! scene, seed, point count and size, so any change of these bytes is a change of behaviour to
//! look at (the determinism test in `foundation.rs` only compares the renderer with itself).
//! `REPLACE=1 cargo test --release --test cpu_golden` rewrites the images; on a difference the
//! actual and difference images are written and the message names them.

mod common;

/// Renders `scene` through the binary at 160×120 with a fixed seed and point count and compares
/// the result with the golden image `golden`.
fn check_render(golden: &str, scene: &str, extra_args: &[&str]) {
    // One directory per golden and argument list: tests of one golden run in parallel.
    let dir = common::temp_dir(&format!("golden-{golden}-{}", extra_args.join("").replace('-', "")));
    let png = dir.join("render.png");
    let scene_path = common::scene_path(scene);
    let mut args = vec![
        "render",
        scene_path.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--width",
        "160",
        "--height",
        "120",
        "--points",
        "200000",
        "--seed",
        "7",
        "--backend",
        "cpu",
    ];
    args.extend(extra_args);
    let out = common::run_nlifs(&args);
    assert!(out.status.success(), "nlifs render failed: {}", String::from_utf8_lossy(&out.stderr));
    let actual = image::open(&png).unwrap().to_rgb8();
    common::assert_golden_exact(golden, &actual);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Plant 2 of the paper (3D, closest point) in the paper's look: depth-cued flat colour, one
/// setting away from the default.
#[test]
fn plant2_closest_matches_golden() {
    check_render("plant2_160x120", "plant2", &["--mode", "closest", "--look", "paper"]);
}

/// Plant 2 in the default look of 3D scenes (the solid look: normals from the depth buffer,
/// key and fill light, occlusion).
#[test]
fn plant2_default_solid_look_matches_golden() {
    check_render("plant2_solid_160x120", "plant2", &["--mode", "closest"]);
}

/// The Julia set scene (2D) in density mode: the log-density tone curve and per-function colour.
#[test]
fn julia_density_matches_golden() {
    check_render("julia_density_160x120", "julia", &["--mode", "density"]);
}

/// flam3's tone controls at their neutral values (gamma 1, exposure 0, vibrancy 1, highlight
/// power off) give the density image of the code before them: the golden above, byte for byte.
#[test]
fn julia_density_neutral_tone_matches_golden() {
    check_render(
        "julia_density_160x120",
        "julia",
        &["--mode", "density", "--gamma", "1", "--exposure", "0", "--vibrancy", "1", "--highlight-power", "-1"],
    );
}
