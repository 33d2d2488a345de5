//! A flame as an ordinary scene (`kind = "flame"`, `src/scene/flame_import.rs`): imported flames
//! saved and reopened as the same scene; the chaos game of an imported scene drawing where
//! flam3's renderer (`nlifs::flame::render`) draws; located errors for bad flame tables; keys
//! that animate a flame's numbers; a flame mixed with an affine function; `nlifs import flame`
//! on the command line.

mod common;

use std::path::Path;

use common::{run_nlifs, temp_dir};
use nlifs::flame::read_str;
use nlifs::scene::Scene;
use nlifs::scene::flame_import::{load_flame, scene_of_flame};
use nlifs::scene::spec::{FlameDef, FunctionDef};
use nlifs::shot::{Framing, Shot};

/// Three flames: one with a post-affine, julian's parameters, waves (which reads its xform's
/// coefs), an opacity, xaos, a final xform, a rotated camera and an off-centre view; one with
/// xaos and a final xform of opacity ½ (the chance that it maps a drawn point); one with
/// flam3's linear palette and an xform of a variation flam3 lacks (JWildfire's `hemisphere`),
/// which maps every point to the origin: its scene says `linear = 0`, so that it reopens.
const FILE: &str = r#"<flames>
<flame name="spiral" size="64 48" center="0.2 -0.1" scale="18" rotate="30" quality="40" brightness="4" gamma="4">
  <xform weight="0.5" color="0" linear="1" coefs="0.5 0.2 -0.2 0.5 -0.5 0.1" color_speed="0.3" chaos="0 1 1"/>
  <xform weight="0.3" color="0.7" julian="0.8" julian_power="3" julian_dist="1" coefs="0.6 0 0 0.6 0.4 0" post="1 0 0.2 1 0 0.1" opacity="0.8"/>
  <xform weight="0.2" color="1" spherical="0.5" swirl="0.3" waves="0.2" coefs="0.4 -0.1 0.1 0.4 0.3 0.5"/>
  <finalxform color="0.4" color_speed="0.3" linear="0.8" spherical="0.25" coefs="0.9 0.15 -0.15 0.9 0.05 0"/>
  <color index="0" rgb="255 40 0"/><color index="128" rgb="40 255 120"/><color index="255" rgb="0 60 255"/>
</flame>
<flame name="finals" size="40 30" scale="12" quality="10">
  <xform weight="1" color="0" swirl="1" coefs="0.6 0.1 -0.1 0.6 0 0" chaos="1 0"/>
  <xform weight="1" color="1" linear="1" coefs="0.5 0 0 0.5 0.3 0.3"/>
  <finalxform color="0.5" spherical="1" coefs="1 0 0 1 0 0" opacity="0.5"/>
  <color index="0" rgb="0 255 0"/><color index="255" rgb="255 255 0"/>
</flame>
<flame name="origin" size="40 30" scale="12" quality="10" palette_mode="linear">
  <xform weight="1" color="0" linear="1" coefs="0.5 0 0 0.5 0.5 0"/>
  <xform weight="0.5" color="1" hemisphere="1" coefs="1 0 0 1 0 0" post="1 0 0 1 0 -0.25"/>
  <color index="0" rgb="0 255 0"/><color index="255" rgb="255 255 0"/>
</flame>
</flames>
"#;

fn write_flames(dir: &Path) -> std::path::PathBuf {
    let file = dir.join("two.flame");
    std::fs::write(&file, FILE).expect("flame file");
    file
}

/// The flame file of flam3 itself, where it is installed (its `vidres.flam3` is a size template
/// without xforms).
fn flam3_samples() -> Vec<std::path::PathBuf> {
    ["test.flam3"].iter().map(|n| Path::new("/usr/share/flam3").join(n)).filter(|p| p.exists()).collect()
}

fn without_path(s: &Scene) -> Scene {
    Scene { path: None, ..s.clone() }
}

