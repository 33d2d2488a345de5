//! The flame renderer (`src/flame/render.rs`) on its own and through `nlifs render FILE.flame`:
//! the same bytes for a seed whatever the thread count, other bytes for another seed, flam3's
//! sample count, errors for flames that cannot be rendered, and the command's options (the
//! file's size by default, `--width`, `--index`, `--name`, a bad index as exit code 2 with
//! nothing written).

mod common;

use common::{run_nlifs, temp_dir};
use nlifs::flame::render::{RenderError, render, sample_count};
use nlifs::flame::{Flame, PaletteMode, Variation, VariationTerm, Xform};

fn flame() -> Flame {
    let term = |name: &str, weight: f64| {
        let variation = Variation::by_name(name).expect("variation");
        VariationTerm { variation, weight, params: variation.default_params() }
    };
    let xform = |weight: f64, color: f64, coefs: [f64; 6]| Xform {
        weight,
        color,
        color_speed: 0.5,
        opacity: 1.0,
        coefs,
        post: None,
        variation_coefs: None,
        variations: vec![term("linear", 0.7), term("swirl", 0.3)],
        chaos: Vec::new(),
    };
    Flame {
        name: "test".into(),
        size: [48, 40],
        scale: 14.0,
        rotate: 10.0,
        quality: 40.0,
        supersample: 2,
        filter: 0.6,
        estimator_radius: 4.0,
        palette_mode: PaletteMode::Linear,
        palette: (0..256).map(|i| [i as f64 / 255.0, 1.0 - i as f64 / 255.0, 0.5, 1.0]).collect(),
        xforms: vec![
            xform(0.5, 0.0, [0.5, 0.0, 0.0, 0.5, -0.5, -0.3]),
            xform(0.5, 1.0, [0.5, 0.2, -0.2, 0.5, 0.5, 0.3]),
            xform(0.3, 0.5, [0.4, 0.0, 0.0, 0.4, 0.0, 0.6]),
        ],
        ..Flame::default()
    }
}

fn render_on(threads: usize, flame: &Flame, seed: u32) -> Vec<u8> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
    pool.install(|| render(flame, seed, &|_| {})).expect("render").rgba
}

/// Runs finish in any order on any thread; integer buckets make the sums exact.
#[test]
fn same_bytes_on_any_thread_count() {
    let f = flame();
    let one = render_on(1, &f, 7);
    assert!(one.chunks(4).any(|p| p[..3] != [0, 0, 0]), "nothing drawn");
    assert_eq!(one, render_on(3, &f, 7), "1 and 3 threads differ");
    assert_eq!(one, render_on(4, &f, 7), "1 and 4 threads differ");
    assert_ne!(one, render_on(2, &f, 8), "seeds 7 and 8 give the same picture");
}

#[test]
fn samples_are_quality_times_pixels_times_four_to_the_zoom() {
    let mut f = flame();
    assert_eq!(sample_count(&f), 40 * 48 * 40);
    f.zoom = 1.0;
    assert_eq!(sample_count(&f), 4 * 40 * 48 * 40);
    let image = render_on(2, &f, 1);
    assert_eq!(image.len(), 48 * 40 * 4);
}

#[test]
fn unrenderable_flames_are_errors() {
    let mut f = flame();
    f.xforms.iter_mut().for_each(|x| x.weight = 0.0);
    assert!(matches!(render(&f, 1, &|_| {}), Err(RenderError::Empty(_))));
    let mut f = flame();
    f.palette.truncate(10);
    assert_eq!(render(&f, 1, &|_| {}), Err(RenderError::BadPalette(10)));
    let mut f = flame();
    f.estimator_minimum = 9.0;
    assert!(matches!(render(&f, 1, &|_| {}), Err(RenderError::BadEstimator(_))));
    let mut f = flame();
    f.size = [0, 10];
    assert_eq!(render(&f, 1, &|_| {}), Err(RenderError::BadSize(0, 10)));
}

const FILE: &str = r#"<flames>
<flame name="first" size="40 30" scale="12" quality="20" estimator_radius="0">
  <xform weight="0.5" color="0" linear="1" coefs="0.5 0 0 0.5 -0.5 0"/>
  <xform weight="0.5" color="1" spherical="0.5" linear="0.5" coefs="0.5 0 0 0.5 0.5 0"/>
  <color index="0" rgb="255 0 0"/><color index="255" rgb="0 0 255"/>
</flame>
<flame name="second" size="36 24" scale="10" quality="20">
  <xform weight="1" color="0" swirl="1" coefs="0.6 0.1 -0.1 0.6 0 0"/>
  <xform weight="1" color="1" linear="1" coefs="0.5 0 0 0.5 0.3 0.3"/>
  <color index="0" rgb="0 255 0"/><color index="255" rgb="255 255 0"/>
</flame>
</flames>
"#;

#[test]
fn render_command_takes_the_file_and_its_options() {
    let dir = temp_dir("flame-render");
    let file = dir.join("two.flame");
    std::fs::write(&file, FILE).expect("flame file");
    let out = dir.join("a.png");
    let run = |args: &[&str]| {
        let mut all = vec!["render", file.to_str().expect("path"), "-o", out.to_str().expect("path")];
        all.extend_from_slice(args);
        let o = run_nlifs(&all);
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let size = || image::image_dimensions(&out).expect("png");
    let (code, err) = run(&[]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(size(), (40, 30), "the first flame's size");
    // The file holds two flames: the render says which it drew and how to choose another.
    assert!(err.contains("holds 2 flames; this renders the first, `first`") && err.contains("--index"), "{err}");
    let first = std::fs::read(&out).expect("png");
    let (code, err) = run(&["--name", "second"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("holds 2 flames"), "a flame chosen by name needs no note: {err}");
    assert_eq!(size(), (36, 24));
    let (code, err) = run(&["--index", "1", "--width", "72", "--threads", "1"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(size(), (72, 24), "--width over the file's size");
    let (code, err) = run(&["--threads", "3"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(std::fs::read(&out).expect("png"), first, "3 threads and the default give other bytes");
    std::fs::remove_file(&out).expect("remove");
    let (code, err) = run(&["--index", "2"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("2 flame(s)"), "{err}");
    let (code, err) = run(&["--name", "third"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("`first`, `second`"), "{err}");
    assert!(!out.exists(), "a failed render wrote its output");
}
