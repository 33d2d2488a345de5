//! Saving over a scene's own file changes only what was edited, in the viewer's plain state
//! (commands in, file out, no window and no GPU): every shipped scene, saved after one edit,
//! differs from its file in the edited lines only (comments, order, `4_000_000` and unset
//! defaults kept) and reads back as the edited scene; an added function is one new table with
//! the rest of the file byte-identical, a deleted one takes only its table; a dragged point is
//! written with the fewest digits; a key edited on a timeline changes its line only; a value
//! keeps the comment next to it; a file that is not a scene is written in full.

mod common;

use std::path::{Path, PathBuf};

use glam::DVec3;
use nlifs::live::LiveSettings;
use nlifs::model::builder::Step;
use nlifs::scene::Scene;
use nlifs::scene::spec::FunctionDef;
use nlifs::viewer::command::Command;
use nlifs::viewer::state::ViewerState;

/// Every scene in `scenes/`, by name.
fn shipped_scenes() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(common::repo_path("scenes"))
        .unwrap()
        .filter_map(|e| {
            let path = e.unwrap().path();
            (path.extension()? == "toml").then(|| path.file_stem().unwrap().to_string_lossy().into_owned())
        })
        .collect();
    names.sort();
    assert!(names.len() >= 10, "scenes/ holds the paper scenes: {names:?}");
    names
}

/// A copy of `scenes/<name>.toml` in a fresh folder (kept while the returned guard lives), and
/// its text.
fn copy_of(name: &str, test: &str) -> (common::TempDir, PathBuf, String) {
    let dir = common::temp_dir(&format!("scene-save-{test}-{name}"));
    let path = dir.join(format!("{name}.toml"));
    std::fs::copy(common::scene_path(name), &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    (dir, path, text)
}

/// The viewer on `path`, as the event loop opens a file.
fn open(path: &Path) -> ViewerState {
    ViewerState::new(Scene::load(path).unwrap(), Some(path.to_path_buf()), LiveSettings::default())
}

/// Saves through the viewer (Ctrl+S) and returns the file's text; the file reads back as the
/// viewer's scene.
fn save(s: &mut ViewerState, path: &Path) -> String {
    s.apply([Command::EndGesture, Command::Save]);
    assert!(s.error.is_none(), "{:?}", s.error);
    assert!(!s.modified(), "the save wrote the scene");
    let reloaded = Scene::load(path).unwrap_or_else(|e| panic!("the saved file reads: {e}"));
    assert_eq!(reloaded, s.scene, "the saved file reads back as the edited scene");
    std::fs::read_to_string(path).unwrap()
}

/// The lines only `before` has and the lines only `after` has, by a longest common
/// subsequence of lines.
fn line_diff(before: &str, after: &str) -> (Vec<String>, Vec<String>) {
    let a: Vec<&str> = before.lines().collect();
    let b: Vec<&str> = after.lines().collect();
    let mut lcs = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for i in (0..a.len()).rev() {
        for j in (0..b.len()).rev() {
            lcs[i][j] = if a[i] == b[j] { lcs[i + 1][j + 1] + 1 } else { lcs[i + 1][j].max(lcs[i][j + 1]) };
        }
    }
    let (mut removed, mut added) = (Vec::new(), Vec::new());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        if i < a.len() && j < b.len() && a[i] == b[j] {
            i += 1;
            j += 1;
        } else if j == b.len() || (i < a.len() && lcs[i + 1][j] >= lcs[i][j + 1]) {
            removed.push(a[i].to_string());
            i += 1;
        } else {
            added.push(b[j].to_string());
            j += 1;
        }
    }
    (removed, added)
}

/// `text` without its bytes `from..to`.
fn without(text: &str, from: usize, to: usize) -> String {
    format!("{}{}", &text[..from], &text[to..])
}

#[test]
fn every_shipped_scene_saved_after_one_edit_differs_in_the_edited_line_only() {
    for name in shipped_scenes() {
        // Switching the first function off: one line added to its table.
        let (_dir, path, original) = copy_of(&name, "enabled");
        let mut s = open(&path);
        let enabled = s.scene.functions[0].enabled;
        s.apply([Command::SetFunctionEnabled { function: 0, enabled: !enabled }]);
        let saved = save(&mut s, &path);
        let (removed, added) = line_diff(&original, &saved);
        assert!(enabled, "{name}: the shipped scenes start with every function on");
        assert_eq!((removed, added), (vec![], vec!["enabled = false".to_string()]), "{name}:\n{saved}");
        // Where the line went: in the first function's table, before the second table.
        let at = saved.find("enabled = false").unwrap();
        assert_eq!(saved[..at].matches("[[function]]").count(), 1, "{name}: in function 1's table");
        // Every comment, and every number as the file spells it, stays.
        for line in original.lines().filter(|l| l.trim_start().starts_with('#') || l.contains("_000")) {
            assert!(saved.contains(line), "{name}: `{line}` is kept");
        }

        // A new colour for the first function: its colour line changes, or one is added.
        let (_dir, path, original) = copy_of(&name, "color");
        let mut s = open(&path);
        let color = [0x12, 0x34, 0x56].map(nlifs::color::srgb8_to_linear);
        s.apply([Command::SetFunctionColor { function: 0, color }]);
        let saved = save(&mut s, &path);
        let (removed, added) = line_diff(&original, &saved);
        assert_eq!(added, vec!["color = \"#123456\"".to_string()], "{name}:\n{saved}");
        assert!(removed.len() <= 1 && removed.iter().all(|l| l.starts_with("color = ")), "{name}: {removed:?}");
        // The edit goes again on the saved file: the second save starts from the first's text.
        s.apply([Command::SetFunctionColor {
            function: 0,
            color: [0x65, 0x43, 0x21].map(nlifs::color::srgb8_to_linear),
        }]);
        let again = save(&mut s, &path);
        assert_eq!(
            line_diff(&saved, &again),
            (vec!["color = \"#123456\"".to_string()], vec!["color = \"#654321\"".to_string()]),
            "{name}"
        );
    }
}

