//! Scene files: the versioned TOML format (documented in README.md) and the scene model.
//!
//! Parsing is two passes. serde reads the text into `*Toml` structs that keep the span of every
//! field (`toml::Spanned`), with unknown fields rejected; then `Scene::from_toml` checks the
//! meaning (counts, ranges, names) and reports any problem with the file, line, column and
//! field. A [`Scene`] keeps functions as editable definitions (builders stay parameters); the
//! resolved [`Ifs`] for a time comes from [`Scene::at`].

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use serde::Deserialize;
use toml::Spanned;

use crate::camera::{OrbitCamera, Projection};
use crate::color;
use crate::model::builder::{Axis, Builder, Step};
use crate::model::{AffineMap, Function, GridMap, Ifs, JuliaMap, Map, ProbabilityMode, RectGrid};
use crate::splat::SplatMode;
use crate::timeline::{self, Ease, FunctionKey, Interpolation, Key, LoopMode, RenderKey, Timeline};

/// The scene format version this build reads and writes.
pub const FORMAT_VERSION: i64 = 1;

/// A problem in a scene file, located.
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}:{column}: {message}")]
pub struct SceneError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    /// The dotted path of the field at fault, when known (e.g. `function[2].points`).
    pub field: Option<String>,
    pub message: String,
}

#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("cannot read scene file {path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error(transparent)]
    Scene(#[from] SceneError),
}

