//! The `nlifs` command line: a thin layer over the library that parses arguments, shows
//! progress, adds context to errors and maps bad input to exit code 2.
//!
//! This file holds the command tree, the dispatch, the exit-code mapping and what every command
//! uses (the bad-input error, scene loading, the progress bar). Each command lives in a module
//! of its own that owns its arguments and its output; `args` holds the argument types several
//! commands share.

mod args;
mod bench;
mod bench_look;
mod bench_render;
mod color_args;
mod export;
mod image_args;
mod import;
mod info;
mod info_flame;
mod lens_args;
mod light_args;
mod merge;
mod record;
mod render;
mod render_cpu;
mod render_flame;
mod snapshot;
mod tone_args;
mod view;

use std::path::Path;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use nlifs::scene::Scene;

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
    Info(info::InfoArgs),
    /// Render a still with the chaos game (headless).
    // clap leaves an output that is required unless another option is given out of the usage.
    #[command(override_usage = "nlifs render [OPTIONS] --output <OUTPUT> <SCENE>\n       \
                                nlifs render [OPTIONS] --part <PART> --raw <RAW> <SCENE>")]
    Render(render::RenderArgs),
    /// Export geometry.
    #[command(subcommand)]
    Export(export::ExportCommand),
    /// Merge the part files of one still (`render --part K/N --raw`) into its image.
    Merge(merge::MergeArgs),
    /// Render an animated scene to DIR/frame_00000.png, ... (optionally a video).
    Record(record::RecordArgs),
    /// Ray-trace a still of the deterministic approximation W^n(A) (spheres or meshes).
    Snapshot(snapshot::SnapshotArgs),
    /// Open the interactive viewer (GPU) on a scene; `nlifs` alone opens it on a built-in scene.
    View(view::ViewArgs),
    /// Benchmarks (throughput figures for the README).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Make a scene of another program's file (a flam3 flame).
    #[command(subcommand)]
    Import(import::ImportCommand),
}

/// An error caused by the user's input: exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct BadInput(String);

/// Parses the command line and runs it: exit code 0 on success, 2 for bad input (arguments,
/// scene files, geometry the ray tracer refuses), 1 for anything else.
pub fn main() -> ExitCode {
    quiet_on_closed_pipe();
    no_display_probing_without_a_display();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = match negative_numbers_are_values(Cli::command())
        .try_get_matches()
        .and_then(|matches| Cli::from_arg_matches(&matches))
    {
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
            eprintln!("error: {}", message(&e));
            let bad_input = e.chain().any(|c| {
                c.is::<BadInput>()
                    || c.downcast_ref::<nlifs::raytrace::RaytraceError>().is_some_and(|e| e.is_bad_input())
                    || c.is::<nlifs::scene::LoadError>()
                    || c.is::<nlifs::scene::SceneError>()
                    || c.downcast_ref::<std::io::Error>()
                        .and_then(nlifs::io::WriteError::of)
                        .is_some_and(|e| e.is_bad_input())
            });
            ExitCode::from(if bad_input { 2 } else { 1 })
        }
    }
}

