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
use nlifs::scene::spec::SplatMode;

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
    /// Render an animated scene to DIR/frame_00000.png, ... (optionally a video).
    Record(RecordArgs),
    /// Ray-trace a still of the deterministic approximation W^n(A) (spheres or meshes).
    Snapshot(raytrace_cli::SnapshotArgs),
    /// Open the interactive viewer (GPU) on a scene; `nlifs` alone opens it on a built-in scene.
    View(ViewArgs),
    /// Benchmarks (throughput figures for the README).
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
    /// Start with the grid overlay (initial and transformed grids) shown.
    #[arg(long)]
    grid: bool,
    /// Start playing the timeline.
    #[arg(long)]
    play: bool,
    /// Print frames per second and per-stage frame times to stderr once a second.
    #[arg(long)]
    log_fps: bool,
    /// Where the chaos game runs: gpu (compute shader), cpu (CPU kernel; the GPU only
    /// resolves), or auto (default: cpu on a software adapter such as lavapipe, gpu otherwise).
    #[arg(long, value_parser = ["auto", "gpu", "cpu"])]
    chaos_backend: Option<String>,
}

#[derive(Subcommand)]
enum BenchCommand {
    #[command(flatten)]
    Raytrace(raytrace_cli::BenchCommand),
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
    /// CPU chaos game on one core: map only and map + splat at 1920×1080.
    Cpu {
        /// Scene to run (default: the paper's tapering).
        #[arg(default_value = "scenes/tapering.toml")]
        scene: PathBuf,
        #[arg(long, default_value_t = 50_000_000)]
        points: u64,
        #[arg(long, default_value_t = 3)]
        repeats: usize,
    },
    /// How much of the attractor a fixed budget of points covers under uniform, contractivity
    /// and locally adaptive probabilities.
    Coverage {
        scene: PathBuf,
        #[arg(long, default_value_t = 200_000)]
        budget: u64,
        #[arg(long, default_value_t = 40_000_000)]
        reference: u64,
        #[arg(long, default_value_t = 512)]
        size: u32,
    },
}

#[derive(Args)]
struct RecordArgs {
    scene: PathBuf,
    /// Output directory for frame_NNNNN.png.
    #[arg(short, long)]
    output: PathBuf,
    /// Frames A..B to render (end exclusive; default: the whole animation).
    #[arg(long, value_parser = nlifs::record::parse_frame_range)]
    frames: Option<std::ops::Range<u32>>,
    #[arg(long, default_value_t = 24.0)]
    fps: f64,
    /// Frame width in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Frame height in pixels (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Points per frame (default: the scene's render.points at the frame's time).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    points_per_frame: Option<u64>,
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Keep frames that are already complete (decode fully); redo anything else.
    #[arg(long)]
    resume: bool,
    /// Also encode the frames into this video with the system ffmpeg.
    #[arg(long)]
    video: Option<PathBuf>,
    /// Average this many temporal samples within each frame's shutter (1: no blur).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    motion_blur: u32,
    /// Open shutter as a fraction of the frame interval (for --motion-blur).
    #[arg(long, default_value_t = 0.5)]
    shutter: f64,
    /// Print the animation's frame count at --fps and exit (for splitting over a job array).
    #[arg(long)]
    print_frame_count: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    Gpu,
    Cpu,
    Auto,
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
    /// The deterministic approximation W^n(A) as a glTF 2.0 binary mesh (.glb).
    Mesh(raytrace_cli::ExportMeshArgs),
    /// W^n(A) of spheres as a POV-Ray 3.7 scene (for benchmarks).
    #[command(hide = true)]
    Pov(raytrace_cli::ExportPovArgs),
}

/// An error caused by the user's input: exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct BadInput(String);

