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
//!
//! The timeline knows the scene's plain types (`spec`) and nothing of `Scene`: the scene asks it
//! for a channel's value at a time; checking a whole timeline, which needs the scene, lives in
//! `timeline_check.rs`.

use crate::scene::spec::{CameraSpec, FunctionDef};

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
    /// The tone controls, in the order of `spec::TONE_FIELDS` (boxed: keys stay small enough to
    /// be held two to an undoable edit).
    pub tone: Box<[Option<f32>; 5]>,
    // Shadows (`crate::resolve::shadow`).
    /// The key light's fields, in the order of `spec::LIGHT_FIELDS` (boxed, as the tone).
    pub light: Box<[Option<f32>; 3]>,
    // Depth of field.
    pub aperture: Option<f32>,
    pub focus_distance: Option<f32>,
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
}
