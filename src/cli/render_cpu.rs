//! `nlifs render` on the CPU, in bounded memory: the memory check before anything is
//! allocated, the chaos game into one framebuffer (shared by the threads when per-thread copies
//! would be large, `Accumulation`), and the resolve streamed row by row into the PNG, so that a
//! 16384² still holds its framebuffer and little more; the rows are resolved a block ahead of
//! the encoder (`BlocksAhead`), whose filter and compression take one thread. Other formats go
//! through the float layers (`ImageLayers`), with the EXR layers chosen by `--layers`.

use std::path::Path;
use std::sync::mpsc;

use indicatif::ProgressBar;
use rayon::prelude::*;

use nlifs::color::linear_to_srgb8;
use nlifs::output::memory;
use nlifs::output::png_rows::{RowLayout, write_rows};
use nlifs::output::{self, Format, ImageLayers, OutputOptions, Provenance};
use nlifs::resolve::density_estimation::{self, Estimated};
use nlifs::resolve::{ResolveArgs, ResolveInputs, resolve_row};
use nlifs::scene::spec::SplatMode;
use nlifs::shot::{Accumulation, Shot};

use super::BadInput;
use super::image_args::bad;

/// Rows resolved together (in parallel) before they go to the PNG encoder.
const ROWS_PER_BLOCK: u32 = 64;

/// The EXR layers `--layers` asks for (None: all the mode has).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LayerChoice(pub Option<Vec<String>>);

impl LayerChoice {
    /// `--layers` for an output written with `options`: names from [`output::LAYER_NAMES`],
    /// EXR only.
    pub fn parse(text: Option<&str>, options: &OutputOptions) -> anyhow::Result<Self> {
        let Some(text) = text else { return Ok(Self(None)) };
        if options.format != Format::Exr {
            return Err(BadInput(format!("--layers applies to exr output, not {}", options.format.name())).into());
        }
        let names: Vec<String> = text.split(',').map(|n| n.trim().to_string()).filter(|n| !n.is_empty()).collect();
        for n in &names {
            if !output::LAYER_NAMES.contains(&n.as_str()) {
                return Err(BadInput(format!(
                    "--layers: `{n}` is not a layer; the layers are {}",
                    output::LAYER_NAMES.join(", ")
                ))
                .into());
            }
        }
        Ok(Self(Some(names)))
    }
}

/// Renders `shot` on the CPU and writes it to `path` as `options` say; returns how many pixels
/// the attractor covers. `bar` (over chunks) follows the chaos game.
pub fn render_still(
    shot: &Shot,
    path: &Path,
    options: &OutputOptions,
    layers: &LayerChoice,
    provenance: &Provenance,
    bar: &ProgressBar,
) -> anyhow::Result<usize> {
    let view = &shot.view;
    // A layer the mode lacks is refused before the render, so nothing is written.
    if let Some(names) = &layers.0 {
        let have = output::layer_names_of(view.mode, &shot.style);
        if let Some(missing) = names.iter().find(|n| !have.contains(&n.as_str())) {
            return Err(BadInput(format!(
                "--layers: {} mode{} has no `{missing}` layer; it has {}",
                view.mode.name(),
                if view.mode == SplatMode::Closest { " with this look" } else { "" },
                have.join(", ")
            ))
            .into());
        }
    }
    let accumulation = Accumulation::for_view(view);
    let streamed = options.is_plain_png();
    // Density estimation (`src/resolve/density_estimation.rs`): 8-bit PNG only, and its float
    // copy of the accumulation counts in the memory check.
    let estimation = density_estimation::applies(shot.settings.density_estimation.as_ref(), view.mode);
    if estimation.is_some() && !streamed {
        return Err(BadInput(format!(
            "density estimation writes 8-bit PNG only, not {}; leave out estimator_radius / --density-estimation",
            options.format.name()
        ))
        .into());
    }
    let estimation_bytes =
        if estimation.is_some() { view.accumulation_bytes() + view.accumulation_bytes() / 8 } else { 0 };
    let need = memory::still_need(view, accumulation_bytes(shot, accumulation) + estimation_bytes, streamed);
    let what = format!("a {}×{} {} render", view.width, view.height, view.mode.name());
    memory::check(&what, need, memory::available_bytes()).map_err(|e| BadInput(e.to_string()))?;

    let framebuffer = shot.splat_chunks(0..shot.plan.chunks(), accumulation, || bar.inc(1));
    bar.finish_and_clear();
    if streamed {
        return stream_png(shot, &framebuffer, path, provenance);
    }
    let mut image = ImageLayers::of(&framebuffer, &shot.camera, &shot.style);
    if let Some(names) = &layers.0 {
        image.keep_only(names);
    }
    let covered = framebuffer.covered_pixels();
    drop(framebuffer);
    output::write_image(path, &image, options, Some(provenance)).map_err(bad)?;
    Ok(covered)
}

