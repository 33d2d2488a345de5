//! Checking a scene along its timeline: contractivity (Lipschitz bound < 1) and containment of
//! every enabled function, at each key and at sampled times between keys, reported per stretch
//! of the timeline. It resolves the IFS at each sampled time, so it needs the whole `Scene`;
//! the timeline itself (`timeline.rs`) does not.
//!
//! The cost is that of the Lipschitz bound (64 matrices per grid cell) times the functions
//! that change times the sampled times. A function that no key changes is checked once, a
//! function is re-checked only when its definition differs from the last one checked, and when
//! the total would pass [`MAX_CHECK_MATRICES`] the times between keys are sampled more thinly
//! (down to the keys alone); the check says how many it took.

use crate::model::{Function, Map};
use crate::scene::Scene;
use crate::scene::spec::FunctionDef;
use crate::scene::timeline::LoopMode;

/// The most 3×3 spectral norms one timeline check computes (about 20 s on one core, a few on
/// many); past it fewer times between keys are sampled.
pub const MAX_CHECK_MATRICES: u64 = 2_000_000_000;

/// Where along the timeline a check failed.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "at", rename_all = "snake_case")]
pub enum TimelineSpan {
    /// At key `index`.
    Key { index: usize, t_secs: f64 },
    /// Strictly between two times on the timeline; `from_key`/`to_key` are None for the stretch
    /// before the first key or after the last.
    Interval { from_key: Option<usize>, to_key: Option<usize>, from_secs: f64, to_secs: f64 },
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "problem", rename_all = "snake_case")]
pub enum TimelineProblemKind {
    /// The Lipschitz bound reached `max_bound` ≥ 1 (at `t_secs`): maybe not contractive.
    NotContractive { max_bound: f64, t_secs: f64 },
    /// Grid points (or box corners) left the domain, first at `t_secs`.
    NotContained { t_secs: f64, outside: usize },
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TimelineProblem {
    pub span: TimelineSpan,
    pub function: String,
    pub kind: TimelineProblemKind,
}

/// The result of [`check_timeline`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TimelineCheck {
    pub loop_mode: &'static str,
    pub duration_secs: f64,
    pub keys: usize,
    /// Times at which the IFS was resolved and checked.
    pub samples: usize,
    /// Times sampled strictly between neighbouring keys: as asked, or fewer to keep the check
    /// within [`MAX_CHECK_MATRICES`].
    pub samples_per_interval: usize,
    pub problems: Vec<TimelineProblem>,
}

/// Checks contractivity (Lipschitz bound < 1) and containment along the timeline: at every key
/// and at `samples_per_interval` evenly spaced times strictly inside each stretch between keys
/// (including before the first key, after the last, and in loop mode the wrap back to the first).
/// A problem is reported once per stretch and function, with the worst bound or first time seen.
pub fn check_timeline(scene: &Scene, samples_per_interval: usize) -> Option<TimelineCheck> {
    check_timeline_with_progress(scene, samples_per_interval, &mut |_, _| {})
}

/// The 3×3 matrices one Lipschitz bound of `def` computes (0 for maps without one).
fn bound_cost(def: &FunctionDef, scene: &Scene) -> u64 {
    let combos = if scene.domain.dimension() == 3 { 64 } else { 4 };
    let cells = |dims: [usize; 3]| dims.iter().map(|&n| n.saturating_sub(1).max(1) as u64).product::<u64>();
    match def {
        FunctionDef::Grid { .. } => cells(scene.domain.dims()) * combos,
        FunctionDef::Builder { resolution, .. } => cells(*resolution) * combos,
        FunctionDef::Affine(_) | FunctionDef::Julia(_) | FunctionDef::Flame(_) => 1,
    }
}

