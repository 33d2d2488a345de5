//! Density estimation on the GPU (`shaders/density_estimation.wgsl`, host side
//! `src/gpu/density_estimation.rs`) against its CPU twin (`src/resolve/density_estimation.rs`):
//! the same accumulation goes through both, and every estimated sum and count, and the largest
//! count, must agree within the bound derived at [`summation_bound`]. Accumulations with sparse
//! single hits, dense clusters and points on the border, in several settings, and a 5×3 image
//! narrower than the kernel (taps reflected more than once). Runs on any adapter (lavapipe in
//! CI); without one it skips loudly, unless NLIFS_REQUIRE_GPU=1, in which case it fails.

mod common;

use nlifs::gpu::GpuContext;
use nlifs::gpu::density_estimation::GpuDensityEstimation;
use nlifs::live::{LiveSettings, LiveView};
use nlifs::resolve::Tone;
use nlifs::resolve::density_estimation::{KernelTables, estimate};
use nlifs::rng::Pcg32;
use nlifs::scene::spec::DensityEstimation;

use common::gpu;

/// A `w`×`h` accumulation drawn from `seed`: clusters of dense pixels (counts up to 5000, none
/// within 9 columns and 7 rows of the top left corner, so a small image is sparse),
/// isolated single hits, and the outermost rows and columns hit, with colour sums of channels
/// in 0..=255 per point.
fn accumulation(w: u32, h: u32, seed: u32) -> Vec<[u32; 4]> {
    let mut r = Pcg32::for_stream(seed, 0, 0);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let border = x == 0 || y == 0 || x == w - 1 || y == h - 1;
            let n = if (x / 9 + y / 7) % 4 == 1 {
                r.next_u32() % 5000
            } else if border || r.next_u32().is_multiple_of(7) {
                1 + r.next_u32() % 3
            } else {
                0
            };
            [n * (r.next_u32() % 256), n * (r.next_u32() % 256), n * (r.next_u32() % 256), n]
        })
        .collect()
}

/// Most images (t + 2nk, −1 − t + 2nk) of any pixel of an axis of `n` pixels that lie within
/// `reach` of the axis, i.e. in [−reach, n − 1 + reach]: the taps landing on one pixel come
/// from at most this many positions per axis.
fn images_per_axis(n: i64, reach: i64) -> i64 {
    (0..n)
        .map(|t| {
            (-4..=4)
                .flat_map(|k| [t + 2 * n * k, -1 - t + 2 * n * k])
                .filter(|v| (-reach..n + reach).contains(v))
                .count() as i64
        })
        .max()
        .unwrap_or(1)
}

/// How far the GPU's estimated value V may be from the CPU's, relative to V. Both compute
/// V = Σ w_i a_i over the same N terms (the same weights, uploaded from the CPU's tables; the
/// same kernel per pixel, `kernel_lookup_matches_the_cpu_choice` in the CPU twin's tests; the
/// same u32 → f32 conversions, round to nearest) in different orders, and every term is ≥ 0.
/// With u = 2^-24, a sum of N non-negative products in any order, with or without a fused
/// multiply-add, is within γ_N · V of the exact sum, γ_N = N u / (1 − N u) (Higham, Accuracy
/// and Stability of Numerical Algorithms, §3.1 and §4.2); a conversion that does not round to
/// nearest would add ≤ 2u per term, so N + 2 is used. The two results are then within
/// 2 γ_{N+2} V of each other. N is at most the taps of one position (2 reach + 1)² times the
/// positions per axis squared ([`images_per_axis`]).
fn summation_bound(w: u32, h: u32, reach: u32) -> f64 {
    let r = reach as i64;
    let n = ((2 * r + 1).pow(2) * images_per_axis(w as i64, r) * images_per_axis(h as i64, r) + 2) as f64;
    let u = 2f64.powi(-24);
    2.0 * n * u / (1.0 - n * u)
}

