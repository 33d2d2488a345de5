//! What the job forms check before a job may start, as plain functions of the scene and the
//! form (the panel shows the verdict, `actions.rs` refuses to start against it, `jobs.rs` runs
//! the plan): the ray-trace's hierarchy size against a node budget and its default depth, the
//! recording's frames, format and video, and where both write: next to the scene, numbered so
//! that no run overwrites an earlier one.

use std::path::{Path, PathBuf};

use crate::output::{Format, OutputOptions};
use crate::record::{MAX_FRAMES_PER_RUN, RecordSettings};
use crate::scene::Scene;
use crate::scene::timeline::LoopMode;

pub use super::command::RecordPlan;
use super::command::{RaytraceForm, RecordForm};
use super::state::ViewerState;

/// The most hierarchy nodes a ray-trace from the viewer may build. W^n(A) for m functions has
/// 1 + m + … + m^n nodes; the build holds each node with its path, its sphere and, for the
/// last level, a leaf entry: about [`BYTES_PER_NODE`] bytes a node at its peak, so 8 million
/// nodes are about 2 GB, and their build takes seconds to tens of seconds before the first
/// ray. It is also the most `raytrace::hierarchy` builds at all (past it the build stops with
/// an error after doing the work), so refusing up front loses nothing that would work.
pub const NODE_BUDGET: f64 = 8.0e6;

/// Peak memory of the hierarchy build per node (bytes), rounded up: `nlifs snapshot` of plant2
/// (5 functions) peaked at 138 MB for depth 8 (488 281 nodes) and 480 MB for depth 9
/// (2 441 406 nodes), 190 to 240 bytes a node over the process's 20 MB; depth 9 built in
/// 2.2 s on 2 busy cores.
pub const BYTES_PER_NODE: f64 = 250.0;

/// Nodes of W^depth(A) for `functions` enabled functions: 1 + m + m² + … + m^depth.
pub fn hierarchy_nodes(functions: usize, depth: u32) -> f64 {
    let m = functions.max(1) as f64;
    (0..=depth).map(|k| m.powi(k as i32)).sum()
}

/// The deepest hierarchy of `functions` functions within [`NODE_BUDGET`].
pub fn deepest_within_budget(functions: usize) -> u32 {
    (0..=64).take_while(|&d| hierarchy_nodes(functions, d) <= NODE_BUDGET).last().unwrap_or(0)
}

/// The most nodes the ray-trace form's default depth builds: under a third of [`NODE_BUDGET`],
/// about 600 MB and a few seconds of building, so that the default starts soon; deeper is the
/// user's choice, up to the budget. It holds the built-in plant2's depth 9 (2.4 million nodes,
/// built in 2.2 s; at depth 8 its leaves are still blobs) and gives 4 functions depth 10
/// (1.4 million nodes: tapering at 640×480 in 2.5 s on 2 busy cores).
pub const DEFAULT_DEPTH_NODES: f64 = 2.5e6;

/// How small the default depth makes the largest leaf, in pixels across. A few pixels rather
/// than one: the bound is the largest branch's, most leaves are smaller, and spheres below a
/// pixel render as sparse dust (twist-anim at 640×480: depth 7, largest leaf 2.5 px, reads as
/// solid detail; depth 8, 1 px, already thins out).
pub const LEAF_TARGET_PX: f64 = 3.0;

/// The deepest the form offers.
pub const MAX_DEPTH: u32 = 12;

