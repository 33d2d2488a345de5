//! The flame renderer (`src/flame/render.rs`) against flam3 itself: a set of small flames
//! (every variation alone and in mixtures, random mixtures in the manner of `flam3-genome`,
//! xaos, a final xform, step and linear palettes, density estimation on and off, opacity, post
//! transforms, camera rotation, supersampling, highlight power, a background) is rendered by
//! `flam3-render` and by nlifs at the same size and quality. The metric is the mean |Δ| of the
//! 8-bit RGB bytes over the pixels either image draws (differs from the background); a flame
//! matches when nlifs's difference to flam3 is within twice flam3's own difference between two
//! of its seeds (`isaac_seed`), plus 3: the two renderers draw different random numbers, so
//! flam3's seed-to-seed noise is the scale.
//!
//! Twenty of them are also imported as scenes and drawn by the scene renderer ([`IMPORTED`]),
//! with the same metric.
//!
//! Without `flam3-render` the test says so loudly and passes, unless `CI` or
//! `NLIFS_REQUIRE_TOOLS=1` is set, where it fails. The images go to
//! `target/flame-fidelity/NAME-{nlifs,flam3}.png` to be looked at side by side.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use nlifs::flame::variations::VARIATIONS;
use nlifs::flame::{Coefs, FilterShape, Flame, PaletteMode, Variation, VariationTerm, Xform};

fn tools_required() -> bool {
    std::env::var_os("CI").is_some() || std::env::var("NLIFS_REQUIRE_TOOLS").as_deref() == Ok("1")
}

fn flam3_render_path() -> Option<PathBuf> {
    let path = PathBuf::from("/usr/bin/flam3-render");
    if path.exists() {
        return Some(path);
    }
    std::env::var_os("PATH")?.to_str()?.split(':').map(|d| Path::new(d).join("flam3-render")).find(|p| p.exists())
}

/// A smooth palette with hue, brightness and saturation varying along it.
fn palette() -> Vec<[f64; 4]> {
    (0..256)
        .map(|i| {
            let t = i as f64 / 255.0;
            let r = (0.5 + 0.5 * (std::f64::consts::TAU * t).cos()) * 255.0;
            let g = (0.5 + 0.5 * (std::f64::consts::TAU * t + 2.1).cos()) * 255.0;
            let b = (0.5 + 0.5 * (std::f64::consts::TAU * t + 4.2).cos()) * 255.0;
            // Whole byte values, as palettes in files hold them.
            [r.round() / 255.0, g.round() / 255.0, b.round() / 255.0, 1.0]
        })
        .collect()
}

/// Variations of the table that flam3 3.1.1 does not have (Apophysis' and JWildfire's): flam3
/// leaves them out of an xform, so its pictures cannot be the reference for them.
const NOT_IN_FLAM3: &[&str] = &["linear3D", "flatten"];

/// A variation term; parameters whose default is 0 get 0.4, so that variations like fan2 or
/// split do not reduce to a linear map.
fn var(name: &str, weight: f64) -> VariationTerm {
    let variation = Variation::by_name(name).unwrap_or_else(|| panic!("no variation {name}"));
    let params = variation.info().params.iter().map(|(_, d)| if *d == 0.0 { 0.4 } else { *d }).collect();
    VariationTerm { variation, weight, params }
}

fn xform(weight: f64, color: f64, coefs: Coefs, variations: Vec<VariationTerm>) -> Xform {
    Xform {
        weight,
        color,
        color_speed: 0.5,
        opacity: 1.0,
        coefs,
        post: None,
        variation_coefs: None,
        variations,
        chaos: Vec::new(),
    }
}

/// A three-xform Sierpinski-like base with the given variations on every xform.
fn base(name: &str, variations: &[(&str, f64)]) -> Flame {
    let terms = || variations.iter().map(|(n, w)| var(n, *w)).collect::<Vec<_>>();
    Flame {
        name: name.to_string(),
        size: [96, 72],
        scale: 24.0,
        quality: 60.0,
        estimator_radius: 0.0,
        palette: palette(),
        xforms: vec![
            xform(0.5, 0.0, [0.55, 0.1, -0.1, 0.55, -0.6, -0.4], terms()),
            xform(0.3, 0.5, [0.5, -0.2, 0.2, 0.5, 0.6, -0.4], terms()),
            xform(0.2, 1.0, [0.45, 0.0, 0.0, 0.45, 0.0, 0.6], terms()),
        ],
        ..Flame::default()
    }
}