#[test]
fn imported_flames_save_and_reopen_as_the_same_scene() {
    let dir = temp_dir("flame-scene-roundtrip");
    let mut files = vec![write_flames(&dir)];
    files.extend(flam3_samples());
    let mut imported = 0;
    for file in &files {
        let count = nlifs::flame::read_file(file).expect("flame file").flames.len();
        for k in 0..count {
            let import = load_flame(file, Some(k), None).expect("import");
            let scene = &import.scene;
            assert!(scene.functions.iter().all(|f| matches!(f.def, FunctionDef::Flame(_))));
            let out = dir.join(format!("flame{imported}.toml"));
            scene.save(&out).expect("save");
            let palette = &scene.render.palette.as_ref().expect("a palette").source;
            assert!(dir.join(palette).exists(), "the palette image {palette} is written beside the scene");
            let back = Scene::load(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
            assert_eq!(without_path(&back), without_path(scene), "{} flame {k}", file.display());
            // And the text of the reopened scene is the text saved (one spelling per value).
            assert_eq!(back.to_toml(), scene.to_toml());
            imported += 1;
        }
    }
    assert!(imported >= 2);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_import_warns_of_what_it_leaves_out() {
    let file = read_str(FILE, "two.flame").expect("flames");
    let spiral = scene_of_flame(&file.flames[0], "p.png").expect("import");
    assert!(spiral.warnings.is_empty(), "{:?}", spiral.warnings);
    let finals = scene_of_flame(&file.flames[1], "p.png").expect("import");
    assert!(finals.warnings.is_empty(), "{:?}", finals.warnings);
    // The final xforms (with their opacity) and the xaos rows are kept.
    assert!(spiral.scene.final_xform.is_some() && finals.scene.final_xform.is_some());
    assert_eq!(finals.scene.final_xform.as_ref().map(|f| f.def.opacity), Some(0.5));
    // A final xform's opacity cannot be told apart from the function index's flag beyond 128
    // xforms: named, and drawn as 1.
    let mut many = file.flames[1].clone();
    many.xforms = (0..130).map(|_| file.flames[1].xforms[1].clone()).collect();
    let text = scene_of_flame(&many, "p.png").expect("import").warnings.join("\n");
    assert!(text.contains("final xform's opacity is left out with more than 128 xforms"), "{text}");
    assert_eq!(spiral.scene.functions[0].xaos, [0.0, 1.0, 1.0]);
    assert!(spiral.scene.functions[1].xaos.is_empty(), "a row of 1s is no row");
    assert_eq!(finals.scene.functions[0].xaos, [1.0, 0.0]);
    // Supersampling is named, not drawn.
    let mut supersampled = file.flames[0].clone();
    supersampled.supersample = 2;
    let text = scene_of_flame(&supersampled, "p.png").expect("import").warnings.join("\n");
    assert!(text.contains("its supersampling (2) is not drawn"), "{text}");
}

/// Sierpiński's triangle as three linear flame functions of opacity 1, ½ and 0: each point of
/// a function is drawn with chance 10^(log₂ opacity) (flam3's plotted weight), so 1, 0.1 and 0,
/// and the orbit goes on through every function whatever its opacity.
#[test]
fn opacity_draws_a_functions_points_with_its_plotted_weight() {
    let mut text = String::from("version = 1\n[grid]\nx = [-1.0, 1.0]\ny = [-1.0, 1.0]\n");
    for ((vx, vy), opacity) in [((-1.0, -1.0), 1.0), ((1.0, -1.0), 0.5), ((0.0, 1.0), 0.0)] {
        let (e, f) = (0.5 * vx, 0.5 * vy);
        text += &format!(
            "[[function]]\nkind = \"flame\"\nprobability = 1\ncoefs = [0.5, 0, 0, 0.5, {e}, {f}]\n\
             variations = {{ linear = 1 }}\nopacity = {opacity}\n"
        );
    }
    let scene = Scene::parse(&text, "opacity.toml").unwrap_or_else(|e| panic!("{text}\n{e}"));
    let compiled = nlifs::chaos_game::CompiledIfs::new(&scene.at(0.0)).expect("compiled");
    let mut sink = nlifs::chaos_game::CollectSink::default();
    for chunk in 0..16 {
        nlifs::chaos_game::run_chunk(&compiled, 7, 0, chunk, 4096, &mut sink);
    }
    let (mut chosen, mut drawn) = ([0u64; 3], [0u64; 3]);
    for (p, &fi) in sink.points.iter().zip(&sink.functions) {
        chosen[fi as usize] += 1;
        if p.is_finite() {
            drawn[fi as usize] += 1;
            // Every drawn point lies in its own function's corner (the orbit is the triangle's).
            let corner = if p.y > 0.0 {
                2
            } else if p.x < 0.0 {
                0
            } else {
                1
            };
            assert!(corner == fi as usize || p.y.abs() < 1e-6, "{p} drawn by function {fi}");
        }
    }
    let fraction = |i: usize| drawn[i] as f64 / chosen[i] as f64;
    assert!(chosen.iter().all(|&n| n > 1_000_000), "each function chosen about a third of the time: {chosen:?}");
    assert_eq!(fraction(0), 1.0);
    // 1.4 M draws: the fraction's standard deviation is 0.00025.
    assert!((fraction(1) - 0.1).abs() < 0.002, "function 1 drew {:.4} of its points, not 0.1", fraction(1));
    assert_eq!(drawn[2], 0);
}

/// Luminance summed over `cells` blocks of an RGB(A) image, normalized to sum 1.
fn coarse_luminance(pixels: &[u8], channels: usize, width: usize, height: usize, cells: (usize, usize)) -> Vec<f64> {
    let mut out = vec![0.0; cells.0 * cells.1];
    for y in 0..height {
        for x in 0..width {
            let p = &pixels[(y * width + x) * channels..][..3];
            let l = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            out[(y * cells.1 / height) * cells.0 + x * cells.0 / width] += l;
        }
    }
    let total: f64 = out.iter().sum();
    out.iter_mut().for_each(|v| *v /= total.max(1e-12));
    out
}

fn l1(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum()
}

#[test]
fn imported_scene_draws_where_the_flame_renderer_draws() {
    let file = read_str(FILE, "two.flame").expect("flames");
    let flame = &file.flames[0];
    let reference = nlifs::flame::render::render(flame, 3, &|_| {}).expect("flame render");
    let (w, h) = (reference.width as usize, reference.height as usize);
    let scene = scene_of_flame(flame, "p.png").expect("import").scene;
    let shot = Shot::prepare(&scene, 0.0, &scene.render, Framing::Scene, None).expect("shot");
    assert!(shot.compiled.has_flames());
    // waves reads the file's coefs, not the conjugated ones.
    let FunctionDef::Flame(waves) = &scene.functions[2].def else { panic!("a flame function") };
    assert_eq!(waves.variation_coefs, Some([0.4, -0.1, 0.1, 0.4, 0.3, 0.5]));
    let rendered = nlifs::render::render_cpu(&shot, &|_, _| {});
    assert_eq!((rendered.image.width() as usize, rendered.image.height() as usize), (w, h));
    let cells = (8, 6);
    let ours = coarse_luminance(rendered.image.as_raw(), 3, w, h, cells);
    let theirs = coarse_luminance(&reference.rgba, 4, w, h, cells);
    let d = l1(&ours, &theirs);
    // Without its xaos row the scene draws another picture.
    let mut without = scene.clone();
    without.functions[0].xaos.clear();
    let shot = Shot::prepare(&without, 0.0, &without.render, Framing::Scene, None).expect("shot");
    let rendered = nlifs::render::render_cpu(&shot, &|_, _| {});
    let d_without = l1(&coarse_luminance(rendered.image.as_raw(), 3, w, h, cells), &theirs);
    eprintln!("L1 of the coarse luminance without the xaos row: {d_without:.3}");
    assert!(d_without > 2.0 * d, "the xaos row matters: {d_without:.3} without it against {d:.3}");
    // The same picture upside down (what the import's mirror corrects) or turned (its rotation)
    // is far from it: the comparison sees orientation.
    let flipped: Vec<u8> = (0..h).rev().flat_map(|y| reference.rgba[y * w * 4..(y + 1) * w * 4].to_vec()).collect();
    let d_flipped = l1(&ours, &coarse_luminance(&flipped, 4, w, h, cells));
    eprintln!("L1 of the coarse luminance: {d:.3}, against flam3's picture flipped: {d_flipped:.3}");
    assert!(
        d < 0.25 && d < 0.5 * d_flipped,
        "L1 of the coarse luminance: {d:.3} (against flam3's flipped: {d_flipped:.3})"
    );
}

/// A final xform of opacity ½ (swirl after Sierpiński's triangle: half the drawn points
/// swirled, half as they are) draws as the flame renderer draws it; the same scene with the
/// final's opacity 1 draws another picture.
#[test]
fn an_imported_final_xforms_opacity_draws_as_the_flame_renderer() {
    const HALF_FINAL: &str = r#"<flame name="half-final" size="64 48" scale="14" quality="200" brightness="4" gamma="2">
  <xform weight="1" color="0" linear="1" coefs="0.5 0 0 0.5 -0.5 -0.5"/>
  <xform weight="1" color="0.5" linear="1" coefs="0.5 0 0 0.5 0.5 -0.5"/>
  <xform weight="1" color="1" linear="1" coefs="0.5 0 0 0.5 0 0.5"/>
  <finalxform color="0.5" color_speed="0" swirl="1" coefs="1 0 0 1 0 0" opacity="0.5"/>
  <color index="0" rgb="255 40 0"/><color index="255" rgb="0 60 255"/>
</flame>"#;
    let flame = read_str(HALF_FINAL, "half.flame").expect("a flame").flames.remove(0);
    let reference = nlifs::flame::render::render(&flame, 3, &|_| {}).expect("flame render");
    let (w, h) = (reference.width as usize, reference.height as usize);
    let cells = (8, 6);
    let theirs = coarse_luminance(&reference.rgba, 4, w, h, cells);
    let scene = scene_of_flame(&flame, "p.png").expect("import").scene;
    let distance = |scene: &Scene| {
        let shot = Shot::prepare(scene, 0.0, &scene.render, Framing::Scene, None).expect("shot");
        let rendered = nlifs::render::render_cpu(&shot, &|_, _| {});
        l1(&coarse_luminance(rendered.image.as_raw(), 3, w, h, cells), &theirs)
    };
    let d = distance(&scene);
    let mut opaque = scene.clone();
    opaque.final_xform.as_mut().expect("a final xform").def.opacity = 1.0;
    let d_opaque = distance(&opaque);
    eprintln!("L1 of the coarse luminance: {d:.3}; with the final's opacity 1: {d_opaque:.3}");
    assert!(d < 0.25 && d < 0.5 * d_opaque, "L1 of the coarse luminance: {d:.3} (opacity 1: {d_opaque:.3})");
}

#[test]
fn imported_points_fill_flam3s_view() {
    // The attractor's bounds of the imported scene are the flame's, mapped into nlifs's plane:
    // the camera of the import frames them as flam3's view does.
    let file = read_str(FILE, "two.flame").expect("flames");
    let flame = &file.flames[1];
    let scene = scene_of_flame(flame, "p.png").expect("import").scene;
    let shot = Shot::prepare(&scene, 0.0, &scene.render, Framing::Scene, None).expect("shot");
    let (lo, hi) = shot.bounds;
    let centre = nlifs::scene::flame_import::view_point(flame, flame.center);
    let target = shot.camera.target;
    assert!((target - centre).length() < 1e-6, "camera target {target:?}, flame centre {centre:?}");
    let half_height = shot.camera.half_height_at_target() as f64;
    assert!((half_height - 15.0 / 12.0).abs() < 1e-5, "{half_height}");
    assert!(lo.is_finite() && hi.is_finite() && hi.x > lo.x && hi.y > lo.y);
}

/// A scene with one flame function whose table is `table` (the lines after `kind`).
fn scene_with(table: &str) -> String {
    format!("version = 1\n[grid]\nx = [-1.0, 1.0]\ny = [-1.0, 1.0]\n\n[[function]]\nkind = \"flame\"\n{table}")
}

fn error_of(text: &str) -> String {
    Scene::parse(text, "bad.toml").expect_err("a bad scene").to_string()
}

#[test]
fn bad_flame_tables_give_located_errors() {
    let cases: [(&str, &str, &[&str]); 9] = [
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 0.5, spherica = 0.5 }\n",
            "bad.toml:9:",
            &["function[0].variations.spherica", "`spherica` is not one of flam3's variations"],
        ),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { julian = 1 }\nparams = { julian_powr = 2 }\n",
            "bad.toml:10:",
            &["function[0].params.julian_powr", "not a parameter"],
        ),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\nparams = { julian_power = 2 }\n",
            "bad.toml:10:",
            &["function[0].params.julian_power", "parameter of `julian`, which the function does not use"],
        ),
        ("coefs = [1, 0, 0, 1]\nvariations = { linear = 1 }\n", "bad.toml:8:", &["function[0].coefs", "6 numbers"]),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariation_coefs = [1, 0]\nvariations = { waves = 1 }\n",
            "bad.toml:9:",
            &["function[0].variation_coefs", "6 numbers"],
        ),
        ("variations = { linear = 1 }\n", "bad.toml:", &["function[0].coefs", "needs `coefs`"]),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\ncolor_speed = 1.5\n",
            "bad.toml:10:",
            &["function[0].color_speed", "0..1"],
        ),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\nopacity = -0.2\n",
            "bad.toml:10:",
            &["function[0].opacity", "0..1"],
        ),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\nmatrix = [[1, 0], [0, 1]]\n",
            "bad.toml:10:",
            &["function[0].matrix", "not a field of a `flame` function"],
        ),
    ];
    for (table, place, words) in cases {
        let e = error_of(&scene_with(table));
        assert!(e.starts_with(place), "{e}\n(expected at {place})");
        for w in words {
            assert!(e.contains(w), "{e}\n(expected {w:?})");
        }
    }
    // A flame field on another kind is refused, and a key may not add a variation.
    let e = error_of(
        "version = 1\n[grid]\nx = [0.0, 1.0]\ny = [0.0, 1.0]\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\ncoefs = [1, 0, 0, 1, 0, 0]\n",
    );
    assert!(e.contains("function[0].coefs") && e.contains("not a field of a `affine` function"), "{e}");
    let keyed = format!(
        "{}\n[[key]]\nt_secs = 1.0\n[[key.function]]\nname = \"f1\"\nvariations = {{ swirl = 1 }}\n",
        scene_with("coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\n")
    );
    let e = error_of(&keyed);
    assert!(e.contains("key[0].function[0].variations.swirl") && e.contains("does not use `swirl`"), "{e}");
    // The final xform: a flame's fields, its colour coordinate and its opacity, no selection
    // weight.
    let with_final = |table: &str| {
        format!("{}\n[final]\n{table}", scene_with("coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\n"))
    };
    let cases: [(&str, &[&str]); 4] = [
        ("coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\nprobability = 1\n", &["bad.toml:", "probability"]),
        ("variations = { linear = 1 }\n", &["bad.toml:", "final.coefs", "needs `coefs`"]),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\npalette_index = 2\n",
            &["bad.toml:14:", "final.palette_index", "0..1"],
        ),
        (
            "coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\nopacity = 1.5\n",
            &["bad.toml:14:", "final.opacity", "0..1"],
        ),
    ];
    for (table, words) in cases {
        let e = error_of(&with_final(table));
        for w in words {
            assert!(e.contains(w), "{e}\n(expected {w:?})");
        }
    }
    let scene = Scene::parse(&with_final("coefs = [1, 0, 0, 1, 0.5, 0]\nvariations = { spherical = 1 }\n"), "f.toml")
        .expect("a scene with a final xform");
    let f = scene.final_xform.as_ref().expect("the final xform");
    assert_eq!((f.palette_index, f.def.color_speed, f.def.coefs[4], f.def.opacity), (0.0, 0.5, 0.5, 1.0));
    assert_eq!(without_path(&Scene::parse(&scene.to_toml(), "again.toml").expect("again")), without_path(&scene));
    let scene =
        Scene::parse(&with_final("coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 1 }\nopacity = 0.4\n"), "o.toml")
            .expect("a final xform with an opacity");
    assert_eq!(scene.final_xform.as_ref().map(|f| f.def.opacity), Some(0.4));
    assert_eq!(without_path(&Scene::parse(&scene.to_toml(), "again.toml").expect("again")), without_path(&scene));
}