/// Mesa's Vulkan device-selection layer (an implicit layer, so in every Vulkan instance) asks a
/// Wayland compositor, then an X server, for the default GPU; where there is no display
/// (ssh, cron) libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set in the
/// environment" on stderr, twice per instance, on every headless run that tries the GPU. wgpu
/// enables the surface extensions that make the layer ask even for an instance without a
/// display. Where neither Wayland (a usable XDG_RUNTIME_DIR or an absolute WAYLAND_DISPLAY) nor
/// X (DISPLAY) can be reached, the layer has no one to ask, so it is turned off with its own
/// switch, `NODEVICE_SELECT=1`, unless the user chose a device through it (DRI_PRIME,
/// MESA_VK_DEVICE_SELECT) or set the switch. wgpu then picks the adapter as it does elsewhere.
fn no_display_probing_without_a_display() {
    let given = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    let absolute = |name: &str| std::env::var_os(name).is_some_and(|v| Path::new(&v).is_absolute());
    let reachable =
        absolute("XDG_RUNTIME_DIR") || absolute("WAYLAND_DISPLAY") || given("WAYLAND_SOCKET") || given("DISPLAY");
    let chosen = given("DRI_PRIME") || given("MESA_VK_DEVICE_SELECT") || std::env::var_os("NODEVICE_SELECT").is_some();
    if cfg!(target_os = "linux") && !reachable && !chosen {
        // SAFETY: called first thing in main, before any thread exists, so no other thread
        // reads the environment while it changes.
        #[expect(unsafe_code, reason = "std::env::set_var is unsafe in edition 2024")]
        unsafe {
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    }
}

/// `cmd` with every option that takes a value accepting a negative number as that value, so
/// that `--width -100` reaches the option's own range check ("-100 is not in 1..=16384")
/// instead of reading as an unknown flag `-1`.
fn negative_numbers_are_values(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|arg| if arg.get_action().takes_values() { arg.allow_negative_numbers(true) } else { arg })
        .mut_subcommands(negative_numbers_are_values)
}

/// `nlifs info scene.toml | head` ends quietly when `head` closes the pipe, as Unix tools do,
/// instead of panicking in `println!`: Rust ignores SIGPIPE by default, so writes fail with
/// EPIPE; the default action ends the process at the first write to a closed pipe.
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid action
    // for SIGPIPE and `signal` has no other precondition.
    #[expect(unsafe_code, reason = "restoring a signal's default action has no safe wrapper in std")]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The error and its causes joined by ": ", each said once: a library error that already
/// quotes its source (`cannot write x: <why>`) is not followed by that source again.
fn message(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain().map(|c| c.to_string()) {
        if text.contains(&cause) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&cause);
    }
    text
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None => view::view(view::ViewArgs::default()),
        Some(Command::View(args)) => view::view(args),
        Some(Command::Info(args)) => info::info(args),
        Some(Command::Render(args)) => render::render(args),
        Some(Command::Export(command)) => export::run(command),
        Some(Command::Record(args)) => record::record(args),
        Some(Command::Merge(args)) => merge::merge(args),
        Some(Command::Snapshot(args)) => snapshot::snapshot(args),
        Some(Command::Bench(command)) => bench::run(command),
        Some(Command::Import(command)) => import::run(command),
    }
}

/// The scene file `path`, or the scene of the first flame of a flame file (`.flame`, `.flam3`;
/// the import of `nlifs import flame`), whose reader's and import's warnings are printed here.
fn load(path: &Path) -> anyhow::Result<Scene> {
    if nlifs::flame::xml::is_flame_path(path) {
        let import = nlifs::scene::flame_import::load_flame(path, None, None)?;
        for warning in &import.warnings {
            eprintln!("warning: {warning}");
        }
        return Ok(import.scene);
    }
    Ok(Scene::load(path)?)
}

/// Checks that `paths` can be written before the command's work starts ([`nlifs::io::probe`]):
/// a read-only or impossible place fails at once with exit code 2, not after the render, and
/// leaves no folder behind. A missing folder is created, and said so on stderr (`created
/// folder /abs/path`).
fn probe_outputs(paths: &[&Path]) -> anyhow::Result<()> {
    let mut created: Vec<Vec<std::path::PathBuf>> = Vec::new();
    for path in paths {
        match nlifs::io::probe(path) {
            Ok(folders) => created.push(folders),
            Err(e) => {
                created.iter().rev().for_each(|folders| nlifs::io::remove_created(folders));
                return Err(anyhow::Error::from(e).context(format!("cannot write {}", path.display())));
            }
        }
    }
    for dir in created.iter().filter_map(|folders| folders.last()) {
        eprintln!("created folder {}", std::path::absolute(dir).unwrap_or_else(|_| dir.clone()).display());
    }
    Ok(())
}

/// [`probe_outputs`] of one output.
fn probe_output(path: &Path) -> anyhow::Result<()> {
    probe_outputs(&[path])
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