/// How a flame file gives its palette.
#[derive(Clone, Copy)]
enum PaletteForm {
    /// `<color index="i" rgb="r g b"/>` elements.
    Colors,
    /// `<palette count="256" format="RGB">` with hexadecimal RRGGBB.
    Hex,
    /// `palette="N"`: entry N of flam3's palette library.
    Library(u32),
}

/// The flames of the test, each with what it exercises in its name.
fn cases() -> Vec<(Flame, PaletteForm)> {
    let mut cases = Vec::new();
    // Every variation alone (mixed with a little linear so that the attractor stays in view).
    for info in VARIATIONS.iter().filter(|v| !NOT_IN_FLAM3.contains(&v.name)) {
        if info.name == "linear" {
            cases.push(base("linear", &[("linear", 1.0)]));
        } else {
            cases.push(base(&format!("var-{}", info.name), &[(info.name, 0.8), ("linear", 0.2)]));
        }
    }
    let mixture: Vec<(&str, f64)> = VARIATIONS.iter().take(6).map(|v| (v.name, 1.0 / 6.0)).collect();
    cases.push(base("mixture", &mixture));
    let mut f = base("mix-sinusoidal-swirl", &[("sinusoidal", 0.6), ("swirl", 0.4)]);
    f.xforms[1].variations = vec![var("spherical", 0.7), var("linear", 0.3)];
    cases.push(f);
    let mut f = base("xaos", &[("linear", 1.0)]);
    f.xforms[0].chaos = vec![0.0, 1.0, 1.0];
    f.xforms[1].chaos = vec![1.0, 0.0, 3.0];
    f.xforms[2].chaos = vec![2.0, 1.0, 0.0];
    // The same with a spatial filter too narrow to spread a point: its thin pieces are then
    // drawn as the import draws them (it has no spatial filter), which checks the import's xaos.
    let sharp = Flame { name: "xaos-sharp".into(), filter: 0.01, ..f.clone() };
    cases.push(f);
    cases.push(sharp);
    let mut f = base("final-xform", &[("linear", 1.0)]);
    f.final_xform = Some(Xform {
        weight: 0.0,
        color: 0.8,
        color_speed: 0.3,
        ..xform(0.0, 0.8, [0.9, 0.2, -0.2, 0.9, 0.1, 0.0], vec![var("swirl", 0.5), var("linear", 0.5)])
    });
    // The same final xform mapping half the drawn points (flam3's final opacity), in its colour
    // at a faster colour speed.
    let mut half = Flame { name: "final-opacity".into(), ..f.clone() };
    if let Some(x) = &mut half.final_xform {
        (x.opacity, x.color_speed) = (0.5, 0.8);
    }
    cases.push(f);
    cases.push(half);
    let mut f = base("linear-palette", &[("linear", 0.7), ("sinusoidal", 0.3)]);
    f.palette_mode = PaletteMode::Linear;
    cases.push(f);
    let mut f = base("density-estimation", &[("linear", 0.7), ("spherical", 0.3)]);
    f.estimator_radius = 9.0;
    f.estimator_minimum = 0.0;
    f.estimator_curve = 0.4;
    f.quality = 30.0;
    cases.push(f);
    let mut f = base("density-estimation-ss2", &[("linear", 1.0)]);
    f.estimator_radius = 5.0;
    f.estimator_minimum = 1.0;
    f.estimator_curve = 0.6;
    f.supersample = 2;
    f.quality = 30.0;
    cases.push(f);
    let mut f = base("opacity", &[("linear", 1.0)]);
    f.xforms[0].opacity = 0.4;
    f.xforms[2].opacity = 0.0;
    cases.push(f);
    let mut f = base("post", &[("linear", 0.6), ("swirl", 0.4)]);
    f.xforms[0].post = Some([0.8, 0.3, -0.3, 0.8, 0.1, 0.05]);
    f.xforms[2].post = Some([1.0, 0.0, 0.0, -1.0, 0.0, 0.2]);
    cases.push(f);
    let mut f = base("camera", &[("linear", 1.0)]);
    f.center = [0.2, -0.1];
    f.rotate = 30.0;
    f.zoom = 0.5;
    f.scale = 20.0;
    f.quality = 30.0;
    cases.push(f);
    let mut f = base("supersample-filter", &[("linear", 0.8), ("sinusoidal", 0.2)]);
    f.supersample = 3;
    f.filter = 1.0;
    f.filter_shape = FilterShape::Mitchell;
    cases.push(f);
    // flam3 evaluates other kernels than these names say (see render_filter.rs).
    for (name, shape, radius, supersample) in [
        ("filter-catrom", FilterShape::Catrom, 0.7, 1),
        ("filter-lanczos3-ss2", FilterShape::Lanczos3, 0.8, 2),
        ("filter-hanning", FilterShape::Hanning, 0.6, 1),
        ("filter-box", FilterShape::Box, 1.0, 2),
    ] {
        let mut f = base(name, &[("linear", 0.8), ("swirl", 0.2)]);
        f.filter_shape = shape;
        f.filter = radius;
        f.supersample = supersample;
        cases.push(f);
    }
    let mut f = base("highlight-background", &[("linear", 1.0)]);
    f.highlight_power = 1.0;
    f.brightness = 12.0;
    f.background = [0.1, 0.05, 0.2];
    f.vibrancy = 0.6;
    f.gamma = 2.2;
    f.gamma_threshold = 0.05;
    cases.push(f);
    let mut f = base("color-speed", &[("linear", 1.0)]);
    f.xforms[0].color_speed = 0.9;
    f.xforms[1].color_speed = 0.1;
    f.xforms[2].color_speed = 0.0;
    cases.push(f);
    cases.extend(RANDOM_MIXTURES.iter().map(|&seed| random_mixture(seed)));
    let mut cases: Vec<(Flame, PaletteForm)> = cases.into_iter().map(|f| (f, PaletteForm::Colors)).collect();
    cases.push((base("palette-hex", &[("linear", 0.8), ("swirl", 0.2)]), PaletteForm::Hex));
    let mut f = base("palette-library-linear", &[("linear", 0.8), ("sinusoidal", 0.2)]);
    f.palette_mode = PaletteMode::Linear;
    cases.push((f, PaletteForm::Library(12)));
    cases
}

