//! The live view: the GPU chaos game kept running across frames. Points persist on the GPU;
//! a change of the scene clears only the accumulation (after a few settling steps that are not
//! splatted), a change of the view or of the splat settings clears it too, and while nothing
//! changes frames accumulate until `max_splats` points were splatted (then the image is
//! converged and the GPU idles). The same object serves the viewer, `render --backend gpu` and
//! the benchmarks.
//!
//! With [`LiveSettings::chaos_backend`] taking the CPU route (`cpu`, or `auto` on a software
//! adapter) the chaos game runs on the CPU instead ([`super::cpu_route`]): fresh orbits every
//! frame into CPU framebuffers, uploaded into the same accumulation buffer and resolved by the
//! same pass; clears happen at the same moments.

use glam::DVec3;

use crate::camera::{OrbitCamera, Projection};
use crate::chaos_game::CompiledIfs;
use crate::scene::spec::SplatMode;
use crate::splat::SplatView;

use super::chaos_game::{FrameArgs, GpuChaosGame};
use super::cpu_route::{ChaosBackend, ChaosRoute, CpuChaosGame};
use super::resolve::{GpuResolve, ResolveArgs};
use super::{GpuContext, GpuError};

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
    /// Drawn point radius in pixels (closest mode: the nearest key within the radius).
    pub point_radius_px: u32,
    /// Splats after which accumulation stops (keeps the u32 sums far from overflow).
    pub max_splats: u64,
    /// Steps not splatted after a scene edit while the kept points settle on the new attractor.
    pub settle_steps: u32,
    /// Where the chaos game runs (the GPU only resolves on the CPU route). The default, `gpu`,
    /// serves `render --backend gpu` and the benchmarks; the viewer starts on `auto`.
    pub chaos_backend: ChaosBackend,
}

impl Default for LiveSettings {
    fn default() -> Self {
        Self {
            point_count: 1 << 20,
            steps_per_frame: 1,
            seed: 1,
            mode: SplatMode::Closest,
            depth_cue: 0.75,
            background: crate::scene::spec::RenderSettings::default().background,
            shading: 0.0,
            point_radius_px: 0,
            max_splats: 1 << 30,
            settle_steps: 8,
            chaos_backend: ChaosBackend::Gpu,
        }
    }
}

pub struct LiveView {
    game: GpuChaosGame,
    resolve: GpuResolve,
    pub settings: LiveSettings,
    bounds: (DVec3, DVec3),
    transient: u32,
    camera: Option<OrbitCamera>,
    view: Option<SplatView>,
    frame: u32,
    restart: bool,
    clear: bool,
    /// Steps still to run without splatting before the next splat.
    skip_steps: u32,
    pub frames_since_clear: u32,
    pub splats_since_clear: u64,
    has_ifs: bool,
    route: ChaosRoute,
    device_type: wgpu::DeviceType,
    cpu: CpuChaosGame,
}

fn same_view(a: &SplatView, b: &SplatView) -> bool {
    a.width == b.width
        && a.height == b.height
        && a.pixel_from_world == b.pixel_from_world
        && a.near == b.near
        && a.far == b.far
        && a.mode == b.mode
        && a.depth_cue == b.depth_cue
        && a.background == b.background
}

