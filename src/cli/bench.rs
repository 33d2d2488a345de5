//! `nlifs bench`: throughput figures for the documents. The ray tracer against POV-Ray on the
//! same spheres, the GPU chaos game, a 1920×1080 recording on the CPU and the GPU, the CPU
//! chaos game on one core, and how much of an attractor a budget of points covers under each
//! probability choice.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::Context;
use clap::Subcommand;

use nlifs::io::save_png;
use nlifs::raytrace::{self, RaytraceSettings};

use super::export::write_pov;
use super::{BadInput, load};

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
    /// Frames per second of `nlifs record` at 1920×1080, the chaos game on the CPU and on the
    /// GPU (any adapter, a software one included, to measure it).
    Record {
        #[arg(default_value = "scenes/twist-anim.toml")]
        scene: PathBuf,
        /// Frames to record (after one untimed frame).
        #[arg(long, default_value_t = 4)]
        frames: u32,
        #[arg(long, default_value_t = 1920)]
        width: u32,
        #[arg(long, default_value_t = 1080)]
        height: u32,
        /// Points per frame (default: the scene's).
        #[arg(long, value_parser = super::args::point_count)]
        points_per_frame: Option<u64>,
        /// Where the frames go (one folder per backend).
        #[arg(long, default_value = "target/bench-record")]
        out: PathBuf,
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
    /// The solid look's cost in `nlifs render`: a still's preparation (bounds and camera) and
    /// chaos game + splat (closest mode, all threads), then its resolve in the paper look, with shading only and in the solid look
    /// (shading + occlusion), and the PNG write; of each part the best wall time of R runs and
    /// the mean process CPU time, and what each look adds in % of the whole render (chaos game,
    /// preparation, chaos game, resolve and write).
    Look {
        #[arg(default_value = "scenes/plant2.toml")]
        scene: PathBuf,
        #[arg(long, default_value_t = 1920)]
        width: u32,
        #[arg(long, default_value_t = 1080)]
        height: u32,
        #[arg(long, default_value_t = 4_000_000)]
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
    /// CPU render accumulation on all threads: per-thread framebuffers against one shared
    /// framebuffer, points/s per splat mode, side by side.
    Render(super::bench_render::BenchRenderArgs),
}

pub fn run(command: BenchCommand) -> anyhow::Result<()> {
    match command {
        BenchCommand::Raytrace { scenes, width, height, spp, no_povray, out } => {
            raytrace(&scenes, width, height, spp, no_povray, &out)
        }
        BenchCommand::Gpu { scene, points, steps, frames } => {
            let scene = load(&scene)?;
            let report = nlifs::gpu::bench::run(&scene, points, steps, frames)?;
            println!("{report}");
            Ok(())
        }
        BenchCommand::Cpu { scene, points, repeats } => cpu(&scene, points, repeats),
        BenchCommand::Record { scene, frames, width, height, points_per_frame, out } => {
            record(&scene, frames, width, height, points_per_frame, &out)
        }
        BenchCommand::Render(args) => super::bench_render::run(args),
        BenchCommand::Look { scene, width, height, points, repeats } => look(&scene, width, height, points, repeats),
        BenchCommand::Coverage { scene, budget, reference, size } => {
            let s = load(&scene)?;
            println!("{}: share of the attractor's {size}x{size} pixels lit by {budget} points", s.name);
            let shares = nlifs::bench::coverage(&s, budget, reference, size).map_err(|e| BadInput(e.to_string()))?;
            for (name, share) in shares {
                println!("  {name:<14} {:6.2} %", 100.0 * share);
            }
            Ok(())
        }
    }
}

fn record(
    path: &Path,
    frames: u32,
    width: u32,
    height: u32,
    points_per_frame: Option<u64>,
    out: &Path,
) -> anyhow::Result<()> {
    let scene = load(path)?;
    let settings = nlifs::record::RecordSettings {
        width,
        height,
        points_per_frame,
        ..nlifs::record::RecordSettings::for_scene(&scene)
    };
    let points = points_per_frame.unwrap_or(scene.render.points);
    println!("record {}: {width}×{height}, {points} points per frame, {frames} frames", scene.name);
    for gpu in [false, true] {
        let ctx = if gpu {
            match nlifs::gpu::GpuContext::headless() {
                Ok(ctx) => Some(ctx),
                Err(e) => {
                    println!("  gpu: skipped ({e})");
                    continue;
                }
            }
        } else {
            None
        };
        let dir = out.join(if gpu { "gpu" } else { "cpu" });
        let r =
            nlifs::bench::record(&scene, settings.clone(), frames, ctx, &dir).map_err(|e| BadInput(e.to_string()))?;
        println!(
            "  {:<40} {:6.3} frames/s ({:.2} s wall, {:.2} s process CPU for {} frames) -> {}",
            r.backend,
            r.frames as f64 / r.secs,
            r.secs,
            r.cpu_secs,
            r.frames,
            dir.display()
        );
    }
    Ok(())
}

fn cpu(path: &Path, points: u64, repeats: usize) -> anyhow::Result<()> {
    let scene = load(path)?;
    eprintln!("CPU chaos game, one thread, {} ({points} points, best of {repeats})", scene.name);
    let r = nlifs::bench::cpu(&scene, points, 1920, 1080, repeats.max(1)).map_err(|e| BadInput(e.to_string()))?;
    println!("map only:                 {:8.1} M points/s", r.map_points_per_sec / 1e6);
    for (mode, rate) in r.splat_points_per_sec {
        println!("map + splat 1920x1080 {:<8} {:8.1} M points/s", mode.name(), rate / 1e6);
    }
    Ok(())
}

/// `nlifs bench look`: see [`BenchCommand::Look`].
fn look(path: &Path, width: u32, height: u32, points: u64, repeats: usize) -> anyhow::Result<()> {
    use nlifs::resolve::{ResolveStyle, resolve_image};
    use nlifs::scene::spec::SplatMode;
    use nlifs::shot::{Framing, Shot};

    let scene = load(path)?;
    let mut settings = scene.render_at(0.0);
    (settings.width, settings.height, settings.points, settings.mode) = (width, height, points, SplatMode::Closest);
    let prepare = || Shot::prepare(&scene, 0.0, &settings, Framing::Fit, None).map_err(|e| BadInput(e.to_string()));
    let shot = prepare()?;
    // The splat without the shadow map (the solid look without shadows), then with it.
    let no_shadows = ResolveStyle { shadows: 0.0, ..ResolveStyle::SOLID };
    let shot_without_shadows = shot.clone().with_style(no_shadows);
    let shot = shot.with_style(ResolveStyle::SOLID);
    // The best wall seconds of `repeats` runs of `f`, and their mean process CPU seconds (the
    // CPU clock ticks at 10 ms: a mean over many runs resolves finer).
    let repeats = repeats.max(1);
    let best = |f: &mut dyn FnMut()| {
        let mut wall = f64::INFINITY;
        let c = cpu_secs().0;
        for _ in 0..repeats {
            let t = Instant::now();
            f();
            wall = wall.min(t.elapsed().as_secs_f64());
        }
        (wall, (cpu_secs().0 - c) / repeats as f64)
    };
    // The render's preparation: the attractor's bounds and the camera fitted to a sample.
    let prepared = best(&mut || drop(prepare()));
    let splat_without_shadows = best(&mut || drop(shot_without_shadows.splat(|| {})));
    let mut framebuffer = None;
    let splat = best(&mut || framebuffer = Some(shot.splat(|| {})));
    let Some(framebuffer) = framebuffer else { return Ok(()) };
    println!(
        "{}: {width}×{height}, {points} points, closest mode, {} threads; best wall time of {repeats} runs, mean process CPU",
        scene.name,
        rayon::current_num_threads()
    );
    println!("  prepare (bounds, camera) {:8.1} ms wall {:8.1} ms CPU", 1e3 * prepared.0, 1e3 * prepared.1);
    println!(
        "  chaos game + splat       {:8.1} ms wall {:8.1} ms CPU",
        1e3 * splat_without_shadows.0,
        1e3 * splat_without_shadows.1
    );
    println!(
        "  + shadow map splat       {:8.1} ms wall {:8.1} ms CPU ({}² texels)",
        1e3 * splat.0,
        1e3 * splat.1,
        shot.view.shadow.map_or(0, |s| s.side_px)
    );
    // `nlifs render` also writes its picture: the PNG of the paper resolve, written as the
    // render writes it, counts in the render's time (a scratch file, removed after).
    let paper_image = resolve_image(&framebuffer, &shot.camera, &ResolveStyle::PAPER);
    let scratch = std::env::temp_dir().join(format!("nlifs-bench-look-{}.png", std::process::id()));
    let write = best(&mut || {
        if let Err(e) = nlifs::output::png::save_rgb8(&scratch, &paper_image, None) {
            eprintln!("warning: could not write {}: {e}", scratch.display());
        }
    });
    let _ = std::fs::remove_file(&scratch);
    println!("  write PNG                {:8.1} ms wall {:8.1} ms CPU", 1e3 * write.0, 1e3 * write.1);
    let shading_only = ResolveStyle { occlusion: 0.0, shadows: 0.0, ..ResolveStyle::SOLID };
    // Each look's render: preparation, the splat it needs (with the shadow map where it casts
    // shadows), its resolve and the write; its cost is what it adds to the paper look's render.
    let mut paper_render = (0.0, 0.0);
    for (name, style) in [
        ("paper", ResolveStyle::PAPER),
        ("shading only", shading_only),
        ("solid, no shadow", no_shadows),
        ("solid", ResolveStyle::SOLID),
    ] {
        let r = best(&mut || drop(resolve_image(&framebuffer, &shot.camera, &style)));
        let splat = if style.shadows > 0.0 { splat } else { splat_without_shadows };
        let render = (prepared.0 + splat.0 + r.0 + write.0, prepared.1 + splat.1 + r.1 + write.1);
        if name == "paper" {
            paper_render = render;
        }
        let look = (render.0 - paper_render.0, render.1 - paper_render.1);
        println!(
            "  resolve, {name:<16} {:8.1} ms wall {:8.1} ms CPU; the look adds {:7.1} ms wall ({:4.1} % of its render) {:7.1} ms CPU ({:4.1} %)",
            1e3 * r.0,
            1e3 * r.1,
            1e3 * look.0,
            100.0 * look.0 / render.0,
            1e3 * look.1,
            100.0 * look.1 / render.1.max(1e-9),
        );
    }
    Ok(())
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

fn raytrace(scenes: &Path, width: u32, height: u32, spp: u32, no_povray: bool, out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out)?;
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