// ---------------------------------------------------------------------------------------------
// The file as written.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    version: Spanned<i64>,
    name: Option<String>,
    description: Option<String>,
    grid: Spanned<GridToml>,
    #[serde(default, rename = "function")]
    functions: Vec<Spanned<FunctionToml>>,
    probabilities: Option<Spanned<String>>,
    camera: Option<CameraToml>,
    render: Option<RenderToml>,
    timeline: Option<Spanned<TimelineToml>>,
    #[serde(default, rename = "key")]
    keys: Vec<Spanned<KeyToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TimelineToml {
    #[serde(rename = "loop")]
    loop_mode: Option<Spanned<String>>,
    duration_secs: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyToml {
    t_secs: Spanned<f64>,
    interpolation: Option<Spanned<String>>,
    ease: Option<Spanned<String>>,
    #[serde(default, rename = "function")]
    functions: Vec<Spanned<KeyFunctionToml>>,
    camera: Option<CameraToml>,
    render: Option<KeyRenderToml>,
}

/// A key's override of one function: the fields of its kind that hold numbers.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyFunctionToml {
    name: Spanned<String>,
    points: Option<Spanned<Vec<Spanned<Vec<f64>>>>>,
    steps: Option<Spanned<Vec<Spanned<StepToml>>>>,
    matrix: Option<Spanned<Vec<Vec<f64>>>>,
    offset: Option<Spanned<Vec<f64>>>,
    c: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyRenderToml {
    points: Option<Spanned<i64>>,
    background: Option<Spanned<ColorToml>>,
    depth_cue: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridToml {
    x: Spanned<Vec<f64>>,
    y: Spanned<Vec<f64>>,
    z: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ColorToml {
    Hex(String),
    Rgb(Vec<f64>),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum VectorToml {
    Scalar(f64),
    Vector(Vec<f64>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FunctionToml {
    name: Option<String>,
    kind: Spanned<String>,
    color: Option<Spanned<ColorToml>>,
    probability: Option<Spanned<f64>>,
    enabled: Option<bool>,
    points: Option<Spanned<Vec<Spanned<Vec<f64>>>>>,
    resolution: Option<Spanned<Vec<i64>>>,
    steps: Option<Spanned<Vec<Spanned<StepToml>>>>,
    matrix: Option<Spanned<Vec<Vec<f64>>>>,
    offset: Option<Spanned<Vec<f64>>>,
    c: Option<Spanned<Vec<f64>>>,
    sign: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepToml {
    op: Spanned<String>,
    by: Option<Spanned<VectorToml>>,
    axis: Option<Spanned<String>>,
    toward: Option<Spanned<String>>,
    along: Option<Spanned<String>>,
    degrees: Option<Spanned<f64>>,
    amount: Option<Spanned<f64>>,
    range: Option<Spanned<Vec<f64>>>,
    center: Option<Spanned<Vec<f64>>>,
    matrix: Option<Spanned<Vec<Vec<f64>>>>,
    offset: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    target: Option<Spanned<Vec<f64>>>,
    yaw_deg: Option<f64>,
    pitch_deg: Option<Spanned<f64>>,
    distance: Option<Spanned<f64>>,
    fov_y_deg: Option<Spanned<f64>>,
    projection: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderToml {
    width: Option<Spanned<i64>>,
    height: Option<Spanned<i64>>,
    points: Option<Spanned<i64>>,
    seed: Option<Spanned<i64>>,
    mode: Option<Spanned<String>>,
    background: Option<Spanned<ColorToml>>,
    depth_cue: Option<Spanned<f64>>,
}

// ---------------------------------------------------------------------------------------------
// The scene model.

/// How a function is defined in the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum FunctionDef {
    /// Explicit transformed points of the scene grid.
    Grid {
        points: Vec<DVec3>,
    },
    /// Builder steps sampled on a uniform grid of `resolution` points over the scene grid's box.
    Builder {
        resolution: [usize; 3],
        builder: Builder,
    },
    Affine(AffineMap),
    Julia(JuliaMap),
}

#[derive(Clone, Debug, PartialEq)]
pub struct FunctionSpec {
    pub name: String,
    /// Linear RGB.
    pub color: [f32; 3],
    pub probability: Option<f64>,
    pub enabled: bool,
    pub def: FunctionDef,
}

/// Camera settings from the scene; unset fields are derived from the attractor's bounds.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CameraSpec {
    pub target: Option<DVec3>,
    pub yaw_deg: Option<f64>,
    pub pitch_deg: Option<f64>,
    pub distance: Option<f64>,
    pub fov_y_deg: Option<f64>,
    pub projection: Option<Projection>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub points: u64,
    pub seed: u32,
    pub mode: SplatMode,
    /// Linear RGB.
    pub background: [f32; 3],
    /// 0: no depth cueing; 1: the farthest points fade to the background.
    pub depth_cue: f32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 960,
            height: 720,
            points: 4_000_000,
            seed: 1,
            mode: SplatMode::Closest,
            background: [0x0b, 0x0d, 0x14].map(color::srgb8_to_linear),
            depth_cue: 0.75,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub path: Option<PathBuf>,
    pub name: String,
    pub description: String,
    pub domain: RectGrid,
    pub functions: Vec<FunctionSpec>,
    pub probability_mode: ProbabilityMode,
    pub camera: CameraSpec,
    pub render: RenderSettings,
    /// Keys animating the functions, camera and render settings; None for a still scene.
    pub timeline: Option<Timeline>,
}

impl Scene {
    /// Reads and checks a scene file.
    pub fn load(path: &Path) -> Result<Self, LoadError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| LoadError::Io { path: path.display().to_string(), source })?;
        let mut scene = Self::parse(&text, &path.display().to_string())?;
        scene.path = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses scene text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, SceneError> {
        let raw: SceneToml = toml::from_str(text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            let (line, column) = line_col(text, span.start);
            SceneError { file: file.to_string(), line, column, field: None, message: e.message().trim().to_string() }
        })?;
        Checker { text, file }.scene(raw)
    }

    /// The resolved IFS at scene time `t_secs`: every function's definition interpolated
    /// between the keys around `t_secs`, then resolved (scenes without a timeline are static).
    pub fn at(&self, t_secs: f64) -> Ifs {
        let functions = self
            .functions
            .iter()
            .enumerate()
            .map(|(i, f)| Function {
                name: f.name.clone(),
                map: self.resolve(&self.function_def_at(i, t_secs)),
                color: f.color,
                weight: f.probability,
                enabled: f.enabled,
            })
            .collect();
        Ifs { domain: self.domain.clone(), functions, probability_mode: self.probability_mode }
    }

    /// Function `i`'s definition at scene time `t_secs` (interpolated, not yet resolved).
    pub fn function_def_at(&self, i: usize, t_secs: f64) -> FunctionDef {
        let base = &self.functions[i].def;
        let Some(tl) = &self.timeline else { return base.clone() };
        tl.channel_at(t_secs, |k| k.function(i).map(timeline::flatten))
            .and_then(|v| timeline::unflatten(base, &v))
            .unwrap_or_else(|| base.clone())
    }

    /// The camera settings at scene time `t_secs`: each orbit parameter interpolated over the
    /// keys that set it, else the scene's.
    pub fn camera_at(&self, t_secs: f64) -> CameraSpec {
        let mut out = self.camera.clone();
        let Some(tl) = &self.timeline else { return out };
        let scalar = |get: fn(&CameraSpec) -> Option<f64>| {
            tl.channel_at(t_secs, |k| get(&k.camera).map(|v| vec![v])).map(|v| v[0])
        };
        // Yaw is an angle: keys are joined the short way round (see `sample_channel_wrapped`).
        if let Some(v) = tl.angle_channel_at(t_secs, Some(360.0), |k| k.camera.yaw_deg.map(|v| vec![v])) {
            out.yaw_deg = Some(v[0]);
        }
        if let Some(v) = scalar(|c| c.pitch_deg) {
            out.pitch_deg = Some(v.clamp(-89.9, 89.9));
        }
        if let Some(v) = scalar(|c| c.distance) {
            out.distance = Some(v.max(1e-9));
        }
        if let Some(v) = scalar(|c| c.fov_y_deg) {
            out.fov_y_deg = Some(v.clamp(1.0, 170.0));
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.camera.target.map(|p| p.to_array().to_vec())) {
            out.target = Some(DVec3::new(v[0], v[1], v[2]));
        }
        if let Some(k) = tl.held_key(t_secs, |k| k.camera.projection.is_some()) {
            out.projection = k.camera.projection;
        }
        out
    }

    /// The render settings at scene time `t_secs` (depth cue, background and point count may be
    /// keyed).
    pub fn render_at(&self, t_secs: f64) -> RenderSettings {
        let mut out = self.render.clone();
        let Some(tl) = &self.timeline else { return out };
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.depth_cue.map(|v| vec![v as f64])) {
            out.depth_cue = v[0].clamp(0.0, 1.0) as f32;
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.background.map(|c| c.iter().map(|&x| x as f64).collect())) {
            out.background = [0, 1, 2].map(|c| v[c].clamp(0.0, 1.0) as f32);
        }
        if let Some(v) = tl.channel_at(t_secs, |k| k.render.points.map(|n| vec![n as f64])) {
            out.points = v[0].round().max(1.0) as u64;
        }
        out
    }

    /// Turns one definition into a map over the scene's grid.
    pub fn resolve(&self, def: &FunctionDef) -> Map {
        match def {
            FunctionDef::Grid { points } => Map::Grid(GridMap::new(self.domain.clone(), points.clone())),
            FunctionDef::Builder { resolution, builder } => {
                let grid = RectGrid::uniform(self.domain.min(), self.domain.max(), *resolution);
                Map::Grid(GridMap::from_fn(grid, |p| builder.apply(p)))
            }
            FunctionDef::Affine(a) => Map::Affine(a.clone()),
            FunctionDef::Julia(j) => Map::Julia(j.clone()),
        }
    }

    /// The scene camera (at time 0) with unset fields filled in from `bounds` (the attractor's box).
    pub fn camera_for(&self, bounds: (DVec3, DVec3)) -> OrbitCamera {
        self.camera_for_at(0.0, bounds)
    }

    /// The camera at scene time `t_secs` with unset fields filled in from `bounds`.
    pub fn camera_for_at(&self, t_secs: f64, bounds: (DVec3, DVec3)) -> OrbitCamera {
        let dim = self.domain.dimension();
        let mut cam = OrbitCamera::framing(bounds, dim);
        let c = &self.camera_at(t_secs);
        if let Some(v) = c.yaw_deg {
            cam.yaw_deg = v as f32;
        }
        if let Some(v) = c.pitch_deg {
            cam.pitch_deg = v as f32;
        }
        if let Some(v) = c.fov_y_deg {
            cam.fov_y_deg = v as f32;
        }
        if let Some(v) = c.projection {
            cam.projection = v;
        }
        if let Some(v) = c.target {
            cam.target = v.as_vec3();
        }
        // Re-frame with the final angles unless the distance is given.
        cam.distance = match c.distance {
            Some(d) => d as f32,
            None => cam.framing_distance(bounds),
        };
        cam
    }
}

/// 1-based line and column (in characters) of byte `offset` in `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
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

    fn finite(&self, v: &Spanned<f64>, field: &str) -> Res<f64> {
        if v.get_ref().is_finite() {
            Ok(*v.get_ref())
        } else {
            Err(self.err(v.span(), field, "must be a finite number"))
        }
    }

    fn vec3(&self, v: &Spanned<Vec<f64>>, field: &str, dim: usize) -> Res<DVec3> {
        let xs = v.get_ref();
        if xs.len() != dim {
            return Err(self.err(v.span(), field, format!("expected {dim} numbers, found {}", xs.len())));
        }
        if xs.iter().any(|x| !x.is_finite()) {
            return Err(self.err(v.span(), field, "numbers must be finite"));
        }
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
        if rows.iter().flatten().any(|x| !x.is_finite()) {
            return Err(self.err(m.span(), field, "numbers must be finite"));
        }
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
        let camera = match &raw.camera {
            None => CameraSpec::default(),
            Some(c) => self.camera("camera", c, dim)?,
        };
        let render = match &raw.render {
            None => RenderSettings::default(),
            Some(r) => self.render(r)?,
        };
        let timeline = self.timeline(raw.timeline.as_ref(), &raw.keys, &functions, &domain)?;
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
            other => {
                return Err(self.err(
                    f.kind.span(),
                    &field("kind"),
                    format!("`{other}` is not a function kind; use \"grid\", \"builder\", \"affine\" or \"julia\""),
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
        for (name, s) in present {
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
                FunctionDef::Builder { resolution, builder: Builder { steps: out } }
            }
            "affine" => {
                let matrix = self.matrix(f.matrix.as_ref().ok_or_else(|| missing("matrix"))?, &field("matrix"), dim)?;
                let offset = match &f.offset {
                    None => DVec3::ZERO,
                    Some(o) => self.vec3(o, &field("offset"), dim)?,
                };
                FunctionDef::Affine(AffineMap { matrix, offset })
            }
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
        })
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
                    if v.len() != 2 || v.iter().any(|x| !x.is_finite()) || v[0] == v[1] {
                        return Err(self.err(r.span(), &field("range"), "expected [start, end] with start ≠ end"));
                    }
                    Ok([v[0], v[1]])
                }
            }
        };
        let by = |default_scalar: bool| -> Res<DVec3> {
            let b = s.by.as_ref().ok_or_else(|| missing("by"))?;
            match b.get_ref() {
                VectorToml::Scalar(x) if default_scalar && x.is_finite() => {
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
        let step = match op {
            "scale" => Step::Scale { by: by(true)?, center },
            "rotate" => Step::Rotate { axis: axis(default_axis)?, degrees: number(&s.degrees, "degrees")?, center },
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
                Step::Twist {
                    axis: a,
                    along,
                    degrees: number(&s.degrees, "degrees")?,
                    range: range_along(along)?,
                    center,
                }
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
                Step::Bend {
                    axis: a,
                    toward: t,
                    degrees: number(&s.degrees, "degrees")?,
                    range: range_along(a)?,
                    center,
                }
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

    fn timeline(
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
                if v <= 0.0 {
                    return Err(self.err(d.span(), "timeline.duration_secs", "must be positive"));
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
        let t_secs = self.finite(&k.t_secs, &field("t_secs"))?;
        if t_secs < 0.0 {
            return Err(self.err(k.t_secs.span(), &field("t_secs"), "must not be negative"));
        }
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
            };
            let present: [(&str, Option<Range<usize>>); 5] = [
                ("points", f.points.as_ref().map(|v| v.span())),
                ("steps", f.steps.as_ref().map(|v| v.span())),
                ("matrix", f.matrix.as_ref().map(|v| v.span())),
                ("offset", f.offset.as_ref().map(|v| v.span())),
                ("c", f.c.as_ref().map(|v| v.span())),
            ];
            for (field_name, s) in present {
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
                        FunctionDef::Builder { resolution: *resolution, builder: Builder { steps: out } }
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
            };
            if let Err(msg) = timeline::same_structure(base, &def) {
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
                if !(1..=1 << 40).contains(&x) {
                    return Err(self.err(
                        p.span(),
                        &field("render.points"),
                        format!("must lie in 1..={}, found {x}", 1u64 << 40),
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
        }
        Ok(Key { t_secs, interpolation, ease, functions: keyed, camera, render })
    }

    fn camera(&self, prefix: &str, c: &CameraToml, dim: usize) -> Res<CameraSpec> {
        let mut out = CameraSpec { yaw_deg: c.yaw_deg, ..Default::default() };
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
            if v <= 0.0 {
                return Err(self.err(d.span(), &format!("{prefix}.distance"), "must be positive"));
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

    fn render(&self, r: &RenderToml) -> Res<RenderSettings> {
        let mut out = RenderSettings::default();
        let int = |v: &Spanned<i64>, field: &str, lo: i64, hi: i64| -> Res<i64> {
            let x = *v.get_ref();
            if x < lo || x > hi {
                return Err(self.err(v.span(), field, format!("must lie in {lo}..={hi}, found {x}")));
            }
            Ok(x)
        };
        if let Some(v) = &r.width {
            out.width = int(v, "render.width", 1, 16384)? as u32;
        }
        if let Some(v) = &r.height {
            out.height = int(v, "render.height", 1, 16384)? as u32;
        }
        if let Some(v) = &r.points {
            out.points = int(v, "render.points", 1, 1 << 40)? as u64;
        }
        if let Some(v) = &r.seed {
            out.seed = int(v, "render.seed", 0, u32::MAX as i64)? as u32;
        }
        if let Some(m) = &r.mode {
            out.mode = SplatMode::parse(m.get_ref()).ok_or_else(|| {
                self.err(
                    m.span(),
                    "render.mode",
                    format!("`{}` is not a mode; use \"closest\", \"average\" or \"density\"", m.get_ref()),
                )
            })?;
        }
        if let Some(b) = &r.background {
            out.background = self.color(b, "render.background")?;
        }
        if let Some(d) = &r.depth_cue {
            let v = self.finite(d, "render.depth_cue")?;
            if !(0.0..=1.0).contains(&v) {
                return Err(self.err(d.span(), "render.depth_cue", "must lie in 0..1"));
            }
            out.depth_cue = v as f32;
        }
        Ok(out)
    }
}

// ---------------------------------------------------------------------------------------------
// Writing scenes back (for the viewer's save): every field explicit, so parse(to_toml(s)) == s.

/// TOML text of a number that reads back to the same f64 (Rust's shortest round-trip form).
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn nums(xs: &[f64]) -> String {
    format!("[{}]", xs.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", "))
}

fn vec_dim(v: DVec3, dim: usize) -> String {
    nums(&v.to_array()[..dim])
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A linear colour as "#rrggbb" when that reads back exactly, else as sRGB [r, g, b].
fn color_text(c: [f32; 3]) -> String {
    let srgb = c.map(color::linear_to_srgb);
    // The nearest byte; hex is written only when it decodes back to `c` exactly.
    let bytes = srgb.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8);
    if bytes.map(color::srgb8_to_linear) == c {
        format!("\"{}\"", color::hex_text(bytes))
    } else {
        format!("[{}]", srgb.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(", "))
    }
}

fn matrix_text(m: &DMat3, dim: usize) -> String {
    let rows: Vec<String> = (0..dim).map(|r| nums(&(0..dim).map(|c| m.col(c)[r]).collect::<Vec<_>>())).collect();
    format!("[{}]", rows.join(", "))
}

fn step_text(s: &Step, dim: usize) -> String {
    let v = |p: DVec3| vec_dim(p, dim);
    match s {
        Step::Scale { by, center } => format!("{{ op = \"scale\", by = {}, center = {} }}", v(*by), v(*center)),
        Step::Rotate { axis, degrees, center } => {
            format!(
                "{{ op = \"rotate\", axis = \"{}\", degrees = {}, center = {} }}",
                axis.name(),
                num(*degrees),
                v(*center)
            )
        }
        Step::Translate { by } => format!("{{ op = \"translate\", by = {} }}", v(*by)),
        Step::Taper { axis, amount, range, center } => {
            format!(
                "{{ op = \"taper\", axis = \"{}\", amount = {}, range = {}, center = {} }}",
                axis.name(),
                num(*amount),
                nums(range),
                v(*center)
            )
        }
        Step::Twist { axis, along, degrees, range, center } => format!(
            "{{ op = \"twist\", axis = \"{}\", along = \"{}\", degrees = {}, range = {}, center = {} }}",
            axis.name(),
            along.name(),
            num(*degrees),
            nums(range),
            v(*center)
        ),
        Step::Bend { axis, toward, degrees, range, center } => format!(
            "{{ op = \"bend\", axis = \"{}\", toward = \"{}\", degrees = {}, range = {}, center = {} }}",
            axis.name(),
            toward.name(),
            num(*degrees),
            nums(range),
            v(*center)
        ),
        Step::Affine { matrix, offset } => {
            format!("{{ op = \"affine\", matrix = {}, offset = {} }}", matrix_text(matrix, dim), v(*offset))
        }
    }
}

/// The number-holding fields of a definition (what a key may override), one per line.
fn def_fields(def: &FunctionDef, dim: usize) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    match def {
        FunctionDef::Grid { points } => {
            out += "points = [\n";
            for p in points {
                let _ = writeln!(out, "  {},", vec_dim(*p, dim));
            }
            out += "]\n";
        }
        FunctionDef::Builder { builder, .. } => {
            out += "steps = [\n";
            for s in &builder.steps {
                let _ = writeln!(out, "  {},", step_text(s, dim));
            }
            out += "]\n";
        }
        FunctionDef::Affine(a) => {
            let _ = writeln!(out, "matrix = {}", matrix_text(&a.matrix, dim));
            let _ = writeln!(out, "offset = {}", vec_dim(a.offset, dim));
        }
        FunctionDef::Julia(j) => {
            let _ = writeln!(out, "c = {}", nums(&j.c));
        }
    }
    out
}

fn camera_fields(c: &CameraSpec) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    if let Some(t) = c.target {
        let _ = writeln!(out, "target = {}", nums(&t.to_array()));
    }
    for (name, v) in
        [("yaw_deg", c.yaw_deg), ("pitch_deg", c.pitch_deg), ("distance", c.distance), ("fov_y_deg", c.fov_y_deg)]
    {
        if let Some(v) = v {
            let _ = writeln!(out, "{name} = {}", num(v));
        }
    }
    if let Some(p) = c.projection {
        let _ =
            writeln!(out, "projection = \"{}\"", if p == Projection::Perspective { "perspective" } else { "parallel" });
    }
    out
}

impl Scene {
    /// Writes [`Scene::to_toml`] to `path` atomically.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let text = self.to_toml();
        crate::io::write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))
    }

    /// The scene as format-version-1 TOML, with every setting explicit; reading it back gives
    /// an equal scene (colours are written as hex when that is exact, else as sRGB floats).
    pub fn to_toml(&self) -> String {
        use std::fmt::Write;
        let dim = self.domain.dimension();
        let mut out = String::new();
        let _ = writeln!(out, "version = {FORMAT_VERSION}");
        let _ = writeln!(out, "name = {}", toml_string(&self.name));
        if !self.description.is_empty() {
            let _ = writeln!(out, "description = {}", toml_string(&self.description));
        }
        let _ = writeln!(out, "probabilities = \"{}\"", self.probability_mode.name());
        out += "\n[grid]\n";
        for (a, name) in self.domain.axes.iter().zip(["x", "y", "z"]).take(dim) {
            let _ = writeln!(out, "{name} = {}", nums(a));
        }
        for f in &self.functions {
            out += "\n[[function]]\n";
            let _ = writeln!(out, "name = {}", toml_string(&f.name));
            let kind = match &f.def {
                FunctionDef::Grid { .. } => "grid",
                FunctionDef::Builder { .. } => "builder",
                FunctionDef::Affine(_) => "affine",
                FunctionDef::Julia(_) => "julia",
            };
            let _ = writeln!(out, "kind = \"{kind}\"");
            let _ = writeln!(out, "color = {}", color_text(f.color));
            if let Some(p) = f.probability {
                let _ = writeln!(out, "probability = {}", num(p));
            }
            if !f.enabled {
                out += "enabled = false\n";
            }
            match &f.def {
                FunctionDef::Builder { resolution, .. } => {
                    let _ = writeln!(
                        out,
                        "resolution = [{}]",
                        resolution[..dim].iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
                    );
                }
                FunctionDef::Julia(j) => {
                    let _ = writeln!(out, "sign = {}", num(j.sign));
                }
                _ => {}
            }
            out += &def_fields(&f.def, dim);
        }
        let camera = camera_fields(&self.camera);
        if !camera.is_empty() {
            out += "\n[camera]\n";
            out += &camera;
        }
        let r = &self.render;
        out += "\n[render]\n";
        let _ = writeln!(out, "width = {}\nheight = {}\npoints = {}\nseed = {}", r.width, r.height, r.points, r.seed);
        let _ = writeln!(
            out,
            "mode = \"{}\"\nbackground = {}\ndepth_cue = {:?}",
            r.mode.name(),
            color_text(r.background),
            r.depth_cue
        );
        if let Some(tl) = &self.timeline {
            out += "\n[timeline]\n";
            let _ = writeln!(out, "loop = \"{}\"\nduration_secs = {}", tl.loop_mode.name(), num(tl.duration_secs));
            for k in &tl.keys {
                out += "\n[[key]]\n";
                let _ = writeln!(
                    out,
                    "t_secs = {}\ninterpolation = \"{}\"\nease = \"{}\"",
                    num(k.t_secs),
                    k.interpolation.name(),
                    k.ease.name()
                );
                for fk in &k.functions {
                    out += "[[key.function]]\n";
                    let _ = writeln!(out, "name = {}", toml_string(&self.functions[fk.function].name));
                    out += &def_fields(&fk.def, dim);
                }
                let camera = camera_fields(&k.camera);
                if !camera.is_empty() {
                    out += "[key.camera]\n";
                    out += &camera;
                }
                let kr = &k.render;
                if kr != &RenderKey::default() {
                    out += "[key.render]\n";
                    if let Some(p) = kr.points {
                        let _ = writeln!(out, "points = {p}");
                    }
                    if let Some(b) = kr.background {
                        let _ = writeln!(out, "background = {}", color_text(b));
                    }
                    if let Some(d) = kr.depth_cue {
                        let _ = writeln!(out, "depth_cue = {d:?}");
                    }
                }
            }
        }
        out
    }
}
