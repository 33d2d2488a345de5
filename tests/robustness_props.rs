//! Property tests over the scene format and the command line: scene files whose numbers are
//! drawn at random, extremes included (NaN, ±inf, ±1e308, denormals, huge integers, text where
//! a number belongs), must either load or give a located error naming a field, and a scene
//! that loads must resolve, report and render a few points without a panic. Command lines with
//! random numbers must exit 0 or 2, never 101 (a panic) or 1. The case counts keep each
//! property to a few seconds in `cargo test --release`; `PROPTEST_CASES` raises them.

use proptest::prelude::*;
use proptest::test_runner::Config;

use nlifs::scene::Scene;

/// A TOML number (or, rarely, something else) for any numeric field.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-4.0f64..4.0).prop_map(|x| format!("{x:?}")),
        2 => (-2i64..70).prop_map(|x| x.to_string()),
        1 => prop::sample::select(vec![
            "nan", "inf", "-inf", "1e308", "-1e308", "1.7976931348623157e308", "5e-324", "-5e-324", "0", "-0.0",
            "1e39", "1e150", "1e151", "-1e300", "9223372036854775807", "-9223372036854775808", "1099511627777",
            "4294967296", "\"1\"", "true", "[1, 2]", "{ a = 1 }",
        ])
        .prop_map(str::to_string),
        1 => any::<f64>().prop_map(|x| format!("{x:?}")),
    ]
}

/// The usual range of field `i` of [`scene_text`] (low, high, whole numbers only).
const SANE: [(f64, f64, bool); 40] = [
    (-1.0, 0.0, false),
    (1.0, 2.0, false),
    (-1.0, 0.0, false),
    (1.0, 2.0, false), // grid x, y
    (2.0, 10.0, true),
    (2.0, 10.0, true),
    (0.0, 1.0, false), // resolution, probability
    (0.1, 0.9, false),
    (-90.0, 90.0, false),
    (-1.0, 0.9, false), // scale, degrees, amount
    (-0.6, 0.6, false),
    (-0.6, 0.6, false),
    (-0.6, 0.6, false),
    (-0.6, 0.6, false), // matrix
    (-0.5, 0.5, false),
    (-0.5, 0.5, false),
    (0.0, 1.0, false), // offset, probability
    (-360.0, 360.0, false),
    (-80.0, 80.0, false),
    (0.5, 10.0, false),
    (10.0, 120.0, false), // camera
    (1.0, 64.0, true),
    (1.0, 64.0, true),
    (1.0, 100_000.0, true), // width, height, points
    (-0.2, 0.2, false),
    (-0.2, 0.2, false),
    (-0.2, 0.2, false), // translate
    (0.0, 0.4, false),
    (0.6, 1.0, false),
    (0.0, 1000.0, true), // taper range, seed
    (-1.0, 0.0, false),
    (1.0, 2.0, false),
    (2.0, 6.0, true),
    (-0.6, 0.6, false), // z, resolution, matrix
    (0.0, 1.0, false),
    (0.0, 1.0, false),
    (1.0, 10.0, false), // depth cue, background, duration
    (0.0, 1.0, false),
    (-360.0, 360.0, false),
    (1.0, 100_000.0, true), // key time, yaw, points
];

/// One value per field: mostly in its usual range, so that most scenes load and go on to be
/// resolved and rendered, and about one field in thirty an extreme from [`number`], so that
/// each check is met alone as well as together.
fn numbers(n: usize) -> impl Strategy<Value = Vec<String>> {
    let fields: Vec<BoxedStrategy<String>> = SANE[..n]
        .iter()
        .map(|&(lo, hi, int)| {
            let sane = if int {
                (lo as i64..=hi as i64).prop_map(|x| x.to_string()).boxed()
            } else {
                (lo..hi).prop_map(|x| format!("{x:?}")).boxed()
            };
            prop_oneof![30 => sane, 1 => number()].boxed()
        })
        .collect();
    fields
}

/// A scene using every numeric field of the format, with the numbers `v` (in order).
fn scene_text(v: &[String], three_d: bool) -> String {
    let z = if three_d { format!("z = [{}, {}]\n", v[30], v[31]) } else { String::new() };
    let (pt, res) = if three_d {
        (format!("[{}, {}, {}]", v[24], v[25], v[26]), format!("[{}, {}, {}]", v[4], v[5], v[32]))
    } else {
        (format!("[{}, {}]", v[24], v[25]), format!("[{}, {}]", v[4], v[5]))
    };
    let matrix = if three_d {
        format!("[[{}, 0, 0], [0, {}, 0], [0, 0, {}]]", v[10], v[13], v[33])
    } else {
        format!("[[{}, {}], [{}, {}]]", v[10], v[11], v[12], v[13])
    };
    let offset = if three_d { format!("[{}, {}, 0]", v[14], v[15]) } else { format!("[{}, {}]", v[14], v[15]) };
    format!(
        "version = 1\n[grid]\nx = [{}, {}]\ny = [{}, {}]\n{z}\
[[function]]\nname = \"b\"\nkind = \"builder\"\nresolution = {res}\nprobability = {}\n\
steps = [{{ op = \"scale\", by = {} }}, {{ op = \"rotate\", axis = \"z\", degrees = {} }}, \
{{ op = \"taper\", axis = \"y\", amount = {}, range = [{}, {}] }}, {{ op = \"translate\", by = {pt} }}]\n\
[[function]]\nname = \"a\"\nkind = \"affine\"\nmatrix = {matrix}\noffset = {offset}\nprobability = {}\n\
[camera]\nyaw_deg = {}\npitch_deg = {}\ndistance = {}\nfov_y_deg = {}\n\
[render]\nwidth = {}\nheight = {}\npoints = {}\nseed = {}\ndepth_cue = {}\nbackground = [{}, 0.5, 0.5]\n\
[timeline]\nduration_secs = {}\n[[key]]\nt_secs = {}\n[key.camera]\nyaw_deg = {}\n[key.render]\npoints = {}\n",
        v[0],
        v[1],
        v[2],
        v[3],
        v[6],
        v[7],
        v[8],
        v[9],
        v[27],
        v[28],
        v[16],
        v[17],
        v[18],
        v[19],
        v[20],
        v[21],
        v[22],
        v[23],
        v[29],
        v[34],
        v[35],
        v[36],
        v[37],
        v[38],
        v[39],
    )
}

