//! Reading a scene: the second pass over the file, which gives the `*Toml` structs of
//! `file.rs` their meaning. It checks counts, ranges and names and reports the first problem
//! with the file, line, column and the dotted path of the field (`function[2].points`), so a
//! bad scene becomes a message and never a panic. `[render]` is checked in `render.rs`, the
//! `[timeline]` and `[[key]]` sections in `keys.rs`, against the functions read here.

use std::ops::Range;

use glam::{DMat3, DVec3};
use toml::Spanned;

use crate::camera::Projection;
use crate::color;
use crate::model::builder::{Axis, Builder, Step};
use crate::model::{AffineMap, JuliaMap, ProbabilityMode, RectGrid};
use crate::scene::file::{CameraToml, ColorToml, FORMAT_VERSION, FunctionToml, SceneToml, StepToml, VectorToml};
use crate::scene::spec::{CameraSpec, FinalXform, FunctionDef, FunctionSpec, MAX_COORDINATE, RenderSettings};
use crate::scene::{Scene, SceneError};

mod flame;
mod keys;
mod lens;
mod numbers;
mod palette;
mod read;
mod render;
mod words;

impl Scene {
    /// Parses scene text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, SceneError> {
        let raw: SceneToml = toml::from_str(text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            let (line, column) = line_col(text, span.start);
            let field = words::key_path(&e).map(|p| words::with_index(&p, text, span.start));
            let message = words::in_user_words(e.message());
            let message = match &field {
                Some(f) => format!("`{f}`: {message}"),
                None => message,
            };
            SceneError { file: file.to_string(), line, column, field, message }
        })?;
        Checker { text, file }.scene(raw)
    }
}

/// 1-based line and column (in characters) of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// Second pass: meaning checks with located errors.
struct Checker<'a> {
    text: &'a str,
    file: &'a str,
}

type Res<T> = Result<T, SceneError>;

