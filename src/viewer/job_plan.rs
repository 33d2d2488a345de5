//! What the job forms check before a job may start, as plain functions of the scene and the
//! form (the panel shows the verdict, `actions.rs` refuses to start against it, `jobs.rs` runs
//! the plan): the ray-trace's hierarchy size against a node budget, and the recording's frames,
//! format and video.

use std::ops::Range;
use std::path::PathBuf;

use crate::output::{Format, OutputOptions};
use crate::record::{MAX_FRAMES_PER_RUN, RecordSettings};
use crate::scene::Scene;
use crate::scene::timeline::LoopMode;

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

/// A recording the form asks for, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordPlan {
    pub settings: RecordSettings,
    /// The frames to write.
    pub frames: Range<u32>,
    /// Frames in the whole timeline at this frame rate.
    pub frame_count: u32,
    pub dir: PathBuf,
    pub options: OutputOptions,
    /// Where the video goes (None: frames only).
    pub video: Option<PathBuf>,
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

/// Checks the record form against `scene`; `ffmpeg`: whether ffmpeg runs here. The error says
/// what to change.
pub fn plan_record(form: &RecordForm, scene: &Scene, ffmpeg: bool) -> Result<RecordPlan, String> {
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
    let dir = PathBuf::from(form.dir_text.trim());
    if dir.as_os_str().is_empty() {
        return Err("no folder for the frames".into());
    }
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
        let path = PathBuf::from(form.video_text.trim());
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
        let functions = self.scene.functions.iter().filter(|f| f.enabled).count();
        RaytraceEstimate::new(functions, effective_depth(&self.raytrace_form))
    }

    /// The record form checked against the scene as it is.
    pub fn record_plan(&self) -> Result<RecordPlan, String> {
        plan_record(&self.record_form, &self.scene, self.files.ffmpeg)
    }
}

/// The depth a ray-trace runs at (the form's, at most 12 as the form allows).
pub fn effective_depth(form: &RaytraceForm) -> u32 {
    form.depth.min(12)
}
