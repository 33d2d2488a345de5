//! flam3's spatial filter in the resolve of the average and density modes (`[render] filter`,
//! `filter_shape`; [`PixelFilter`]): before the tone map, each pixel takes the weighted sum of
//! the pixels around it of their linear density a0 and of their colour times a0, with flam3's
//! weights for the shape and radius (`crate::flame::render_filter::filter_weights`: one axis's
//! weights, the square filter their outer product). Its colour is then that sum's colour over
//! its density, so a pixel next to a lit one takes a share of its light, as flam3 filters its
//! log-scaled accumulation. Pixels outside the image add nothing; a pixel whose filtered
//! density is not above 0 shows the background.
//!
//! The shader's `filtered` and `filtered_estimate` (`shaders/resolve.wgsl`,
//! `shaders/density_estimation.wgsl`) repeat [`gather`] term by term, in the same order; the
//! taps are the pipeline constant `FILTER_TAPS`, the weights `ResolveParams::filter_weights`.

use crate::flame::render_filter::filter_weights;
use crate::scene::spec::PixelFilter;

use super::ResolveParams;

/// The resolve's table of one axis's weights: [`PixelFilter::MAX_TAPS`] weights and a zero.
pub type Weights = [[f32; 4]; 4];
const _: () = assert!(PixelFilter::MAX_TAPS < 16);

/// The resolve's uniforms for `filter`: its taps along each axis (odd; 0: off) and their
/// weights. A filter wider than the table (the scene check refuses one) or whose weights sum to
/// 0 is off.
pub fn uniforms(filter: Option<PixelFilter>) -> (u32, Weights) {
    let mut table = [[0.0; 4]; 4];
    let Some(f) = filter.filter(|f| f.radius_px > 0.0) else { return (0, table) };
    match filter_weights(f.shape, f64::from(f.radius_px)) {
        Some(w) if w.len() <= PixelFilter::MAX_TAPS => {
            for (i, v) in w.iter().enumerate() {
                table[i / 4][i % 4] = *v as f32;
            }
            (w.len() as u32, table)
        }
        _ => (0, table),
    }
}

fn weight(p: &ResolveParams, i: u32) -> f32 {
    p.filter_weights[(i / 4) as usize][(i % 4) as usize]
}

