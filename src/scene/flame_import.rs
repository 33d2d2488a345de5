//! A flam3 flame as an nlifs scene (`nlifs import flame`, and `nlifs view` / `nlifs record` of a
//! `.flame` file): each xform becomes a `kind = "flame"` function, the palette the scene's
//! palette, the flame's camera the scene's camera, its tone the density look.
//!
//! - **Orientation.** flam3 draws +y down, nlifs +y up, and flam3 may rotate its camera
//!   (`rotate`), which nlifs's orbit camera cannot (it has no roll). The import conjugates every
//!   xform by the similarity M that takes flam3's plane to what nlifs shows (a rotation about
//!   the flame's `center`, then the mirror y → −y): the function M∘w∘M⁻¹ is the xform with
//!   pre-affine `coefs`∘M⁻¹ and post-affine M∘`post` (M itself where the xform has no post), so
//!   the attractor is M of the flame's, exactly, and the picture is flam3's way up. The imported
//!   coefs therefore differ from the file's (y negated for an unrotated flame).
//! - **Functions.** An xform's `weight` is the function's `probability` (explicit
//!   probabilities), its `color` the function's `palette_index`, its `color_speed`, `opacity`,
//!   variations and parameters the flame function's own, its xaos row (`chaos`) the function's
//!   `xaos`. The domain is flam3's start square [−1, 1]².
//! - **The final xform** is the scene's `[final]`, conjugated as the xforms are, its `color`
//!   the final's `palette_index`, its `opacity` (the chance that it maps a drawn point) the
//!   final's.
//! - **Left out, with a warning:** supersampling above 1 (see Look); a final xform's opacity
//!   below 1 in a flame of more than 128 xforms (drawn as 1: `chaos_game/flame.rs`).
//! - **The palette** is the scene's, with flam3's `palette_mode` (`step`: the entry ⌊256 c⌋;
//!   `linear`: the two entries around it, interpolated by a dither per point).
//! - **Camera.** Parallel projection seen from +z, the target at M(center), the visible height
//!   size_y / (scale · 2^zoom); the image size is the flame's.
//! - **Look.** Density mode on the absolute scale (flam3's log density: log(1 + points per
//!   point drawn and square unit)) coloured by the palette, the flame's background, and flam3's
//!   tone: the exposure log₂(brightness · 268 / 256) stops (flam3's k1), its gamma, gamma
//!   threshold, vibrancy and highlight power, all in the sRGB blend space (`blend_space =
//!   "srgb"`): the palette's colours are mixed and toned as flam3 mixes their bytes, so a
//!   flame's gamma, vibrancy below 1 and colour mixtures come out as flam3's; density estimation with flam3's estimator radius, minimum and curve; as many points
//!   as flam3 draws samples (quality × width × height × 4^zoom); flam3's spatial filter (`filter`,
//!   `filter_shape`) at one sample a pixel. Not drawn: flam3's supersampling (its
//!   anti-aliasing within a pixel).

use std::path::Path;

use glam::{DVec3, Vec3};

use crate::camera::Projection;
use crate::color;
use crate::flame::render_filter::{filter_weights, filter_width};
use crate::flame::{Coefs, Flame, IDENTITY, Xform};
use crate::model::{ProbabilityMode, RectGrid};
use crate::palette::Palette;
use crate::scene::spec::{
    BlendSpace, CameraSpec, ColorMode, DensityEstimation, DensityScale, FinalXform, FlameDef, FunctionDef,
    FunctionSpec, MAX_POINTS, PixelFilter, RenderSettings, SplatMode, TONE_FIELDS,
};
use crate::scene::{LoadError, Scene};

/// The scene of a flame and what the import left out or changed.
#[derive(Clone, Debug)]
pub struct FlameImport {
    pub scene: Scene,
    /// One line each (supersampling, a filter narrowed to fit, a final xform's opacity that
    /// cannot be drawn).
    pub warnings: Vec<String>,
}

/// Why a flame cannot be a scene.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FlameImportError {
    #[error("flame `{0}` has no xform with a weight above 0")]
    NoXform(String),
}

