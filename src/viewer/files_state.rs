//! The viewer's files as plain data (what `files.rs` changes and the panels read): the recent
//! files, the error shown over the view, what this machine offers for files (native dialogs,
//! ffmpeg), and the text of the scene's file that a save edits. Kept apart from `files.rs` so that the state imports no command logic.

use std::path::PathBuf;

use super::recent::RecentFiles;

/// Files, dialogs and what the machine offers for them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FilesState {
    /// Where the recent files list is kept (None: only in memory).
    pub config_dir: Option<PathBuf>,
    pub recent: RecentFiles,
    /// A file that did not open or reload, said over the view until dismissed or until a scene
    /// loads.
    pub view_error: Option<String>,
    /// Native file dialogs can be shown here (a desktop portal or zenity).
    pub native_dialogs: bool,
    /// ffmpeg runs here (the record form's video).
    pub ffmpeg: bool,
    /// A native dialog is open (one at a time).
    pub dialog_open: bool,
    /// The text of the scene's file as read or last written (None: the built-in scene): a save
    /// edits it, so that the file keeps its comments and spellings (`Scene::save_over`).
    pub scene_text: Option<String>,
    /// The name of the file the scene came from where it has no path (the browser's file
    /// chooser, a drop on the page, the page's address): said in the Scene section.
    pub opened_name: Option<String>,
    /// The image whose embedded scene is open (it has no path of its own): the Save As dialog
    /// starts in the image's folder.
    pub opened_image: Option<PathBuf>,
}