#[test]
fn an_added_function_is_one_new_table_after_the_others_and_the_rest_stays_byte_identical() {
    let (_dir, path, original) = copy_of("plant1", "add");
    let mut s = open(&path);
    s.apply([Command::AddFunction]);
    assert_eq!(s.scene.functions.len(), 6);
    let saved = save(&mut s, &path);
    // The new table: after the last function, before [render], the rest byte-identical.
    let from = saved.find("\n[[function]]\nname = \"f6\"").expect("a new function table");
    let to = saved.find("\n\n[render]").unwrap() + 1;
    assert!(from > saved.find("name = \"f5\"").unwrap() && from < to, "{saved}");
    let table = &saved[from..to];
    assert_eq!(table.matches("[[function]]").count(), 1, "one table:\n{table}");
    assert!(table.contains("kind = \"affine\"") && !table.lines().any(|l| l.starts_with('#')), "{table}");
    assert_eq!(without(&saved, from, to), original, "the rest of the file is byte-identical");
    // Ten comment lines and `4_000_000` untouched.
    assert_eq!(saved.lines().filter(|l| l.starts_with('#')).count(), 10);
    assert!(saved.contains("points = 4_000_000"));
}

#[test]
fn a_deleted_function_takes_only_its_table() {
    let (_dir, path, original) = copy_of("plant1", "delete");
    let mut s = open(&path);
    s.apply([Command::DeleteFunction(1)]);
    let saved = save(&mut s, &path);
    let from = original.find("\n[[function]]\nname = \"f2\"").unwrap();
    let to = original.find("\n[[function]]\nname = \"f3\"").unwrap();
    assert_eq!(saved, without(&original, from, to), "only f2's table is gone");

    // On a timeline, the keys' entries for the function go too. Its functions have no colour
    // lines (each takes the palette colour of its place): the two that move up keep theirs,
    // written out, and nothing else is added.
    let (_dir, path, original) = copy_of("twist-anim", "delete");
    let mut s = open(&path);
    let colors: Vec<String> = s.scene.functions[2..]
        .iter()
        .map(|f| format!("color = \"{}\"", nlifs::color::hex_text(f.color.map(nlifs::color::linear_to_srgb8))))
        .collect();
    s.apply([Command::DeleteFunction(1)]);
    let saved = save(&mut s, &path);
    let (removed, added) = line_diff(&original, &saved);
    assert_eq!(added, colors);
    assert!(!saved.contains("\"f2\"") && !removed.iter().any(|l| l.starts_with('#')), "{removed:?}");
}

/// The significant digits of each number in `line`.
fn digit_counts(line: &str) -> Vec<usize> {
    line.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
        .filter(|w| w.chars().any(|c| c.is_ascii_digit()))
        .map(|w| w.split('e').next().unwrap().chars().filter(char::is_ascii_digit).count())
        .collect()
}

#[test]
fn a_dragged_point_is_written_with_the_fewest_digits_and_its_line_only_changes() {
    let (_dir, path, original) = copy_of("plant1", "drag");
    let mut s = open(&path);
    s.apply([Command::SetGridOverlay(true), Command::BeginPointDrag { function: 3, point: 2 }]);
    s.apply([Command::DragPoint { delta_px: [-37.0, 23.0] }, Command::EndGesture]);
    let saved = save(&mut s, &path);
    let (removed, added) = line_diff(&original, &saved);
    assert_eq!(removed, vec!["  [38.53, 4.14, -26.74],".to_string()]);
    assert_eq!(added.len(), 1, "{added:?}");
    // Shortest f32 decimals: at most 9 significant digits (an f32 widened to f64 and written
    // as such takes 16 or 17).
    let counts = digit_counts(&added[0]);
    assert_eq!(counts.len(), 3, "{}", added[0]);
    assert!(counts.iter().all(|&n| n <= 9), "{} has long numbers", added[0]);
    let FunctionDef::Grid { points } = &s.scene.functions[3].def else { panic!() };
    let p = points[2];
    for v in p.to_array() {
        assert_eq!((v as f32).to_string().parse::<f64>().unwrap(), v, "the model holds the short value");
    }

    // Along one axis: the other two coordinates keep their spelling.
    let (_dir, path, original) = copy_of("plant1", "drag-axis");
    let mut s = open(&path);
    s.apply([Command::SetGridOverlay(true), Command::SetAxisLock(Some(1))]);
    s.apply([Command::BeginPointDrag { function: 3, point: 2 }, Command::DragPoint { delta_px: [5.0, -31.0] }]);
    let saved = save(&mut s, &path);
    let (removed, added) = line_diff(&original, &saved);
    assert_eq!(removed, vec!["  [38.53, 4.14, -26.74],".to_string()]);
    assert_eq!(added.len(), 1);
    assert!(added[0].starts_with("  [38.53, ") && added[0].ends_with(", -26.74],"), "{}", added[0]);
    assert!(digit_counts(&added[0]).iter().all(|&n| n <= 9), "{}", added[0]);
}