#[test]
fn keys_animate_a_flames_numbers() {
    let text = format!(
        "{}\n[[key]]\nt_secs = 0.0\ninterpolation = \"linear\"\n[[key.function]]\nname = \"f1\"\n\
         coefs = [0.5, 0, 0, 0.5, 0, 0]\nvariations = {{ julian = 0.2 }}\nparams = {{ julian_power = 2 }}\n\
         [[key]]\nt_secs = 2.0\ninterpolation = \"linear\"\n[[key.function]]\nname = \"f1\"\n\
         coefs = [0.7, 0, 0, 0.5, 0.2, 0]\nvariations = {{ julian = 0.6 }}\nparams = {{ julian_power = 4 }}\n",
        scene_with("coefs = [1, 0, 0, 1, 0, 0]\nvariations = { linear = 0.5, julian = 0.5 }\n")
    );
    let scene = Scene::parse(&text, "keys.toml").expect("scene");
    let FunctionDef::Flame(mid) = scene.function_def_at(0, 1.0) else { panic!("a flame") };
    assert!((mid.coefs[0] - 0.6).abs() < 1e-12 && (mid.coefs[4] - 0.1).abs() < 1e-12, "{:?}", mid.coefs);
    let julian = mid.variations.iter().find(|t| t.variation.name() == "julian").expect("julian");
    assert!((julian.weight - 0.4).abs() < 1e-12 && (julian.params[0] - 3.0).abs() < 1e-12, "{julian:?}");
    let linear = mid.variations.iter().find(|t| t.variation.name() == "linear").expect("linear");
    assert_eq!(linear.weight, 0.5, "a number no key sets stays the function's");
    // The scene writes and reads back with its keys.
    assert_eq!(without_path(&Scene::parse(&scene.to_toml(), "again.toml").expect("again")), without_path(&scene));
}

