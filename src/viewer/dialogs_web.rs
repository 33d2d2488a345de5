//! The browser's Open and Save As (the platform seam's twin of `dialogs.rs`, chosen in
//! `viewer/mod.rs`): Open clicks the page's file input, whose file comes back as
//! [`Command::OpenBytes`] through the page (`src/web/`); Save As answers at once with the file
//! name, and the save becomes a download (`io::write_atomic`). No thread, no native dialog.

use std::path::PathBuf;

use super::command::{Command, FileDialogKind, FileDialogRequest};

/// The page offers its own dialogs (a file input, downloads).
pub fn native_dialogs_available() -> bool {
    true
}

/// The answer to give at the next poll.
#[derive(Default)]
pub struct Dialogs {
    answer: Option<Command>,
}

impl Dialogs {
    /// Opens the page's file chooser (Open) or names the download (Save As).
    pub fn start(&mut self, request: FileDialogRequest, _window: &winit::window::Window) -> Result<(), String> {
        let kind = request.kind;
        let path = match kind {
            FileDialogKind::Open => {
                crate::platform::web::click(crate::platform::web::FILE_INPUT_ID)
                    .map_err(|e| format!("cannot show the file chooser: {e}"))?;
                // The chosen file arrives on its own (OpenBytes), or nothing on cancel.
                None
            }
            FileDialogKind::SaveAs => {
                Some(PathBuf::from(request.file_name.unwrap_or_else(|| "nlifs-scene.toml".into())))
            }
        };
        self.answer = Some(Command::FileDialogDone { kind, path });
        Ok(())
    }

    /// An answer is waiting.
    pub fn pending(&self) -> bool {
        self.answer.is_some()
    }

    /// The answer, once.
    pub fn poll(&mut self) -> Option<Command> {
        self.answer.take()
    }
}