/// Bytes the accumulation takes: the framebuffer, and per-thread copies or buffers.
fn accumulation_bytes(shot: &Shot, accumulation: Accumulation) -> u64 {
    let one = shot.view.accumulation_bytes();
    let threads = rayon::current_num_threads() as u64;
    match accumulation {
        // The copies and their merge.
        Accumulation::PerThread => one * (threads + 1),
        Accumulation::Shared => one + threads * nlifs::splat::shared::writer_bytes(&shot.view, threads as usize),
    }
}

/// Resolves `framebuffer` row by row into an 8-bit PNG at `path` (the bytes `resolve_image`
/// and `save_rgb8` would give); returns the pixels that differ from the background.
fn stream_png(
    shot: &Shot,
    framebuffer: &nlifs::splat::Framebuffer,
    path: &Path,
    provenance: &Provenance,
) -> anyhow::Result<usize> {
    let view = &framebuffer.view;
    let (width, height) = (view.width, view.height);
    let params =
        ResolveArgs::new(view, &shot.camera, &shot.style).drawn(framebuffer.points_drawn).params(width, height, true);
    let inputs = ResolveInputs::of(framebuffer);
    let estimated: Option<Estimated> =
        density_estimation::applies(shot.settings.density_estimation.as_ref(), view.mode)
            .map(|de| density_estimation::estimate(&framebuffer.accum, width, height, &de));
    // What an 8-bit unorm target stores (the resolve's `unorm8`).
    let unorm8 = |c: [f32; 3]| c.map(|v| (v * 255.0 + 0.5) as u8);
    let background = view.background.map(linear_to_srgb8);
    let bar = super::progress_bar(height as u64, "write");
    let row_bytes = width as usize * 3;
    let resolve_block = |start: u32, block: &mut [u8]| {
        let rows = ROWS_PER_BLOCK.min(height - start) as usize;
        block[..rows * row_bytes].par_chunks_mut(row_bytes).enumerate().for_each(|(i, row)| {
            let y = start + i as u32;
            match &estimated {
                Some(e) => {
                    for (x, px) in row.chunks_exact_mut(3).enumerate() {
                        px.copy_from_slice(&unorm8(e.fragment(&params, x as u32, y)));
                    }
                }
                None => resolve_row(&params, &inputs, y, |x, c| row[3 * x..3 * x + 3].copy_from_slice(&unorm8(c))),
            }
        });
    };
    let mut covered = 0usize;
    std::thread::scope(|scope| -> anyhow::Result<()> {
        let mut ahead = BlocksAhead::start(scope, &resolve_block, row_bytes * ROWS_PER_BLOCK as usize, height);
        let mut counting = true;
        let (covered, bar) = (&mut covered, &bar);
        write_rows(path, width, height, RowLayout::Rgb8, Some(provenance), move |y, out| {
            let start = y / ROWS_PER_BLOCK * ROWS_PER_BLOCK;
            let i = (y - start) as usize;
            out.copy_from_slice(&ahead.block(start)[i * row_bytes..(i + 1) * row_bytes]);
            if counting {
                *covered += out.chunks_exact(3).filter(|p| **p != background).count();
                bar.set_position(y as u64 + 1);
                // A second pass (stored blocks) sends the rows again: count them once.
                counting = y + 1 < height;
            }
        })
        .map_err(bad)
    })?;
    bar.finish_and_clear();
    Ok(covered)
}

