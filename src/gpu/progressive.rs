//! Progressive GPU rendering: the GPU chaos game kept running across frames with its resolve.
//! Points persist on the GPU; a change of the scene clears only the accumulation (after a few
//! settling steps that are not splatted), a change of the view or of the splat settings clears
//! it too, and while nothing changes frames accumulate until `max_splats` points were splatted
//! (then the image is converged and the GPU idles).
//!
//! This is the GPU half of the live view (`src/live/`, the layer above, which adds the CPU
//! point source and the viewer's settings) and, on its own, the engine of `render --backend gpu` and
//! of the GPU benchmarks. A point source outside the GPU writes its frames into the same
//! accumulation ([`Progressive::begin_uploaded_frame`], [`Progressive::finish_uploaded_frame`]),
//! so both are resolved by the same pass and cleared at the same moments.
//!
//! The resolve takes the settings' tone map; in density mode with density estimation on, the
//! draw shows the estimate of `shaders/density_estimation.wgsl` instead of the raw counts. The
//! filter reads every pixel's neighbourhood (up to about a second for 1280×720 at radius 9 on
//! lavapipe, two busy cores), too costly for every frame on a software rasterizer, so it waits
//! until the accumulation has rested [`ESTIMATE_FIRST_FRAMES`] frames after a clear (while the camera
//! moves, the raw counts are drawn), runs again whenever the frames since the clear have
//! doubled, at most [`ESTIMATE_EVERY_FRAMES`] apart, and once more when accumulation stops;
//! draws in between show the last estimate as it was made (on the absolute scale of the points
//! it was made of; snapshots estimate afresh). A spatial filter (`Tone::filter`) goes with the
//! estimate: filtered once per estimate (without one, density mode makes the estimate that
//! spreads nothing, `SPREADS_NOTHING`), and left out of the raw counts drawn before the first.
//! A point source on the CPU may make the estimate itself, with the CPU twin, and hand it over
//! ([`Progressive::upload_estimate`] when [`Progressive::estimate_due`] asks for one).

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::chaos_game::CompiledIfs;
use crate::scene::spec::SplatMode;
use crate::splat::{Lens, SplatView};

use super::chaos_game::{FrameArgs, GpuChaosGame};
use super::density_estimation::GpuDensityEstimation;
use super::picture::CpuPicture;
use super::resolve::{GpuResolve, LightRows};
use super::{GpuContext, GpuError};
use crate::resolve::density_estimation::{self, Estimated};
use crate::resolve::{ResolveArgs, Tone};
use crate::scene::spec::DensityEstimation;

/// Settings of a progressive render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressiveSettings {
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
    /// The radius of the normals' plane fit (the solid look), 1 ..= `resolve::NORMAL_RADIUS_PX`.
    pub normal_radius_px: u32,
    /// Splats after which accumulation stops (keeps the u32 sums far from overflow).
    pub max_splats: u64,
    /// Steps not splatted after a scene edit while the kept points settle on the new attractor.
    pub settle_steps: u32,
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
    /// The tone map of the average and density modes.
    pub tone: Tone,
    /// Density estimation (density mode); None: off.
    pub density_estimation: Option<DensityEstimation>,
}

/// What a draw does about density estimation ([`Progressive::estimate_due`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EstimateDue {
    /// Not in use (another mode, or off): the raw resolve.
    Off,
    /// The accumulation is too young since its clear: the raw resolve.
    Young,
    /// The last estimate is recent enough: drawn again.
    Keep,
    /// A fresh estimate with this setting, then drawn.
    Make(DensityEstimation),
}

/// Frames after a clear before the first density estimate (a moving camera clears every frame).
pub const ESTIMATE_FIRST_FRAMES: u32 = 8;
/// Most frames between two density estimates (before, the estimate is refreshed whenever the
/// frames since the clear have doubled).
pub const ESTIMATE_EVERY_FRAMES: u32 = 256;

