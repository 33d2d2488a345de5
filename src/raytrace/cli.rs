//! The ray tracer's part of the command line (`snapshot`, `export mesh`, `export pov`,
//! `bench raytrace`), compiled into the binary only: argument parsing, progress bars and
//! files; the work is done by `nlifs::raytrace`.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};

use nlifs::io::{save_png, write_atomic};
use nlifs::raytrace::{self, ColorMode, Initial, RaytraceSettings};
use nlifs::scene::Scene;

use super::{BadInput, check_png, load, progress_bar};

#[derive(Clone, Copy, ValueEnum)]
pub enum ColorArg {
    /// Per-function colour (the outermost function of each leaf).
    Function,
    /// Colour by depth.
    Depth,
}

#[derive(Args)]
pub struct GeometryArgs {
    /// n of W^n(A) (with --adaptive: the most refinement).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(0..=16))]
    pub depth: u32,
    /// Initial object A: `sphere`, `grid` (the initial grid's surface) or a .glb/.gltf file.
    #[arg(long, default_value = "sphere")]
    pub initial: String,
    /// Scene time in seconds.
    #[arg(long, default_value_t = 0.0)]
    pub time: f64,
}

#[derive(Args)]
pub struct SnapshotArgs {
    pub scene: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    #[arg(long, default_value_t = 960, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    #[arg(long, default_value_t = 720, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// Samples per pixel (stratified).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub spp: u32,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Stop refining where a node projects smaller than a pixel (--depth becomes the cap).
    #[arg(long)]
    pub adaptive: bool,
    /// With --adaptive: stop where a node's sphere projects smaller than this many pixels.
    #[arg(long, default_value_t = 1.0)]
    pub stop_pixels: f32,
    #[arg(long, value_enum, default_value = "function")]
    pub color: ColorArg,
    /// No shadow rays.
    #[arg(long)]
    pub no_shadows: bool,
    /// No ground plane.
    #[arg(long)]
    pub no_ground: bool,
    /// Background as sRGB hex (#rrggbb); default: the scene's.
    #[arg(long)]
    pub background: Option<String>,
}

#[derive(Args)]
pub struct ExportMeshArgs {
    pub scene: PathBuf,
    /// Output .glb.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub geometry: GeometryArgs,
}

#[derive(Args)]
pub struct ExportPovArgs {
    pub scene: PathBuf,
    /// Output .pov.
    #[arg(short, long)]
    pub output: PathBuf,
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(0..=16))]
    pub depth: u32,
    #[arg(long, default_value_t = 0.0)]
    pub time: f64,
}

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Rays per second and 1920×1080 stills of tapering (n = 6) and plant2 (n = 7), side by side
    /// with POV-Ray 3.7 rendering the same spheres.
    Raytrace {
        /// Directory with the paper scenes.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        #[arg(long, default_value_t = 1920)]
        width: u32,
        #[arg(long, default_value_t = 1080)]
        height: u32,
        /// Samples per pixel (POV-Ray: +AM1 +A0.0 +R2, 1 + 4 rays per supersampled pixel).
        #[arg(long, default_value_t = 5)]
        spp: u32,
        /// Skip POV-Ray.
        #[arg(long)]
        no_povray: bool,
        /// Where to keep the images and .pov files.
        #[arg(long, default_value = "target/bench-raytrace")]
        out: PathBuf,
    },
}

fn parse_initial(text: &str) -> anyhow::Result<Initial> {
    let initial = Initial::parse(text);
    if let Initial::Gltf(path) = &initial {
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
        if !matches!(ext.as_deref(), Some("glb" | "gltf")) {
            return Err(BadInput(format!("--initial {text}: expected sphere, grid or a .glb/.gltf file")).into());
        }
    }
    Ok(initial)
}

