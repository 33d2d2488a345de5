//! Applying the palette-colour commands (`ui/palette.rs`): a function's colour coordinate (a
//! slider: part of the running gesture, one undo step per drag), the colour mode and the
//! palette (one undo step each). Each is a whole-scene edit, so the IFS is recompiled with the
//! new colours (`Shot::prepare`) and the accumulation restarts.

use crate::edit::Edit;
use crate::palette::Palette;

use super::command::Command;
use super::state::ViewerState;

impl ViewerState {
    /// Applies a palette command; returns whether the scene changed.
    pub(super) fn palette_command(&mut self, command: Command) -> bool {
        let mut after = self.scene.clone();
        match command {
            Command::SetPaletteIndex { function, index } => {
                let Some(f) = after.functions.get_mut(function) else { return false };
                if index.is_some_and(|c| !(0.0..=1.0).contains(&c)) {
                    return false;
                }
                f.palette_index = index;
                return self.preview_scene(after);
            }
            Command::SetColorMode(mode) => after.render.color = mode,
            Command::SetPalette(name) => match Palette::builtin(&name) {
                Some(p) => after.render.palette = Some(p),
                None => {
                    self.error = Some(format!("unknown palette \"{name}\" (built in: {})", Palette::known()));
                    return false;
                }
            },
            _ => return false,
        }
        if after == self.scene {
            return false;
        }
        self.end_gesture();
        self.apply_edit(Edit::ReplaceScene { before: Box::new(self.scene.clone()), after: Box::new(after) })
    }
}