/// The filtered average colour and linear density of pixel (x, y): `sample(x, y)` gives a
/// pixel's average colour and linear density (None: no points), `p.filter_taps` > 0 the taps.
/// None where the filtered density is not above 0.
pub fn gather(
    p: &ResolveParams,
    x: u32,
    y: u32,
    sample: impl Fn(u32, u32) -> Option<([f32; 3], f32)>,
) -> Option<([f32; 3], f32)> {
    let taps = p.filter_taps;
    let half = (taps / 2) as i64;
    let mut sum = [0.0f32; 4];
    for j in 0..taps {
        let sy = i64::from(y) + i64::from(j) - half;
        if sy < 0 || sy >= i64::from(p.height) {
            continue;
        }
        let wy = weight(p, j);
        for i in 0..taps {
            let sx = i64::from(x) + i64::from(i) - half;
            if sx < 0 || sx >= i64::from(p.width) {
                continue;
            }
            if let Some((avg, a0)) = sample(sx as u32, sy as u32) {
                let q = a0 * (wy * weight(p, i));
                sum = [sum[0] + avg[0] * q, sum[1] + avg[1] * q, sum[2] + avg[2] * q, sum[3] + q];
            }
        }
    }
    (sum[3] > 0.0).then(|| ([sum[0] / sum[3], sum[1] / sum[3], sum[2] / sum[3]], sum[3]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::OrbitCamera;
    use crate::flame::FilterShape;
    use crate::resolve::{ResolveArgs, ResolveInputs, ResolveStyle, Tone, resolve_fragment};
    use crate::scene::spec::SplatMode;
    use crate::splat::SplatView;

    /// Linear `mode` parameters of a `size`×`size` accumulation over a black background with
    /// `filter`.
    fn params(mode: SplatMode, size: u32, filter: Option<PixelFilter>) -> ResolveParams {
        let bounds = (glam::DVec3::ZERO, glam::DVec3::ONE);
        let camera = OrbitCamera::framing(bounds, 2);
        let view = SplatView::new(&camera, size, size, bounds, mode, 0.0, [0.0; 3]);
        let style = ResolveStyle { tone: Tone { filter, ..Tone::NEUTRAL }, ..ResolveStyle::PAPER };
        ResolveArgs::new(&view, &camera, &style).params(size, size, false)
    }

    const GAUSSIAN: PixelFilter = PixelFilter { radius_px: 0.5, shape: FilterShape::Gaussian };

    #[test]
    fn weights_are_flam3s_square_filter_along_one_axis() {
        // flam3's Gaussian of radius 0.5 spans 3 pixels, of radius 1 five, of 4.5 fifteen.
        for (radius, taps) in [(0.5, 3), (1.0, 5), (2.0, 7), (4.5, 15)] {
            let (n, table) = uniforms(Some(PixelFilter { radius_px: radius, shape: FilterShape::Gaussian }));
            assert_eq!(n, taps, "radius {radius}");
            let w: Vec<f32> = table.iter().flatten().copied().collect();
            let sum: f32 = w[..taps as usize].iter().sum();
            assert!((sum - 1.0).abs() < 1e-6, "radius {radius}: weights sum to {sum}");
            for i in 0..taps as usize {
                assert!((w[i] - w[taps as usize - 1 - i]).abs() < 1e-7, "radius {radius}: not symmetric");
            }
            assert!(w[taps as usize..].iter().all(|&v| v == 0.0));
        }
        assert_eq!(uniforms(None).0, 0);
        assert_eq!(uniforms(Some(PixelFilter { radius_px: 0.0, ..GAUSSIAN })).0, 0);
        // Wider than the table: off (the scene check refuses it first).
        assert_eq!(uniforms(Some(PixelFilter { radius_px: 5.0, ..GAUSSIAN })).0, 0);
    }

    #[test]
    fn a_lone_pixel_spreads_its_density_by_the_weights_and_keeps_its_colour() {
        let size = 5;
        let mut accum = vec![0u32; 4 * 25];
        // Pixel (2, 2): 10 points of colour (0.8, 0.4, 0.2).
        accum[4 * 12..4 * 13].copy_from_slice(&[2040, 1020, 510, 10]);
        let colors = [[1.0; 3]];
        let inputs = ResolveInputs { accum: &accum, colors: &colors, max_count: 10, shadow: &[] };
        let plain = params(SplatMode::Average, size, None);
        let filtered = params(SplatMode::Average, size, Some(GAUSSIAN));
        let w = |i: u32| filtered.filter_weights[0][i as usize];
        for y in 0..size {
            for x in 0..size {
                let c = resolve_fragment(&filtered, &inputs, x, y);
                let near = x.abs_diff(2) <= 1 && y.abs_diff(2) <= 1;
                if near {
                    // Average mode: the colour times the covered share of the filter.
                    let share = w(x - 1) * w(y - 1);
                    for (k, v) in [0.8f32, 0.4, 0.2].iter().enumerate() {
                        assert!((c[k] - v * share).abs() < 1e-6, "({x}, {y}) channel {k}: {} vs {}", c[k], v * share);
                    }
                } else {
                    assert_eq!(c, [0.0; 3], "({x}, {y}) is beyond the filter");
                }
            }
        }
        // Without the filter only the pixel itself is drawn.
        let c = resolve_fragment(&plain, &inputs, 2, 2);
        assert!((0..3).all(|k| (c[k] - [0.8, 0.4, 0.2][k]).abs() < 1e-6), "{c:?}");
        assert_eq!(resolve_fragment(&plain, &inputs, 1, 2), [0.0; 3]);
    }

    #[test]
    fn a_uniform_field_stays_uniform_inside_and_the_filter_off_changes_nothing() {
        let size = 9;
        let accum: Vec<u32> = (0..81).flat_map(|i| [510 * (1 + i % 3), 255 * 7, 255, 7 + i % 3]).collect();
        let uniform: Vec<u32> = (0..81).flat_map(|_| [1020u32, 1785, 255, 7]).collect();
        let colors = [[1.0; 3]];
        for mode in [SplatMode::Average, SplatMode::Density] {
            let inputs = ResolveInputs { accum: &uniform, colors: &colors, max_count: 7, shadow: &[] };
            let plain = params(mode, size, None);
            let filtered = params(mode, size, Some(PixelFilter { radius_px: 1.0, ..GAUSSIAN }));
            for (x, y) in [(2, 2), (4, 4), (6, 5)] {
                let (a, b) = (resolve_fragment(&plain, &inputs, x, y), resolve_fragment(&filtered, &inputs, x, y));
                for k in 0..3 {
                    assert!((a[k] - b[k]).abs() < 1e-6, "{mode:?} ({x}, {y}): {a:?} vs {b:?}");
                }
            }
            // The filter off is the unfiltered resolve, bit for bit.
            let inputs = ResolveInputs { accum: &accum, colors: &colors, max_count: 9, shadow: &[] };
            let off = params(mode, size, Some(PixelFilter { radius_px: 0.0, ..GAUSSIAN }));
            assert_eq!(off, plain);
            for i in 0..81 {
                assert_eq!(
                    resolve_fragment(&off, &inputs, i % 9, i / 9),
                    resolve_fragment(&plain, &inputs, i % 9, i / 9)
                );
            }
        }
    }
}