/// Blocks of rows resolved one block ahead of the PNG encoder, on a thread of their own (whose
/// resolve takes rayon's threads), so that the encoder's filter and compression, which run on
/// one thread, overlap the next block's resolve instead of leaving a core idle. Two buffers
/// take turns: the block the encoder reads and the one being resolved.
struct BlocksAhead {
    /// (first row, buffer to fill) to the resolving thread; dropping it ends that thread.
    requests: mpsc::Sender<(u32, Vec<u8>)>,
    /// (first row, resolved rows) back.
    resolved: mpsc::Receiver<(u32, Vec<u8>)>,
    /// The block the encoder reads, by its first row.
    current: Option<(u32, Vec<u8>)>,
    /// The first row of the block being resolved, if one is.
    pending: Option<u32>,
    idle: Vec<Vec<u8>>,
    height: u32,
}

impl BlocksAhead {
    /// Starts the resolving thread in `scope`: `resolve(first row, buffer)` fills a block of
    /// `block_bytes` (fewer rows at the image's end).
    fn start<'scope, 'env>(
        scope: &'scope std::thread::Scope<'scope, 'env>,
        resolve: &'env (impl Fn(u32, &mut [u8]) + Sync),
        block_bytes: usize,
        height: u32,
    ) -> Self {
        let (requests, asked) = mpsc::channel::<(u32, Vec<u8>)>();
        let (done, resolved) = mpsc::channel();
        scope.spawn(move || {
            for (start, mut block) in asked {
                resolve(start, &mut block);
                // The encoder gone (a write error): nothing more to do.
                if done.send((start, block)).is_err() {
                    break;
                }
            }
        });
        Self { requests, resolved, current: None, pending: None, idle: vec![vec![0; block_bytes]; 2], height }
    }

    fn ask(&mut self, start: u32) {
        let buffer = self.idle.pop().expect("two buffers: one being read, one being resolved");
        self.requests.send((start, buffer)).expect("the resolving thread waits for requests until dropped");
        self.pending = Some(start);
    }

    fn receive(&mut self) -> (u32, Vec<u8>) {
        self.pending = None;
        self.resolved.recv().expect("the resolving thread answers every request")
    }

    /// The block whose first row is `start`; asks for the next one before returning.
    fn block(&mut self, start: u32) -> &[u8] {
        if self.current.as_ref().map(|c| c.0) != Some(start) {
            if self.pending != Some(start) {
                // Not the block asked for (the first, or a second pass starting over).
                if self.pending.is_some() {
                    let (_, unused) = self.receive();
                    self.idle.push(unused);
                }
                self.ask(start);
            }
            let block = self.receive();
            if let Some((_, read)) = self.current.replace(block) {
                self.idle.push(read);
            }
            if start + ROWS_PER_BLOCK < self.height {
                self.ask(start + ROWS_PER_BLOCK);
            }
        }
        &self.current.as_ref().expect("received above").1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocks come back with the rows their first row names, in order and over again (the
    /// encoder's second pass), with a short last block, whatever the order they are asked in.
    #[test]
    fn blocks_ahead_give_each_block_its_rows() {
        let height = 3 * ROWS_PER_BLOCK + 5;
        let row_bytes = 4;
        let fill = |start: u32, block: &mut [u8]| {
            let rows = ROWS_PER_BLOCK.min(height - start) as usize;
            for (i, row) in block[..rows * row_bytes].chunks_mut(row_bytes).enumerate() {
                row.fill((start as usize + i) as u8);
            }
        };
        std::thread::scope(|scope| {
            let mut ahead = BlocksAhead::start(scope, &fill, row_bytes * ROWS_PER_BLOCK as usize, height);
            let passes = (0..height).chain(0..height).chain([ROWS_PER_BLOCK + 1, 2, height - 1, 0]);
            for y in passes {
                let start = y / ROWS_PER_BLOCK * ROWS_PER_BLOCK;
                let i = (y - start) as usize;
                assert_eq!(ahead.block(start)[i * row_bytes..(i + 1) * row_bytes], [y as u8; 4], "row {y}");
            }
        });
    }
}
