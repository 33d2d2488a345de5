//! The plain data of a scene, shared by the file format, the timeline and the renderers: how a
//! function is defined ([`FunctionDef`], with its name and colour in [`FunctionSpec`]), the
//! camera settings ([`CameraSpec`]), the render settings ([`RenderSettings`], with the splat
//! mode) and the flat parameter vectors the timeline interpolates ([`flatten`], [`unflatten`]).
//! These types sit below both the scene format and the timeline so that neither needs the
//! other: a key holds a `FunctionDef`, the format reads one, and neither knows about `Scene`.

use glam::DVec3;

use crate::camera::Projection;
use crate::color;
use crate::flame::{Coefs, PaletteMode, VariationTerm, Xform};
use crate::model::builder::{Builder, Step};
use crate::model::{AffineMap, JuliaMap};
use crate::palette::Palette;
pub use crate::scene::blend::BlendSpace;

/// The most points one render draws, in the scene (`render.points`, `key.render.points`) and on
/// the command line (`render --points`, `record --points-per-frame`), so that both refuse the
/// same counts with the same words. 2^40 points take days on any machine of today; past it the
/// chunk arithmetic of the chaos game would need more than 32 bits of chunk index.
pub const MAX_POINTS: u64 = 1 << 40;

/// The largest magnitude of a coordinate, offset, centre, matrix entry or scale factor in a
/// scene. Squares of it (distances, norms, determinants) stay finite in f64, so every derived
/// quantity of a checked scene is a number.
pub const MAX_COORDINATE: f64 = 1e150;

/// The supported extent of a grid axis (its last coordinate minus its first). The renderers
/// work in f32: below 1e-6 the chaos game's points collapse onto one pixel and the ray
/// tracer's spheres to nothing; above 1e18 the renders go blank. Within it a scene renders the
/// same picture at any scale.
pub const GRID_EXTENT_RANGE: (f64, f64) = (1e-6, 1e18);

/// How far from the origin a grid may lie, in multiples of its extent along that axis: f32
/// has 24 bits, and a grid 1e5 widths away already shows the steps between f32 numbers in a
/// render (1e6: every point on a visible lattice).
pub const MAX_GRID_OFFSET_RATIO: f64 = 1e4;

/// The largest magnitude of an angle in degrees (steps' `degrees`, `camera.yaw_deg`): ten turns.
/// The renderers turn angles into f32 sines and cosines; beyond a few turns f32 has too few
/// digits left for the fraction of a turn.
pub const MAX_ANGLE_DEG: f64 = 3600.0;

/// The latest scene time in seconds (key times, `timeline.duration_secs`, `--time`): about 31
/// years, far beyond any animation, and small enough that a time of frame k at 1000 fps is
/// still exact to the microsecond in f64.
pub const MAX_TIME_SECS: f64 = 1e9;

/// How points become pixels; the splat (`src/splat.rs` and its GPU twin) explains each mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SplatMode {
    #[default]
    Closest,
    Average,
    Density,
}

impl SplatMode {
    pub const ALL: [SplatMode; 3] = [SplatMode::Closest, SplatMode::Average, SplatMode::Density];

    /// The space this mode mixes colours in for a scene's `blend_space`: that one in the
    /// average and density modes; closest mode draws its colours as they are, in linear light.
    pub fn blend_space(self, blend: BlendSpace) -> BlendSpace {
        if self == SplatMode::Closest { BlendSpace::Linear } else { blend }
    }

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "closest" => Some(SplatMode::Closest),
            "average" => Some(SplatMode::Average),
            "density" => Some(SplatMode::Density),
            _ => None,
        }
    }

    /// The mode's number in the shaders (`params.mode`, the `SPLAT_MODE` and `RESOLVE_MODE`
    /// pipeline constants of `chaos_game.wgsl` and `resolve.wgsl`).
    pub fn index(self) -> u32 {
        match self {
            SplatMode::Closest => 0,
            SplatMode::Average => 1,
            SplatMode::Density => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            SplatMode::Closest => "closest",
            SplatMode::Average => "average",
            SplatMode::Density => "density",
        }
    }
}