#[test]
fn gpu_density_estimation_matches_cpu() {
    let Some(ctx) = gpu() else { return };
    let mut gpu = GpuDensityEstimation::new(&ctx.device);
    let settings = |max_radius_px, min_radius_px, curve| DensityEstimation { max_radius_px, min_radius_px, curve };
    let cases = [
        (83, 57, 1, settings(6.0, 0.0, 0.4)),
        (83, 57, 2, settings(3.5, 1.0, 0.4)),
        (64, 48, 3, settings(9.0, 0.0, 0.2)),
        (40, 30, 4, settings(2.0, 2.0, 1.0)),
        // Narrower than the kernel: taps reflect off both sides, several times.
        (5, 3, 5, settings(4.0, 0.0, 0.4)),
    ];
    for (w, h, seed, de) in cases {
        let accum = accumulation(w, h, seed);
        let cpu = estimate(&accum, w, h, &de);
        let g = gpu.estimate(&ctx, &accum, w, h, &de).unwrap();
        let bound = summation_bound(w, h, KernelTables::of(&de).reach_max);
        let mut worst = 0f64;
        for (i, (c, v)) in cpu.sums.iter().zip(&g.sums).enumerate() {
            for k in 0..4 {
                let (c, v) = (c[k] as f64, v[k] as f64);
                let allowed = bound * c.max(v);
                assert!(
                    (c - v).abs() <= allowed,
                    "{w}×{h} {de:?}: pixel ({}, {}) channel {k}: GPU {v} vs CPU {c} (allowed ±{allowed:e})",
                    i as u32 % w,
                    i as u32 / w,
                );
                if c > 0.0 {
                    worst = worst.max((c - v).abs() / c);
                }
            }
        }
        let (c, v) = (cpu.max_count as f64, g.max_count as f64);
        assert!((c - v).abs() <= bound * c.max(v), "{w}×{h} {de:?}: largest count GPU {v} vs CPU {c}");
        // The estimate is not the input: the filter ran (a sparse hit spreads).
        assert!(g.sums.iter().zip(&accum).any(|(s, a)| s[3] != a[3] as f32), "{w}×{h} {de:?}: nothing spread");
        eprintln!("{w}×{h} {de:?}: largest relative difference {worst:e}, bound {bound:e}");
    }
}

/// A live view of `settings` on the paper's plant 2 at time 0, its camera framing the attractor.
fn plant2_view(ctx: &GpuContext, settings: LiveSettings, width: u32, height: u32) -> LiveView {
    let path = format!("{}/scenes/plant2.toml", env!("CARGO_MANIFEST_DIR"));
    let scene = nlifs::scene::Scene::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let compiled = nlifs::chaos_game::CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = nlifs::chaos_game::attractor_bounds(&compiled, 1);
    let mut live = LiveView::new(ctx, settings, width, height).unwrap();
    live.set_ifs(ctx, &compiled, bounds, true);
    live.set_camera(&scene.camera_for(bounds));
    live
}

/// One frame of `live`'s chaos game, submitted; the points it splatted.
fn advance(ctx: &GpuContext, live: &mut LiveView) -> u64 {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let splats = live.advance(ctx, &mut encoder);
    ctx.queue.submit([encoder.finish()]);
    splats
}

/// A live view of plant 2 in density mode on `backend` (4,096 points, `tone`, `de`), that
/// accumulates without end.
fn density_view(
    ctx: &GpuContext,
    backend: nlifs::live::ChaosBackend,
    tone: Tone,
    de: Option<DensityEstimation>,
    (width, height): (u32, u32),
) -> LiveView {
    use nlifs::gpu::progressive::ProgressiveSettings;
    let draw = ProgressiveSettings {
        point_count: 1 << 12,
        mode: nlifs::scene::spec::SplatMode::Density,
        max_splats: u64::MAX,
        tone,
        density_estimation: de,
        ..ProgressiveSettings::default()
    };
    plant2_view(ctx, LiveSettings { draw, chaos_backend: backend, render_density: None }, width, height)
}

/// `live` drawn into an offscreen target of `width`×`height` (RGBA8 unorm).
fn drawn(ctx: &GpuContext, live: &mut LiveView, (width, height): (u32, u32)) -> image::RgbImage {
    nlifs::gpu::readback::draw_offscreen(ctx, width, height, |encoder, target, format| {
        live.draw(ctx, encoder, target, format, [0, 0])
    })
    .unwrap()
}

