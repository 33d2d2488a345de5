//! `nlifs render FILE.flame -o OUT.png`: a flam3 flame rendered as flam3-render renders it
//! (size, camera, quality and tone from the file), and `nlifs bench flame FILE`, the same
//! flames through `nlifs render` and through `flam3-render` side by side in CPU seconds.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::Context;

use nlifs::flame::Flame;
use nlifs::flame::render::{FlameImage, sample_count};

use super::{BadInput, probe_output, progress_bar};

/// What `nlifs render` was asked for a flame file.
pub struct FlameRequest<'a> {
    pub file: &'a Path,
    pub output: &'a Path,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub quality: Option<f64>,
    pub seed: Option<u32>,
    pub threads: Option<usize>,
    pub index: Option<usize>,
    pub name: Option<&'a str>,
}

/// The seed of a flame render without `--seed`.
const DEFAULT_SEED: u32 = 1;

/// The flame chosen by `--index` / `--name` (the first without either).
fn choose(file: &Path, flames: Vec<Flame>, index: Option<usize>, name: Option<&str>) -> anyhow::Result<Flame> {
    let count = flames.len();
    if let Some(name) = name {
        let names: Vec<String> = flames.iter().map(|f| format!("`{}`", f.name)).collect();
        return flames.into_iter().find(|f| f.name == name).ok_or_else(|| {
            BadInput(format!("{} has no flame named `{name}` (its flames: {})", file.display(), names.join(", ")))
                .into()
        });
    }
    let k = index.unwrap_or(0);
    flames.into_iter().nth(k).ok_or_else(|| {
        BadInput(format!("--index {k}: {} has {count} flame(s), numbered from 0", file.display())).into()
    })
}

/// `flame` with the command line's size and quality: a new size keeps the picture's width in
/// view (its height's with `--height` alone), as flam3-render's `ss` scales size and scale.
fn with_overrides(mut flame: Flame, req: &FlameRequest) -> anyhow::Result<Flame> {
    let [w, h] = flame.size;
    let ratio = match (req.width, req.height) {
        (Some(nw), _) => f64::from(nw) / f64::from(w.max(1)),
        (None, Some(nh)) => f64::from(nh) / f64::from(h.max(1)),
        (None, None) => 1.0,
    };
    flame.scale *= ratio;
    flame.size = [req.width.unwrap_or(w), req.height.unwrap_or(h)];
    if let Some(q) = req.quality {
        if !(q > 0.0 && q.is_finite()) {
            return Err(BadInput(format!("--quality {q}: it must be a number greater than 0")).into());
        }
        flame.quality = q;
    }
    Ok(flame)
}

pub fn render(req: FlameRequest) -> anyhow::Result<()> {
    let ext = req.output.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("png") {
        return Err(BadInput(format!("{}: a flame renders to a .png file", req.output.display())).into());
    }
    let read = nlifs::flame::read_file(req.file).map_err(|e| BadInput(e.to_string()))?;
    for warning in &read.warnings {
        eprintln!("warning: {warning}");
    }
    let count = read.flames.len();
    let flame = with_overrides(choose(req.file, read.flames, req.index, req.name)?, &req)?;
    if count > 1 && req.index.is_none() && req.name.is_none() {
        let which =
            if flame.name.is_empty() { "the first".to_string() } else { format!("the first, `{}`", flame.name) };
        eprintln!(
            "note: {} holds {count} flames; this renders {which} (--index K or --name N for another; \
             `nlifs info {}` lists them)",
            req.file.display(),
            req.file.display()
        );
    }
    probe_output(req.output)?;
    let seed = req.seed.unwrap_or(DEFAULT_SEED);
    let start = std::time::Instant::now();
    let samples = sample_count(&flame);
    let bar = progress_bar(samples, "flame");
    let work = || nlifs::flame::render::render(&flame, seed, &|n| bar.inc(n));
    let result = match req.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the render threads")?
            .install(work),
        None => work(),
    };
    bar.finish_and_clear();
    let image = result.map_err(|e| BadInput(format!("{}: flame `{}`: {e}", req.file.display(), flame.name)))?;
    write_png(req.output, &image)?;
    eprintln!(
        "wrote {} ({}×{}, {} samples, {:.2} s)",
        req.output.display(),
        image.width,
        image.height,
        image.samples,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn write_png(path: &Path, image: &FlameImage) -> anyhow::Result<()> {
    let img = image::RgbaImage::from_raw(image.width, image.height, image.rgba.clone())
        .context("the rendered image has the wrong size")?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).context("cannot encode the PNG")?;
    nlifs::io::write_atomic(path, |w| w.write_all(&bytes)).with_context(|| format!("cannot write {}", path.display()))
}

