//! `nlifs merge`: combines the part files of one still (`nlifs render --part K/N --raw`) into
//! the image one render of all points would have made, byte for byte.

use std::path::PathBuf;

use clap::Args;

use nlifs::output::part::merge_parts;

use super::image_args::{ImageArgs, bad, write_still};

#[derive(Args)]
pub struct MergeArgs {
    /// The part files (all N parts of one still, in any order).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Output image (.png or .exr).
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    image: ImageArgs,
}

pub fn merge(args: MergeArgs) -> anyhow::Result<()> {
    let options = args.image.for_file(&args.output)?;
    super::probe_output(&args.output)?;
    let start = std::time::Instant::now();
    let merged = merge_parts(&args.parts).map_err(bad)?;
    write_still(
        &args.output,
        &options,
        &merged.framebuffer,
        &merged.camera,
        &merged.style,
        merged.density_estimation.as_ref(),
        None,
        &merged.provenance,
    )?;
    let v = &merged.framebuffer.view;
    eprintln!(
        "merged {} parts into {} ({}×{}, {:.2} s)",
        args.parts.len(),
        args.output.display(),
        v.width,
        v.height,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
