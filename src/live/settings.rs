//! The live view's settings as plain data: what the viewer's render panel edits and its state
//! holds, namely the GPU side's settings (plain data too, no GPU handles) and the choice of where
//! the chaos game runs ([`ChaosBackend`]), with the route it took on the adapter at hand
//! ([`ChaosRoute`]).

use crate::gpu::progressive::ProgressiveSettings;
use crate::resolve::Tone;
use crate::scene::spec::DensityEstimation;

/// Settings of the live view (the viewer's render panel edits them): what the GPU side draws and
/// where the chaos game runs. The default draws as `gpu::progressive::ProgressiveSettings`'s
/// default does, with the GPU chaos game.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LiveSettings {
    /// Points, steps, the look, the light, the lens and the tone: what the GPU resolves (the CPU
    /// route's chaos game reads its point count, steps and seed). The live view draws with the
    /// full normal fit and narrows it while navigating ([`crate::live::LiveView::set_navigating`]).
    pub draw: ProgressiveSettings,
    /// Where the chaos game runs (the GPU only resolves on the CPU route). The default, `gpu`,
    /// is what `render --backend gpu` and the benchmarks run; the viewer starts on `auto`.
    pub chaos_backend: ChaosBackend,
    /// Density mode on the relative scale: the points of the scene's render, at which the live
    /// view stops accumulating (scaled to its own size). None: it accumulates to
    /// `draw.max_splats`, as it does on the absolute scale.
    pub render_density: Option<RenderDensity>,
}

/// The density of the scene's render: `points` into an image `width_px` × `height_px`. Density
/// mode on the relative scale shows log(1 + count) / log(1 + max count), which flattens towards
/// 1 as the counts grow: a view that went on accumulating past the render's points per pixel
/// would drift from the render's picture and wash out (a flame of quality 1 did within a
/// second). The live view stops where it has drawn as many points per pixel as the render. The
/// viewer frames the render's image in the view (its height, or its width where the view is
/// narrower), so a view pixel covers (render height / framed height)² of a render's pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderDensity {
    pub points: u64,
    pub width_px: u32,
    pub height_px: u32,
}

impl RenderDensity {
    /// The splats of a view of `width_px` × `height_px` at the render's points per pixel (at
    /// least 1).
    pub fn splats_in_view(&self, width_px: u32, height_px: u32) -> u64 {
        let (w, h) = (f64::from(self.width_px.max(1)), f64::from(self.height_px.max(1)));
        // The height of the render's image framed in the view.
        let framed = f64::from(height_px).min(f64::from(width_px) * h / w);
        let scale = framed / h;
        ((self.points as f64 * scale * scale).ceil() as u64).max(1)
    }
}

/// The live view's imaging: its tone map and density estimation (the viewer's render panel
/// edits them as scene edits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Imaging {
    pub tone: Tone,
    /// None: off.
    pub density_estimation: Option<DensityEstimation>,
}

impl Imaging {
    /// The tone fields in the order of `scene::spec::TONE_FIELDS`.
    pub fn tone_fields(&self) -> [f32; 5] {
        let t = &self.tone;
        [t.exposure, t.gamma, t.gamma_threshold, t.vibrancy, t.highlight_power]
    }

    pub fn with_tone_fields(self, v: [f32; 5]) -> Self {
        let tone = Tone {
            exposure: v[0],
            gamma: v[1],
            gamma_threshold: v[2],
            vibrancy: v[3],
            highlight_power: v[4],
            ..self.tone
        };
        Self { tone, ..self }
    }
}

/// Which chaos game the live view runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ChaosBackend {
    /// The compute shader (points persist on the GPU).
    #[default]
    Gpu,
    /// The CPU kernel; the GPU only resolves.
    Cpu,
    /// CPU on a software adapter (lavapipe, llvmpipe), GPU otherwise.
    Auto,
}

impl ChaosBackend {
    pub const ALL: [ChaosBackend; 3] = [ChaosBackend::Auto, ChaosBackend::Gpu, ChaosBackend::Cpu];

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "gpu" => Some(Self::Gpu),
            "cpu" => Some(Self::Cpu),
            "auto" => Some(Self::Auto),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Gpu => "gpu",
            Self::Cpu => "cpu",
            Self::Auto => "auto",
        }
    }

    /// The route this setting takes on a software adapter (`software_adapter`: it rasterizes
    /// on the CPU, as lavapipe does) or a hardware one, and why; where the GPU cannot run the
    /// chaos game (`gpu_unable`: why not; a browser's WebGL2 has no compute shaders) the CPU's
    /// whatever the setting.
    pub fn route(self, software_adapter: bool, gpu_unable: Option<&'static str>) -> ChaosRoute {
        match self {
            _ if gpu_unable.is_some() => ChaosRoute { cpu: true, reason: gpu_unable.unwrap_or_default() },
            Self::Gpu => ChaosRoute { cpu: false, reason: "chosen: gpu" },
            Self::Cpu => ChaosRoute { cpu: true, reason: "chosen: cpu" },
            Self::Auto if software_adapter => ChaosRoute { cpu: true, reason: "auto: software adapter" },
            Self::Auto => ChaosRoute { cpu: false, reason: "auto: hardware adapter" },
        }
    }
}

/// Where the chaos game runs, and why (the viewer's statistics show both).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChaosRoute {
    pub cpu: bool,
    pub reason: &'static str,
}

impl ChaosRoute {
    pub fn name(&self) -> &'static str {
        if self.cpu { "cpu" } else { "gpu" }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_density_stop_scales_with_the_square_of_the_framed_height() {
        let d = RenderDensity { points: 1_000_000, width_px: 2000, height_px: 1000 };
        assert_eq!(d.splats_in_view(2000, 1000), 1_000_000);
        assert_eq!(d.splats_in_view(1000, 500), 250_000);
        assert_eq!(d.splats_in_view(4000, 2000), 4_000_000);
        assert_eq!(d.splats_in_view(3000, 500), 250_000, "a wider view: the height frames it");
        assert_eq!(d.splats_in_view(1000, 1000), 250_000, "a narrower view: the width frames it");
        assert_eq!(d.splats_in_view(0, 0), 1, "never 0: a stop before the first splat");
        let flat = RenderDensity { points: 5, width_px: 0, height_px: 0 };
        assert_eq!(flat.splats_in_view(10, 10), 500, "sizes of 0 count as 1");
    }

    #[test]
    fn auto_takes_the_cpu_on_software_adapters_only() {
        assert!(ChaosBackend::Auto.route(true, None).cpu);
        assert!(!ChaosBackend::Auto.route(false, None).cpu);
        assert!(!ChaosBackend::Gpu.route(true, None).cpu);
        assert!(ChaosBackend::Cpu.route(false, None).cpu);
        for b in ChaosBackend::ALL {
            assert_eq!(ChaosBackend::parse(b.name()), Some(b));
            let route = b.route(false, Some(crate::live::NO_COMPUTE));
            assert_eq!(route, ChaosRoute { cpu: true, reason: crate::live::NO_COMPUTE }, "only the CPU route runs");
        }
    }
}
