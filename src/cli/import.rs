//! `nlifs import flame FILE.flame [--name N | --index K] -o SCENE.toml`: a flam3 flame as an
//! nlifs scene (`nlifs::scene::flame_import`), written with its palette as the image
//! `SCENE.palette.png` next to it. The same import opens a flame file in `nlifs view` and
//! `nlifs record` ([`super::load`]).

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};

use nlifs::scene::flame_import;

use super::{BadInput, probe_outputs};

#[derive(Subcommand)]
pub enum ImportCommand {
    /// A flam3 flame file (.flame, .flam3) as a scene: each xform a `kind = "flame"` function,
    /// its palette, camera and density look.
    Flame(ImportFlameArgs),
}

#[derive(Args)]
pub struct ImportFlameArgs {
    /// The flame file.
    file: PathBuf,
    /// The scene file to write (.toml); its palette goes to SCENE.palette.png beside it.
    #[arg(short, long)]
    output: PathBuf,
    /// The flame to import by its position in the file, from 0 (default: the first).
    #[arg(long, conflicts_with = "name")]
    index: Option<usize>,
    /// The flame to import by its `name`.
    #[arg(long)]
    name: Option<String>,
}

pub fn run(command: ImportCommand) -> anyhow::Result<()> {
    match command {
        ImportCommand::Flame(args) => import_flame(&args),
    }
}

fn import_flame(args: &ImportFlameArgs) -> anyhow::Result<()> {
    if !nlifs::flame::xml::is_flame_path(&args.file) {
        return Err(BadInput(format!("{}: `import flame` reads .flame and .flam3 files", args.file.display())).into());
    }
    let ext = args.output.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("toml") {
        return Err(BadInput(format!("{}: a scene is written to a .toml file", args.output.display())).into());
    }
    let mut import = flame_import::load_flame(&args.file, args.index, args.name.as_deref())?;
    for warning in &import.warnings {
        eprintln!("warning: {warning}");
    }
    let palette_file = flame_import::palette_file_for(&args.output);
    let palette_path = args.output.parent().unwrap_or(Path::new("")).join(&palette_file);
    probe_outputs(&[&args.output, &palette_path])?;
    if let Some(p) = &mut import.scene.render.palette {
        p.source = palette_file;
    }
    import.scene.path = Some(args.output.clone());
    // A palette image of that name already there would be kept by the save: this import's goes.
    nlifs::io::save_png(
        &palette_path,
        &import.scene.render.palette.as_ref().map(|p| p.strip_image()).unwrap_or_default(),
    )
    .map_err(|e| anyhow::Error::from(e).context(format!("cannot write {}", palette_path.display())))?;
    import
        .scene
        .save(&args.output)
        .map_err(|e| anyhow::Error::from(e).context(format!("cannot write {}", args.output.display())))?;
    eprintln!(
        "wrote {} ({} flame functions) and its palette {}",
        args.output.display(),
        import.scene.functions.len(),
        palette_path.display()
    );
    Ok(())
}
