//! The interactive viewer: a winit window showing the live GPU chaos game with egui panels.
//!
//! How a frame goes: window events go to egui first; what egui did not consume drives the
//! orbit camera as [`Command`]s. Once per frame the egui panels (`ui/`) emit more commands,
//! [`ViewerState::apply`] applies them all and reports what changed, the [`LiveView`] is told
//! (scene edits keep the points, view changes clear the accumulation), one chaos-game frame is
//! recorded, resolved onto the surface with the same `draw` that screenshots use, and egui is
//! drawn on top. A bad scene, a lost or outdated surface or a minimized window never panic: the
//! error is shown and the last good state kept.
//!
//! The event loop is the only place that reads a clock: while the timeline plays it sends
//! [`Command::Tick`] with the measured frame interval, and the scene edit that follows keeps the
//! points (accumulation cleared). A left press near a grid point (grid overlay on) starts a point
//! drag instead of an orbit. Ray-tracing and recording run on threads (`jobs.rs`).
//!
//! The files: `state.rs` (plain data), `command.rs` (what can change it), `apply.rs` (the
//! command logic, with `authoring.rs` for kinds, probabilities, builder steps and key times,
//! and `files.rs` for open, save and drops), `picking.rs` (projection, picking and drag maths on
//! a `SplatView`), the UI files that read the state and emit commands (the `ui/` folder: the side
//! panel in `ui/mod.rs`, a file a section or overlay, `ui/layer.rs` for egui on wgpu), `jobs.rs` with the forms' checks in
//! `job_plan.rs`, `recent.rs` (the recent files list, its state in `files_state.rs`) and
//! `dialogs.rs` (native dialogs on a thread of their own) and `redraw.rs` (when a frame is drawn: a
//! view at rest is not redrawn). State, command and apply import no
//! UI file.

pub mod actions;
pub mod apply;
mod authoring;
pub mod clock;
pub mod command;
// The browser's Open and Save As are the page's file input and downloads (`platform/`).
#[cfg_attr(target_arch = "wasm32", path = "dialogs_web.rs")]
pub mod dialogs;
pub mod files;
pub mod files_state;
mod frame_log;
pub mod framing;
pub mod host;
pub mod imaging;
mod input;
pub mod job_plan;
pub mod jobs;
pub mod lens;
mod palette_edit;
pub mod picking;
pub mod pointer;
pub mod recent;
pub mod recovery;
mod redraw;
mod screenshot;
mod start;
pub mod state;
pub mod ui;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use crate::platform::Instant;

use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::gpu::{GpuContext, GpuError};
use crate::live::{LiveSettings, LiveView};
use start::Starting;

use clock::{Clock, PlaybackClock, WallClock};
use frame_log::FrameLog;
use input::{pointer_button, pointer_context};
use pointer::{PointerEvent, PointerRouter, Route};
use redraw::Redraw;

pub use command::Command;
use command::NestingView;
pub use state::ViewerState;

