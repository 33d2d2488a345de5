//! The animation timeline of a scene: keys at times in seconds, each overriding some function
//! definitions, camera fields and render settings, and how scene time maps to values between
//! them.
//!
//! Every animatable quantity is a *channel*: one function's definition, one camera field, one
//! render setting. A channel's keys are the keys that set it; a key that does not mention a
//! channel leaves it alone, so a camera-only key does not stop a twist in its tracks. Values are
//! interpolated as flat parameter vectors: grid points point by point, builders by their step
//! parameters (so a twist animates as a rotation; the scene resolves the interpolated builder),
//! the camera by its orbit parameters. A key's `interpolation` and `ease` shape the segment that
//! starts at it. Catmull-Rom tangents are central differences in value per second; at the first
//! and last key of a non-looping timeline the tangent is zero, so motion starts and ends at rest
//! (C1 into the held value after the end and through the ping-pong turnaround, and no overshoot
//! past the end keys). In loop mode channels are periodic: the segment after the last key runs
//! into the first key of the next cycle, with wrapped tangents, so the loop is seamless.

use glam::DVec3;

use crate::model::builder::Step;
use crate::scene::{CameraSpec, FunctionDef};

/// How scene time beyond the timeline's duration maps back onto it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LoopMode {
    /// Values hold after the end.
    #[default]
    Once,
    /// Time wraps modulo the duration; the duration is the time at which the first key repeats.
    Loop,
    /// Time runs forwards then backwards.
    PingPong,
}

impl LoopMode {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "once" => Some(Self::Once),
            "loop" => Some(Self::Loop),
            "ping-pong" => Some(Self::PingPong),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Once => "once",
            Self::Loop => "loop",
            Self::PingPong => "ping-pong",
        }
    }
}

/// How the segment that starts at a key runs to the next key of the same channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// The key's value holds until the next key.
    Hold,
    Linear,
    /// Cubic Hermite with Catmull-Rom tangents (C1 across keys).
    #[default]
    CatmullRom,
}

impl Interpolation {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "hold" => Some(Self::Hold),
            "linear" => Some(Self::Linear),
            "catmull-rom" => Some(Self::CatmullRom),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Hold => "hold",
            Self::Linear => "linear",
            Self::CatmullRom => "catmull-rom",
        }
    }
}

/// A reparametrisation of a segment's fraction u ∈ [0, 1]; all map 0 to 0 and 1 to 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Ease {
    #[default]
    None,
    /// Starts at rest: u².
    In,
    /// Ends at rest: 1 − (1 − u)².
    Out,
    /// Starts and ends at rest: 3u² − 2u³.
    InOut,
}

impl Ease {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "none" => Some(Self::None),
            "in" => Some(Self::In),
            "out" => Some(Self::Out),
            "in-out" => Some(Self::InOut),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::In => "in",
            Self::Out => "out",
            Self::InOut => "in-out",
        }
    }

    pub fn apply(self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        match self {
            Self::None => u,
            Self::In => u * u,
            Self::Out => 1.0 - (1.0 - u) * (1.0 - u),
            Self::InOut => u * u * (3.0 - 2.0 * u),
        }
    }
}

/// A key's override of one function's definition. The definition has the kind and structure
/// of the scene's function (same grid, same builder steps and axes), checked when parsed.
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionKey {
    /// Index into `Scene::functions`.
    pub function: usize,
    pub def: FunctionDef,
}

/// Render settings a key may change.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RenderKey {
    pub depth_cue: Option<f32>,
    /// Linear RGB.
    pub background: Option<[f32; 3]>,
    pub points: Option<u64>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    pub t_secs: f64,
    pub interpolation: Interpolation,
    pub ease: Ease,
    pub functions: Vec<FunctionKey>,
    /// Set fields override the scene's camera; `projection` holds (it does not interpolate).
    pub camera: CameraSpec,
    pub render: RenderKey,
}

impl Key {
    pub fn new(t_secs: f64) -> Self {
        Self {
            t_secs,
            interpolation: Interpolation::default(),
            ease: Ease::default(),
            functions: Vec::new(),
            camera: CameraSpec::default(),
            render: RenderKey::default(),
        }
    }

    pub fn function(&self, function: usize) -> Option<&FunctionDef> {
        self.functions.iter().find(|f| f.function == function).map(|f| &f.def)
    }

