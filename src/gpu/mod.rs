//! The GPU side of nlifs (wgpu): the device context, the WGSL sources, the compute chaos game
//! with its splat, the resolve pass, the progressive render that keeps both running across
//! frames, readback and offscreen targets, and a headless renderer. The live view on top of this
//! (`crate::live`) adds the CPU point source and the viewer's settings; nothing here imports it. Every stage has a CPU twin with
//! the same stem (`chaos_game`, `splat`/`resolve`), and `tests/gpu_vs_cpu.rs` compares them.
//!
//! Without an adapter everything here returns [`GpuError::NoAdapter`]; callers fall back to the
//! CPU path (`render --backend auto`) or report it.

pub mod batch;
pub mod bench;
pub mod chaos_game;
pub mod density_estimation;
pub mod picture;
pub mod progressive;
pub mod readback;
pub mod render;
pub mod resolve;
pub mod shaders;
pub mod shadow;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("no GPU adapter available{}", crate::platform::NO_ADAPTER_HINT)]
    NoAdapter,
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    #[error("the GPU could not read back the image: {0}")]
    Readback(String),
    #[error("{0} points do not fit in one GPU buffer on this device")]
    TooManyPoints(u64),
    #[error("the scene has no enabled function")]
    NoFunctions,
    #[error(
        "a {width}×{height} image needs a {bytes}-byte accumulation buffer on the GPU, more than the {limit} bytes {adapter} can bind; render it on the CPU (--backend cpu) or smaller"
    )]
    FramebufferTooLarge { width: u32, height: u32, bytes: u64, limit: u64, adapter: String },
    /// Bad depth-of-field settings.
    #[error(transparent)]
    Lens(#[from] crate::splat::lens::LensError),
}

impl GpuError {
    /// The request cannot be met on this machine's GPU whatever is tried again (a size or a
    /// point count past its limits, no adapter): the command line's bad input, exit 2.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            GpuError::NoAdapter | GpuError::TooManyPoints(_) | GpuError::FramebufferTooLarge { .. } | GpuError::Lens(_)
        )
    }
}

/// An instance, adapter, device and queue.
pub struct GpuContext {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl GpuContext {
    /// A context without a window (headless rendering, tests, benchmarks). Honours
    /// `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`.
    pub fn headless() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        Self::with_instance(instance, None)
    }

    /// A context on `instance` whose adapter can present to `surface` when given.
    pub fn with_instance(instance: wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Self, GpuError> {
        pollster::block_on(Self::request(instance, surface))
    }

    /// [`Self::with_instance`] as a future: the browser cannot block on the adapter and device
    /// requests (`platform::run_async`).
    pub async fn request(instance: wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Self, GpuError> {
        let adapter = wgpu::util::initialize_adapter_from_env_or_default(&instance, surface)
            .await
            .map_err(|_| GpuError::NoAdapter)?;
        // The chaos game binds 7 storage buffers (more than the downlevel defaults' 4) and its
        // point buffer wants the largest binding the device has: ask for what it offers.
        let required_limits = adapter.limits();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("nlifs"),
                required_features: wgpu::Features::empty(),
                required_limits,
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(Self { instance, adapter, device, queue })
    }

    /// The adapter's name and backend, for reports.
    pub fn describe(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    /// The largest point buffer this device can bind (16 bytes a point).
    pub fn max_points(&self) -> u64 {
        let limits = self.device.limits();
        limits.max_storage_buffer_binding_size.min(limits.max_buffer_size) / 16
    }
}

/// True when an adapter exists (cheap enough to call once at start-up).
pub fn adapter_available() -> bool {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(&instance, None)).is_ok()
}
