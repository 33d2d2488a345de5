//! The scene's palette-colour fields, checked: `[render] color` and `palette` (a built-in name
//! or an image file relative to the scene file, read here so that a missing or broken image
//! is reported at its line), and a function's `palette_index`.

use std::path::Path;

use toml::Spanned;

use crate::palette::Palette;
use crate::scene::file::RenderToml;
use crate::scene::spec::{ColorMode, RenderSettings};

use super::{Checker, Res};

impl Checker<'_> {
    /// Sets `out.color` and `out.palette` from `r`.
    pub(super) fn color_fields(&self, r: &RenderToml, out: &mut RenderSettings) -> Res<()> {
        if let Some(v) = &r.color {
            out.color =
                self.named(v, "render.color", ColorMode::parse, "a colour mode", "\"function\" or \"palette\"")?;
        }
        if let Some(p) = &r.palette {
            // Relative to the scene file's directory (the working directory for text without one).
            let base_dir = Path::new(self.file).parent();
            let palette = Palette::resolve(p.get_ref(), base_dir)
                .map_err(|e| self.err(p.span(), "render.palette", e.to_string()))?;
            out.palette = Some(palette);
        }
        Ok(())
    }

    /// A function's `palette_index`, in 0..1.
    pub(super) fn palette_index(&self, v: Option<&Spanned<f64>>, field: &str) -> Res<Option<f64>> {
        v.map(|v| self.in_range(v, field, 0.0, 1.0)).transpose()
    }
}
