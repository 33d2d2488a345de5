//! The resolve on the CPU: the twin of `shaders/resolve.wgsl` (host side `src/gpu/resolve.rs`),
//! turning a splat's accumulation (a [`Framebuffer`]) into an image. Same constants, same
//! parameters ([`ResolveParams`], the one mirror of the WGSL struct, shared by both sides), same
//! loop shape: [`resolve_fragment`] is the fragment stage `resolve` for one pixel, [`max_count`]
//! the density mode's reduction, and [`resolve_image`] runs the fragment over every pixel and
//! writes what an 8-bit unorm target stores. Keep in sync with `shaders/resolve.wgsl`.
//!
//! Closest keys become depth-cued function colours, optionally shaded from the depth of the
//! neighbouring keys (normals from depth, lit by a head light, so that 3D point sets read as
//! solids) and widened to a point radius (each pixel shows the nearest key within it); sums
//! become average colours, which density mode scales by log(1 + count) / log(1 + max count).
//! With [`ResolveStyle::default`] (no shading, radius 0) the image is the plain resolve that
//! `nlifs render` has always written.

use glam::Vec3;

use crate::camera::{OrbitCamera, Projection};
use crate::color::linear_to_srgb;
use crate::scene::spec::SplatMode;
use crate::splat::{Framebuffer, SplatView};

/// The closest mode's number in `ResolveParams::mode` ([`SplatMode::index`]).
pub const MODE_CLOSEST: u32 = 0;
/// The average mode's number in `ResolveParams::mode`.
pub const MODE_AVERAGE: u32 = 1;
/// The empty closest-point key (`EMPTY` in the shader; the splat's [`crate::splat::EMPTY`]).
pub const EMPTY: u32 = u32::MAX;
/// Largest key depth: depth fraction t = (key >> 8) / DEPTH_SCALE (24 bits of depth).
pub const DEPTH_SCALE: f32 = 16_777_215.0;
/// Colour sums are of channels scaled to 0..=COLOR_SCALE ([`crate::splat::COLOR_SCALE`]).
pub const COLOR_SCALE: f32 = 255.0;
/// Largest point radius the resolve draws: the closest mode's neighbourhood is (2r + 1)² key
/// reads per pixel, which a software rasterizer pays in full.
pub const MAX_POINT_RADIUS_PX: u32 = 8;

const _: () = assert!(EMPTY == crate::splat::EMPTY);
const _: () = assert!(DEPTH_SCALE == ((1u32 << crate::splat::DEPTH_BITS) - 1) as f32);
const _: () = assert!(COLOR_SCALE == crate::splat::COLOR_SCALE);

/// Mirrors `struct ResolveParams` in `shaders/resolve.wgsl`: keep in sync.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ResolveParams {
    /// rgb: linear background; w: depth cue.
    pub background: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub mode: u32,
    /// 1: the fragment writes sRGB-encoded values (unorm target); 0: linear (sRGB target).
    pub encode_srgb: u32,
    /// 0: flat colours; 1: full screen-space shading (closest mode).
    pub shading: f32,
    /// View-space depth range of the keys, for normals from depth.
    pub near: f32,
    pub far: f32,
    /// View-space size of a pixel at unit distance (perspective) or absolute (parallel).
    pub pixel_size: f32,
    pub perspective: u32,
    /// Closest mode: each pixel shows the nearest key within this radius.
    pub point_radius_px: u32,
    /// Target pixel of the accumulation's pixel (0, 0) (the GPU draw's viewport origin).
    pub origin_x: u32,
    pub origin_y: u32,
}
const _: () = assert!(std::mem::size_of::<ResolveParams>() == 64);

/// How the resolve draws, beyond the splat's own settings (mode, background, depth cue). The
/// default is the plain resolve: flat colours, one pixel per key.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResolveStyle {
    /// Screen-space shading strength in [0, 1] (closest mode): 0 flat, 1 fully shaded.
    pub shading: f32,
    /// Closest mode: each pixel shows the nearest key within this radius (at most
    /// [`MAX_POINT_RADIUS_PX`]).
    pub point_radius_px: u32,
}