#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("cannot start the window system: {0}")]
    EventLoop(#[from] winit::error::EventLoopError),
    #[error("cannot open a window: {0}")]
    Window(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// How the viewer starts.
#[derive(Clone, Debug, Default)]
pub struct ViewerOptions {
    /// Scene file (None: the built-in default scene).
    pub scene: Option<PathBuf>,
    pub live: LiveSettings,
    /// Testing: close after this many seconds and print frame statistics.
    pub exit_after_secs: Option<f64>,
    /// Testing: save the attractor (offscreen, same draw) to this PNG before closing.
    pub screenshot: Option<PathBuf>,
    /// Start with the grid overlay shown.
    pub grid_overlay: bool,
    /// Start with the nesting view at this level.
    pub nesting_level: Option<u32>,
    /// Start playing the timeline (if the scene has one).
    pub play: bool,
    /// Print frames per second, process CPU per frame and the wall time of each stage of a
    /// frame to stderr, once a second (measuring the viewer under Xvfb).
    pub log_fps: bool,
    /// Shared with the page that embeds the viewer (the browser build): its commands are
    /// applied before the first frame and then once per frame.
    pub host: host::Host,
    /// The graphics APIs to try (None: all, or the environment's `WGPU_BACKEND`); the page's
    /// `?backend=webgl2` asks for WebGL2 alone.
    pub backends: Option<wgpu::Backends>,
}

/// Opens the viewer and runs until the window closes.
pub fn run(options: ViewerOptions) -> Result<(), ViewerError> {
    let mut state = ViewerState::new(ViewerState::default_scene(), None, options.live);
    state.apply([
        Command::SetConfigDir(recent::config_dir()),
        Command::SetToolSupport {
            native_dialogs: dialogs::native_dialogs_available(),
            ffmpeg: crate::record::ffmpeg_available(),
        },
    ]);
    if let Some(path) = &options.scene {
        state.apply([Command::OpenScene(path.clone())]);
        // A bad scene leaves the default one on screen with the error in the panel.
    }
    state.apply([
        Command::SetGridOverlay(options.grid_overlay),
        Command::SetNestingView(NestingView {
            shown: options.nesting_level.is_some(),
            level: options.nesting_level.unwrap_or(1),
            translucent: false,
        }),
        Command::SetPlaying(options.play),
        Command::SetRecoveryDir(recovery::recovery_dir()),
    ]);
    state.apply(options.host.with(|h| std::mem::take(&mut h.inbox)));
    let event_loop = EventLoop::new()?;
    let app = App {
        state,
        options,
        gfx: None,
        starting: None,
        screenshot: None,
        commands: Vec::with_capacity(64),
        drag: None,
        drag_start_camera: crate::camera::OrbitCamera::framing((glam::DVec3::ZERO, glam::DVec3::ONE), 3),
        point_drag: None,
        router: PointerRouter::default(),
        modifiers: Default::default(),
        jobs: jobs::Jobs::default(),
        dialogs: dialogs::Dialogs::default(),
        clock: WallClock::default(),
        playback_clock: PlaybackClock::default(),
        last_autosave_secs: 0.0,
        toast_shown: None,
        title: String::new(),
        cursor: None,
        last_frame: None,
        last_poll: Instant::now(),
        egui_repaint_at: None,
        started: Instant::now(),
        frames: 0,
        splats: 0,
        smoothed: state::FrameStats::default(),
        stats_shown: None,
        log: FrameLog::default(),
        fatal: None,
    };
    // In the browser the page runs the loop and this returns at once, with no app to report on.
    let Some(app) = crate::platform::run_app(event_loop, app)? else { return Ok(()) };
    if app.options.exit_after_secs.is_some() {
        let secs = app.started.elapsed().as_secs_f64();
        eprintln!(
            "viewer: {} frames in {:.2} s ({:.1} fps), {:.1} M points/s, {} points × {} steps per frame, chaos game on the {}",
            app.frames,
            secs,
            app.frames as f64 / secs,
            app.splats as f64 / secs / 1e6,
            app.state.live.draw.point_count,
            app.state.live.draw.steps_per_frame,
            app.smoothed.chaos_route.name()
        );
    }
    app.fatal.map_or(Ok(()), Err)
}

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    live: LiveView,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    ui_layer: ui::layer::UiLayer,
}

struct App {
    state: ViewerState,
    options: ViewerOptions,
    gfx: Option<Gfx>,
    starting: Option<Starting>,
    screenshot: Option<screenshot::PendingShot>,
    commands: Vec<Command>,
    /// The camera drag (orbit, pan) in progress and the camera at its press (Esc restores it).
    drag: Option<MouseButton>,
    drag_start_camera: crate::camera::OrbitCamera,
    /// Cursor position at the press of a grid point drag.
    point_drag: Option<(f64, f64)>,
    /// Who gets pointer input, the camera or the panels.
    router: PointerRouter,
    modifiers: winit::keyboard::ModifiersState,
    jobs: jobs::Jobs,
    dialogs: dialogs::Dialogs,
    clock: WallClock,
    playback_clock: PlaybackClock,
    last_autosave_secs: f64,
    /// The toast on screen and since when (clock seconds).
    toast_shown: Option<(String, f64)>,
    /// The window's title as last set.
    title: String,
    cursor: Option<(f64, f64)>,
    last_frame: Option<Instant>,
    last_poll: Instant,
    /// When egui asked for its next frame.
    egui_repaint_at: Option<Instant>,
    started: Instant,
    frames: u64,
    splats: u64,
    /// Frame statistics smoothed every frame; the panel shows a copy refreshed twice a second
    /// (text that changes every frame would re-render the cached egui layer every frame).
    smoothed: state::FrameStats,
    stats_shown: Option<Instant>,
    log: FrameLog,
    fatal: Option<ViewerError>,
}

impl Gfx {
    /// The window's drawing state once its GPU context is there.
    fn new(
        window: Arc<Window>,
        ctx: GpuContext,
        surface: wgpu::Surface<'static>,
        state: &ViewerState,
    ) -> Result<Self, ViewerError> {
        let size = window.inner_size();
        let (width, height) = (size.width.max(1), size.height.max(1));
        let mut config = surface
            .get_default_config(&ctx.adapter, width, height)
            .ok_or_else(|| ViewerError::Window("the surface is not supported by the adapter".into()))?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // A unorm target: the resolve pass encodes sRGB itself (the CPU's exact maths) and egui
        // prefers it.
        if let Some(f) = caps.formats.iter().find(|f| !f.is_srgb()) {
            config.format = *f;
        }
        config.desired_maximum_frame_latency = 2;
        // On a software adapter, waiting for vsync in the present costs about half the frame
        // rate (measured under Xvfb on lavapipe): present immediately there.
        if ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
            config.present_mode = wgpu::PresentMode::AutoNoVsync;
        }
        surface.configure(&ctx.device, &config);
        let mut live = LiveView::new(&ctx, state.live, width, height)?;
        // A costly scene on the CPU route still moves: its frames are cut to a time.
        live.bound_frame_time(true);
        if let Some(c) = &state.compiled {
            live.set_ifs(&ctx, c, state.bounds, true);
        }
        live.set_camera(&state.camera);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, config.format, egui_wgpu::RendererOptions::default());
        let ui_layer = ui::layer::UiLayer::new(&ctx.device, config.format);
        Ok(Self { window, surface, config, ctx, live, egui_ctx, egui_state, egui_renderer, ui_layer })
    }

    fn reconfigure(&mut self) {
        if self.config.width > 0 && self.config.height > 0 {
            self.surface.configure(&self.ctx.device, &self.config);
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() || self.starting.is_some() {
            return;
        }
        match Gfx::start(event_loop, &self.state, self.options.backends) {
            Ok(starting) => self.starting = Some(starting),
            Err(e) => self.fail(event_loop, e),
        }
        self.finish_start(event_loop);
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        self.finish_start(event_loop);
        let Some(gfx) = &mut self.gfx else { return };
        let text_focus = gfx.egui_ctx.egui_wants_keyboard_input();
        // Tab hides the panel rather than moving egui's keyboard focus (unless a text field
        // has it): egui does not see it.
        let tab = matches!(&event, WindowEvent::KeyboardInput { event: k, .. }
            if k.logical_key == Key::Named(NamedKey::Tab));
        if !tab || text_focus {
            let response = gfx.egui_state.on_window_event(&gfx.window, &event);
            // egui asks for a repaint on RedrawRequested too: that event is the repaint (asking
            // again redrew an untouched window forever).
            if response.repaint && !matches!(event, WindowEvent::RedrawRequested) {
                gfx.window.request_redraw();
            }
        }
        match event {
            WindowEvent::CloseRequested => {
                self.commands.push(Command::RequestClose);
                gfx.window.request_redraw();
            }
            WindowEvent::Resized(size) => {
                gfx.config.width = size.width;
                gfx.config.height = size.height;
                if size.width > 0 && size.height > 0 {
                    // The view (and the live view's size) follows in the next frame, from the
                    // rectangle the panels leave.
                    gfx.reconfigure();
                    gfx.window.request_redraw();
                }
            }
            WindowEvent::RedrawRequested => self.frame(),
            WindowEvent::DroppedFile(path) => {
                self.commands.push(Command::OpenFile(path));
                gfx.window.request_redraw();
            }
            WindowEvent::Focused(false) => {
                // Releases may never come while another window has the pointer.
                self.router.reset();
                self.drag = None;
                if self.point_drag.take().is_some() {
                    self.commands.push(Command::EndGesture);
                }
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseInput { state: pressed, button, .. } => {
                let b = pointer_button(button);
                let event =
                    if pressed == ElementState::Pressed { PointerEvent::Press(b) } else { PointerEvent::Release(b) };
                let ctx = pointer_context(&self.state, &gfx.egui_ctx, self.cursor);
                if self.router.route(event, &ctx) == Route::Camera {
                    let ctrl = self.modifiers.control_key() && pressed == ElementState::Pressed;
                    if let Some(c) = ui::lens::focus_click(&self.state, &gfx.live, &gfx.ctx, button, ctrl, self.cursor)
                    {
                        self.commands.push(c);
                    } else if pressed == ElementState::Pressed {
                        let picked = (button == MouseButton::Left)
                            .then_some(self.cursor)
                            .flatten()
                            .and_then(|(x, y)| self.state.pick_point([x as f32, y as f32]));
                        match picked {
                            Some((function, point)) => {
                                self.commands.push(Command::BeginPointDrag { function, point });
                                self.point_drag = self.cursor;
                            }
                            None if self.drag.is_none() => {
                                self.drag = Some(button);
                                self.drag_start_camera = self.state.camera;
                            }
                            None => {}
                        }
                    } else if button == MouseButton::Left && self.point_drag.is_some() {
                        self.point_drag = None;
                        self.commands.push(Command::EndGesture);
                    } else if self.drag == Some(button) {
                        self.drag = None;
                    }
                }
                gfx.window.request_redraw();
            }
            WindowEvent::CursorMoved { position, .. } => {
                let ctx = pointer_context(&self.state, &gfx.egui_ctx, Some((position.x, position.y)));
                if self.router.route(PointerEvent::Move, &ctx) == Route::Camera {
                    if let Some((x0, y0)) = self.point_drag {
                        self.commands.push(Command::DragPoint {
                            delta_px: [(position.x - x0) as f32, (position.y - y0) as f32],
                        });
                        gfx.window.request_redraw();
                    } else if let (Some(button), Some((x, y))) = (self.drag, self.cursor) {
                        let (dx_px, dy_px) = ((position.x - x) as f32, (position.y - y) as f32);
                        self.commands.push(self.state.camera_drag(pointer_button(button), dx_px, dy_px));
                        gfx.window.request_redraw();
                    }
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                let ctx = pointer_context(&self.state, &gfx.egui_ctx, self.cursor);
                if self.router.route(PointerEvent::Wheel(steps), &ctx) == Route::Camera
                    && let Some((x, y)) = self.cursor
                {
                    self.commands.push(Command::ZoomAt { steps, cursor_px: [x as f32, y as f32] });
                    gfx.window.request_redraw();
                }
            }
            WindowEvent::KeyboardInput { event, .. } if !text_focus && event.state == ElementState::Pressed => {
                self.key(&event);
                if let Some(gfx) = &self.gfx {
                    gfx.window.request_redraw();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(limit) = self.options.exit_after_secs
            && self.started.elapsed().as_secs_f64() >= limit
        {
            if let (Some(path), Some(gfx)) = (&self.options.screenshot, &mut self.gfx) {
                match gfx.live.snapshot(&gfx.ctx) {
                    Ok(image) => {
                        if let Err(e) = screenshot::save_screenshot(&self.state, path, &image) {
                            eprintln!("{e}");
                        }
                    }
                    Err(e) => eprintln!("screenshot failed: {e}"),
                }
            }
            event_loop.exit();
            return;
        }
        if self.state.ui.quit {
            event_loop.exit();
            return;
        }
        self.wake();
        let Some(gfx) = &self.gfx else { return };
        let now = Instant::now();
        match self.redraw(gfx, now) {
            Redraw::Continuous => {
                event_loop.set_control_flow(ControlFlow::Poll);
                gfx.window.request_redraw();
            }
            Redraw::At(at) if at <= now => {
                gfx.window.request_redraw();
                event_loop.set_control_flow(ControlFlow::Wait);
            }
            Redraw::At(at) => event_loop.set_control_flow(ControlFlow::WaitUntil(at.min(self.next_wake(now)))),
            Redraw::OnEvent => event_loop.set_control_flow(ControlFlow::WaitUntil(self.next_wake(now))),
        }
    }
}

impl App {
    fn frame(&mut self) {
        self.commands.extend(self.options.host.with(|h| std::mem::take(&mut h.inbox)));
        let Some(gfx) = &mut self.gfx else { return };
        let t_start = Instant::now();
        // Playback: scene time advances by the wall-clock interval since the last frame
        // (`clock.rs`).
        let now_secs = self.clock.now_secs();
        if let Some(dt_secs) = self.playback_clock.advance(now_secs, self.state.playback.playing) {
            self.commands.push(Command::Tick { dt_secs });
        }
        // A toast shows for a few seconds from when it (or another text) appeared.
        match (&self.state.ui.toast, &self.toast_shown) {
            (Some(t), Some((shown, since))) if t == shown => {
                if now_secs - since > TOAST_SECS {
                    self.commands.push(Command::SetToast(None));
                }
            }
            (Some(t), _) => self.toast_shown = Some((t.clone(), now_secs)),
            (None, _) => self.toast_shown = None,
        }
        self.jobs.poll(&gfx.egui_ctx);
        for notice in self.jobs.take_notices() {
            self.commands.push(Command::SetToast(Some(notice)));
        }
        let raw_input = gfx.egui_state.take_egui_input(&gfx.window);
        // While the timeline plays untouched the side panel's animated values may lag the
        // playhead by a few frames (`ui/layer.rs`); any input shows them at once.
        let panels_lag_secs =
            (self.state.playback.playing && raw_input.events.is_empty()).then_some(PLAYING_PANELS_LAG_SECS);
        let state = &self.state;
        let commands = &mut self.commands;
        let job_view = &self.jobs.view;
        let ppp = gfx.egui_ctx.pixels_per_point();
        let mut layout = ui::PanelLayout { view: egui::Rect::NOTHING, timeline: None };
        let full_output =
            gfx.egui_ctx.run_ui(raw_input, |ui| layout = ui::panels_ui(ui, state, job_view, ppp, commands));
        let view_rect = layout.view;
        gfx.egui_state.handle_platform_output(&gfx.window, full_output.platform_output);
        // When egui wants its next frame (an animation, a tooltip's delay); none: Duration::MAX.
        self.egui_repaint_at = full_output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .and_then(|v| Instant::now().checked_add(v.repaint_delay));
        // The attractor is drawn and framed in what the panels leave, in whole window pixels.
        let (origin_px, size_px) = ui::view_pixels(view_rect, ppp, [gfx.config.width, gfx.config.height]);
        let minimized = gfx.config.width == 0 || gfx.config.height == 0;
        if !minimized {
            self.commands.push(Command::SetViewRect {
                origin_px: origin_px.map(|v| v as f32),
                size_px: size_px.map(|v| v as f32),
            });
        }

        let mut changes = self.state.apply(self.commands.drain(..));
        for request in changes.jobs.drain(..) {
            self.jobs.handle(request);
        }
        if let Some(request) = changes.file_dialog.take() {
            let kind = request.kind;
            if let Err(e) = self.dialogs.start(request, &gfx.window) {
                self.state.apply([Command::FileDialogDone { kind, path: None }]);
                self.state.error = Some(e);
            }
        }
        if (changes.scene_replaced || changes.scene_edited)
            && let Some(c) = &self.state.compiled
        {
            gfx.live.set_ifs(&gfx.ctx, c, self.state.bounds, changes.scene_replaced);
        }
        let title = self.state.window_title();
        if title != self.title {
            gfx.window.set_title(&title);
            self.title = title;
        }
        if changes.live_settings
            && let Err(e) = gfx.live.set_settings(&gfx.ctx, self.state.live)
        {
            self.state.error = Some(e.to_string());
            self.state.live = *gfx.live.settings();
        }
        if !minimized && gfx.live.size() != (size_px[0], size_px[1]) {
            gfx.live.resize(&gfx.ctx, size_px[0], size_px[1]);
        }
        // Playing, as dragging, draws without shadows and occlusion (back when it stops).
        if let Err(e) = gfx.live.set_navigating(&gfx.ctx, self.drag.is_some() || self.state.playback.playing) {
            self.state.error = Some(e.to_string());
        }
        gfx.live.set_camera(&self.state.camera);
        if let Some(path) = changes.screenshot {
            self.screenshot = Some(screenshot::start(gfx, path));
        }
        screenshot::finish(&mut self.state, &mut self.screenshot);

        // Textures must be applied every frame even when nothing is drawn.
        let textures_changed =
            !full_output.textures_delta.set.is_empty() || !full_output.textures_delta.free.is_empty();
        for (id, deltas) in &full_output.textures_delta.set {
            for delta in deltas {
                gfx.egui_renderer.update_texture(&gfx.ctx.device, &gfx.ctx.queue, *id, delta);
            }
        }
        let free = |gfx: &mut Gfx| {
            for id in &full_output.textures_delta.free {
                gfx.egui_renderer.free_texture(id);
            }
        };
        if gfx.config.width == 0 || gfx.config.height == 0 {
            free(gfx);
            return;
        }
        let t_ui = Instant::now();
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => Some((t, false)),
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some((t, true)),
            wgpu::CurrentSurfaceTexture::Timeout
            | wgpu::CurrentSurfaceTexture::Occluded
            | wgpu::CurrentSurfaceTexture::Validation => None,
            wgpu::CurrentSurfaceTexture::Outdated => {
                gfx.reconfigure();
                None
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                match gfx.ctx.instance.create_surface(gfx.window.clone()) {
                    Ok(surface) => {
                        gfx.surface = surface;
                        gfx.reconfigure();
                    }
                    Err(e) => self.state.error = Some(format!("lost the window surface: {e}")),
                }
                None
            }
        };
        let Some((frame, suboptimal)) = frame else {
            free(gfx);
            gfx.window.request_redraw();
            return;
        };
        let t_acquired = Instant::now();
        let view = frame.texture.create_view(&Default::default());
        let mut encoder =
            gfx.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        let splats = gfx.live.advance(&gfx.ctx, &mut encoder);
        gfx.live.draw(&gfx.ctx, &mut encoder, &view, gfx.config.format, origin_px);

        let ui_stale = gfx.ui_layer.update(
            &gfx.ctx.device,
            &gfx.ctx.queue,
            &mut gfx.egui_renderer,
            &gfx.egui_ctx,
            ui::layer::EguiFrame {
                shapes: full_output.shapes,
                pixels_per_point: full_output.pixels_per_point,
                textures_changed,
                strip: layout.timeline,
                now_secs,
                panels_lag_secs,
            },
            [gfx.config.width, gfx.config.height],
        );
        gfx.ui_layer.composite(&mut encoder, &view);
        gfx.ctx.queue.submit([encoder.finish()]);
        let t_submitted = Instant::now();
        gfx.ctx.queue.present(frame);
        free(gfx);
        if ui_stale {
            gfx.window.request_redraw();
        }
        if suboptimal {
            gfx.reconfigure();
        }
        if self.options.log_fps {
            let log = &mut self.log;
            log.frames += 1;
            log.ui_renders = gfx.ui_layer.renders;
            log.splats += splats;
            log.route = gfx.live.route();
            log.ui_secs += (t_ui - t_start).as_secs_f64();
            log.acquire_secs += (t_acquired - t_ui).as_secs_f64();
            log.record_secs += (t_submitted - t_acquired).as_secs_f64();
            log.present_secs += t_submitted.elapsed().as_secs_f64();
            log.report(Instant::now());
        }

        let now = Instant::now();
        if let Some(last) = self.last_frame {
            let dt = (now - last).as_secs_f64();
            let s = &mut self.smoothed;
            // Exponential smoothing over ~20 frames.
            let a = if s.frames == 0 { 1.0 } else { 0.05 };
            s.frame_secs += a * (dt - s.frame_secs);
            s.points_per_sec += a * (splats as f64 / dt.max(1e-6) - s.points_per_sec);
            s.frames += 1;
            s.chaos_route = gfx.live.route();
            if self.stats_shown.is_none_or(|t| now - t >= Duration::from_millis(500)) {
                s.accumulated = gfx.live.splats_since_clear();
                s.lit_pixels = gfx.live.lit_pixels().unwrap_or(0);
                self.state.stats = self.smoothed;
                self.stats_shown = Some(now);
            }
        }
        self.last_frame = Some(now);
        self.frames += 1;
        self.splats += splats;
        self.report_to_host();
    }
}

/// Seconds a toast stays on screen.
const TOAST_SECS: f64 = 4.0;

/// How long the side panel may lag the playhead while playing (its re-render is costly: ui/layer.rs).
const PLAYING_PANELS_LAG_SECS: f64 = 0.25;
