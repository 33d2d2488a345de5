//! The live view: the chaos game kept running across frames and resolved on the GPU, as the
//! viewer shows it. Its GPU half is [`crate::gpu::progressive::Progressive`] (persistent points,
//! accumulation, clears, convergence, the resolve); this layer adds where the points come from
//! and the viewer's settings:
//!
//! - `settings.rs`: [`LiveSettings`], plain data the viewer's state holds, and the choice of
//!   backend ([`ChaosBackend`]) with the route it takes ([`ChaosRoute`]);
//! - `cpu_source.rs`: the CPU point source ([`cpu_source::CpuChaosGame`]);
//! - here, [`LiveView`], which converts the settings at the GPU boundary and runs each frame on
//!   the route the backend takes on the adapter at hand.
//!
//! On an adapter without compute shaders (a browser's WebGL2) the CPU route is the only one, and
//! the accumulation is resolved on the CPU too and drawn as a texture (`gpu/picture.rs`).
//!
//! With [`LiveSettings::chaos_backend`] taking the CPU route (`cpu`, or `auto` on a software
//! adapter) the chaos game runs on the CPU: persistent chains advanced every frame into CPU
//! framebuffers, uploaded into the same accumulation buffer and resolved by the same pass;
//! clears, restarts and the settling after an edit happen at the same moments. Density
//! estimation is then made on the CPU too (`src/resolve/density_estimation.rs`, from the
//! accumulation the route uploads), where it costs milliseconds instead of the GPU gather's
//! tenths of a second on a software rasterizer; the GPU draws it the same way.

pub mod cpu_source;
pub mod settings;

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::chaos_game::CompiledIfs;
use crate::gpu::progressive::{EstimateDue, Progressive, ProgressiveSettings};
use crate::gpu::{GpuContext, GpuError};
use crate::platform::Instant;
use crate::resolve::density_estimation;
use crate::scene::spec::SplatMode;

use self::cpu_source::CpuChaosGame;
pub use self::settings::{ChaosBackend, ChaosRoute, Imaging, LiveSettings, RenderDensity};

/// The live view refreshes the solid look's light a quarter of the rows per frame while the
/// view rests ([`Progressive::light_bands`]): the look's cost a frame drops about fourfold.
pub const LIGHT_BANDS: u32 = 4;

/// Why the CPU route runs on an adapter without compute shaders (a browser's WebGL2).
pub const NO_COMPUTE: &str = "the adapter has no compute shaders";

/// Settle steps after an edit while navigating ([`LiveView::set_navigating`]).
pub const NAVIGATING_SETTLE_STEPS: u32 = 2;

/// The CPU route's chaos game a frame, at most, where the viewer bounds it
/// ([`LiveView::bound_frame_time`]): with the resolve and the present, a costly scene (a flame's
/// variations, builders) still draws about 20 frames a second on lavapipe while it accumulates
/// and while navigating, for 0.4–0.8 times the points a second of unbounded frames (their
/// fixed costs, merge, upload, resolve and present, come more often).
pub const CPU_FRAME_SECS: f64 = 0.020;

pub struct LiveView {
    gpu: Progressive,
    settings: LiveSettings,
    route: ChaosRoute,
    /// The adapter rasterizes on the CPU (lavapipe, llvmpipe): `auto` takes the CPU route.
    software_adapter: bool,
    /// Why the GPU cannot run this IFS's chaos game, if it cannot (no compute shaders, or tables
    /// that need more storage buffers than the device binds): the CPU route runs.
    gpu_unable: Option<&'static str>,
    cpu: CpuChaosGame,
    /// The camera is being dragged: the view draws without the key light's shadows
    /// ([`Self::set_navigating`]).
    navigating: bool,
    /// The CPU route's frames are cut to [`CPU_FRAME_SECS`] of chaos game
    /// ([`Self::bound_frame_time`]); otherwise every frame runs the settings' points, as the
    /// tests and benchmarks want.
    bounded_frame_time: bool,
    /// Points a second the CPU route's frames have splatted lately (whole frames, fixed costs
    /// included), from which the next bounded frame is sized.
    cpu_points_per_sec: Option<f64>,
}

