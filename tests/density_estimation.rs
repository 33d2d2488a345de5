//! Density estimation (`src/resolve/density_estimation.rs`) from the outside: the scene fields
//! checked with located errors and written back, `--density-estimation` parsed and refused
//! where it cannot apply (exit 2, nothing written), off giving the bytes of a render without
//! it, and on spreading a sparse density render's covered area.

mod common;

use common::{lit_pixels, render_sparse_density, temp_dir};
use nlifs::scene::Scene;
use nlifs::scene::spec::DensityEstimation;

const BASE: &str = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n[render]\n";

/// Bad values give an error naming the field at its line (line 9: the field after `[render]`).
#[test]
fn bad_fields_give_located_errors() {
    let cases = [
        ("estimator_radius = -1\n", "`render.estimator_radius`", 9),
        ("estimator_radius = 40\n", "`render.estimator_radius`", 9),
        ("estimator_radius = nan\n", "`render.estimator_radius`", 9),
        ("estimator_radius = 4\nestimator_minimum = 5\n", "`render.estimator_minimum`", 10),
        ("estimator_radius = 4\nestimator_curve = 0\n", "`render.estimator_curve`", 10),
        ("estimator_curve = 0.5\n", "needs `estimator_radius` above 0", 9),
    ];
    for (fields, expected, line) in cases {
        let text = format!("{BASE}{fields}");
        let err = Scene::parse(&text, "bad.toml").err().unwrap_or_else(|| panic!("parsed:\n{text}"));
        let msg = err.to_string();
        assert!(msg.contains(expected), "expected `{expected}` in `{msg}`");
        assert_eq!(err.line, line, "{msg}");
    }
}

/// The fields read (defaults filled in), are written back and read again unchanged; a scene
/// without them has none (off).
#[test]
fn fields_read_and_write_back() {
    let scene = Scene::parse(&format!("{BASE}estimator_radius = 7.5\nestimator_minimum = 0.5\n"), "s.toml").unwrap();
    let de = scene.render.density_estimation.expect("on");
    assert_eq!(de, DensityEstimation { max_radius_px: 7.5, min_radius_px: 0.5, curve: 0.4 });
    let again = Scene::parse(&scene.to_toml(), "again.toml").unwrap();
    assert_eq!(again.render.density_estimation, Some(de));
    assert_eq!(Scene::parse(BASE, "off.toml").unwrap().render.density_estimation, None);
    assert_eq!(
        Scene::parse(&format!("{BASE}estimator_radius = 0\n"), "o.toml").unwrap().render.density_estimation,
        None
    );
}

/// `--density-estimation 0` writes the same bytes as no flag; radius 6 on a sparse render
/// leaves more pixels off the background; bad flags and non-PNG outputs exit 2 writing nothing.
#[test]
fn cli_flag_off_on_and_refusals() {
    let dir = temp_dir("density-estimation");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let run = |extra: &[&str], out: &str| render_sparse_density("julia", extra, out);
    let (plain, off, on) = (path("plain.png"), path("off.png"), path("on.png"));
    assert!(run(&[], &plain).status.success());
    assert!(run(&["--density-estimation", "0"], &off).status.success());
    assert!(run(&["--density-estimation", "6,0,0.4"], &on).status.success());
    assert_eq!(std::fs::read(&plain).unwrap(), std::fs::read(&off).unwrap());
    let (lit_plain, lit_on) = (lit_pixels(&plain), lit_pixels(&on));
    assert!(lit_on > 2 * lit_plain, "spread {lit_on} vs plain {lit_plain}");
    // The filtered image goes through the tone map too: one stop more exposure doubles the
    // linear light over the background where nothing saturates, so the summed 8-bit levels
    // above the background grow by well over a fifth (sRGB encoding compresses the factor 2).
    let brighter = path("brighter.png");
    assert!(run(&["--density-estimation", "6,0,0.4", "--exposure", "1"], &brighter).status.success());
    let above_background = |p: &str| {
        let img = image::open(p).unwrap().to_rgb8();
        let bg = *img.get_pixel(0, 0);
        img.pixels().map(|px| (0..3).map(|k| px.0[k].saturating_sub(bg.0[k]) as u64).sum::<u64>()).sum::<u64>()
    };
    let (sum_on, sum_brighter) = (above_background(&on), above_background(&brighter));
    assert!(sum_brighter as f64 > 1.2 * sum_on as f64, "exposure +1: {sum_brighter} vs {sum_on}");
    for (flag, out) in [("-1", "neg.png"), ("5,6", "min.png"), ("5,0,0", "curve.png"), ("x", "nan.png")] {
        let o = run(&["--density-estimation", flag], &path(out));
        assert_eq!(o.status.code(), Some(2), "{flag}: {}", String::from_utf8_lossy(&o.stderr));
        assert!(!dir.join(out).exists());
    }
    let o = run(&["--density-estimation", "6"], &path("on.exr"));
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!dir.join("on.exr").exists());
}