/// What density mode's full brightness means (`[render] density_scale`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DensityScale {
    /// log(1 + count) / log(1 + max count): the densest pixel is full. A picture keeps its
    /// contrast whatever it shows, but flattens as the points grow.
    #[default]
    Relative,
    /// flam3's: log(1 + d), d the pixel's points per point drawn and per square scene unit
    /// (at the camera's target): the attractor's own density, so a picture converges as points
    /// are added and keeps its brightness when the camera zooms.
    Absolute,
}

impl DensityScale {
    pub const ALL: [DensityScale; 2] = [DensityScale::Relative, DensityScale::Absolute];

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "relative" => Some(DensityScale::Relative),
            "absolute" => Some(DensityScale::Absolute),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DensityScale::Relative => "relative",
            DensityScale::Absolute => "absolute",
        }
    }
}

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
    /// One of flam3's xforms (`kind = "flame"`).
    Flame(FlameDef),
}

/// A flame function as the scene holds it: flam3's xform without the fields the scene keeps
/// elsewhere (its weight is the function's `probability`, its colour coordinate the function's
/// `palette_index`). The variations are in flam3's order (by variation number), each with all
/// of its parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct FlameDef {
    /// flam3's `coefs` `[a, b, c, d, e, f]`: x' = a·x + c·y + e, y' = b·x + d·y + f.
    pub coefs: Coefs,
    /// flam3's `post`, the same form; None: none.
    pub post: Option<Coefs>,
    /// The coefficients the variations that read their xform's (waves, popcorn, rings, fan)
    /// take, where they are not `coefs`: an imported flame's xform conjugated into nlifs's
    /// view keeps its file's here (`scene::flame_import`). None: `coefs`, flam3's rule.
    pub variation_coefs: Option<Coefs>,
    pub variations: Vec<VariationTerm>,
    /// s in c' = s·c_i + (1 − s)·c, in [0, 1] (flam3's `color_speed`; the other kinds' rule is
    /// s = ½).
    pub color_speed: f64,
    /// flam3's `opacity` in [0, 1]: the function's points are drawn with chance 10^(log₂
    /// opacity) (flam3's plotted weight; 1 draws all, 0 none), the orbit passes through it
    /// whatever it is.
    pub opacity: f64,
}

impl FlameDef {
    /// The default colour speed (flam3's, and the other kinds' (c + c_i) / 2).
    pub const DEFAULT_COLOR_SPEED: f64 = 0.5;
    /// The default opacity: every point drawn.
    pub const DEFAULT_OPACITY: f64 = 1.0;

    /// The xform this definition is, with selection weight 1 and colour coordinate 0 (the
    /// scene function's own are used where they matter).
    pub fn xform(&self) -> Xform {
        Xform {
            weight: 1.0,
            color: 0.0,
            color_speed: self.color_speed,
            opacity: self.opacity,
            coefs: self.coefs,
            post: self.post,
            variation_coefs: self.variation_coefs,
            variations: self.variations.clone(),
            chaos: Vec::new(),
        }
    }
}

/// flam3's final xform as the scene holds it (`[final]`): a flame definition applied to drawn
/// points, not to the orbit (`chaos_game/flame.rs`), and its colour coordinate; no selection
/// weight; `def.opacity` is the chance that it maps a drawn point (flam3's final opacity).
#[derive(Clone, Debug, PartialEq)]
pub struct FinalXform {
    pub def: FlameDef,
    /// The colour coordinate c_f in [0, 1]: the drawn point's coordinate is s·c_f + (1 − s)·c
    /// with s the definition's colour speed.
    pub palette_index: f64,
}

impl FinalXform {
    /// The xform the chaos game applies.
    pub fn xform(&self) -> Xform {
        Xform { color: self.palette_index, ..self.def.xform() }
    }
}