/// The live view's CPU route makes its density estimate on the CPU and uploads it; a snapshot
/// (which filters afresh on the GPU) of the same accumulation must show the same image. Both
/// images resolve estimates within [`summation_bound`] of each other with the same shader, so
/// a channel may differ only where the exact value lies within a rounding of a level boundary:
/// at most one level, and in under 1 % of the channels.
#[test]
fn live_cpu_route_estimate_matches_the_gpu_estimate() {
    use nlifs::gpu::progressive::ProgressiveSettings;
    use nlifs::live::ChaosBackend;
    use nlifs::scene::spec::SplatMode;
    let Some(ctx) = gpu() else { return };
    let (width, height) = (160u32, 120u32);
    let settings = LiveSettings {
        draw: ProgressiveSettings {
            point_count: 1 << 16,
            mode: SplatMode::Density,
            max_splats: u64::MAX,
            tone: Tone { exposure: 0.5, gamma: 2.2, ..Tone::NEUTRAL },
            density_estimation: Some(DensityEstimation { max_radius_px: 5.0, min_radius_px: 0.0, curve: 0.4 }),
            ..ProgressiveSettings::default()
        },
        chaos_backend: ChaosBackend::Cpu,
        render_density: None,
    };
    let mut live = plant2_view(&ctx, settings, width, height);
    // Past the frames before the first estimate, so that the draw makes one.
    for _ in 0..12 {
        advance(&ctx, &mut live);
    }
    let drawn = nlifs::gpu::readback::draw_offscreen(&ctx, width, height, |encoder, target, format| {
        live.draw(&ctx, encoder, target, format, [0, 0])
    })
    .unwrap();
    let snapshot = live.snapshot(&ctx).unwrap();
    let (mut differing, mut lit) = (0, 0);
    for (a, b) in drawn.pixels().zip(snapshot.pixels()) {
        for c in 0..3 {
            assert!(a.0[c].abs_diff(b.0[c]) <= 1, "CPU-route estimate {a:?} vs GPU estimate {b:?}");
            differing += (a.0[c] != b.0[c]) as u32;
        }
        lit += (a.0 != drawn.get_pixel(0, 0).0) as u32;
    }
    assert!(lit > 1000, "only {lit} pixels differ from the background");
    assert!(differing * 100 < 3 * width * height, "{differing} channels differ by one level");
}

/// A converged view with density estimation comes to rest (the viewer then stops drawing): the
/// estimate made after the last frame is what every later draw shows. Before, only the light
/// cache's bands counted, which the estimated picture never draws, so a flame's view (density
/// mode with an estimate) redrew at 60 frames a second forever. Both routes; a view without
/// the estimate rests too.
#[test]
fn a_converged_view_with_density_estimation_comes_to_rest() {
    use nlifs::gpu::progressive::ProgressiveSettings;
    use nlifs::live::ChaosBackend;
    use nlifs::scene::spec::SplatMode;
    let Some(ctx) = gpu() else { return };
    let (width, height) = (96u32, 64u32);
    let de = Some(DensityEstimation { max_radius_px: 5.0, min_radius_px: 0.0, curve: 0.4 });
    for (backend, density_estimation) in
        [(ChaosBackend::Cpu, de), (ChaosBackend::Gpu, de), (ChaosBackend::Cpu, None), (ChaosBackend::Gpu, None)]
    {
        let point_count = 1u32 << 14;
        let settings = LiveSettings {
            draw: ProgressiveSettings {
                point_count,
                mode: SplatMode::Density,
                // Converged after 20 frames: past the frames before the first estimate.
                max_splats: 20 * point_count as u64,
                density_estimation,
                ..ProgressiveSettings::default()
            },
            chaos_backend: backend,
            render_density: None,
        };
        let mut live = plant2_view(&ctx, settings, width, height);
        let mut frames = 0;
        while !live.at_rest() {
            assert!(frames < 60, "{backend:?}, estimate {density_estimation:?}: not at rest after {frames} frames");
            advance(&ctx, &mut live);
            nlifs::gpu::readback::draw_offscreen(&ctx, width, height, |encoder, target, format| {
                live.draw(&ctx, encoder, target, format, [0, 0])
            })
            .unwrap();
            frames += 1;
        }
        assert!(live.converged(), "{backend:?}: at rest before converging");
        // And it stays at rest: the draws that follow change nothing.
        assert_eq!(advance(&ctx, &mut live), 0);
        nlifs::gpu::readback::draw_offscreen(&ctx, width, height, |encoder, target, format| {
            live.draw(&ctx, encoder, target, format, [0, 0])
        })
        .unwrap();
        assert!(live.at_rest(), "{backend:?}, estimate {density_estimation:?}: a draw at rest woke it");
    }
}

