//! The scene file as written: the versioned TOML format (documented in README.md) read by serde
//! into `*Toml` structs that keep the span of every field (`toml::Spanned`) and reject unknown
//! fields. This is the first of the two reading passes; the second (`check/`) gives the
//! structs their meaning. The two fields that take either of two shapes (a colour, a step's
//! `by`) have hand-written visitors rather than serde's untagged enums, whose one message
//! ("data did not match any variant of untagged enum …") names a Rust type and not the shapes
//! the user may write; `check/words.rs` puts serde's remaining messages in the user's words.

use std::collections::BTreeMap;

use serde::Deserialize;
use serde::de::{Deserializer, SeqAccess, Visitor};
use toml::Spanned;

/// The scene format version this build reads and writes.
pub const FORMAT_VERSION: i64 = 1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneToml {
    pub(super) version: Spanned<i64>,
    pub(super) name: Option<String>,
    pub(super) description: Option<String>,
    pub(super) grid: Spanned<GridToml>,
    #[serde(default, rename = "function")]
    pub(super) functions: Vec<Spanned<FunctionToml>>,
    pub(super) probabilities: Option<Spanned<String>>,
    pub(super) camera: Option<CameraToml>,
    pub(super) render: Option<RenderToml>,
    pub(super) timeline: Option<Spanned<TimelineToml>>,
    #[serde(default, rename = "key")]
    pub(super) keys: Vec<Spanned<KeyToml>>,
    /// flam3's final xform.
    #[serde(rename = "final")]
    pub(super) final_xform: Option<Spanned<FinalToml>>,
}

/// The [`FlameFields`] of a table that has a flame's fields (a function, a key's override, the
/// final xform; serde's `flatten` cannot be used with `deny_unknown_fields`), with `opacity`.
macro_rules! flame_fields {
    ($table:expr, $opacity:expr) => {
        FlameFields {
            coefs: &$table.coefs,
            post: &$table.post,
            variation_coefs: &$table.variation_coefs,
            variations: &$table.variations,
            params: &$table.params,
            color_speed: &$table.color_speed,
            opacity: $opacity,
        }
    };
}

/// `[final]`: a flame definition without selection weight, its colour coordinate, and its
/// opacity (here the chance that it maps a drawn point, flam3's final xform's).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FinalToml {
    pub(super) palette_index: Option<Spanned<f64>>,
    pub(super) coefs: Option<Spanned<Vec<f64>>>,
    pub(super) post: Option<Spanned<Vec<f64>>>,
    pub(super) variation_coefs: Option<Spanned<Vec<f64>>>,
    pub(super) variations: Option<NamedNumbers>,
    pub(super) params: Option<NamedNumbers>,
    pub(super) color_speed: Option<Spanned<f64>>,
    pub(super) opacity: Option<Spanned<f64>>,
}

impl FinalToml {
    pub(super) fn flame(&self) -> FlameFields<'_> {
        flame_fields!(self, &self.opacity)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TimelineToml {
    #[serde(rename = "loop")]
    pub(super) loop_mode: Option<Spanned<String>>,
    pub(super) duration_secs: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeyToml {
    pub(super) t_secs: Spanned<f64>,
    pub(super) interpolation: Option<Spanned<String>>,
    pub(super) ease: Option<Spanned<String>>,
    #[serde(default, rename = "function")]
    pub(super) functions: Vec<Spanned<KeyFunctionToml>>,
    pub(super) camera: Option<CameraToml>,
    pub(super) render: Option<KeyRenderToml>,
}

/// A key's override of one function: the fields of its kind that hold numbers.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeyFunctionToml {
    pub(super) name: Spanned<String>,
    pub(super) points: Option<Spanned<Vec<Spanned<Vec<f64>>>>>,
    pub(super) steps: Option<Spanned<Vec<Spanned<StepToml>>>>,
    pub(super) matrix: Option<Spanned<Vec<Vec<f64>>>>,
    pub(super) offset: Option<Spanned<Vec<f64>>>,
    pub(super) c: Option<Spanned<Vec<f64>>>,
    // A flame's (`kind = "flame"`): flam3's xform.
    pub(super) coefs: Option<Spanned<Vec<f64>>>,
    pub(super) post: Option<Spanned<Vec<f64>>>,
    pub(super) variation_coefs: Option<Spanned<Vec<f64>>>,
    /// Weight by variation name (flam3's names).
    pub(super) variations: Option<NamedNumbers>,
    /// Parameter by flam3's attribute name (`julian_power`).
    pub(super) params: Option<NamedNumbers>,
    pub(super) color_speed: Option<Spanned<f64>>,
    pub(super) opacity: Option<Spanned<f64>>,
}

/// Numbers by name, each name and number with its place (a flame's `variations` and `params`).
pub(super) type NamedNumbers = Spanned<BTreeMap<Spanned<String>, Spanned<f64>>>;

/// The flame fields of a function or of a key's override, borrowed.
pub(super) struct FlameFields<'a> {
    pub(super) coefs: &'a Option<Spanned<Vec<f64>>>,
    pub(super) post: &'a Option<Spanned<Vec<f64>>>,
    pub(super) variation_coefs: &'a Option<Spanned<Vec<f64>>>,
    pub(super) variations: &'a Option<NamedNumbers>,
    pub(super) params: &'a Option<NamedNumbers>,
    pub(super) color_speed: &'a Option<Spanned<f64>>,
    pub(super) opacity: &'a Option<Spanned<f64>>,
}