impl FunctionDef {
    /// The function's `kind` as the scene file spells it.
    pub fn kind(&self) -> &'static str {
        match self {
            FunctionDef::Grid { .. } => "grid",
            FunctionDef::Builder { .. } => "builder",
            FunctionDef::Affine(_) => "affine",
            FunctionDef::Julia(_) => "julia",
            FunctionDef::Flame(_) => "flame",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct FunctionSpec {
    pub name: String,
    /// Linear RGB.
    pub color: [f32; 3],
    pub probability: Option<f64>,
    pub enabled: bool,
    pub def: FunctionDef,
    // Palette colour (`src/palette.rs`):
    /// The colour coordinate c_i in [0, 1]; None: i / (n − 1) (`palette::default_index`).
    pub palette_index: Option<f64>,
    /// Xaos: the multipliers (≥ 0) of each next function's probability after this one, by
    /// function index; entries missing are 1, empty is none (`model::Function::xaos`).
    pub xaos: Vec<f64>,
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

/// How a closest-mode picture is lit (`[render] look`): `Paper` is the paper's depth-cued flat
/// colour, `Solid` lights normals from the depth buffer and darkens creases by ambient occlusion
/// (`src/resolve.rs` explains both). A preset for the `shading` and `occlusion` strengths, which
/// the scene may also set one by one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Look {
    Paper,
    Solid,
}

impl Look {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "paper" => Some(Look::Paper),
            "solid" => Some(Look::Solid),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Look::Paper => "paper",
            Look::Solid => "solid",
        }
    }
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
    /// The scene's look; None: the default for the scene's dimension
    /// (`crate::resolve::ResolveStyle::of`).
    pub look: Option<Look>,
    /// Lighting strength in [0, 1] (closest mode); None: the look's.
    pub shading: Option<f32>,
    /// Ambient occlusion strength in [0, 1] (closest mode); None: the look's.
    pub occlusion: Option<f32>,
    // flam3's tone controls, average and density modes (`crate::resolve::Tone`; the defaults
    // change nothing).
    /// Stops: the brightness is 2^exposure.
    pub exposure: f32,
    /// The density's alpha is raised to 1 / gamma.
    pub gamma: f32,
    /// Below this alpha the gamma curve blends into a straight line.
    pub gamma_threshold: f32,
    /// 1: gamma on the alpha; 0: gamma per channel.
    pub vibrancy: f32,
    /// Negative: highlights clip per channel; ≥ 0: they keep their hue (0) or fade to white.
    pub highlight_power: f32,
    /// Density mode: relative to the densest pixel, or flam3's absolute density.
    pub density_scale: DensityScale,
    /// Average and density modes: the space the colours are mixed and toned in.
    pub blend_space: BlendSpace,
    /// flam3's adaptive density estimation (density mode; `src/resolve/density_estimation.rs`);
    /// None: off.
    pub density_estimation: Option<DensityEstimation>,
    /// flam3's spatial filter (average and density modes; `crate::resolve::filter`); None: off.
    pub filter: Option<PixelFilter>,
    // Cast shadows from the key light (`crate::resolve::shadow`).
    /// Shadow strength in [0, 1] (closest mode); None: the look's.
    pub shadows: Option<f32>,
    /// The key light's direction relative to the camera: degrees from the view direction
    /// towards the right, and above the view's horizontal plane.
    pub light_yaw_deg: f32,
    pub light_pitch_deg: f32,
    // Depth of field (`crate::splat::lens`).
    /// Thin-lens radius in scene units; 0: no depth of field.
    pub aperture: f32,
    /// View distance that stays sharp; None: the camera's distance to its target.
    pub focus_distance: Option<f32>,
    // Colour by a colour coordinate (`src/palette.rs`, `src/chaos_game/color_coord.rs`):
    /// Per-function colour or a palette indexed by the colour coordinate.
    pub color: ColorMode,
    /// The palette of `color = "palette"`; None: `palette::DEFAULT`.
    pub palette: Option<Palette>,
    /// How a colour coordinate picks the palette's colour: its entry, or flam3's linear
    /// interpolation of the two around it.
    pub palette_mode: PaletteMode,
}

