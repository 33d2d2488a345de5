//! Files in the viewer, tested on its plain state: the recent files list (newest first, no
//! duplicates, at most ten, missing files pruned, kept in the config folder a test chooses, a
//! broken list ignored); files dropped onto the window (a scene opens; a PNG that nlifs wrote
//! opens its scene; a broken scene, a PNG without a scene or any other file is an error over the
//! view, located as file:line:col for scene text, and the scene shown stays; unsaved edits ask
//! first); a reload that fails says so over the view; the Open and Save As dialogs, and what
//! the viewer says where no dialog can be shown.

mod common;

use std::path::{Path, PathBuf};

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::{CloseChoice, Command, FileDialogKind, FileDialogRequest};
use nlifs::viewer::recent::{MAX_RECENT, RECENT_FILE, RecentFiles};
use nlifs::viewer::state::{PendingOpen, ViewerState};

/// A fresh folder with copies of paper scenes and a config folder of its own.
struct Scratch {
    dir: common::TempDir,
    config: PathBuf,
}

impl Scratch {
    fn new(name: &str) -> Self {
        let dir = common::temp_dir(&format!("viewer-files-{name}"));
        let config = dir.join("config");
        Self { dir, config }
    }

    fn scene(&self, name: &str) -> PathBuf {
        let path = self.dir.join(format!("{name}.toml"));
        std::fs::copy(common::scene_path(name), &path).unwrap();
        path
    }

    /// The viewer on `path`, its recent files in this folder's config folder.
    fn open(&self, path: &Path) -> ViewerState {
        let mut s = ViewerState::new(Scene::load(path).unwrap(), Some(path.to_path_buf()), LiveSettings::default());
        s.apply([Command::SetConfigDir(Some(self.config.clone()))]);
        s
    }
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap()
}

#[test]
fn recent_files_are_newest_first_without_duplicates_and_at_most_ten() {
    let scratch = Scratch::new("recent");
    let paths: Vec<PathBuf> = (0..MAX_RECENT + 3)
        .map(|k| {
            let p = scratch.dir.join(format!("s{k}.toml"));
            std::fs::write(&p, "").unwrap();
            p
        })
        .collect();
    let mut recent = RecentFiles::default();
    for p in &paths {
        recent.push(p);
    }
    // Oracle: the last ten pushed, newest first.
    let expected: Vec<PathBuf> = paths.iter().rev().take(MAX_RECENT).map(|p| canonical(p)).collect();
    assert_eq!(recent.paths, expected);
    // Pushing one again moves it to the front, once; a relative way to the same file is the
    // same entry.
    let again = scratch.dir.join(".").join("s5.toml");
    recent.push(&again);
    assert_eq!(recent.paths[0], canonical(&paths[5]));
    assert_eq!(recent.paths.iter().filter(|p| **p == canonical(&paths[5])).count(), 1);
    assert_eq!(recent.paths.len(), MAX_RECENT);

    // Saved and read back; a file that went is pruned.
    recent.save(&scratch.config).unwrap();
    std::fs::remove_file(&paths[12]).unwrap();
    let mut back = RecentFiles::load(&scratch.config);
    assert_eq!(back, recent);
    assert!(back.prune_missing());
    assert!(!back.paths.contains(&paths[12]) && back.paths.len() == MAX_RECENT - 1);
}

#[test]
fn a_broken_recent_list_is_ignored_and_rewritten_on_the_next_open() {
    let scratch = Scratch::new("broken-recent");
    std::fs::create_dir_all(&scratch.config).unwrap();
    let list = scratch.config.join(RECENT_FILE);
    std::fs::write(&list, "files = [unterminated").unwrap();
    let plant1 = scratch.scene("plant1");
    let mut s = scratch.open(&plant1);
    assert!(s.files.recent.paths.is_empty(), "{:?}", s.files.recent);
    assert!(s.error.is_none(), "a broken list is no error for the user: {:?}", s.error);
    let plant2 = scratch.scene("plant2");
    s.apply([Command::OpenFile(plant2.clone())]);
    assert_eq!(RecentFiles::load(&scratch.config).paths, vec![canonical(&plant2)]);
    // No temporary file is left beside it (written atomically).
    let names: Vec<_> = std::fs::read_dir(&scratch.config).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, vec![std::ffi::OsString::from(RECENT_FILE)]);
}