/// Density mode stops where the view has drawn the render's points per pixel (`RenderDensity`:
/// a longer accumulation would flatten the log density and wash the picture out), scaled by the
/// square of the view's size over the render's, never within the first frame, and again when
/// the view is resized, on the relative and the absolute scale; closest mode goes on to
/// `max_splats`. Both routes.
#[test]
fn density_mode_stops_at_the_renders_points_per_pixel() {
    use nlifs::gpu::progressive::ProgressiveSettings;
    use nlifs::live::{ChaosBackend, RenderDensity};
    use nlifs::scene::spec::{DensityScale, SplatMode};
    let absolute = Tone { density_scale: DensityScale::Absolute, ..Tone::NEUTRAL };
    let Some(ctx) = gpu() else { return };
    let (width, height) = (96u32, 64u32);
    let point_count = 1u32 << 12;
    let frame = point_count as u64;
    // 40 frames' points into an image twice the view's size: 10 frames at the view's.
    let render_density = Some(RenderDensity { points: 40 * frame, width_px: 2 * width, height_px: 2 * height });
    let frames_to_stop = |live: &mut LiveView| {
        let mut frames = 0;
        while !live.converged() {
            assert!(frames < 100, "no stop after {frames} frames");
            advance(&ctx, live);
            frames += 1;
        }
        frames
    };
    for backend in [ChaosBackend::Cpu, ChaosBackend::Gpu] {
        let cases = [(SplatMode::Density, Tone::NEUTRAL, 10), (SplatMode::Closest, Tone::NEUTRAL, 50)];
        for (mode, tone, frames) in cases.into_iter().chain([(SplatMode::Density, absolute, 10)]) {
            let settings = LiveSettings {
                draw: ProgressiveSettings {
                    point_count,
                    mode,
                    tone,
                    max_splats: 50 * frame,
                    ..ProgressiveSettings::default()
                },
                chaos_backend: backend,
                render_density,
            };
            let mut live = plant2_view(&ctx, settings, width, height);
            assert_eq!(frames_to_stop(&mut live), frames, "{backend:?}, {mode:?}");
            assert_eq!(live.splats_since_clear(), frames as u64 * frame, "{backend:?}, {mode:?}");
            if mode == SplatMode::Density && tone == Tone::NEUTRAL {
                // A resize clears the accumulation; at the render's own height the stop is
                // the render's 40 frames.
                live.resize(&ctx, 2 * width, 2 * height);
                assert!(!live.converged(), "{backend:?}: a taller view draws on");
                assert_eq!(frames_to_stop(&mut live), 40, "{backend:?}: the render's points");
            }
        }
    }
    // A render of fewer points than one frame still draws that frame.
    let settings = LiveSettings {
        draw: ProgressiveSettings { point_count, mode: SplatMode::Density, ..ProgressiveSettings::default() },
        chaos_backend: ChaosBackend::Cpu,
        render_density: Some(RenderDensity { points: 10, width_px: width, height_px: height }),
    };
    let mut live = plant2_view(&ctx, settings, width, height);
    assert_eq!(frames_to_stop(&mut live), 1);
}