fn parse_hex(text: &str) -> anyhow::Result<[f32; 3]> {
    let h = text.trim_start_matches('#');
    let bad = || BadInput(format!("--background {text}: expected #rrggbb"));
    if h.len() != 6 {
        return Err(bad().into());
    }
    let v = u32::from_str_radix(h, 16).map_err(|_| bad())?;
    let srgb = [(v >> 16) & 255, (v >> 8) & 255, v & 255].map(|c| c as f32 / 255.0);
    Ok(nlifs::color::srgb_to_linear(srgb))
}

pub fn snapshot(args: SnapshotArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    check_png(&args.output)?;
    let settings = RaytraceSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        depth: args.geometry.depth,
        adaptive: args.adaptive,
        stop_pixels: args.stop_pixels,
        initial: parse_initial(&args.geometry.initial)?,
        color_mode: match args.color {
            ColorArg::Function => ColorMode::Function,
            ColorArg::Depth => ColorMode::Depth,
        },
        shadows: !args.no_shadows,
        ground: !args.no_ground,
        seed: scene.render.seed,
        background: args.background.as_deref().map(parse_hex).transpose()?,
    };
    let bar = progress_bar(args.height as u64, "trace");
    let cancel = AtomicBool::new(false);
    let traced = raytrace::render(&scene, args.geometry.time, None, &settings, &|d, _| bar.set_position(d), &cancel)?;
    bar.finish_and_clear();
    save_png(&args.output, &traced.image).with_context(|| format!("cannot write {}", args.output.display()))?;
    let rays = traced.stats.primary_rays + traced.stats.shadow_rays;
    eprintln!(
        "wrote {} ({}×{}, {} spp, {} leaves to depth {}, {} nodes; build {:.2} s, trace {:.2} s, {:.2} Mrays/s)",
        args.output.display(),
        args.width,
        args.height,
        args.spp,
        traced.leaf_count,
        traced.max_depth,
        traced.node_count,
        traced.build_secs,
        traced.trace_secs,
        rays as f64 / traced.trace_secs / 1e6
    );
    Ok(())
}

pub fn export_mesh(args: ExportMeshArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    if !args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
        return Err(BadInput(format!("output {} must end in .glb", args.output.display())).into());
    }
    let ifs = scene.at(args.geometry.time);
    let initial = parse_initial(&args.geometry.initial)?;
    let h = raytrace::build_fixed(&ifs, &initial, args.geometry.depth)?;
    let colors: Vec<[f32; 3]> = ifs.active().iter().map(|&i| ifs.functions[i].color).collect();
    let names: Vec<String> = ifs.active().iter().map(|&i| ifs.functions[i].name.clone()).collect();
    write_atomic(&args.output, |w| raytrace::export::write_glb_mesh(w, &h, &colors, &names))
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    eprintln!("wrote {} ({} leaves of W^{}(A))", args.output.display(), h.leaf_count, args.geometry.depth);
    Ok(())
}