#[test]
fn opening_and_saving_fill_the_recent_list_and_a_missing_one_is_pruned() {
    let scratch = Scratch::new("recent-viewer");
    let (plant1, plant2, sierpinski) = (scratch.scene("plant1"), scratch.scene("plant2"), scratch.scene("sierpinski"));
    let mut s = scratch.open(&plant1);
    s.apply([Command::OpenFile(plant2.clone())]);
    s.apply([Command::OpenScene(sierpinski.clone())]);
    let copy = scratch.dir.join("copy.toml");
    s.apply([Command::SaveScene(copy.clone())]);
    let expected = vec![canonical(&copy), canonical(&sierpinski), canonical(&plant2)];
    assert_eq!(s.files.recent.paths, expected);
    // A new viewer reads the same list (what the File menu shows).
    let fresh = scratch.open(&plant1);
    assert_eq!(fresh.files.recent.paths, expected);

    // A recent file that was deleted: picking it says so over the view, drops it, keeps the scene.
    std::fs::remove_file(&plant2).unwrap();
    let mut s = fresh;
    let scene = s.scene.clone();
    s.apply([Command::OpenFile(expected[2].clone())]);
    assert_eq!(s.scene, scene);
    let error = s.files.view_error.clone().expect("an error over the view");
    assert!(error.contains("does not exist") && error.contains("removed from the recent files"), "{error}");
    assert_eq!(RecentFiles::load(&scratch.config).paths, expected[..2].to_vec());
    // Esc dismisses it.
    s.apply([Command::Escape]);
    assert!(s.files.view_error.is_none());
}

#[test]
fn a_dropped_scene_opens_and_a_broken_one_is_an_error_over_the_view_with_its_location() {
    let scratch = Scratch::new("drop-scene");
    let plant1 = scratch.scene("plant1");
    let mut s = scratch.open(&plant1);
    let sierpinski = scratch.scene("sierpinski");
    let changes = s.apply([Command::OpenFile(sierpinski.clone())]);
    assert!(changes.scene_replaced);
    assert_eq!(s.scene_path.as_deref(), Some(sierpinski.as_path()));
    assert_eq!(s.scene, Scene::load(&sierpinski).unwrap());

    // A scene with a TOML error on line 4: the error over the view names file:line:col.
    let broken = scratch.dir.join("broken.toml");
    std::fs::write(&broken, "version = 1\nname = \"broken\"\n[grid]\nx = = 1\n").unwrap();
    let kept = s.scene.clone();
    let changes = s.apply([Command::OpenFile(broken.clone())]);
    assert!(!changes.scene_replaced);
    assert_eq!(s.scene, kept, "the scene shown stays");
    assert_eq!(s.scene_path.as_deref(), Some(sierpinski.as_path()));
    let error = s.files.view_error.clone().expect("an error over the view");
    let located = format!("{}:4:", broken.display());
    assert!(error.starts_with(&located), "{error:?} is not located as {located}<column>");
    // Opening a good one clears it.
    s.apply([Command::OpenFile(plant1.clone())]);
    assert!(s.files.view_error.is_none());

    // A flame file opens as its imported scene (as `nlifs view FILE.flame`), saved beside it as
    // TOML, never over it.
    let flame = scratch.dir.join("waves-popcorn.flame");
    std::fs::copy(common::repo_path("docs/gallery/flames/waves-popcorn.flame"), &flame).unwrap();
    let changes = s.apply([Command::OpenFile(flame.clone())]);
    assert!(changes.scene_replaced, "{:?}", s.files.view_error);
    assert_eq!(s.scene.name, "waves-popcorn");
    assert_eq!(s.edit.save_text, flame.with_extension("toml").display().to_string());

    // Any other kind of file: an error, the scene stays.
    let text = scratch.dir.join("notes.txt");
    std::fs::write(&text, "hello").unwrap();
    let kept = s.scene.clone();
    s.apply([Command::OpenFile(text.clone())]);
    assert_eq!(s.scene, kept);
    let error = s.files.view_error.clone().unwrap();
    assert!(error.contains("notes.txt") && error.contains("not a scene file"), "{error}");
    s.apply([Command::DismissViewError]);
    assert!(s.files.view_error.is_none());
}