    /// Sets (or with None removes) this key's override of `function`.
    pub fn set_function(&mut self, function: usize, def: Option<FunctionDef>) {
        self.functions.retain(|f| f.function != function);
        if let Some(def) = def {
            self.functions.push(FunctionKey { function, def });
            self.functions.sort_by_key(|f| f.function);
        }
    }
}

/// The keys of a scene, sorted by time, and how time runs over them.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Timeline {
    pub loop_mode: LoopMode,
    /// Once and ping-pong: the end of the animation (≥ the last key). Loop: the period.
    pub duration_secs: f64,
    pub keys: Vec<Key>,
}

/// Two keys closer than this (seconds) are the same key for the playhead operations.
pub const KEY_TIME_TOL_SECS: f64 = 1e-6;

/// One sample of a channel: the key's time, shape of the segment after it, and value.
#[derive(Clone, Debug)]
pub struct ChannelKey<'a> {
    pub t_secs: f64,
    pub interpolation: Interpolation,
    pub ease: Ease,
    pub value: &'a [f64],
}

impl Timeline {
    /// Maps scene time to time on the timeline, in [0, duration] (loop: [0, duration)).
    pub fn local_time(&self, t_secs: f64) -> f64 {
        let d = self.duration_secs;
        if !(d > 0.0) || !t_secs.is_finite() {
            return 0.0;
        }
        match self.loop_mode {
            LoopMode::Once => t_secs.clamp(0.0, d),
            LoopMode::Loop => t_secs.rem_euclid(d),
            LoopMode::PingPong => {
                let u = t_secs.rem_euclid(2.0 * d);
                if u > d { 2.0 * d - u } else { u }
            }
        }
    }

    /// The length of one cycle of scene time: duration, or twice it for ping-pong.
    pub fn cycle_secs(&self) -> f64 {
        match self.loop_mode {
            LoopMode::PingPong => 2.0 * self.duration_secs,
            _ => self.duration_secs,
        }
    }

    /// Index of the key at `t_secs` (within [`KEY_TIME_TOL_SECS`]).
    pub fn key_index_at(&self, t_secs: f64) -> Option<usize> {
        self.keys.iter().position(|k| (k.t_secs - t_secs).abs() <= KEY_TIME_TOL_SECS)
    }

    /// Where a key at `t_secs` goes to keep the keys sorted.
    pub fn insertion_index(&self, t_secs: f64) -> usize {
        self.keys.partition_point(|k| k.t_secs < t_secs)
    }

    /// Inserts `key`, or replaces the key at its time; returns its index.
    pub fn upsert_key(&mut self, key: Key) -> usize {
        match self.key_index_at(key.t_secs) {
            Some(i) => {
                self.keys[i] = key;
                i
            }
            None => {
                let i = self.insertion_index(key.t_secs);
                self.keys.insert(i, key);
                self.grow_duration();
                i
            }
        }
    }

    /// The key at the playhead, created (with no overrides) if there is none; returns its index.
    pub fn key_at_playhead(&mut self, t_secs: f64) -> usize {
        match self.key_index_at(t_secs) {
            Some(i) => i,
            None => self.upsert_key(Key::new(t_secs)),
        }
    }

    /// Deletes the key at `t_secs`, returning it.
    pub fn delete_key_at(&mut self, t_secs: f64) -> Option<Key> {
        self.key_index_at(t_secs).map(|i| self.keys.remove(i))
    }

    /// Sets function `function`'s definition at the playhead (adding a key if needed).
    pub fn set_function_at(&mut self, t_secs: f64, function: usize, def: FunctionDef) -> usize {
        let i = self.key_at_playhead(t_secs);
        self.keys[i].set_function(function, Some(def));
        i
    }

    /// Keeps the duration covering the keys (once / ping-pong; in loop mode the period is kept
    /// and the caller is expected to keep keys inside it).
    fn grow_duration(&mut self) {
        if self.loop_mode != LoopMode::Loop
            && let Some(last) = self.keys.last()
        {
            self.duration_secs = self.duration_secs.max(last.t_secs);
        }
    }

    /// Interpolates one channel at scene time `t_secs`; None if no key sets it.
    pub fn sample(&self, keys: &[ChannelKey], t_secs: f64) -> Option<Vec<f64>> {
        self.sample_wrapped(keys, t_secs, None)
    }