pub fn export_pov(args: ExportPovArgs) -> anyhow::Result<()> {
    let scene = load(&args.scene)?;
    write_pov(&scene, args.time, args.depth, args.width, args.height, &args.output)?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

/// Writes the .pov of W^depth(sphere) with the camera, lights and ground the tracer uses.
fn write_pov(
    scene: &Scene,
    t_secs: f64,
    depth: u32,
    width: u32,
    height: u32,
    output: &Path,
) -> anyhow::Result<raytrace::hierarchy::Hierarchy> {
    let ifs = scene.at(t_secs);
    let h = raytrace::build_fixed(&ifs, &Initial::Sphere, depth)?;
    let camera = scene.camera_for((h.bounds.0.as_dvec3(), h.bounds.1.as_dvec3()));
    let settings = RaytraceSettings { width, height, depth, ..Default::default() };
    let shading = raytrace::shading_for(scene, &ifs, &camera, &settings);
    write_atomic(output, |w| raytrace::export::write_pov(w, &h, &camera, &shading))
        .with_context(|| format!("cannot write {}", output.display()))?;
    Ok(h)
}

/// (own, waited-for children's) CPU seconds, user + system, from /proc/self/stat (Linux; zeros
/// elsewhere). CPU time is what the comparison uses: the machine is shared, so wall-clock
/// time depends on what else runs.
fn cpu_secs() -> (f64, f64) {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else { return (0.0, 0.0) };
    // Fields after the parenthesised command name; utime is field 14 (index 11 here).
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest.split_whitespace().map(|v| v.parse().unwrap_or(0.0)).collect();
    if f.len() < 15 {
        return (0.0, 0.0);
    }
    let tick = 100.0; // USER_HZ on Linux
    ((f[11] + f[12]) / tick, (f[13] + f[14]) / tick)
}

pub fn bench(cmd: BenchCommand) -> anyhow::Result<()> {
    let BenchCommand::Raytrace { scenes, width, height, spp, no_povray, out } = cmd;
    std::fs::create_dir_all(&out)?;
    let threads = rayon::current_num_threads();
    println!(
        "machine: {} threads in rayon's pool; {width}×{height}, {spp} spp, 2 lights with shadows, ground plane",
        threads
    );
    for (name, depth) in [("tapering", 6u32), ("plant2", 7)] {
        let scene = load(&scenes.join(format!("{name}.toml")))?;
        let settings = RaytraceSettings { width, height, spp, depth, ..Default::default() };
        let cancel = AtomicBool::new(false);
        let cpu_before = cpu_secs().0;
        let traced = raytrace::render(&scene, 0.0, None, &settings, &|_, _| {}, &cancel)?;
        let cpu = cpu_secs().0 - cpu_before;
        let png = out.join(format!("{name}_n{depth}_nlifs.png"));
        save_png(&png, &traced.image)?;
        let rays = (traced.stats.primary_rays + traced.stats.shadow_rays) as f64;
        println!(
            "{name} n={depth}: {} spheres, build {:.3} s, trace {:.2} s wall, {:.2} s CPU (build + trace), {:.1} M rays ({:.2} M primary), {:.2} Mrays per CPU second  -> {}",
            traced.leaf_count,
            traced.build_secs,
            traced.trace_secs,
            cpu,
            rays / 1e6,
            traced.stats.primary_rays as f64 / 1e6,
            rays / cpu.max(1e-9) / 1e6,
            png.display()
        );
        if no_povray {
            continue;
        }
        let pov = out.join(format!("{name}_n{depth}.pov"));
        write_pov(&scene, 0.0, depth, width, height, &pov)?;
        let pov_png = out.join(format!("{name}_n{depth}_povray.png"));
        let start = Instant::now();
        let children_before = cpu_secs().1;
        let status = std::process::Command::new("povray")
            .arg(format!("+I{}", pov.display()))
            .arg(format!("+O{}", pov_png.display()))
            .args([
                format!("+W{width}"),
                format!("+H{height}"),
                "+A0.0".into(),
                "+AM1".into(),
                "+R2".into(),
                format!("+WT{threads}"),
                "-D".into(),
                "-V".into(),
                "+FN".into(),
                "-GA".into(),
            ])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .context("cannot run povray")?;
        let pov_secs = start.elapsed().as_secs_f64();
        let pov_cpu = cpu_secs().1 - children_before;
        if !status.success() {
            println!("  povray failed ({status})");
            continue;
        }
        let ours = traced.build_secs + traced.trace_secs;
        println!(
            "  POV-Ray 3.7: {pov_secs:.2} s wall, {pov_cpu:.2} s CPU (parse + bounding + trace, {threads} threads) -> {}\n  nlifs: {ours:.2} s wall, {cpu:.2} s CPU: {:.1}× faster by CPU time, {:.1}× by wall time",
            pov_png.display(),
            pov_cpu / cpu.max(1e-9),
            pov_secs / ours
        );
    }
    Ok(())
}
