//! The `nlifs` command line: a thin layer over the library that parses arguments, shows
//! progress, adds context to errors and maps bad input to exit code 2.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use nlifs::chaos_game::{self, CollectSink, CompiledIfs};
use nlifs::export;
use nlifs::io::{save_png, write_atomic};
use nlifs::model::IfsReport;
use nlifs::render::render_cpu;
use nlifs::scene::Scene;
use nlifs::splat::SplatMode;

#[derive(Parser)]
#[command(
    name = "nlifs",
    version,
    about = "Model and render nonlinear iterated function systems defined by grid distortion",
    long_about = "Model and render nonlinear iterated function systems (IFS) whose functions distort \
a regular 2D or 3D grid, after E. Gröller. Scenes are TOML files (see scenes/ and README.md).\n\n\
Examples:\n  nlifs info scenes/tapering.toml\n  nlifs render scenes/plant2.toml -o plant2.png\n  \
nlifs export points scenes/fantasy.toml -o fantasy.glb"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Contractivity, Lipschitz bounds, containment and probabilities of a scene's functions.
    Info {
        scene: PathBuf,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Scene time in seconds.
        #[arg(long, default_value_t = 0.0)]
        time: f64,
    },
    /// Render a still with the chaos game (headless).
    Render(RenderArgs),
    /// Export geometry.
    #[command(subcommand)]
    Export(ExportCommand),
    /// Open the interactive viewer (GPU) on a scene; `nlifs` alone opens it on a built-in scene.
    View(ViewArgs),
    /// Benchmarks.
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Args, Default)]
struct ViewArgs {
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
}

#[derive(Subcommand)]
enum BenchCommand {
    /// GPU chaos game: points/s (map + splat) and frames/s at 1280×720, and frames to converge
    /// after a scene edit.
    Gpu {
        #[arg(default_value = "scenes/plant2.toml")]
        scene: PathBuf,
        /// Persistent GPU points.
        #[arg(long, default_value_t = 1 << 20)]
        points: u32,
        /// Steps per point per frame.
        #[arg(long, default_value_t = 1)]
        steps: u32,
        /// Frames to time.
        #[arg(long, default_value_t = 60)]
        frames: u32,
    },
}

#[derive(Args)]
struct RenderArgs {
    scene: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Image width in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Points to draw after the transient (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    points: Option<u64>,
    /// Random seed (default: the scene's).
    #[arg(long)]
    seed: Option<u32>,
    /// Scene time in seconds.
    #[arg(long, default_value_t = 0.0)]
    time: f64,
    /// Splat mode (default: the scene's).
    #[arg(long, value_enum)]
    mode: Option<ModeArg>,
    /// Where the chaos game runs: gpu, cpu, or auto (gpu when an adapter exists).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    Gpu,
    Cpu,
    Auto,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeArg {
    Closest,
    Average,
    Density,
}

impl From<ModeArg> for SplatMode {
    fn from(m: ModeArg) -> Self {
        match m {
            ModeArg::Closest => SplatMode::Closest,
            ModeArg::Average => SplatMode::Average,
            ModeArg::Density => SplatMode::Density,
        }
    }
}

#[derive(Subcommand)]
enum ExportCommand {
    /// The attractor's points with colour, as binary PLY (.ply) or glTF 2.0 binary (.glb).
    Points {
        scene: PathBuf,
        /// Output file, .ply or .glb.
        #[arg(short, long)]
        output: PathBuf,
        #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(1..=200_000_000))]
        points: u64,
        #[arg(long)]
        seed: Option<u32>,
        /// Scene time in seconds.
        #[arg(long, default_value_t = 0.0)]
        time: f64,
    },
}

/// An error caused by the user's input: exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct BadInput(String);

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            let bad_input = e.chain().any(|c| c.is::<BadInput>() || c.is::<nlifs::scene::LoadError>() || c.is::<nlifs::scene::SceneError>());
            ExitCode::from(if bad_input { 2 } else { 1 })
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None => view(ViewArgs::default()),
        Some(Command::View(args)) => view(args),
        Some(Command::Bench(BenchCommand::Gpu { scene, points, steps, frames })) => {
            let scene = load(&scene)?;
            let report = nlifs::gpu::bench::run(&scene, points, steps, frames)?;
            println!("{report}");
            Ok(())
        }
        Some(Command::Info { scene, json, time }) => info(&scene, json, time),
        Some(Command::Render(args)) => render(args),
        Some(Command::Export(ExportCommand::Points { scene, output, points, seed, time })) => {
            export_points(&scene, &output, points, seed, time)
        }
    }
}

fn view(args: ViewArgs) -> anyhow::Result<()> {
    let mut live = nlifs::gpu::live::LiveSettings::default();
    if let Some(n) = args.points {
        live.point_count = n;
    }
    if let Some(k) = args.steps {
        live.steps_per_frame = k;
    }
    if let Some(s) = args.shading {
        live.shading = s.clamp(0.0, 1.0);
    }
    let options = nlifs::viewer::ViewerOptions { scene: args.scene, live, exit_after_secs: args.exit_after_secs, screenshot: args.screenshot };
    nlifs::viewer::run(options).context("viewer")?;
    Ok(())
}

fn load(path: &Path) -> anyhow::Result<Scene> {
    Ok(Scene::load(path)?)
}

fn progress_bar(total: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed_precise} left {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or("—".into(), |x| format!("{x:.4}"))
}