impl LiveView {
    pub fn new(ctx: &GpuContext, settings: LiveSettings, width: u32, height: u32) -> Result<Self, GpuError> {
        Ok(Self::with_gpu(ctx, settings, Progressive::new(ctx, settings.draw, width, height)?))
    }

    /// [`Self::new`] drawing on the CPU (its route and resolve) whether the adapter has compute
    /// shaders or not, as it does where it has none (a browser's WebGL2). Tests.
    pub fn without_compute(
        ctx: &GpuContext,
        settings: LiveSettings,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        Ok(Self::with_gpu(ctx, settings, Progressive::with_compute(ctx, settings.draw, width, height, false)?))
    }

    fn with_gpu(ctx: &GpuContext, settings: LiveSettings, mut gpu: Progressive) -> Self {
        let software_adapter = ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        gpu.light_bands = LIGHT_BANDS;
        let gpu_unable = (!gpu.computes()).then_some(NO_COMPUTE);
        let mut live = Self {
            route: settings.chaos_backend.route(software_adapter, gpu_unable),
            gpu,
            settings,
            software_adapter,
            gpu_unable,
            cpu: CpuChaosGame::default(),
            navigating: false,
            bounded_frame_time: false,
            cpu_points_per_sec: None,
        };
        live.gpu.set_max_splats(live.max_splats(&settings));
        live
    }

    /// Bounds the time of the CPU route's frames to [`CPU_FRAME_SECS`] (the viewer does). A
    /// frame then splats what the last frames' rate fits in the bound, at most the settings'
    /// points, at least one step of every chain.
    pub fn bound_frame_time(&mut self, bounded: bool) {
        self.bounded_frame_time = bounded;
    }

    /// The CPU route's points for the next frame: the settings' points, or fewer to keep within
    /// the frame time's bound.
    fn cpu_frame_points(&self) -> (u64, u64) {
        let points = self.settings.draw.point_count as u64 * self.settings.draw.steps_per_frame as u64;
        let at_most = match (self.bounded_frame_time, self.cpu_points_per_sec) {
            (true, Some(rate)) => (rate * CPU_FRAME_SECS) as u64,
            _ => u64::MAX,
        };
        (points, at_most)
    }

    /// What the GPU side runs for `settings`: the same, without shadows and occlusion and with
    /// the normals fitted in a smaller window while navigating.
    fn progressive_settings(&self, settings: &LiveSettings) -> ProgressiveSettings {
        let mut p = settings.draw;
        if self.navigating {
            p.shadows = 0.0;
            p.occlusion = 0.0;
            p.normal_radius_px = crate::resolve::NAVIGATING_NORMAL_RADIUS_PX;
        }
        p.settle_steps = self.settle_steps();
        p.max_splats = self.max_splats(settings);
        p
    }

    /// Splats after which accumulation stops: in density mode, the render's points per pixel
    /// ([`RenderDensity`]), though never within the first frame. On the relative scale a longer
    /// accumulation would wash the picture out; on the absolute scale it would only refine past
    /// what `render` draws, for minutes on the CPU route (a flame's 2^30 points at 1–2 M a
    /// second), where the view is meant to rest.
    fn max_splats(&self, settings: &LiveSettings) -> u64 {
        let cap = settings.draw.max_splats;
        match settings.render_density {
            Some(d) if settings.draw.mode == SplatMode::Density => {
                let frame = settings.draw.point_count as u64 * settings.draw.steps_per_frame.max(1) as u64;
                let (width, height) = self.size();
                cap.min(d.splats_in_view(width, height).max(frame))
            }
            _ => cap,
        }
    }