/// What the resolve needs besides the accumulation: the splat's colour settings, the style and
/// the view's geometry (for normals from depth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolveArgs {
    pub mode: SplatMode,
    pub background: [f32; 3],
    pub depth_cue: f32,
    /// 0: flat colours; 1: full screen-space shading (closest mode only).
    pub shading: f32,
    /// Closest mode: each pixel shows the nearest key within this radius.
    pub point_radius_px: u32,
    pub near: f32,
    pub far: f32,
    /// View-space size of a pixel at unit distance (perspective) or absolute (parallel).
    pub pixel_size: f32,
    pub perspective: bool,
    /// Where in the target the accumulation's pixel (0, 0) goes: the GPU draw covers the
    /// rectangle of the accumulation's size there (the rest of the target is cleared to black).
    /// The CPU resolve writes the accumulation's rectangle only and takes (0, 0).
    pub origin_px: [u32; 2],
}

/// View-space size of one of `height_px` pixel rows at unit distance (perspective) or
/// absolute (parallel), and whether the projection is perspective.
pub fn pixel_footprint(camera: &OrbitCamera, height_px: u32) -> (f32, bool) {
    match camera.projection {
        Projection::Perspective => (2.0 * (0.5 * camera.fov_y_deg.to_radians()).tan() / height_px as f32, true),
        Projection::Parallel => (2.0 * camera.half_height_at_target() / height_px as f32, false),
    }
}

impl ResolveArgs {
    /// The resolve of a splat of `view` seen by `camera`, drawn with `style`.
    pub fn new(view: &SplatView, camera: &OrbitCamera, style: &ResolveStyle) -> Self {
        let (pixel_size, perspective) = pixel_footprint(camera, view.height);
        Self {
            mode: view.mode,
            background: view.background,
            depth_cue: view.depth_cue,
            shading: style.shading,
            point_radius_px: style.point_radius_px,
            near: view.near,
            far: view.far,
            pixel_size,
            perspective,
            origin_px: [0, 0],
        }
    }

    /// The shader's parameters for an accumulation of `width`×`height` pixels. Shading and
    /// point radius apply to closest mode only (zero otherwise, so that the GPU picks the
    /// unshaded pipeline); the radius is clamped to [`MAX_POINT_RADIUS_PX`].
    pub fn params(&self, width: u32, height: u32, encode_srgb: bool) -> ResolveParams {
        let closest = self.mode == SplatMode::Closest;
        ResolveParams {
            background: [self.background[0], self.background[1], self.background[2], self.depth_cue],
            width,
            height,
            mode: self.mode.index(),
            encode_srgb: encode_srgb as u32,
            shading: if closest { self.shading } else { 0.0 },
            near: self.near,
            far: self.far,
            pixel_size: self.pixel_size,
            perspective: self.perspective as u32,
            point_radius_px: if closest { self.point_radius_px.min(MAX_POINT_RADIUS_PX) } else { 0 },
            origin_x: self.origin_px[0],
            origin_y: self.origin_px[1],
        }
    }
}

/// The resolve's bindings: the accumulation in the GPU's layout (closest mode: one key per
/// pixel; otherwise r, g, b sums and the count, four u32 per pixel), the function colours
/// (linear RGB) and the maximum count ([`max_count`], density mode).
#[derive(Clone, Copy, Debug)]
pub struct ResolveInputs<'a> {
    pub accum: &'a [u32],
    pub colors: &'a [[f32; 3]],
    pub max_count: u32,
}

impl<'a> ResolveInputs<'a> {
    /// The bindings for `framebuffer` (the maximum count computed for density mode only, as the
    /// GPU runs its reduction only then).
    pub fn of(framebuffer: &'a Framebuffer) -> Self {
        let accum: &[u32] = match framebuffer.view.mode {
            SplatMode::Closest => &framebuffer.closest,
            SplatMode::Average | SplatMode::Density => bytemuck::cast_slice(&framebuffer.accum),
        };
        let width_px = framebuffer.view.width as usize;
        let height_px = framebuffer.view.height as usize;
        let max_count =
            if framebuffer.view.mode == SplatMode::Density { max_count(accum, width_px * height_px) } else { 0 };
        Self { accum, colors: &framebuffer.colors, max_count }
    }
}