/// The seeds of [`random_mixture`]'s flames in the set: those of 1–20 whose flame draws on at
/// least a tenth of the picture (checked by the test; the others drew 0.7–7 %, and matched).
const RANDOM_MIXTURES: &[u32] = &[3, 4, 5, 6, 7, 11, 12, 15, 16, 17, 18, 19, 20];

/// A random flame in the manner of `flam3-genome`'s (whose flames are not repeatable: it seeds
/// itself from the clock): two to four xforms of one to three variations each, drawn from all of
/// flam3's (their parameters' defaults), with random weights, colours, contractive coefficients
/// and post maps; every third one with density estimation. Each xform has its own terms, so
/// the lane game queues its points (the variations alone share theirs: `base`).
fn random_mixture(seed: u32) -> Flame {
    let mut rng = nlifs::rng::Pcg32::for_stream(seed, 7, 11);
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    let in_flam3: Vec<&str> = VARIATIONS.iter().map(|v| v.name).filter(|n| !NOT_IN_FLAM3.contains(n)).collect();
    let xforms = (0..2 + (uniform(0.0, 3.0) as usize))
        .map(|k| {
            let mut names: Vec<&str> = (0..1 + (uniform(0.0, 3.0) as usize))
                .map(|_| in_flam3[uniform(0.0, in_flam3.len() as f64) as usize])
                .collect();
            names.sort_unstable();
            names.dedup();
            let terms = names.iter().map(|n| var(n, uniform(0.2, 1.0))).collect();
            let (size, turn) = (uniform(0.3, 0.9), uniform(0.0, std::f64::consts::TAU));
            let (s, c) = (size * turn.sin(), size * turn.cos());
            let coefs = [c, s, -s, c, uniform(-0.8, 0.8), uniform(-0.8, 0.8)];
            let mut x = xform(uniform(0.2, 1.0), k as f64 / 3.0, coefs, terms);
            if uniform(0.0, 1.0) < 0.3 {
                x.post = Some([uniform(0.6, 1.0), uniform(-0.4, 0.4), uniform(-0.4, 0.4), uniform(0.6, 1.0), 0.0, 0.0]);
            }
            x
        })
        .collect();
    let mut flame = base(&format!("random-{seed}"), &[("linear", 1.0)]);
    flame.xforms = xforms;
    flame.quality = 100.0;
    if seed.is_multiple_of(3) {
        (flame.estimator_radius, flame.estimator_minimum, flame.estimator_curve) = (9.0, 0.0, 0.4);
    }
    flame
}

