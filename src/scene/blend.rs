//! The colour space the average and density modes mix and tone colours in
//! (`[render] blend_space`, docs/imaging.md "Blend space"): linear light, or sRGB values as
//! flam3 mixes its palette's bytes.

use crate::color;

/// Where the average and density modes mix the points' colours and tone the mixture
/// (`[render] blend_space`): the colours of the points, the background and the tone map's
/// arithmetic all live in this space, and the picture is converted to the output's at the end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BlendSpace {
    /// Linear light (physically, what light adds up to): nlifs's own look.
    #[default]
    Linear,
    /// sRGB-encoded values, as flam3 and the flame programs mix their palette's bytes: a
    /// flame's gamma, vibrancy and colour mixtures come out as in those programs (imported
    /// flames use it).
    Srgb,
}

impl BlendSpace {
    pub const ALL: [BlendSpace; 2] = [BlendSpace::Linear, BlendSpace::Srgb];

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "linear" => Some(BlendSpace::Linear),
            "srgb" => Some(BlendSpace::Srgb),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            BlendSpace::Linear => "linear",
            BlendSpace::Srgb => "srgb",
        }
    }

    /// A linear colour (a function's, a palette entry, the background) as this space holds it.
    pub fn of_linear(self, c: [f32; 3]) -> [f32; 3] {
        match self {
            BlendSpace::Linear => c,
            BlendSpace::Srgb => c.map(color::linear_to_srgb),
        }
    }

    /// A colour held in this space as linear light.
    pub fn to_linear(self, c: [f32; 3]) -> [f32; 3] {
        match self {
            BlendSpace::Linear => c,
            BlendSpace::Srgb => color::srgb_to_linear(c),
        }
    }
}
