//! Headless rendering of a prepared [`Shot`] on the CPU: run the chaos game into per-thread
//! framebuffers and resolve. A pure function of the shot, so of (scene, time, settings).

use std::sync::atomic::{AtomicU64, Ordering};

use crate::resolve::density_estimation;
use crate::shot::Shot;
use crate::splat::Framebuffer;

/// What a render produced: the image and the accumulation it was resolved from.
pub struct Rendered {
    pub image: image::RgbImage,
    pub framebuffer: Framebuffer,
}

/// Renders `shot` on the CPU, with its density estimation where it asks for one (as `nlifs
/// render` does). `progress(done, total)` is called as chunks finish (from worker threads).
pub fn render_cpu(shot: &Shot, progress: &(dyn Fn(u64, u64) + Sync)) -> Rendered {
    let chunks = shot.plan.chunks() as u64;
    let done = AtomicU64::new(0);
    let framebuffer = shot.splat(|| progress(done.fetch_add(1, Ordering::Relaxed) + 1, chunks));
    let de = shot.settings.density_estimation.as_ref();
    let image = density_estimation::resolve_image(&framebuffer, &shot.camera, &shot.style, de);
    Rendered { image, framebuffer }
}