#[test]
fn a_flame_mixes_with_an_affine_function() {
    let text = "version = 1\n[grid]\nx = [-1.0, 1.0]\ny = [-1.0, 1.0]\n\
        [[function]]\nkind = \"flame\"\ncoefs = [0.5, 0, 0, 0.5, 0.5, 0]\nvariations = { linear = 0.8, swirl = 0.2 }\n\
        [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [-0.5, 0]\n";
    let scene = Scene::parse(text, "mix.toml").expect("scene");
    let shot = Shot::prepare(&scene, 0.0, &scene.render, Framing::Fit, None).expect("shot");
    let mut sink = nlifs::chaos_game::CollectSink::default();
    nlifs::chaos_game::run_chunk(&shot.compiled, 1, 0, 0, 200, &mut sink);
    assert_eq!(sink.points.len(), 64 * 200);
    // Points of both functions: some on the affine map's side (x < 0), some on the flame's.
    let left = sink.points.iter().filter(|p| p.x < -0.25).count();
    let right = sink.points.iter().filter(|p| p.x > 0.25).count();
    assert!(left > 1000 && right > 1000, "{left} left, {right} right");
    assert!(sink.points.iter().all(|p| p.z == 0.0), "a flame keeps the plane");
}

#[test]
fn import_command_writes_the_scene_and_its_palette() {
    let dir = temp_dir("flame-scene-cli");
    let file = write_flames(&dir);
    let out = dir.join("spiral.toml");
    let o = run_nlifs(&["import", "flame", file.to_str().unwrap(), "--name", "finals", "-o", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("opacity"), "the final xform's opacity is kept: {err}");
    assert!(!err.contains("xaos"), "xaos is kept: {err}");
    assert!(dir.join("spiral.palette.png").exists());
    let scene = Scene::load(&out).expect("scene");
    assert_eq!(scene.name, "finals");
    assert_eq!(scene.functions.len(), 2);
    assert_eq!(scene.final_xform.as_ref().map(|f| f.def.opacity), Some(0.5), "the final xform is the scene's");
    assert_eq!(scene.functions[0].xaos, [1.0, 0.0], "the xaos row is the function's");
    let bad = run_nlifs(&["import", "flame", file.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(2));
    let missing = run_nlifs(&["import", "flame", "no-such.flame", "-o", out.to_str().unwrap()]);
    assert_eq!(missing.status.code(), Some(2), "{}", String::from_utf8_lossy(&missing.stderr));
    let unnamed =
        run_nlifs(&["import", "flame", file.to_str().unwrap(), "--name", "nope", "-o", out.to_str().unwrap()]);
    assert_eq!(unnamed.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&unnamed.stderr).contains("no flame named `nope`"));
    // `record` opens a flame file through the same import.
    let frames = dir.join("frames");
    let rec = run_nlifs(&[
        "record",
        file.to_str().unwrap(),
        "-o",
        frames.to_str().unwrap(),
        "--backend",
        "cpu",
        "--points-per-frame",
        "20000",
    ]);
    let err = String::from_utf8_lossy(&rec.stderr);
    assert_eq!(rec.status.code(), Some(0), "{err}");
    assert_eq!(image::image_dimensions(frames.join("frame_00000.png")).expect("frame"), (64, 48));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_viewer_edits_a_flame_undoably_and_saves_it() {
    use nlifs::viewer::command::Command;
    use nlifs::viewer::state::ViewerState;
    let dir = temp_dir("flame-scene-viewer");
    let file = write_flames(&dir);
    // Opened as a flame file is: through the import, never saved over the flame.
    let mut s = ViewerState::new(ViewerState::default_scene(), None, nlifs::live::LiveSettings::default());
    s.apply([Command::OpenScene(file.clone())]);
    assert!(s.error.is_none(), "{:?}", s.error);
    assert!(s.scene.has_flames());
    let original = s.scene.clone();
    let FunctionDef::Flame(mut def) = s.scene.functions[1].def.clone() else { panic!("a flame") };
    def.coefs[4] += 0.25;
    def.variations[0].weight = 0.3;
    def.variations[0].params[0] = 5.0;
    def.color_speed = 0.8;
    // One drag: two steps of it, then the release.
    let mut half = def.clone();
    half.coefs[4] -= 0.1;
    s.apply([Command::SetFlame { function: 1, value: half }]);
    s.apply([Command::SetFlame { function: 1, value: def.clone() }, Command::EndGesture]);
    assert_eq!(s.scene.functions[1].def, FunctionDef::Flame(def.clone()));
    s.apply([Command::Undo]);
    assert_eq!(s.scene, original, "one undo step undoes the drag");
    s.apply([Command::Redo]);
    assert_eq!(s.scene.functions[1].def, FunctionDef::Flame(def.clone()));
    // A change of structure is not an edit of numbers.
    let mut other = def.clone();
    other.post = None;
    s.apply([Command::SetFlame { function: 1, value: other }]);
    assert_eq!(s.scene.functions[1].def, FunctionDef::Flame(def.clone()));
    // The final xform's numbers, colour coordinate and opacity: one undo step a drag too.
    let before_final = s.scene.clone();
    let mut fin = s.scene.final_xform.clone().expect("the spiral's final xform");
    fin.def.coefs[0] = 0.7;
    fin.def.variations[0].weight = 0.5;
    fin.palette_index = 0.9;
    fin.def.opacity = 0.4;
    let mut half = fin.clone();
    half.palette_index = 0.6;
    s.apply([Command::SetFinalXform(half)]);
    s.apply([Command::SetFinalXform(fin.clone()), Command::EndGesture]);
    assert_eq!(s.scene.final_xform.as_ref(), Some(&fin));
    s.apply([Command::Undo]);
    assert_eq!(s.scene, before_final, "one undo step undoes the final xform's drag");
    s.apply([Command::Redo]);
    assert_eq!(s.scene.final_xform.as_ref(), Some(&fin));
    let mut other = fin.clone();
    other.def.variations.pop();
    s.apply([Command::SetFinalXform(other)]);
    assert_eq!(s.scene.final_xform.as_ref(), Some(&fin), "a change of structure is refused");
    s.apply([Command::SaveScene(file.clone())]);
    assert!(s.error.as_deref().is_some_and(|e| e.contains("cannot save over the flame file")), "{:?}", s.error);
    assert_eq!(std::fs::read_to_string(&file).expect("flame"), FILE, "the flame file is untouched");
    let out = dir.join("edited.toml");
    s.apply([Command::SaveScene(out.clone())]);
    let back = Scene::load(&out).expect("reopen");
    assert_eq!(back.functions[1].def, FunctionDef::Flame(def));
    assert_eq!(back.final_xform, Some(fin));
    assert_eq!(without_path(&back), without_path(&s.scene));
    std::fs::remove_dir_all(&dir).ok();
}

/// The viewer's flame panel adds a variation (at weight 0) and removes one, for a function and
/// for the final xform: each one undo step, saved and reopened; refused, with a message, on a
/// function that a key of the timeline holds.
#[test]
fn the_viewer_adds_and_removes_a_flames_variations() {
    use nlifs::flame::{Variation, VariationTerm};
    use nlifs::viewer::command::Command;
    use nlifs::viewer::state::ViewerState;
    let dir = temp_dir("flame-scene-variations");
    let file = write_flames(&dir);
    let mut s = ViewerState::new(ViewerState::default_scene(), None, nlifs::live::LiveSettings::default());
    s.apply([Command::OpenScene(file)]);
    assert!(s.error.is_none(), "{:?}", s.error);
    let original = s.scene.clone();
    let FunctionDef::Flame(def) = s.scene.functions[1].def.clone() else { panic!("a flame") };
    let swirl = Variation::by_name("swirl").expect("swirl");
    let mut added = def.variations.clone();
    added.push(VariationTerm { variation: swirl, weight: 0.0, params: swirl.default_params() });
    s.apply([Command::SetFlameVariations { function: Some(1), variations: added.clone() }]);
    let FunctionDef::Flame(now) = &s.scene.functions[1].def else { panic!("a flame") };
    assert_eq!(now.variations, added);
    assert_eq!(FlameDef { variations: def.variations.clone(), ..now.clone() }, def, "only the variations change");
    s.apply([Command::Undo]);
    assert_eq!(s.scene, original, "one undo step");
    s.apply([Command::Redo]);
    let removed = added[1..].to_vec();
    s.apply([Command::SetFlameVariations { function: Some(1), variations: removed.clone() }]);
    s.apply([Command::SetFlameVariations { function: Some(1), variations: Vec::new() }]);
    let FunctionDef::Flame(now) = &s.scene.functions[1].def else { panic!("a flame") };
    assert_eq!(now.variations, removed, "an xform keeps at least one variation");
    let mut fin = s.scene.final_xform.clone().expect("the spiral's final xform").def.variations;
    fin.push(VariationTerm { variation: swirl, weight: 0.25, params: swirl.default_params() });
    s.apply([Command::SetFlameVariations { function: None, variations: fin.clone() }]);
    assert_eq!(s.scene.final_xform.as_ref().map(|f| &f.def.variations), Some(&fin));
    let out = dir.join("edited.toml");
    s.apply([Command::SaveScene(out.clone())]);
    let back = Scene::load(&out).expect("reopen");
    assert_eq!(without_path(&back), without_path(&s.scene));
    // Keyed at the playhead (a drag of its numbers on an animated scene), it keeps its list.
    s.apply([Command::AddOrUpdateKey]);
    let FunctionDef::Flame(mut dragged) = s.scene.functions[1].def.clone() else { panic!("a flame") };
    dragged.coefs[4] += 0.1;
    s.apply([Command::SetFlame { function: 1, value: dragged }, Command::EndGesture]);
    assert!(s.scene.is_keyed(1), "the drag keyed the function");
    let before = s.scene.clone();
    s.apply([Command::SetFlameVariations { function: Some(1), variations: added }]);
    assert_eq!(s.scene, before);
    assert!(s.error.as_deref().is_some_and(|e| e.contains("keyed on the timeline")), "{:?}", s.error);
    std::fs::remove_dir_all(&dir).ok();
}