/// The share of pixels `image` draws (differs from `background`).
fn drawn_share(image: &image::RgbaImage, background: [u8; 3]) -> f64 {
    let drawn = image.pixels().filter(|p| p.0[..3] != background).count();
    drawn as f64 / (image.width() * image.height()).max(1) as f64
}

fn attr_list(values: &[f64]) -> String {
    values.iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(" ")
}

fn shape_name(s: FilterShape) -> &'static str {
    match s {
        FilterShape::Gaussian => "gaussian",
        FilterShape::Hermite => "hermite",
        FilterShape::Box => "box",
        FilterShape::Triangle => "triangle",
        FilterShape::Bell => "bell",
        FilterShape::BSpline => "bspline",
        FilterShape::Mitchell => "mitchell",
        FilterShape::Blackman => "blackman",
        FilterShape::Catrom => "catrom",
        FilterShape::Hanning => "hanning",
        FilterShape::Hamming => "hamming",
        FilterShape::Lanczos3 => "lanczos3",
        FilterShape::Lanczos2 => "lanczos2",
        FilterShape::Quadratic => "quadratic",
    }
}

fn xform_xml(tag: &str, x: &Xform, is_final: bool) -> String {
    let mut s = format!("  <{tag}");
    if !is_final {
        let _ = write!(s, " weight=\"{}\"", x.weight);
    }
    let _ = write!(s, " color=\"{}\" color_speed=\"{}\" opacity=\"{}\"", x.color, x.color_speed, x.opacity);
    let _ = write!(s, " coefs=\"{}\"", attr_list(&x.coefs));
    if let Some(post) = &x.post {
        let _ = write!(s, " post=\"{}\"", attr_list(post));
    }
    for t in &x.variations {
        let _ = write!(s, " {}=\"{}\"", t.variation.name(), t.weight);
        for ((name, _), value) in t.variation.info().params.iter().zip(&t.params) {
            let _ = write!(s, " {name}=\"{value}\"");
        }
    }
    if !x.chaos.is_empty() {
        let _ = write!(s, " chaos=\"{}\"", attr_list(&x.chaos));
    }
    s.push_str("/>\n");
    s
}

