//! The resolve in linear light with each pixel's coverage, for the float and alpha outputs
//! (`crate::output`): the fragments of [`super::resolve_fragment`] before the sRGB encode.

use rayon::prelude::*;

use super::{
    COLOR_SCALE, EMPTY, MODE_AVERAGE, MODE_CLOSEST, ResolveArgs, ResolveInputs, ResolveParams, ResolveStyle,
    background, density_of, key_at, resolve_row, tone_uniforms, toned,
};
use crate::camera::OrbitCamera;
use crate::splat::Framebuffer;

/// A resolve in linear light with its coverage: what the float and alpha outputs write
/// (`crate::output`). `rgb` holds the fragment values before the sRGB encode of
/// [`resolve_image`], i.e. the attractor drawn over the background.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    pub width: u32,
    pub height: u32,
    /// Linear RGB over the background, row-major.
    pub rgb: Vec<[f32; 3]>,
    /// How much of each pixel the attractor covers: 1 where a point lies (closest mode: within
    /// the point radius), 0 where none does; in density mode the toned alpha (by default the
    /// brightness log(1 + count) / log(1 + max count)) with which the average colour is laid over
    /// the background.
    pub alpha: Vec<f32>,
    /// The background the colours were drawn over (linear RGB).
    pub background: [f32; 3],
}

/// Resolves `framebuffer` like [`resolve_image`] but keeps linear floats (no 8-bit
/// quantisation) and the coverage of every pixel; rows in parallel.
pub fn resolve_linear(framebuffer: &Framebuffer, camera: &OrbitCamera, style: &ResolveStyle) -> LinearImage {
    let view = &framebuffer.view;
    let params =
        ResolveArgs::new(view, camera, style).drawn(framebuffer.points_drawn).params(view.width, view.height, false);
    let inputs = ResolveInputs::of(framebuffer);
    let width_px = view.width as usize;
    let pixels = width_px * view.height as usize;
    let mut rgb = vec![[0f32; 3]; pixels];
    let mut alpha = vec![0f32; pixels];
    rgb.par_chunks_mut(width_px.max(1)).zip(alpha.par_chunks_mut(width_px.max(1))).enumerate().for_each(
        |(y, (rgb, alpha))| {
            resolve_row(&params, &inputs, y as u32, |x, c| rgb[x] = c);
            for (x, alpha) in alpha.iter_mut().enumerate() {
                *alpha = coverage(&params, &inputs, x as u32, y as u32);
            }
        },
    );
    // The view's background is in the blend space; the image's is linear, as its colours.
    let background = view.mode.blend_space(style.tone.blend).to_linear(view.background);
    LinearImage { width: view.width, height: view.height, rgb, alpha, background }
}

/// The coverage of pixel (x, y) that [`resolve_fragment`] draws over the background.
fn coverage(p: &ResolveParams, inputs: &ResolveInputs<'_>, x: u32, y: u32) -> f32 {
    let accum = inputs.accum;
    let pixel = (y * p.width + x) as usize;
    if p.mode == MODE_CLOSEST {
        let r = p.point_radius_px as i32;
        let hit = (-r..=r).any(|dy| {
            (-r..=r).any(|dx| dx * dx + dy * dy <= r * r && key_at(p, accum, x as i32 + dx, y as i32 + dy) != EMPTY)
        });
        return if hit { 1.0 } else { 0.0 };
    }
    let count = accum[4 * pixel + 3];
    if count == 0 {
        return 0.0;
    }
    let slot = 4 * pixel;
    let n = count as f32 * COLOR_SCALE;
    let avg = [accum[slot] as f32 / n, accum[slot + 1] as f32 / n, accum[slot + 2] as f32 / n];
    toned(&tone_uniforms(p), avg, density_of(p, inputs, count), background(p), p.mode != MODE_AVERAGE).1
}