    /// [`Timeline::sample`] for angles with a full turn of `turn` (see [`sample_channel_wrapped`]).
    pub fn sample_wrapped(&self, keys: &[ChannelKey], t_secs: f64, turn: Option<f64>) -> Option<Vec<f64>> {
        let period = (self.loop_mode == LoopMode::Loop && self.duration_secs > 0.0).then_some(self.duration_secs);
        sample_channel_wrapped(keys, self.local_time(t_secs), period, turn)
    }

    /// A channel made by `get` from every key that sets it.
    pub fn channel(&self, get: impl Fn(&Key) -> Option<Vec<f64>>) -> Vec<ChannelKeyOwned> {
        self.keys
            .iter()
            .filter_map(|k| {
                get(k).map(|value| ChannelKeyOwned {
                    t_secs: k.t_secs,
                    interpolation: k.interpolation,
                    ease: k.ease,
                    value,
                })
            })
            .collect()
    }

    /// The value of the channel made by `get` at scene time `t_secs`.
    pub fn channel_at(&self, t_secs: f64, get: impl Fn(&Key) -> Option<Vec<f64>>) -> Option<Vec<f64>> {
        self.angle_channel_at(t_secs, None, get)
    }

    /// [`Timeline::channel_at`] for angles with a full turn of `turn`, when given.
    pub fn angle_channel_at(
        &self,
        t_secs: f64,
        turn: Option<f64>,
        get: impl Fn(&Key) -> Option<Vec<f64>>,
    ) -> Option<Vec<f64>> {
        let owned = self.channel(get);
        let keys: Vec<ChannelKey> = owned.iter().map(ChannelKeyOwned::borrow).collect();
        self.sample_wrapped(&keys, t_secs, turn)
    }

    /// The key whose segment holds scene time `t_secs`, among those for which `has` holds, for
    /// settings that do not interpolate (such as a projection): the last at or before it.
    pub fn held_key(&self, t_secs: f64, has: impl Fn(&Key) -> bool) -> Option<&Key> {
        let t = self.local_time(t_secs);
        let set: Vec<&Key> = self.keys.iter().filter(|k| has(k)).collect();
        set.iter()
            .rev()
            .find(|k| k.t_secs <= t)
            .or(if self.loop_mode == LoopMode::Loop { set.last() } else { set.first() })
            .copied()
    }
}

/// An owned [`ChannelKey`].
#[derive(Clone, Debug)]
pub struct ChannelKeyOwned {
    pub t_secs: f64,
    pub interpolation: Interpolation,
    pub ease: Ease,
    pub value: Vec<f64>,
}

impl ChannelKeyOwned {
    pub fn borrow(&self) -> ChannelKey<'_> {
        ChannelKey { t_secs: self.t_secs, interpolation: self.interpolation, ease: self.ease, value: &self.value }
    }
}

/// Interpolates sorted channel keys at timeline time `t`. With `period` the channel repeats
/// every `period` seconds (keys must lie in [0, period)).
pub fn sample_channel(keys: &[ChannelKey], t: f64, period: Option<f64>) -> Option<Vec<f64>> {
    sample_channel_wrapped(keys, t, period, None)
}

/// Wraps a difference of angles into [−half turn, half turn).
fn wrap_diff(d: f64, turn: Option<f64>) -> f64 {
    match turn {
        Some(w) => (d + 0.5 * w).rem_euclid(w) - 0.5 * w,
        None => d,
    }
}

