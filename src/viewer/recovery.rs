//! Crash recovery: while a scene has unsaved edits the viewer writes it every few seconds to a
//! recovery file, and the next start on the same scene offers to restore it. The file lives in
//! `$XDG_STATE_HOME/nlifs/recovery/` (else `~/.local/state/nlifs/recovery/`), named after the
//! scene's file name and a hash of its absolute path (the built-in scene has its own name), so
//! two scenes never share one. A clean save or a discard removes it.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use crate::scene::Scene;

/// Seconds between two writes of the recovery file while there are unsaved edits.
pub const AUTOSAVE_SECS: f64 = 3.0;

/// The folder recovery files go to, from the environment; None when neither
/// `XDG_STATE_HOME` nor `HOME` is set.
pub fn recovery_dir() -> Option<PathBuf> {
    let state = std::env::var_os("XDG_STATE_HOME").filter(|v| !v.is_empty()).map(PathBuf::from).or_else(|| {
        std::env::var_os("HOME").filter(|v| !v.is_empty()).map(|h| PathBuf::from(h).join(".local/state"))
    })?;
    Some(state.join("nlifs").join("recovery"))
}

/// The recovery file in `dir` for the scene at `scene_path` (None: the built-in scene).
pub fn recovery_path(dir: &Path, scene_path: Option<&Path>) -> PathBuf {
    let Some(path) = scene_path else { return dir.join("built-in.toml") };
    let absolute = std::fs::canonicalize(path)
        .or_else(|_| std::env::current_dir().map(|d| d.join(path)))
        .unwrap_or_else(|_| path.to_path_buf());
    let stem: String = path
        .file_stem()
        .map(|s| s.to_string_lossy().chars().map(|c| if c.is_alphanumeric() || c == '-' { c } else { '_' }).collect())
        .unwrap_or_else(|| "scene".into());
    dir.join(format!("{stem}-{:016x}.toml", fnv1a(absolute.to_string_lossy().as_bytes())))
}

/// 64-bit FNV-1a: a stable hash (the standard library's may change between releases, and the
/// file must be found again by the next version).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// Writes `scene` to the recovery file `path` (atomically, creating its folder).
pub fn write(path: &Path, scene: &Scene) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    scene.save(path)
}

/// The scene in the recovery file `path` and when it was written; None when there is none or
/// it does not read (a half-written or foreign file is not worth an error at start-up).
pub fn read(path: &Path) -> Option<(Scene, SystemTime)> {
    let text = std::fs::read_to_string(path).ok()?;
    let scene = Scene::parse(&text, &path.display().to_string()).ok()?;
    let written = std::fs::metadata(path).and_then(|m| m.modified()).unwrap_or(SystemTime::UNIX_EPOCH);
    Some((scene, written))
}

/// Removes the recovery file `path` if it exists.
pub fn remove(path: &Path) {
    let _ = std::fs::remove_file(path);
}