impl LiveView {
    pub fn new(ctx: &GpuContext, settings: LiveSettings, width: u32, height: u32) -> Result<Self, GpuError> {
        if settings.point_count as u64 > ctx.max_points() {
            return Err(GpuError::TooManyPoints(settings.point_count as u64));
        }
        let device_type = ctx.adapter.get_info().device_type;
        Ok(Self {
            route: settings.chaos_backend.route(device_type),
            device_type,
            cpu: CpuChaosGame::default(),
            game: GpuChaosGame::new(&ctx.device, settings.point_count, width.max(1), height.max(1)),
            resolve: GpuResolve::new(&ctx.device),
            settings,
            bounds: (DVec3::ZERO, DVec3::ONE),
            transient: 0,
            camera: None,
            view: None,
            frame: 0,
            restart: true,
            clear: true,
            skip_steps: 0,
            frames_since_clear: 0,
            splats_since_clear: 0,
            has_ifs: false,
        })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.game.width, self.game.height)
    }

    /// Uploads a new IFS with its attractor `bounds`. `restart`: a different scene (the points
    /// restart in the domain and skip the full transient); otherwise an edit (the points are
    /// kept and skip `settle_steps`).
    pub fn set_ifs(&mut self, ctx: &GpuContext, ifs: &CompiledIfs, bounds: (DVec3, DVec3), restart: bool) {
        self.game.set_ifs(&ctx.device, &ctx.queue, ifs);
        self.cpu.set_ifs(ifs);
        self.bounds = bounds;
        self.transient = ifs.transient;
        self.has_ifs = true;
        if restart {
            self.restart = true;
        }
        self.skip_steps = if self.restart { ifs.transient } else { self.settings.settle_steps.min(ifs.transient) };
        self.clear = true;
        self.view = None;
        self.update_view();
    }

    pub fn set_camera(&mut self, camera: &OrbitCamera) {
        self.camera = Some(*camera);
        self.update_view();
    }

    fn update_view(&mut self) {
        let Some(camera) = &self.camera else { return };
        let s = &self.settings;
        let view =
            SplatView::new(camera, self.game.width, self.game.height, self.bounds, s.mode, s.depth_cue, s.background);
        if self.view.as_ref().is_none_or(|v| !same_view(v, &view)) {
            self.view = Some(view);
            self.clear = true;
        }
    }

    pub fn set_settings(&mut self, ctx: &GpuContext, settings: LiveSettings) -> Result<(), GpuError> {
        if settings.point_count != self.settings.point_count {
            if settings.point_count as u64 > ctx.max_points() {
                return Err(GpuError::TooManyPoints(settings.point_count as u64));
            }
            self.game.set_point_count(&ctx.device, settings.point_count);
            self.restart = true;
            self.skip_steps = self.transient;
            self.clear = true;
        }
        let route = settings.chaos_backend.route(self.device_type);
        if route.cpu != self.route.cpu {
            // The GPU points did not move while the CPU ran: restart them.
            self.restart = true;
            self.skip_steps = self.transient;
            self.clear = true;
        }
        self.route = route;
        self.settings = settings;
        self.update_view();
        Ok(())
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.game.resize(&ctx.device, width.max(1), height.max(1));
        self.update_view();
    }

    /// Where the chaos game runs, and why.
    pub fn route(&self) -> ChaosRoute {
        self.route
    }

    /// The CPU route's merged accumulation as last uploaded (GPU layout), if it runs.
    pub fn cpu_accum(&self) -> Option<&[u32]> {
        self.route.cpu.then(|| self.cpu.merged())
    }

    /// True when accumulation has stopped (nothing changed for `max_splats` splats).
    pub fn converged(&self) -> bool {
        !self.clear && self.splats_since_clear >= self.settings.max_splats
    }

    /// Records one chaos-game frame into `encoder` unless converged; returns the number of
    /// point steps splatted. Submit `encoder` before the next call.
    pub fn advance(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) -> u64 {
        let Some(view) = self.view else { return 0 };
        if !self.has_ifs || self.converged() {
            return 0;
        }
        if self.route.cpu {
            return self.advance_cpu(ctx, &view);
        }
        let steps = self.skip_steps + self.settings.steps_per_frame;
        let args = FrameArgs {
            view: &view,
            seed: self.settings.seed,
            frame: self.frame,
            steps,
            skip_steps: self.skip_steps,
            restart: self.restart,
            clear: self.clear,
        };
        self.game.encode(&ctx.device, &ctx.queue, encoder, &args);
        if self.clear {
            self.frames_since_clear = 0;
            self.splats_since_clear = 0;
        }
        let splats = self.game.point_count as u64 * self.settings.steps_per_frame as u64;
        self.frames_since_clear += 1;
        self.splats_since_clear += splats;
        self.frame = self.frame.wrapping_add(1);
        self.restart = false;
        self.clear = false;
        self.skip_steps = 0;
        splats
    }

    /// The CPU route's frame: splat on the CPU, upload (through the queue, ordered before the
    /// encoder's resolve once both are submitted).
    fn advance_cpu(&mut self, ctx: &GpuContext, view: &SplatView) -> u64 {
        if self.clear {
            self.cpu.clear(view);
            self.frames_since_clear = 0;
            self.splats_since_clear = 0;
        }
        let points = self.settings.point_count as u64 * self.settings.steps_per_frame as u64;
        let splats = self.cpu.advance(self.settings.seed, self.frame, points);
        self.cpu.upload(&ctx.queue, &self.game.accum);
        self.frames_since_clear += 1;
        self.splats_since_clear += splats;
        self.frame = self.frame.wrapping_add(1);
        self.clear = false;
        splats
    }

    /// Records only an emptying of the accumulation buffer (benchmarks time it alone).
    pub fn encode_clear(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        let Some(view) = self.view else { return };
        let args = FrameArgs {
            view: &view,
            seed: self.settings.seed,
            frame: self.frame,
            steps: 0,
            skip_steps: 0,
            restart: false,
            clear: true,
        };
        self.game.encode(&ctx.device, &ctx.queue, encoder, &args);
        self.clear = false;
        self.frames_since_clear = 0;
        self.splats_since_clear = 0;
    }

    /// Records the resolve onto `target` (the window's surface or an offscreen texture) with
    /// the accumulation's pixel (0, 0) at `origin_px` of the target; the target must hold the
    /// rectangle of [`Self::size`] there.
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        origin_px: [u32; 2],
    ) {
        let s = &self.settings;
        let (near, far) = self.view.map_or((0.0, 1.0), |v| (v.near, v.far));
        let (pixel_size, perspective) = match &self.camera {
            Some(c) if c.projection == Projection::Perspective => {
                (2.0 * (0.5 * c.fov_y_deg.to_radians()).tan() / self.game.height as f32, true)
            }
            Some(c) => (2.0 * c.half_height_at_target() / self.game.height as f32, false),
            None => (1.0, false),
        };
        let args = ResolveArgs {
            mode: s.mode,
            background: s.background,
            depth_cue: s.depth_cue,
            shading: s.shading,
            point_radius_px: s.point_radius_px,
            near,
            far,
            pixel_size,
            perspective,
            origin_px,
        };
        self.resolve.draw(&ctx.device, &ctx.queue, encoder, &self.game, &args, target, format);
    }

    /// Reads the accumulation buffer back (four u32 per pixel, as `Framebuffer` after a
    /// fashion: closest keys in slot 0, or r, g, b sums and the count). Tests and benchmarks.
    pub fn read_accum(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let bytes = super::render::read_buffer(ctx, &self.game.accum)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