/// [`sample_channel`] for values that are angles with a full turn of `turn` (such as yaw in
/// degrees, 360): every difference between keys is taken the short way round, so keys
/// 0°, 90°, 180°, 270° in a loop orbit once per cycle. Tangents use the same wrapped
/// differences on both sides of a key, so the result stays C1 as an angle.
pub fn sample_channel_wrapped(keys: &[ChannelKey], t: f64, period: Option<f64>, turn: Option<f64>) -> Option<Vec<f64>> {
    let n = keys.len();
    if n == 0 {
        return None;
    }
    if n == 1 {
        return Some(keys[0].value.to_vec());
    }
    // Key j of the unrolled sequence: index and time (shifted by whole periods in loop mode).
    let at = |j: i64| -> (usize, f64) {
        match period {
            Some(p) => {
                let i = j.rem_euclid(n as i64) as usize;
                (i, keys[i].t_secs + p * j.div_euclid(n as i64) as f64)
            }
            None => {
                let i = j.clamp(0, n as i64 - 1) as usize;
                (i, keys[i].t_secs)
            }
        }
    };
    // The segment [j, j + 1] holding t.
    let j: i64 = match period {
        Some(_) => {
            let first = keys[0].t_secs;
            if t < first { -1 } else { keys.partition_point(|k| k.t_secs <= t) as i64 - 1 }
        }
        None => {
            if t <= keys[0].t_secs {
                return Some(keys[0].value.to_vec());
            }
            if t >= keys[n - 1].t_secs {
                return Some(keys[n - 1].value.to_vec());
            }
            keys.partition_point(|k| k.t_secs <= t) as i64 - 1
        }
    };
    let (i0, t0) = at(j);
    let (i1, t1) = at(j + 1);
    let k0 = &keys[i0];
    let p0 = k0.value;
    let p1: Vec<f64> = keys[i1].value.iter().zip(p0).map(|(b, a)| a + wrap_diff(b - a, turn)).collect();
    let h = t1 - t0;
    if !(h > 0.0) || p0.len() != p1.len() {
        return Some(p0.to_vec());
    }
    let u = k0.ease.apply((t - t0) / h);
    let out = match k0.interpolation {
        Interpolation::Hold => p0.to_vec(),
        Interpolation::Linear => p0.iter().zip(&p1).map(|(a, b)| a + (b - a) * u).collect(),
        Interpolation::CatmullRom => {
            // Tangent (value per second) at unrolled key j; zero at the ends of a non-looping
            // channel.
            let tangent = |j: i64| -> Vec<f64> {
                let (i, _) = at(j);
                let ends = period.is_none() && (j <= 0 || j >= n as i64 - 1);
                let (ia, ta) = at(j - 1);
                let (ib, tb) = at(j + 1);
                let (pa, pb) = (keys[ia].value, keys[ib].value);
                if ends || !(tb - ta > 0.0) || pa.len() != keys[i].value.len() || pb.len() != pa.len() {
                    return vec![0.0; keys[i].value.len()];
                }
                let pi = keys[i].value;
                (0..pi.len())
                    .map(|c| (wrap_diff(pb[c] - pi[c], turn) - wrap_diff(pa[c] - pi[c], turn)) / (tb - ta))
                    .collect()
            };
            let (m0, m1) = (tangent(j), tangent(j + 1));
            let (u2, u3) = (u * u, u * u * u);
            let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
            let h10 = u3 - 2.0 * u2 + u;
            let h01 = -2.0 * u3 + 3.0 * u2;
            let h11 = u3 - u2;
            (0..p0.len()).map(|c| h00 * p0[c] + h10 * h * m0[c] + h01 * p1[c] + h11 * h * m1[c]).collect()
        }
    };
    Some(out)
}

fn push3(out: &mut Vec<f64>, v: DVec3) {
    out.extend_from_slice(&v.to_array());
}

fn step_params(step: &Step, out: &mut Vec<f64>) {
    match step {
        Step::Scale { by, center } => {
            push3(out, *by);
            push3(out, *center);
        }
        Step::Rotate { degrees, center, .. } => {
            out.push(*degrees);
            push3(out, *center);
        }
        Step::Translate { by } => push3(out, *by),
        Step::Taper { amount: x, range, center, .. }
        | Step::Twist { degrees: x, range, center, .. }
        | Step::Bend { degrees: x, range, center, .. } => {
            out.push(*x);
            out.extend_from_slice(range);
            push3(out, *center);
        }
        Step::Affine { matrix, offset } => {
            out.extend_from_slice(&matrix.to_cols_array());
            push3(out, *offset);
        }
    }
}

/// The animatable numbers of a definition, in a fixed order.
pub fn flatten(def: &FunctionDef) -> Vec<f64> {
    let mut out = Vec::new();
    match def {
        FunctionDef::Grid { points } => points.iter().for_each(|p| push3(&mut out, *p)),
        FunctionDef::Builder { builder, .. } => builder.steps.iter().for_each(|s| step_params(s, &mut out)),
        FunctionDef::Affine(a) => {
            out.extend_from_slice(&a.matrix.to_cols_array());
            push3(&mut out, a.offset);
        }
        FunctionDef::Julia(j) => out.extend_from_slice(&j.c),
    }
    out
}

