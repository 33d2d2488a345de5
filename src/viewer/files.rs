//! Opening and saving files in the viewer, as state and command logic: Save (Ctrl+S), the
//! Open and Save As dialogs (requested here, shown by `dialogs.rs` off the event loop's thread,
//! answered by [`Command::FileDialogDone`]), files dropped onto the window or picked from the
//! recent files, and the recent files list (`recent.rs`).
//!
//! A file that cannot be opened (a scene with an error, located as file:line:col; a PNG without
//! a scene inside; any other kind of file) leaves the current scene in place and shows the
//! error over the view (`FilesState::view_error`, in `files_state.rs`), as a reload that fails does. Opening over
//! unsaved edits asks Save / Discard / Cancel first, as closing does.

use std::path::{Path, PathBuf};

use super::apply::Changes;
use super::command::{Command, FileDialogKind, FileDialogRequest};
use super::recent::{self, RecentFiles};
use super::state::{PendingOpen, ViewerState};

/// Says what to do where no native dialog can be shown.
pub fn no_dialog_notice(kind: FileDialogKind) -> String {
    let what = match kind {
        FileDialogKind::Open => "type the file's path in the Scene section and press Open (or drop the file here)",
        FileDialogKind::SaveAs => "type the new file's path in the Scene section and press Save as",
    };
    format!("No file dialog can be shown here (no desktop portal, no zenity): {what}.")
}

impl ViewerState {
    /// Applies the file commands (see [`Command::Save`] and those after it).
    pub(super) fn file_command(&mut self, command: Command, changes: &mut Changes) {
        match command {
            Command::Save => {
                if self.scene_path.is_none() && self.files.native_dialogs {
                    self.show_file_dialog(FileDialogKind::SaveAs, changes);
                } else {
                    let path = PathBuf::from(self.edit.save_text.trim());
                    self.save_scene(&path);
                }
            }
            Command::ShowFileDialog(kind) => self.show_file_dialog(kind, changes),
            Command::FileDialogDone { kind, path } => {
                self.files.dialog_open = false;
                match (kind, path) {
                    // The browser's file chooser answers with the file's bytes (OpenBytes), or
                    // not at all when cancelled (`dialogs_web.rs`).
                    (FileDialogKind::Open, None) if !crate::platform::DESKTOP => {}
                    (_, None) => {
                        self.message =
                            Some("no file chosen (if no dialog appeared, type the path in the Scene section)".into())
                    }
                    (FileDialogKind::Open, Some(path)) => self.open_file(&path, changes),
                    (FileDialogKind::SaveAs, Some(path)) => {
                        // A name typed without an extension gets the scene's.
                        let path = if path.extension().is_none() { path.with_extension("toml") } else { path };
                        self.save_scene(&path);
                    }
                }
            }
            Command::OpenFile(path) => self.open_file(&path, changes),
            Command::OpenBytes { name, bytes } => self.open_bytes(&name, &bytes, changes),
            Command::SetConfigDir(dir) => {
                self.files.recent = dir.as_deref().map(RecentFiles::load).unwrap_or_default();
                self.files.config_dir = dir;
                if self.files.recent.prune_missing() {
                    self.save_recent();
                }
            }
            Command::SetToolSupport { native_dialogs, ffmpeg } => {
                self.files.native_dialogs = native_dialogs;
                self.files.ffmpeg = ffmpeg;
            }
            Command::DismissViewError => self.files.view_error = None,
            _ => {}
        }
    }

    /// Asks the event loop for a native dialog, or says how to do without one.
    pub(super) fn show_file_dialog(&mut self, kind: FileDialogKind, changes: &mut Changes) {
        if self.files.dialog_open {
            self.message = Some("a file dialog is already open".into());
            return;
        }
        if !self.files.native_dialogs {
            let notice = no_dialog_notice(kind);
            self.message = Some(notice.clone());
            self.ui.toast = Some(notice);
            self.ui.panel_shown = true;
            return;
        }
        // The scene's folder, or the folder of the image whose scene is open.
        let directory = self
            .scene_path
            .as_deref()
            .or(self.files.opened_image.as_deref())
            .map(recent::absolute)
            .and_then(|p| p.parent().map(Path::to_path_buf))
            .or_else(|| std::env::current_dir().ok());
        let file_name = (kind == FileDialogKind::SaveAs).then(|| {
            let beside_image = self.files.opened_image.as_deref().map(scene_path_beside);
            self.scene_path.as_ref().or(beside_image.as_ref()).and_then(|p| p.file_name()).map_or_else(
                || format!("{}.toml", file_stem_for(&self.scene.name)),
                |n| n.to_string_lossy().into_owned(),
            )
        });
        self.files.dialog_open = true;
        changes.file_dialog = Some(FileDialogRequest { kind, directory, file_name });
    }