#[path = "raytrace/cli.rs"]
mod raytrace_cli;

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
            let bad_input = e.chain().any(|c| {
                c.is::<BadInput>()
                    || c.downcast_ref::<nlifs::raytrace::RaytraceError>().is_some_and(|e| e.is_bad_input())
                    || c.is::<nlifs::scene::LoadError>()
                    || c.is::<nlifs::scene::SceneError>()
            });
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
        Some(Command::Bench(BenchCommand::Cpu { scene, points, repeats })) => bench_cpu(&scene, points, repeats),
        Some(Command::Bench(BenchCommand::Coverage { scene, budget, reference, size })) => {
            let s = load(&scene)?;
            println!("{}: share of the attractor's {size}x{size} pixels lit by {budget} points", s.name);
            for (name, share) in nlifs::bench::coverage(&s, budget, reference, size) {
                println!("  {name:<14} {:6.2} %", 100.0 * share);
            }
            Ok(())
        }
        Some(Command::Record(args)) => record(args),
        Some(Command::Export(ExportCommand::Mesh(args))) => raytrace_cli::export_mesh(args),
        Some(Command::Export(ExportCommand::Pov(args))) => raytrace_cli::export_pov(args),
        Some(Command::Snapshot(args)) => raytrace_cli::snapshot(args),
        Some(Command::Bench(BenchCommand::Raytrace(cmd))) => raytrace_cli::bench(cmd),
    }
}