/// `nlifs bench flame FILE`: every flame of the file rendered once by `nlifs render` on one
/// thread and on all threads, and by `flam3-render` on one thread (`nthreads=1`), each a child
/// process; CPU seconds of each whole process, samples per CPU second, and the ratio of nlifs
/// to flam3 at one thread each (the headline) and with nlifs on all threads.
pub fn bench(file: &Path, out: &Path) -> anyhow::Result<()> {
    let read = nlifs::flame::read_file(file).map_err(|e| BadInput(e.to_string()))?;
    let samples: u64 = read.flames.iter().map(sample_count).sum();
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let exe = std::env::current_exe().context("cannot find the nlifs executable")?;
    // CPU seconds of the children and wall seconds.
    let child_cpu = |cmd: &mut Command, what: &str| -> anyhow::Result<(f64, f64)> {
        let before = nlifs::cpu_time::cpu_secs().1;
        let start = std::time::Instant::now();
        let status =
            cmd.stdout(Stdio::null()).stderr(Stdio::null()).status().with_context(|| format!("cannot run {what}"))?;
        if !status.success() {
            anyhow::bail!("{what} failed ({status})");
        }
        Ok((nlifs::cpu_time::cpu_secs().1 - before, start.elapsed().as_secs_f64()))
    };
    let all_threads = rayon::current_num_threads();
    let ours = |threads: usize| -> anyhow::Result<(f64, f64)> {
        let (mut cpu, mut wall) = (0.0, 0.0);
        for k in 0..read.flames.len() {
            let png: PathBuf = out.join(format!("nlifs-{k}-t{threads}.png"));
            let (c, w) = child_cpu(
                Command::new(&exe)
                    .arg("render")
                    .arg(file)
                    .arg("-o")
                    .arg(&png)
                    .arg("--index")
                    .arg(k.to_string())
                    .arg("--threads")
                    .arg(threads.to_string()),
                "nlifs render",
            )?;
            cpu += c;
            wall += w;
        }
        Ok((cpu, wall))
    };
    // The route of `nlifs view` and `nlifs record` of a flame: the flame imported as a scene
    // (not timed) and rendered by nlifs's own chaos game, on one thread.
    let imported = || -> anyhow::Result<(f64, f64)> {
        let (mut cpu, mut wall) = (0.0, 0.0);
        for k in 0..read.flames.len() {
            let scene = out.join(format!("scene-{k}.toml"));
            let import = Command::new(&exe)
                .args(["import", "flame"])
                .arg(file)
                .args(["--index", &k.to_string(), "-o"])
                .arg(&scene)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .context("cannot run nlifs import")?;
            if !import.success() {
                anyhow::bail!("nlifs import flame failed ({import})");
            }
            let png = out.join(format!("scene-{k}.png"));
            let render = &mut Command::new(&exe);
            render.env("RAYON_NUM_THREADS", "1").arg("render").arg(&scene).arg("-o").arg(&png);
            let (c, w) = child_cpu(render, "nlifs render SCENE.toml")?;
            cpu += c;
            wall += w;
        }
        Ok((cpu, wall))
    };
    let (one_cpu, one_wall) = ours(1)?;
    let (all_cpu, all_wall) = ours(all_threads)?;
    let (scene_cpu, scene_wall) = imported()?;
    println!(
        "{}: {} flame(s), {samples} samples; CPU seconds of the whole processes, one run each",
        file.display(),
        read.flames.len()
    );
    let rate = |secs: f64| if secs > 0.0 { samples as f64 / secs } else { f64::INFINITY };
    let row = |what: &str, cpu: f64, wall: f64| {
        println!("  {what:<28} {cpu:8.3} s CPU {wall:8.3} s wall {:14.0} samples/CPU-s", rate(cpu));
    };
    let refusals: Vec<_> = read
        .flames
        .iter()
        .enumerate()
        .filter_map(|(i, f)| Some((i, f, nlifs::flame::render::lanes_refusal(f)?)))
        .collect();
    println!(
        "  chaos game: f32 lanes for {} of {} flame(s), the f64 game for the others (NLIFS_FLAME_F64=1: all)",
        read.flames.len() - refusals.len(),
        read.flames.len()
    );
    for (i, flame, why) in refusals {
        println!("    flame {i} ({}): the f64 game ({why})", flame.name);
    }
    row("nlifs (1 thread)", one_cpu, one_wall);
    row(&format!("nlifs ({all_threads} threads)"), all_cpu, all_wall);
    row("nlifs, imported (1 thread)", scene_cpu, scene_wall);
    let theirs = child_cpu(
        Command::new("flam3-render")
            .env("nthreads", "1")
            .env("isaac_seed", "1")
            .env("verbose", "0")
            .env("format", "png")
            .env("in", file)
            .env("out", out.join("flam3.png")),
        "flam3-render (apt install flam3-utils)",
    );
    match theirs {
        Ok((cpu, wall)) => {
            row("flam3-render (1 thread)", cpu, wall);
            let ratio = |ours: f64| cpu / ours.max(1e-9);
            println!(
                "  nlifs / flam3, samples per CPU second: {:.2}× (1 thread each), {:.2}× (nlifs on {all_threads} threads), {:.2}× (imported, 1 thread)",
                ratio(one_cpu),
                ratio(all_cpu),
                ratio(scene_cpu)
            );
        }
        Err(e) => println!("  flam3-render: not measured ({e:#})"),
    }
    Ok(())
}
