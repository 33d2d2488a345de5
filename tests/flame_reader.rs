//! The flam3 XML reader (`nlifs::flame::xml`) against what flam3's `parser.c` makes of the same
//! text: the system's sample flames when flam3 is installed, and fixtures written here for each
//! palette form, symmetry, xaos, the final xform, the defaults, and the bad inputs (each must
//! be an error naming the file and position, or a warning, and never a panic).

mod common;

use std::path::{Path, PathBuf};

use nlifs::flame::palette::{PaletteLibrary, PaletteSource, hsv_to_rgb, rgb_to_hsv};
use nlifs::flame::xml::{FlameError, FlameFile, MAX_FILE_BYTES, ReadOptions, read_file, read_str_with};
use nlifs::flame::{FilterShape, IDENTITY, PaletteMode, Variation};

/// A palette library written for the tests: palette 0 has entry i = (i, 255 − i, 0), palette 7
/// entry i = (0, 0, i); one malformed palette (number 3) that must be left out.
fn fixture_library(dir: &Path) -> PathBuf {
    let hex = |f: &dyn Fn(usize) -> [usize; 3]| -> String {
        (0..256).map(f).map(|[r, g, b]| format!("00{r:02x}{g:02x}{b:02x}")).collect()
    };
    let text = format!(
        "<palettes>\n<palette number=\"0\" name=\"ramp\" data=\"{}\"/>\n<palette number=\"3\" data=\"00zz\"/>\n<palette number=\"7\" data=\"{}\"/>\n</palettes>\n",
        hex(&|i| [i, 255 - i, 0]),
        hex(&|i| [0, 0, i])
    );
    let path = dir.join("palettes.xml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A folder of its own for each call: the tests run in parallel and `common::temp_dir` empties
/// a folder of the same name.
fn fresh_dir(tag: &str) -> common::TempDir {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    common::temp_dir(&format!("{tag}-{n}"))
}

fn options(dir: &Path) -> ReadOptions {
    ReadOptions { palette_library: fixture_library(dir) }
}

/// Reads `text` as `t.flame` with the fixture library; an error fails the test with its message.
fn read(text: &str) -> FlameFile {
    let dir = fresh_dir("flame-reader");
    read_str_with(text, "t.flame", &options(&dir)).unwrap_or_else(|e| panic!("{e}"))
}

fn read_err(text: &str) -> String {
    let dir = fresh_dir("flame-reader-err");
    match read_str_with(text, "t.flame", &options(&dir)) {
        Ok(f) => panic!("read without error: {} flames, warnings {:?}", f.flames.len(), f.warnings),
        Err(e) => e.to_string(),
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

const XF: &str = r#"<xform weight="1" color="0" linear="1" coefs="1 0 0 1 0 0"/>"#;

fn flame(attrs: &str, body: &str) -> String {
    format!("<flame {attrs}>\n{body}\n</flame>\n")
}

#[test]
fn system_samples_read_as_flam3_reads_them() {
    let test = Path::new("/usr/share/flam3/test.flam3");
    let library = Path::new("/usr/share/flam3/flam3-palettes.xml");
    if !test.exists() || !library.exists() {
        eprintln!("\n*** SKIPPED: flam3's samples are not installed (apt-get install flam3) ***\n");
        return;
    }
    let opts = ReadOptions { palette_library: library.to_path_buf() };
    let file = nlifs::flame::xml::read_file_with(test, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(file.flames.len(), 2);
    let f = &file.flames[0];
    assert_eq!(f.size, [640, 480]);
    assert_eq!((f.scale, f.quality, f.filter, f.supersample), (240.0, 10.0, 1.0, 1));
    assert_eq!((f.brightness, f.gamma, f.vibrancy), (4.0, 4.0, 1.0));
    assert_eq!(f.xforms.len(), 4);
    assert!(f.final_xform.is_none());
    let x = &f.xforms[0];
    assert_eq!((x.weight, x.color), (0.25, 1.0));
    assert_eq!(x.coefs, [-0.681206, -0.0779465, 0.20769, 0.755065, -0.0416126, -0.262334]);
    // The table has spherical from the start; linear is 0 unless given.
    let spherical = Variation::by_name("spherical").unwrap();
    assert_eq!(x.variations.len(), 1);
    assert_eq!((x.variations[0].variation, x.variations[0].weight), (spherical, 1.0));
    // palette 15 turned by hue 0.22851, straight from the library.
    assert_eq!(file.sources[0].palette, PaletteSource::Library { number: 15, hue_turns: 0.22851 });
    let lib = PaletteLibrary::read(library).unwrap();
    assert_eq!(f.palette, lib.get(15, 0.22851).unwrap());
    assert_eq!(file.flames[1].palette, lib.get(29, 0.147038).unwrap());
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);

    // vidres.flam3 is a size template for flam3-genome: no xforms, an error that says so.
    let vidres = Path::new("/usr/share/flam3/vidres.flam3");
    if vidres.exists() {
        let e = read_file(vidres).unwrap_err().to_string();
        assert!(e.starts_with("/usr/share/flam3/vidres.flam3:1:1: flame #0: has no <xform>"), "{e}");
    }
}

#[test]
fn defaults_are_flam3s() {
    let file = read(&flame(r#"name="d""#, r#"<xform weight="0.5" coefs="1 0 0 1 0 0"/><xform weight="0.5"/>"#));
    let f = &file.flames[0];
    assert_eq!(f.name, "d");
    assert_eq!((f.size, f.center, f.scale, f.rotate, f.zoom), ([100, 100], [0.0, 0.0], 50.0, 0.0, 0.0));
    assert_eq!((f.quality, f.supersample, f.filter, f.filter_shape), (1.0, 1, 0.5, FilterShape::Gaussian));
    assert_eq!((f.brightness, f.gamma, f.gamma_threshold, f.vibrancy, f.highlight_power), (4.0, 4.0, 0.01, 1.0, -1.0));
    assert_eq!((f.estimator_radius, f.estimator_minimum, f.estimator_curve), (9.0, 0.0, 0.4));
    assert_eq!((f.background, f.palette_mode), ([0.0; 3], PaletteMode::Step));
    // Xform defaults: colour = parity of the position, speed 0.5, opacity 1, identity, no
    // variation (flam3 zeroes linear when it reads an xform).
    let (a, b) = (&f.xforms[0], &f.xforms[1]);
    assert_eq!((a.color, b.color), (0.0, 1.0));
    assert_eq!((a.color_speed, a.opacity, a.coefs, a.post.is_none()), (0.5, 1.0, IDENTITY, true));
    assert!(a.variations.is_empty() && a.chaos.is_empty());
    // No palette: black, with a warning.
    assert_eq!(file.sources[0].palette, PaletteSource::None);
    assert!(f.palette.iter().all(|c| *c == [0.0; 4]));
    assert!(file.warnings.iter().any(|w| w.contains("no palette")), "{:?}", file.warnings);
}

#[test]
fn flame_attributes() {
    let attrs = r#"name="all" size="320 200" center="1.5 -2" scale="80" rotate="30" zoom="1" quality="50" supersample="2" filter="0.7" filter_shape="mitchell" brightness="3" gamma="2.2" gamma_threshold="0.02" vibrancy="0.5" highlight_power="1" background="0.1 0.2 0.3" estimator_radius="5" estimator_minimum="1" estimator_curve="0.6" palette_mode="linear""#;
    let f = &read(&flame(attrs, XF)).flames[0];
    assert_eq!((f.size, f.center, f.scale, f.rotate, f.zoom), ([320, 200], [1.5, -2.0], 80.0, 30.0, 1.0));
    assert_eq!((f.quality, f.supersample, f.filter, f.filter_shape), (50.0, 2, 0.7, FilterShape::Mitchell));
    assert_eq!((f.brightness, f.gamma, f.gamma_threshold, f.vibrancy, f.highlight_power), (3.0, 2.2, 0.02, 0.5, 1.0));
    assert_eq!(
        (f.background, f.estimator_radius, f.estimator_minimum, f.estimator_curve),
        ([0.1, 0.2, 0.3], 5.0, 1.0, 0.6)
    );
    assert_eq!(f.palette_mode, PaletteMode::Linear);
    // The legacy spelling of supersample.
    assert_eq!(read(&flame(r#"oversample="3""#, XF)).flames[0].supersample, 3);
}

#[test]
fn xform_attributes() {
    let body = r#"
  <xform weight="2" color="0.25 0.9" symmetry="0.5" coefs="1 2 3 4 5 6" post="0 1 -1 0 0 0" opacity="0.5" linear="0.5" swirl="0.25"/>
  <xform weight="1" color_speed="0.1" plotmode="off" spherical="1"/>
  <finalxform color="0.5" color_speed="0" sinusoidal="1"/>"#;
    let file = read(&flame("", body));
    let f = &file.flames[0];
    let x = &f.xforms[0];
    assert_eq!((x.weight, x.color, x.color_speed, x.opacity), (2.0, 0.25, 0.25, 0.5));
    assert_eq!((x.coefs, x.post), ([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], Some([0.0, 1.0, -1.0, 0.0, 0.0, 0.0])));
    // Terms in the table's order, whatever the attributes' order.
    let names: Vec<(&str, f64)> = x.variations.iter().map(|t| (t.variation.name(), t.weight)).collect();
    assert_eq!(names, vec![("linear", 0.5), ("swirl", 0.25)]);
    assert_eq!((f.xforms[1].color_speed, f.xforms[1].opacity), (0.1, 0.0));
    let fin = f.final_xform.as_ref().expect("final xform");
    assert_eq!((fin.weight, fin.color, fin.color_speed), (0.0, 0.5, 0.0));
    assert_eq!(fin.variations[0].variation.name(), "sinusoidal");
    assert!(file.warnings.iter().all(|w| !w.contains("xform")), "{:?}", file.warnings);
}

#[test]
fn legacy_var_forms() {
    let f = &read(&flame("", r#"<xform weight="1" var1="2"/><xform weight="1" var="0.5 0 0 0.5"/>"#)).flames[0];
    assert_eq!(f.xforms[0].variations.len(), 1);
    assert_eq!(f.xforms[0].variations[0].variation.name(), "spherical");
    let v: Vec<(&str, f64)> = f.xforms[1].variations.iter().map(|t| (t.variation.name(), t.weight)).collect();
    assert_eq!(v, vec![("linear", 0.5), ("swirl", 0.5)]);
}

#[test]
fn unknown_variations_are_one_warning_per_xform() {
    let body = r#"<xform weight="1" linear="1" frobnicate="1" frob_param="2" coefs="1 0 0 1 0 0"/>
<xform weight="1" zork="1"/>"#;
    let file = read(&flame(r#"name="u""#, body));
    let warned: Vec<&String> = file.warnings.iter().filter(|w| w.contains("unknown variations")).collect();
    assert_eq!(warned.len(), 2, "{:?}", file.warnings);
    assert_eq!(
        warned[0],
        "t.flame:2: flame #0 'u': xform 0: unknown variations or parameters, left out: frobnicate, frob_param"
    );
    assert!(warned[1].starts_with("t.flame:3: flame #0 'u': xform 1:") && warned[1].ends_with("zork"), "{}", warned[1]);
    let f = &file.flames[0];
    assert_eq!(f.xforms[0].variations.len(), 1);
    // Only an unknown variation: no term at all, so the xform maps to the origin (as flam3).
    assert!(f.xforms[1].variations.is_empty());
}

#[test]
fn other_programs_xform_attributes_are_not_called_variations() {
    // Apophysis 7X names its xforms and writes `var_color`; neither is a variation.
    let body = r#"<xform weight="1" name="iterator_1" linear="1" var_color="1" coefs="1 0 0 1 0 0"/>
<finalxform name="final" var_color="0" spherical="1" coefs="1 0 0 1 0 0"/>"#;
    let file = read(&flame(r#"name="apo""#, body));
    assert!(file.warnings.iter().all(|w| !w.contains("unknown variations")), "{:?}", file.warnings);
    assert!(file.warnings.iter().all(|w| !w.contains("name")), "a label is not worth a warning: {:?}", file.warnings);
    // One warning for the flame, at its first xform that has one.
    let not_read: Vec<&String> = file.warnings.iter().filter(|w| w.contains("var_color")).collect();
    assert_eq!(not_read.len(), 1, "{:?}", file.warnings);
    assert_eq!(
        not_read[0],
        "t.flame:2: flame #0 'apo': xform attributes of other programs flam3 does not read, ignored: var_color"
    );
    let f = &file.flames[0];
    assert_eq!(f.xforms[0].variations.len(), 1);
    assert_eq!(f.final_xform.as_ref().expect("final").variations[0].variation.name(), "spherical");
}

#[test]
fn variation_parameters_take_their_defaults() {
    // Whatever the table holds: every variation with parameters, named in one xform with one
    // of its parameters given; the others must come out as the table's defaults.
    for (index, info) in nlifs::flame::variations::VARIATIONS.iter().enumerate() {
        let Some(((first, _), rest)) = info.params.split_first() else { continue };
        let xml = flame("", &format!(r#"<xform weight="1" {}="0.5" {first}="0.125"/>"#, info.name));
        let f = &read(&xml).flames[0];
        let term = &f.xforms[0].variations[0];
        assert_eq!(term.variation, Variation(index as u8));
        assert_eq!(term.params[0], 0.125, "{}", info.name);
        for (k, (name, default)) in rest.iter().enumerate() {
            assert_eq!(term.params[k + 1], *default, "{}.{name}", info.name);
        }
    }
}

#[test]
fn palette_color_elements_interpolate_and_premultiply() {
    let body = format!(
        "{XF}\n<color index=\"0\" rgb=\"255 0 0\"/>\n<color index=\"128\" rgb=\"0 0 255\"/>\n<color index=\"255\" rgba=\"0 255 0 127.5\"/>"
    );
    let file = read(&flame("", &body));
    let p = &file.flames[0].palette;
    assert_eq!(p[0], [1.0, 0.0, 0.0, 1.0]);
    // rgba is premultiplied by its alpha, as flam3 does for <color>.
    assert_eq!(p[255], [0.0, 0.5, 0.0, 0.5]);
    // Entry 64: halfway between 0 and 128.
    assert_eq!(p[64], [0.5, 0.0, 0.5, 1.0]);
    assert_eq!(
        file.sources[0].palette,
        PaletteSource::Inline { form: nlifs::flame::palette::InlineForm::Color, given: 3 }
    );
    assert!(file.warnings.iter().any(|w| w.contains("gives 3 of 256 entries")), "{:?}", file.warnings);
}

#[test]
fn palette_hex_forms() {
    let hex = |f: &dyn Fn(usize) -> String| -> String { (0..256).map(f).collect::<Vec<_>>().join("") };
    let colors = hex(&|i| format!("00{i:02x}0000"));
    let file = read(&flame("", &format!("{XF}<colors count=\"256\" data=\"{colors}\"/>")));
    assert_eq!(file.flames[0].palette[200], [200.0 / 255.0, 0.0, 0.0, 1.0]);
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);

    // RGB content with line breaks, as flam3 writes it.
    let rgb: Vec<String> = (0..256).map(|i| format!("00{i:02x}00")).collect();
    let text = rgb.chunks(8).map(|c| c.concat()).collect::<Vec<_>>().join("\n      ");
    let file = read(&flame("", &format!("{XF}<palette count=\"256\" format=\"RGB\">\n      {text}\n</palette>")));
    assert_eq!(file.flames[0].palette[17], [0.0, 17.0 / 255.0, 0.0, 1.0]);
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);

    // RGBA, not premultiplied (flam3 premultiplies only <color>); 2 entries: the rest blend.
    let file = read(&flame("", &format!("{XF}<palette count=\"2\" format=\"RGBA\">ff000080 0000ff80</palette>")));
    let p = &file.flames[0].palette;
    assert_eq!(p[0], [1.0, 0.0, 0.0, 128.0 / 255.0]);
    // Entry 128 is in the wrapped run 2..=255 between entry 1 and entry 0 (at 256).
    let t = (128.0 - 1.0) / (256.0 - 1.0);
    assert!(close(p[128][0], t, 1e-12) && close(p[128][2], 1.0 - t, 1e-12), "{:?}", p[128]);
}

#[test]
fn library_palette_with_hue_and_its_errors() {
    let dir = common::temp_dir("flame-reader-lib");
    let opts = options(&dir);
    let file = read_str_with(&flame(r#"palette="0" hue="0.25""#, XF), "t.flame", &opts).unwrap();
    // Entry 10 of the ramp (10, 245, 0) turned a quarter (1.5 sextants).
    let mut hsv = rgb_to_hsv([10.0 / 255.0, 245.0 / 255.0, 0.0]);
    hsv[0] += 1.5;
    let want = hsv_to_rgb(hsv);
    let got = file.flames[0].palette[10];
    for k in 0..3 {
        assert!(close(got[k], want[k], 1e-12), "{got:?} vs {want:?}");
    }
    assert_eq!(got[3], 1.0);
    // The library's palette replaces inline entries (flam3 applies it last), with a warning.
    let body = format!("{XF}<color index=\"0\" rgb=\"1 2 3\"/>");
    let file = read_str_with(&flame(r#"palette="7""#, &body), "t.flame", &opts).unwrap();
    assert_eq!(file.flames[0].palette[255], [0.0, 0.0, 1.0, 1.0]);
    assert!(file.warnings.iter().any(|w| w.contains("replaces")), "{:?}", file.warnings);
    // A number the library lacks (3 is malformed there, so left out): white, as flam3.
    let file = read_str_with(&flame(r#"palette="3""#, XF), "t.flame", &opts).unwrap();
    assert!(file.flames[0].palette.iter().all(|c| *c == [1.0; 4]));
    assert!(file.warnings.iter().any(|w| w.contains("palette 3 is not in")), "{:?}", file.warnings);
    // The old blend form.
    let file =
        read_str_with(&flame("", &format!("{XF}<palette index0=\"0\" index1=\"7\" blend=\"0\"/>")), "t.flame", &opts)
            .unwrap();
    assert!(close(file.flames[0].palette[0][1], 1.0, 1e-12));
    // No library: an error naming its path.
    let missing = ReadOptions { palette_library: dir.join("nowhere.xml") };
    let e = read_str_with(&flame(r#"palette="0""#, XF), "t.flame", &missing).unwrap_err().to_string();
    assert!(e.starts_with("t.flame:1:1: flame #0:") && e.contains("nowhere.xml"), "{e}");
}

#[test]
fn symmetry_adds_flam3s_copies() {
    let f = &read(&flame("", &format!("{XF}<symmetry kind=\"3\"/>"))).flames[0];
    assert_eq!(f.xforms.len(), 3);
    for (k, x) in f.xforms[1..].iter().enumerate() {
        let a = 2.0 * std::f64::consts::PI * (k + 1) as f64 / 3.0;
        assert_eq!((x.weight, x.color_speed), (1.0, 0.0));
        assert_eq!(x.color, k as f64);
        assert!(close(x.coefs[0], a.cos(), 1e-6) && close(x.coefs[1], a.sin(), 1e-6), "{:?}", x.coefs);
        assert_eq!((x.coefs[2], x.coefs[3]), (-x.coefs[1], x.coefs[0]));
        assert_eq!(x.variations[0].variation.name(), "linear");
    }
    // Dihedral: the reflection (determinant −1) first, then the rotation by π.
    let f = &read(&flame("", &format!("{XF}<symmetry kind=\"-2\"/>"))).flames[0];
    assert_eq!(f.xforms.len(), 3);
    assert_eq!((f.xforms[1].coefs, f.xforms[1].color), ([-1.0, 0.0, 0.0, 1.0, 0.0, 0.0], 1.0));
    assert_eq!((f.xforms[2].coefs[0], f.xforms[2].coefs[3], f.xforms[2].color), (-1.0, -1.0, 0.0));
    // Symmetry xforms count in the xaos numbering of the xforms after them.
    let f = &read(&flame("", &format!("<symmetry kind=\"2\"/>{XF}"))).flames[0];
    assert_eq!(f.xforms.len(), 2);
    assert_eq!(f.xforms[1].coefs, IDENTITY);
}

#[test]
fn xaos_rows_are_padded_or_cut() {
    let body = r#"<xform weight="1" linear="1" chaos="0 2"/>
<xform weight="1" linear="1"/>
<xform weight="1" linear="1" chaos="1 1 0 5 5"/>"#;
    let file = read(&flame("", body));
    let f = &file.flames[0];
    assert_eq!(f.xforms[0].chaos, vec![0.0, 2.0, 1.0]);
    assert!(f.xforms[1].chaos.is_empty());
    assert_eq!(f.xforms[2].chaos, vec![1.0, 1.0, 0.0]);
    let w: Vec<&String> = file.warnings.iter().filter(|w| w.contains("chaos")).collect();
    assert_eq!(w.len(), 1, "{:?}", file.warnings);
    assert!(w[0].starts_with("t.flame:4: flame #0: xform 2: chaos has 5 entries for 3 xforms"), "{}", w[0]);
}

#[test]
fn many_flames_without_a_root_keep_their_lines() {
    let text = format!("<?xml version=\"1.0\"?>{}{}", flame(r#"name="a""#, XF), flame(r#"name="b""#, XF));
    let file = read(&text);
    assert_eq!(file.flames.len(), 2);
    assert_eq!((file.sources[0].line, file.sources[1].line), (1, 4));
    // An error in the second flame, on line 5, column 29 of the original text.
    let text = format!("{}{}", flame("", XF), flame("", r#"<xform weight="1" coefs="1 0 0 1 0"/>"#));
    assert_eq!(
        read_err(&text),
        "t.flame:5:26: flame #1: xform 0: attribute coefs: expected 6 numbers, found '1 0 0 1 0'"
    );
    // Roots of any name, nested.
    let file = read(&format!("<Flames><group>{}</group>{}</Flames>", flame("", XF), flame("", XF)));
    assert_eq!(file.flames.len(), 2);
}

#[test]
fn malformed_xml_names_line_and_column() {
    let e = read_err("<flames>\n<flame size=\"10 10\">\n  <xform weight=\"1\" linear=\"1\"\n</flame>\n</flames>\n");
    assert!(e.starts_with("t.flame:4:1: malformed XML"), "{e}");
    let e = read_err("<?xml version=\"1.0\"?><flame name=\"x\"><xform weight=\"1\"/></flam>");
    assert!(e.starts_with("t.flame:1:"), "{e}");
    assert!(read_err("").contains("no <flame>"));
    assert!(read_err("<flames/>").contains("no <flame>"));
}

#[test]
fn bad_values_are_errors_or_warnings() {
    // No xforms, only a final one.
    assert!(read_err(&flame(r#"name="e""#, "")).contains("has no <xform>"));
    assert!(read_err(&flame("", r#"<finalxform linear="1"/>"#)).contains("only a final xform"));
    // Negative weight: 0, warned.
    let file = read(&flame("", r#"<xform weight="-2" linear="1"/><xform weight="1" linear="1"/>"#));
    assert_eq!(file.flames[0].xforms[0].weight, 0.0);
    assert!(file.warnings.iter().any(|w| w.contains("xform 0: weight -2")), "{:?}", file.warnings);
    // NaN centre and scale: the defaults, warned.
    let file = read(&flame(r#"center="nan 3" scale="NaN""#, XF));
    assert_eq!((file.flames[0].center, file.flames[0].scale), ([0.0, 3.0], 50.0));
    assert_eq!(file.warnings.iter().filter(|w| w.contains("the default is used")).count(), 2, "{:?}", file.warnings);
    // Sizes and quality past the limits.
    let e = read_err(&flame(r#"size="100000 100""#, XF));
    assert!(e.starts_with("t.flame:1:14: flame #0: attribute size:") && e.contains("16384"), "{e}");
    assert!(read_err(&flame(r#"size="0 10""#, XF)).contains("attribute size"));
    assert!(read_err(&flame(r#"quality="1e9""#, XF)).contains("samples per pixel"));
    assert!(read_err(&flame(r#"quality="1000" zoom="20""#, XF)).contains("samples per pixel"));
    assert!(read_err(&flame(r#"supersample="1000""#, XF)).contains("supersample"));
    // Numbers that are not.
    assert!(read_err(&flame(r#"scale="big""#, XF)).contains("attribute scale: 'big' is not a number"));
    assert!(read_err(&flame("", r#"<xform weight="1" linear="x"/>"#)).contains("attribute linear"));
    // Palette entries out of range: clamped, warned; bad indices left out.
    let file =
        read(&flame("", &format!("{XF}<color index=\"3\" rgb=\"300 -5 10\"/><color index=\"300\" rgb=\"1 1 1\"/>")));
    assert_eq!(file.flames[0].palette[3], [1.0, 0.0, 10.0 / 255.0, 1.0]);
    assert!(file.warnings.iter().any(|w| w.contains("2 palette channel values")), "{:?}", file.warnings);
    assert!(file.warnings.iter().any(|w| w.contains("(300)")), "{:?}", file.warnings);
    // Hex data: short is warned (the rest interpolated), garbage is an error.
    let file = read(&flame("", &format!("{XF}<colors count=\"4\" data=\"00ff0000\"/>")));
    assert!(file.warnings.iter().any(|w| w.contains("fewer colours")), "{:?}", file.warnings);
    assert!(
        read_err(&flame("", &format!("{XF}<palette count=\"1\" format=\"RGB\">xyzxyz</palette>")))
            .contains("hexadecimal")
    );
    // Two final xforms.
    assert!(
        read_err(&flame("", &format!("{XF}<finalxform linear=\"1\"/><finalxform linear=\"1\"/>")))
            .contains("more than one")
    );
}

#[test]
fn ten_thousand_xforms() {
    let xform = |i: usize| {
        let chaos = if i.is_multiple_of(100) { r#" chaos="1 0""# } else { "" };
        format!("<xform weight=\"1\" color=\"{}\" linear=\"0.5\"{chaos}/>\n", i % 2)
    };
    let body: String = (0..10_000).map(xform).collect();
    let file = read(&flame(r#"name="big""#, &body));
    let f = &file.flames[0];
    assert_eq!(f.xforms.len(), 10_000);
    assert_eq!((f.xforms[9_900].chaos.len(), f.xforms[9_900].chaos[1]), (10_000, 0.0));
    assert!(f.xforms[9_999].chaos.is_empty());
    // A xaos row on every one of them would be 10⁸ entries: refused, not allocated.
    let body: String = (0..10_000).map(|_| r#"<xform weight="1" linear="1" chaos="0"/>"#).collect();
    assert!(read_err(&flame("", &body)).contains("xaos rows"));
}

#[test]
fn huge_files_are_refused_before_reading() {
    let dir = common::temp_dir("flame-reader-huge");
    let path = dir.join("huge.flame");
    // A sparse file: no disk is written, and the reader must not read it.
    std::fs::File::create(&path).unwrap().set_len(1 << 30).unwrap();
    let e = read_file(&path).unwrap_err();
    assert!(matches!(e, FlameError::TooLarge { size_bytes, .. } if size_bytes == 1 << 30));
    let shown = e.to_string();
    assert!(shown.contains("huge.flame") && shown.contains(&MAX_FILE_BYTES.to_string()), "{shown}");
    let e = read_file(&dir.join("absent.flame")).unwrap_err().to_string();
    assert!(e.starts_with("cannot read ") && e.contains("absent.flame"), "{e}");
}

#[test]
fn truncated_and_garbled_inputs_never_panic() {
    let good = format!(
        "<?xml version=\"1.0\"?>\n<flames>\n{}</flames>\n",
        flame(
            r#"name="g" size="64 48" center="0.1 0.2" scale="20" palette_mode="linear""#,
            &format!(
                "{XF}<xform weight=\"0.5\" spherical=\"1\" chaos=\"1 0.5\" post=\"1 0 0 1 0.1 0\"/><finalxform swirl=\"1\"/><symmetry kind=\"-3\"/><color index=\"0\" rgb=\"1 2 3\"/><palette count=\"2\" format=\"RGB\">ff00ff00ff00</palette>"
            )
        )
    );
    read(&good);
    let dir = common::temp_dir("flame-reader-garbled");
    let opts = options(&dir);
    // Every prefix, and one byte replaced by each of a few troublemakers at every position.
    for n in 0..good.len() {
        let _ = read_str_with(&good[..n], "t.flame", &opts);
    }
    let bytes = good.as_bytes();
    for (i, bad) in ["<", ">", "\"", "-", "9", "é", "\u{0}", "&"].iter().cycle().take(bytes.len()).enumerate() {
        let garbled = format!("{}{bad}{}", &good[..i], &good[i + 1..]);
        if let Err(e) = read_str_with(&garbled, "t.flame", &opts) {
            assert!(e.to_string().starts_with("t.flame"), "{e}");
        }
    }
}

#[test]
fn info_lists_the_flames_and_exits_2_for_a_bad_file() {
    let dir = common::temp_dir("flame-reader-info");
    let good = dir.join("two.flame");
    let body = format!(
        "{XF}<xform weight=\"1\" spherical=\"1\" zork=\"1\"/><finalxform swirl=\"1\"/><color index=\"0\" rgb=\"255 0 0\"/>"
    );
    std::fs::write(&good, format!("{}{}", flame(r#"name="first" size="64 32""#, &body), flame("", XF))).unwrap();
    let out = common::run_nlifs(&["info", good.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains(": 2 flames"), "{stdout}");
    let first = stdout.lines().find(|l| l.contains("first")).unwrap_or_else(|| panic!("{stdout}"));
    for part in ["64×32", " 2 ", "yes", "<color> ×1", "linear spherical swirl"] {
        assert!(first.contains(part), "{part:?} missing in {first:?}");
    }
    assert!(stdout.contains("warning: ") && stdout.contains("zork"), "{stdout}");

    let out = common::run_nlifs(&["info", "--json", good.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["flames"][0]["xforms"], 2);
    assert_eq!(v["flames"][0]["final_xform"], true);
    assert_eq!(v["flames"][1]["size"], serde_json::json!([100, 100]));
    assert!(v["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("zork")));

    // A bad flame file, recognised by its content though its name ends .xml: exit 2, the
    // file and position in the message.
    let bad = dir.join("bad.xml");
    std::fs::write(&bad, "<flame>\n<xform weight=\"1\" coefs=\"1 2\"/>\n</flame>\n").unwrap();
    let out = common::run_nlifs(&["info", bad.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("bad.xml:2:26: flame #0: xform 0: attribute coefs"), "{stderr}");
}