fn record(args: RecordArgs) -> anyhow::Result<()> {
    use nlifs::record::{self, RecordSettings, Recorder};
    let scene = load(&args.scene)?;
    if !(args.fps > 0.0 && args.fps.is_finite()) {
        return Err(BadInput(format!("--fps must be a positive number, found {}", args.fps)).into());
    }
    if !(0.0..=1.0).contains(&args.shutter) {
        return Err(BadInput(format!("--shutter must lie in 0..1, found {}", args.shutter)).into());
    }
    if args.backend != BackendArg::Cpu && !args.print_frame_count {
        // The GPU recorder is not part of this build; the CPU path gives the same frames' content.
        eprintln!("note: no GPU recording path in this build; rendering frames on the CPU");
    }
    if args.video.is_some() && !record::ffmpeg_available() {
        return Err(BadInput("--video needs ffmpeg, which was not found on PATH; install ffmpeg or leave out --video (frames can be encoded later)".into()).into());
    }
    let mut settings = RecordSettings::for_scene(&scene);
    settings.fps = args.fps;
    settings.width = args.width.unwrap_or(settings.width);
    settings.height = args.height.unwrap_or(settings.height);
    settings.points_per_frame = args.points_per_frame;
    settings.motion_blur_samples = args.motion_blur;
    settings.shutter = args.shutter;
    let rec = Recorder::new(&scene, settings).map_err(|e| BadInput(e.to_string()))?;
    let count = rec.frame_count();
    if args.print_frame_count {
        println!("{count}");
        return Ok(());
    }
    let frames = args.frames.clone().unwrap_or(0..count);
    if frames.end > count {
        return Err(BadInput(format!(
            "--frames {}..{} goes past the animation's {count} frames (0..{count} at {} fps)",
            frames.start, frames.end, args.fps
        ))
        .into());
    }
    let todo = record::frames_to_render(&rec, &args.output, frames.clone(), args.resume).len();
    if args.resume && todo < frames.len() {
        eprintln!("resume: {} of {} frames already complete", frames.len() - todo, frames.len());
    }
    let bar = ProgressBar::new(todo as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "record [{bar:30}] {pos}/{len} frames, {per_sec}, {elapsed_precise} elapsed, {eta} left",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let report =
        record::record(&rec, &args.output, frames.clone(), args.resume, &mut |done, _| bar.set_position(done as u64))
            .with_context(|| format!("recording {}", args.scene.display()))?;
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    eprintln!(
        "wrote {} frames to {} ({}×{}, {:.2} s, {:.2} frames/s){}",
        report.rendered.len(),
        args.output.display(),
        rec.settings().width,
        rec.settings().height,
        secs,
        report.rendered.len() as f64 / secs.max(1e-9),
        if report.skipped.is_empty() { String::new() } else { format!(", kept {} complete", report.skipped.len()) }
    );
    if let Some(video) = &args.video {
        record::encode_video(&args.output, frames, args.fps, video)?;
        eprintln!("wrote {}", video.display());
    }
    Ok(())
}

fn view(args: ViewArgs) -> anyhow::Result<()> {
    use nlifs::gpu::cpu_route::ChaosBackend;
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
    live.chaos_backend = args.chaos_backend.as_deref().and_then(ChaosBackend::parse).unwrap_or(ChaosBackend::Auto);
    let options = nlifs::viewer::ViewerOptions {
        scene: args.scene,
        live,
        exit_after_secs: args.exit_after_secs,
        screenshot: args.screenshot,
        grid_overlay: args.grid,
        play: args.play,
        log_fps: args.log_fps,
    };
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
    // Sampled along the whole timeline, for animated scenes.
    let timeline = nlifs::scene::timeline_check::check_timeline(&scene, TIMELINE_SAMPLES_PER_INTERVAL);
    if json {
        let mut value = serde_json::to_value(&report)?;
        if let (Some(check), Some(obj)) = (&timeline, value.as_object_mut()) {
            obj.insert("timeline".into(), serde_json::to_value(check)?);
        }
        println!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    let d = scene.domain.dims();
    println!(
        "{} ({}D, grid {}×{}×{}, probabilities: {})",
        scene.name, report.dimension, d[0], d[1], d[2], report.probability_mode
    );
    if !scene.description.is_empty() {
        println!("{}", scene.description);
    }
    println!(
        "{:<12} {:<8} {:>10} {:>15} {:>10} {:>11}",
        "function", "kind", "grid_ratio", "lipschitz_bound", "contained", "probability"
    );
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
    if let Some(check) = timeline {
        print!(
            "timeline: {}, {:.3} s, {} keys; checked at {} times (keys and {} between each): ",
            check.loop_mode, check.duration_secs, check.keys, check.samples, TIMELINE_SAMPLES_PER_INTERVAL
        );
        if check.problems.is_empty() {
            println!("contractive and contained throughout");
        } else {
            println!("{} problems", check.problems.len());
            for p in &check.problems {
                println!("    {p}");
            }
        }
    }
    Ok(())
}

/// Samples strictly between neighbouring keys for the timeline check of `nlifs info`.
const TIMELINE_SAMPLES_PER_INTERVAL: usize = 8;

fn render(args: RenderArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    let mut settings = scene.render_at(args.time);
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
            nlifs::gpu::render::render_gpu(ctx, &scene, args.time, &settings, None)
                .map_err(|e| match e {
                    nlifs::gpu::GpuError::NoFunctions => anyhow::Error::new(BadInput(e.to_string())),
                    e => e.into(),
                })?
                .image
        }
        None => {
            render_cpu(&scene, args.time, &settings, None, &|d, _| bar.set_position(d))
                .map_err(|e| BadInput(e.to_string()))?
                .image
        }
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
    write_atomic(output, |w| {
        if glb { export::write_glb_points(w, &pts, &colors) } else { export::write_ply(w, &pts, &colors) }
    })
    .with_context(|| format!("cannot write {}", output.display()))?;
    eprintln!("wrote {} ({} points)", output.display(), pts.len());
    Ok(())
}

fn bench_cpu(path: &Path, points: u64, repeats: usize) -> anyhow::Result<()> {
    let scene = load(path)?;
    eprintln!("CPU chaos game, one thread, {} ({points} points, best of {repeats})", scene.name);
    let r = nlifs::bench::cpu(&scene, points, 1920, 1080, repeats.max(1));
    println!("map only:                 {:8.1} M points/s", r.map_points_per_sec / 1e6);
    for (mode, rate) in r.splat_points_per_sec {
        println!("map + splat 1920x1080 {:<8} {:8.1} M points/s", mode.name(), rate / 1e6);
    }
    Ok(())
}