/// The maximum count over the first `pixels` pixels of a sum accumulation: the twin of the
/// shader's `max_count` (a workgroup reduction there, `atomicMax` into `stats[0]`).
pub fn max_count(accum: &[u32], pixels: usize) -> u32 {
    accum.chunks_exact(4).take(pixels).map(|a| a[3]).max().unwrap_or(0)
}

/// The shader's `linear_to_srgb` (the same function as the scene's).
fn encode(c: [f32; 3]) -> [f32; 3] {
    c.map(linear_to_srgb)
}

fn cue(p: &ResolveParams, color: [f32; 3], t: f32) -> [f32; 3] {
    let k = p.background[3] * t;
    [0, 1, 2].map(|c| color[c] + (p.background[c] - color[c]) * k)
}

/// View-space position of pixel (x, y) with key depth fraction t (for normals).
fn view_position(p: &ResolveParams, x: f32, y: f32, t: f32) -> Vec3 {
    let d = p.near + t * (p.far - p.near);
    let sx = (x - 0.5 * p.width as f32) * p.pixel_size;
    let sy = (0.5 * p.height as f32 - y) * p.pixel_size;
    if p.perspective != 0 { Vec3::new(sx * d, sy * d, -d) } else { Vec3::new(sx, sy, -d) }
}

fn key_at(p: &ResolveParams, accum: &[u32], x: i32, y: i32) -> u32 {
    if x < 0 || y < 0 || x >= p.width as i32 || y >= p.height as i32 {
        return EMPTY;
    }
    accum[y as usize * p.width as usize + x as usize]
}

fn depth_of(key: u32) -> f32 {
    (key >> 8) as f32 / DEPTH_SCALE
}

/// Lambert head-light factor from the depths of the 4-neighbourhood (1 where undefined).
fn shade(p: &ResolveParams, accum: &[u32], x: i32, y: i32, t: f32) -> f32 {
    let at = view_position(p, x as f32 + 0.5, y as f32 + 0.5, t);
    let kr = key_at(p, accum, x + 1, y);
    let kl = key_at(p, accum, x - 1, y);
    let kd = key_at(p, accum, x, y + 1);
    let ku = key_at(p, accum, x, y - 1);
    let or_t = |k: u32| if k != EMPTY { depth_of(k) } else { t };
    let (tr, tl, td, tu) = (or_t(kr), or_t(kl), or_t(kd), or_t(ku));
    // One-sided differences from the nearer neighbour avoid smearing across silhouettes.
    let dx = if (tr - t).abs() < (tl - t).abs() {
        view_position(p, x as f32 + 1.5, y as f32 + 0.5, tr) - at
    } else {
        at - view_position(p, x as f32 - 0.5, y as f32 + 0.5, tl)
    };
    let dy = if (td - t).abs() < (tu - t).abs() {
        view_position(p, x as f32 + 0.5, y as f32 + 1.5, td) - at
    } else {
        at - view_position(p, x as f32 + 0.5, y as f32 - 0.5, tu)
    };
    let n = dy.cross(dx);
    let len = n.length();
    if !(len > 0.0) {
        return 1.0;
    }
    let to_eye = (-at).normalize();
    let lambert = (n / len).dot(to_eye).abs();
    0.25 + 0.75 * lambert
}

