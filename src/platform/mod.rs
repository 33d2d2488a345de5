//! What differs between the desktop and the browser (`wasm32-unknown-unknown`), in one place, so
//! that the rest of the program reads the same on both.
//!
//! - **Clock**: [`Instant`] is `std::time::Instant` itself on the desktop (the `web-time` crate
//!   re-exports it, so native builds keep their code) and `performance.now()` in the browser,
//!   where std's clock panics.
//! - **Desktop tools**: threads, files, child processes (ffmpeg, a file manager) and native
//!   dialogs exist on the desktop only; [`DESKTOP`] says which build this is, and the viewer
//!   offers the ray-trace and recording jobs, file paths and the file watcher only there. In the
//!   browser std answers such calls with an error ("unsupported"), never a panic, except
//!   `std::process::id`, which nothing on the browser's paths calls.
//! - **Threads for the CPU route**: rayon runs on the calling thread where threads cannot be
//!   spawned (rayon-core's fallback), so the CPU chaos game, splat and resolve run unchanged,
//!   single-threaded, in the page.
//! - **CPU features**: `simd.rs` detects AVX2 / AVX-512F on x86-64 only; other targets take the
//!   portable lane kernels.
//! - **Files**: in the browser `io::write_atomic`, through which every file is written, offers
//!   the bytes as a download instead (`web.rs`); files are opened from their bytes (a file
//!   input, a drop), never by path.
//! - **The window**: in the browser the viewer draws into the page's canvas ([`window_attributes`]),
//!   whose WebGL2 context, where WebGPU is missing, keeps its pixels between frames
//!   ([`keep_webgl2_pixels`]).
//! - **Waiting for the GPU**: adapter and device requests are futures; [`run_async`] blocks on
//!   them on the desktop and hands them to the page's event loop in the browser, where blocking
//!   would never let them finish.
//! - **Memory pages**: a zeroed buffer's pages are mapped on first touch; buffers that several
//!   threads update at random have every page written first ([`write_every_page`]); the flame
//!   renderer's large buffers ask Linux for huge pages as well ([`zeroed_pages`]).

#[cfg(target_arch = "wasm32")]
pub mod web;

use std::cell::RefCell;
use std::future::Future;
use std::rc::Rc;

pub use web_time::Instant;

/// Writes `zero` (the value a zeroed allocation already holds) into every 4 KiB page of
/// `values`, for buffers that several threads will read and update at random. A page that is
/// read before anything wrote it maps the kernel's shared zero page, and its first write then
/// replaces that mapping (copy on write), which, while the process runs on several cores,
/// flushes the other cores' TLBs by interrupt: in a two-thread 1920×1080 average render of
/// tapering, 0.12–0.15 s of system time in 1.5 s. Written first, each page is faulted in once,
/// without the flush.
pub fn write_every_page<T: Copy>(values: &mut [T], zero: T) {
    let per_page = (4096 / std::mem::size_of::<T>().max(1)).max(1);
    for i in (0..values.len()).step_by(per_page) {
        // Through black_box, so that a store of zero into a zeroed allocation stays.
        values[i] = std::hint::black_box(zero);
    }
}