/// The flame as flam3's XML, its palette in the given form.
fn flame_xml(f: &Flame, form: PaletteForm) -> String {
    let mut s = String::from("<flames>\n");
    let _ = writeln!(
        s,
        "<flame name=\"{}\" size=\"{} {}\" center=\"{} {}\" scale=\"{}\" rotate=\"{}\" zoom=\"{}\" quality=\"{}\" \
         supersample=\"{}\" filter=\"{}\" filter_shape=\"{}\" brightness=\"{}\" gamma=\"{}\" gamma_threshold=\"{}\" \
         vibrancy=\"{}\" highlight_power=\"{}\" background=\"{}\" estimator_radius=\"{}\" estimator_minimum=\"{}\" \
         estimator_curve=\"{}\" palette_mode=\"{}\"{}>",
        f.name,
        f.size[0],
        f.size[1],
        f.center[0],
        f.center[1],
        f.scale,
        f.rotate,
        f.zoom,
        f.quality,
        f.supersample,
        f.filter,
        shape_name(f.filter_shape),
        f.brightness,
        f.gamma,
        f.gamma_threshold,
        f.vibrancy,
        f.highlight_power,
        attr_list(&f.background),
        f.estimator_radius,
        f.estimator_minimum,
        f.estimator_curve,
        if f.palette_mode == PaletteMode::Linear { "linear" } else { "step" },
        match form {
            PaletteForm::Library(n) => format!(" palette=\"{n}\""),
            _ => String::new(),
        },
    );
    for x in &f.xforms {
        s.push_str(&xform_xml("xform", x, false));
    }
    if let Some(x) = &f.final_xform {
        s.push_str(&xform_xml("finalxform", x, true));
    }
    let byte = |v: f64| (v * 255.0).round() as u8;
    match form {
        PaletteForm::Colors => {
            for (i, c) in f.palette.iter().enumerate() {
                let _ = writeln!(s, "  <color index=\"{i}\" rgb=\"{} {} {}\"/>", byte(c[0]), byte(c[1]), byte(c[2]));
            }
        }
        PaletteForm::Hex => {
            s.push_str("  <palette count=\"256\" format=\"RGB\">\n");
            for row in f.palette.chunks(8) {
                s.push_str("    ");
                for c in row {
                    let _ = write!(s, "{:02X}{:02X}{:02X}", byte(c[0]), byte(c[1]), byte(c[2]));
                }
                s.push('\n');
            }
            s.push_str("  </palette>\n");
        }
        PaletteForm::Library(_) => {}
    }
    s.push_str("</flame>\n</flames>\n");
    s
}

fn flam3(tool: &Path, flame_file: &Path, out: &Path, seed: u32) -> image::RgbaImage {
    let status = Command::new(tool)
        .env("nthreads", "1")
        .env("isaac_seed", seed.to_string())
        .env("out", out)
        .env("format", "png")
        .env("enable_png_comments", "0")
        .env("verbose", "0")
        .env("in", flame_file)
        .status()
        .expect("flam3-render runs");
    assert!(status.success(), "flam3-render failed on {}", flame_file.display());
    image::open(out).unwrap_or_else(|e| panic!("{}: {e}", out.display())).to_rgba8()
}

/// Mean |Δ| of the RGB bytes (composited on black) over the pixels either image draws.
fn difference(a: &image::RgbaImage, b: &image::RgbaImage, background: [u8; 3]) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let (mut sum, mut n) = (0u64, 0u64);
    for (p, q) in a.pixels().zip(b.pixels()) {
        let drawn = |px: &image::Rgba<u8>| px.0[..3] != background;
        if !drawn(p) && !drawn(q) {
            continue;
        }
        let on_black = |px: &image::Rgba<u8>, c: usize| u32::from(px.0[c]) * u32::from(px.0[3]) / 255;
        sum += (0..3).map(|c| on_black(p, c).abs_diff(on_black(q, c)) as u64).sum::<u64>();
        n += 3;
    }
    if n == 0 { 0.0 } else { sum as f64 / n as f64 }
}

/// Flames whose features the import keeps (flam3's Gaussian spatial filter at one sample a
/// pixel; no supersampling), also imported as scenes (`nlifs import flame`) and rendered by the
/// scene renderer: the conjugation into nlifs's view (a rotated camera; waves and popcorn keep
/// their xform's coefs), the absolute density with flam3's brightness and gamma, density
/// estimation, opacity, the final xform and its opacity, xaos, the palette and the spatial filter (the "xaos"
/// flame's pieces are thin: without the filter its import lit 159 pixels where flam3 lights 331
/// and differed by 7.97; "xaos-sharp" is its twin with a filter too narrow to spread a point;
/// bipolar, exponential, rings and separation differed by 6.7–11.5 unfiltered).
const IMPORTED: &[&str] = &[
    "camera",
    "color-speed",
    "density-estimation",
    "final-opacity",
    "final-xform",
    "linear",
    "mix-sinusoidal-swirl",
    "opacity",
    "palette-hex",
    "var-bipolar",
    "var-exponential",
    "var-julian",
    "var-popcorn",
    "var-rings",
    "var-separation",
    "var-spherical",
    "var-swirl",
    "var-waves",
    "xaos",
    "xaos-sharp",
];

