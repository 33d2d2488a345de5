//! flam3's spatial filter in scenes (`[render] filter`, `filter_shape`; `src/resolve/filter.rs`)
//! from the outside: the fields checked with located errors and written back, `--filter` parsed
//! and refused where it cannot be, off giving the bytes of a render without it, on lighting the
//! pixels around a sparse render's points, and the flame import taking the flame's filter.

mod common;

use common::{lit_pixels, render_sparse_density, temp_dir};
use nlifs::flame::FilterShape;
use nlifs::scene::Scene;
use nlifs::scene::spec::PixelFilter;

const BASE: &str = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n[render]\n";

/// Bad values give an error naming the field at its line (line 9: the field after `[render]`).
#[test]
fn bad_fields_give_located_errors() {
    let cases = [
        ("filter = -1\n", "`render.filter`", "not in 0..=100", 9),
        ("filter = nan\n", "`render.filter`", "finite", 9),
        ("filter = 6\n", "`render.filter`", "spans 19 pixels; at most 15", 9),
        ("filter = 1\nfilter_shape = \"round\"\n", "`render.filter_shape`", "use one of gaussian", 10),
        ("filter_shape = \"box\"\n", "`render.filter_shape`", "needs `filter` above 0", 9),
    ];
    for (fields, field, why, line) in cases {
        let text = format!("{BASE}{fields}");
        let err = Scene::parse(&text, "bad.toml").err().unwrap_or_else(|| panic!("parsed:\n{text}"));
        let msg = err.to_string();
        assert!(msg.contains(field) && msg.contains(why), "expected {field} and `{why}` in `{msg}`");
        assert_eq!(err.line, line, "{msg}");
    }
}

/// The fields are read, written back and read again unchanged; a scene without them, or with a
/// radius of 0, has no filter.
#[test]
fn fields_read_and_write_back() {
    for (fields, expected) in [
        ("filter = 0.5\n", PixelFilter { radius_px: 0.5, shape: FilterShape::Gaussian }),
        ("filter = 1.25\nfilter_shape = \"mitchell\"\n", PixelFilter { radius_px: 1.25, shape: FilterShape::Mitchell }),
    ] {
        let scene = Scene::parse(&format!("{BASE}{fields}"), "s.toml").unwrap();
        assert_eq!(scene.render.filter, Some(expected));
        let again = Scene::parse(&scene.to_toml(), "again.toml").unwrap();
        assert_eq!(again.render.filter, Some(expected));
    }
    assert_eq!(Scene::parse(BASE, "off.toml").unwrap().render.filter, None);
    assert_eq!(Scene::parse(&format!("{BASE}filter = 0\n"), "o.toml").unwrap().render.filter, None);
}

/// `--filter 0` writes the same bytes as no flag; a Gaussian of radius 1 on a sparse density
/// render lights more pixels; bad flags exit 2 writing nothing.
#[test]
fn cli_flag_off_on_and_refusals() {
    let dir = temp_dir("spatial-filter");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let run = |extra: &[&str], out: &str| render_sparse_density("julia", extra, out);
    let (plain, off, on) = (path("plain.png"), path("off.png"), path("on.png"));
    assert!(run(&[], &plain).status.success());
    assert!(run(&["--filter", "0"], &off).status.success());
    let out = run(&["--filter", "1"], &on);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read(&plain).unwrap(), std::fs::read(&off).unwrap());
    let (lit_plain, lit_on) = (lit_pixels(&plain), lit_pixels(&on));
    assert!(lit_on > 2 * lit_plain, "filtered {lit_on} vs plain {lit_plain}");
    for (flag, why) in
        [("-1", "not in 0..=100"), ("x", "is not a number"), ("1,round", "is not a filter shape"), ("9", "at most 15")]
    {
        let refused = path("refused.png");
        let out = run(&["--filter", flag], &refused);
        assert_eq!(out.status.code(), Some(2), "--filter {flag}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(why), "--filter {flag}: {stderr}");
        assert!(!std::path::Path::new(&refused).exists(), "--filter {flag} left a file");
    }
}

/// A flame's `filter` and `filter_shape` become the imported scene's; a flame without a filter
/// gives none, one wider than the resolve's table the widest that fits, with a warning.
#[test]
fn the_import_takes_the_flames_filter() {
    let flame = |attrs: &str| {
        let text = format!(
            "<flame name=\"f\" size=\"64 48\" {attrs}><xform weight=\"1\" color=\"0\" coefs=\"0.5 0 0 0.5 0 0\" linear=\"1\"/></flame>"
        );
        let read = nlifs::flame::xml::read_str(&text, "f.flame").expect("a flame");
        nlifs::scene::flame_import::scene_of_flame(&read.flames[0], "p.png").expect("import")
    };
    let import = flame("filter=\"0.7\" filter_shape=\"bell\"");
    assert_eq!(import.scene.render.filter, Some(PixelFilter { radius_px: 0.7, shape: FilterShape::Bell }));
    assert!(import.warnings.iter().all(|w| !w.contains("filter")), "{:?}", import.warnings);
    assert_eq!(flame("filter=\"0\"").scene.render.filter, None);
    let wide = flame("filter=\"9\"");
    let f = wide.scene.render.filter.expect("narrowed, not dropped");
    assert!(f.radius_px < 9.0 && nlifs::flame::render_filter::filter_width(f.shape, f64::from(f.radius_px)) <= 15);
    assert!(wide.warnings.iter().any(|w| w.contains("filter of radius 9")), "{:?}", wide.warnings);
}