impl Default for ProgressiveSettings {
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
            normal_radius_px: crate::resolve::NORMAL_RADIUS_PX,
            max_splats: 1 << 30,
            settle_steps: 8,
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

impl ProgressiveSettings {
    /// The background as the splat and the resolve hold it: in the space the colours are mixed
    /// in ([`SplatMode::blend_space`]).
    pub fn splat_background(&self) -> [f32; 3] {
        self.mode.blend_space(self.tone.blend).of_linear(self.background)
    }
}

/// A frame that a point source outside the GPU fills: the view to splat with, whether the
/// accumulation starts empty, and the frame's index (its random streams).
#[derive(Clone, Copy, Debug)]
pub struct UploadedFrame {
    pub view: SplatView,
    pub clear: bool,
    pub frame: u32,
}

/// Where the accumulation lives and what resolves it.
#[allow(
    clippy::large_enum_variant,
    reason = "one per progressive render, never moved in a loop; wasm32's pointers make the GPU variant the larger"
)]
enum Engine {
    /// Compute shaders: the chaos game, its accumulation and the resolve on the GPU, and the
    /// density estimation pass (made on first use).
    Gpu { game: GpuChaosGame, resolve: GpuResolve, estimation: Option<GpuDensityEstimation> },
    /// No compute shaders (a browser's WebGL2): the accumulation comes from the CPU
    /// ([`Progressive::begin_uploaded_frame`]) and is resolved there, the picture drawn as a
    /// texture (`gpu/picture.rs`).
    Picture(Box<CpuPicture>),
}

pub struct Progressive {
    engine: Engine,
    width: u32,
    height: u32,
    pub settings: ProgressiveSettings,
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
    /// The solid look's light (normals, occlusion) refreshed in this many bands of rows, one
    /// per draw, while the view rests (0 or 1: computed in every draw for every pixel). The
    /// first [`LIGHT_FULL_FRAMES`] frames after a clear compute it in the draw, the next one
    /// and any change of the resolve's arguments refresh it whole. Snapshots always compute it
    /// whole.
    pub light_bands: u32,
    /// The next band to refresh, and the arguments the light cache was last refreshed with.
    light_band: u32,
    /// Bands refreshed since the accumulation last changed (all of them: the light is current).
    bands_since_change: u32,
    light_args: Option<ResolveArgs>,
    /// Clears of the accumulation so far (an estimate belongs to one accumulation).
    clears: u64,
    /// What the last density estimate was made of.
    estimated: Option<MadeEstimate>,
}

/// What a density estimate was made of: the accumulation (its clear count), the frames and
/// points splatted since that clear, and the setting.
#[derive(Clone, Copy, Debug, PartialEq)]
struct MadeEstimate {
    clears: u64,
    frames: u32,
    splats: u64,
    de: DensityEstimation,
}

/// Frames after a clear whose draws refresh the whole light cache (a cloud filling in changes
/// its normals fast; after these frames a band that is a few frames old looks the same).
pub const LIGHT_FULL_FRAMES: u32 = 8;

fn same_view(a: &SplatView, b: &SplatView) -> bool {
    a.width == b.width
        && a.height == b.height
        && a.pixel_from_world == b.pixel_from_world
        && a.near == b.near
        && a.far == b.far
        && a.mode == b.mode
        && a.depth_cue == b.depth_cue
        && a.background == b.background
        && a.shadow == b.shadow
        && a.lens == b.lens
}

