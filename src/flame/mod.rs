//! Fractal flames: flam3's model (`.flame` / `.flam3` XML files of the flame community) read,
//! rendered as flam3 renders it, and turned into nlifs scenes.
//!
//! A flame is a set of xforms: each maps a point of the plane by a pre-affine map, a weighted
//! sum of *variations* of the affine image (`variations.rs`, flam3's 99 and their parameters),
//! and an optional post-affine map; each carries a colour coordinate and a colour speed. flam3's
//! conventions are kept in these types, not converted: coefs `[a, b, c, d, e, f]` map
//! x' = a·x + c·y + e, y' = b·x + d·y + f; θ = atan2(x, y) with the arguments swapped; +y points
//! down in the image.
//!
//! Where each part lives: this file holds the flame's data; `variations.rs` the variations,
//! `xml.rs` the reader, `palette.rs` the palettes, `render.rs` the chaos game, histogram, density
//! estimation, spatial filter and tone map (flam3's `rect.c`, `filters.c`).

pub mod palette;
pub mod render;
mod render_base;
mod render_camera;
mod render_chains;
mod render_density;
pub mod render_filter;
mod render_layout;
pub mod render_tone;
mod trig;
mod trig32;
pub mod variations;
mod variations_lanes;
pub mod xml;
mod xml_palette;
mod xml_source;
mod xml_xform;

pub use variations::{Variation, VariationInfo};
pub use xml::{FlameError, FlameFile, read_file, read_str};

/// flam3's affine coefficients `[a, b, c, d, e, f]`: x' = a·x + c·y + e, y' = b·x + d·y + f.
pub type Coefs = [f64; 6];

/// The identity in flam3's coefficient order.
pub const IDENTITY: Coefs = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];

/// Applies flam3 coefficients to a point.
#[inline(always)]
pub fn apply_coefs(c: &Coefs, p: [f64; 2]) -> [f64; 2] {
    [c[0] * p[0] + c[2] * p[1] + c[4], c[1] * p[0] + c[3] * p[1] + c[5]]
}

/// One weighted variation of an xform, with its parameters (in the order of
/// [`VariationInfo::params`], defaults filled in by the reader).
#[derive(Clone, Debug, PartialEq)]
pub struct VariationTerm {
    pub variation: Variation,
    pub weight: f64,
    pub params: Vec<f64>,
}

/// One function of a flame (`<xform>` or `<finalxform>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Xform {
    /// Selection weight (0 for the final xform).
    pub weight: f64,
    /// Colour coordinate c_f in [0, 1].
    pub color: f64,
    /// s in c' = s·c_f + (1 − s)·c (`color_speed`; legacy `symmetry` σ gives s = (1 − σ) / 2).
    pub color_speed: f64,
    /// Plotted weight in [0, 1] (`opacity`); 0 = never plotted (flam3's `plotmode="off"` too).
    pub opacity: f64,
    pub coefs: Coefs,
    pub post: Option<Coefs>,
    /// The coefficients waves, popcorn, rings and fan read where they are not `coefs` (an
    /// xform conjugated by a change of view, `scene::flame_import`); None: `coefs`, as in a file.
    pub variation_coefs: Option<Coefs>,
    pub variations: Vec<VariationTerm>,
    /// Xaos row: the weight multipliers of the next xform after this one; empty = all 1.
    pub chaos: Vec<f64>,
}

impl Xform {
    /// flam3's weight of this xform's points in the histogram (`vis_adjusted`): 10^(log₂
    /// opacity), so 1 for opacity 1, 0.1 for ½, 0 for 0.
    pub fn plotted_weight(&self) -> f64 {
        if self.opacity <= 0.0 { 0.0 } else { 10f64.powf(self.opacity.log2()) }
    }
}

/// How the colour coordinate picks a palette entry (`palette_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PaletteMode {
    /// The entry ⌊256 c⌋.
    #[default]
    Step,
    /// Between the two entries around 256 c, linearly.
    Linear,
}

