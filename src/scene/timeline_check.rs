//! Checking a scene along its timeline: contractivity (Lipschitz bound < 1) and containment of
//! every enabled function, at each key and at sampled times between keys, reported per stretch
//! of the timeline. It resolves the IFS at each sampled time, so it needs the whole `Scene`;
//! the timeline itself (`timeline.rs`) does not.

use crate::scene::Scene;
use crate::scene::timeline::LoopMode;

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
    pub problems: Vec<TimelineProblem>,
}

/// Checks contractivity (Lipschitz bound < 1) and containment along the timeline: at every key
/// and at `samples_per_interval` evenly spaced times strictly inside each stretch between keys
/// (including before the first key, after the last, and in loop mode the wrap back to the first).
/// A problem is reported once per stretch and function, with the worst bound or first time seen.
pub fn check_timeline(scene: &Scene, samples_per_interval: usize) -> Option<TimelineCheck> {
    let tl = scene.timeline.as_ref()?;
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
    for (span, times) in spans {
        let mut worst: Vec<Option<(f64, f64)>> = vec![None; scene.functions.len()];
        let mut leaves: Vec<Option<(f64, usize)>> = vec![None; scene.functions.len()];
        for &t in &times {
            samples += 1;
            let report = scene.at(t).report();
            for (fi, f) in report.functions.iter().enumerate() {
                if !scene.functions[fi].enabled {
                    continue;
                }
                if let Some(l) = f.lipschitz_bound
                    && l >= 1.0
                    && worst[fi].is_none_or(|(m, _)| l > m)
                {
                    worst[fi] = Some((l, t));
                }
                if f.contained == Some(false) && leaves[fi].is_none() {
                    leaves[fi] = Some((t, f.outside.len()));
                }
            }
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
    Some(TimelineCheck { loop_mode: tl.loop_mode.name(), duration_secs: d, keys: n, samples, problems })
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
