//! Helpers the integration suites share (each includes this file with `mod common;`): paths in
//! the repository, running the binary, fresh temporary folders, the rule for tests that need a
//! GPU adapter, coarse normalized densities and their 6σ comparison, and image comparisons that
//! write the actual and difference images on failure and say where.
//!
//! The GPU rule: without an adapter a GPU test skips with a loud message, unless
//! `NLIFS_REQUIRE_GPU=1`, in which case a missing adapter (or tool) is a failure, so that CI on
//! lavapipe cannot pass by skipping.
#![allow(dead_code, reason = "each suite compiles this file and uses a subset of it")]

#[cfg(target_arch = "wasm32")]
pub mod browser;
pub mod window;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use nlifs::chaos_game::{CompiledIfs, ORBITS_PER_CHUNK, run_chunk};
use nlifs::gpu::GpuContext;
use nlifs::gpu::progressive::ProgressiveSettings;
use nlifs::live::{ChaosBackend, LiveSettings};
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::{Framebuffer, SplatView};

/// A path relative to the repository root.
pub fn repo_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// `scenes/<name>.toml`.
pub fn scene_path(name: &str) -> PathBuf {
    repo_path("scenes").join(format!("{name}.toml"))
}

/// The shipped scene `scenes/<name>.toml`, loaded (a load error fails the test with its message).
pub fn load_scene(name: &str) -> Scene {
    Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// The `nlifs` binary that cargo built for this test run, as a command to add arguments to.
/// Its config folder (the viewer's recent files) is one of this test process's in the
/// temporary directory, so that no test writes into the user's (a test may set its own).
pub fn nlifs_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_nlifs"));
    command.env("NLIFS_CONFIG_DIR", scratch_root().join(format!("nlifs-config-{}", std::process::id())));
    command
}

/// Runs `nlifs` with `args` to completion and returns its exit status and output.
pub fn run_nlifs(args: &[&str]) -> Output {
    nlifs_command().args(args).output().expect("start the nlifs binary")
}

