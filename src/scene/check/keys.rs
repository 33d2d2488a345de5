//! Reading the `[timeline]` and `[[key]]` sections: loop mode, duration and keys in increasing
//! time, each key's overrides checked against the function it names (same kind, same structure,
//! only numbers may change) so that every key can be interpolated with its neighbours.

use std::ops::Range;

use toml::Spanned;

use crate::model::builder::Builder;
use crate::model::{AffineMap, JuliaMap, RectGrid};
use crate::scene::file::{KeyToml, TimelineToml};
use crate::scene::spec::{
    self, CameraSpec, FunctionDef, FunctionSpec, LIGHT_FIELDS, MAX_POINTS, MAX_TIME_SECS, TONE_FIELDS,
};
use crate::scene::timeline::{Ease, FunctionKey, Interpolation, Key, LoopMode, RenderKey, Timeline};

use super::{Checker, Res};

impl Checker<'_> {
    pub(super) fn timeline(
        &self,
        raw: Option<&Spanned<TimelineToml>>,
        keys: &[Spanned<KeyToml>],
        functions: &[FunctionSpec],
        domain: &RectGrid,
    ) -> Res<Option<Timeline>> {
        if raw.is_none() && keys.is_empty() {
            return Ok(None);
        }
        let loop_mode = match raw.and_then(|r| r.get_ref().loop_mode.as_ref()) {
            None => LoopMode::Once,
            Some(m) => LoopMode::parse(m.get_ref()).ok_or_else(|| {
                self.err(
                    m.span(),
                    "timeline.loop",
                    format!("`{}` is not a loop mode; use \"once\", \"loop\" or \"ping-pong\"", m.get_ref()),
                )
            })?,
        };
        let mut out = Vec::new();
        for (i, k) in keys.iter().enumerate() {
            out.push(self.key(i, k, functions, domain)?);
        }
        for (i, w) in out.windows(2).enumerate() {
            if w[1].t_secs <= w[0].t_secs {
                return Err(self.err(
                    keys[i + 1].get_ref().t_secs.span(),
                    &format!("key[{}].t_secs", i + 1),
                    "keys must be listed in increasing time",
                ));
            }
        }
        let last = out.last().map_or(0.0, |k| k.t_secs);
        let duration_secs = match raw.and_then(|r| r.get_ref().duration_secs.as_ref()) {
            Some(d) => {
                let v = self.finite(d, "timeline.duration_secs")?;
                if !(v > 0.0 && v <= MAX_TIME_SECS) {
                    return Err(self.err(
                        d.span(),
                        "timeline.duration_secs",
                        format!("must be positive and at most {MAX_TIME_SECS:e} s, found {}", super::words::show(v)),
                    ));
                }
                if loop_mode == LoopMode::Loop && v <= last {
                    return Err(self.err(
                        d.span(),
                        "timeline.duration_secs",
                        format!("in loop mode the duration is the period, when the first key repeats; it must exceed the last key's time {last}"),
                    ));
                }
                if v < last {
                    return Err(self.err(
                        d.span(),
                        "timeline.duration_secs",
                        format!("ends before the last key at {last} s"),
                    ));
                }
                v
            }
            None if loop_mode == LoopMode::Loop => {
                let span = raw.map_or(0..0, |r| r.span());
                return Err(self.err(
                    span,
                    "timeline.duration_secs",
                    "loop mode needs `duration_secs`, the period after which the first key repeats",
                ));
            }
            None => last,
        };
        Ok(Some(Timeline { loop_mode, duration_secs, keys: out }))
    }

    fn key(&self, i: usize, k: &Spanned<KeyToml>, functions: &[FunctionSpec], domain: &RectGrid) -> Res<Key> {
        let dim = domain.dimension();
        let field = |name: &str| format!("key[{i}].{name}");
        let k = k.get_ref();
        let t_secs = self.in_range(&k.t_secs, &field("t_secs"), 0.0, MAX_TIME_SECS)?;
        let interpolation = match &k.interpolation {
            None => Interpolation::default(),
            Some(s) => Interpolation::parse(s.get_ref()).ok_or_else(|| {
                self.err(
                    s.span(),
                    &field("interpolation"),
                    format!("`{}` is not an interpolation; use \"hold\", \"linear\" or \"catmull-rom\"", s.get_ref()),
                )
            })?,
        };
        let ease = match &k.ease {
            None => Ease::default(),
            Some(s) => Ease::parse(s.get_ref()).ok_or_else(|| {
                self.err(
                    s.span(),
                    &field("ease"),
                    format!("`{}` is not an ease; use \"none\", \"in\", \"out\" or \"in-out\"", s.get_ref()),
                )
            })?,
        };
        let mut keyed = Vec::new();
        for (j, f) in k.functions.iter().enumerate() {
            let prefix = format!("key[{i}].function[{j}]");
            let span = f.span();
            let f = f.get_ref();
            let name = f.name.get_ref();
            let index = functions.iter().position(|s| &s.name == name).ok_or_else(|| {
                self.err(f.name.span(), &format!("{prefix}.name"), format!("no [[function]] is named `{name}`"))
            })?;
            if keyed.iter().any(|g: &FunctionKey| g.function == index) {
                return Err(self.err(
                    f.name.span(),
                    &format!("{prefix}.name"),
                    format!("`{name}` appears twice in this key"),
                ));
            }
            let base = &functions[index].def;
            let (kind, allowed): (&str, &[&str]) = match base {
                FunctionDef::Grid { .. } => ("grid", &["points"]),
                FunctionDef::Builder { .. } => ("builder", &["steps"]),
                FunctionDef::Affine(_) => ("affine", &["matrix", "offset"]),
                FunctionDef::Julia(_) => ("julia", &["c"]),
                FunctionDef::Flame(_) => ("flame", &super::flame::FLAME_FIELDS),
            };
            let present: [(&str, Option<Range<usize>>); 5] = [
                ("points", f.points.as_ref().map(|v| v.span())),
                ("steps", f.steps.as_ref().map(|v| v.span())),
                ("matrix", f.matrix.as_ref().map(|v| v.span())),
                ("offset", f.offset.as_ref().map(|v| v.span())),
                ("c", f.c.as_ref().map(|v| v.span())),
            ];
            let flame_fields = f.flame().present().into_iter().map(|(n, s)| (n, Some(s)));
            for (field_name, s) in present.into_iter().chain(flame_fields) {
                if let Some(s) = s
                    && !allowed.contains(&field_name)
                {
                    return Err(self.err(
                        s,
                        &format!("{prefix}.{field_name}"),
                        format!("`{name}` is a `{kind}` function; a key may set {}", allowed.join(" or ")),
                    ));
                }
            }
            let def = match base {
                FunctionDef::Grid { points: base_points } => match &f.points {
                    None => base.clone(),
                    Some(pts) => {
                        if pts.get_ref().len() != base_points.len() {
                            return Err(self.err(
                                pts.span(),
                                &format!("{prefix}.points"),
                                format!("has {} points, the grid has {}", pts.get_ref().len(), base_points.len()),
                            ));
                        }
                        let points = pts
                            .get_ref()
                            .iter()
                            .enumerate()
                            .map(|(n, p)| self.vec3(p, &format!("{prefix}.points[{n}]"), dim))
                            .collect::<Res<Vec<_>>>()?;
                        FunctionDef::Grid { points }
                    }
                },
                FunctionDef::Builder { resolution, .. } => match &f.steps {
                    None => base.clone(),
                    Some(steps) => {
                        let centre = 0.5 * (domain.min() + domain.max());
                        let mut out = Vec::new();
                        for (n, s) in steps.get_ref().iter().enumerate() {
                            out.push(self.step(&format!("{prefix}.steps[{n}]"), s, domain, centre)?);
                        }
                        let def = FunctionDef::Builder { resolution: *resolution, builder: Builder { steps: out } };
                        self.resolves_finite(&def, domain, steps.span(), &format!("{prefix}.steps"))?;
                        def
                    }
                },
                FunctionDef::Affine(a) => {
                    let matrix = match &f.matrix {
                        None => a.matrix,
                        Some(m) => self.matrix(m, &format!("{prefix}.matrix"), dim)?,
                    };
                    let offset = match &f.offset {
                        None => a.offset,
                        Some(o) => self.vec3(o, &format!("{prefix}.offset"), dim)?,
                    };
                    FunctionDef::Affine(AffineMap { matrix, offset })
                }
                FunctionDef::Julia(jm) => {
                    let c = match &f.c {
                        None => jm.c,
                        Some(c) => {
                            let v = self.vec3(c, &format!("{prefix}.c"), 2)?;
                            [v.x, v.y]
                        }
                    };
                    FunctionDef::Julia(JuliaMap { c, sign: jm.sign })
                }
                FunctionDef::Flame(fd) => {
                    FunctionDef::Flame(self.flame_def(&prefix, span.clone(), f.flame(), Some(fd))?)
                }
            };
            if let Err(msg) = spec::same_structure(base, &def) {
                return Err(self.err(
                    f.steps.as_ref().map_or(span.clone(), |s| s.span()),
                    &format!("{prefix}.steps"),
                    msg,
                ));
            }
            keyed.push(FunctionKey { function: index, def });
        }
        keyed.sort_by_key(|f| f.function);
        let camera = match &k.camera {
            None => CameraSpec::default(),
            Some(c) => self.camera(&field("camera"), c, dim)?,
        };
        let mut render = RenderKey::default();
        if let Some(r) = &k.render {
            if let Some(p) = &r.points {
                let x = *p.get_ref();
                if !(1..=MAX_POINTS as i64).contains(&x) {
                    return Err(self.err(
                        p.span(),
                        &field("render.points"),
                        format!("must lie in 1..={MAX_POINTS}, found {x}"),
                    ));
                }
                render.points = Some(x as u64);
            }
            if let Some(b) = &r.background {
                render.background = Some(self.color(b, &field("render.background"))?);
            }
            if let Some(d) = &r.depth_cue {
                let v = self.finite(d, &field("render.depth_cue"))?;
                if !(0.0..=1.0).contains(&v) {
                    return Err(self.err(d.span(), &field("render.depth_cue"), "must lie in 0..1"));
                }
                render.depth_cue = Some(v as f32);
            }
            // The tone controls.
            for ((value, (name, lo, hi)), slot) in r.tone().into_iter().zip(TONE_FIELDS).zip(render.tone.iter_mut()) {
                if let Some(v) = value {
                    *slot = Some(self.in_range(v, &field(&format!("render.{name}")), lo, hi)? as f32);
                }
            }
            // The key light.
            for ((value, (name, lo, hi)), slot) in r.light().into_iter().zip(LIGHT_FIELDS).zip(render.light.iter_mut())
            {
                if let Some(v) = value {
                    *slot = Some(self.in_range(v, &field(&format!("render.{name}")), lo, hi)? as f32);
                }
            }
            (render.aperture, render.focus_distance) = self.lens(&r.aperture, &r.focus_distance, &field("render"))?;
        }
        Ok(Key { t_secs, interpolation, ease, functions: keyed, camera, render })
    }
}