/// The vertical field of view of an imported camera (any works in parallel projection).
const FOV_Y_DEG: f64 = 30.0;

/// flam3's brightness is multiplied by this (its k1's 268 / 256).
const BRIGHTNESS_FACTOR: f64 = 268.0 / 256.0;

/// An affine map in flam3's coefficient order as a 3 × 3 matrix (rows x, y, 1).
fn matrix(c: &Coefs) -> [[f64; 3]; 3] {
    [[c[0], c[2], c[4]], [c[1], c[3], c[5]], [0.0, 0.0, 1.0]]
}

fn coefs(m: &[[f64; 3]; 3]) -> Coefs {
    [m[0][0], m[1][0], m[0][1], m[1][1], m[0][2], m[1][2]]
}

fn apply(m: &[[f64; 3]; 3], p: [f64; 2]) -> [f64; 2] {
    [m[0][0] * p[0] + m[0][1] * p[1] + m[0][2], m[1][0] * p[0] + m[1][1] * p[1] + m[1][2]]
}

fn compose(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// M and M⁻¹ of the module note, for the flame's center and rotation.
fn view_map(flame: &Flame) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let (s, c) = flame.rotate.to_radians().sin_cos();
    let [cx, cy] = flame.center;
    // flam3 shows p at center + R (p − center), R = [[c, −s], [s, c]]; nlifs mirrors y.
    let rotate = |s: f64| {
        let (rx, ry) = (cx - (c * cx - s * cy), cy - (s * cx + c * cy));
        [[c, -s, rx], [s, c, ry], [0.0, 0.0, 1.0]]
    };
    let mirror = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];
    // R⁻¹ is the rotation by −rotate about the same center.
    (compose(&mirror, &rotate(s)), compose(&rotate(-s), &mirror))
}

/// `x` conjugated by M (see the module note) as a flame function's definition. The variations
/// that read their xform's coefficients (waves, popcorn, rings, fan) keep the file's
/// (`variation_coefs`), or the conjugate would be another function.
fn conjugated(x: &Xform, m: &[[f64; 3]; 3], m_inv: &[[f64; 3]; 3]) -> FlameDef {
    let pre = coefs(&compose(&matrix(&x.coefs), m_inv));
    let post = coefs(&compose(m, &matrix(&x.post.unwrap_or(IDENTITY))));
    let mut variations = x.variations.clone();
    variations.sort_by_key(|t| t.variation.0);
    if variations.is_empty() {
        // An xform of no variation flam3 knows maps every point to the origin (before its
        // post-affine); a scene says so with `linear = 0`, as it lists at least one.
        let linear = crate::flame::Variation::by_name("linear").expect("linear is a variation");
        variations.push(crate::flame::VariationTerm { variation: linear, weight: 0.0, params: Vec::new() });
    }
    let reads_coefs = variations.iter().any(|t| t.weight != 0.0 && t.variation.reads_xform_coefs());
    let variation_coefs = (reads_coefs && pre != x.coefs).then_some(x.coefs);
    FlameDef {
        coefs: pre,
        post: Some(post),
        variation_coefs,
        variations,
        color_speed: x.color_speed.clamp(0.0, 1.0),
        opacity: x.opacity.clamp(0.0, 1.0),
    }
}

/// flam3's spatial filter of `flame` as the scene's, at one sample a pixel (flam3 spreads it
/// over its supersampled buffer, the same extent in output pixels); one wider than the
/// resolve's table is narrowed to the widest that fits, with a warning.
fn pixel_filter(flame: &Flame, name: &str, warnings: &mut Vec<String>) -> Option<PixelFilter> {
    if !(flame.filter > 0.0) {
        return None;
    }
    let shape = flame.filter_shape;
    let mut radius = flame.filter;
    if filter_width(shape, radius) > PixelFilter::MAX_TAPS {
        // The widest radius that fits: the width grows in steps of 2 with the radius.
        while radius > 0.01 && filter_width(shape, radius) > PixelFilter::MAX_TAPS {
            radius *= 0.99;
        }
        warnings.push(format!(
            "flame `{name}`: its {} filter of radius {} is drawn with radius {radius:.3}, the widest the scene allows",
            shape.name(),
            flame.filter
        ));
    }
    filter_weights(shape, radius).is_some().then_some(PixelFilter { radius_px: radius as f32, shape })
}