/// The ray-trace form's default depth n of W^n(A), for `functions` enabled functions whose
/// largest Lipschitz bound is `contraction` (None: not known), where A (the sphere around the
/// grid's box that the tracer starts from) spans `initial_px` pixels of the image.
///
/// The rule: as deep as [`DEFAULT_DEPTH_NODES`] allows, but no deeper than where the largest
/// leaf is below [`LEAF_TARGET_PX`]. Each map shrinks by at most c = `contraction`, so a leaf
/// of W^n(A) lies in a sphere of at most c^n times A's: it spans at most c^n · `initial_px`
/// pixels, below the target from n = ⌈ln(initial_px / target) / ln(1/c)⌉ on. Past that depth
/// more nodes add little but dust; short of it the leaves show as blobs (tapering, c = 0.63, at
/// the old fixed depth 5 has leaves up to about 100 px across and looks like four sausages; the
/// budget gives it depth 10). A scene that may not be contractive (c ≥ 1, or no bound) gets the
/// budget's depth.
pub fn default_depth(functions: usize, contraction: Option<f64>, initial_px: f64) -> u32 {
    let budget = (0..=MAX_DEPTH).take_while(|&d| hierarchy_nodes(functions, d) <= DEFAULT_DEPTH_NODES).last();
    let budget = budget.unwrap_or(0);
    let sub_pixel = match contraction {
        Some(c) if c > 0.0 && c < 1.0 => {
            let n = ((initial_px.max(1.0) / LEAF_TARGET_PX).ln() / (1.0 / c).ln()).ceil();
            n.clamp(0.0, MAX_DEPTH as f64) as u32
        }
        Some(c) if c <= 0.0 => 1,
        _ => MAX_DEPTH,
    };
    budget.min(sub_pixel).max(1)
}

/// The ray-trace form's estimate: how large the hierarchy would be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaytraceEstimate {
    /// Enabled functions (children per node).
    pub functions: usize,
    pub depth: u32,
    pub nodes: f64,
    /// Peak memory of the build, bytes.
    pub bytes: f64,
}

impl RaytraceEstimate {
    pub fn new(functions: usize, depth: u32) -> Self {
        let nodes = hierarchy_nodes(functions, depth);
        Self { functions, depth, nodes, bytes: nodes * BYTES_PER_NODE }
    }

    pub fn within_budget(&self) -> bool {
        self.nodes <= NODE_BUDGET
    }

    /// Why the ray-trace may not start (None: it may).
    pub fn refusal(&self) -> Option<String> {
        if self.functions == 0 {
            return Some("no function is enabled: nothing to ray-trace".into());
        }
        (!self.within_budget()).then(|| {
            format!(
                "depth {} with {} functions is about {} nodes (about {}), past the budget of {} nodes: \
                 at most depth {} here",
                self.depth,
                self.functions,
                format_count(self.nodes),
                format_bytes(self.bytes),
                format_count(NODE_BUDGET),
                deepest_within_budget(self.functions)
            )
        })
    }
}

/// `1234567.0` as `1.23 million`, smaller numbers in full.
pub fn format_count(n: f64) -> String {
    if n >= 1e9 {
        format!("{:.2} billion", n / 1e9)
    } else if n >= 1e6 {
        format!("{:.2} million", n / 1e6)
    } else {
        format!("{n:.0}")
    }
}

/// Bytes as MB or GB.
pub fn format_bytes(bytes: f64) -> String {
    if bytes >= 1e9 { format!("{:.1} GB", bytes / 1e9) } else { format!("{:.0} MB", (bytes / 1e6).max(1.0)) }
}

/// Where jobs (and `F12`) write by default, and the name their files start with: the scene
/// file's folder and stem, else, for the built-in scene, the working folder and `nlifs`. The
/// folder is absolute, so that messages name it in full.
pub fn output_place(scene_path: Option<&Path>) -> (PathBuf, String) {
    let (dir, stem) = match scene_path {
        Some(p) => (
            p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new(".")),
            p.file_stem().map_or("nlifs".into(), |s| s.to_string_lossy().into_owned()),
        ),
        None => (Path::new("."), "nlifs".into()),
    };
    (super::recent::absolute(dir), stem)
}

/// The first of `names(1)`, `names(2)`, … none of whose paths exists (a broken link counts
/// as existing: writing there would replace it).
pub fn first_free<const N: usize>(names: impl Fn(u32) -> [PathBuf; N]) -> [PathBuf; N] {
    let free = |paths: &[PathBuf; N]| paths.iter().all(|p| std::fs::symlink_metadata(p).is_err());
    (1..u32::MAX).map(&names).find(free).unwrap_or_else(|| names(u32::MAX))
}

/// The PNG a ray-trace writes: the form's path (a relative one taken from the scene's folder),
/// or, with the field empty, the first free `SCENE-raytrace-N.png` next to the scene.
pub fn raytrace_png(form: &RaytraceForm, scene_path: Option<&Path>) -> PathBuf {
    let (dir, stem) = output_place(scene_path);
    match form.png_text.trim() {
        "" => {
            let [png] = first_free(|n| [dir.join(format!("{stem}-raytrace-{n}.png"))]);
            png
        }
        typed => dir.join(typed),
    }
}

