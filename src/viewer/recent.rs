//! The recent files list: the last [`MAX_RECENT`] scene files the viewer opened or saved, newest
//! first, kept in `recent.toml` in the user's config folder (`$NLIFS_CONFIG_DIR`, else
//! `$XDG_CONFIG_HOME/nlifs`, else `~/.config/nlifs`). The file is written atomically; one that
//! does not read is ignored with a log warning (a recent list is not worth an error), and files
//! that no longer exist drop out of the list.

use std::path::{Path, PathBuf};

/// How many paths the list keeps.
pub const MAX_RECENT: usize = 10;

/// The list's file name in the config folder.
pub const RECENT_FILE: &str = "recent.toml";

/// The folder the viewer keeps its settings in, from the environment; None when none of
/// `NLIFS_CONFIG_DIR`, `XDG_CONFIG_HOME` and `HOME` is set. `NLIFS_CONFIG_DIR` is used as it
/// is (tests point it at a temporary folder so that they never touch the user's).
pub fn config_dir() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    var("NLIFS_CONFIG_DIR")
        .or_else(|| var("XDG_CONFIG_HOME").map(|d| d.join("nlifs")))
        .or_else(|| var("HOME").map(|h| h.join(".config").join("nlifs")))
}

/// The file's contents.
#[derive(Debug, Default, serde::Deserialize, serde::Serialize)]
struct RecentToml {
    #[serde(default)]
    files: Vec<String>,
}

/// The recent files, newest first, as absolute paths.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecentFiles {
    pub paths: Vec<PathBuf>,
}

impl RecentFiles {
    /// The list in `dir`; empty when there is none, or when it does not read (logged).
    pub fn load(dir: &Path) -> Self {
        let path = dir.join(RECENT_FILE);
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Self::default(),
            Err(e) => {
                log::warn!("ignoring the recent files list {}: {e}", path.display());
                return Self::default();
            }
        };
        match toml::from_str::<RecentToml>(&text) {
            Ok(t) => {
                let mut recent = Self::default();
                // Oldest first, so that each push puts a newer one in front.
                for p in t.files.iter().rev() {
                    recent.push(Path::new(p));
                }
                recent
            }
            Err(e) => {
                log::warn!("ignoring the recent files list {}: {e}", path.display());
                Self::default()
            }
        }
    }

    /// Writes the list to `dir` (atomically, creating the folder).
    pub fn save(&self, dir: &Path) -> std::io::Result<()> {
        let files = self.paths.iter().filter_map(|p| p.to_str().map(str::to_owned)).collect();
        let text = toml::to_string(&RecentToml { files }).map_err(std::io::Error::other)?;
        let text = format!("# The viewer's recent files, newest first (nlifs writes this file).\n{text}");
        crate::io::write_atomic(&dir.join(RECENT_FILE), |w| w.write_all(text.as_bytes()))
    }

    /// Puts `path` (made absolute) first, removing an earlier entry of it; keeps at most
    /// [`MAX_RECENT`]. A path that is not valid UTF-8 is left out (the file is TOML text).
    pub fn push(&mut self, path: &Path) {
        let path = absolute(path);
        if path.to_str().is_none() {
            return;
        }
        self.paths.retain(|p| *p != path);
        self.paths.insert(0, path);
        self.paths.truncate(MAX_RECENT);
    }

    /// Removes `path` from the list; true if it was there.
    pub fn remove(&mut self, path: &Path) -> bool {
        let path = absolute(path);
        let before = self.paths.len();
        self.paths.retain(|p| *p != path);
        self.paths.len() != before
    }

    /// Drops files that no longer exist; true if any did.
    pub fn prune_missing(&mut self) -> bool {
        let before = self.paths.len();
        self.paths.retain(|p| p.is_file());
        self.paths.len() != before
    }
}

/// `path` as an absolute path with `.` and `..` resolved where the file exists (so that one
/// file reached two ways is one entry).
pub fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).or_else(|_| std::path::absolute(path)).unwrap_or_else(|_| path.to_path_buf())
}
