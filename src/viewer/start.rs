//! How the viewer's window gets its GPU context, and what a page embedding the viewer hears of
//! it. The window opens at once; the instance (the browser's WebGPU where it has an adapter),
//! surface, adapter and device are futures, which `platform::run_async` finishes before
//! returning on the desktop and hands to the page's event loop in the browser. The event loop
//! then makes the drawing state ([`Gfx`]) at the first event after they arrive
//! ([`App::finish_start`]); a failure ends the viewer with the reason, said to the page too.

use std::sync::Arc;

use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use super::{App, Gfx, ViewerError, ViewerState};
use crate::gpu::GpuContext;
use crate::platform::Pending;

/// The window, and its GPU context on the way (at once on the desktop; in the browser once the
/// page's promises for the adapter and the device have settled).
pub(super) struct Starting {
    pub(super) window: Arc<Window>,
    pub(super) pending: Pending<Result<(GpuContext, wgpu::Surface<'static>), ViewerError>>,
}

impl Gfx {
    /// Opens the window and asks for a GPU context that can draw into it: an instance with the
    /// browser's WebGPU where it has an adapter (WebGL2 otherwise), its surface, adapter and
    /// device; `backends`, when given, are the only APIs tried.
    pub(super) fn start(
        event_loop: &ActiveEventLoop,
        state: &ViewerState,
        backends: Option<wgpu::Backends>,
    ) -> Result<Starting, ViewerError> {
        let attributes = crate::platform::window_attributes(
            Window::default_attributes()
                .with_title(state.window_title())
                .with_inner_size(winit::dpi::PhysicalSize::new(1280u32, 720u32)),
        );
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| ViewerError::Window(e.to_string()))?);
        let mut descriptor =
            wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(event_loop.owned_display_handle()));
        if let Some(backends) = backends {
            descriptor.backends = backends;
        }
        let target = window.clone();
        let request = async move {
            if descriptor.backends.contains(wgpu::Backends::BROWSER_WEBGPU)
                && !wgpu::util::is_browser_webgpu_supported().await
            {
                descriptor.backends.remove(wgpu::Backends::BROWSER_WEBGPU);
            }
            if !descriptor.backends.contains(wgpu::Backends::BROWSER_WEBGPU) {
                crate::platform::keep_webgl2_pixels(&target);
            }
            let instance = wgpu::Instance::new(descriptor);
            let surface = instance.create_surface(target).map_err(|e| ViewerError::Window(e.to_string()))?;
            let ctx = GpuContext::request(instance, Some(&surface)).await?;
            Ok((ctx, surface))
        };
        let woken = window.clone();
        let pending = crate::platform::run_async(request, move || woken.request_redraw());
        Ok(Starting { window, pending })
    }
}

impl App {
    /// Makes the window's drawing state once its GPU context has arrived.
    pub(super) fn finish_start(&mut self, event_loop: &ActiveEventLoop) {
        let Some(result) = self.starting.as_ref().and_then(|s| s.pending.take()) else { return };
        let Some(Starting { window, .. }) = self.starting.take() else { return };
        // Without compute shaders (a browser's WebGL2) the live view runs the chaos game and
        // the resolve on the CPU (`live::LiveView`).
        let drawing = result.and_then(|(ctx, surface)| Gfx::new(window, ctx, surface, &self.state));
        match drawing {
            Ok(gfx) => {
                gfx.window.request_redraw();
                self.options.host.with(|h| {
                    h.started = true;
                    h.adapter = gfx.ctx.describe();
                });
                self.gfx = Some(gfx);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    /// The viewer cannot go on: said to the page, kept for `run`'s caller, and the loop ends.
    pub(super) fn fail(&mut self, event_loop: &ActiveEventLoop, e: ViewerError) {
        self.options.host.with(|h| h.fatal = Some(e.to_string()));
        self.fatal = Some(e);
        event_loop.exit();
    }

    /// Tells the page what the viewer shows (once per frame).
    pub(super) fn report_to_host(&self) {
        let (state, gfx) = (&self.state, &self.gfx);
        self.options.host.with(|h| {
            h.error = state.files.view_error.clone().or_else(|| state.error.clone());
            h.message.clone_from(&state.message);
            h.scene_name.clone_from(&state.scene.name);
            h.frames = self.frames;
            h.can_undo = state.history.can_undo();
            h.modified = state.modified();
            if let Some(gfx) = gfx {
                h.route = gfx.live.route().name().to_string();
            }
        });
    }
}
