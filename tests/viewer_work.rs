//! Work is never lost in the viewer, tested on its plain state: Esc never quits (it closes a
//! dialog, an overlay, or cancels a point drag, putting the point back); closing with unsaved
//! edits asks Save / Discard / Cancel; the title marks unsaved edits; unsaved edits go to a
//! recovery file that the next start offers back; a file that changes on disk under unsaved
//! edits is not reloaded over them; `nlifs view missing.toml` exits 2 with the located error.

mod common;

use std::path::{Path, PathBuf};

use nlifs::live::LiveSettings;
use nlifs::scene::Scene;
use nlifs::viewer::command::{CloseChoice, Command};
use nlifs::viewer::recovery;
use nlifs::viewer::state::ViewerState;

/// A copy of a paper scene in a fresh folder (tests write next to it), with a recovery folder.
fn scratch(name: &str, scene: &str) -> (common::TempDir, PathBuf, PathBuf) {
    let dir = common::temp_dir(&format!("viewer-work-{name}"));
    let path = dir.join(format!("{scene}.toml"));
    std::fs::copy(common::scene_path(scene), &path).unwrap();
    let state = dir.join("state");
    (dir, path, state)
}

fn open(path: &Path, recovery_dir: &Path) -> ViewerState {
    let mut s = ViewerState::new(Scene::load(path).unwrap(), Some(path.to_path_buf()), LiveSettings::default());
    s.apply([Command::SetRecoveryDir(Some(recovery_dir.to_path_buf()))]);
    s
}

/// An edit: the first function switched on or off.
fn edit(s: &mut ViewerState) {
    let enabled = !s.scene.functions[0].enabled;
    s.apply([Command::SetFunctionEnabled { function: 0, enabled }]);
}

#[test]
fn the_title_marks_unsaved_edits_and_saving_clears_it() {
    let (_dir, path, rec) = scratch("title", "plant1");
    let mut s = open(&path, &rec);
    assert!(!s.modified());
    let name = s.scene.name.clone();
    assert_eq!(s.window_title(), format!("{name} — nlifs"));
    edit(&mut s);
    assert!(s.modified());
    assert_eq!(s.window_title(), format!("{name}* — nlifs"));
    // Undo back to the file: not modified.
    s.apply([Command::SetFunctionEnabled { function: 0, enabled: true }]);
    assert!(!s.modified());
    edit(&mut s);
    s.apply([Command::SaveScene(path.clone())]);
    assert!(!s.modified(), "{:?}", s.error);
    assert_eq!(s.window_title(), format!("{name} — nlifs"));
    assert!(!Scene::load(&path).unwrap().functions[0].enabled);
    assert!(s.ui.toast.as_deref().is_some_and(|t| t.contains("saved")), "a toast says where it saved");
}

#[test]
fn escape_never_quits_and_cancels_a_point_drag() {
    let (_dir, path, rec) = scratch("escape", "plant1");
    let mut s = open(&path, &rec);
    edit(&mut s);
    // With unsaved edits and nothing open, Esc does nothing at all.
    let scene = s.scene.clone();
    s.apply([Command::Escape]);
    assert!(!s.ui.quit && !s.ui.close_dialog);
    assert_eq!(s.scene, scene);
    // It closes the shortcuts overlay.
    s.apply([Command::SetShortcutsShown(true), Command::Escape]);
    assert!(!s.ui.shortcuts_shown && !s.ui.quit);
    // It cancels a point drag: the point goes back, nothing to undo from it.
    s.apply([Command::SetGridOverlay(true)]);
    let before = s.scene.clone();
    let undo_before = s.history.can_undo();
    s.apply([Command::BeginPointDrag { function: 3, point: 2 }, Command::DragPoint { delta_px: [-40.0, 25.0] }]);
    assert_ne!(s.scene, before, "the drag moved the point");
    let changes = s.apply([Command::Escape]);
    assert!(changes.scene_edited);
    assert_eq!(s.scene, before, "Esc put the point back");
    assert!(s.edit.gesture.is_none());
    // The release that follows records nothing.
    s.apply([Command::EndGesture]);
    assert_eq!(s.history.can_undo(), undo_before);
    assert!(!s.ui.quit);
}

#[test]
fn closing_with_unsaved_edits_asks_save_discard_or_cancel() {
    let (_dir, path, rec) = scratch("close", "plant1");
    // Without edits: closes at once.
    let mut s = open(&path, &rec);
    s.apply([Command::RequestClose]);
    assert!(s.ui.quit && !s.ui.close_dialog);

    // Cancel (and Esc) keep the window and the edits.
    let mut s = open(&path, &rec);
    edit(&mut s);
    s.apply([Command::RequestClose]);
    assert!(s.ui.close_dialog && !s.ui.quit);
    s.apply([Command::CloseDialog(CloseChoice::Cancel)]);
    assert!(!s.ui.close_dialog && !s.ui.quit && s.modified());
    s.apply([Command::RequestClose, Command::Escape]);
    assert!(!s.ui.close_dialog && !s.ui.quit && s.modified());

    // Discard closes and leaves the file alone.
    s.apply([Command::RequestClose, Command::CloseDialog(CloseChoice::Discard)]);
    assert!(s.ui.quit);
    assert!(Scene::load(&path).unwrap().functions[0].enabled);

    // Save writes the file, then closes.
    let mut s = open(&path, &rec);
    edit(&mut s);
    s.apply([Command::RequestClose, Command::CloseDialog(CloseChoice::Save)]);
    assert!(s.ui.quit, "{:?}", s.error);
    assert!(!Scene::load(&path).unwrap().functions[0].enabled);
    assert!(!s.modified());

    // A save that fails keeps the window open with the dialog and the error.
    let mut s = open(&path, &rec);
    edit(&mut s);
    // Under a plain file: no folder can be made there, even by root.
    let blocked = path.with_extension("txt");
    std::fs::write(&blocked, "a file").unwrap();
    let target = blocked.join("scene.toml");
    s.apply([Command::SetSaveText(target.display().to_string()), Command::RequestClose]);
    s.apply([Command::CloseDialog(CloseChoice::Save)]);
    assert!(!s.ui.quit && s.ui.close_dialog && s.error.is_some(), "{:?} {:?}", s.ui, s.error);
}

