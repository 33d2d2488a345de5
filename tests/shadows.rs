//! Shadows through the command line: with `--shadows 0` the solid look keeps the bytes it had
//! before shadows existed (`tests/golden/plant2_solid_no_shadows_160x120.png` holds them, as the
//! solid look's golden did then; tolerance 0), the scene format's fields are checked with
//! located errors, and the scene writer writes them back.

mod common;

use nlifs::scene::Scene;

/// Plant 2 in the solid look with shadows 0 gives the solid look's bytes from before shadows.
#[test]
fn shadows_zero_keeps_the_solid_bytes() {
    let dir = common::temp_dir("shadows-zero");
    let png = dir.join("render.png");
    let scene_path = common::scene_path("plant2");
    let args = [
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
        "--mode",
        "closest",
        "--shadows",
        "0",
    ];
    let out = common::run_nlifs(&args);
    assert!(out.status.success(), "nlifs render failed: {}", String::from_utf8_lossy(&out.stderr));
    let actual = image::open(&png).unwrap().to_rgb8();
    common::assert_golden_exact("plant2_solid_no_shadows_160x120", &actual);
    let _ = std::fs::remove_dir_all(&dir);
}

const GRID: &str = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\nz = [0, 1]\n\
    [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0, 0], [0, 0.5, 0], [0, 0, 0.5]]\n";

/// Out-of-range values are errors that name the field and its line; good values read back
/// through the writer unchanged, keyed ones included.
#[test]
fn light_fields_are_checked_and_written_back() {
    for (field, value) in [("shadows", "1.5"), ("light_yaw_deg", "200"), ("light_pitch_deg", "-91")] {
        let text = format!("{GRID}[render]\n{field} = {value}\n");
        let err = Scene::parse(&text, "bad.toml").unwrap_err().to_string();
        assert!(err.contains(&format!("render.{field}")) && err.contains("bad.toml:10:"), "{field}: {err}");
    }
    let text = format!(
        "{GRID}[render]\nshadows = 0.25\nlight_yaw_deg = 40.0\nlight_pitch_deg = -10.0\n\
         [timeline]\nduration_secs = 2\n[[key]]\nt_secs = 0\n[key.render]\nshadows = 0.5\n\
         [[key]]\nt_secs = 2\n[key.render]\nshadows = 1.0\nlight_yaw_deg = 80.0\n"
    );
    let scene = Scene::parse(&text, "good.toml").unwrap();
    assert_eq!(scene.render.shadows, Some(0.25));
    assert_eq!((scene.render.light_yaw_deg, scene.render.light_pitch_deg), (40.0, -10.0));
    // Halfway between the keys (linear interpolation by default): shadows 0.75; the yaw is keyed
    // at the second key only, so it holds that key's value.
    let at = scene.render_at(1.0);
    assert!((at.shadows.unwrap() - 0.75).abs() < 1e-6, "{:?}", at.shadows);
    let written = scene.to_toml();
    let again = Scene::parse(&written, "written.toml").unwrap();
    assert_eq!(again.render, scene.render, "{written}");
    assert_eq!(again.timeline, scene.timeline, "{written}");
}
