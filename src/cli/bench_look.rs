//! `nlifs bench look`: what the solid look costs in `nlifs render`. First the whole command,
//! run as a child process in each look (what a user waits for: start, scene, bounds, chaos game,
//! splats, resolve, PNG), then the parts in this process, to say where the time goes.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use nlifs::cpu_time::cpu_secs;
use nlifs::output::png_rows::{RowLayout, write_rows};
use nlifs::resolve::{ResolveStyle, resolve_image};
use nlifs::scene::spec::SplatMode;
use nlifs::shot::{Framing, Shot};

use super::{BadInput, load};

/// The looks compared: name, `nlifs render` flags, style.
fn looks() -> [(&'static str, &'static [&'static str], ResolveStyle); 4] {
    [
        ("paper", &["--look", "paper"], ResolveStyle::PAPER),
        (
            "shading only",
            &["--look", "solid", "--occlusion", "0", "--shadows", "0"],
            ResolveStyle { occlusion: 0.0, shadows: 0.0, ..ResolveStyle::SOLID },
        ),
        (
            "solid, no shadows",
            &["--look", "solid", "--shadows", "0"],
            ResolveStyle { shadows: 0.0, ..ResolveStyle::SOLID },
        ),
        ("solid", &["--look", "solid"], ResolveStyle::SOLID),
    ]
}

/// The best wall seconds of `repeats` runs of `f` in this process, and its mean CPU seconds
/// per run.
fn best(repeats: usize, f: &mut dyn FnMut() -> anyhow::Result<()>) -> anyhow::Result<(f64, f64)> {
    let cpu = || cpu_secs().0;
    let (mut wall, c) = (f64::INFINITY, cpu());
    for _ in 0..repeats {
        let t = Instant::now();
        f()?;
        wall = wall.min(t.elapsed().as_secs_f64());
    }
    Ok((wall, (cpu() - c) / repeats as f64))
}

pub fn run(path: &Path, width: u32, height: u32, points: u64, repeats: usize) -> anyhow::Result<()> {
    let scene = load(path)?;
    let repeats = repeats.max(1);
    let scratch = std::env::temp_dir().join(format!("nlifs-bench-look-{}.png", std::process::id()));
    println!(
        "{}: {width}×{height}, {points} points, closest mode, {} threads",
        scene.name,
        rayon::current_num_threads()
    );

    // The whole command, as a user runs it: rounds of one run per look, the looks' order
    // rotating from round to round, so that each look's cost is its render's time minus the
    // paper look's time in the same round (the machine's load drifts between rounds; it
    // changes little within one).
    println!("nlifs render (the whole command, on the CPU), {repeats} rounds of one run per look:");
    let exe = std::env::current_exe()?;
    let size = [width.to_string(), height.to_string(), points.to_string()];
    let looks = looks();
    let render = |name: &str, flags: &[&str]| -> anyhow::Result<(f64, f64)> {
        let (cpu, t) = (cpu_secs().1, Instant::now());
        let out = Command::new(&exe)
            .arg("render")
            .arg(path)
            .args(["--width", &size[0], "--height", &size[1], "--points", &size[2], "--mode", "closest"])
            .args(["--backend", "cpu"])
            .args(flags)
            .arg("-o")
            .arg(&scratch)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .output()?;
        if !out.status.success() {
            anyhow::bail!("nlifs render {name} failed: {}", String::from_utf8_lossy(&out.stderr));
        }
        Ok((t.elapsed().as_secs_f64(), cpu_secs().1 - cpu))
    };
    // One untimed run first: the executable and the scene into the page cache.
    render(looks[0].0, looks[0].1)?;
    let mut walls = vec![Vec::with_capacity(repeats); looks.len()];
    let mut cpus = vec![0.0; looks.len()];
    for round in 0..repeats {
        for k in 0..looks.len() {
            let i = (k + round) % looks.len();
            let (wall, cpu) = render(looks[i].0, looks[i].1)?;
            walls[i].push(wall);
            cpus[i] += cpu / repeats as f64;
        }
    }
    let _ = std::fs::remove_file(&scratch);
    for (i, (name, _, _)) in looks.iter().enumerate() {
        let median = quantile(&walls[i], 0.5);
        let best = walls[i].iter().copied().fold(f64::INFINITY, f64::min);
        print!("  {name:<18} {:7.1} ms wall (best {:6.1}) {:7.1} ms CPU", 1e3 * median, 1e3 * best, 1e3 * cpus[i]);
        if i > 0 {
            // The share of its render the look adds, round by round.
            let shares: Vec<f64> = walls[i].iter().zip(&walls[0]).map(|(w, p)| (w - p) / w).collect();
            let adds_cpu = cpus[i] - cpus[0];
            print!(
                "; adds {:5.1} ms wall: {:4.1} % of its render (middle half of the rounds {:4.1}–{:4.1} %), {:5.1} ms CPU ({:4.1} %)",
                1e3 * (median - quantile(&walls[0], 0.5)),
                100.0 * quantile(&shares, 0.5),
                100.0 * quantile(&shares, 0.25),
                100.0 * quantile(&shares, 0.75),
                1e3 * adds_cpu,
                100.0 * adds_cpu / cpus[i].max(1e-9),
            );
        }
        println!();
    }

    // The parts, in this process.
    let mut settings = scene.render_at(0.0);
    (settings.width, settings.height, settings.points, settings.mode) = (width, height, points, SplatMode::Closest);
    let prepare = || Shot::prepare(&scene, 0.0, &settings, Framing::Fit, None).map_err(|e| BadInput(e.to_string()));
    let shot = prepare()?;
    let no_shadows = shot.clone().with_style(ResolveStyle { shadows: 0.0, ..ResolveStyle::SOLID });
    let shot = shot.with_style(ResolveStyle::SOLID);
    println!("parts (in this process; best wall time of {repeats} runs, mean CPU):");
    let part = |name: &str, (wall, cpu): (f64, f64), note: &str| {
        println!("  {name:<28} {:7.1} ms wall {:7.1} ms CPU{note}", 1e3 * wall, 1e3 * cpu);
    };
    part(
        "prepare (bounds, camera)",
        best(repeats, &mut || {
            prepare()?;
            Ok(())
        })?,
        "",
    );
    part(
        "chaos game + splat",
        best(repeats, &mut || {
            no_shadows.splat(|| {});
            Ok(())
        })?,
        "",
    );
    let mut framebuffer = None;
    let splat = best(repeats, &mut || {
        framebuffer = Some(shot.splat(|| {}));
        Ok(())
    })?;
    let side = shot.view.shadow.map_or(0, |s| s.side_px);
    part("  with the shadow map's", splat, &format!(" ({side}² texels)"));
    let Some(framebuffer) = framebuffer else { return Ok(()) };
    for (name, _, style) in looks {
        let r = best(repeats, &mut || {
            resolve_image(&framebuffer, &shot.camera, &style);
            Ok(())
        })?;
        part(&format!("resolve, {name}"), r, "");
    }
    // The PNG as `nlifs render` writes it: streamed rows, adaptive filters (a scratch file).
    let image = resolve_image(&framebuffer, &shot.camera, &ResolveStyle::PAPER);
    let row_bytes = 3 * width as usize;
    let write = best(repeats, &mut || {
        write_rows(&scratch, width, height, RowLayout::Rgb8, None, |y, out| {
            out.copy_from_slice(&image.as_raw()[y as usize * row_bytes..][..row_bytes]);
        })
        .map_err(anyhow::Error::from)
    });
    let _ = std::fs::remove_file(&scratch);
    part("write PNG", write?, "");
    Ok(())
}

/// The `q` quantile of `values` (0.5: the median), interpolated between the sorted values.
fn quantile(values: &[f64], q: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    if sorted.is_empty() {
        return f64::NAN;
    }
    let at = q * (sorted.len() - 1) as f64;
    let (low, high) = (at.floor() as usize, at.ceil() as usize);
    sorted[low] + (sorted[high] - sorted[low]) * (at - low as f64)
}