impl PaletteMode {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "step" => Some(PaletteMode::Step),
            "linear" => Some(PaletteMode::Linear),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            PaletteMode::Step => "step",
            PaletteMode::Linear => "linear",
        }
    }
}

/// The spatial filter's shape (`filter_shape`); flam3's default is gaussian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FilterShape {
    #[default]
    Gaussian,
    Hermite,
    Box,
    Triangle,
    Bell,
    BSpline,
    Mitchell,
    Blackman,
    Catrom,
    Hanning,
    Hamming,
    Lanczos3,
    Lanczos2,
    Quadratic,
}

impl FilterShape {
    /// Every shape, in the order of [`FilterShape::NAMES`].
    pub const ALL: [FilterShape; 14] = [
        FilterShape::Gaussian,
        FilterShape::Hermite,
        FilterShape::Box,
        FilterShape::Triangle,
        FilterShape::Bell,
        FilterShape::BSpline,
        FilterShape::Mitchell,
        FilterShape::Blackman,
        FilterShape::Catrom,
        FilterShape::Hanning,
        FilterShape::Hamming,
        FilterShape::Lanczos3,
        FilterShape::Lanczos2,
        FilterShape::Quadratic,
    ];
    /// flam3's `filter_shape` names (also the scene's `[render] filter_shape`).
    pub const NAMES: [&'static str; 14] = [
        "gaussian",
        "hermite",
        "box",
        "triangle",
        "bell",
        "bspline",
        "mitchell",
        "blackman",
        "catrom",
        "hanning",
        "hamming",
        "lanczos3",
        "lanczos2",
        "quadratic",
    ];

    pub fn parse(name: &str) -> Option<Self> {
        Self::NAMES.iter().position(|n| *n == name).map(|i| Self::ALL[i])
    }

    pub fn name(self) -> &'static str {
        Self::NAMES[Self::ALL.iter().position(|s| *s == self).expect("every shape is in ALL")]
    }
}

/// 256 RGBA entries, each channel in [0, 1].
pub type Palette = Vec<[f64; 4]>;

/// One `<flame>`: its functions, palette, camera and tone map, as flam3 reads them.
#[derive(Clone, Debug, PartialEq)]
pub struct Flame {
    pub name: String,
    /// Image size in pixels (`size`).
    pub size: [u32; 2],
    pub center: [f64; 2],
    /// Pixels per unit (`scale`), before `zoom`.
    pub scale: f64,
    /// Degrees (`rotate`).
    pub rotate: f64,
    pub zoom: f64,
    /// Samples per output pixel (`quality`).
    pub quality: f64,
    pub supersample: u32,
    /// Spatial filter radius (`filter`) and shape.
    pub filter: f64,
    pub filter_shape: FilterShape,
    pub brightness: f64,
    pub gamma: f64,
    pub gamma_threshold: f64,
    pub vibrancy: f64,
    pub highlight_power: f64,
    /// RGB in [0, 1].
    pub background: [f64; 3],
    pub estimator_radius: f64,
    pub estimator_minimum: f64,
    pub estimator_curve: f64,
    pub palette_mode: PaletteMode,
    pub palette: Palette,
    pub xforms: Vec<Xform>,
    pub final_xform: Option<Xform>,
}

/// flam3's defaults (`clear_cp` with defaults on) for everything but the xforms and palette.
impl Default for Flame {
    fn default() -> Self {
        Flame {
            name: String::new(),
            size: [100, 100],
            center: [0.0, 0.0],
            scale: 50.0,
            rotate: 0.0,
            zoom: 0.0,
            quality: 1.0,
            supersample: 1,
            filter: 0.5,
            filter_shape: FilterShape::Gaussian,
            brightness: 4.0,
            gamma: 4.0,
            gamma_threshold: 0.01,
            vibrancy: 1.0,
            highlight_power: -1.0,
            background: [0.0; 3],
            estimator_radius: 9.0,
            estimator_minimum: 0.0,
            estimator_curve: 0.4,
            palette_mode: PaletteMode::Step,
            palette: vec![[0.0; 4]; palette::PALETTE_LEN],
            xforms: Vec::new(),
            final_xform: None,
        }
    }
}