    /// Steps the kept points run unsplatted after an edit: fewer while navigating, where the
    /// edits come every frame (a playing timeline) and each moves the attractor by one frame's
    /// change, which `NAVIGATING_SETTLE_STEPS` contractions shrink below what a moving view
    /// shows; the settle steps were most of a playing frame's chaos game.
    fn settle_steps(&self) -> u32 {
        match self.navigating {
            true => self.settings.draw.settle_steps.min(NAVIGATING_SETTLE_STEPS),
            false => self.settings.draw.settle_steps,
        }
    }

    /// While the camera is dragged (orbit, pan) the view draws without the key light's shadows
    /// and without ambient occlusion, its normals fitted to 3×3 keys instead of 5×5 (key, fill
    /// and highlight stay), as 3D viewports lower their quality while navigating: every frame
    /// of a moving camera starts afresh and lights every pixel, and on lavapipe the shadow map,
    /// its lookups, the 16 occlusion samples and the 25-key plane fit a pixel take it below
    /// 20 fps. All come back, with a fresh accumulation, when the drag ends.
    pub fn set_navigating(&mut self, ctx: &GpuContext, navigating: bool) -> Result<(), GpuError> {
        if navigating == self.navigating {
            return Ok(());
        }
        self.navigating = navigating;
        self.gpu.set_settings(ctx, self.progressive_settings(&self.settings))
    }

    pub fn settings(&self) -> &LiveSettings {
        &self.settings
    }

    pub fn size(&self) -> (u32, u32) {
        self.gpu.size()
    }

    /// Splats since the accumulation was last cleared.
    pub fn splats_since_clear(&self) -> u64 {
        self.gpu.splats_since_clear
    }

    /// What the next draw does about density estimation.
    pub fn estimate_due(&self) -> EstimateDue {
        self.gpu.estimate_due()
    }

    /// Uploads a new IFS with its attractor `bounds`. `restart`: a different scene (the points
    /// restart in the domain and skip the full transient); otherwise an edit (the points are
    /// kept and skip `settle_steps`).
    pub fn set_ifs(&mut self, ctx: &GpuContext, ifs: &CompiledIfs, bounds: (DVec3, DVec3), restart: bool) {
        self.gpu.set_ifs(ctx, ifs, bounds, restart);
        self.cpu.set_ifs(ifs, restart, self.settle_steps());
        self.gpu_unable = match self.gpu.computes() {
            true => crate::gpu::chaos_game::unable_to_run(&ctx.device.limits(), ifs),
            false => Some(NO_COMPUTE),
        };
        self.take_route(self.settings.chaos_backend);
    }

    /// Takes the route `backend` gives on this adapter for this IFS; the points of a route that
    /// did not run did not follow the edits: they restart when the route changes.
    fn take_route(&mut self, backend: ChaosBackend) {
        let route = backend.route(self.software_adapter, self.gpu_unable);
        if route.cpu != self.route.cpu {
            self.gpu.restart_points();
            self.cpu.restart();
        }
        self.route = route;
    }

    pub fn set_camera(&mut self, camera: &OrbitCamera) {
        self.gpu.set_camera(camera);
    }

    pub fn set_settings(&mut self, ctx: &GpuContext, settings: LiveSettings) -> Result<(), GpuError> {
        self.gpu.set_settings(ctx, self.progressive_settings(&settings))?;
        self.take_route(settings.chaos_backend);
        self.settings = settings;
        Ok(())
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.gpu.resize(ctx, width, height);
        // The density stop scales with the view's size.
        self.gpu.set_max_splats(self.max_splats(&self.settings));
    }

    /// Where the chaos game runs, and why.
    pub fn route(&self) -> ChaosRoute {
        self.route
    }

    /// The CPU route's merged accumulation as last uploaded (GPU layout), if it runs.
    pub fn cpu_accum(&self) -> Option<&[u32]> {
        self.route.cpu.then(|| self.cpu.merged())
    }

    /// The CPU route's point source (its persistent chains), whichever route runs.
    pub fn cpu_source(&self) -> &CpuChaosGame {
        &self.cpu
    }