#[test]
fn a_dropped_png_that_nlifs_wrote_opens_its_scene_and_another_png_is_an_error() {
    let scratch = Scratch::new("drop-png");
    let plant1 = scratch.scene("plant1");
    let mut s = scratch.open(&plant1);
    let recovery_dir = scratch.dir.join("recovery");
    s.apply([Command::SetRecoveryDir(Some(recovery_dir.clone()))]);
    // A PNG with sierpinski's scene inside, as every image nlifs writes carries it.
    let scene = common::load_scene("sierpinski");
    let png = scratch.dir.join("sierpinski-shot.png");
    let image = image::RgbImage::from_pixel(8, 6, image::Rgb([10, 20, 30]));
    let provenance = nlifs::output::Provenance::for_command(&scene, 0.0, "test", serde_json::json!({}));
    nlifs::output::png::save_rgb8(&png, &image, Some(&provenance)).unwrap();
    let changes = s.apply([Command::OpenFile(png.clone())]);
    assert!(changes.scene_replaced, "{:?}", s.files.view_error);
    assert_eq!(s.scene.functions, scene.functions);
    assert_eq!(s.scene.name, scene.name);
    // The scene has no path, so that a save never writes over the image (nor anywhere the
    // user did not choose); the PNG is what the recent files remember, and a save goes beside
    // it by default, to a name not taken: here sierpinski-shot.toml is (the scene it came from,
    // say), so sierpinski-shot-2.toml.
    assert_eq!(s.scene_path, None);
    assert_eq!(s.files.recent.paths[0], canonical(&png));
    assert_eq!(s.files.opened_name.as_deref(), Some(png.display().to_string().as_str()));
    assert_eq!(s.edit.save_text, scratch.dir.join("sierpinski-shot.toml").display().to_string());
    std::fs::write(scratch.dir.join("sierpinski-shot.toml"), "# another scene\n").unwrap();
    s.apply([Command::OpenFile(png.clone())]);
    assert_eq!(s.edit.save_text, scratch.dir.join("sierpinski-shot-2.toml").display().to_string());
    // Edits to it are kept in a recovery file of the image's own (not the scene opened before).
    assert_eq!(s.recovery_file, Some(nlifs::viewer::recovery::recovery_path(&recovery_dir, Some(&png))));
    // Without a native dialog (as here) Save writes that file; the image keeps its bytes.
    let image_bytes = std::fs::read(&png).unwrap();
    s.apply([Command::Save]);
    let saved = scratch.dir.join("sierpinski-shot-2.toml");
    assert_eq!(s.scene_path.as_deref(), Some(saved.as_path()), "{:?}", s.error);
    assert_eq!(nlifs::scene::Scene::load(&saved).unwrap().functions, scene.functions);
    assert_eq!(std::fs::read(&png).unwrap(), image_bytes);
    assert_eq!(std::fs::read_to_string(scratch.dir.join("sierpinski-shot.toml")).unwrap(), "# another scene\n");
    // The same image as bytes (the browser's way): its scene opens, to be saved as TOML.
    let changes =
        s.apply([Command::OpenBytes { name: "sierpinski-shot.png".into(), bytes: std::fs::read(&png).unwrap() }]);
    assert!(changes.scene_replaced, "{:?}", s.files.view_error);
    assert_eq!(s.scene.functions, scene.functions);
    assert_eq!(s.edit.save_text, "sierpinski-shot.toml");
    assert_eq!(s.files.opened_name.as_deref(), Some("sierpinski-shot.png"));

    // A PNG without a scene: an error over the view, the scene stays.
    let plain = scratch.dir.join("plain.png");
    image.save(&plain).unwrap();
    let kept = s.scene.clone();
    let changes = s.apply([Command::OpenFile(plain.clone())]);
    assert!(!changes.scene_replaced);
    assert_eq!(s.scene, kept);
    let error = s.files.view_error.clone().unwrap();
    assert!(error.contains("plain.png") && error.contains("no embedded scene"), "{error}");
}

#[test]
fn a_drop_over_unsaved_edits_asks_first() {
    let scratch = Scratch::new("drop-modified");
    let plant1 = scratch.scene("plant1");
    let plant2 = scratch.scene("plant2");
    let mut s = scratch.open(&plant1);
    s.apply([Command::SetFunctionEnabled { function: 0, enabled: false }]);
    let edited = s.scene.clone();
    let changes = s.apply([Command::OpenFile(plant2.clone())]);
    assert!(!changes.scene_replaced);
    assert!(s.ui.close_dialog);
    assert_eq!(s.ui.pending_open, Some(PendingOpen::File(plant2.clone())));
    // Cancel: the edits stay.
    s.apply([Command::CloseDialog(CloseChoice::Cancel)]);
    assert_eq!(s.scene, edited);
    assert!(s.ui.pending_open.is_none());
    // Discard: the dropped scene opens.
    s.apply([Command::OpenFile(plant2.clone())]);
    let changes = s.apply([Command::CloseDialog(CloseChoice::Discard)]);
    assert!(changes.scene_replaced);
    assert_eq!(s.scene_path.as_deref(), Some(plant2.as_path()));
}

