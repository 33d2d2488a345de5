//! Argument types and checks that several commands share: the geometry of W^n(A) (`snapshot`,
//! `export mesh`), the PNG output check (`render`, `snapshot`) and the value parsers that give
//! every number on the command line its stated range (`--time`, `--points`, a hex colour),
//! the same ranges the scene format states (`nlifs::scene::spec`).

use std::convert::Infallible;
use std::path::Path;

use clap::Args;

use nlifs::raytrace::Initial;
use nlifs::scene::spec::{MAX_POINTS, MAX_TIME_SECS};

use super::BadInput;

#[derive(Args)]
pub struct GeometryArgs {
    /// n of W^n(A).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(0..=16))]
    pub depth: u32,
    /// Initial object A: `sphere`, `grid` (the initial grid's surface) or a .glb/.gltf file.
    #[arg(long, default_value = "sphere", value_parser = initial_from_text)]
    pub initial: Initial,
    /// Scene time in seconds (0 to 1e9).
    #[arg(long, default_value_t = 0.0, value_parser = time_secs)]
    pub time: f64,
}

impl GeometryArgs {
    /// The initial object, once a mesh path is known to name a glTF file. Checked here rather
    /// than while parsing so that a bad scene is reported first and the message stays the
    /// command's own.
    pub fn initial(&self) -> anyhow::Result<Initial> {
        if let Initial::Gltf(path) = &self.initial {
            let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
            if !matches!(ext.as_deref(), Some("glb" | "gltf")) {
                return Err(BadInput(format!(
                    "--initial {}: expected sphere, grid or a .glb/.gltf file",
                    path.display()
                ))
                .into());
            }
        }
        Ok(self.initial.clone())
    }
}

/// `sphere`, `grid`, or anything else as the path of a mesh.
fn initial_from_text(text: &str) -> Result<Initial, Infallible> {
    Ok(Initial::parse(text))
}

/// Bad input unless `path` ends in .png (any case).
pub fn check_png(path: &Path) -> anyhow::Result<()> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(()),
        _ => Err(BadInput(format!("output {} must end in .png", path.display())).into()),
    }
}

/// `--time`: a scene time in seconds, 0 to [`MAX_TIME_SECS`] (the scene format's key range).
pub fn time_secs(text: &str) -> Result<f64, String> {
    let t: f64 = text.trim().parse().map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if !(0.0..=MAX_TIME_SECS).contains(&t) {
        return Err(format!("must lie in 0..{MAX_TIME_SECS:e} seconds, found {text}"));
    }
    Ok(t)
}

/// A point count, 1 to [`MAX_POINTS`] (the scene format's `render.points` range). `_` may
/// group digits as in the scene file (`4_000_000`).
pub fn point_count(text: &str) -> Result<u64, String> {
    let n: u64 = text
        .trim()
        .replace('_', "")
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number from 1 to {MAX_POINTS}"))?;
    if !(1..=MAX_POINTS).contains(&n) {
        return Err(format!("must lie in 1..={MAX_POINTS} (2^40), found {n}"));
    }
    Ok(n)
}

/// A positive finite number of pixels, at most 1e6 (`--stop-pixels`).
pub fn positive_pixels(text: &str) -> Result<f32, String> {
    let v: f32 = text.trim().parse().map_err(|_| format!("`{text}` is not a number"))?;
    if !(v > 0.0 && v <= 1e6) {
        return Err(format!("must be a positive number of pixels up to 1e6, found {text}"));
    }
    Ok(v)
}

/// `--background`: `#rrggbb` (the scene format's hex colour parser), as linear RGB.
pub fn hex_color(text: &str) -> Result<[f32; 3], String> {
    let srgb = nlifs::color::parse_hex(text).ok_or_else(|| format!("`{text}` is not a colour; expected #rrggbb"))?;
    Ok(srgb.map(nlifs::color::srgb8_to_linear))
}