/// `len` zeroed values in a new vector whose pages Linux may map 2 MiB at a time (transparent
/// huge pages, asked by `madvise` before the first write; where the system's setting is
/// `never`, or elsewhere, the usual 4 KiB pages), all its pages then mapped in one call
/// (`MADV_POPULATE_WRITE`, Linux 5.14 on; where refused, each page written once by
/// [`write_every_page`]): the chaos game's random adds do not stop for page faults. The memory
/// comes zeroed from the allocator (fresh pages are not written twice). The flame renderer's
/// buffers (tens of MB) paid about a quarter of a small render's time in 4 KiB page faults, and
/// one call maps them for half the faults of a write a page.
pub fn zeroed_pages<T: bytemuck::Zeroable + Copy>(len: usize) -> Vec<T> {
    let Ok(layout) = std::alloc::Layout::array::<T>(len) else { panic!("{len} values do not fit in memory") };
    if layout.size() == 0 {
        return std::iter::repeat_with(T::zeroed).take(len).collect();
    }
    #[expect(unsafe_code, reason = "a zeroed allocation made a vector")]
    // SAFETY: `layout` has a non-zero size; all-zero bytes are a valid `T` (`Zeroable`); the
    // vector takes the allocation with the layout it was made with (`len` values of `T`).
    let mut values = unsafe {
        let ptr = std::alloc::alloc_zeroed(layout).cast::<T>();
        if ptr.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        Vec::from_raw_parts(ptr, len, len)
    };
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let first = values.as_mut_ptr() as usize;
        let start = first / PAGE * PAGE;
        let length = (first + layout.size()).next_multiple_of(PAGE) - start;
        #[expect(unsafe_code, reason = "advice on the pages of an allocation this function owns")]
        // SAFETY: the range is `values`' allocation, rounded out to whole pages (the allocator's
        // header, or a neighbouring allocation, may share the first and last). MADV_HUGEPAGE
        // changes how pages are mapped and MADV_POPULATE_WRITE maps them all now as a write
        // fault would; neither changes what they hold. A refusal (an old kernel, the setting
        // `never`) leaves the usual pages, written below one by one.
        let populated = unsafe {
            if layout.size() >= 2 << 20 {
                libc::madvise(start as *mut libc::c_void, length, libc::MADV_HUGEPAGE);
            }
            libc::madvise(start as *mut libc::c_void, length, libc::MADV_POPULATE_WRITE) == 0
        };
        if populated {
            return values;
        }
    }
    write_every_page(&mut values, T::zeroed());
    values
}

/// True on the desktop, false in the browser: background jobs (threads), files by path,
/// child processes and native dialogs are available.
pub const DESKTOP: bool = cfg!(not(target_arch = "wasm32"));

/// What to try when no GPU adapter is found: Mesa's software Vulkan on the desktop; nothing to
/// add in the browser, whose page says what it needs.
pub const NO_ADAPTER_HINT: &str = if DESKTOP { " (set WGPU_BACKEND=vulkan for Mesa's lavapipe)" } else { "" };

/// The result of [`run_async`], once its future has finished.
pub struct Pending<T>(Rc<RefCell<Option<T>>>);

impl<T> Pending<T> {
    /// The result, the first time it is asked for after the future finished; None before.
    pub fn take(&self) -> Option<T> {
        self.0.borrow_mut().take()
    }
}

/// Runs `future`: to completion before returning on the desktop; on the page's event loop in the
/// browser (the result appears in the [`Pending`] later; call `wake` there to be told).
pub fn run_async<T: 'static>(future: impl Future<Output = T> + 'static, wake: impl FnOnce() + 'static) -> Pending<T> {
    let slot = Rc::new(RefCell::new(None));
    let filled = slot.clone();
    let finish = async move {
        let value = future.await;
        *filled.borrow_mut() = Some(value);
        wake();
    };
    #[cfg(not(target_arch = "wasm32"))]
    pollster::block_on(finish);
    #[cfg(target_arch = "wasm32")]
    wasm_bindgen_futures::spawn_local(finish);
    Pending(slot)
}

/// The viewer window's attributes for this platform: in the browser, the page's canvas
/// `#nlifs` (made and appended to the page's body if the page has none).
pub fn window_attributes(attributes: winit::window::WindowAttributes) -> winit::window::WindowAttributes {
    #[cfg(target_arch = "wasm32")]
    return web::canvas_attributes(attributes);
    #[cfg(not(target_arch = "wasm32"))]
    attributes
}

/// Before a WebGL2 surface is made for `window`: in the browser, its canvas keeps the last
/// frame's pixels for read-backs between frames (`web::keep_webgl2_pixels`); nothing on the
/// desktop.
pub fn keep_webgl2_pixels(window: &winit::window::Window) {
    #[cfg(target_arch = "wasm32")]
    web::keep_webgl2_pixels(window);
    #[cfg(not(target_arch = "wasm32"))]
    let _ = window;
}

/// Runs `app` on `event_loop`: until it exits on the desktop (the app is given back); in the
/// browser the loop is handed to the page, this returns at once, and the app is not given back.
pub fn run_app<A: winit::application::ApplicationHandler + 'static>(
    event_loop: winit::event_loop::EventLoop<()>,
    app: A,
) -> Result<Option<A>, winit::error::EventLoopError> {
    #[cfg(target_arch = "wasm32")]
    {
        use winit::platform::web::EventLoopExtWebSys;
        event_loop.spawn_app(app);
        Ok(None)
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        let mut app = app;
        event_loop.run_app(&mut app)?;
        Ok(Some(app))
    }
}