/// The key light's default direction relative to the camera (the solid look's
/// `crate::resolve::KEY_LIGHT`): degrees from the view direction towards the right, and above
/// the view's horizontal plane.
pub const KEY_LIGHT_YAW_DEG: f32 = -32.735_224;
pub const KEY_LIGHT_PITCH_DEG: f32 = 33.461_75;

/// The key light's fields in `[render]` (and `[key.render]`): name and range, in the order of
/// [`RenderSettings::light`].
pub const LIGHT_FIELDS: [(&str, f64, f64); 3] =
    [("shadows", 0.0, 1.0), ("light_yaw_deg", -180.0, 180.0), ("light_pitch_deg", -90.0, 90.0)];

impl RenderSettings {
    /// The space colours are mixed and toned in ([`SplatMode::blend_space`]).
    pub fn blend(&self) -> BlendSpace {
        self.mode.blend_space(self.blend_space)
    }

    /// The key light's direction in the order of the last two [`LIGHT_FIELDS`], to set.
    pub fn light_mut(&mut self) -> [&mut f32; 2] {
        [&mut self.light_yaw_deg, &mut self.light_pitch_deg]
    }
}

/// How points are coloured (`[render] color`): by their function's colour, or by the palette
/// entry of the colour coordinate they carry through the chaos game.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorMode {
    #[default]
    Function,
    Palette,
}

impl ColorMode {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "function" => Some(ColorMode::Function),
            "palette" => Some(ColorMode::Palette),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Function => "function",
            ColorMode::Palette => "palette",
        }
    }
}

/// flam3's tone controls in `[render]` (and `[key.render]`): name and range, in the order of
/// [`RenderSettings::tone`]. A highlight power below 0 is off (per-channel clipping).
pub const TONE_FIELDS: [(&str, f64, f64); 5] = [
    ("exposure", -10.0, 10.0),
    ("gamma", 0.1, 10.0),
    ("gamma_threshold", 0.0, 1.0),
    ("vibrancy", 0.0, 1.0),
    ("highlight_power", -1.0, 16.0),
];

impl RenderSettings {
    /// The tone settings in the order of [`TONE_FIELDS`].
    pub fn tone(&self) -> [f32; 5] {
        [self.exposure, self.gamma, self.gamma_threshold, self.vibrancy, self.highlight_power]
    }

    /// The tone settings in the order of [`TONE_FIELDS`], to set.
    pub fn tone_mut(&mut self) -> [&mut f32; 5] {
        [&mut self.exposure, &mut self.gamma, &mut self.gamma_threshold, &mut self.vibrancy, &mut self.highlight_power]
    }
}

/// flam3's adaptive density estimation filter: each pixel's sums are spread by a kernel whose
/// radius is `max_radius_px / count^curve`, clamped to [`min_radius_px`, `max_radius_px`].
/// Scene fields `estimator_radius`, `estimator_minimum`, `estimator_curve` (flam3's names).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensityEstimation {
    pub max_radius_px: f32,
    pub min_radius_px: f32,
    pub curve: f32,
}

impl DensityEstimation {
    /// flam3's default curve.
    pub const DEFAULT_CURVE: f32 = 0.4;
    /// Largest `estimator_radius` (the kernel is (2r + 1)² taps).
    pub const MAX_RADIUS_PX: f32 = 32.0;
}