/// The imported scene of `flame` rendered on the CPU as `nlifs render SCENE.toml` does.
fn imported_render(flame: &Flame) -> image::RgbaImage {
    use nlifs::shot::{Framing, Shot};
    let scene = nlifs::scene::flame_import::scene_of_flame(flame, "palette.png").expect("import").scene;
    let shot = Shot::prepare(&scene, 0.0, &scene.render, Framing::Scene, None).expect("shot");
    image::DynamicImage::ImageRgb8(nlifs::render::render_cpu(&shot, &|_, _| {}).image).to_rgba8()
}

#[test]
fn flames_match_flam3_render() {
    let Some(tool) = flam3_render_path() else {
        assert!(!tools_required(), "CI or NLIFS_REQUIRE_TOOLS=1 but flam3-render is missing (apt install flam3-utils)");
        eprintln!(
            "\n\n*** SKIPPED flames_match_flam3_render: flam3-render is not installed (apt install flam3-utils) ***\n"
        );
        return;
    };
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("../flame-fidelity");
    std::fs::create_dir_all(&dir).expect("output folder");
    let mut table = String::from("flame                          nlifs-flam3  flam3-flam3  bound   match\n");
    let mut failures = Vec::new();
    for (built, form) in cases() {
        let file = dir.join(format!("{}.flame", built.name));
        std::fs::write(&file, flame_xml(&built, form)).expect("flame file");
        // nlifs renders what its reader makes of the file, as `nlifs render FILE` does.
        let read = nlifs::flame::read_file(&file).unwrap_or_else(|e| panic!("{e}"));
        let flame = read.flames.into_iter().next().expect("one flame");
        let a = flam3(&tool, &file, &dir.join(format!("{}-flam3.png", flame.name)), 1);
        let b = flam3(&tool, &file, &dir.join(format!("{}-flam3-seed2.png", flame.name)), 2);
        let ours = nlifs::flame::render::render(&flame, 1, &|_| {}).unwrap_or_else(|e| panic!("{}: {e}", flame.name));
        let ours = image::RgbaImage::from_raw(ours.width, ours.height, ours.rgba).expect("image size");
        ours.save(dir.join(format!("{}-nlifs.png", flame.name))).expect("png");
        let bg = flame.background.map(|c| (c * 256.0).min(255.0) as u8);
        let d_ours = difference(&ours, &a, bg);
        let d_self = difference(&a, &b, bg);
        let bound = 2.0 * d_self + 3.0;
        let ok = d_ours <= bound;
        let _ = writeln!(
            table,
            "{:<30} {d_ours:>11.2} {d_self:>12.2} {bound:>6.2}   {}",
            flame.name,
            if ok { "yes" } else { "NO" }
        );
        if !ok {
            failures.push(flame.name.clone());
        }
        if flame.name.starts_with("random-") && drawn_share(&a, bg) < 0.1 {
            failures.push(format!("{} (draws {:.3} of the picture)", flame.name, drawn_share(&a, bg)));
        }
        if IMPORTED.contains(&flame.name.as_str()) {
            let scene = imported_render(&flame);
            scene.save(dir.join(format!("{}-imported.png", flame.name))).expect("png");
            let d = difference(&scene, &a, bg);
            let ok = d <= bound;
            let name = format!("{} (imported)", flame.name);
            let _ =
                writeln!(table, "{name:<30} {d:>11.2} {d_self:>12.2} {bound:>6.2}   {}", if ok { "yes" } else { "NO" });
            if !ok {
                failures.push(name);
            }
        }
    }
    assert_eq!(
        IMPORTED.iter().filter(|n| table.contains(&format!("{n} (imported)"))).count(),
        IMPORTED.len(),
        "every flame of IMPORTED is in the set"
    );
    eprintln!("\n{table}images in {}", dir.display());
    assert!(failures.is_empty(), "flames that do not match flam3-render: {failures:?}\n{table}");
}