/// A definition of `template`'s structure with the numbers `values` (as made by [`flatten`]).
/// None if the count does not match.
pub fn unflatten(template: &FunctionDef, values: &[f64]) -> Option<FunctionDef> {
    if values.len() != flatten(template).len() {
        return None;
    }
    let mut it = values.iter().copied();
    let mut next = || it.next().unwrap_or(0.0);
    let v3 = |next: &mut dyn FnMut() -> f64| DVec3::new(next(), next(), next());
    let mut def = template.clone();
    match &mut def {
        FunctionDef::Grid { points } => points.iter_mut().for_each(|p| *p = v3(&mut next)),
        FunctionDef::Builder { builder, .. } => {
            for s in builder.steps.iter_mut() {
                match s {
                    Step::Scale { by, center } => {
                        *by = v3(&mut next);
                        *center = v3(&mut next);
                    }
                    Step::Rotate { degrees, center, .. } => {
                        *degrees = next();
                        *center = v3(&mut next);
                    }
                    Step::Translate { by } => *by = v3(&mut next),
                    Step::Taper { amount: x, range, center, .. }
                    | Step::Twist { degrees: x, range, center, .. }
                    | Step::Bend { degrees: x, range, center, .. } => {
                        *x = next();
                        *range = [next(), next()];
                        *center = v3(&mut next);
                    }
                    Step::Affine { matrix, offset } => {
                        let cols: [f64; 9] = std::array::from_fn(|_| next());
                        *matrix = glam::DMat3::from_cols_array(&cols);
                        *offset = v3(&mut next);
                    }
                }
            }
        }
        FunctionDef::Affine(a) => {
            let cols: [f64; 9] = std::array::from_fn(|_| next());
            a.matrix = glam::DMat3::from_cols_array(&cols);
            a.offset = v3(&mut next);
        }
        FunctionDef::Julia(j) => j.c = [next(), next()],
    }
    Some(def)
}