/// The fragment stage `resolve` at accumulation pixel (x, y) (the shader's fragment position
/// less the origin): the colour the shader returns, sRGB-encoded when `p.encode_srgb` is set.
/// The mode and the shading switch on the uniforms, which [`ResolveArgs::params`] makes equal
/// to the GPU pipeline's constants `RESOLVE_MODE` and `SHADED`.
pub fn resolve_fragment(p: &ResolveParams, inputs: &ResolveInputs<'_>, x: u32, y: u32) -> [f32; 3] {
    let accum = inputs.accum;
    let mut c = [p.background[0], p.background[1], p.background[2]];
    if x < p.width && y < p.height {
        let pixel = (y * p.width + x) as usize;
        let slot = 4 * pixel;
        if p.mode == MODE_CLOSEST {
            let mut key = accum[pixel];
            let mut at = (x as i32, y as i32);
            let r = p.point_radius_px as i32;
            // r = 0 skips the loop (the shader's `r > 0` in its loop condition): the pixel's
            // own key is the only one within radius 0.
            if r > 0 {
                for dy in -r..=r {
                    for dx in -r..=r {
                        let k = key_at(p, accum, x as i32 + dx, y as i32 + dy);
                        if dx * dx + dy * dy <= r * r && k < key {
                            key = k;
                            at = (x as i32 + dx, y as i32 + dy);
                        }
                    }
                }
            }
            if key != EMPTY {
                let fi = (key & 0xff) as usize;
                let t = depth_of(key);
                // The GPU's table has 256 entries; keys only hold indices of compiled functions.
                let mut base = inputs.colors[fi.min(inputs.colors.len() - 1)];
                if p.shading > 0.0 {
                    // WGSL's mix(1, s, shading) = 1 · (1 − shading) + s · shading.
                    let factor = 1.0 * (1.0 - p.shading) + shade(p, accum, at.0, at.1, t) * p.shading;
                    base = base.map(|b| b * factor);
                }
                c = cue(p, base, t);
            }
        } else {
            let count = accum[slot + 3];
            if count > 0 {
                let n = count as f32 * COLOR_SCALE;
                let avg = [accum[slot] as f32 / n, accum[slot + 1] as f32 / n, accum[slot + 2] as f32 / n];
                if p.mode == MODE_AVERAGE {
                    c = avg;
                } else {
                    let log_max = (1.0 + inputs.max_count.max(1) as f32).ln();
                    let b = (1.0 + count as f32).ln() / log_max;
                    c = [0, 1, 2].map(|k| p.background[k] + (avg[k] - p.background[k]) * b);
                }
            }
        }
    }
    if p.encode_srgb != 0 { encode(c) } else { c }
}

/// What an 8-bit unorm target stores for a fragment value: round to nearest.
fn unorm8(v: f32) -> u8 {
    (v * 255.0 + 0.5) as u8
}

/// Resolves `framebuffer` (seen by `camera`, for the normals of the shading) with `style` to an
/// 8-bit sRGB image, as the GPU resolve draws it into an RGBA8 unorm target.
pub fn resolve_image(framebuffer: &Framebuffer, camera: &OrbitCamera, style: &ResolveStyle) -> image::RgbImage {
    let view = &framebuffer.view;
    let params = ResolveArgs::new(view, camera, style).params(view.width, view.height, true);
    let inputs = ResolveInputs::of(framebuffer);
    image::RgbImage::from_fn(view.width, view.height, |x, y| {
        image::Rgb(resolve_fragment(&params, &inputs, x, y).map(unorm8))
    })
}

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
    /// the point radius), 0 where none does; in density mode the brightness
    /// log(1 + count) / log(1 + max count) with which the average colour is laid over the
    /// background.
    pub alpha: Vec<f32>,
    /// The background the colours were drawn over (linear RGB).
    pub background: [f32; 3],
}