/// The scene of `flame`; its palette is named `palette_file` (an image path relative to the
/// scene file, written when the scene is saved: `Scene::save_over`).
pub fn scene_of_flame(flame: &Flame, palette_file: &str) -> Result<FlameImport, FlameImportError> {
    if !flame.xforms.iter().any(|x| x.weight > 0.0) {
        return Err(FlameImportError::NoXform(flame.name.clone()));
    }
    let mut warnings = Vec::new();
    let name = if flame.name.is_empty() { "flame".to_string() } else { flame.name.clone() };
    if flame.final_xform.as_ref().is_some_and(|f| f.opacity < 1.0) && flame.xforms.len() > 128 {
        warnings.push(format!(
            "flame `{name}`: its final xform's opacity is left out with more than 128 xforms (the final xform maps every point drawn)"
        ));
    }
    if flame.supersample > 1 {
        warnings.push(format!(
            "flame `{name}`: its supersampling ({}) is not drawn (the anti-aliasing inside a pixel); `nlifs render` of the flame file draws it",
            flame.supersample
        ));
    }
    let n = flame.xforms.len();
    // An xform's xaos row, as the scene's (flam3 reads a missing entry as 1, a negative one as 0).
    let xaos = |x: &Xform| -> Vec<f64> {
        let row: Vec<f64> = x.chaos.iter().take(n).map(|&c| if c >= 0.0 { c } else { 0.0 }).collect();
        if row.iter().all(|&c| (c - 1.0).abs() <= 1e-10) { Vec::new() } else { row }
    };
    let filter = pixel_filter(flame, &name, &mut warnings);
    let samples: Vec<[f32; 3]> = flame
        .palette
        .iter()
        .map(|c| [c[0], c[1], c[2]].map(|v| color::srgb8_to_linear((v.clamp(0.0, 1.0) * 255.0).round() as u8)))
        .collect();
    let palette = Palette { source: palette_file.to_string(), samples };
    let entry = |c: f64| palette.at(c as f32);
    let (m, m_inv) = view_map(flame);
    let functions = flame
        .xforms
        .iter()
        .enumerate()
        .map(|(i, x)| FunctionSpec {
            name: format!("xform{}", i + 1),
            color: entry(x.color),
            probability: Some(x.weight.max(0.0)),
            enabled: true,
            def: FunctionDef::Flame(conjugated(x, &m, &m_inv)),
            palette_index: Some(x.color.clamp(0.0, 1.0)),
            xaos: xaos(x),
        })
        .collect();
    let final_xform = flame
        .final_xform
        .as_ref()
        .map(|x| FinalXform { def: conjugated(x, &m, &m_inv), palette_index: x.color.clamp(0.0, 1.0) });
    let ppu = flame.scale * 2f64.powf(flame.zoom);
    let half_height = f64::from(flame.size[1].max(1)) / (2.0 * ppu);
    let target = apply(&m, flame.center);
    let camera = CameraSpec {
        target: Some(DVec3::new(target[0], target[1], 0.0)),
        yaw_deg: Some(0.0),
        pitch_deg: Some(0.0),
        distance: Some(half_height / (0.5 * FOV_Y_DEG.to_radians()).tan()),
        fov_y_deg: Some(FOV_Y_DEG),
        projection: Some(Projection::Parallel),
    };
    let tone = |k: usize, v: f64| v.clamp(TONE_FIELDS[k].1, TONE_FIELDS[k].2) as f32;
    let bg = flame.background.map(|v| color::srgb8_to_linear((v.clamp(0.0, 1.0) * 255.0).round() as u8));
    let estimator = (flame.estimator_radius > 0.0).then(|| {
        let max_radius_px = flame.estimator_radius.min(DensityEstimation::MAX_RADIUS_PX as f64) as f32;
        DensityEstimation {
            max_radius_px,
            min_radius_px: (flame.estimator_minimum.max(0.0) as f32).min(max_radius_px),
            curve: flame.estimator_curve.clamp(0.01, 10.0) as f32,
        }
    });
    let render = RenderSettings {
        width: flame.size[0].max(1),
        height: flame.size[1].max(1),
        points: crate::flame::render::sample_count(flame).clamp(1, MAX_POINTS),
        mode: SplatMode::Density,
        background: bg,
        depth_cue: 0.0,
        exposure: tone(0, (flame.brightness.max(1e-3) * BRIGHTNESS_FACTOR).log2()),
        gamma: tone(1, flame.gamma),
        gamma_threshold: tone(2, flame.gamma_threshold),
        vibrancy: tone(3, flame.vibrancy),
        highlight_power: tone(4, flame.highlight_power),
        density_scale: DensityScale::Absolute,
        blend_space: BlendSpace::Srgb,
        density_estimation: estimator,
        filter,
        color: ColorMode::Palette,
        palette: Some(palette),
        palette_mode: flame.palette_mode,
        ..RenderSettings::default()
    };
    let scene = Scene {
        path: None,
        name,
        description: "imported from a flam3 flame".to_string(),
        domain: RectGrid::uniform(DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.0), [2, 2, 1]),
        functions,
        probability_mode: ProbabilityMode::Explicit,
        camera,
        render,
        timeline: None,
        final_xform,
    };
    Ok(FlameImport { scene, warnings })
}