/// Where a recording writes its frames and its video: the form's folder and file (relative
/// ones taken from the scene's folder), or, with a field empty, `SCENE-record-N/` and
/// `SCENE-record-N.mp4` next to the scene with the first N for which neither exists. An empty
/// video field beside a typed folder names the video after the folder (`frames/`,
/// `frames.mp4`).
pub fn record_outputs(form: &RecordForm, scene_path: Option<&Path>) -> (PathBuf, PathBuf) {
    let (dir, stem) = output_place(scene_path);
    let [frames, auto_video] = match form.dir_text.trim() {
        "" => first_free(|n| [dir.join(format!("{stem}-record-{n}")), dir.join(format!("{stem}-record-{n}.mp4"))]),
        typed => {
            let frames = dir.join(typed);
            let name = frames.file_name().map_or("video".into(), |n| n.to_string_lossy().into_owned());
            let video = frames.with_file_name(format!("{name}.mp4"));
            [frames, video]
        }
    };
    let video = match form.video_text.trim() {
        "" => auto_video,
        typed => dir.join(typed),
    };
    (frames, video)
}

/// Frames of `scene`'s timeline at `fps`: the rule of `Recorder::frame_count` (once: both ends;
/// loop: one period, its end being frame 0 again; ping-pong: there and back), without the
/// recorder's bounds pass, so that the form can show it every frame. A test holds the two equal.
pub fn frame_count(scene: &Scene, fps: f64) -> u32 {
    let Some(tl) = &scene.timeline else { return 1 };
    let eps = 1e-9;
    let n = match tl.loop_mode {
        LoopMode::Once => (tl.duration_secs * fps + eps).floor() + 1.0,
        LoopMode::Loop | LoopMode::PingPong => (tl.cycle_secs() * fps - eps).ceil(),
    };
    n.clamp(1.0, u32::MAX as f64) as u32
}

/// Checks the record form against `scene` (read from `scene_path`, where its outputs go by
/// default: [`record_outputs`]); `ffmpeg`: whether ffmpeg runs here. The error says what to
/// change.
pub fn plan_record(
    form: &RecordForm,
    scene: &Scene,
    scene_path: Option<&Path>,
    ffmpeg: bool,
) -> Result<RecordPlan, String> {
    for (what, v) in [("width", form.width), ("height", form.height)] {
        if !(16..=4096).contains(&v) {
            return Err(format!("the {what} must be 16 to 4096 pixels, not {v}"));
        }
    }
    if !(form.fps.is_finite() && (1.0..=240.0).contains(&form.fps)) {
        return Err(format!("the frame rate must be 1 to 240 fps, not {}", form.fps));
    }
    if form.points_per_frame == 0 {
        return Err("at least one point per frame".into());
    }
    let (dir, video_path) = record_outputs(form, scene_path);
    let count = frame_count(scene, form.fps);
    let frames = match form.frame_range {
        None => 0..count,
        Some((first, end)) if end <= first => {
            return Err(format!("frames {first}..{end} are none: the end is exclusive (0..{count} is all)"));
        }
        Some((first, end)) if end > count => {
            return Err(format!(
                "frames {first}..{end} go past the end: the timeline has {count} frames at {} fps (0..{count})",
                form.fps
            ));
        }
        Some((first, end)) => first..end,
    };
    if frames.len() > MAX_FRAMES_PER_RUN as usize {
        return Err(format!("{} frames are more than the {MAX_FRAMES_PER_RUN} one recording makes", frames.len()));
    }
    let renderer = if form.ray_traced {
        // Traced frames are 8-bit PNG (the snapshot's output), and their hierarchy is built per
        // frame: the ray-trace form's budget holds for each.
        if form.format != Format::Png {
            return Err("ray-traced frames are 8-bit PNG: choose png, or the chaos game".into());
        }
        let functions = scene.functions.iter().filter(|f| f.enabled).count();
        if let Some(why) = RaytraceEstimate::new(functions, form.trace_depth).refusal() {
            return Err(why);
        }
        let trace = crate::record::TraceOptions {
            depth: form.trace_depth,
            spp: form.trace_spp.max(1),
            ..crate::record::TraceOptions::default()
        };
        crate::record::Renderer::Raytrace(trace)
    } else {
        crate::record::Renderer::Chaos
    };
    let video = if form.video {
        let path = video_path;
        if form.format == Format::Exr {
            return Err("a video is made from PNG frames: choose png or png16, or untick the video".into());
        }
        if !ffmpeg {
            return Err(
                "ffmpeg was not found: install ffmpeg to make a video, or untick it to write the frames only".into()
            );
        }
        if path.extension().is_none() {
            return Err("the video's file name needs an extension (.mp4, .mov or .mkv)".into());
        }
        Some(path)
    } else {
        None
    };
    Ok(RecordPlan {
        settings: RecordSettings {
            fps: form.fps,
            width: form.width,
            height: form.height,
            points_per_frame: Some(form.points_per_frame),
            motion_blur_samples: 1,
            shutter: 0.5,
            renderer,
        },
        frames,
        frame_count: count,
        dir,
        options: OutputOptions { format: form.format, ..OutputOptions::default() },
        video,
    })
}