/// Between two density estimates the live view draws the last one as it was made: on the
/// absolute scale of the points it was made of (the current count would dim it frame by frame
/// until the next estimate, which brightened it again), and with the spatial filter the pass
/// made with it (`GpuDensityEstimation::draw` filters once per estimate). So a draw that keeps
/// the estimate shows the bytes of the draw that made it, and the next estimate's draw shows
/// the new estimate (the toned picture is drawn once per estimate and copied: an sRGB target,
/// as a window's, gets the same bytes while the estimate is kept). Both routes, filter on and
/// off, the absolute and the relative scale.
#[test]
fn a_kept_estimate_is_drawn_as_it_was_made() {
    use nlifs::flame::FilterShape;
    use nlifs::gpu::progressive::EstimateDue;
    use nlifs::live::ChaosBackend;
    use nlifs::scene::spec::{DensityScale, PixelFilter};
    let Some(ctx) = gpu() else { return };
    let (width, height) = (96u32, 64u32);
    let filter = Some(PixelFilter { radius_px: 1.0, shape: FilterShape::Gaussian });
    let cases = [ChaosBackend::Cpu, ChaosBackend::Gpu].into_iter().flat_map(|backend| {
        [None, filter].into_iter().flat_map(move |filter| {
            [DensityScale::Absolute, DensityScale::Relative].map(|scale| (backend, filter, scale))
        })
    });
    for (backend, filter, density_scale) in cases {
        let tone = Tone { density_scale, gamma: 2.2, filter, ..Tone::NEUTRAL };
        let de = DensityEstimation { max_radius_px: 5.0, min_radius_px: 0.0, curve: 0.4 };
        let mut live = density_view(&ctx, backend, tone, Some(de), (width, height));
        let draw = |live: &mut LiveView| drawn(&ctx, live, (width, height));
        for _ in 0..12 {
            advance(&ctx, &mut live);
        }
        assert!(matches!(live.estimate_due(), EstimateDue::Make(_)), "{backend:?}: no estimate due");
        let made = draw(&mut live);
        let lit = made.pixels().filter(|p| p.0 != made.get_pixel(0, 0).0).count();
        assert!(lit > 500, "{backend:?}, filter {filter:?}: only {lit} pixels lit");
        for frame in 0..3 {
            advance(&ctx, &mut live);
            assert_eq!(live.estimate_due(), EstimateDue::Keep, "{backend:?}: frame {frame}");
            let kept = draw(&mut live);
            let differing = made.pixels().zip(kept.pixels()).filter(|(a, b)| a != b).count();
            assert_eq!(differing, 0, "{backend:?}, filter {filter:?}: frame {frame} after the estimate");
        }
        // The next estimate is drawn, not the filter's pass of the last one: as a snapshot
        // (a fresh estimate on the GPU) shows it, within a level as above.
        while !matches!(live.estimate_due(), EstimateDue::Make(_)) {
            advance(&ctx, &mut live);
        }
        let next = draw(&mut live);
        let snapshot = live.snapshot(&ctx).unwrap();
        let mut differing = 0;
        for (a, b) in next.pixels().zip(snapshot.pixels()) {
            for c in 0..3 {
                assert!(a.0[c].abs_diff(b.0[c]) <= 1, "{backend:?}, filter {filter:?}: {a:?} vs snapshot {b:?}");
                differing += (a.0[c] != b.0[c]) as u32;
            }
        }
        assert!(differing * 100 < 3 * width * height, "{differing} channels differ by one level");
        assert!(next.pixels().zip(made.pixels()).any(|(a, b)| a != b), "{backend:?}: the picture did not change");
        // An sRGB target (a window's surface) gets the picture that the texture, sRGB too,
        // encoded: within a level of the shader's encoding for a plain target, the same bytes
        // while the estimate is kept.
        let srgb = |live: &mut LiveView| {
            let format = wgpu::TextureFormat::Rgba8UnormSrgb;
            nlifs::gpu::readback::draw_offscreen_as(&ctx, width, height, format, |encoder, target, format| {
                live.draw(&ctx, encoder, target, format, [0, 0])
            })
            .unwrap()
        };
        let made_srgb = srgb(&mut live);
        for (a, b) in snapshot.pixels().zip(made_srgb.pixels()) {
            assert!((0..3).all(|c| a.0[c].abs_diff(b.0[c]) <= 1), "{backend:?}: plain {a:?}, sRGB {b:?}");
        }
        advance(&ctx, &mut live);
        assert_eq!(live.estimate_due(), EstimateDue::Keep, "{backend:?}");
        assert!(srgb(&mut live) == made_srgb, "{backend:?}, filter {filter:?}: a kept estimate on an sRGB target");
    }
}