#[test]
fn a_key_edited_on_a_timeline_changes_its_line_only() {
    // A builder step edited at the key at 2 s: that key's step line.
    let (_dir, path, original) = copy_of("twist-anim", "key-step");
    let mut s = open(&path);
    s.apply([Command::SetTime(2.0)]);
    let FunctionDef::Builder { builder, .. } = s.scene.function_def_at(0, 2.0) else { panic!() };
    let Step::Twist { axis, along, range, center, .. } = builder.steps[0] else { panic!() };
    let value = Step::Twist { axis, along, degrees: 95.5, range, center };
    s.apply([Command::SetBuilderStep { function: 0, step: 0, value }, Command::EndGesture]);
    let saved = save(&mut s, &path);
    let (removed, added) = line_diff(&original, &saved);
    assert_eq!(removed, vec!["  { op = \"twist\", axis = \"y\", degrees = 120 },".to_string()], "{saved}");
    assert_eq!(added, vec!["  { op = \"twist\", axis = \"y\", degrees = 95.5 },".to_string()]);
    assert!(saved.find("degrees = 95.5").unwrap() > saved.find("t_secs = 2.0").unwrap(), "in the key at 2 s");

    // A key moved in time: its time line.
    let (_dir, path, original) = copy_of("twist-anim", "key-time");
    let mut s = open(&path);
    s.apply([Command::MoveKey { key: 1, t_secs: 1.25 }, Command::EndGesture]);
    let saved = save(&mut s, &path);
    assert_eq!(line_diff(&original, &saved), (vec!["t_secs = 1.0".to_string()], vec!["t_secs = 1.25".to_string()]));
}

#[test]
fn a_changed_value_keeps_its_comment_and_grouped_digits_stay_grouped() {
    let text = "# A scene.\nversion = 1\nname = \"s\" # its name\n\n[grid]\nx = [0, 1]\ny = [0, 1]\n\n\
                [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]] # halves\noffset = [0, 0]\n\n\
                [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]\n\n\
                [render]\npoints = 1_000_000 # a million\n";
    let mut scene = Scene::parse(text, "s.toml").unwrap();
    scene.name = "t".into();
    scene.render.points = 2_500_000;
    let FunctionDef::Affine(a) = &mut scene.functions[0].def else { panic!() };
    a.matrix.x_axis.x = 0.25;
    let out = scene.to_toml_over(text);
    assert_eq!(Scene::parse(&out, "s.toml").unwrap(), scene);
    let (removed, added) = line_diff(text, &out);
    assert_eq!(
        removed,
        ["name = \"s\" # its name", "matrix = [[0.5, 0], [0, 0.5]] # halves", "points = 1_000_000 # a million"]
    );
    assert_eq!(
        added,
        ["name = \"t\" # its name", "matrix = [[0.25, 0], [0, 0.5]] # halves", "points = 2_500_000 # a million"]
    );
    // Unnamed functions (named by their place) keep no name line until their place changes.
    scene.functions.remove(0);
    let out = scene.to_toml_over(text);
    assert_eq!(Scene::parse(&out, "s.toml").unwrap(), scene);
    assert!(out.contains("name = \"f2\""), "the second function keeps its name f2 in first place:\n{out}");
}

#[test]
fn text_that_is_not_a_scene_gives_the_full_writer() {
    let scene = common::load_scene("sierpinski");
    assert_eq!(scene.to_toml_over("this is = not [a scene"), scene.to_toml());
    assert_eq!(scene.to_toml_over(""), scene.to_toml());
}

#[test]
fn a_scene_without_a_file_saves_in_full() {
    let dir = common::temp_dir("scene-save-built-in");
    let path = dir.join("new.toml");
    let mut s = ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default());
    s.apply([Command::SetPoint { function: 0, point: 0, p: DVec3::new(-2.0, -20.0, -0.1) }, Command::EndGesture]);
    s.apply([Command::SaveScene(path.clone())]);
    assert!(s.error.is_none(), "{:?}", s.error);
    assert_eq!(std::fs::read_to_string(&path).unwrap(), s.scene.to_toml());
}