#[test]
fn unsaved_edits_survive_a_kill_through_the_recovery_file() {
    let (_dir, path, rec) = scratch("recovery", "plant2");
    let mut s = open(&path, &rec);
    let file = s.recovery_file.clone().expect("a recovery file for the scene");
    assert!(file.starts_with(&rec));
    s.apply([Command::Autosave]);
    assert!(!file.exists(), "nothing to recover without edits");
    edit(&mut s);
    s.apply([Command::Autosave]);
    assert!(file.exists());
    let edited = s.scene.clone();
    // The process is killed here: nothing else runs. The next start offers the edits back.
    drop(s);
    let mut s = open(&path, &rec);
    assert!(s.recovery_offer.is_some());
    // Autosave does not touch a file whose offer is not answered.
    s.apply([Command::Autosave]);
    assert!(file.exists());
    s.apply([Command::Recover(true)]);
    assert_eq!(s.scene, edited);
    assert!(s.modified(), "restored edits are unsaved edits");
    // A clean save removes the recovery file.
    s.apply([Command::Autosave]);
    s.apply([Command::SaveScene(path.clone())]);
    assert!(!file.exists());
    assert!(open(&path, &rec).recovery_offer.is_none());

    // Discarding the offer removes the file too; so does discarding on close.
    let mut s = open(&path, &rec);
    edit(&mut s);
    s.apply([Command::Autosave]);
    let mut s = open(&path, &rec);
    s.apply([Command::Recover(false)]);
    assert!(!file.exists() && !s.modified());
    edit(&mut s);
    s.apply([Command::Autosave]);
    assert!(file.exists());
    s.apply([Command::RequestClose, Command::CloseDialog(CloseChoice::Discard)]);
    assert!(!file.exists());

    // Two scenes never share a recovery file.
    let other = recovery::recovery_path(&rec, Some(&common::scene_path("plant2")));
    assert_ne!(other, file);
}

#[test]
fn a_file_changed_on_disk_does_not_overwrite_unsaved_edits() {
    let (_dir, path, rec) = scratch("reload", "plant1");
    let mut s = open(&path, &rec);
    edit(&mut s);
    let edited = s.scene.clone();
    // Someone else writes the file (a later mtime).
    std::thread::sleep(std::time::Duration::from_millis(20));
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str("\n# touched\n");
    std::fs::write(&path, &text).unwrap();
    let t = std::time::SystemTime::now() + std::time::Duration::from_secs(2);
    std::fs::File::options().write(true).open(&path).unwrap().set_modified(t).unwrap();
    let command = s.poll_file().expect("the change is seen");
    assert_eq!(command, Command::FileChangedOnDisk);
    s.apply([command]);
    assert_eq!(s.scene, edited, "the edits are kept");
    assert!(s.ui.file_changed_on_disk);
    assert_eq!(s.poll_file(), None, "said once");
    // Reloading is the user's choice.
    s.apply([Command::ReloadScene]);
    assert!(!s.modified() && !s.ui.file_changed_on_disk);
    // Without edits a change reloads at once.
    std::fs::File::options()
        .write(true)
        .open(&path)
        .unwrap()
        .set_modified(t + std::time::Duration::from_secs(2))
        .unwrap();
    assert_eq!(s.poll_file(), Some(Command::ReloadScene));
}

#[test]
fn view_of_a_missing_scene_exits_2_with_the_located_error() {
    let out = common::run_nlifs(&["view", "missing-scene.toml"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("missing-scene.toml"), "{err}");
    let dir = common::temp_dir("viewer-work-bad");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "version = 1\n[grid]\nx = [0, 1]\ny = \"oops\"\n").unwrap();
    let out = common::run_nlifs(&["view", bad.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("bad.toml:4"), "{err}");
}

#[test]
fn opening_another_scene_over_unsaved_edits_asks_first() {
    let (_dir, path, rec) = scratch("open-over", "plant1");
    let other = common::scene_path("plant2");
    let mut s = open(&path, &rec);
    edit(&mut s);
    let edited = s.scene.clone();
    // Asked, not opened; Cancel (or Esc) keeps the edits.
    let changes = s.apply([Command::OpenScene(other.clone())]);
    assert!(!changes.scene_replaced && s.ui.close_dialog && s.scene == edited);
    s.apply([Command::CloseDialog(CloseChoice::Cancel)]);
    assert!(s.scene == edited && !s.ui.quit && s.ui.pending_open.is_none());
    // Discard opens the other scene, and does not quit.
    s.apply([Command::OpenScene(other.clone())]);
    let changes = s.apply([Command::CloseDialog(CloseChoice::Discard)]);
    assert!(changes.scene_replaced && !s.ui.quit);
    assert_eq!(s.scene_path.as_deref(), Some(other.as_path()));
    // Without edits it opens at once.
    let changes = s.apply([Command::OpenScene(path.clone())]);
    assert!(changes.scene_replaced && !s.ui.close_dialog);
}
