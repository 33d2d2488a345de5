//! The live view's settings as plain data: what the viewer's render panel edits and its state
//! holds, free of GPU types ([`crate::live::LiveView`] converts them for the GPU at the
//! boundary), with the choice of where the chaos game runs ([`ChaosBackend`]) and the route it
//! took on the adapter at hand ([`ChaosRoute`]).

use crate::resolve::Tone;
use crate::scene::spec::{DensityEstimation, SplatMode};

/// Settings of the live view (the viewer's render panel edits them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveSettings {
    /// Persistent points on the GPU.
    pub point_count: u32,
    /// Steps every point advances (and splats) per frame.
    pub steps_per_frame: u32,
    pub seed: u32,
    pub mode: SplatMode,
    pub depth_cue: f32,
    /// Linear RGB.
    pub background: [f32; 3],
    /// Screen-space shading strength in [0, 1] (closest mode).
    pub shading: f32,
    /// Screen-space ambient occlusion strength in [0, 1] (closest mode).
    pub occlusion: f32,
    /// Drawn point radius in pixels (closest mode: the nearest key within the radius).
    pub point_radius_px: u32,
    /// Splats after which accumulation stops (keeps the u32 sums far from overflow).
    pub max_splats: u64,
    /// Steps not splatted after a scene edit while the kept points settle on the new attractor.
    pub settle_steps: u32,
    /// Where the chaos game runs (the GPU only resolves on the CPU route). The default, `gpu`,
    /// is what `render --backend gpu` and the benchmarks run; the viewer starts on `auto`.
    pub chaos_backend: ChaosBackend,
    // Shadows (`crate::resolve::shadow`).
    /// Cast shadow strength in [0, 1] (closest mode, with shading on).
    pub shadows: f32,
    /// The key light's direction relative to the camera.
    pub light_yaw_deg: f32,
    pub light_pitch_deg: f32,
    // Depth of field (`crate::splat::lens`).
    /// Thin-lens radius in scene units; 0: none.
    pub aperture: f32,
    /// View distance in focus; None: the camera's distance to its target.
    pub focus_distance: Option<f32>,
    /// flam3's tone map (average and density modes): the scene's `[render]` tone at the
    /// playhead, as `render` resolves it.
    pub tone: Tone,
    /// flam3's density estimation (density mode): the scene's, None off.
    pub density_estimation: Option<DensityEstimation>,
}

impl Default for LiveSettings {
    /// The same values as `gpu::progressive::ProgressiveSettings::default` (a test in
    /// `crate::live` keeps them equal), with the GPU chaos game.
    fn default() -> Self {
        Self {
            point_count: 1 << 20,
            steps_per_frame: 1,
            seed: 1,
            mode: SplatMode::Closest,
            depth_cue: 0.75,
            background: crate::scene::spec::RenderSettings::default().background,
            shading: 0.0,
            occlusion: 0.0,
            point_radius_px: 0,
            max_splats: 1 << 30,
            settle_steps: 8,
            chaos_backend: ChaosBackend::Gpu,
            shadows: 0.0,
            light_yaw_deg: crate::resolve::KEY_LIGHT_YAW_DEG,
            light_pitch_deg: crate::resolve::KEY_LIGHT_PITCH_DEG,
            aperture: 0.0,
            focus_distance: None,
            tone: Tone::NEUTRAL,
            density_estimation: None,
        }
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
        let tone = Tone { exposure: v[0], gamma: v[1], gamma_threshold: v[2], vibrancy: v[3], highlight_power: v[4] };
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
    /// on the CPU, as lavapipe does) or a hardware one, and why.
    pub fn route(self, software_adapter: bool) -> ChaosRoute {
        match self {
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
    fn auto_takes_the_cpu_on_software_adapters_only() {
        assert!(ChaosBackend::Auto.route(true).cpu);
        assert!(!ChaosBackend::Auto.route(false).cpu);
        assert!(!ChaosBackend::Gpu.route(true).cpu);
        assert!(ChaosBackend::Cpu.route(false).cpu);
        for b in ChaosBackend::ALL {
            assert_eq!(ChaosBackend::parse(b.name()), Some(b));
        }
    }
}