/// [`check_timeline`], calling `progress(times_done, times)` after each sampled time.
pub fn check_timeline_with_progress(
    scene: &Scene,
    samples_per_interval: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Option<TimelineCheck> {
    check_timeline_capped(scene, samples_per_interval, MAX_CHECK_MATRICES, progress)
}

/// [`check_timeline_with_progress`] with the work cap `max_matrices` (3×3 spectral norms)
/// instead of [`MAX_CHECK_MATRICES`].
pub fn check_timeline_capped(
    scene: &Scene,
    samples_per_interval: usize,
    max_matrices: u64,
    progress: &mut dyn FnMut(usize, usize),
) -> Option<TimelineCheck> {
    let tl = scene.timeline.as_ref()?;
    // Functions that a key changes cost a bound per sampled time; the rest one in all.
    let keyed_cost: u64 = (0..scene.functions.len())
        .filter(|&i| tl.keys.iter().any(|k| k.function(i).is_some()))
        .map(|i| bound_cost(&scene.functions[i].def, scene))
        .sum();
    let stretches = tl.keys.len() as u64 + 2;
    let mut samples_per_interval = samples_per_interval;
    while samples_per_interval > 0
        && keyed_cost.saturating_mul(stretches * (samples_per_interval as u64 + 1)) > max_matrices
    {
        samples_per_interval /= 2;
    }
    let d = tl.duration_secs;
    let mut spans: Vec<(TimelineSpan, Vec<f64>)> = Vec::new();
    let interior = |a: f64, b: f64| -> Vec<f64> {
        (1..=samples_per_interval).map(|i| a + (b - a) * i as f64 / (samples_per_interval + 1) as f64).collect()
    };
    let n = tl.keys.len();
    let first = tl.keys.first().map_or(d, |k| k.t_secs);
    if first > 0.0 {
        spans.push((
            TimelineSpan::Interval { from_key: None, to_key: (n > 0).then_some(0), from_secs: 0.0, to_secs: first },
            interior(0.0, first),
        ));
    }
    for (i, k) in tl.keys.iter().enumerate() {
        spans.push((TimelineSpan::Key { index: i, t_secs: k.t_secs }, vec![k.t_secs]));
        let (next, to_key) = match tl.keys.get(i + 1) {
            Some(nk) => (nk.t_secs, Some(i + 1)),
            None => (d, if tl.loop_mode == LoopMode::Loop { Some(0) } else { None }),
        };
        if next > k.t_secs {
            spans.push((
                TimelineSpan::Interval { from_key: Some(i), to_key, from_secs: k.t_secs, to_secs: next },
                interior(k.t_secs, next),
            ));
        }
    }
    let mut problems = Vec::new();
    let mut samples = 0;
    let total: usize = spans.iter().map(|(_, t)| t.len()).sum();
    // Per function: the last definition checked, its Lipschitz bound and outside count.
    let mut last: Vec<Option<(FunctionDef, Option<f64>, usize)>> = vec![None; scene.functions.len()];
    for (span, times) in spans {
        let mut worst: Vec<Option<(f64, f64)>> = vec![None; scene.functions.len()];
        let mut leaves: Vec<Option<(f64, usize)>> = vec![None; scene.functions.len()];
        for &t in &times {
            samples += 1;
            for (fi, spec) in scene.functions.iter().enumerate() {
                if !spec.enabled {
                    continue;
                }
                let def = scene.function_def_at(fi, t);
                if last[fi].as_ref().is_none_or(|(d, _, _)| *d != def) {
                    let map = scene.resolve(&def);
                    let ifs = crate::model::Ifs {
                        domain: scene.domain.clone(),
                        functions: vec![Function {
                            name: spec.name.clone(),
                            map,
                            color: spec.color,
                            weight: spec.probability,
                            enabled: true,
                            xaos: Vec::new(),
                        }],
                        probability_mode: scene.probability_mode,
                        final_xform: None,
                    };
                    let bound = ifs.functions[0].map.lipschitz_bound();
                    let outside = match &ifs.functions[0].map {
                        Map::Julia(_) | Map::Flame(_) => 0,
                        _ => ifs.outside_points(0).map_or(0, |o| o.len()),
                    };
                    last[fi] = Some((def, bound, outside));
                }
                let Some((_, bound, outside)) = &last[fi] else { continue };
                if let Some(l) = *bound
                    && l >= 1.0
                    && worst[fi].is_none_or(|(m, _)| l > m)
                {
                    worst[fi] = Some((l, t));
                }
                if *outside > 0 && leaves[fi].is_none() {
                    leaves[fi] = Some((t, *outside));
                }
            }
            progress(samples, total);
        }
        for (fi, f) in scene.functions.iter().enumerate() {
            if let Some((max_bound, t_secs)) = worst[fi] {
                problems.push(TimelineProblem {
                    span: span.clone(),
                    function: f.name.clone(),
                    kind: TimelineProblemKind::NotContractive { max_bound, t_secs },
                });
            }
            if let Some((t_secs, outside)) = leaves[fi] {
                problems.push(TimelineProblem {
                    span: span.clone(),
                    function: f.name.clone(),
                    kind: TimelineProblemKind::NotContained { t_secs, outside },
                });
            }
        }
    }
    Some(TimelineCheck {
        loop_mode: tl.loop_mode.name(),
        duration_secs: d,
        keys: n,
        samples,
        samples_per_interval,
        problems,
    })
}

impl std::fmt::Display for TimelineProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.span {
            TimelineSpan::Key { index, t_secs } => write!(f, "key {index} (t = {t_secs:.3} s): ")?,
            TimelineSpan::Interval { from_key, to_key, from_secs, to_secs } => {
                let name = |k: &Option<usize>, end: &str| k.map_or(end.to_string(), |k| format!("key {k}"));
                write!(
                    f,
                    "between {} and {} ({from_secs:.3}–{to_secs:.3} s): ",
                    name(from_key, "the start"),
                    name(to_key, "the end")
                )?
            }
        }
        match &self.kind {
            TimelineProblemKind::NotContractive { max_bound, t_secs } => {
                write!(
                    f,
                    "{} may not be contractive (Lipschitz bound up to {max_bound:.4}, at t = {t_secs:.3} s)",
                    self.function
                )
            }
            TimelineProblemKind::NotContained { t_secs, outside } => {
                write!(f, "{} leaves the grid ({outside} points outside, first at t = {t_secs:.3} s)", self.function)
            }
        }
    }
}
