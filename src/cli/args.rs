//! Argument types and checks that several commands share: the geometry of W^n(A) (`snapshot`,
//! `export mesh`) and the PNG output check (`render`, `snapshot`).

use std::convert::Infallible;
use std::path::Path;

use clap::Args;

use nlifs::raytrace::Initial;

use super::BadInput;

#[derive(Args)]
pub struct GeometryArgs {
    /// n of W^n(A) (with --adaptive: the most refinement).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(0..=16))]
    pub depth: u32,
    /// Initial object A: `sphere`, `grid` (the initial grid's surface) or a .glb/.gltf file.
    #[arg(long, default_value = "sphere", value_parser = initial_from_text)]
    pub initial: Initial,
    /// Scene time in seconds.
    #[arg(long, default_value_t = 0.0)]
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
