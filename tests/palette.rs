//! Colour by a colour coordinate (`[render] color = "palette"`): equal coordinates give one
//! colour, the coordinate of the binary-digit IFS is its point's address (a closed form), the
//! GPU carries the same coordinate as the CPU, and palette errors are located. That function
//! colour keeps its bytes is `cpu_golden.rs`'s and `gpu_vs_cpu.rs`'s.

mod common;

use glam::Vec3;
use nlifs::chaos_game::{CollectSink, run_chunk};
use nlifs::palette::{Palette, index_of};
use nlifs::scene::Scene;
use nlifs::scene::spec::{ColorMode, SplatMode};
use nlifs::shot::{Framing, Shot};
use nlifs::splat::Framebuffer;

/// Two maps of the unit square halving x toward 0 and toward 1 (and y toward 0): the
/// attractor is the segment [0, 1] × {0}, the point with address b₁b₂… at x = 0.b₁b₂… in
/// binary. `extra` is appended to each function.
fn binary_scene(extra: [&str; 2], render: &str) -> Scene {
    let text = format!(
        "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n\
         [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0, 0]\n{}\n\
         [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]\n{}\n\
         [render]\nwidth = 256\nheight = 64\ndepth_cue = 0\ncolor = \"palette\"\n{render}\n",
        extra[0], extra[1]
    );
    Scene::parse(&text, "binary.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// The colour indices of `points` points of `scene`'s shot (CPU, seed 5).
fn collect(scene: &Scene, points: u64) -> (Shot, CollectSink) {
    let settings = nlifs::scene::spec::RenderSettings { points, seed: 5, ..scene.render.clone() };
    let shot = Shot::prepare(scene, 0.0, &settings, Framing::Fit, None).unwrap();
    let sink = shot.run(
        CollectSink::default,
        |mut a, b| {
            a.points.extend(b.points);
            a.functions.extend(b.functions);
            a
        },
        || {},
    );
    (shot, sink)
}

/// All c_i equal to a: c → a (exactly: (a + a) / 2 = a, and the start's weight halves every
/// step of the ≥ 24-step transient), so every point carries index ⌊256 a⌋ and every
/// covered pixel of a flat closest-mode render is that palette entry, byte for byte.
#[test]
fn equal_coordinates_give_one_colour() {
    let a = 0.3;
    let scene = binary_scene(["palette_index = 0.3", "palette_index = 0.3"], "palette = \"lagoon\"");
    let (_, sink) = collect(&scene, 200_000);
    assert!(!sink.functions.is_empty());
    let want = index_of(a);
    assert!(sink.functions.iter().all(|&i| i == want), "indices other than {want}");

    let dir = common::temp_dir("palette-one-colour");
    let scene_path = dir.join("one.toml");
    std::fs::write(&scene_path, nlifs::scene::Scene::to_toml(&scene)).unwrap();
    let png = dir.join("one.png");
    let out = common::run_nlifs(&[
        "render",
        scene_path.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--mode",
        "closest",
        "--look",
        "paper",
        "--points",
        "200000",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = image::open(&png).unwrap().to_rgb8();
    let colour = Palette::builtin("lagoon").unwrap().samples[want as usize].map(nlifs::color::linear_to_srgb8);
    let background = scene.render.background.map(nlifs::color::linear_to_srgb8);
    let covered: Vec<[u8; 3]> = img.pixels().map(|p| p.0).filter(|p| *p != background).collect();
    assert!(covered.len() > 100, "only {} covered pixels", covered.len());
    assert!(covered.iter().all(|p| *p == colour), "a covered pixel is not {colour:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The binary-digit IFS with c₀ = 0, c₁ = 1: c ← (c + b) / 2 is the recurrence of x, so after
/// the transient a point's colour coordinate is its x (both forget their start as 2^-steps,
/// below 2^-24 here; f32 rounding adds at most a few 2^-24). The index is ⌊256 x⌋ (255 at
/// x = 1) except within 10^-3 of an entry's boundary: 256 x − 1 − 10^-3 ≤ index ≤ 256 x + 10^-3.
#[test]
fn colour_coordinate_is_the_binary_address() {
    let scene = binary_scene(["palette_index = 0", "palette_index = 1"], "");
    let (_, sink) = collect(&scene, 400_000);
    let mut seen = [false; 256];
    for (p, &i) in sink.points.iter().zip(&sink.functions) {
        let d = i as f64 - 256.0 * p.x as f64;
        assert!((-1.0 - 1e-3..=1e-3).contains(&d), "point {p} has index {i}, 256 x = {}", 256.0 * p.x);
        seen[i as usize] = true;
    }
    // The uniform measure on [0, 1] reaches every index.
    assert!(seen.iter().all(|&s| s), "an index never occurs");
}

/// Default coordinates spread i / (n − 1): the same binary IFS without `palette_index` is the
/// case above (c₀ = 0, c₁ = 1), index for index.
#[test]
fn default_coordinates_are_spread_evenly() {
    let given = collect(&binary_scene(["palette_index = 0", "palette_index = 1"], ""), 50_000).1;
    let spread = collect(&binary_scene(["", ""], ""), 50_000).1;
    assert_eq!(given.functions, spread.functions);
}

/// The GPU carries the CPU's colour coordinate: on the binary IFS with a grey ramp palette
/// (entry i = i / 255) in average mode, a pixel's mean colour is the mean c of its points, and
/// c is x, so on both devices the mean colour lies within [(256 x₀ − 1) / 255, 256 x₁ / 255]
/// for the pixel's x range [x₀, x₁] (entry ⌊256 c⌋ = i is colour i / 255), widened by the
/// splat's rounding of colour × 255 (½ / 255). The two means therefore differ by at most
/// 256 / 255 of that range plus 2 / 255 (no statistics: a wrong coordinate on the GPU, e.g.
/// the function index, misses by far more).
#[test]
fn gpu_carries_the_colour_coordinate() {
    let Some(ctx) = common::gpu() else { return };
    let mut scene = binary_scene(["", ""], "");
    scene.render.mode = SplatMode::Average;
    scene.render.palette =
        Some(Palette { source: "grey ramp".into(), samples: (0..256).map(|i| [i as f32 / 255.0; 3]).collect() });
    assert_eq!(scene.render.color, ColorMode::Palette);
    let settings = nlifs::scene::spec::RenderSettings { points: 1 << 20, seed: 9, ..scene.render.clone() };
    let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Fit, None).unwrap();
    let gpu = nlifs::gpu::render::render_gpu(&ctx, &shot).unwrap();
    let mut cpu = Framebuffer::new(shot.view, shot.compiled.colors.clone());
    for c in 0..(1u32 << 20) / 64 / 16 {
        run_chunk(&shot.compiled, 9, 0, c, 16, &mut cpu);
    }
    let x_of = |x: f32| shot.view.pixel_from_world.project_point3(Vec3::new(x, 0.0, 0.0)).x;
    let pixel_range = 1.0 / (x_of(1.0) - x_of(0.0)) as f64;
    let tolerance = pixel_range * 256.0 / 255.0 + 2.0 / 255.0;
    let (mut compared, mut worst) = (0, 0.0f64);
    for (i, (g, c)) in gpu.framebuffer.accum.iter().zip(&cpu.accum).enumerate() {
        if g[3] == 0 || c[3] == 0 {
            continue;
        }
        let mean = |a: &[u32; 4]| a[0] as f64 / a[3] as f64 / 255.0;
        let d = (mean(g) - mean(c)).abs();
        assert!(d <= tolerance, "pixel {i}: GPU mean c {} vs CPU {} (tolerance {tolerance})", mean(g), mean(c));
        compared += 1;
        worst = worst.max(d / tolerance);
    }
    eprintln!("GPU vs CPU mean colour coordinate: {compared} pixels, worst |Δ|/tolerance {worst:.3}");
    assert!(compared > 100, "only {compared} pixels covered by both");
}

/// flam3's linear palette mode (`palette_mode = "linear"`): with every c_i equal to a, 256 a =
/// 100.25, a palette of black even and white odd entries, the points carry entry 100 or 101,
/// a quarter of them 101 (the dither: within 4 standard deviations of the binomial, on the
/// CPU's points and in the GPU's average-mode sums alike), so that a pixel's mean colour is
/// flam3's interpolation ¾ · entry 100 + ¼ · entry 101; step mode carries entry 100 only. The
/// mode is read, checked and written back.
#[test]
fn linear_palette_mode_interpolates_the_entries() {
    let a = 100.25 / 256.0;
    let coords = [format!("palette_index = {a}"), format!("palette_index = {a}")];
    let zebra = Palette {
        source: "zebra".into(),
        samples: (0..256).map(|i| [if i % 2 == 1 { 1.0 } else { 0.0 }; 3]).collect(),
    };
    let scene_of = |mode: &str| {
        let mut scene =
            binary_scene([&coords[0], &coords[1]], &format!("mode = \"average\"\npalette_mode = \"{mode}\""));
        scene.render.palette = Some(zebra.clone());
        scene
    };
    let n = 400_000u64;
    let sd = (0.25f64 * 0.75 / n as f64).sqrt();
    let (_, step) = collect(&scene_of("step"), n);
    assert!(step.functions.iter().all(|&i| i == 100), "step mode: entries other than 100");
    let linear = scene_of("linear");
    assert_eq!(linear.render.palette_mode, nlifs::flame::PaletteMode::Linear);
    assert!(Scene::to_toml(&linear).contains("palette_mode = \"linear\""));
    let (_, sink) = collect(&linear, n);
    assert!(sink.functions.iter().all(|&i| i == 100 || i == 101), "entries other than 100 and 101");
    let share = sink.functions.iter().filter(|&&i| i == 101).count() as f64 / sink.functions.len() as f64;
    assert!((share - 0.25).abs() <= 4.0 * sd, "CPU: {share} of the points carry entry 101, not a quarter");

    let err = Scene::parse(
        "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0, 0]\n[render]\npalette_mode = \"smooth\"\n",
        "s.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("s.toml:10:16") && err.contains("render.palette_mode") && err.contains("\"linear\""), "{err}");

    let Some(ctx) = common::gpu() else { return };
    let settings = nlifs::scene::spec::RenderSettings { points: 1 << 20, seed: 9, ..linear.render.clone() };
    let shot = Shot::prepare(&linear, 0.0, &settings, Framing::Fit, None).unwrap();
    let gpu = nlifs::gpu::render::render_gpu(&ctx, &shot).unwrap();
    let (red, count) =
        gpu.framebuffer.accum.iter().fold((0u64, 0u64), |(r, n), a| (r + u64::from(a[0]), n + u64::from(a[3])));
    assert!(count > 500_000, "only {count} points splatted");
    let share = red as f64 / 255.0 / count as f64;
    let sd = (0.25f64 * 0.75 / count as f64).sqrt();
    assert!((share - 0.25).abs() <= 4.0 * sd + 1.0 / 255.0, "GPU: mean red {share}, not a quarter");
}

/// Palette errors name the field, its line and column, and the known palettes or the file.
#[test]
fn palette_errors_are_located() {
    let base = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n[[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0, 0]\n";
    let err = |tail: &str| Scene::parse(&format!("{base}{tail}"), "/nonexistent-dir/s.toml").unwrap_err().to_string();
    let e = err("[render]\npalette = \"sunrise\"\n");
    assert!(e.contains("s.toml:10:11") && e.contains("render.palette") && e.contains("ember, lagoon"), "{e}");
    assert!(e.contains("/nonexistent-dir/sunrise"), "{e}");
    let e = err("[render]\ncolor = \"rainbow\"\n");
    assert!(e.contains("s.toml:10:9") && e.contains("\"function\" or \"palette\""), "{e}");
    let e = err("palette_index = 1.5\n");
    assert!(e.contains("s.toml:9:17") && e.contains("function[0].palette_index") && e.contains("0..1"), "{e}");

    let dir = common::temp_dir("palette-errors");
    std::fs::write(dir.join("broken.png"), b"no image").unwrap();
    let e = Scene::parse(&format!("{base}[render]\npalette = \"broken.png\"\n"), dir.join("s.toml").to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot read palette image") && e.contains("broken.png") && e.contains(":10:11"), "{e}");
    // The command line: a missing palette file is bad input (exit 2), named, and no image.
    let png = dir.join("out.png");
    let sierpinski = common::scene_path("sierpinski");
    let out = common::run_nlifs(&[
        "render",
        sierpinski.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--palette",
        "missing-strip.png",
        "--points",
        "1000",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("missing-strip.png") && stderr.contains("spectrum"), "{stderr}");
    assert!(!png.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A palette scene reads back from its own text unchanged.
#[test]
fn palette_fields_round_trip() {
    let scene = binary_scene(["palette_index = 0.25", ""], "palette = \"moss\"");
    let again = Scene::parse(&scene.to_toml(), "binary.toml").unwrap();
    assert_eq!(again.render.color, ColorMode::Palette);
    assert_eq!(again.render.palette, scene.render.palette);
    assert_eq!(again.functions[0].palette_index, Some(0.25));
    assert_eq!(again.functions[1].palette_index, None);
}

/// The viewer's palette controls: colour mode, palette and a c_i slider drag are three undo
/// steps; each recompiles the IFS with the new colours, and undo restores each exactly.
#[test]
fn viewer_palette_edits_are_undoable() {
    use nlifs::live::LiveSettings;
    use nlifs::viewer::command::Command;
    use nlifs::viewer::state::ViewerState;
    let path = common::scene_path("sierpinski");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut s = ViewerState::new(scene.clone(), Some(path), LiveSettings::default());
    let coords = |s: &ViewerState| s.compiled.as_ref().unwrap().color_coords.clone();
    assert_eq!(coords(&s), None);
    s.apply([Command::SetColorMode(ColorMode::Palette)]);
    // Three functions: the default spread 0, ½, 1.
    assert_eq!(coords(&s), Some(vec![0.0, 0.5, 1.0]));
    s.apply([Command::SetPalette("moss".into())]);
    assert_eq!(s.compiled.as_ref().unwrap().colors, Palette::builtin("moss").unwrap().samples);
    s.apply([Command::SetPaletteIndex { function: 1, index: Some(0.2) }]);
    s.apply([Command::SetPaletteIndex { function: 1, index: Some(0.75) }, Command::EndGesture]);
    assert_eq!(coords(&s), Some(vec![0.0, 0.75, 1.0]));
    s.apply([Command::Undo]);
    assert_eq!(s.scene.functions[1].palette_index, None, "the drag is one undo step");
    s.apply([Command::Undo]);
    assert_eq!(s.scene.render.palette, None);
    s.apply([Command::Undo]);
    assert_eq!(s.scene, scene);
    assert_eq!(coords(&s), None);
}

/// `--palette` on `render --part`: the merged parts equal one whole render byte for byte (the
/// palette travels in the parts' provenance with its entries).
#[test]
fn palette_parts_merge_to_the_whole_render() {
    let dir = common::temp_dir("palette-parts");
    let scene = common::scene_path("plant2");
    let base =
        [scene.to_str().unwrap(), "--palette", "ember", "--width", "160", "--height", "120", "--points", "200000"];
    let run = |extra: &[&str]| {
        let out = common::run_nlifs(&[&["render"], &base[..], extra].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    };
    let (whole, merged) = (dir.join("whole.png"), dir.join("merged.png"));
    run(&["-o", whole.to_str().unwrap()]);
    let parts: Vec<String> = (1..=2).map(|k| dir.join(format!("p{k}.part")).to_str().unwrap().to_string()).collect();
    for (k, part) in parts.iter().enumerate() {
        run(&["--part", &format!("{}/2", k + 1), "--raw", part]);
    }
    let out = common::run_nlifs(&["merge", &parts[0], &parts[1], "-o", merged.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read(&whole).unwrap() == std::fs::read(&merged).unwrap(), "merged parts differ from the whole");
    let _ = std::fs::remove_dir_all(&dir);
}