    /// Pixels hit by at least one point since the last clear, where it is known without a GPU
    /// read-back (the CPU route's accumulation: one closest-point key per pixel, or four
    /// words per pixel with the count last).
    pub fn lit_pixels(&self) -> Option<u64> {
        let accum = self.cpu_accum()?;
        let (w, h) = self.size();
        let pixels = w as usize * h as usize;
        if accum.len() == pixels {
            Some(accum.iter().filter(|&&k| k != crate::splat::EMPTY).count() as u64)
        } else if accum.len() == 4 * pixels {
            Some(accum.chunks_exact(4).filter(|a| a[3] > 0).count() as u64)
        } else {
            None
        }
    }

    /// True when accumulation has stopped (nothing changed for `max_splats` splats).
    pub fn converged(&self) -> bool {
        self.gpu.converged()
    }

    /// True when another draw would show the same picture (see [`Progressive::at_rest`]): the
    /// viewer then draws nothing until something changes.
    pub fn at_rest(&self) -> bool {
        self.gpu.at_rest()
    }

    /// Records one chaos-game frame into `encoder` (GPU route) or splats and uploads one on
    /// the CPU, unless converged; returns the number of point steps splatted. Submit `encoder`
    /// before the next call.
    pub fn advance(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) -> u64 {
        if !self.route.cpu {
            return self.gpu.advance(ctx, encoder);
        }
        let Some(frame) = self.gpu.begin_uploaded_frame() else { return 0 };
        if frame.clear {
            self.cpu.clear(&frame.view);
        }
        let (points, at_most) = self.cpu_frame_points();
        let started = Instant::now();
        let splats = self.cpu.advance_within(self.settings.draw.seed, frame.frame, points, at_most);
        let secs = started.elapsed().as_secs_f64();
        if splats > 0 && secs > 0.0 {
            // Half the last frame, half the frames before: one slow frame (the machine busy
            // elsewhere) does not halve the next.
            let rate = splats as f64 / secs;
            self.cpu_points_per_sec = Some(self.cpu_points_per_sec.map_or(rate, |r| 0.5 * (r + rate)));
        }
        if frame.view.shadow.is_some() {
            self.gpu.upload_shadow(ctx, self.cpu.merged_shadow());
        }
        self.gpu.finish_uploaded_frame(ctx, self.cpu.merged(), splats);
        splats
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
        // The CPU route's accumulation is on the CPU, where the density estimate's scatter
        // costs a fraction of the GPU's gather on a software rasterizer.
        if let (true, EstimateDue::Make(de)) = (self.route.cpu, self.gpu.estimate_due()) {
            let (width, height) = self.size();
            let merged = self.cpu.merged();
            if merged.len() == 4 * width as usize * height as usize {
                let e = density_estimation::estimate(bytemuck::cast_slice(merged), width, height, &de);
                self.gpu.upload_estimate(ctx, e, &de);
            }
        }
        self.gpu.draw(ctx, encoder, target, format, origin_px);
    }

    /// Resolves into an offscreen texture of [`Self::size`] and reads it back (screenshots).
    pub fn snapshot(&mut self, ctx: &GpuContext) -> Result<image::RgbImage, GpuError> {
        self.gpu.snapshot(ctx)
    }

    /// [`Self::snapshot`] as a submitted copy whose image can be awaited (the browser's way).
    pub fn snapshot_start(&mut self, ctx: &GpuContext) -> crate::gpu::readback::OffscreenCopy {
        self.gpu.snapshot_start(ctx)
    }

    /// Reads the accumulation buffer back (see [`Progressive::read_accum`]). Tests.
    pub fn read_accum(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        self.gpu.read_accum(ctx)
    }

    /// [`Self::read_accum`] that also works in the browser (awaits the map). Tests.
    pub async fn read_accum_async(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        self.gpu.read_accum_async(ctx).await
    }
}