impl Checker<'_> {
    fn err(&self, span: Range<usize>, field: &str, message: impl Into<String>) -> SceneError {
        let (line, column) = line_col(self.text, span.start);
        let message = message.into();
        SceneError {
            file: self.file.to_string(),
            line,
            column,
            field: Some(field.to_string()),
            message: format!("`{field}`: {message}"),
        }
    }

    /// A field that names one of a few words: its value by `parse`, or a located error that
    /// says it is not `what` and lists the `words`.
    fn named<T>(
        &self,
        v: &toml::Spanned<String>,
        field: &str,
        parse: impl Fn(&str) -> Option<T>,
        what: &str,
        words: &str,
    ) -> Res<T> {
        parse(v.get_ref())
            .ok_or_else(|| self.err(v.span(), field, format!("`{}` is not {what}; use {words}", v.get_ref())))
    }

    fn vec3(&self, v: &Spanned<Vec<f64>>, field: &str, dim: usize) -> Res<DVec3> {
        let xs = v.get_ref();
        if xs.len() != dim {
            return Err(self.err(v.span(), field, format!("expected {dim} numbers, found {}", xs.len())));
        }
        self.coordinates(v.span(), xs, field)?;
        Ok(DVec3::new(xs[0], xs[1], if dim == 3 { xs[2] } else { 0.0 }))
    }

    fn color(&self, c: &Spanned<ColorToml>, field: &str) -> Res<[f32; 3]> {
        match c.get_ref() {
            ColorToml::Hex(s) => color::parse_hex(s).map(|srgb| srgb.map(color::srgb8_to_linear)).ok_or_else(|| {
                self.err(c.span(), field, format!("`{s}` is not a colour; write \"#rrggbb\" or [r, g, b] in 0..1"))
            }),
            ColorToml::Rgb(v) => {
                if v.len() != 3 || v.iter().any(|x| !(0.0..=1.0).contains(x)) {
                    return Err(self.err(c.span(), field, "an [r, g, b] colour needs 3 numbers in 0..1"));
                }
                Ok(color::srgb_to_linear([v[0] as f32, v[1] as f32, v[2] as f32]))
            }
        }
    }

    fn axis(&self, s: &Spanned<String>, field: &str) -> Res<Axis> {
        Axis::parse(s.get_ref()).ok_or_else(|| {
            self.err(s.span(), field, format!("`{}` is not an axis; use \"x\", \"y\" or \"z\"", s.get_ref()))
        })
    }

    fn matrix(&self, m: &Spanned<Vec<Vec<f64>>>, field: &str, dim: usize) -> Res<DMat3> {
        let rows = m.get_ref();
        if rows.len() != dim || rows.iter().any(|r| r.len() != dim) {
            return Err(self.err(
                m.span(),
                field,
                format!("expected a {dim}×{dim} matrix as {dim} rows of {dim} numbers"),
            ));
        }
        self.coordinates(m.span(), &rows.iter().flatten().copied().collect::<Vec<_>>(), field)?;
        let at = |r: usize, c: usize| if r < dim && c < dim { rows[r][c] } else { 0.0 };
        // Rows as written; glam is column-major.
        Ok(DMat3::from_cols(
            DVec3::new(at(0, 0), at(1, 0), at(2, 0)),
            DVec3::new(at(0, 1), at(1, 1), at(2, 1)),
            DVec3::new(at(0, 2), at(1, 2), at(2, 2)),
        ))
    }

    fn scene(&self, raw: SceneToml) -> Res<Scene> {
        if *raw.version.get_ref() != FORMAT_VERSION {
            return Err(self.err(
                raw.version.span(),
                "version",
                format!(
                    "this nlifs reads scene format version {FORMAT_VERSION}, the file says {}",
                    raw.version.get_ref()
                ),
            ));
        }
        let grid_span = raw.grid.span();
        let g = raw.grid.into_inner();
        let mut axes = [g.x.get_ref().clone(), g.y.get_ref().clone(), vec![0.0]];
        if let Some(z) = &g.z {
            axes[2] = z.get_ref().clone();
        }
        self.coordinates(g.x.span(), g.x.get_ref(), "grid.x")?;
        self.coordinates(g.y.span(), g.y.get_ref(), "grid.y")?;
        if let Some(z) = &g.z {
            self.coordinates(z.span(), z.get_ref(), "grid.z")?;
        }
        let domain = RectGrid { axes };
        if let Err(msg) = domain.validate() {
            let (span, field) = if msg.contains("axis x") {
                (g.x.span(), "grid.x")
            } else if msg.contains("axis y") {
                (g.y.span(), "grid.y")
            } else {
                (g.z.as_ref().map_or(grid_span.clone(), |z| z.span()), "grid.z")
            };
            return Err(self.err(span, field, msg));
        }
        for (axis, field) in [(&g.x, "grid.x"), (&g.y, "grid.y")].into_iter().chain(g.z.as_ref().map(|z| (z, "grid.z")))
        {
            self.supported_extent(axis, field)?;
        }
        if let Some(z) = &g.z
            && z.get_ref().len() < 2
        {
            return Err(self.err(
                z.span(),
                "grid.z",
                "a 3D grid needs at least 2 z coordinates (leave `z` out for 2D)",
            ));
        }
        let dim = domain.dimension();
        if raw.functions.is_empty() {
            return Err(self.err(0..0, "function", "the scene has no [[function]]"));
        }
        let mut functions = Vec::new();
        for (i, f) in raw.functions.iter().enumerate() {
            functions.push(self.function(i, f, &domain)?);
        }
        let probability_mode = match &raw.probabilities {
            None => {
                if functions.iter().all(|f| f.probability.is_some()) {
                    ProbabilityMode::Explicit
                } else {
                    ProbabilityMode::Contractivity
                }
            }
            Some(s) => match s.get_ref().as_str() {
                "explicit" => ProbabilityMode::Explicit,
                "contractivity" => ProbabilityMode::Contractivity,
                "adaptive" => ProbabilityMode::Adaptive,
                other => {
                    return Err(self.err(
                        s.span(),
                        "probabilities",
                        format!("`{other}` is not a mode; use \"explicit\", \"contractivity\" or \"adaptive\""),
                    ));
                }
            },
        };
        if probability_mode == ProbabilityMode::Explicit
            && let Some((i, _)) = functions.iter().enumerate().find(|(_, f)| f.probability.is_none())
        {
            return Err(self.err(
                raw.functions[i].span(),
                &format!("function[{i}].probability"),
                "explicit probabilities need a `probability` on every function",
            ));
        }
        let n = functions.len();
        for (i, f) in raw.functions.iter().enumerate() {
            let Some(row) = &f.get_ref().xaos else { continue };
            let field = format!("function[{i}].xaos");
            if row.get_ref().len() > n {
                let msg = format!("has {} entries; the scene has {n} functions (one entry each)", row.get_ref().len());
                return Err(self.err(row.span(), &field, msg));
            }
            if probability_mode == ProbabilityMode::Adaptive {
                let msg = "xaos draws the next function after the last; adaptive probabilities draw it by the point's place: use one of them";
                return Err(self.err(row.span(), &field, msg));
            }
        }
        let camera = match &raw.camera {
            None => CameraSpec::default(),
            Some(c) => self.camera("camera", c, dim)?,
        };
        let render = match &raw.render {
            None => RenderSettings::default(),
            Some(r) => self.render(r)?,
        };
        let timeline = self.timeline(raw.timeline.as_ref(), &raw.keys, &functions, &domain)?;
        let final_xform = match &raw.final_xform {
            None => None,
            Some(f) => Some(FinalXform {
                def: self.flame_def("final", f.span(), f.get_ref().flame(), None)?,
                palette_index: self
                    .palette_index(f.get_ref().palette_index.as_ref(), "final.palette_index")?
                    .unwrap_or(0.0),
            }),
        };
        Ok(Scene {
            path: None,
            name: raw.name.unwrap_or_else(|| "untitled".into()),
            description: raw.description.unwrap_or_default(),
            domain,
            functions,
            probability_mode,
            camera,
            render,
            timeline,
            final_xform,
        })
    }

    fn function(&self, i: usize, f: &Spanned<FunctionToml>, domain: &RectGrid) -> Res<FunctionSpec> {
        let dim = domain.dimension();
        let span = f.span();
        let f = f.get_ref();
        let field = |name: &str| format!("function[{i}].{name}");
        let kind = f.kind.get_ref().as_str();
        // Fields that belong to another kind are errors, so typos in the kind do not pass silently.
        let allowed: &[&str] = match kind {
            "grid" => &["points"],
            "builder" => &["resolution", "steps"],
            "affine" => &["matrix", "offset"],
            "julia" => &["c", "sign"],
            "flame" => &flame::FLAME_FIELDS,
            other => {
                return Err(self.err(
                    f.kind.span(),
                    &field("kind"),
                    format!(
                        "`{other}` is not a function kind; use \"grid\", \"builder\", \"affine\", \"julia\" or \"flame\""
                    ),
                ));
            }
        };
        let present: [(&str, Option<Range<usize>>); 8] = [
            ("points", f.points.as_ref().map(|v| v.span())),
            ("resolution", f.resolution.as_ref().map(|v| v.span())),
            ("steps", f.steps.as_ref().map(|v| v.span())),
            ("matrix", f.matrix.as_ref().map(|v| v.span())),
            ("offset", f.offset.as_ref().map(|v| v.span())),
            ("c", f.c.as_ref().map(|v| v.span())),
            ("sign", f.sign.as_ref().map(|v| v.span())),
            ("kind", None),
        ];
        let flame_fields = f.flame().present().into_iter().map(|(n, s)| (n, Some(s)));
        for (name, s) in present.into_iter().chain(flame_fields) {
            if let Some(s) = s
                && !allowed.contains(&name)
            {
                return Err(self.err(s, &field(name), format!("is not a field of a `{kind}` function")));
            }
        }
        let missing = |name: &str| self.err(span.clone(), &field(name), format!("a `{kind}` function needs `{name}`"));
        let def = match kind {
            "grid" => {
                let pts = f.points.as_ref().ok_or_else(|| missing("points"))?;
                let expected = domain.point_count();
                if pts.get_ref().len() != expected {
                    let d = domain.dims();
                    return Err(self.err(
                        pts.span(),
                        &field("points"),
                        format!(
                            "has {} points, the {}×{}×{} grid has {expected}",
                            pts.get_ref().len(),
                            d[0],
                            d[1],
                            d[2]
                        ),
                    ));
                }
                let points = pts
                    .get_ref()
                    .iter()
                    .enumerate()
                    .map(|(k, p)| self.vec3(p, &format!("function[{i}].points[{k}]"), dim))
                    .collect::<Res<Vec<_>>>()?;
                FunctionDef::Grid { points }
            }
            "builder" => {
                let resolution = match &f.resolution {
                    None => {
                        if dim == 3 {
                            [5, 5, 5]
                        } else {
                            [9, 9, 1]
                        }
                    }
                    Some(r) => {
                        let v = r.get_ref();
                        if v.len() != dim || v.iter().any(|&n| !(2..=64).contains(&n)) {
                            return Err(self.err(
                                r.span(),
                                &field("resolution"),
                                format!("expected {dim} point counts, each from 2 to 64"),
                            ));
                        }
                        [v[0] as usize, v[1] as usize, if dim == 3 { v[2] as usize } else { 1 }]
                    }
                };
                let steps = f.steps.as_ref().ok_or_else(|| missing("steps"))?;
                let centre = 0.5 * (domain.min() + domain.max());
                let mut out = Vec::new();
                for (k, s) in steps.get_ref().iter().enumerate() {
                    out.push(self.step(&format!("function[{i}].steps[{k}]"), s, domain, centre)?);
                }
                let def = FunctionDef::Builder { resolution, builder: Builder { steps: out } };
                self.resolves_finite(&def, domain, steps.span(), &field("steps"))?;
                def
            }
            "affine" => {
                let matrix = self.matrix(f.matrix.as_ref().ok_or_else(|| missing("matrix"))?, &field("matrix"), dim)?;
                let offset = match &f.offset {
                    None => DVec3::ZERO,
                    Some(o) => self.vec3(o, &field("offset"), dim)?,
                };
                FunctionDef::Affine(AffineMap { matrix, offset })
            }
            "flame" => FunctionDef::Flame(self.flame_def(&format!("function[{i}]"), span.clone(), f.flame(), None)?),
            _ => {
                if dim != 2 {
                    return Err(self.err(
                        f.kind.span(),
                        &field("kind"),
                        "a `julia` function works in the complex plane and needs a 2D grid",
                    ));
                }
                let c = self.vec3(f.c.as_ref().ok_or_else(|| missing("c"))?, &field("c"), 2)?;
                let sign = match &f.sign {
                    None => 1.0,
                    Some(s) if *s.get_ref() == 1.0 || *s.get_ref() == -1.0 => *s.get_ref(),
                    Some(s) => return Err(self.err(s.span(), &field("sign"), "must be 1 or -1")),
                };
                FunctionDef::Julia(JuliaMap { c: [c.x, c.y], sign })
            }
        };
        let color = match &f.color {
            None => color::palette_color(i),
            Some(c) => self.color(c, &field("color"))?,
        };
        let probability = match &f.probability {
            None => None,
            Some(p) => {
                let v = self.finite(p, &field("probability"))?;
                if v < 0.0 {
                    return Err(self.err(p.span(), &field("probability"), "must not be negative"));
                }
                Some(v)
            }
        };
        Ok(FunctionSpec {
            name: f.name.clone().unwrap_or_else(|| format!("f{}", i + 1)),
            color,
            probability,
            enabled: f.enabled.unwrap_or(true),
            def,
            palette_index: self.palette_index(f.palette_index.as_ref(), &field("palette_index"))?,
            xaos: match &f.xaos {
                None => Vec::new(),
                Some(row) => {
                    if let Some(v) = row.get_ref().iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                        return Err(self.err(row.span(), &field("xaos"), format!("{v} is not a number ≥ 0")));
                    }
                    row.get_ref().clone()
                }
            },
        })
    }

    /// Whether a builder's steps keep every sampled point a number: each parameter is bounded,
    /// but a chain of large scales can still overflow f64, and one infinite corner would turn
    /// every later computation on the map into NaN.
    pub(super) fn resolves_finite(
        &self,
        def: &FunctionDef,
        domain: &RectGrid,
        span: Range<usize>,
        field: &str,
    ) -> Res<()> {
        let FunctionDef::Builder { resolution, builder } = def else { return Ok(()) };
        let grid = RectGrid::uniform(domain.min(), domain.max(), *resolution);
        if let Some(p) = grid.points().into_iter().find(|&p| !builder.apply(p).is_finite()) {
            return Err(self.err(
                span,
                field,
                format!(
                    "the steps send the grid point ({}, {}, {}) past the largest number; use smaller factors",
                    p.x, p.y, p.z
                ),
            ));
        }
        Ok(())
    }

    fn step(&self, prefix: &str, s: &Spanned<StepToml>, domain: &RectGrid, centre: DVec3) -> Res<Step> {
        let dim = domain.dimension();
        let field = |name: &str| format!("{prefix}.{name}");
        let span = s.span();
        let s = s.get_ref();
        let op = s.op.get_ref().as_str();
        let allowed: &[&str] = match op {
            "scale" => &["by", "center"],
            "rotate" => &["axis", "degrees", "center"],
            "translate" => &["by"],
            "taper" => &["axis", "amount", "range", "center"],
            "twist" => &["axis", "along", "degrees", "range", "center"],
            "bend" => &["axis", "toward", "degrees", "range", "center"],
            "affine" => &["matrix", "offset"],
            other => {
                return Err(self.err(
                    s.op.span(),
                    &field("op"),
                    format!("`{other}` is not a step; use scale, rotate, translate, taper, twist, bend or affine"),
                ));
            }
        };
        let present: [(&str, Option<Range<usize>>); 10] = [
            ("by", s.by.as_ref().map(|v| v.span())),
            ("along", s.along.as_ref().map(|v| v.span())),
            ("axis", s.axis.as_ref().map(|v| v.span())),
            ("toward", s.toward.as_ref().map(|v| v.span())),
            ("degrees", s.degrees.as_ref().map(|v| v.span())),
            ("amount", s.amount.as_ref().map(|v| v.span())),
            ("range", s.range.as_ref().map(|v| v.span())),
            ("center", s.center.as_ref().map(|v| v.span())),
            ("matrix", s.matrix.as_ref().map(|v| v.span())),
            ("offset", s.offset.as_ref().map(|v| v.span())),
        ];
        for (name, sp) in present {
            if let Some(sp) = sp
                && !allowed.contains(&name)
            {
                return Err(self.err(sp, &field(name), format!("is not a parameter of a `{op}` step")));
            }
        }
        let missing = |name: &str| self.err(span.clone(), &field(name), format!("a `{op}` step needs `{name}`"));
        let center = match &s.center {
            None => centre,
            Some(c) => self.vec3(c, &field("center"), dim)?,
        };
        let axis = |default: Option<Axis>| -> Res<Axis> {
            match &s.axis {
                Some(a) => self.axis(a, &field("axis")),
                None => default.ok_or_else(|| missing("axis")),
            }
        };
        let default_axis = if dim == 2 { Some(Axis::Z) } else { None };
        let range_along = |a: Axis| -> Res<[f64; 2]> {
            match &s.range {
                None => Ok([domain.min()[a.index()], domain.max()[a.index()]]),
                Some(r) => {
                    let v = r.get_ref();
                    if v.len() != 2 || v[0] == v[1] {
                        return Err(self.err(r.span(), &field("range"), "expected [start, end] with start ≠ end"));
                    }
                    self.coordinates(r.span(), v, &field("range"))?;
                    if !(v[1] - v[0]).is_finite() {
                        return Err(self.err(r.span(), &field("range"), "start and end are too far apart"));
                    }
                    Ok([v[0], v[1]])
                }
            }
        };
        let by = |default_scalar: bool| -> Res<DVec3> {
            let b = s.by.as_ref().ok_or_else(|| missing("by"))?;
            match b.get_ref() {
                VectorToml::Scalar(x) if default_scalar => {
                    self.coordinates(b.span(), &[*x], &field("by"))?;
                    Ok(if dim == 3 { DVec3::splat(*x) } else { DVec3::new(*x, *x, 1.0) })
                }
                VectorToml::Scalar(_) => Err(self.err(b.span(), &field("by"), format!("expected {dim} numbers"))),
                VectorToml::Vector(v) => {
                    let mut p = self.vec3(&Spanned::new(b.span(), v.clone()), &field("by"), dim)?;
                    if dim == 2 && default_scalar {
                        p.z = 1.0;
                    }
                    Ok(p)
                }
            }
        };
        let number = |v: &Option<Spanned<f64>>, name: &str| -> Res<f64> {
            let v = v.as_ref().ok_or_else(|| missing(name))?;
            self.finite(v, &field(name))
        };
        let degrees = |name: &str| -> Res<f64> {
            let v = s.degrees.as_ref().ok_or_else(|| missing(name))?;
            self.angle(v, &field(name))
        };
        let step = match op {
            "scale" => Step::Scale { by: by(true)?, center },
            "rotate" => Step::Rotate { axis: axis(default_axis)?, degrees: degrees("degrees")?, center },
            "translate" => Step::Translate { by: by(false)? },
            "taper" => {
                let a = axis(if dim == 2 { Some(Axis::Y) } else { None })?;
                if dim == 2 && a == Axis::Z {
                    return Err(self.err(span, &field("axis"), "a 2D taper runs along x or y"));
                }
                let amount = number(&s.amount, "amount")?;
                if !(-4.0..=1.0).contains(&amount) {
                    return Err(self.err(
                        s.amount.as_ref().map_or(span.clone(), |a| a.span()),
                        &field("amount"),
                        "must lie in -4..1 (1 tapers to a point)",
                    ));
                }
                Step::Taper { axis: a, amount, range: range_along(a)?, center }
            }
            "twist" => {
                let a = axis(default_axis)?;
                let along = match &s.along {
                    Some(x) => self.axis(x, &field("along"))?,
                    None if dim == 2 => Axis::Y,
                    None => a,
                };
                if dim == 2 && (a != Axis::Z || along == Axis::Z) {
                    return Err(self.err(
                        span,
                        &field("axis"),
                        "a 2D twist rotates about z, with the angle growing `along` x or y",
                    ));
                }
                Step::Twist { axis: a, along, degrees: degrees("degrees")?, range: range_along(along)?, center }
            }
            "bend" => {
                let a = axis(None)?;
                let t = self.axis(s.toward.as_ref().ok_or_else(|| missing("toward"))?, &field("toward"))?;
                if a == t {
                    return Err(self.err(span, &field("toward"), "must differ from `axis`"));
                }
                if dim == 2 && (a == Axis::Z || t == Axis::Z) {
                    return Err(self.err(span, &field("axis"), "a 2D bend uses the x and y axes"));
                }
                Step::Bend { axis: a, toward: t, degrees: degrees("degrees")?, range: range_along(a)?, center }
            }
            _ => {
                let matrix = self.matrix(s.matrix.as_ref().ok_or_else(|| missing("matrix"))?, &field("matrix"), dim)?;
                let offset = match &s.offset {
                    None => DVec3::ZERO,
                    Some(o) => self.vec3(o, &field("offset"), dim)?,
                };
                Step::Affine { matrix, offset }
            }
        };
        Ok(step)
    }

    fn camera(&self, prefix: &str, c: &CameraToml, dim: usize) -> Res<CameraSpec> {
        let mut out = CameraSpec::default();
        if let Some(y) = &c.yaw_deg {
            out.yaw_deg = Some(self.angle(y, &format!("{prefix}.yaw_deg"))?);
        }
        if let Some(t) = &c.target {
            out.target = Some(self.vec3(t, &format!("{prefix}.target"), 3.min(t.get_ref().len().max(dim)))?);
        }
        if let Some(p) = &c.pitch_deg {
            let v = self.finite(p, &format!("{prefix}.pitch_deg"))?;
            if !(-89.9..=89.9).contains(&v) {
                return Err(self.err(p.span(), &format!("{prefix}.pitch_deg"), "must lie in -89.9..89.9"));
            }
            out.pitch_deg = Some(v);
        }
        if let Some(d) = &c.distance {
            let v = self.finite(d, &format!("{prefix}.distance"))?;
            if !(v > 0.0 && v <= MAX_COORDINATE) {
                return Err(self.err(
                    d.span(),
                    &format!("{prefix}.distance"),
                    format!("must be positive and at most {MAX_COORDINATE:e}, found {}", words::show(v)),
                ));
            }
            out.distance = Some(v);
        }
        if let Some(f) = &c.fov_y_deg {
            let v = self.finite(f, &format!("{prefix}.fov_y_deg"))?;
            if !(1.0..=170.0).contains(&v) {
                return Err(self.err(f.span(), &format!("{prefix}.fov_y_deg"), "must lie in 1..170"));
            }
            out.fov_y_deg = Some(v);
        }
        if let Some(p) = &c.projection {
            out.projection = Some(match p.get_ref().as_str() {
                "perspective" => Projection::Perspective,
                "parallel" => Projection::Parallel,
                other => {
                    return Err(self.err(
                        p.span(),
                        &format!("{prefix}.projection"),
                        format!("`{other}` is not a projection; use \"perspective\" or \"parallel\""),
                    ));
                }
            });
        }
        Ok(out)
    }
}