/// flam3's spatial filter in density mode without density estimation: the live view filters on
/// the estimate's schedule, over the estimate that spreads nothing (`SPREADS_NOTHING`), instead
/// of gathering the taps in every draw. Its picture is the resolve's that filters the
/// raw counts (`filtered` in `shaders/resolve.wgsl`) drawn from the same accumulation: the same
/// sums, the same loop, so within a level in under 1 % of the channels (the two passes may fuse
/// differently); the draws while the estimate is kept are the same bytes. Both routes.
#[test]
fn a_filter_without_density_estimation_is_drawn_once_per_estimate() {
    use nlifs::flame::FilterShape;
    use nlifs::gpu::chaos_game::GpuChaosGame;
    use nlifs::gpu::progressive::EstimateDue;
    use nlifs::gpu::resolve::{GpuResolve, LightRows};
    use nlifs::live::ChaosBackend;
    use nlifs::resolve::ResolveArgs;
    use nlifs::scene::spec::{PixelFilter, SplatMode};
    let Some(ctx) = gpu() else { return };
    let (width, height) = (96u32, 64u32);
    for backend in [ChaosBackend::Cpu, ChaosBackend::Gpu] {
        let tone = Tone {
            gamma: 2.2,
            filter: Some(PixelFilter { radius_px: 1.0, shape: FilterShape::Gaussian }),
            ..Tone::NEUTRAL
        };
        let mut live = density_view(&ctx, backend, tone, None, (width, height));
        let draw = |live: &mut LiveView| drawn(&ctx, live, (width, height));
        for _ in 0..12 {
            advance(&ctx, &mut live);
        }
        assert_eq!(
            live.estimate_due(),
            EstimateDue::Make(nlifs::resolve::density_estimation::SPREADS_NOTHING),
            "{backend:?}"
        );
        let made = draw(&mut live);
        let lit = made.pixels().filter(|p| p.0 != made.get_pixel(0, 0).0).count();
        assert!(lit > 500, "{backend:?}: only {lit} pixels lit");
        // The resolve's own filter over the same accumulation.
        let accum = live.read_accum(&ctx).unwrap();
        let mut game = GpuChaosGame::new(&ctx.device, 1, width, height);
        ctx.queue.write_buffer(&game.accum, 0, bytemuck::cast_slice(&accum));
        game.generation = 1;
        let args = ResolveArgs {
            mode: SplatMode::Density,
            background: live.settings().draw.splat_background(),
            depth_cue: 0.0,
            shading: 0.0,
            occlusion: 0.0,
            point_radius_px: 1,
            near: 0.0,
            far: 1.0,
            pixel_size: 1.0,
            perspective: false,
            origin_px: [0, 0],
            tone,
            shadows: 0.0,
            key_light: [0.0, 0.0, 1.0],
            shadow: None,
            normal_radius_px: 1,
            pixel_area: 1.0,
            points_drawn: 0,
        };
        let mut resolve = GpuResolve::new(&ctx.device);
        let inline = nlifs::gpu::readback::draw_offscreen(&ctx, width, height, |encoder, target, format| {
            resolve.draw(&ctx, encoder, &game, &args, target, format, LightRows::Inline)
        })
        .unwrap();
        let mut differing = 0;
        for (a, b) in made.pixels().zip(inline.pixels()) {
            for c in 0..3 {
                assert!(a.0[c].abs_diff(b.0[c]) <= 1, "{backend:?}: {a:?} vs the resolve's filter {b:?}");
                differing += (a.0[c] != b.0[c]) as u32;
            }
        }
        assert!(differing * 100 < 3 * width * height, "{backend:?}: {differing} channels differ by one level");
        for frame in 0..3 {
            advance(&ctx, &mut live);
            assert_eq!(live.estimate_due(), EstimateDue::Keep, "{backend:?}: frame {frame}");
            assert!(draw(&mut live) == made, "{backend:?}: frame {frame} after the estimate");
        }
    }
}