    /// Opens a scene file, a flame file, or the scene inside a PNG that nlifs wrote; anything
    /// else, or a file that does not read, is an error over the view and the scene stays.
    pub(super) fn open_file(&mut self, path: &Path, changes: &mut Changes) {
        if !path.is_file() {
            let what = if path.exists() { "is not a file" } else { "does not exist" };
            let pruned = if self.files.recent.remove(path) {
                self.save_recent();
                " (removed from the recent files)"
            } else {
                ""
            };
            self.set_view_error(format!("cannot open {}: it {what}{pruned}", path.display()));
            return;
        }
        if crate::output::png::is_png(path) {
            let origin = format!("{} (embedded scene)", path.display());
            match crate::output::png::scene_from_png(path).and_then(|p| Ok((p.scene(&origin)?, p.scene_toml))) {
                Ok((scene, text)) => self.request_open(
                    PendingOpen::Image { png: path.to_path_buf(), scene: Box::new(scene), text },
                    changes,
                ),
                Err(e) => self.set_view_error(e.to_string()),
            }
        } else if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"))
            || crate::flame::xml::is_flame_path(path)
        {
            // A scene file, or a flame file (opened as its imported scene).
            self.request_open(PendingOpen::File(path.to_path_buf()), changes);
        } else {
            self.set_view_error(format!(
                "cannot open {}: not a scene file (.toml), a flame file (.flame) or a PNG that nlifs wrote",
                path.display()
            ));
        }
    }

    /// Opens a file's contents (the browser's file input and drops): a scene's TOML or a PNG
    /// that nlifs wrote. Errors are located in `name` and shown over the view, the scene stays.
    /// There is no path: a save afterwards asks for a name.
    pub(super) fn open_bytes(&mut self, name: &str, bytes: &[u8], changes: &mut Changes) {
        let opened = if crate::output::png::is_png_bytes(bytes) {
            let origin = format!("{name} (embedded scene)");
            crate::output::png::scene_from_png_bytes(bytes, Path::new(name))
                .and_then(|p| Ok((p.scene(&origin)?, p.scene_toml)))
                .map_err(|e| e.to_string())
        } else {
            match std::str::from_utf8(bytes) {
                Ok(text) => crate::scene::Scene::parse(text, name)
                    .map(|scene| (scene, text.to_string()))
                    .map_err(|e| e.to_string()),
                Err(e) => {
                    Err(format!("cannot open {name}: not a scene file (TOML text) or a PNG that nlifs wrote ({e})"))
                }
            }
        };
        match opened {
            Ok((scene, text)) => {
                self.request_open(PendingOpen::Read { name: name.to_string(), scene: Box::new(scene), text }, changes)
            }
            Err(e) => self.set_view_error(e),
        }
    }

    /// Opens a scene now, or, over unsaved edits, once the Save / Discard / Cancel dialog is
    /// answered ([`Self::open_pending`]).
    pub(super) fn request_open(&mut self, open: PendingOpen, changes: &mut Changes) {
        if self.modified() {
            self.end_gesture();
            self.ui.close_dialog = true;
            self.ui.pending_open = Some(open);
        } else {
            self.open_pending(open, changes);
        }
    }

    /// Opens what [`Self::request_open`] was asked for, edits or not.
    pub(super) fn open_pending(&mut self, open: PendingOpen, changes: &mut Changes) {
        match open {
            PendingOpen::File(path) => self.open_scene(&path, changes),
            PendingOpen::Read { name, scene, text } => {
                self.install_scene(*scene, text, None);
                self.show_opened(changes);
                // Save (a download in the browser) keeps the file's name; a PNG's scene is
                // saved as TOML.
                if let Some(file_name) = Path::new(&name).with_extension("toml").file_name() {
                    self.edit.save_text = file_name.to_string_lossy().into_owned();
                }
                self.message = Some(format!("opened {name}"));
                self.files.opened_name = Some(name);
            }
            PendingOpen::Image { png, scene, text } => {
                self.install_scene(*scene, text, None);
                self.show_opened(changes);
                self.edit.save_text = scene_path_beside(&png).display().to_string();
                self.message = Some(format!(
                    "opened the scene inside {}; Save asks where to write it (the image stays as it is)",
                    png.display()
                ));
                self.files.opened_name = Some(png.display().to_string());
                self.remember_recent(&png);
                self.files.opened_image = Some(png);
                self.check_recovery();
            }
        }
    }

    /// An error over the view (and in the panel).
    pub(super) fn set_view_error(&mut self, error: String) {
        self.error = Some(error.clone());
        self.files.view_error = Some(error);
    }

    /// Puts `path` first in the recent files and writes the list.
    pub(super) fn remember_recent(&mut self, path: &Path) {
        self.files.recent.prune_missing();
        self.files.recent.push(path);
        self.save_recent();
    }

    fn save_recent(&self) {
        if let Some(dir) = &self.files.config_dir
            && let Err(e) = self.files.recent.save(dir)
        {
            log::warn!("cannot write the recent files list in {}: {e}", dir.display());
        }
    }
}

/// Where the scene inside `png` is saved by default: `STEM.toml` beside the image, or
/// `STEM-2.toml`, `STEM-3.toml`, … where that name is taken (the image may sit beside the
/// scene it was rendered from).
fn scene_path_beside(png: &Path) -> PathBuf {
    let stem = png.file_stem().map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
    (1..)
        .map(|n| {
            if n == 1 {
                png.with_file_name(format!("{stem}.toml"))
            } else {
                png.with_file_name(format!("{stem}-{n}.toml"))
            }
        })
        .find(|p| !p.exists())
        .unwrap_or_else(|| png.with_extension("toml"))
}

/// A file name stem for a scene's name: letters, digits, `-` and `_`; `scene` when none is left.
fn file_stem_for(name: &str) -> String {
    let stem: String =
        name.trim().chars().map(|c| if c.is_alphanumeric() || c == '-' || c == '_' { c } else { '-' }).collect();
    let stem = stem.trim_matches('-');
    if stem.is_empty() { "scene".into() } else { stem.to_string() }
}