/// flam3's spatial filter of `[render] filter`, `filter_shape` (its home is the flame module's
/// filters).
pub use crate::flame::render_filter::PixelFilter;

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
            look: None,
            shading: None,
            occlusion: None,
            exposure: 0.0,
            gamma: 1.0,
            gamma_threshold: 0.01,
            vibrancy: 1.0,
            highlight_power: -1.0,
            density_scale: DensityScale::Relative,
            blend_space: BlendSpace::Linear,
            density_estimation: None,
            filter: None,
            shadows: None,
            light_yaw_deg: KEY_LIGHT_YAW_DEG,
            light_pitch_deg: KEY_LIGHT_PITCH_DEG,
            aperture: 0.0,
            focus_distance: None,
            color: ColorMode::Function,
            palette: None,
            palette_mode: PaletteMode::Step,
        }
    }
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
        FunctionDef::Flame(f) => {
            out.extend_from_slice(&f.coefs);
            if let Some(post) = &f.post {
                out.extend_from_slice(post);
            }
            if let Some(c) = &f.variation_coefs {
                out.extend_from_slice(c);
            }
            for t in &f.variations {
                out.push(t.weight);
                out.extend_from_slice(&t.params);
            }
            out.push(f.color_speed);
            out.push(f.opacity);
        }
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
        FunctionDef::Flame(f) => {
            f.coefs = std::array::from_fn(|_| next());
            if let Some(post) = &mut f.post {
                *post = std::array::from_fn(|_| next());
            }
            if let Some(c) = &mut f.variation_coefs {
                *c = std::array::from_fn(|_| next());
            }
            for t in f.variations.iter_mut() {
                t.weight = next();
                t.params.iter_mut().for_each(|p| *p = next());
            }
            f.color_speed = next();
            f.opacity = next();
        }
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
        (FunctionDef::Flame(fa), FunctionDef::Flame(fb)) => {
            let names = |f: &FlameDef| f.variations.iter().map(|t| t.variation.name()).collect::<Vec<_>>().join(", ");
            if fa.post.is_some() != fb.post.is_some() {
                Err(format!(
                    "{} a post-affine and the function {}; keys may change only numbers",
                    if fb.post.is_some() { "has" } else { "has no" },
                    if fa.post.is_some() { "has one" } else { "has none" }
                ))
            } else if fa.variation_coefs.is_some() != fb.variation_coefs.is_some() {
                Err(format!(
                    "{} variation_coefs and the function {}; keys may change only numbers",
                    if fb.variation_coefs.is_some() { "has" } else { "has no" },
                    if fa.variation_coefs.is_some() { "has them" } else { "has none" }
                ))
            } else if names(fa) != names(fb) {
                Err(format!(
                    "uses the variations {}, the function {}; keys may change only numbers",
                    names(fb),
                    names(fa)
                ))
            } else {
                Ok(())
            }
        }
        _ if discriminant(a) != discriminant(b) => Err("is not of the function's kind".into()),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn unflatten_inverts_flatten_for_a_flame() {
        use crate::flame::{Variation, VariationTerm};
        let julian = Variation::by_name("julian").unwrap();
        let def = FunctionDef::Flame(FlameDef {
            coefs: [0.5, 0.1, -0.2, 0.6, 0.3, -0.4],
            post: Some([1.0, 0.0, 0.2, -1.0, 0.0, 0.5]),
            variation_coefs: Some([0.7, 0.0, 0.1, 0.7, -0.2, 0.3]),
            variations: vec![
                VariationTerm { variation: Variation::LINEAR, weight: 0.25, params: vec![] },
                VariationTerm { variation: julian, weight: 0.75, params: vec![3.0, 1.5] },
            ],
            color_speed: 0.3,
            opacity: 0.6,
        });
        // 6 coefs, 6 post, 6 variation coefs, (1 + 0) + (1 + 2) variation numbers, 1 speed,
        // 1 opacity.
        assert_eq!(flatten(&def).len(), 24);
        assert_eq!(unflatten(&def, &flatten(&def)), Some(def.clone()));
        let shifted: Vec<f64> = flatten(&def).iter().map(|v| v + 1.0).collect();
        let FunctionDef::Flame(f) = unflatten(&def, &shifted).unwrap() else { panic!("a flame") };
        assert_eq!((f.coefs[0], f.variations[1].params[1], f.color_speed, f.opacity), (1.5, 2.5, 1.3, 1.6));
        assert_eq!(f.variation_coefs.map(|c| c[4]), Some(0.8));
    }
}
