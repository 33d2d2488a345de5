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

/// The GPU chaos game's shadow map (`splat_shadow` in `shaders/chaos_game.wgsl`) against the
/// CPU's (`src/splat/shadow.rs`) for the same shot: plant 2 in the solid look, 320×240,
/// 2·10^6 points. Both hold the closest depth per texel of points on the same attractor,
/// drawn from different random streams, so they agree as converged minima do: the covered
/// texels differ by under 2 % of those covered, and where both hold a key the depth fractions
/// of 95 % of the texels agree within 0.01 (the map's depth range is 1).
#[test]
fn gpu_shadow_map_agrees_with_the_cpu_one() {
    let Some(ctx) = common::gpu() else { return };
    let scene = common::load_scene("plant2");
    let mut settings = scene.render_at(0.0);
    (settings.width, settings.height, settings.points) = (320, 240, 2_000_000);
    settings.mode = nlifs::scene::spec::SplatMode::Closest;
    let shot = nlifs::shot::Shot::prepare(&scene, 0.0, &settings, nlifs::shot::Framing::Fit, None).unwrap();
    let side = shot.view.shadow.expect("the solid look casts shadows").side_px as usize;
    let cpu = shot.splat(|| {}).shadow;
    let gpu = nlifs::gpu::render::render_gpu(&ctx, &shot).unwrap().framebuffer.shadow;
    assert_eq!((cpu.len(), gpu.len()), (side * side, side * side));
    let empty = nlifs::splat::EMPTY;
    let covered = |map: &[u32]| map.iter().filter(|&&k| k != empty).count();
    let (cpu_covered, gpu_covered) = (covered(&cpu), covered(&gpu));
    assert!(cpu_covered > side * side / 20, "the CPU map covers {cpu_covered} of {} texels", side * side);
    let coverage_difference = cpu_covered.abs_diff(gpu_covered) as f64 / cpu_covered as f64;
    let mut depth_differences: Vec<f64> = cpu
        .iter()
        .zip(&gpu)
        .filter(|&(&a, &b)| a != empty && b != empty)
        .map(|(&a, &b)| ((a >> 8) as f64 - (b >> 8) as f64).abs() / ((1u32 << 24) - 1) as f64)
        .collect();
    depth_differences.sort_by(f64::total_cmp);
    let p95 = depth_differences[depth_differences.len() * 95 / 100];
    eprintln!(
        "shadow maps {side}²: covered CPU {cpu_covered}, GPU {gpu_covered} ({:.2} %), 95th percentile depth difference {p95:.5}",
        100.0 * coverage_difference
    );
    assert!(coverage_difference < 0.02, "covered texels differ by {:.2} %", 100.0 * coverage_difference);
    assert!(p95 < 0.01, "95th percentile depth difference {p95}");
}