/// Whether `a` and `b` can be interpolated: same kind, same point count, same steps with the
/// same axes. Returns what differs.
pub fn same_structure(a: &FunctionDef, b: &FunctionDef) -> Result<(), String> {
    use std::mem::discriminant;
    match (a, b) {
        (FunctionDef::Grid { points: pa }, FunctionDef::Grid { points: pb }) if pa.len() != pb.len() => {
            Err(format!("has {} points, the function has {}", pb.len(), pa.len()))
        }
        (FunctionDef::Builder { builder: ba, .. }, FunctionDef::Builder { builder: bb, .. }) => {
            if ba.steps.len() != bb.steps.len() {
                return Err(format!(
                    "has {} steps, the function has {} (a key lists every step of the builder)",
                    bb.steps.len(),
                    ba.steps.len()
                ));
            }
            for (k, (sa, sb)) in ba.steps.iter().zip(&bb.steps).enumerate() {
                let axes = |s: &Step| match s {
                    Step::Rotate { axis, .. } | Step::Taper { axis, .. } => Some((*axis, None)),
                    Step::Twist { axis, along, .. } => Some((*axis, Some(*along))),
                    Step::Bend { axis, toward, .. } => Some((*axis, Some(*toward))),
                    _ => None,
                };
                if discriminant(sa) != discriminant(sb) || axes(sa) != axes(sb) {
                    return Err(format!(
                        "step {k} differs in kind or axis from the function's step {k}; keys may change only numbers"
                    ));
                }
            }
            Ok(())
        }
        _ if discriminant(a) != discriminant(b) => Err("is not of the function's kind".into()),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(ts: &[f64], vs: &[f64], interpolation: Interpolation) -> Vec<ChannelKeyOwned> {
        ts.iter()
            .zip(vs)
            .map(|(&t, &v)| ChannelKeyOwned { t_secs: t, interpolation, ease: Ease::None, value: vec![v] })
            .collect()
    }

    fn eval(k: &[ChannelKeyOwned], t: f64, period: Option<f64>) -> f64 {
        let b: Vec<ChannelKey> = k.iter().map(ChannelKeyOwned::borrow).collect();
        sample_channel(&b, t, period).unwrap()[0]
    }

    #[test]
    fn keys_are_hit_exactly() {
        let ts = [0.0, 0.7, 2.0, 3.1];
        let vs = [1.0, -2.5, 4.0, 0.25];
        for interp in [Interpolation::Hold, Interpolation::Linear, Interpolation::CatmullRom] {
            let k = keys(&ts, &vs, interp);
            for period in [None, Some(4.0)] {
                for (t, v) in ts.iter().zip(vs) {
                    assert_eq!(eval(&k, *t, period), v, "{interp:?} {period:?} t={t}");
                }
            }
        }
    }

    #[test]
    fn ease_endpoints() {
        for e in [Ease::None, Ease::In, Ease::Out, Ease::InOut] {
            assert_eq!(e.apply(0.0), 0.0);
            assert_eq!(e.apply(1.0), 1.0);
        }
        // Slopes at the ends by one-sided differences: O(h) error for these quadratics.
        let h = 1e-6;
        let slope0 = |e: Ease| (e.apply(h) - e.apply(0.0)) / h;
        let slope1 = |e: Ease| (e.apply(1.0) - e.apply(1.0 - h)) / h;
        assert!(slope0(Ease::In).abs() < 1e-5 && (slope1(Ease::In) - 2.0).abs() < 1e-5);
        assert!((slope0(Ease::Out) - 2.0).abs() < 1e-5 && slope1(Ease::Out).abs() < 1e-5);
        assert!(slope0(Ease::InOut).abs() < 1e-5 && slope1(Ease::InOut).abs() < 1e-5);
    }

    #[test]
    fn loop_is_periodic_and_wraps_into_first_key() {
        let k = keys(&[0.0, 1.0, 2.5], &[0.0, 3.0, 1.0], Interpolation::Linear);
        // Segment from the last key (2.5) into the first key of the next cycle (4.0).
        assert!((eval(&k, 3.25, Some(4.0)) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn playhead_operations_keep_keys_sorted() {
        let mut tl =
            Timeline { loop_mode: LoopMode::Once, duration_secs: 1.0, keys: vec![Key::new(0.0), Key::new(1.0)] };
        assert_eq!(tl.key_at_playhead(0.5), 1);
        assert_eq!(tl.key_at_playhead(0.5 + KEY_TIME_TOL_SECS / 2.0), 1, "the same key within the tolerance");
        assert_eq!(tl.upsert_key(Key::new(3.0)), 3);
        assert_eq!(tl.duration_secs, 3.0, "once: the duration grows to the last key");
        let mut replaced = Key::new(1.0);
        replaced.ease = Ease::Out;
        assert_eq!(tl.upsert_key(replaced), 2);
        assert_eq!(tl.keys.iter().map(|k| k.t_secs).collect::<Vec<_>>(), vec![0.0, 0.5, 1.0, 3.0]);
        assert_eq!(tl.keys[2].ease, Ease::Out);
        let def = FunctionDef::Julia(crate::model::JuliaMap { c: [0.1, 0.2], sign: 1.0 });
        assert_eq!(tl.set_function_at(2.0, 1, def.clone()), 3);
        assert_eq!(tl.keys[3].function(1), Some(&def));
        assert_eq!(tl.delete_key_at(0.5).map(|k| k.t_secs), Some(0.5));
        assert!(tl.delete_key_at(0.25).is_none());
        assert_eq!(tl.keys.len(), 4);
    }

    #[test]
    fn unflatten_inverts_flatten() {
        use crate::model::builder::{Axis, Builder};
        let def = FunctionDef::Builder {
            resolution: [3, 3, 3],
            builder: Builder {
                steps: vec![
                    Step::Twist {
                        axis: Axis::Y,
                        along: Axis::Y,
                        degrees: 30.0,
                        range: [0.0, 1.0],
                        center: DVec3::new(0.5, 0.5, 0.5),
                    },
                    Step::Affine {
                        matrix: glam::DMat3::from_cols_array(&[1., 2., 3., 4., 5., 6., 7., 8., 9.]),
                        offset: DVec3::X,
                    },
                ],
            },
        };
        assert_eq!(unflatten(&def, &flatten(&def)), Some(def));
    }
}

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
pub fn check_timeline(scene: &crate::scene::Scene, samples_per_interval: usize) -> Option<TimelineCheck> {
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