/// The browser's way in (its file chooser and drops send the file's bytes): the same question
/// over unsaved edits, and a file that does not read is an error without one.
#[test]
fn bytes_opened_over_unsaved_edits_ask_first_and_bad_bytes_are_an_error_at_once() {
    let scratch = Scratch::new("bytes-modified");
    let plant1 = scratch.scene("plant1");
    let mut s = scratch.open(&plant1);
    let plant2_text = std::fs::read_to_string(common::scene_path("plant2")).unwrap();
    let open_plant2 = || Command::OpenBytes { name: "plant2.toml".into(), bytes: plant2_text.as_bytes().to_vec() };
    s.apply([Command::SetFunctionEnabled { function: 0, enabled: false }]);
    let edited = s.scene.clone();

    let changes = s.apply([open_plant2()]);
    assert!(!changes.scene_replaced);
    assert!(s.ui.close_dialog);
    assert!(matches!(&s.ui.pending_open, Some(open @ PendingOpen::Read { .. }) if open.name() == "plant2.toml"));
    // Cancel: the edits stay.
    s.apply([Command::CloseDialog(CloseChoice::Cancel)]);
    assert_eq!(s.scene, edited);
    assert!(s.ui.pending_open.is_none() && !s.ui.close_dialog);

    // A file that does not read: its error, no question, the edits stay.
    let bad = "name = \"bad\"\n[grid]\nnx = \"three\"\n";
    s.apply([Command::OpenBytes { name: "bad.toml".into(), bytes: bad.as_bytes().to_vec() }]);
    assert!(!s.ui.close_dialog && s.ui.pending_open.is_none());
    assert_eq!(s.scene, edited);
    let error = s.files.view_error.clone().expect("the bad file's error over the view");
    assert!(error.contains("bad.toml:"), "{error}");

    // Discard: the file opens, the edits are gone.
    s.apply([open_plant2()]);
    let changes = s.apply([Command::CloseDialog(CloseChoice::Discard)]);
    assert!(changes.scene_replaced);
    assert_eq!(s.scene, Scene::parse(&plant2_text, "plant2.toml").unwrap());
    assert!(!s.modified());
    assert_eq!(s.message.as_deref(), Some("opened plant2.toml"));
    // Its name stays: in the Scene section and as Save's file (a download in the browser).
    assert_eq!(s.files.opened_name.as_deref(), Some("plant2.toml"));
    assert_eq!(s.edit.save_text, "plant2.toml");
    // Unedited, bytes open at once.
    let changes = s.apply([Command::OpenBytes { name: "plant1.toml".into(), bytes: std::fs::read(&plant1).unwrap() }]);
    assert!(changes.scene_replaced && !s.ui.close_dialog);
}

#[test]
fn a_reload_that_fails_is_an_error_over_the_view_until_the_file_is_fixed() {
    let scratch = Scratch::new("reload");
    let path = scratch.scene("plant1");
    let mut s = scratch.open(&path);
    let kept = s.scene.clone();
    let good = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, good.replacen("[grid]", "[grid\n", 1)).unwrap();
    s.apply([Command::ReloadScene]);
    assert_eq!(s.scene, kept);
    let error = s.files.view_error.clone().expect("an error over the view");
    assert!(error.starts_with(&format!("{}:", path.display())), "{error}");
    std::fs::write(&path, &good).unwrap();
    s.apply([Command::ReloadScene]);
    assert!(s.files.view_error.is_none(), "{:?}", s.files.view_error);
}

#[test]
fn without_a_native_dialog_the_viewer_says_to_use_its_path_fields() {
    let scratch = Scratch::new("no-dialog");
    let path = scratch.scene("plant1");
    let mut s = scratch.open(&path);
    s.apply([Command::SetToolSupport { native_dialogs: false, ffmpeg: false }, Command::SetPanelShown(false)]);
    for kind in [FileDialogKind::Open, FileDialogKind::SaveAs] {
        let changes = s.apply([Command::ShowFileDialog(kind)]);
        assert_eq!(changes.file_dialog, None);
        let toast = s.ui.toast.clone().expect("a notice over the view");
        assert!(toast.contains("No file dialog can be shown here") && toast.contains("Scene section"), "{toast}");
        assert!(s.ui.panel_shown, "the panel with the path fields is shown");
        assert!(!s.files.dialog_open);
    }
    // Ctrl+S on the built-in scene then saves to the save field's file.
    let mut built_in = ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default());
    let target = scratch.dir.join("from-built-in.toml");
    built_in.apply([Command::SetSaveText(target.display().to_string())]);
    let changes = built_in.apply([Command::Save]);
    assert_eq!(changes.file_dialog, None);
    assert_eq!(built_in.scene_path.as_deref(), Some(target.as_path()), "{:?}", built_in.error);
}

