//! `nlifs view` (and `nlifs` alone): the interactive viewer, with its start-up settings.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};

use nlifs::live::ChaosBackend;

#[derive(Args, Default)]
pub struct ViewArgs {
    scene: Option<PathBuf>,
    /// Persistent GPU points (default 2^20).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=(1 << 26)))]
    points: Option<u32>,
    /// Chaos-game steps per point per frame.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    steps: Option<u32>,
    /// Screen-space shading strength 0..1 (closest mode).
    #[arg(long)]
    shading: Option<f32>,
    /// Testing: close after this many seconds and print frame statistics.
    #[arg(long, hide = true)]
    exit_after_secs: Option<f64>,
    /// Testing: save the attractor to this PNG before closing.
    #[arg(long, hide = true)]
    screenshot: Option<PathBuf>,
    /// Start with the grid overlay (initial and transformed grids) shown.
    #[arg(long)]
    grid: bool,
    /// Start with the nesting view W^K of the grid box shown (the paper's plates 5 and 7).
    #[arg(long, value_name = "K")]
    nesting: Option<u32>,
    /// Start playing the timeline.
    #[arg(long)]
    play: bool,
    /// Print frames per second and per-stage frame times to stderr once a second.
    #[arg(long)]
    log_fps: bool,
    /// Where the chaos game runs: gpu (compute shader), cpu (CPU kernel; the GPU only
    /// resolves), or auto (default: cpu on a software adapter such as lavapipe, gpu otherwise).
    #[arg(long, value_enum)]
    chaos_backend: Option<ChaosBackendArg>,
}

/// The viewer's [`ChaosBackend`], in the order the help lists them.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ChaosBackendArg {
    Auto,
    Gpu,
    Cpu,
}

impl From<ChaosBackendArg> for ChaosBackend {
    fn from(b: ChaosBackendArg) -> Self {
        match b {
            ChaosBackendArg::Auto => ChaosBackend::Auto,
            ChaosBackendArg::Gpu => ChaosBackend::Gpu,
            ChaosBackendArg::Cpu => ChaosBackend::Cpu,
        }
    }
}

pub fn view(args: ViewArgs) -> anyhow::Result<()> {
    // A missing or bad scene is an error like in every other command (exit 2, located), not
    // the default scene with the error in a panel: the window opens only on a scene that reads.
    if let Some(path) = &args.scene {
        if nlifs::output::png::is_png(path) {
            // A PNG that nlifs wrote: read here, so that a bad one is an error before the window
            // opens; the viewer opens its scene without a path (a save asks where, beside the
            // image by default, and never writes over it).
            let embedded = nlifs::output::png::scene_from_png(path).map_err(super::image_args::bad)?;
            embedded.scene(&format!("{} (embedded scene)", path.display())).map_err(super::image_args::bad)?;
            eprintln!("opening the scene inside {} (made at t = {} s)", path.display(), embedded.t_secs);
        } else {
            // A flame file opens as its imported scene; its warnings are printed here, once.
            super::load(path)?;
        }
    }
    if let Some(path) = &args.screenshot {
        super::probe_output(path)?;
    }
    let mut live = nlifs::live::LiveSettings::default();
    if let Some(n) = args.points {
        live.draw.point_count = n;
    }
    if let Some(k) = args.steps {
        live.draw.steps_per_frame = k;
    }
    if let Some(s) = args.shading {
        live.draw.shading = s.clamp(0.0, 1.0);
    }
    live.chaos_backend = args.chaos_backend.map_or(ChaosBackend::Auto, ChaosBackend::from);
    let options = nlifs::viewer::ViewerOptions {
        scene: args.scene,
        live,
        exit_after_secs: args.exit_after_secs,
        screenshot: args.screenshot,
        grid_overlay: args.grid,
        nesting_level: args.nesting,
        play: args.play,
        log_fps: args.log_fps,
        host: Default::default(),
        backends: None,
    };
    nlifs::viewer::run(options).context("viewer")?;
    Ok(())
}
