//! The image-output flags that `render`, `record` and `merge` share (`--format`,
//! `--transparent`, `--half`), and writing a still in the chosen format.

use std::path::Path;

use clap::Args;

use nlifs::camera::OrbitCamera;
use nlifs::output::part::PartSpec;
use nlifs::output::{self, Format, ImageLayers, OutputError, OutputOptions, Provenance};
use nlifs::resolve::ResolveStyle;
use nlifs::resolve::density_estimation;
use nlifs::scene::spec::DensityEstimation;
use nlifs::splat::Framebuffer;

use super::BadInput;

#[derive(Args, Clone, Copy, Default)]
pub struct ImageArgs {
    /// png (8-bit sRGB), png16 (16-bit, from the linear colour) or exr (linear, with depth,
    /// function-id and count layers). Default: by the output's extension (.exr → exr, else png).
    #[arg(long, value_parser = format_from_text)]
    pub format: Option<Format>,
    /// Leave the background transparent: an alpha channel of the attractor's coverage.
    #[arg(long)]
    pub transparent: bool,
    /// EXR: write the colour as 16-bit halves (depth, id and count stay 32-bit floats).
    #[arg(long)]
    pub half: bool,
}

fn format_from_text(text: &str) -> Result<Format, String> {
    Format::parse(text).ok_or_else(|| format!("`{text}` is not a format; use png, png16 or exr"))
}

impl ImageArgs {
    /// The options for the output file `path` (whose extension must fit the format).
    pub fn for_file(&self, path: &Path) -> anyhow::Result<OutputOptions> {
        let format = Format::resolve(path, self.format).map_err(bad)?;
        self.with_format(format)
    }

    /// The options for files this command names itself (record's frames): png by default.
    pub fn for_frames(&self) -> anyhow::Result<OutputOptions> {
        self.with_format(self.format.unwrap_or_default())
    }

    fn with_format(&self, format: Format) -> anyhow::Result<OutputOptions> {
        if self.half && format != Format::Exr {
            return Err(BadInput(format!("--half applies to exr output, not {}", format.name())).into());
        }
        Ok(OutputOptions { format, transparent: self.transparent, half: self.half })
    }
}

/// An output error as the CLI reports it: bad input (exit 2) unless the machine failed.
pub fn bad(e: OutputError) -> anyhow::Error {
    if e.is_bad_input() { BadInput(e.to_string()).into() } else { e.into() }
}

/// Writes the still of `framebuffer` in the look `style` with density estimation `de` (density
/// mode, 8-bit PNG only): the plain 8-bit PNG from `resolved` (the image `resolve_image` made,
/// when already at hand), any other format from the framebuffer's layers; PNGs carry
/// `provenance`.
#[expect(clippy::too_many_arguments, reason = "each is one part of the still, named at the call")]
pub fn write_still(
    path: &Path,
    options: &OutputOptions,
    framebuffer: &Framebuffer,
    camera: &OrbitCamera,
    style: &ResolveStyle,
    de: Option<&DensityEstimation>,
    resolved: Option<&image::RgbImage>,
    provenance: &Provenance,
) -> anyhow::Result<()> {
    if options.is_plain_png() {
        let made;
        let image = match resolved {
            Some(image) => image,
            None => {
                made = density_estimation::resolve_image(framebuffer, camera, style, de);
                &made
            }
        };
        output::png::save_rgb8(path, image, Some(provenance)).map_err(bad)
    } else {
        if density_estimation::applies(de, framebuffer.view.mode).is_some() {
            return Err(BadInput(
                "density estimation is drawn into 8-bit PNG only: write a .png without --format, or drop it".into(),
            )
            .into());
        }
        let layers = ImageLayers::of(framebuffer, camera, style);
        output::write_image(path, &layers, options, Some(provenance)).map_err(bad)
    }
}

/// `render --part K/N --raw PATH`: renders part `spec` of the still and writes its accumulation.
pub fn render_part(
    scene: &nlifs::scene::Scene,
    t_secs: f64,
    settings: &nlifs::scene::spec::RenderSettings,
    spec: PartSpec,
    raw: &Path,
) -> anyhow::Result<()> {
    let chunks =
        nlifs::chaos_game::ChunkPlan::new(settings.points).map_err(|e| super::BadInput(e.to_string()))?.chunks();
    let range = spec.chunk_range(chunks);
    super::probe_output(raw)?;
    let bar = super::progress_bar(range.len() as u64, "part");
    let start = std::time::Instant::now();
    let part = output::part::render_part(scene, t_secs, settings, spec, &|d, _| bar.set_position(d)).map_err(bad)?;
    bar.finish_and_clear();
    output::part::write_part(raw, &part).map_err(bad)?;
    eprintln!(
        "wrote part {}/{} to {} (chunks {}..{} of {}, {:.2} s)",
        spec.k,
        spec.n,
        raw.display(),
        range.start,
        range.end,
        chunks,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
