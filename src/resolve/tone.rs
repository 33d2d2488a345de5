//! flam3's tone controls for the average and density modes (after flam3's `rect.c`): the CPU
//! half of the tone map that `shaders/resolve.wgsl` repeats in `toned` (keep in sync).
//!
//! A pixel with points has an average colour `avg` (linear, channels in 0..=1) and a linear
//! density `a0`: 1 in average mode; in density mode ln(1 + count) / ln(1 + max count) on the
//! relative scale, ln(1 + count · s) on the absolute one (flam3's; s = 1 / (points drawn · a
//! pixel's area in square scene units at the camera's target), see [`DensityScale`]). With brightness B = 2^exposure, g = 1 / gamma and τ = gamma_threshold:
//!
//! ```text
//! a      = B · a0                                  linear alpha (flam3's k1 · log(1 + k2 n) / n)
//! γ(x)   = x^g                                     for x ≥ τ
//!        = (1 − x/τ) · x · τ^g / τ + (x/τ) · x^g   for x < τ (flam3's linear ramp, gam_lin_thresh)
//! α      = γ(a)                                    the gamma on the alpha
//! c      = avg                                     colour whose α-multiple is drawn, except when
//!                                                  highlight_power h ≥ 0 and m · α > 1 (m = max avg):
//! c      = (1 − (1 − avg/m) · r) / α,  r = (1 / (m · α))^h
//!                                                  the overflowing colour scaled to fit, its HSV
//!                                                  saturation times r: h = 0 keeps the hue, large
//!                                                  h turns highlights white
//! vivid  = bg + (c − bg) · α                       (density mode, α ≤ 1: over the background)
//!        = c · α                                   (average mode, or α > 1: the pixel is covered)
//! out    = vivid + (1 − v) · ((avg · a)^g − c · α) vibrancy v: 1 gamma on the alpha (hues kept),
//!                                                  0 gamma per channel (flam3's pow(t, g))
//! out    clamped to 0..=1; the coverage (alpha layer) is min(α, 1) in density mode.
//! ```
//!
//! The defaults (exposure 0, gamma 1, vibrancy 1, highlight power −1: off) skip every power, so
//! the image is today's byte for byte: B = 1, α = a0, c = avg, the vibrancy term is exactly 0.

use crate::scene::spec::{BlendSpace, DensityScale, PixelFilter, RenderSettings};

/// Highlight power below 0: overflowing channels are clipped one by one (flam3's default −1).
pub const HIGHLIGHT_OFF: f32 = -1.0;

/// The tone settings of a resolve (`[render]`'s `exposure`, `gamma`, `gamma_threshold`,
/// `vibrancy`, `highlight_power`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tone {
    /// Stops: the brightness is 2^exposure.
    pub exposure: f32,
    /// The alpha is raised to 1 / gamma (above the threshold).
    pub gamma: f32,
    /// Below this alpha the gamma curve is blended into a straight line (no infinite slope at 0).
    pub gamma_threshold: f32,
    /// 1: the gamma on the alpha (saturated colours); 0: the gamma per channel.
    pub vibrancy: f32,
    /// Negative: highlights clip per channel; ≥ 0: they keep their hue (0) or fade to white.
    pub highlight_power: f32,
    /// Density mode: relative to the densest pixel, or absolute.
    pub density_scale: DensityScale,
    /// flam3's spatial filter before the tone map (`crate::resolve::filter`); None: off.
    pub filter: Option<PixelFilter>,
    /// The space the colours are mixed and toned in: the accumulated colours and the
    /// background are in it, and the resolve converts its result to the output's encoding.
    pub blend: BlendSpace,
}

impl Tone {
    /// The tone that changes nothing.
    pub const NEUTRAL: Self = Self {
        exposure: 0.0,
        gamma: 1.0,
        gamma_threshold: 0.01,
        vibrancy: 1.0,
        highlight_power: HIGHLIGHT_OFF,
        density_scale: DensityScale::Relative,
        filter: None,
        blend: BlendSpace::Linear,
    };

    /// The tone a scene's render settings ask for.
    pub fn of(settings: &RenderSettings) -> Self {
        Self {
            exposure: settings.exposure,
            gamma: settings.gamma,
            gamma_threshold: settings.gamma_threshold,
            vibrancy: settings.vibrancy,
            highlight_power: settings.highlight_power,
            density_scale: settings.density_scale,
            filter: settings.filter,
            blend: settings.blend_space,
        }
    }
}

impl Default for Tone {
    fn default() -> Self {
        Self::NEUTRAL
    }
}

/// The uniforms of the tone map (fields of `ResolveParams`): brightness 2^exposure, the exponent
/// g = 1 / gamma, the threshold, vibrancy and highlight power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneUniforms {
    pub brightness: f32,
    pub inv_gamma: f32,
    pub gamma_threshold: f32,
    pub vibrancy: f32,
    pub highlight_power: f32,
}

impl ToneUniforms {
    pub fn of(tone: &Tone) -> Self {
        Self {
            brightness: if tone.exposure == 0.0 { 1.0 } else { tone.exposure.exp2() },
            inv_gamma: if tone.gamma == 1.0 { 1.0 } else { 1.0 / tone.gamma },
            gamma_threshold: tone.gamma_threshold,
            vibrancy: tone.vibrancy,
            highlight_power: tone.highlight_power,
        }
    }
}

/// x^g for x > 0 (0 otherwise); x itself when g = 1.
fn power(x: f32, g: f32) -> f32 {
    if g == 1.0 {
        x
    } else if x > 0.0 {
        x.powf(g)
    } else {
        0.0
    }
}

/// γ(x): the gamma with flam3's linear ramp below the threshold τ.
pub fn gamma_ramp(u: &ToneUniforms, x: f32) -> f32 {
    let g = u.inv_gamma;
    let tau = u.gamma_threshold;
    if g == 1.0 {
        x
    } else if x < tau {
        let frac = x / tau;
        (1.0 - frac) * x * (power(tau, g) / tau) + frac * power(x, g)
    } else {
        power(x, g)
    }
}

/// The toned colour of a pixel with average colour `avg` and linear density `a0` over
/// `background`, and its coverage min(α, 1) (average mode: `density` false, coverage 1).
pub fn toned(u: &ToneUniforms, avg: [f32; 3], a0: f32, background: [f32; 3], density: bool) -> ([f32; 3], f32) {
    let a = a0 * u.brightness;
    let alpha = gamma_ramp(u, a);
    let m = avg[0].max(avg[1]).max(avg[2]);
    let mut c = avg;
    if u.highlight_power >= 0.0 && m * alpha > 1.0 {
        let r = (1.0 / (m * alpha)).powf(u.highlight_power);
        c = avg.map(|x| (1.0 - (1.0 - x / m) * r) / alpha);
    }
    let covered = !density || alpha > 1.0;
    let mut out =
        if covered { c.map(|x| x * alpha) } else { [0, 1, 2].map(|k| background[k] + (c[k] - background[k]) * alpha) };
    if u.vibrancy != 1.0 {
        let per_channel = 1.0 - u.vibrancy;
        for k in 0..3 {
            out[k] += per_channel * (power(avg[k] * a, u.inv_gamma) - c[k] * alpha);
        }
    }
    let coverage = if density { alpha.min(1.0) } else { 1.0 };
    (out.map(|x| x.clamp(0.0, 1.0)), coverage)
}
