//! Tests of `density_estimation.rs`: the total kept, a uniform field unchanged, a lone point
//! spread over the widest disc, a dense pixel kept.

use super::*;
use crate::rng::Pcg32;

fn de(max_radius_px: f32, min_radius_px: f32) -> DensityEstimation {
    DensityEstimation { max_radius_px, min_radius_px, curve: DensityEstimation::DEFAULT_CURVE }
}

/// Sums of every channel, in f64.
fn totals(sums: impl Iterator<Item = [f64; 4]>) -> [f64; 4] {
    sums.fold([0.0; 4], |t, s| [0, 1, 2, 3].map(|c| t[c] + s[c]))
}

/// A random accumulation (sparse, with dense clusters and pixels by the border) keeps the sum
/// of each channel within 1 % (tolerance stated by the format: 1 %; f32 sums do far better).
#[test]
fn total_brightness_is_kept() {
    let (w, h) = (97u32, 61u32);
    let mut r = Pcg32::for_stream(3, 0, 0);
    let accum: Vec<[u32; 4]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let n = if (x / 10 + y / 10) % 5 == 0 {
                r.next_u32() % 4000
            } else if r.next_u32().is_multiple_of(9) {
                1
            } else {
                0
            };
            [n * (r.next_u32() % 256), n * (r.next_u32() % 256), n * 255, n]
        })
        .collect();
    for (max, min) in [(9.0, 0.0), (4.5, 1.0), (20.0, 0.0)] {
        let e = estimate(&accum, w, h, &de(max, min));
        let before = totals(accum.iter().map(|a| a.map(|v| v as f64)));
        let after = totals(e.sums.iter().map(|a| a.map(|v| v as f64)));
        for c in 0..4 {
            assert!((after[c] - before[c]).abs() <= 0.01 * before[c], "channel {c}: {} vs {}", after[c], before[c]);
        }
    }
}

/// A uniform field stays uniform, border included (tolerance 1e-5 relative: f32 rounding).
#[test]
fn uniform_field_is_unchanged() {
    let (w, h) = (40u32, 23u32);
    for count in [1u32, 3, 50] {
        let accum = vec![[count * 200, count * 100, count * 7, count]; (w * h) as usize];
        let e = estimate(&accum, w, h, &de(9.0, 0.0));
        for s in &e.sums {
            for c in 0..4 {
                let want = accum[0][c] as f32;
                assert!((s[c] - want).abs() <= 1e-5 * want, "{s:?} vs {:?}", accum[0]);
            }
        }
    }
}

/// A lone point (count 1) covers exactly the pixels within `max_radius` of it, brightest at
/// the centre and falling outwards (oracle: the lattice points of the disc, counted apart).
#[test]
fn lone_point_spreads_over_the_widest_disc() {
    let (w, h) = (64u32, 64u32);
    let mut accum = vec![[0u32; 4]; (w * h) as usize];
    let (cx, cy) = (30i32, 33i32);
    accum[(cy as u32 * w + cx as u32) as usize] = [255, 128, 0, 1];
    let radius = 9i32;
    let e = estimate(&accum, w, h, &de(radius as f32, 0.0));
    let mut lit = 0;
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            let d2 = (x - cx).pow(2) + (y - cy).pow(2);
            let s = e.sums[(y as u32 * w + x as u32) as usize];
            assert_eq!(s[3] > 0.0, d2 <= radius * radius, "({x}, {y})");
            lit += (s[3] > 0.0) as i32;
            // Colour follows the count (the sums are the point's colour times the weight).
            assert!((s[0] - 255.0 * s[3]).abs() <= 1e-4 * s[0].max(1.0));
        }
    }
    let disc = (-radius..=radius).flat_map(|y| (-radius..=radius).map(move |x| (x, y)));
    assert_eq!(lit, disc.filter(|(x, y)| x * x + y * y <= radius * radius).count() as i32);
    let at = |dx: i32| e.sums[((cy as u32) * w + (cx + dx) as u32) as usize][3];
    assert!(at(0) > at(3) && at(3) > at(6) && at(6) > at(9), "{} {} {} {}", at(0), at(3), at(6), at(9));
}

/// A dense pixel (min radius 0) keeps its sums exactly and lends nothing to its neighbours.
#[test]
fn dense_pixel_keeps_its_value() {
    let (w, h) = (21u32, 21u32);
    let mut accum = vec![[0u32; 4]; (w * h) as usize];
    let centre = (10 * w + 10) as usize;
    accum[centre] = [255_000_000, 3_000_000, 77, 1_000_000];
    let e = estimate(&accum, w, h, &de(9.0, 0.0));
    assert_eq!(e.sums[centre], accum[centre].map(|v| v as f32));
    assert!(e.sums.iter().enumerate().all(|(i, s)| i == centre || s[3] == 0.0));
    assert_eq!(e.max_count, 1_000_000.0);
}

/// The radius follows flam3's curve: max at count 1, max / count^curve, clamped to the minimum.
#[test]
fn radius_follows_the_curve() {
    let d = de(9.0, 1.5);
    assert_eq!(radius_px(&d, 1.0), 9.0);
    assert!((radius_px(&d, 32.0) - 9.0 / 32f32.powf(0.4)).abs() < 1e-5);
    assert_eq!(radius_px(&d, 1e6), 1.5);
}

/// The GPU's kernel choice ([`kernel_index`] over [`KernelTables::first_count`]) is the CPU's
/// ([`kernel_step`]) for every count up to 2^18 and for the powers of two and their neighbours
/// beyond, in settings with and without a minimum radius and with flat and steep curves: the
/// two sides pick the same kernel, exactly (no tolerance: the lookup is a table of integers).
#[test]
fn kernel_lookup_matches_the_cpu_choice() {
    let settings = [
        de(9.0, 0.0),
        de(4.5, 1.0),
        DensityEstimation { max_radius_px: 20.0, min_radius_px: 0.5, curve: 0.1 },
        DensityEstimation { max_radius_px: 3.0, min_radius_px: 0.0, curve: 2.0 },
        DensityEstimation { max_radius_px: 32.0, min_radius_px: 32.0, curve: 0.4 },
    ];
    for d in settings {
        let tables = KernelTables::of(&d);
        let max_steps = tables.kernels.len() - 1;
        assert_eq!(tables.first_count[max_steps], 1, "{d:?}: the widest step takes a count of 1");
        let powers = (18..32).flat_map(|p| [(1u32 << p) - 1, 1 << p, (1 << p) + 1]);
        for count in (1..=1u32 << 18).chain(powers).chain([u32::MAX - 1]) {
            assert_eq!(
                kernel_index(&tables.first_count, count),
                kernel_step(&d, count, max_steps),
                "{d:?}: count {count}"
            );
        }
        for (s, k) in tables.kernels.iter().enumerate() {
            let cpu = kernel(s as f32 / RADIUS_STEPS);
            let side = (2 * k[1] + 1) as usize;
            assert_eq!(k[1] as i32, cpu.reach);
            assert_eq!(&tables.weights[k[0] as usize..k[0] as usize + side * side], &cpu.weights[..]);
        }
    }
}
