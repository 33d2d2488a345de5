//! The lanes against the scalar light: every pixel's lit colour the same bits.

use super::*;

/// A `width`×`height` accumulation of a wavy surface with noise and holes (about one pixel in
/// four empty), keys in [near, far], function indices in the low byte; xorshift, fixed seed.
fn field(width: u32, height: u32, seed: u32) -> Vec<u32> {
    let mut state = seed | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    (0..width * height)
        .map(|i| {
            let (x, y) = ((i % width) as f32, (i / width) as f32);
            let r = next();
            if r % 4 == 0 {
                return EMPTY;
            }
            let t = 0.5 + 0.3 * (0.3 * x).sin() * (0.2 * y).cos() + 0.02 * ((r >> 8) % 100) as f32 / 100.0;
            (((t * DEPTH_SCALE) as u32) << 8) | (r >> 28)
        })
        .collect()
}

fn params(width: u32, height: u32, perspective: bool, shadows: f32) -> ResolveParams {
    let args = ResolveArgs {
        mode: SplatMode::Closest,
        background: [0.1, 0.2, 0.3],
        depth_cue: 0.3,
        shading: 0.9,
        occlusion: 0.6,
        point_radius_px: 0,
        near: 2.0,
        far: 5.0,
        pixel_size: if perspective { 0.004 } else { 0.02 },
        perspective,
        origin_px: [0, 0],
        tone: Tone::NEUTRAL,
        shadows: 0.0,
        key_light: shadow::key_light(40.0, 25.0),
        shadow: None,
        normal_radius_px: NORMAL_RADIUS_PX,
        pixel_area: 4e-4,
        points_drawn: 0,
    };
    let side = 24u32;
    // A map from view space: texels across x and y, depth along z, turned a little.
    let map = Mat4::from_cols_array_2d(&[
        [6.0, 0.8, 0.01, 0.0],
        [-0.7, -6.0, 0.02, 0.0],
        [0.5, 0.3, -0.25, 0.0],
        [12.0, 12.0, 0.1, 1.0],
    ]);
    ResolveParams {
        shadows,
        shadow_from_view: map.to_cols_array_2d(),
        shadow_side_px: side,
        shadow_texel_world: 0.17,
        shadow_inv_depth_world: 0.25,
        ..args.params(width, height, false)
    }
}

#[test]
fn lanes_equal_the_scalar_light() {
    // Widths off the lane count (the row's last group is partial), both projections, with and
    // without the shadow map, and the occlusion's reach past the borders.
    for (case, &(width, height, perspective, shadows)) in
        [(37u32, 23u32, true, 0.6f32), (37, 23, false, 0.6), (64, 9, true, 0.0), (5, 7, false, 1.0)].iter().enumerate()
    {
        let p = params(width, height, perspective, shadows);
        let accum = field(width, height, 7 + case as u32);
        let shadow = field(24, 24, 99 + case as u32);
        let colors = [[0.8, 0.5, 0.2]; 16];
        let inputs = ResolveInputs { accum: &accum, colors: &colors, max_count: 0, shadow: &shadow };
        let rows = LightRows::new(&p, &inputs, 0..=height as i32 - 1);
        let (mut checked, mut shadowed, mut occluded) = (0, 0, 0);
        for y in 0..height as i32 {
            for x in 0..width as i32 {
                let key = accum[(y * width as i32 + x) as usize];
                if key == EMPTY {
                    continue;
                }
                for albedo in [[1.0, 1.0, 1.0], [0.8, 0.5, 0.2]] {
                    let scalar = solid::light(&p, &inputs, x, y, key, Vec3::from_array(albedo), (0.0, 0.0)).to_array();
                    let lanes = rows.lit(x, y, albedo);
                    assert_eq!(scalar.map(f32::to_bits), lanes.map(f32::to_bits), "case {case}, pixel ({x}, {y})");
                }
                checked += 1;
                // The test means something only where shadows and occlusion take light.
                let slopes = solid::fitted_slopes(&p, &accum, x, y, key);
                let (normal, _) = solid::normal_and_eye(&p, x, y, slopes);
                let s = shadow::shadow_at(&p, &shadow, x, y, key, normal);
                shadowed += (p.shadows > 0.0 && s > 0.0 && s < 1.0) as usize;
                occluded += (solid::occlusion(&p, &accum, x, y, key, slopes) > 0.0) as usize;
            }
        }
        assert!(checked > (width * height / 2) as usize, "case {case}: {checked} keys");
        assert!(occluded > checked / 10, "case {case}: {occluded} of {checked} occluded");
        if p.shadows > 0.0 {
            assert!(shadowed > checked / 10, "case {case}: {shadowed} of {checked} partly shadowed");
        }
    }
}

/// The portable lanes (what a CPU without AVX2 runs) give the AVX2 path's factors.
#[test]
fn portable_lanes_equal_the_dispatched_ones() {
    let (width, height) = (41u32, 13u32);
    let p = params(width, height, true, 0.6);
    let accum = field(width, height, 3);
    let shadow = field(24, 24, 5);
    let colors = [[1.0; 3]; 16];
    let inputs = ResolveInputs { accum: &accum, colors: &colors, max_count: 0, shadow: &shadow };
    for y in 0..height as i32 {
        let mut portable = vec![[1.0f32, 0.0]; width as usize];
        let mut dispatched = portable.clone();
        light_row_lanes::<F8>(&p, &inputs, y, &mut portable);
        light_row(&p, &inputs, y, &mut dispatched);
        let bits = |v: &[[f32; 2]]| v.iter().flat_map(|f| f.map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&portable), bits(&dispatched), "row {y}");
    }
}