#[test]
fn the_dialogs_ask_the_event_loop_and_their_answers_open_and_save() {
    let scratch = Scratch::new("dialogs");
    let path = scratch.scene("plant1");
    let mut s = scratch.open(&path);
    s.apply([Command::SetToolSupport { native_dialogs: true, ffmpeg: false }]);
    let changes = s.apply([Command::ShowFileDialog(FileDialogKind::SaveAs)]);
    assert_eq!(
        changes.file_dialog,
        Some(FileDialogRequest {
            kind: FileDialogKind::SaveAs,
            directory: Some(canonical(&scratch.dir)),
            file_name: Some("plant1.toml".into()),
        })
    );
    // One at a time.
    assert!(s.apply([Command::ShowFileDialog(FileDialogKind::Open)]).file_dialog.is_none());
    // Save As without an extension: the scene's; it becomes the scene's file.
    s.apply([Command::SetFunctionEnabled { function: 0, enabled: false }]);
    let chosen = scratch.dir.join("saved-as");
    s.apply([Command::FileDialogDone { kind: FileDialogKind::SaveAs, path: Some(chosen.clone()) }]);
    let saved = chosen.with_extension("toml");
    assert_eq!(s.scene_path.as_deref(), Some(saved.as_path()), "{:?}", s.error);
    assert!(!s.modified());
    assert!(!Scene::load(&saved).unwrap().functions[0].enabled);
    assert!(s.ui.toast.as_deref().is_some_and(|t| t.contains("saved-as.toml")), "{:?}", s.ui.toast);
    // The title names the new file (the scene keeps its name).
    assert_eq!(s.window_title(), "plant1 (saved-as.toml) — nlifs");
    assert!(!s.files.dialog_open);

    // Open: the answer opens like a drop; a cancel changes nothing.
    let plant2 = scratch.scene("plant2");
    assert!(s.apply([Command::ShowFileDialog(FileDialogKind::Open)]).file_dialog.is_some());
    let scene = s.scene.clone();
    let changes = s.apply([Command::FileDialogDone { kind: FileDialogKind::Open, path: None }]);
    assert!(!changes.scene_replaced && s.scene == scene && !s.files.dialog_open);
    s.apply([Command::ShowFileDialog(FileDialogKind::Open)]);
    let changes = s.apply([Command::FileDialogDone { kind: FileDialogKind::Open, path: Some(plant2.clone()) }]);
    assert!(changes.scene_replaced);
    assert_eq!(s.scene_path.as_deref(), Some(plant2.as_path()));

    // The Open button with no path typed shows the dialog, edits or not (no question about
    // opening nothing).
    s.apply([Command::SetFunctionEnabled { function: 0, enabled: false }]);
    let changes = s.apply([Command::OpenScene("".into())]);
    assert_eq!(changes.file_dialog.map(|r| r.kind), Some(FileDialogKind::Open));
    assert!(!s.ui.close_dialog && s.ui.pending_open.is_none());
    s.apply([Command::FileDialogDone { kind: FileDialogKind::Open, path: None }]);

    // Ctrl+S on a scene without a file asks where.
    let mut built_in = ViewerState::new(ViewerState::default_scene(), None, LiveSettings::default());
    built_in.apply([Command::SetToolSupport { native_dialogs: true, ffmpeg: false }]);
    let changes = built_in.apply([Command::Save]);
    assert_eq!(changes.file_dialog.map(|r| r.kind), Some(FileDialogKind::SaveAs));
}

#[test]
fn save_view_and_a_restored_recovery_file_say_so_in_a_toast() {
    let scratch = Scratch::new("toasts");
    let path = scratch.scene("plant1");
    let mut s = scratch.open(&path);
    s.apply([Command::Orbit { dx_px: 40.0, dy_px: 0.0 }, Command::SaveView]);
    assert!(s.ui.toast.as_deref().is_some_and(|t| t.contains("camera")), "{:?}", s.ui.toast);

    // Unsaved edits in a recovery file, offered and restored by a second viewer.
    let rec = scratch.dir.join("state");
    s.apply([Command::SetRecoveryDir(Some(rec.clone())), Command::Autosave]);
    let mut second = scratch.open(&path);
    second.apply([Command::SetRecoveryDir(Some(rec))]);
    assert!(second.recovery_offer.is_some());
    second.apply([Command::SetToast(None), Command::Recover(true)]);
    assert!(second.ui.toast.as_deref().is_some_and(|t| t.contains("restored")), "{:?}", second.ui.toast);
}