/// Resolves `framebuffer` like [`resolve_image`] but keeps linear floats (no 8-bit
/// quantisation) and the coverage of every pixel.
pub fn resolve_linear(framebuffer: &Framebuffer, camera: &OrbitCamera, style: &ResolveStyle) -> LinearImage {
    let view = &framebuffer.view;
    let params = ResolveArgs::new(view, camera, style).params(view.width, view.height, false);
    let inputs = ResolveInputs::of(framebuffer);
    let pixels = view.width as usize * view.height as usize;
    let mut rgb = Vec::with_capacity(pixels);
    let mut alpha = Vec::with_capacity(pixels);
    for y in 0..view.height {
        for x in 0..view.width {
            rgb.push(resolve_fragment(&params, &inputs, x, y));
            alpha.push(coverage(&params, &inputs, x, y));
        }
    }
    LinearImage { width: view.width, height: view.height, rgb, alpha, background: view.background }
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
        0.0
    } else if p.mode == MODE_AVERAGE {
        1.0
    } else {
        (1.0 + count as f32).ln() / (1.0 + inputs.max_count.max(1) as f32).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parameters of a closest-mode resolve of `size`×`size` pixels in parallel projection,
    /// white functions, no depth cue, linear output: a fragment's value is its shade factor.
    fn params(size: u32, shading: f32, point_radius_px: u32) -> ResolveParams {
        let args = ResolveArgs {
            mode: SplatMode::Closest,
            background: [0.0; 3],
            depth_cue: 0.0,
            shading,
            point_radius_px,
            near: 1.0,
            far: 3.0,
            pixel_size: 0.01,
            perspective: false,
            origin_px: [0, 0],
        };
        args.params(size, size, false)
    }

    fn key(depth_view: f32, p: &ResolveParams) -> u32 {
        let t = (depth_view - p.near) / (p.far - p.near);
        ((t * DEPTH_SCALE) as u32) << 8
    }

    /// A key alone in an empty accumulation covers the pixels within the point radius: the
    /// lattice points of a disc, 1, 5 and 13 of them for radius 0, 1 and 2.
    #[test]
    fn radius_fills_a_disc() {
        for (radius, covered) in [(0, 1), (1, 5), (2, 13), (3, 29)] {
            let p = params(9, 0.0, radius);
            let mut accum = vec![EMPTY; 81];
            accum[4 * 9 + 4] = key(2.0, &p);
            let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0 };
            let lit: Vec<[f32; 3]> =
                (0..81).map(|i| resolve_fragment(&p, &inputs, i % 9, i / 9)).filter(|c| c[0] > 0.0).collect();
            assert_eq!(lit.len(), covered, "radius {radius}");
            assert!(lit.iter().all(|&c| c == [1.0; 3]), "radius {radius}: {lit:?}");
        }
    }

    /// Shading from known slopes, seen from the image centre (where the direction to the eye is
    /// the view axis): a plane facing the camera keeps its colour (Lambert 1), a plane tilted by
    /// 60° about the vertical gets 0.25 + 0.75 cos 60° = 0.625, and at a silhouette the normal
    /// comes from the nearer neighbour (the facing plane, not the step to the far one).
    #[test]
    fn shading_of_known_slopes() {
        let size = 15;
        let p = params(size, 1.0, 0);
        let slope_per_px = p.pixel_size * 60f32.to_radians().tan();
        let field = |depth: &dyn Fn(i32) -> f32| -> Vec<u32> {
            (0..size * size).map(|i| key(depth((i % size) as i32 - 7), &p)).collect()
        };
        let cases: [(&str, Vec<u32>, f32); 3] = [
            ("facing", field(&|_| 2.0), 1.0),
            ("tilted 60°", field(&|dx| 2.0 + dx as f32 * slope_per_px), 0.625),
            ("silhouette", field(&|dx| if dx < 0 { 2.8 } else { 2.0 }), 1.0),
        ];
        for (name, accum, expected) in cases {
            let inputs = ResolveInputs { accum: &accum, colors: &[[1.0; 3]], max_count: 0 };
            let c = resolve_fragment(&p, &inputs, 7, 7);
            // Truncating depths to 24 bits moves a depth difference by < 2 · 2^-24 · (far − near),
            // about 1e-5 of the tilted plane's 0.017 per pixel.
            assert!((c[0] - expected).abs() < 1e-4, "{name}: shade {} (expected {expected})", c[0]);
        }
    }

    /// Shading and point radius apply to closest mode only; the radius is clamped.
    #[test]
    fn params_gate_the_closest_only_settings() {
        let bounds = (glam::DVec3::ZERO, glam::DVec3::ONE);
        let camera = OrbitCamera::framing(bounds, 3);
        let view = SplatView::new(&camera, 4, 4, bounds, SplatMode::Closest, 0.5, [0.0; 3]);
        let style = ResolveArgs::new(&view, &camera, &ResolveStyle { shading: 0.5, point_radius_px: 20 });
        let closest = style.params(4, 4, true);
        assert_eq!((closest.shading, closest.point_radius_px), (0.5, MAX_POINT_RADIUS_PX));
        for mode in [SplatMode::Average, SplatMode::Density] {
            let p = ResolveArgs { mode, ..style }.params(4, 4, true);
            assert_eq!((p.mode, p.shading, p.point_radius_px), (mode.index(), 0.0, 0));
        }
    }
}
