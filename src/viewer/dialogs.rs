//! Native Open and Save As dialogs (`rfd`), shown off the event loop's thread so that the view
//! keeps drawing while one is open: [`Dialogs::start`] hands the dialog to a thread, and
//! [`Dialogs::poll`] turns its answer into a [`Command::FileDialogDone`] once per frame.
//!
//! On Linux `rfd` asks the desktop portal over D-Bus and falls back to zenity; where neither can
//! answer (a bare X server, a container) it returns "nothing chosen", which cannot be told from
//! a cancel. So [`native_dialogs_available`] checks for them first, and the viewer then offers
//! its own path fields instead (`files.rs`). `NLIFS_NO_FILE_DIALOG=1` forces that.

use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, TryRecvError};

use super::command::{Command, FileDialogKind, FileDialogRequest};

/// Whether a native file dialog can be shown here.
pub fn native_dialogs_available() -> bool {
    if std::env::var_os("NLIFS_NO_FILE_DIALOG").is_some_and(|v| !v.is_empty() && v != "0") {
        return false;
    }
    if cfg!(any(target_os = "windows", target_os = "macos")) {
        return true;
    }
    // The portal lives on the session bus; zenity needs only the display.
    std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some_and(|v| !v.is_empty()) || on_path("zenity")
}

/// Whether an executable `name` is in a folder of `PATH`.
fn on_path(name: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(name).is_file()))
}

/// The dialog in progress, if any.
#[derive(Default)]
pub struct Dialogs {
    pending: Option<(FileDialogKind, Receiver<Option<PathBuf>>)>,
}

impl Dialogs {
    /// Shows the dialog `request` asks for, over `window`, on a thread of its own. An error
    /// (no thread) is said as a finished dialog that chose nothing, with the reason.
    pub fn start(&mut self, request: FileDialogRequest, window: &winit::window::Window) -> Result<(), String> {
        let mut dialog = rfd::FileDialog::new().set_parent(window);
        dialog = match request.kind {
            FileDialogKind::Open => dialog
                .set_title("Open a scene")
                .add_filter("nlifs scenes and images", &["toml", "png"])
                .add_filter("all files", &["*"]),
            FileDialogKind::SaveAs => dialog.set_title("Save the scene as").add_filter("nlifs scene", &["toml"]),
        };
        if let Some(dir) = &request.directory {
            dialog = dialog.set_directory(dir);
        }
        if let Some(name) = &request.file_name {
            dialog = dialog.set_file_name(name);
        }
        let (send, receive) = mpsc::channel();
        let kind = request.kind;
        std::thread::Builder::new()
            .name("nlifs-file-dialog".into())
            .spawn(move || {
                let chosen = match kind {
                    FileDialogKind::Open => dialog.pick_file(),
                    FileDialogKind::SaveAs => dialog.save_file(),
                };
                // The viewer may have closed meanwhile: nobody to tell.
                let _ = send.send(chosen);
            })
            .map_err(|e| format!("cannot show a file dialog: {e}"))?;
        self.pending = Some((kind, receive));
        Ok(())
    }

    /// A dialog is open (its answer is polled for).
    pub fn pending(&self) -> bool {
        self.pending.is_some()
    }

    /// The dialog's answer, once it has one.
    pub fn poll(&mut self) -> Option<Command> {
        let (kind, receive) = self.pending.as_ref()?;
        let path = match receive.try_recv() {
            Ok(path) => path,
            Err(TryRecvError::Empty) => return None,
            // The thread ended without answering (it panicked inside the dialog library).
            Err(TryRecvError::Disconnected) => None,
        };
        let kind = *kind;
        self.pending = None;
        Some(Command::FileDialogDone { kind, path })
    }
}