impl Progressive {
    /// A progressive render on the GPU where the adapter has compute shaders; otherwise one
    /// whose frames come from the CPU and are resolved there ([`Self::computes`] tells which).
    pub fn new(ctx: &GpuContext, settings: ProgressiveSettings, width: u32, height: u32) -> Result<Self, GpuError> {
        let compute = ctx.adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS);
        Self::with_compute(ctx, settings, width, height, compute)
    }

    /// [`Self::new`] on the GPU (`compute`, which the adapter must have) or with the picture
    /// resolved on the CPU (any adapter; tests draw both on one).
    pub fn with_compute(
        ctx: &GpuContext,
        settings: ProgressiveSettings,
        width: u32,
        height: u32,
        compute: bool,
    ) -> Result<Self, GpuError> {
        crate::splat::lens::check(settings.aperture, settings.focus_distance)?;
        let (width, height) = (width.max(1), height.max(1));
        let engine = if compute {
            if settings.point_count as u64 > ctx.max_points() {
                return Err(GpuError::TooManyPoints(settings.point_count as u64));
            }
            Engine::Gpu {
                game: GpuChaosGame::new(&ctx.device, settings.point_count, width, height),
                resolve: GpuResolve::new(&ctx.device),
                estimation: None,
            }
        } else {
            Engine::Picture(Box::new(CpuPicture::new(&ctx.device)))
        };
        Ok(Self {
            engine,
            width,
            height,
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
            light_bands: 0,
            light_band: 0,
            bands_since_change: 0,
            light_args: None,
            clears: 0,
            estimated: None,
        })
    }

    /// The chaos game and the resolve run on the GPU; false: frames come from the CPU
    /// ([`Self::begin_uploaded_frame`]) and are resolved there.
    pub fn computes(&self) -> bool {
        matches!(self.engine, Engine::Gpu { .. })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Uploads a new IFS with its attractor `bounds`. `restart`: a different scene (the points
    /// restart in the domain and skip the full transient); otherwise an edit (the points are
    /// kept and skip `settle_steps`).
    pub fn set_ifs(&mut self, ctx: &GpuContext, ifs: &CompiledIfs, bounds: (DVec3, DVec3), restart: bool) {
        match &mut self.engine {
            Engine::Gpu { game, .. } => game.set_ifs(&ctx.device, &ctx.queue, ifs),
            Engine::Picture(picture) => picture.set_colors(&ifs.colors),
        }
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
            SplatView::new(camera, self.width, self.height, self.bounds, s.mode, s.depth_cue, s.splat_background());
        let casts = s.mode == SplatMode::Closest && s.shadows > 0.0 && s.shading > 0.0;
        let to_light = crate::resolve::shadow::key_light(s.light_yaw_deg, s.light_pitch_deg);
        let view = super::shadow::live_shadow(view, casts, glam::Vec3::from_array(to_light), camera, self.bounds);
        // The settings' lens was checked when they were set.
        let lens = Lens::new(camera, self.height, s.aperture, s.focus_distance, s.seed).unwrap_or(Lens::NONE);
        let view = view.with_lens(lens);
        if self.view.as_ref().is_none_or(|v| !same_view(v, &view)) {
            self.view = Some(view);
            self.clear = true;
        }
    }

    pub fn set_settings(&mut self, ctx: &GpuContext, settings: ProgressiveSettings) -> Result<(), GpuError> {
        crate::splat::lens::check(settings.aperture, settings.focus_distance)?;
        if settings.point_count != self.settings.point_count {
            if let Engine::Gpu { game, .. } = &mut self.engine {
                if settings.point_count as u64 > ctx.max_points() {
                    return Err(GpuError::TooManyPoints(settings.point_count as u64));
                }
                game.set_point_count(&ctx.device, settings.point_count);
            }
            self.restart_points();
        }
        self.settings = settings;
        self.update_view();
        Ok(())
    }

    /// Accumulation stops after `max_splats` splats from now on (the settings' own, changed
    /// alone: a view resized keeps its density stop).
    pub fn set_max_splats(&mut self, max_splats: u64) {
        self.settings.max_splats = max_splats;
    }

    /// Restarts the persistent points in the domain (they skip the full transient again) and
    /// clears the accumulation.
    pub fn restart_points(&mut self) {
        self.restart = true;
        self.skip_steps = self.transient;
        self.clear = true;
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        (self.width, self.height) = (width.max(1), height.max(1));
        if let Engine::Gpu { game, .. } = &mut self.engine {
            game.resize(&ctx.device, self.width, self.height);
        }
        self.update_view();
    }

    /// True when accumulation has stopped (nothing changed for `max_splats` splats).
    pub fn converged(&self) -> bool {
        !self.clear && self.splats_since_clear >= self.settings.max_splats
    }

    /// True when another draw would show what the last one showed: accumulation has stopped,
    /// and the picture drawn caught up with it: the density estimate made since the last frame
    /// (drawn as it is), else the light cache's bands all refreshed since it last changed.
    pub fn at_rest(&self) -> bool {
        if !self.converged() {
            return false;
        }
        match self.estimate_due() {
            EstimateDue::Keep => true,
            EstimateDue::Make(_) => false,
            EstimateDue::Off | EstimateDue::Young => {
                self.light_bands <= 1 || self.bands_since_change >= self.light_bands
            }
        }
    }

    /// Records one chaos-game frame into `encoder` unless converged; returns the number of
    /// point steps splatted (none without compute shaders: the frames come from the CPU).
    /// Submit `encoder` before the next call.
    pub fn advance(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) -> u64 {
        let Some(view) = self.view else { return 0 };
        if !self.has_ifs || self.converged() {
            return 0;
        }
        let Engine::Gpu { game, .. } = &mut self.engine else { return 0 };
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
        game.encode(&ctx.device, &ctx.queue, encoder, &args);
        let splats = game.point_count as u64 * self.settings.steps_per_frame as u64;
        if self.clear {
            self.frames_since_clear = 0;
            self.splats_since_clear = 0;
            self.clears += 1;
        }
        self.bands_since_change = 0;
        self.frames_since_clear += 1;
        self.splats_since_clear += splats;
        self.frame = self.frame.wrapping_add(1);
        self.restart = false;
        self.clear = false;
        self.skip_steps = 0;
        splats
    }

    /// Starts a frame whose points come from elsewhere (the live view's CPU route) unless
    /// converged or nothing is set up yet; the persistent GPU points do not move. Fill the
    /// frame and hand it to [`Self::finish_uploaded_frame`].
    pub fn begin_uploaded_frame(&mut self) -> Option<UploadedFrame> {
        let view = self.view?;
        if !self.has_ifs || self.converged() {
            return None;
        }
        if self.clear {
            self.frames_since_clear = 0;
            self.splats_since_clear = 0;
            self.clears += 1;
        }
        Some(UploadedFrame { view, clear: self.clear, frame: self.frame })
    }

    /// Ends a frame begun by [`Self::begin_uploaded_frame`]: writes `accum` (the whole
    /// accumulation since the last clear, in the GPU layout of `shaders/chaos_game.wgsl`) to the
    /// start of the accumulation buffer through the queue (ordered before an encoder's resolve
    /// once both are submitted), and counts `splats`.
    /// Uploads the shadow map of a frame from elsewhere (before [`Self::finish_uploaded_frame`]).
    pub fn upload_shadow(&mut self, ctx: &GpuContext, shadow: &[u32]) {
        let Some(view) = self.view else { return };
        match &mut self.engine {
            Engine::Gpu { game, .. } => {
                game.fit_shadow(&ctx.device, view.shadow.as_ref());
                if view.shadow.is_some_and(|s| s.texels() == shadow.len()) {
                    ctx.queue.write_buffer(&game.shadow, 0, bytemuck::cast_slice(shadow));
                }
            }
            Engine::Picture(picture) => picture.set_shadow(shadow),
        }
    }

    pub fn finish_uploaded_frame(&mut self, ctx: &GpuContext, accum: &[u32], splats: u64) {
        match &mut self.engine {
            Engine::Gpu { game, .. } if !accum.is_empty() => {
                ctx.queue.write_buffer(&game.accum, 0, bytemuck::cast_slice(accum))
            }
            Engine::Gpu { .. } => {}
            Engine::Picture(picture) => picture.set_accum(accum),
        }
        self.bands_since_change = 0;
        self.frames_since_clear += 1;
        self.splats_since_clear += splats;
        self.frame = self.frame.wrapping_add(1);
        self.clear = false;
    }

    /// Records only an emptying of the accumulation buffer (benchmarks time it alone).
    pub fn encode_clear(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        let Some(view) = self.view else { return };
        let game = match &mut self.engine {
            Engine::Gpu { game, .. } => game,
            Engine::Picture(picture) => {
                picture.clear();
                self.clear = false;
                self.frames_since_clear = 0;
                self.splats_since_clear = 0;
                self.clears += 1;
                return;
            }
        };
        let args = FrameArgs {
            view: &view,
            seed: self.settings.seed,
            frame: self.frame,
            steps: 0,
            skip_steps: 0,
            restart: false,
            clear: true,
        };
        game.encode(&ctx.device, &ctx.queue, encoder, &args);
        self.clear = false;
        self.frames_since_clear = 0;
        self.splats_since_clear = 0;
        self.clears += 1;
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
        let due = self.estimate_due();
        let s = &self.settings;
        let (near, far) = self.view.map_or((0.0, 1.0), |v| (v.near, v.far));
        let ((pixel_size, perspective), pixel_area) = match &self.camera {
            Some(c) => (crate::resolve::pixel_footprint(c, self.height), crate::resolve::pixel_area(c, self.height)),
            None => ((1.0, false), 1.0),
        };
        let args = ResolveArgs {
            mode: s.mode,
            background: s.splat_background(),
            depth_cue: s.depth_cue,
            shading: s.shading,
            occlusion: s.occlusion,
            point_radius_px: s.point_radius_px,
            near,
            far,
            pixel_size,
            perspective,
            origin_px,
            // While the estimate waits for the accumulation to rest (a moving camera), the raw
            // counts are drawn without the spatial filter too: both read every pixel's
            // neighbourhood, the filter once per estimate (`GpuDensityEstimation::draw`).
            tone: if due == EstimateDue::Young { Tone { filter: None, ..s.tone } } else { s.tone },
            shadows: s.shadows,
            key_light: crate::resolve::shadow::key_light(s.light_yaw_deg, s.light_pitch_deg),
            shadow: self.view.and_then(|v| v.shadow),
            normal_radius_px: s.normal_radius_px,
            pixel_area,
            // Density mode only: the other modes' arguments (the light cache's) stay the same
            // from frame to frame. An estimate kept from an earlier frame is drawn on the scale
            // of the points it was made of (the current count would dim it until the next).
            points_drawn: match (s.mode, due, self.estimated) {
                (SplatMode::Density, EstimateDue::Keep, Some(made)) => made.splats,
                (SplatMode::Density, ..) => self.splats_since_clear,
                _ => 0,
            },
        };
        let estimated = matches!(due, EstimateDue::Keep | EstimateDue::Make(_));
        // Light rows only where the estimate is not drawn (their bands count towards the rest).
        let light = if estimated { LightRows::Inline } else { self.light_rows(&args) };
        let size = self.size();
        let made = if let EstimateDue::Make(de) = due { Some(self.made_estimate(de)) } else { None };
        match &mut self.engine {
            Engine::Gpu { game, estimation, .. } if estimated => {
                let estimation = estimation.get_or_insert_with(|| GpuDensityEstimation::new(&ctx.device));
                if let EstimateDue::Make(de) = due {
                    estimation.encode(ctx, encoder, &game.accum, size.0, size.1, &de);
                    self.estimated = made;
                }
                estimation.draw(ctx, encoder, &args, target, format);
            }
            Engine::Gpu { game, resolve, .. } => resolve.draw(ctx, encoder, game, &args, target, format, light),
            Engine::Picture(picture) => {
                if let EstimateDue::Make(de) = due {
                    // The CPU twin, from the accumulation as handed over.
                    let accum = picture.accum();
                    if accum.len() == 4 * size.0 as usize * size.1 as usize {
                        picture.set_estimate(density_estimation::estimate(
                            bytemuck::cast_slice(accum),
                            size.0,
                            size.1,
                            &de,
                        ));
                    }
                    self.estimated = made;
                }
                picture.draw(ctx, encoder, &args, size, estimated, light, target, format);
            }
        }
    }

    /// What the next draw does about density estimation (see the module's notes; `light_bands`
    /// 0, a snapshot's, makes a fresh estimate always).
    pub fn estimate_due(&self) -> EstimateDue {
        let s = &self.settings;
        let de = match density_estimation::applies(s.density_estimation.as_ref(), s.mode) {
            Some(de) => de,
            // The filter without density estimation, on the estimate's schedule (module notes).
            None if s.mode == SplatMode::Density && s.tone.filter.is_some() => density_estimation::SPREADS_NOTHING,
            None => return EstimateDue::Off,
        };
        let frames = self.frames_since_clear;
        let snapshot = self.light_bands == 0;
        match self.estimated {
            Some(MadeEstimate { clears, frames: at, de: made_with, .. })
                if clears == self.clears && made_with == de =>
            {
                let next = at.saturating_add(at.clamp(1, ESTIMATE_EVERY_FRAMES));
                if frames >= next || (frames != at && self.converged()) || snapshot {
                    EstimateDue::Make(de)
                } else {
                    EstimateDue::Keep
                }
            }
            _ if frames < ESTIMATE_FIRST_FRAMES && !self.converged() && !snapshot => EstimateDue::Young,
            _ => EstimateDue::Make(de),
        }
    }

    /// An estimate made with `de` from the accumulation as it is now.
    fn made_estimate(&self, de: DensityEstimation) -> MadeEstimate {
        MadeEstimate { clears: self.clears, frames: self.frames_since_clear, splats: self.splats_since_clear, de }
    }

    /// Takes `e`, made with `de` on the CPU from the accumulation as it is now (the live view's
    /// CPU route), as the estimate the next draws show.
    pub fn upload_estimate(&mut self, ctx: &GpuContext, e: Estimated, de: &DensityEstimation) {
        match &mut self.engine {
            Engine::Gpu { estimation, .. } => {
                estimation.get_or_insert_with(|| GpuDensityEstimation::new(&ctx.device)).upload(ctx, &e)
            }
            Engine::Picture(picture) => picture.set_estimate(e),
        }
        self.estimated = Some(self.made_estimate(*de));
    }

    /// Which rows of the light cache this draw refreshes (see [`Self::light_bands`]).
    fn light_rows(&mut self, args: &ResolveArgs) -> LightRows {
        if self.light_bands <= 1 {
            return LightRows::Inline;
        }
        let height = self.height;
        if self.frames_since_clear <= LIGHT_FULL_FRAMES {
            // Lit in the draw itself: the same pixels as a whole refresh in one pass instead of
            // two (a playing timeline or a dragged camera clears every frame and never reads
            // the cache back). The first banded draw after these frames refreshes it whole.
            self.light_args = None;
            self.bands_since_change = self.light_bands;
            return LightRows::Inline;
        }
        let same_args = self.light_args.is_some_and(|a| ResolveArgs { origin_px: a.origin_px, ..*args } == a);
        if !same_args {
            self.light_args = Some(*args);
            self.bands_since_change = self.light_bands;
            return LightRows::Refresh { start: 0, end: height };
        }
        let (band, bands) = (self.light_band % self.light_bands, self.light_bands);
        self.light_band = self.light_band.wrapping_add(1);
        self.bands_since_change = self.bands_since_change.saturating_add(1);
        LightRows::Refresh { start: band * height / bands, end: (band + 1) * height / bands }
    }

    /// Resolves into an offscreen texture of [`Self::size`] and reads it back.
    pub fn snapshot(&mut self, ctx: &GpuContext) -> Result<image::RgbImage, GpuError> {
        let (width, height) = self.size();
        let bands = std::mem::replace(&mut self.light_bands, 0);
        let image = super::readback::draw_offscreen(ctx, width, height, |encoder, target, format| {
            self.draw(ctx, encoder, target, format, [0, 0])
        });
        self.light_bands = bands;
        image
    }

    /// [`Self::snapshot`] up to the submission; the image comes when the copy maps (the
    /// browser awaits it).
    pub fn snapshot_start(&mut self, ctx: &GpuContext) -> super::readback::OffscreenCopy {
        let (width, height) = self.size();
        let bands = std::mem::replace(&mut self.light_bands, 0);
        let copy = super::readback::draw_offscreen_start(ctx, width, height, |encoder, target, format| {
            self.draw(ctx, encoder, target, format, [0, 0])
        });
        self.light_bands = bands;
        copy
    }

    /// Reads the accumulation buffer back (four u32 per pixel, as `Framebuffer` after a
    /// fashion: closest keys in slot 0, or r, g, b sums and the count). Tests and benchmarks.
    pub fn read_accum(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        match &self.engine {
            Engine::Gpu { game, .. } => {
                Ok(bytemuck::pod_collect_to_vec(&super::readback::read_buffer(ctx, &game.accum)?))
            }
            Engine::Picture(picture) => Ok(picture.accum().to_vec()),
        }
    }

    /// [`Self::read_accum`] that also works in the browser (awaits the map).
    pub async fn read_accum_async(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        match &self.engine {
            Engine::Gpu { game, .. } => {
                Ok(bytemuck::pod_collect_to_vec(&super::readback::read_buffer_async(ctx, &game.accum).await?))
            }
            Engine::Picture(picture) => Ok(picture.accum().to_vec()),
        }
    }
}