fn info(path: &Path, json: bool, time: f64) -> anyhow::Result<()> {
    let scene = load(path)?;
    let ifs = scene.at(time);
    let report: IfsReport = ifs.report();
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    let d = scene.domain.dims();
    println!("{} ({}D, grid {}×{}×{}, probabilities: {})", scene.name, report.dimension, d[0], d[1], d[2], report.probability_mode);
    if !scene.description.is_empty() {
        println!("{}", scene.description);
    }
    println!("{:<12} {:<8} {:>10} {:>15} {:>10} {:>11}", "function", "kind", "grid_ratio", "lipschitz_bound", "contained", "probability");
    for f in &report.functions {
        let contained = match f.contained {
            None => "n/a".to_string(),
            Some(true) => "yes".to_string(),
            Some(false) => format!("NO ({})", f.outside.len()),
        };
        println!(
            "{:<12} {:<8} {:>10} {:>15} {:>10} {:>11.4}",
            f.name,
            f.kind,
            fmt_opt(f.grid_ratio),
            fmt_opt(f.lipschitz_bound),
            contained,
            f.probability
        );
        for (k, p) in &f.outside {
            println!("    point {k} at ({:.4}, {:.4}, {:.4}) lies outside the grid", p[0], p[1], p[2]);
        }
        if let Some(l) = f.lipschitz_bound
            && l >= 1.0
        {
            println!("    warning: {} may not be contractive (Lipschitz bound {l:.4} ≥ 1)", f.name);
        }
    }
    println!(
        "IFS: max grid_ratio {}, max lipschitz_bound {}, all contained: {}",
        fmt_opt(report.max_grid_ratio),
        fmt_opt(report.max_lipschitz_bound),
        report.all_contained.map_or("n/a", |c| if c { "yes" } else { "NO" })
    );
    Ok(())
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    let mut settings = scene.render.clone();
    if let Some(w) = args.width {
        settings.width = w;
    }
    if let Some(h) = args.height {
        settings.height = h;
    }
    if let Some(n) = args.points {
        settings.points = n;
    }
    if let Some(s) = args.seed {
        settings.seed = s;
    }
    if let Some(m) = args.mode {
        settings.mode = m.into();
    }
    check_png(&args.output)?;
    let (chunks, _, _) = chaos_game::chunking(settings.points);
    let bar = progress_bar(chunks as u64, "render");
    let start = std::time::Instant::now();
    // GPU: explicit `gpu` fails without an adapter; `auto` falls back to the CPU.
    let gpu = match args.backend {
        BackendArg::Cpu => None,
        BackendArg::Gpu => Some(nlifs::gpu::GpuContext::headless()?),
        BackendArg::Auto => nlifs::gpu::GpuContext::headless().ok(),
    };
    let image = match &gpu {
        Some(ctx) => {
            bar.finish_and_clear();
            eprintln!("rendering on {}", ctx.describe());
            nlifs::gpu::render::render_gpu(ctx, &scene, args.time, &settings, None).map_err(|e| match e {
                nlifs::gpu::GpuError::NoFunctions => anyhow::Error::new(BadInput(e.to_string())),
                e => e.into(),
            })?.image
        }
        None => render_cpu(&scene, args.time, &settings, None, &|d, _| bar.set_position(d)).map_err(|e| BadInput(e.to_string()))?.image,
    };
    bar.finish_and_clear();
    save_png(&args.output, &image).with_context(|| format!("cannot write {}", args.output.display()))?;
    eprintln!(
        "wrote {} ({}×{}, {} points, {:.2} s)",
        args.output.display(),
        settings.width,
        settings.height,
        settings.points,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn check_png(path: &Path) -> anyhow::Result<()> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(()),
        _ => Err(BadInput(format!("output {} must end in .png", path.display())).into()),
    }
}

fn export_points(path: &Path, output: &Path, points: u64, seed: Option<u32>, time: f64) -> anyhow::Result<()> {
    let scene = load(path)?;
    let ext = output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    let glb = match ext.as_deref() {
        Some("glb") => true,
        Some("ply") => false,
        _ => return Err(BadInput(format!("output {} must end in .ply or .glb", output.display())).into()),
    };
    let ifs = scene.at(time);
    let compiled = CompiledIfs::new(&ifs).ok_or_else(|| BadInput("the scene has no enabled function".into()))?;
    let seed = seed.unwrap_or(scene.render.seed);
    let (chunks, _, _) = chaos_game::chunking(points);
    let bar = progress_bar(chunks as u64, "points");
    let done = std::sync::atomic::AtomicU64::new(0);
    // Chunks are collected in index order so the file is deterministic.
    let sinks: Vec<CollectSink> = {
        use rayon::prelude::*;
        let (_, steps, last) = chaos_game::chunking(points);
        (0..chunks)
            .into_par_iter()
            .map(|c| {
                let mut s = CollectSink::default();
                chaos_game::run_chunk(&compiled, seed, 0, c, if c + 1 == chunks { last } else { steps }, &mut s);
                bar.set_position(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                s
            })
            .collect()
    };
    bar.finish_and_clear();
    let mut pts = Vec::new();
    let mut colors = Vec::new();
    for s in sinks {
        for (p, f) in s.points.iter().zip(&s.functions) {
            pts.push(*p);
            colors.push(compiled.colors[*f as usize]);
        }
    }
    pts.truncate(points as usize);
    colors.truncate(points as usize);
    write_atomic(output, |w| if glb { export::write_glb_points(w, &pts, &colors) } else { export::write_ply(w, &pts, &colors) })
        .with_context(|| format!("cannot write {}", output.display()))?;
    eprintln!("wrote {} ({} points)", output.display(), pts.len());
    Ok(())
}
