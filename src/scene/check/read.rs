//! Reading a scene file from disk: at most [`MAX_SCENE_BYTES`] (so that `/dev/zero` or a huge
//! file is refused instead of read until memory runs out), as UTF-8 with the line and column
//! of the first byte that is not, and the operating system's reason for a file that cannot be
//! opened given once. The text then goes to [`Scene::parse`].

use std::path::Path;

use crate::scene::{LoadError, Scene, SceneError};

use super::line_col;

/// The largest scene file read. The largest real scene is a 64×64×64 grid function written out,
/// about 20 MB; a file past this is not a scene, and reading it whole (`/dev/zero`) would not end.
const MAX_SCENE_BYTES: u64 = 64 << 20;

impl Scene {
    /// Reads and checks a scene file.
    pub fn load(path: &Path) -> Result<Self, LoadError> {
        Self::load_with_text(path).map(|(scene, _)| scene)
    }

    /// [`Scene::load`], with the file's text (what a save over the file edits,
    /// [`Scene::save_over`]). A flame file (`.flame`, `.flam3`) is read as the scene of its
    /// first flame (`flame_import.rs`), its text the scene's TOML; its warnings are not shown
    /// here (`flame_import::load_flame` gives them).
    pub fn load_with_text(path: &Path) -> Result<(Self, String), LoadError> {
        use std::io::Read;
        if crate::flame::xml::is_flame_path(path) {
            let scene = crate::scene::flame_import::load_flame(path, None, None)?.scene;
            let text = scene.to_toml();
            return Ok((scene, text));
        }
        let file = path.display().to_string();
        let io_error = |cause: std::io::Error| LoadError::Io { path: file.clone(), cause };
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes))
            .map_err(io_error)?;
        if bytes.len() as u64 > MAX_SCENE_BYTES {
            return Err(LoadError::TooLarge { path: file, limit_bytes: MAX_SCENE_BYTES });
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            let valid = e.utf8_error().valid_up_to();
            let bytes = e.as_bytes();
            // The valid prefix is text, so the line and column of the first bad byte are known.
            let prefix = std::str::from_utf8(&bytes[..valid]).unwrap_or_default();
            let (line, column) = line_col(prefix, valid);
            SceneError {
                file: file.clone(),
                line,
                column,
                field: None,
                message: format!(
                    "byte 0x{:02x} is not UTF-8 text; a scene file is UTF-8 (save it as such)",
                    bytes[valid]
                ),
            }
        })?;
        let mut scene = Self::parse(&text, &file)?;
        scene.path = Some(path.to_path_buf());
        Ok((scene, text))
    }
}