impl FunctionToml {
    pub(super) fn flame(&self) -> FlameFields<'_> {
        flame_fields!(self, &self.opacity)
    }
}

impl KeyFunctionToml {
    pub(super) fn flame(&self) -> FlameFields<'_> {
        flame_fields!(self, &self.opacity)
    }
}

impl FlameFields<'_> {
    /// The fields with their names and places, those present.
    pub(super) fn present(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        [
            ("coefs", self.coefs.as_ref().map(|v| v.span())),
            ("post", self.post.as_ref().map(|v| v.span())),
            ("variation_coefs", self.variation_coefs.as_ref().map(|v| v.span())),
            ("variations", self.variations.as_ref().map(|v| v.span())),
            ("params", self.params.as_ref().map(|v| v.span())),
            ("color_speed", self.color_speed.as_ref().map(|v| v.span())),
            ("opacity", self.opacity.as_ref().map(|v| v.span())),
        ]
        .into_iter()
        .filter_map(|(n, s)| s.map(|s| (n, s)))
        .collect()
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeyRenderToml {
    pub(super) points: Option<Spanned<i64>>,
    pub(super) background: Option<Spanned<ColorToml>>,
    pub(super) depth_cue: Option<Spanned<f64>>,
    // The tone controls (`spec::TONE_FIELDS`).
    pub(super) exposure: Option<Spanned<f64>>,
    pub(super) gamma: Option<Spanned<f64>>,
    pub(super) gamma_threshold: Option<Spanned<f64>>,
    pub(super) vibrancy: Option<Spanned<f64>>,
    pub(super) highlight_power: Option<Spanned<f64>>,
    // The key light (`spec::LIGHT_FIELDS`).
    pub(super) shadows: Option<Spanned<f64>>,
    pub(super) light_yaw_deg: Option<Spanned<f64>>,
    pub(super) light_pitch_deg: Option<Spanned<f64>>,
    // Depth of field.
    pub(super) aperture: Option<Spanned<f64>>,
    pub(super) focus_distance: Option<Spanned<f64>>,
}

impl KeyRenderToml {
    /// The tone fields in the order of `spec::TONE_FIELDS`.
    pub(super) fn tone(&self) -> [&Option<Spanned<f64>>; 5] {
        [&self.exposure, &self.gamma, &self.gamma_threshold, &self.vibrancy, &self.highlight_power]
    }

    /// The key light's fields in the order of `spec::LIGHT_FIELDS`.
    pub(super) fn light(&self) -> [&Option<Spanned<f64>>; 3] {
        [&self.shadows, &self.light_yaw_deg, &self.light_pitch_deg]
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GridToml {
    pub(super) x: Spanned<Vec<f64>>,
    pub(super) y: Spanned<Vec<f64>>,
    pub(super) z: Option<Spanned<Vec<f64>>>,
}

/// A colour as written: `"#rrggbb"` or `[r, g, b]`.
pub(super) enum ColorToml {
    Hex(String),
    Rgb(Vec<f64>),
}

/// A step's `by`: one number for every axis, or one per axis.
pub(super) enum VectorToml {
    Scalar(f64),
    Vector(Vec<f64>),
}

/// Reads the numbers of a list (integers are numbers too).
fn numbers<'de, A: SeqAccess<'de>>(mut seq: A) -> Result<Vec<f64>, A::Error> {
    let mut out = Vec::new();
    while let Some(x) = seq.next_element::<f64>()? {
        out.push(x);
    }
    Ok(out)
}

impl<'de> Deserialize<'de> for ColorToml {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ColorToml;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a colour, \"#rrggbb\" or [r, g, b] with numbers in 0..1")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<ColorToml, E> {
                Ok(ColorToml::Hex(v.to_string()))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ColorToml, A::Error> {
                numbers(seq).map(ColorToml::Rgb)
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for VectorToml {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = VectorToml;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a list of numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<VectorToml, E> {
                Ok(VectorToml::Scalar(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<VectorToml, E> {
                Ok(VectorToml::Scalar(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<VectorToml, E> {
                Ok(VectorToml::Scalar(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<VectorToml, A::Error> {
                numbers(seq).map(VectorToml::Vector)
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FunctionToml {
    pub(super) name: Option<String>,
    pub(super) kind: Spanned<String>,
    pub(super) color: Option<Spanned<ColorToml>>,
    pub(super) probability: Option<Spanned<f64>>,
    pub(super) enabled: Option<bool>,
    pub(super) points: Option<Spanned<Vec<Spanned<Vec<f64>>>>>,
    pub(super) resolution: Option<Spanned<Vec<i64>>>,
    pub(super) steps: Option<Spanned<Vec<Spanned<StepToml>>>>,
    pub(super) matrix: Option<Spanned<Vec<Vec<f64>>>>,
    pub(super) offset: Option<Spanned<Vec<f64>>>,
    pub(super) c: Option<Spanned<Vec<f64>>>,
    pub(super) sign: Option<Spanned<f64>>,
    // Palette colour:
    pub(super) palette_index: Option<Spanned<f64>>,
    // A flame's (`kind = "flame"`): flam3's xform.
    pub(super) coefs: Option<Spanned<Vec<f64>>>,
    pub(super) post: Option<Spanned<Vec<f64>>>,
    pub(super) variation_coefs: Option<Spanned<Vec<f64>>>,
    /// Weight by variation name (flam3's names).
    pub(super) variations: Option<NamedNumbers>,
    /// Parameter by flam3's attribute name (`julian_power`).
    pub(super) params: Option<NamedNumbers>,
    pub(super) color_speed: Option<Spanned<f64>>,
    pub(super) opacity: Option<Spanned<f64>>,
    /// The multipliers of the next function's probability after this one.
    pub(super) xaos: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StepToml {
    pub(super) op: Spanned<String>,
    pub(super) by: Option<Spanned<VectorToml>>,
    pub(super) axis: Option<Spanned<String>>,
    pub(super) toward: Option<Spanned<String>>,
    pub(super) along: Option<Spanned<String>>,
    pub(super) degrees: Option<Spanned<f64>>,
    pub(super) amount: Option<Spanned<f64>>,
    pub(super) range: Option<Spanned<Vec<f64>>>,
    pub(super) center: Option<Spanned<Vec<f64>>>,
    pub(super) matrix: Option<Spanned<Vec<Vec<f64>>>>,
    pub(super) offset: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraToml {
    pub(super) target: Option<Spanned<Vec<f64>>>,
    pub(super) yaw_deg: Option<Spanned<f64>>,
    pub(super) pitch_deg: Option<Spanned<f64>>,
    pub(super) distance: Option<Spanned<f64>>,
    pub(super) fov_y_deg: Option<Spanned<f64>>,
    pub(super) projection: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderToml {
    pub(super) width: Option<Spanned<i64>>,
    pub(super) height: Option<Spanned<i64>>,
    pub(super) points: Option<Spanned<i64>>,
    pub(super) seed: Option<Spanned<i64>>,
    pub(super) mode: Option<Spanned<String>>,
    pub(super) background: Option<Spanned<ColorToml>>,
    pub(super) depth_cue: Option<Spanned<f64>>,
    pub(super) look: Option<Spanned<String>>,
    pub(super) shading: Option<Spanned<f64>>,
    pub(super) occlusion: Option<Spanned<f64>>,
    // The tone controls (`spec::TONE_FIELDS`).
    pub(super) exposure: Option<Spanned<f64>>,
    pub(super) gamma: Option<Spanned<f64>>,
    pub(super) gamma_threshold: Option<Spanned<f64>>,
    pub(super) vibrancy: Option<Spanned<f64>>,
    pub(super) highlight_power: Option<Spanned<f64>>,
    pub(super) density_scale: Option<Spanned<String>>,
    pub(super) blend_space: Option<Spanned<String>>,
    pub(super) palette_mode: Option<Spanned<String>>,
    pub(super) estimator_radius: Option<Spanned<f64>>,
    pub(super) estimator_minimum: Option<Spanned<f64>>,
    pub(super) estimator_curve: Option<Spanned<f64>>,
    pub(super) filter: Option<Spanned<f64>>,
    pub(super) filter_shape: Option<Spanned<String>>,
    // The key light (`spec::LIGHT_FIELDS`).
    pub(super) shadows: Option<Spanned<f64>>,
    pub(super) light_yaw_deg: Option<Spanned<f64>>,
    pub(super) light_pitch_deg: Option<Spanned<f64>>,
    // Depth of field.
    pub(super) aperture: Option<Spanned<f64>>,
    pub(super) focus_distance: Option<Spanned<f64>>,
    // Colour by a colour coordinate:
    pub(super) color: Option<Spanned<String>>,
    pub(super) palette: Option<Spanned<String>>,
}

impl RenderToml {
    /// The key light's fields in the order of `spec::LIGHT_FIELDS`.
    pub(super) fn light(&self) -> [&Option<Spanned<f64>>; 3] {
        [&self.shadows, &self.light_yaw_deg, &self.light_pitch_deg]
    }

    /// The tone fields in the order of `spec::TONE_FIELDS`.
    pub(super) fn tone(&self) -> [&Option<Spanned<f64>>; 5] {
        [&self.exposure, &self.gamma, &self.gamma_threshold, &self.vibrancy, &self.highlight_power]
    }
}