/// Loads `text`; a scene that loads is resolved, reported and rendered with a few points.
fn load_or_locate(text: &str) -> Result<(), TestCaseError> {
    match Scene::parse(text, "p.toml") {
        Err(e) => {
            prop_assert!(e.line >= 1 && e.column >= 1, "{e}");
            let shown = e.to_string();
            prop_assert!(shown.starts_with("p.toml:"), "{shown}");
            // Either the checker named the field, or the parser's message points at the text.
            prop_assert!(e.field.is_some() || !e.message.is_empty(), "{shown}");
            for word in ["Toml", "untagged", "f64", "i64"] {
                prop_assert!(!shown.contains(word), "`{word}` in {shown}");
            }
        }
        Ok(scene) => {
            let ifs = scene.at(0.0);
            let report = ifs.report();
            for p in ifs.probabilities() {
                prop_assert!(p.is_finite() && p >= 0.0, "{:?}", report);
            }
            let mut settings = scene.render_at(0.0);
            settings.width = settings.width.min(16);
            settings.height = settings.height.min(16);
            settings.points = 2000;
            if let Ok(shot) = nlifs::shot::Shot::prepare(&scene, 0.0, &settings, nlifs::shot::Framing::Fit, None) {
                let _ = nlifs::render::render_cpu(&shot, &|_, _| {});
            }
            let _ = nlifs::scene::warnings::scene_warnings(&scene, 0.0);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(Config { cases: 300, failure_persistence: None, ..Config::default() })]

    #[test]
    fn scene_numbers_load_or_give_a_located_error(v in numbers(40), three_d in any::<bool>()) {
        load_or_locate(&scene_text(&v, three_d))?;
    }

    #[test]
    fn scene_text_mutations_never_panic(v in numbers(40), cut in 0usize..2000, byte in any::<u8>()) {
        // The same scenes with one byte replaced: broken syntax, keys and strings.
        let mut bytes = scene_text(&v, false).into_bytes();
        let at = cut % bytes.len();
        bytes[at] = byte;
        if let Ok(text) = String::from_utf8(bytes) {
            load_or_locate(&text)?;
        }
    }
}

/// One run of the command line; exit codes other than 0 and 2 fail the property.
fn exit_code(args: &[String]) -> i32 {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nlifs")).args(args).output().expect("nlifs runs");
    out.status.code().unwrap_or(-1)
}

proptest! {
    // Each case starts the program, so fewer cases than above.
    #![proptest_config(Config { cases: 40, failure_persistence: None, ..Config::default() })]

    #[test]
    fn cli_numbers_exit_0_or_2(time in number(), points in number(), stop in number(), width in number()) {
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("nlifs-props-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("s.toml");
        std::fs::write(&scene, "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n\
            [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n\
            [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]\n").unwrap();
        let s = scene.to_string_lossy().into_owned();
        let out = dir.join("o.png").to_string_lossy().into_owned();
        let unquote = |t: &str| t.trim_matches('"').to_string();
        let info = exit_code(&["info".into(), s.clone(), "--time".into(), unquote(&time)]);
        prop_assert!(info == 0 || info == 2, "info --time {time}: {info}");
        // Small images and point counts only where the number is small; else the range check.
        let points = if points.parse::<f64>().is_ok_and(|p| p > 5000.0) { format!("{points}000") } else { unquote(&points) };
        let render = exit_code(&[
            "render".into(), s.clone(), "-o".into(), out.clone(), "--width".into(), "8".into(),
            "--height".into(), "8".into(), "--points".into(), points.clone(), "--time".into(), unquote(&time),
        ]);
        prop_assert!(render == 0 || render == 2, "render --points {points} --time {time}: {render}");
        let width = if width.parse::<f64>().is_ok_and(|w| w > 32.0) { format!("{width}000") } else { unquote(&width) };
        let snapshot = exit_code(&[
            "snapshot".into(), s, "-o".into(), out, "--width".into(), width.clone(), "--height".into(), "8".into(),
            "--depth".into(), "2".into(), "--spp".into(), "1".into(), "--stop-pixels".into(), unquote(&stop),
        ]);
        prop_assert!(snapshot == 0 || snapshot == 2, "snapshot --width {width} --stop-pixels {stop}: {snapshot}");
    }
}