impl ViewerState {
    /// The ray-trace form's hierarchy estimate for the scene as it is.
    pub fn raytrace_estimate(&self) -> RaytraceEstimate {
        RaytraceEstimate::new(self.enabled_functions(), self.raytrace_depth())
    }

    fn enabled_functions(&self) -> usize {
        self.scene.functions.iter().filter(|f| f.enabled).count()
    }

    /// The depth the ray-trace form's *auto* picks for the scene at the current time
    /// ([`default_depth`], from the largest Lipschitz bound of its enabled functions).
    pub fn default_raytrace_depth(&self) -> u32 {
        let bounds = self.report.as_ref().map(|r| {
            r.functions
                .iter()
                .zip(&self.scene.functions)
                .filter(|(_, spec)| spec.enabled)
                .map(|(f, _)| f.lipschitz_bound)
        });
        // One function without a bound leaves the contraction unknown.
        let contraction =
            bounds.and_then(|mut b| b.try_fold(0.0f64, |c, l| l.map(|l| c.max(l)))).filter(|c| c.is_finite());
        default_depth(self.enabled_functions(), contraction, self.initial_sphere_px())
    }

    /// About how many pixels across the ray-trace form's image A's sphere (around the grid's
    /// box) spans: the view frames the attractor, so its bounds' largest side spans about the
    /// image's larger side.
    pub fn initial_sphere_px(&self) -> f64 {
        let form = &self.raytrace_form;
        let (lo, hi) = (self.scene.domain.min(), self.scene.domain.max());
        let attractor = (self.bounds.1 - self.bounds.0).max_element();
        let image_px = form.width.max(form.height) as f64;
        if attractor > 0.0 && attractor.is_finite() { image_px * (hi - lo).length() / attractor } else { image_px }
    }

    /// The depth a ray-trace runs at: the form's, or, on *auto*, [`Self::default_raytrace_depth`].
    pub fn raytrace_depth(&self) -> u32 {
        self.raytrace_form.depth.unwrap_or_else(|| self.default_raytrace_depth()).min(MAX_DEPTH)
    }

    /// The PNG a ray-trace started now would write ([`raytrace_png`]).
    pub fn raytrace_png(&self) -> PathBuf {
        raytrace_png(&self.raytrace_form, self.scene_path.as_deref())
    }

    /// The record form checked against the scene as it is.
    pub fn record_plan(&self) -> Result<RecordPlan, String> {
        plan_record(&self.record_form, &self.scene, self.scene_path.as_deref(), self.files.ffmpeg)
    }
}

/// The depth a ray-trace of `form` runs at: its depth, at most [`MAX_DEPTH`] as the form
/// allows (the viewer fills in *auto* before a request; one left open runs at the depth the
/// command line's ray-trace defaults to).
pub fn effective_depth(form: &RaytraceForm) -> u32 {
    form.depth.unwrap_or(crate::raytrace::RaytraceSettings::default().depth).min(MAX_DEPTH)
}