/// `nlifs render` of the shipped scene `scene` in density mode at 160×120 with 20,000 points (a
/// sparse picture), with `extra` arguments, into `out`.
pub fn render_sparse_density(scene: &str, extra: &[&str], out: &str) -> Output {
    let path = scene_path(scene);
    let mut args = vec![
        "render",
        path.to_str().unwrap(),
        "--mode",
        "density",
        "--width",
        "160",
        "--height",
        "120",
        "--points",
        "20000",
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", out]);
    run_nlifs(&args)
}

/// The pixels of the image at `path` that differ from its pixel (0, 0) (the background).
pub fn lit_pixels(path: &str) -> usize {
    let img = image::open(path).unwrap().to_rgb8();
    let bg = *img.get_pixel(0, 0);
    img.pixels().filter(|px| **px != bg).count()
}

/// A test's scratch folder ([`temp_dir`]): removed when it goes out of scope, unless the test
/// is failing (then it is kept, for a look at what the test wrote).
#[derive(Debug)]
pub struct TempDir(PathBuf);

impl TempDir {
    /// Keeps the folder after the test (what it wrote is the test's product, e.g. the soak
    /// test's samples).
    pub fn keep(self) -> PathBuf {
        let path = self.0.clone();
        std::mem::forget(self);
        path
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for TempDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept {} (the test failed)", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The folder where the tests write: cargo's scratch folder for integration tests (inside the
/// target folder, so `cargo clean` removes whatever a failed or killed test left).
pub fn scratch_root() -> &'static Path {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
}

/// A fresh, empty folder `nlifs-<name>-<pid>` in [`scratch_root`] (whatever an earlier run left
/// there is removed first), removed again when the returned guard is dropped.
pub fn temp_dir(name: &str) -> TempDir {
    let dir = scratch_root().join(format!("nlifs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// Whether `NLIFS_REQUIRE_GPU=1`: a missing adapter or tool fails the test instead of skipping it.
pub fn gpu_required() -> bool {
    std::env::var("NLIFS_REQUIRE_GPU").as_deref() == Ok("1")
}

/// Whether a missing system tool (oiiotool, Slurm) fails the test instead of skipping it: `CI`
/// or `NLIFS_REQUIRE_TOOLS=1` is set, as `.ci/run` does after installing the tools.
pub fn tools_required() -> bool {
    std::env::var_os("CI").is_some() || std::env::var("NLIFS_REQUIRE_TOOLS").as_deref() == Ok("1")
}

/// Skips a test that cannot run here, loudly; fails it instead when `NLIFS_REQUIRE_GPU=1`.
pub fn skip(why: &str) {
    assert!(!gpu_required(), "NLIFS_REQUIRE_GPU=1 but {why}");
    eprintln!("\n*** SKIPPED: {why} ***\n");
}

/// A headless GPU context, or `None` after [`skip`] when there is no adapter.
pub fn gpu() -> Option<GpuContext> {
    match GpuContext::headless() {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            skip(&format!("no GPU adapter: {e}"));
            None
        }
    }
}

/// Per-pixel counts (row-major, `width` × `height`) summed over a coarse grid of `cells`
/// (columns, rows) and normalized to sum 1: the distribution of samples over the cells.
pub fn coarse_density(counts: &[u32], width: usize, height: usize, cells: (usize, usize)) -> Vec<f64> {
    assert_eq!(counts.len(), width * height, "counts of a {width}×{height} image");
    let mut out = vec![0.0; cells.0 * cells.1];
    for y in 0..height {
        for x in 0..width {
            out[(y * cells.1 / height) * cells.0 + x * cells.0 / width] += counts[y * width + x] as f64;
        }
    }
    let total: f64 = out.iter().sum();
    assert!(total > 0.0, "no samples on the {width}×{height} image");
    out.iter().map(|c| c / total).collect()
}

/// The live view's settings for [`assert_gpu_density_matches_cpu`]: the GPU chaos game's
/// `orbits` orbits of `k` steps in one frame (seed 3), splatted as raw counts (density mode on
/// black, no depth cue, shading, occlusion or point radius, no settling, never stopped).
pub fn raw_density_settings(orbits: u32, k: u32) -> LiveSettings {
    let draw = ProgressiveSettings {
        point_count: orbits,
        steps_per_frame: k,
        seed: 3,
        mode: SplatMode::Density,
        depth_cue: 0.0,
        background: [0.0; 3],
        shading: 0.0,
        occlusion: 0.0,
        point_radius_px: 0,
        max_splats: u64::MAX,
        settle_steps: 0,
        ..ProgressiveSettings::default()
    };
    LiveSettings { draw, chaos_backend: ChaosBackend::Gpu, render_density: None }
}

/// A GPU chaos game's hit counts against the CPU's: `orbits` orbits of `k` steps (seed 77,
/// frame 0, in chunks of [`ORBITS_PER_CHUNK`] after the transient) splatted into `view`, both
/// reduced to `cells` and compared within 6σ ([`assert_densities_agree`]). `gpu_counts`: the
/// GPU's hits per pixel of `view`. Returns the samples on each side and the worst
/// |Δ| / tolerance.
#[track_caller]
pub fn assert_gpu_density_matches_cpu(
    what: &str,
    gpu_label: &str,
    gpu_counts: &[u32],
    compiled: &CompiledIfs,
    view: SplatView,
    (orbits, k): (u32, u32),
    cells: (usize, usize),
) -> DensityAgreement {
    let mut fb = Framebuffer::new(view, compiled.colors.clone());
    for c in 0..orbits / ORBITS_PER_CHUNK as u32 {
        run_chunk(compiled, 77, 0, c, k as usize, &mut fb);
    }
    let cpu_counts: Vec<u32> = fb.accum.iter().map(|a| a[3]).collect();
    let gpu_samples: f64 = gpu_counts.iter().map(|&c| c as f64).sum();
    let cpu_samples: f64 = cpu_counts.iter().map(|&c| c as f64).sum();
    let (width, height) = (view.width as usize, view.height as usize);
    let pg = coarse_density(gpu_counts, width, height, cells);
    let pc = coarse_density(&cpu_counts, width, height, cells);
    let worst = assert_densities_agree(
        what,
        &Density { label: gpu_label, density: &pg, samples: gpu_samples, steps_per_orbit: k as f64 },
        &Density { label: "CPU", density: &pc, samples: cpu_samples, steps_per_orbit: k as f64 },
        cells,
    );
    DensityAgreement { gpu_samples, cpu_samples, worst }
}

/// The GPU chaos game's sums per pixel (r, g, b, count) after `dispatches` of `compiled`, each
/// (steps, steps not splatted, restart and clear): every orbit from its start point at a
/// restart, else from where the dispatch before left it.
pub fn gpu_accum(
    ctx: &GpuContext,
    game: &mut nlifs::gpu::chaos_game::GpuChaosGame,
    compiled: &CompiledIfs,
    view: &SplatView,
    dispatches: &[(u32, u32, bool)],
) -> Vec<[u32; 4]> {
    game.set_ifs(&ctx.device, &ctx.queue, compiled);
    for &(steps, skip_steps, first) in dispatches {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let args = nlifs::gpu::chaos_game::FrameArgs {
            view,
            seed: 3,
            frame: 0,
            steps,
            skip_steps,
            restart: first,
            clear: first,
        };
        game.encode(&ctx.device, &ctx.queue, &mut encoder, &args);
        ctx.queue.submit([encoder.finish()]);
    }
    let accum: Vec<u32> = bytemuck::pod_collect_to_vec(&nlifs::gpu::readback::read_buffer(ctx, &game.accum).unwrap());
    accum.chunks(4).map(|a| [a[0], a[1], a[2], a[3]]).take((view.width * view.height) as usize).collect()
}

/// What [`assert_gpu_density_matches_cpu`] found.
pub struct DensityAgreement {
    pub gpu_samples: f64,
    pub cpu_samples: f64,
    /// The worst cell's |Δ| / tolerance (at most 1).
    pub worst: f64,
}

/// One side of a density comparison: a coarse density, how many samples made it, and the
/// length of the orbits they came in (samples of one orbit are correlated).
pub struct Density<'a> {
    pub label: &'a str,
    pub density: &'a [f64],
    pub samples: f64,
    pub steps_per_orbit: f64,
}

/// Asserts that two coarse densities agree in every cell within 6 standard deviations of the
/// difference of two sample frequencies, and returns the worst |Δ| / tolerance.
///
/// The bound: a cell's frequency over N samples taken in orbits of k steps has variance at most
/// k·p(1−p)/N (at worst the k samples of an orbit are perfectly correlated; Cauchy–Schwarz on
/// the covariances), so the difference of two independent estimates has
/// σ² ≤ p(1−p)·(k_a/N_a + k_b/N_b), with p the mean of the two. On failure a picture of both
/// densities and of |Δ| / tolerance per cell is written and its path is in the message.
#[track_caller]
pub fn assert_densities_agree(what: &str, a: &Density, b: &Density, cells: (usize, usize)) -> f64 {
    assert_eq!(a.density.len(), cells.0 * cells.1);
    assert_eq!(b.density.len(), cells.0 * cells.1);
    let mut ratios = Vec::with_capacity(a.density.len());
    let mut failures = Vec::new();
    for (i, (&pa, &pb)) in a.density.iter().zip(b.density).enumerate() {
        let p = 0.5 * (pa + pb);
        let sigma = (p * (1.0 - p) * (a.steps_per_orbit / a.samples + b.steps_per_orbit / b.samples)).sqrt();
        let tol = 6.0 * sigma + 1e-12;
        let d = (pa - pb).abs();
        ratios.push(d / tol);
        if d > tol {
            failures.push(format!(
                "cell {i} (column {}, row {}): {} {pa} vs {} {pb} (|Δ| {d:.3e} > tolerance {tol:.3e})",
                i % cells.0,
                i / cells.0,
                a.label,
                b.label
            ));
        }
    }
    if !failures.is_empty() {
        let picture = density_picture(a.density, b.density, &ratios, cells);
        let path = failure_path(&format!("{}.densities.png", file_stem_of(what)));
        picture.save(&path).unwrap();
        panic!(
            "{what}: {} of {} cells differ beyond 6σ ({} vs {} samples):\n  {}\npicture ({}, {}, |Δ|/tolerance with red above 1): {}",
            failures.len(),
            ratios.len(),
            a.samples,
            b.samples,
            failures.join("\n  "),
            a.label,
            b.label,
            path.display()
        );
    }
    ratios.into_iter().fold(0.0, f64::max)
}

/// Three panels side by side, 8 pixels a cell: density a, density b (grey, scaled to their
/// common maximum) and |Δ| / tolerance (grey up to 1, red above).
fn density_picture(a: &[f64], b: &[f64], ratios: &[f64], cells: (usize, usize)) -> image::RgbImage {
    const SCALE: u32 = 8;
    let (cw, ch) = (cells.0 as u32, cells.1 as u32);
    let max = a.iter().chain(b).copied().fold(f64::MIN_POSITIVE, f64::max);
    let mut img = image::RgbImage::new(3 * cw * SCALE + 2 * SCALE, ch * SCALE);
    for (panel, values) in [a, b, ratios].into_iter().enumerate() {
        for (i, &v) in values.iter().enumerate() {
            let pixel = if panel < 2 {
                let g = (255.0 * v / max).round() as u8;
                [g, g, g]
            } else if v > 1.0 {
                [255, 0, 0]
            } else {
                let g = (255.0 * v).round() as u8;
                [g, g, g]
            };
            let (x0, y0) = (panel as u32 * (cw + 1) * SCALE + (i as u32 % cw) * SCALE, (i as u32 / cw) * SCALE);
            for y in y0..y0 + SCALE {
                for x in x0..x0 + SCALE {
                    img.put_pixel(x, y, image::Rgb(pixel));
                }
            }
        }
    }
    img
}

fn file_stem_of(what: &str) -> String {
    what.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

/// Where failing image tests write what they saw: `nlifs-test-failures/` in
/// [`scratch_root`], kept after the run.
pub fn failure_path(file_name: &str) -> PathBuf {
    let dir = scratch_root().join("nlifs-test-failures");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(file_name)
}

/// Per-channel absolute differences of two images of the same size.
pub struct Difference {
    /// |actual − expected| per channel.
    pub delta: image::RgbImage,
}

impl Difference {
    pub fn of(actual: &image::RgbImage, expected: &image::RgbImage) -> Self {
        assert_eq!(actual.dimensions(), expected.dimensions(), "image sizes differ");
        let mut delta = image::RgbImage::new(actual.width(), actual.height());
        for ((a, e), d) in actual.pixels().zip(expected.pixels()).zip(delta.pixels_mut()) {
            *d = image::Rgb([0, 1, 2].map(|c| a[c].abs_diff(e[c])));
        }
        Self { delta }
    }

    /// Mean absolute channel difference, in 8-bit levels.
    pub fn mean_levels(&self) -> f64 {
        let sum: u64 = self.delta.as_raw().iter().map(|&v| v as u64).sum();
        sum as f64 / self.delta.as_raw().len().max(1) as f64
    }

    /// How many pixels have a channel that differs by more than `levels`.
    pub fn pixels_over(&self, levels: u8) -> usize {
        self.delta.pixels().filter(|d| d.0.iter().any(|&v| v > levels)).count()
    }

    /// Writes `<name>.actual.png` and `<name>.diff.png` (the differences ×8) with
    /// [`failure_path`] and returns a sentence naming both, for the failure message.
    pub fn write_failure_images(&self, name: &str, actual: &image::RgbImage) -> String {
        let (a, d) = (failure_path(&format!("{name}.actual.png")), failure_path(&format!("{name}.diff.png")));
        actual.save(&a).unwrap();
        let mut amplified = self.delta.clone();
        amplified.as_mut().iter_mut().for_each(|v| *v = v.saturating_mul(8));
        amplified.save(&d).unwrap();
        format!("actual {}, difference ×8 {}", a.display(), d.display())
    }
}

/// `tests/golden/<name>.png`.
pub fn golden_path(name: &str) -> PathBuf {
    repo_path("tests/golden").join(format!("{name}.png"))
}

/// The golden image `name`, or `None` after writing `actual` as the golden image when `REPLACE`
/// is set. A missing golden image is written too, and the test fails so that it gets looked at.
pub fn golden_or_replace(name: &str, actual: &image::RgbImage) -> Option<image::RgbImage> {
    let path = golden_path(name);
    let replace = std::env::var_os("REPLACE").is_some();
    if replace || !path.exists() {
        actual.save(&path).unwrap();
        eprintln!("wrote golden image {}", path.display());
        assert!(replace, "golden image {} was missing and has been written; look at it and rerun", path.display());
        return None;
    }
    Some(image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8())
}

/// Asserts that `actual` has exactly the pixels of the golden image `name` (`REPLACE=1`
/// rewrites it). Pixels, not file bytes: the PNG encoder's choices are not what is tested.
#[track_caller]
pub fn assert_golden_exact(name: &str, actual: &image::RgbImage) {
    let Some(expected) = golden_or_replace(name, actual) else { return };
    assert_eq!(actual.dimensions(), expected.dimensions(), "{name}: size differs from {}", golden_path(name).display());
    if actual.as_raw() != expected.as_raw() {
        let diff = Difference::of(actual, &expected);
        panic!(
            "{name}: {} pixels differ from {} (largest channel difference {}); {}",
            diff.pixels_over(0),
            golden_path(name).display(),
            diff.delta.as_raw().iter().max().unwrap(),
            diff.write_failure_images(name, actual)
        );
    }
}