/// The point of nlifs's plane where flame `flame` shows the flam3 point `p` (M of the module
/// note): for comparing the chaos game of an imported scene with flam3's.
pub fn view_point(flame: &Flame, p: [f64; 2]) -> Vec3 {
    let q = apply(&view_map(flame).0, p);
    Vec3::new(q[0] as f32, q[1] as f32, 0.0)
}

/// The palette image of the scene imported as `path` (a scene file, or the flame file itself
/// for a scene made in memory): `<stem>.palette.png`, next to it.
pub fn palette_file_for(path: &Path) -> String {
    let stem = path.file_stem().map_or_else(|| "flame".into(), |s| s.to_string_lossy().into_owned());
    format!("{stem}.palette.png")
}

/// Reads the flame file `path` and imports the flame `name` names, else the one at `index`
/// (from 0), else the first; the warnings are the reader's and the import's. The scene's path
/// is the flame file's and its palette `palette_file_for(path)` (`<stem>-<k>.palette.png` for
/// the flame at k > 0; written when the scene is saved).
pub fn load_flame(path: &Path, index: Option<usize>, name: Option<&str>) -> Result<FlameImport, LoadError> {
    let read = crate::flame::read_file(path).map_err(|e| LoadError::Flame(e.to_string()))?;
    let count = read.flames.len();
    let k = match name {
        Some(name) => read.flames.iter().position(|f| f.name == name).ok_or_else(|| {
            let names: Vec<String> = read.flames.iter().map(|f| format!("`{}`", f.name)).collect();
            LoadError::Flame(format!(
                "{} has no flame named `{name}` (its flames: {})",
                path.display(),
                names.join(", ")
            ))
        })?,
        None => {
            let k = index.unwrap_or(0);
            if k >= count {
                return Err(LoadError::Flame(format!(
                    "flame {k}: {} has {count} flame(s), numbered from 0",
                    path.display()
                )));
            }
            k
        }
    };
    let flame = &read.flames[k];
    // The flames of one file have palettes of their own: the first's keeps the plain name.
    let palette_file = match k {
        0 => palette_file_for(path),
        k => palette_file_for(path).replace(".palette.png", &format!("-{k}.palette.png")),
    };
    let mut import =
        scene_of_flame(flame, &palette_file).map_err(|e| LoadError::Flame(format!("{}: {e}", path.display())))?;
    if flame.name.is_empty()
        && let Some(stem) = path.file_stem()
    {
        import.scene.name = stem.to_string_lossy().into_owned();
    }
    import.scene.path = Some(path.to_path_buf());
    let mut warnings = read.warnings;
    warnings.append(&mut import.warnings);
    import.warnings = warnings;
    Ok(import)
}
