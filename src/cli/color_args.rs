//! The colour overrides `nlifs render` and `nlifs record` share: `--color function|palette`
//! and `--palette NAME|FILE` (a built-in palette or an image strip, relative to the working
//! directory) over the scene's `[render] color` and `palette` (`nlifs::palette`).

use clap::{Args, ValueEnum};

use nlifs::palette::Palette;
use nlifs::scene::spec::{ColorMode, RenderSettings};

use super::BadInput;

#[derive(Args, Clone, Debug, Default)]
pub struct ColorArgs {
    /// How points are coloured: by their function's colour, or by the palette entry of the
    /// colour coordinate they carry (c ← (c + c_i) / 2 per step). Default: the scene's.
    #[arg(long, value_enum)]
    color: Option<ColorArg>,
    /// The palette of `--color palette`: a built-in name (ember, lagoon, moss, dusk, glacier,
    /// spectrum) or a PNG/JPEG whose middle row is the palette. Implies `--color palette`
    /// unless `--color` says otherwise.
    #[arg(long, value_name = "NAME|FILE")]
    palette: Option<String>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ColorArg {
    Function,
    Palette,
}

impl ColorArgs {
    /// The first of these flags given, by name (for commands where they do not apply).
    pub fn given(&self) -> Option<&'static str> {
        if self.color.is_some() {
            Some("--color")
        } else if self.palette.is_some() {
            Some("--palette")
        } else {
            None
        }
    }

    /// Sets the given colour mode and palette in `settings`; an unknown palette or an
    /// unreadable image is bad input.
    pub fn apply(&self, settings: &mut RenderSettings) -> Result<(), BadInput> {
        if let Some(spec) = &self.palette {
            settings.palette = Some(Palette::resolve(spec, None).map_err(|e| BadInput(format!("--palette: {e}")))?);
            settings.color = ColorMode::Palette;
        }
        match self.color {
            Some(ColorArg::Function) => settings.color = ColorMode::Function,
            Some(ColorArg::Palette) => settings.color = ColorMode::Palette,
            None => {}
        }
        Ok(())
    }
}
