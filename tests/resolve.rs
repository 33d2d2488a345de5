//! The GPU resolve (`shaders/resolve.wgsl`, host side `src/gpu/resolve.rs`) against its CPU twin
//! (`src/resolve.rs`): the same accumulation goes through both, for every splat mode, every look
//! term (paper; lights only; occlusion only; the solid look; a half-strength mix) and point
//! radius 0, 1 and 2, and the 8-bit images must agree within the tolerance derived at
//! [`Tolerance`]; with the solid look the GPU's light cache (refreshed whole or in bands) must
//! give the inline light's bytes. Runs on any adapter (lavapipe in CI); without one it skips loudly,
//! unless NLIFS_REQUIRE_GPU=1, in which case it fails.

mod common;

use nlifs::camera::Projection;
use nlifs::chaos_game::{self, CompiledIfs, run_chunk};
use nlifs::gpu::GpuContext;
use nlifs::gpu::chaos_game::GpuChaosGame;
use nlifs::gpu::resolve::{GpuResolve, LightRows};
use nlifs::resolve::{
    DEPTH_SCALE, EMPTY, ResolveArgs, ResolveInputs, ResolveParams, ResolveStyle, Tone, max_count, resolve_fragment,
    resolve_fragment_perturbed,
};
use nlifs::scene::Scene;
use nlifs::scene::spec::{BlendSpace, DensityScale, SplatMode};
use nlifs::splat::{Framebuffer, SplatView};

use common::gpu;

/// One accumulation in the GPU's layout with what the resolve needs to draw it.
struct Accumulation {
    name: String,
    width: u32,
    height: u32,
    words: Vec<u32>,
    colors: Vec<[f32; 3]>,
    /// The arguments with the style left at its default.
    args: ResolveArgs,
    /// The key light's shadow map (closest mode of plant2; empty otherwise).
    shadow: Vec<u32>,
}

/// A CPU framebuffer of plant2 (a 3D point set, so the shading has slopes in every direction)
/// in `mode`, seen by the scene's camera.
fn plant2(mode: SplatMode) -> Accumulation {
    let path = format!("{}/scenes/plant2.toml", env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
    let bounds = chaos_game::attractor_bounds(&compiled, 1);
    let camera = scene.camera_for(bounds);
    assert_eq!(camera.projection, Projection::Perspective);
    let (width, height) = (160, 120);
    let view = SplatView::new(&camera, width, height, bounds, mode, 0.6, [0.05, 0.04, 0.03]);
    // The solid look's shadow map (closest mode only), of the default key light.
    let view = view.with_shadow(&camera, bounds, ResolveStyle::SOLID.key_light());
    let mut fb = Framebuffer::new(view, compiled.colors.clone());
    for chunk in 0..512 {
        run_chunk(&compiled, 7, 0, chunk, 8, &mut fb);
    }
    assert!(fb.covered_pixels() > 1200, "{mode:?}: {} pixels covered", fb.covered_pixels());
    let inputs = ResolveInputs::of(&fb);
    Accumulation {
        name: format!("plant2 {}", mode.name()),
        width,
        height,
        words: inputs.accum.to_vec(),
        colors: fb.colors.clone(),
        args: ResolveArgs::new(&fb.view, &camera, &ResolveStyle::default())
            .drawn(512 * 8 * chaos_game::ORBITS_PER_CHUNK as u64),
        shadow: fb.shadow.clone(),
    }
}

/// A closest-mode depth field with known slopes: a plane tilted along x and y, a paraboloid bump
/// (slopes in every direction), a sharp step (a silhouette) and a roof (a crease, with exact
/// depth ties along its crest), three functions, with holes on a lattice (for the radius to
/// fill) and an empty border.
fn depth_field(perspective: bool) -> Accumulation {
    let (width, height) = (96u32, 72u32);
    let mut words = vec![EMPTY; (width * height) as usize];
    for y in 4..height - 4 {
        for x in 4..width - 4 {
            if x % 7 == 3 && y % 5 == 2 {
                continue;
            }
            let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
            let bump = 0.25 - ((u - 0.4).powi(2) + (v - 0.5).powi(2)) * 2.0;
            // Right of u = 0.75, a step towards the viewer and a roof with its crest on column 84.
            let roof = 0.002 * (x as f32 - 84.0).abs();
            let t = if u > 0.75 { 0.1 + 0.3 * v + roof } else { 0.35 + 0.3 * u + 0.2 * v - bump.max(0.0) };
            let depth = (t.clamp(0.0, 1.0) * DEPTH_SCALE) as u32;
            words[(y * width + x) as usize] = depth << 8 | (x * 3 / width);
        }
    }
    let (pixel_size, near, far) = if perspective { (0.012, 4.0, 6.0) } else { (0.02, 1.0, 3.0) };
    Accumulation {
        name: format!("depth field ({})", if perspective { "perspective" } else { "parallel" }),
        width,
        height,
        words,
        colors: vec![[0.8, 0.3, 0.1], [0.2, 0.7, 0.3], [0.02, 0.05, 0.9]],
        args: ResolveArgs {
            mode: SplatMode::Closest,
            background: [0.01, 0.01, 0.02],
            depth_cue: 0.5,
            shading: 0.0,
            occlusion: 0.0,
            point_radius_px: 0,
            near,
            far,
            pixel_size,
            perspective,
            origin_px: [0, 0],
            tone: Tone::NEUTRAL,
            shadows: 0.0,
            key_light: nlifs::resolve::KEY_LIGHT,
            shadow: None,
            normal_radius_px: nlifs::resolve::NORMAL_RADIUS_PX,
            pixel_area: pixel_size * pixel_size,
            points_drawn: 0,
        },
        shadow: Vec::new(),
    }
}

/// The GPU side: one resolve (its pipelines made once) drawing accumulation after accumulation.
struct Gpu {
    ctx: GpuContext,
    resolve: GpuResolve,
    draws: u64,
}

impl Gpu {
    /// The GPU resolve of `acc` with `args` into an RGBA8 unorm target (the format `render
    /// --backend gpu` reads back) of the accumulation's size grown by `args.origin_px`.
    fn image(&mut self, acc: &Accumulation, args: &ResolveArgs, light: LightRows) -> image::RgbImage {
        let ctx = &self.ctx;
        let mut game = GpuChaosGame::new(&ctx.device, 1, acc.width, acc.height);
        ctx.queue.write_buffer(&game.accum, 0, bytemuck::cast_slice(&acc.words));
        let colors: Vec<[f32; 4]> = acc.colors.iter().map(|c| [c[0], c[1], c[2], 0.0]).collect();
        ctx.queue.write_buffer(&game.colors, 0, bytemuck::cast_slice(&colors));
        if let Some(shadow) = &args.shadow {
            game.fit_shadow(&ctx.device, Some(shadow));
            ctx.queue.write_buffer(&game.shadow, 0, bytemuck::cast_slice(&acc.shadow));
        }
        // A new accumulation buffer each draw: a new generation, so that the resolve rebinds.
        self.draws += 1;
        game.generation = self.draws;
        let (width, height) = (acc.width + args.origin_px[0], acc.height + args.origin_px[1]);
        // The library's offscreen target and readback (RGBA8, rows padded), as the live view uses.
        nlifs::gpu::readback::draw_offscreen(ctx, width, height, |encoder, target, format| {
            self.resolve.draw(ctx, encoder, &game, args, target, format, light)
        })
        .unwrap()
    }
}

/// How far the GPU's 8-bit image may be from the CPU twin's. u = 2^-24 is the unit roundoff
/// of f32; the CPU twin's operations are correctly rounded, WGSL's within its stated ULP (2.5
/// for a division, inverseSqrt-based normalize 2 + ½ per operation, and a GPU may fuse a
/// multiply-add, which changes a result by ≤ ½ ULP of the product).
///
/// Flat pixels (paper, average, density; everything but the solid look's light):
/// 1. Key depths: t = (key >> 8) / 16777215 is off by ≤ 2.5 ULP ≤ 2.5 · 2^-24 of the depth
///    range; the depth cue (a convex blend with the background by t · cue) moves by as much:
///    a relative error of the linear colour c below 2^-20.
/// 2. The other operations (the colour divisions at 2.5 ULP, density's logs at 3 ULP, the
///    absolute density's log(1 + x): a series below x = 1/8, log(1 + x) at ≤ 2^-17.9 relative
///    above; the convex blends): a relative error ρ_ops below 2^-16 of c, generously.
/// 3. The sRGB encode: its slope times its argument, s'(c) · c, is ≤ 1.055 / 2.4 on [0, 1]
///    (≤ 12.92 · 0.0031308 on the linear segment), so a relative error ρ of c moves the encoded
///    value by ≤ 0.44 ρ; WGSL's pow (exp2 of y · log2 x) adds ≤ 2e-6 of the value.
///    So the encoded value is off by E = 255 · (0.44 · ρ_ops + 1.055 · 2e-6) levels, E ≪ 1.
///
/// Lit pixels (shading or occlusion > 0):
/// 4. The plane fit's moments are sums of ≤ 25 terms w · (offset or depth products), each with
///    ≤ 8 operations (two divisions among them): each moment is off by ≤ γ = 64 u of the sum of
///    its terms' magnitudes. Those sums are bounded whatever the depths: Σw ≤ 25, Σw|dx| ≤ 30,
///    Σw dx² ≤ 50, and w · |z| ≤ SLOPE_SCALE · r / 2 (the weight falls as 1 / z²), so
///    Σw |dx| |z| ≤ Σ r² = 100 and |Σw dx · Σw z| / Σw ≤ 2 · 47. The covariances are then off
///    by ≤ 2 · 50 γ (offsets) and ≤ 200 γ (with depth).
/// 5. The slopes solve (C + RIDGE · I) s = b, whose matrix has eigenvalues in [RIDGE, 51]
///    (RIDGE = 1): ‖δs‖ ≤ (‖δb‖ + ‖δC‖ ‖s‖) / RIDGE plus Cramer's rule's own rounding, whose
///    determinant and numerators lose ≤ 8 u · 51 to cancellation. So each slope is off by
///    ≤ [`SLOPE_ABS`] + [`SLOPE_REL`] · |s| (≈ 283 γ and 100 γ + 408 u, rounded up to powers of
///    two); the clamp to ±SLOPE_MAX does not add to it. The depth scale (footprints per key
///    unit, ≤ 4 operations) scales every z alike, by ≤ 8 u, which the slope's relative term
///    covers; in the occlusion samples it moves an elevation e by ≤ 8 u · |z| / 3 ≤ 2e-5 where
///    e matters (|z| ≤ 80 there; beyond, the falloff leaves < 1e-3 of the sample).
/// 6. The colour as a function of the slopes is what [`resolve_fragment_perturbed`] computes:
///    the test evaluates the CPU twin at the fitted slopes moved by ± that bound on each axis
///    (the four corners; over so small a box the colour is monotone along each axis but at the
///    highlight's crest, where its slope is near zero) and takes the encoded range they span.
/// 7. The remaining operations of the light (normalize, dot products, the squarings of the
///    highlight, 16 occlusion samples, the blend by `shading` and `occlusion`) are off by
///    ≤ 2^-14 of c relative (as 2. with more operations) plus ≤ 2^-18 absolute where the
///    occlusion takes nearly all light (1 − occlusion · ao cancels); the absolute part moves
///    the encoded value by ≤ 12.92 · 2^-18 (the encode's steepest slope).
///
///
/// Toned pixels (average and density modes with a tone other than the neutral one):
/// 8. The tone map's powers (WGSL's pow is exp2 of y · log2 x: log2 off by ≤ 3 ULP of its
///    value, ≤ 2^-19.4 absolute for x ≥ 0.01, times |y| ≤ 3 for the exponents tested, then
///    exp2's 3 ULP) are off by ≤ 2^-16 relative, the ramp and the highlight's divisions add a few
///    ULP: ρ ≤ 2^-14 of c relative, generously; the vibrancy term t^g − c · α cancels, which
///    adds ≤ 2^-18 absolute (terms ≤ 4, 2^-20 each). E as in 7.
///
/// Filtered pixels (average and density modes with flam3's spatial filter, of non-negative
/// weights):
/// 10. Each of the ≤ N² terms (N ≤ 15 taps a side) is a0 · (w_y · w_x) times the colour: item
///    2's relative error of a0 and the colour, and ≤ 3 u of its own products; the running sums
///    of non-negative terms round by ≤ u of themselves at each of the ≤ N² additions (a fused
///    multiply-add only lessens that). So the sums are off by ≤ 2^-16 + (N² + 3) u ≤ 2^-15
///    relative, and the colour (their quotient, 2.5 ULP more) and the density by ≤ 2^-13.9:
///    ρ ≤ 2^-13 of c relative, generously, before the tone map's item 8. E as in 7.
///
/// Shadows (closest mode with a shadow map):
/// 9. Each PCF tap compares the receiver's depth in the map with a texel's: where the two are
///    closer than the receiver's float error, GPU and CPU may decide the tap differently. The
///    receiver's depth error is bounded at [`shadow_depth_error`]; the test evaluates the CPU
///    twin with the receiver moved by ± that bound (a shift of the matrix's depth translation),
///    together with the slope corners of 6. (the normal enters the receiver plane and the
///    bias), and widens lo..hi to what they span.
///
/// A GPU channel must lie within the rounding of [lo − E, hi + E], lo..hi the range of 6. (a
/// single value for flat pixels) and E from 3. or 7.: where that interval does not reach a
/// rounding boundary (k + ½ levels) the GPU must give the CPU's byte.
struct Tolerance {
    /// E: the float error of an encoded channel beyond the slopes, in 8-bit levels.
    levels: f32,
}

/// Item 9 of [`Tolerance`]: the bound on the GPU's error in the receiver's depth fraction in the
/// shadow map. That depth is a 4-term dot product of the shadow matrix's depth row with the
/// view-space position (itself off by ≤ 8 u relative: the key depth's division, the ray's
/// products), plus the receiver-plane and bias terms (a few operations on values ≤ 2 · 4 texels
/// of depth, off by ≤ 16 u of that). Each term is off by ≤ 16 u of its magnitude, so the sum is
/// off by ≤ 16 u · Σ|terms|, with |x|, |y| ≤ |z| · (half the image in footprints) and |z| ≤ far.
/// Doubled for the comparison's other side (the map key's depth fraction, 2.5 ULP).
fn shadow_depth_error(p: &ResolveParams) -> f32 {
    let u = 2f32.powi(-24);
    let m = p.shadow_from_view;
    let half_extent = 0.5 * p.width.max(p.height) as f32 * p.pixel_size * if p.perspective != 0 { 1.0 } else { 0.0 };
    let lateral = p.far * half_extent.max(1.0);
    let terms = (m[0][2].abs() + m[1][2].abs()) * lateral + m[2][2].abs() * p.far + m[3][2].abs();
    let receiver_plane = 2.0 * 4.0 * p.shadow_texel_world * p.shadow_inv_depth_world * 4.0;
    2.0 * 16.0 * u * (terms + receiver_plane + 1.0)
}

/// Slope error bounds of item 5 of [`Tolerance`] (slopes in footprints per pixel).
const SLOPE_ABS: f32 = 1.0 / 512.0;
const SLOPE_REL: f32 = 1.0 / 2048.0;

impl Tolerance {
    fn of(p: &ResolveParams) -> Self {
        let lit = p.mode == 0 && (p.shading > 0.0 || p.occlusion > 0.0);
        let toned =
            p.mode != 0 && (p.brightness != 1.0 || p.inv_gamma != 1.0 || p.vibrancy != 1.0 || p.highlight_power >= 0.0);
        let (mut relative, absolute) =
            if lit || toned { (2f32.powi(-14), 2f32.powi(-18)) } else { (2f32.powi(-16), 0.0) };
        if p.mode != 0 && p.filter_taps > 0 {
            relative += 2f32.powi(-13);
        }
        Self { levels: 255.0 * (1.055 / 2.4 * relative + 12.92 * absolute + 1.055 * 2e-6) }
    }
}

/// Compares the GPU resolve of `acc` with `args` to the CPU twin's fragments, panicking with the
/// first channel outside the tolerance; returns the largest difference in levels.
fn compare(gpu: &mut Gpu, acc: &Accumulation, args: &ResolveArgs) -> u8 {
    let p = args.params(acc.width, acc.height, true);
    let max =
        if args.mode == SplatMode::Density { max_count(&acc.words, (acc.width * acc.height) as usize) } else { 0 };
    let inputs = ResolveInputs { accum: &acc.words, colors: &acc.colors, max_count: max, shadow: &acc.shadow };
    // Item 9 of [`Tolerance`]: the receiver's depth in the shadow map moved by ± its bound.
    let shadow_depth_error = shadow_depth_error(&p);
    let moved = |delta: f32| {
        let mut moved = p;
        moved.shadow_from_view[3][2] += delta;
        moved
    };
    let (p_nearer, p_farther) = (moved(-shadow_depth_error), moved(shadow_depth_error));
    let tolerance = Tolerance::of(&p);
    assert!(tolerance.levels < 0.1, "{}: the derived tolerance {} levels is too loose", acc.name, tolerance.levels);
    let lit = p.mode == 0 && (p.shading > 0.0 || p.occlusion > 0.0);
    let image = gpu.image(acc, args, LightRows::Inline);
    if lit {
        // The light cache (the live view's) gives the same bytes once every row is refreshed,
        // in one draw or in bands over several draws of the same accumulation.
        let h = acc.height;
        let whole = gpu.image(acc, args, LightRows::Refresh { start: 0, end: h });
        assert!(whole == image, "{}: light cache refreshed whole differs from the inline light", acc.name);
        gpu.image(acc, args, LightRows::Refresh { start: 0, end: h / 3 });
        let banded = gpu.image(acc, args, LightRows::Refresh { start: h / 3, end: h });
        assert!(banded == image, "{}: light cache refreshed in bands differs from the inline light", acc.name);
    }
    let [ox, oy] = args.origin_px;
    // Outside the accumulation's rectangle the target is cleared to black.
    for (x, y, px) in image.enumerate_pixels() {
        if x < ox || y < oy {
            assert_eq!(px.0, [0, 0, 0], "{}: pixel ({x}, {y}) outside the drawn rectangle", acc.name);
        }
    }
    let levels = |c: [f32; 3]| c.map(|v| v.clamp(0.0, 1.0) * 255.0);
    let (mut differing, mut max_diff, mut widest) = (0, 0u8, 0.0f32);
    for y in 0..acc.height {
        for x in 0..acc.width {
            let exact = levels(resolve_fragment(&p, &inputs, x, y));
            let (mut lo, mut hi) = (exact, exact);
            if lit {
                let cpu_slopes = |offset| levels(resolve_fragment_perturbed(&p, &inputs, x, y, offset));
                // Item 5's bound at |s| = SLOPE_MAX, the largest it gets.
                let d = SLOPE_ABS + SLOPE_REL * nlifs::resolve::SLOPE_MAX;
                for offset in [(-d, -d), (-d, d), (d, -d), (d, d)] {
                    let v = cpu_slopes(offset);
                    for c in 0..3 {
                        lo[c] = lo[c].min(v[c]);
                        hi[c] = hi[c].max(v[c]);
                    }
                }
                if p.shadows > 0.0 {
                    for q in [&p_nearer, &p_farther] {
                        for offset in [(0.0, 0.0), (-d, -d), (-d, d), (d, -d), (d, d)] {
                            let v = levels(resolve_fragment_perturbed(q, &inputs, x, y, offset));
                            for c in 0..3 {
                                lo[c] = lo[c].min(v[c]);
                                hi[c] = hi[c].max(v[c]);
                            }
                        }
                    }
                }
            }
            let gpu_px = image.get_pixel(x + ox, y + oy).0;
            for c in 0..3 {
                let (low, high) = (lo[c] - tolerance.levels, hi[c] + tolerance.levels);
                widest = widest.max(high - low);
                let cpu = (exact[c] + 0.5) as u8;
                let allowed = ((low.max(0.0) + 0.5) as u8)..=((high.min(255.0) + 0.5) as u8);
                if gpu_px[c] != cpu {
                    differing += 1;
                    max_diff = max_diff.max(gpu_px[c].abs_diff(cpu));
                }
                assert!(
                    allowed.contains(&gpu_px[c]),
                    "{}, shading {}, occlusion {}, shadows {}, radius {}: pixel ({x}, {y}) channel {c}: GPU {} vs \
                     CPU {cpu} (exact {:.4} levels; the tolerance allows {allowed:?})",
                    acc.name,
                    p.shading,
                    p.occlusion,
                    p.shadows,
                    p.point_radius_px,
                    gpu_px[c],
                    exact[c],
                );
            }
        }
    }
    eprintln!(
        "{}, shading {} (drawn {}), occlusion {} (drawn {}), shadows {} (drawn {}), radius {} (drawn {}), {:?}: \
         {differing} channels differ, by ≤ {max_diff} levels; widest allowed interval {widest:.3} levels",
        acc.name,
        args.shading,
        p.shading,
        args.occlusion,
        p.occlusion,
        args.shadows,
        p.shadows,
        args.point_radius_px,
        p.point_radius_px,
        args.tone,
    );
    max_diff
}

#[test]
fn resolve_matches_cpu() {
    let Some(ctx) = gpu() else { return };
    let mut gpu = Gpu { resolve: GpuResolve::new(&ctx.device), ctx, draws: 0 };
    let mut accumulations: Vec<Accumulation> = SplatMode::ALL.into_iter().map(plant2).collect();
    accumulations.push(depth_field(true));
    accumulations.push(depth_field(false));
    let styles = [
        ResolveStyle::PAPER,
        ResolveStyle { shading: 1.0, ..ResolveStyle::PAPER },
        ResolveStyle { occlusion: 1.0, ..ResolveStyle::PAPER },
        ResolveStyle::SOLID,
        ResolveStyle { shading: 0.5, occlusion: 0.5, ..ResolveStyle::PAPER },
        // Shadows alone at full strength (only plant2's closest accumulation has a map).
        ResolveStyle { shading: 1.0, shadows: 1.0, ..ResolveStyle::PAPER },
    ];
    for acc in &accumulations {
        for style in styles {
            for point_radius_px in [0, 1, 2] {
                let args = ResolveArgs {
                    shading: style.shading,
                    occlusion: style.occlusion,
                    point_radius_px,
                    shadows: style.shadows,
                    ..acc.args
                };
                compare(&mut gpu, acc, &args);
            }
        }
    }
    // flam3's tone controls on the average and density accumulations: a brighter gamma with
    // the default threshold, a wide linear ramp with per-channel gamma, half vibrancy with
    // highlights fading to white, and a darker exposure with a gamma below 1 keeping the hue.
    let tones = [
        Tone { exposure: 1.0, gamma: 2.2, ..Tone::NEUTRAL },
        Tone { exposure: 0.5, gamma: 3.0, gamma_threshold: 0.2, vibrancy: 0.0, ..Tone::NEUTRAL },
        Tone { exposure: 2.0, gamma: 1.5, vibrancy: 0.5, highlight_power: 1.0, ..Tone::NEUTRAL },
        Tone { exposure: -1.0, gamma: 0.5, highlight_power: 0.0, ..Tone::NEUTRAL },
    ];
    for acc in accumulations.iter().filter(|a| a.args.mode != SplatMode::Closest) {
        for tone in tones {
            compare(&mut gpu, acc, &ResolveArgs { tone, ..acc.args });
        }
    }
    // A draw placed off the target's origin (the viewer draws right of its side panel) reads the
    // same accumulation pixels.
    let field = &accumulations[3];
    compare(
        &mut gpu,
        field,
        &ResolveArgs { shading: 0.7, occlusion: 0.6, point_radius_px: 1, origin_px: [5, 3], ..field.args },
    );
    // The live view's smaller plane fit while navigating (3×3 keys instead of 5×5).
    for acc in accumulations.iter().filter(|a| a.args.mode == SplatMode::Closest) {
        let navigating = nlifs::resolve::NAVIGATING_NORMAL_RADIUS_PX;
        compare(&mut gpu, acc, &ResolveArgs { shading: 1.0, normal_radius_px: navigating, ..acc.args });
    }
}

/// flam3's spatial filter (`FILTER_TAPS` > 0: `filtered` in `shaders/resolve.wgsl` against
/// `filter::gather`) on plant2's average and density accumulations: Gaussians of 3, 5 and 7
/// taps, a bell, and one under a tone. Tolerance: item 10 of [`Tolerance`] (and 8).
#[test]
fn spatial_filter_matches_cpu() {
    use nlifs::flame::FilterShape;
    use nlifs::scene::spec::PixelFilter;
    let Some(ctx) = gpu() else { return };
    let mut gpu = Gpu { resolve: GpuResolve::new(&ctx.device), ctx, draws: 0 };
    let filter = |radius_px, shape| Some(PixelFilter { radius_px, shape });
    let tones = [
        Tone { filter: filter(0.5, FilterShape::Gaussian), ..Tone::NEUTRAL },
        Tone { filter: filter(1.0, FilterShape::Gaussian), ..Tone::NEUTRAL },
        Tone { filter: filter(2.0, FilterShape::Gaussian), density_scale: DensityScale::Absolute, ..Tone::NEUTRAL },
        Tone { filter: filter(1.0, FilterShape::Bell), ..Tone::NEUTRAL },
        Tone {
            exposure: 1.0,
            gamma: 2.2,
            highlight_power: 1.0,
            filter: filter(0.8, FilterShape::Gaussian),
            ..Tone::NEUTRAL
        },
    ];
    for mode in [SplatMode::Average, SplatMode::Density] {
        let acc = plant2(mode);
        for tone in tones {
            let args = ResolveArgs { tone, ..acc.args };
            assert!(args.params(acc.width, acc.height, true).filter_taps >= 3, "{tone:?}: the filter is off");
            compare(&mut gpu, &acc, &args);
        }
    }
}

/// Every combination of flam3's tone settings on the average and density accumulations:
/// exposure 0 and 1.5 stops; gamma 1, and 2.2 with a wide linear threshold (0.05); vibrancy 0
/// and 1; highlight power off (−1), 0 (hue kept) and 2 (towards white); density relative and
/// absolute (density mode); mixed and toned in linear light and in sRGB values (`blend_space`;
/// the sRGB result goes to the target without the encode, so within the same tolerance).
/// Tolerance: item 8 of [`Tolerance`] (the exponents are ≤ 2, within its |y| ≤ 3).
#[test]
fn every_tone_setting_matches_cpu() {
    let Some(ctx) = gpu() else { return };
    let mut gpu = Gpu { resolve: GpuResolve::new(&ctx.device), ctx, draws: 0 };
    for mode in [SplatMode::Average, SplatMode::Density] {
        let acc = plant2(mode);
        for exposure in [0.0, 1.5] {
            for (gamma, gamma_threshold) in [(1.0, Tone::NEUTRAL.gamma_threshold), (2.2, 0.05)] {
                for vibrancy in [0.0, 1.0] {
                    for highlight_power in [-1.0, 0.0, 2.0] {
                        for (density_scale, blend) in
                            DensityScale::ALL.into_iter().flat_map(|d| BlendSpace::ALL.map(|b| (d, b)))
                        {
                            let tone = Tone {
                                exposure,
                                gamma,
                                gamma_threshold,
                                vibrancy,
                                highlight_power,
                                density_scale,
                                filter: None,
                                blend,
                            };
                            compare(&mut gpu, &acc, &ResolveArgs { tone, ..acc.args });
                        }
                    }
                }
            }
        }
    }
}

/// Colours mixed in sRGB values (`blend_space = "srgb"`, imported flames) reach an sRGB target
/// (the viewer's surface) decoded, so that the target's encode gives back the values: its
/// bytes are the unorm target's within a level (the decode and encode round trip in f32 and
/// the target's rounding), and the CPU twin's linear output, encoded, is those bytes too.
#[test]
fn srgb_blend_reaches_an_srgb_target_unchanged() {
    let Some(ctx) = gpu() else { return };
    let mut gpu = Gpu { resolve: GpuResolve::new(&ctx.device), ctx, draws: 0 };
    let acc = plant2(SplatMode::Density);
    let tone = Tone { exposure: 1.0, gamma: 4.0, vibrancy: 0.3, blend: BlendSpace::Srgb, ..Tone::NEUTRAL };
    let args = ResolveArgs { tone, ..acc.args };
    let unorm = gpu.image(&acc, &args, LightRows::Inline);
    let mut game = GpuChaosGame::new(&gpu.ctx.device, 1, acc.width, acc.height);
    gpu.ctx.queue.write_buffer(&game.accum, 0, bytemuck::cast_slice(&acc.words));
    game.generation = 1_000_000;
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let srgb =
        nlifs::gpu::readback::draw_offscreen_as(&gpu.ctx, acc.width, acc.height, format, |encoder, target, f| {
            gpu.resolve.draw(&gpu.ctx, encoder, &game, &args, target, f, LightRows::Inline)
        })
        .unwrap();
    let linear = args.params(acc.width, acc.height, false);
    let max = max_count(&acc.words, (acc.width * acc.height) as usize);
    let inputs = ResolveInputs { accum: &acc.words, colors: &acc.colors, max_count: max, shadow: &acc.shadow };
    let (mut lit, mut worst) = (0, 0u8);
    let corner = unorm.get_pixel(0, 0).0;
    for (x, y, px) in srgb.enumerate_pixels() {
        let plain = unorm.get_pixel(x, y).0;
        let cpu = resolve_fragment(&linear, &inputs, x, y).map(nlifs::color::linear_to_srgb8);
        for c in 0..3 {
            worst = worst.max(px.0[c].abs_diff(plain[c])).max(cpu[c].abs_diff(plain[c]));
        }
        lit += usize::from(plain != corner);
    }
    assert!(lit > 1000, "too few lit pixels ({lit}) to say anything");
    assert!(worst <= 1, "an sRGB target or the linear output is {worst} levels from the unorm target's bytes");
}

/// The viewer's density-estimated resolve (`resolve_estimated` in
/// `shaders/density_estimation.wgsl`, after the GPU's estimate) against the CPU twin's
/// (`Estimated::fragment` of `estimate`), on plant2's density accumulation, neutral and toned.
/// Tolerance: the estimated sums differ by a relative β (`summation_bound` in
/// tests/density_estimation_gpu.rs: 2 γ_N, N ≤ 4 (2r + 1)² + 2 terms, here r = 4, so
/// β ≈ 3.9e-5); the average colour s / n moves by ≤ 2β relative, the density ln(1 + s) /
/// ln(1 + max) by ≤ 2β relative (ln(1 + s(1 + β)) − ln(1 + s) ≤ β · s / (1 + s) ≤ β ln(1 + s)
/// for s ≤ 1, and ≤ β ≪ β ln(1 + s) · 3 above), the absolute density ln(1 + k s) by ≤ β
/// relative (k s / (1 + k s) ≤ ln(1 + k s)), and the tone map multiplies relative errors by
/// at most 2 + g + 2 h (the colour times the gamma'd alpha; the highlight's (1 / mα)^h): a
/// relative error ≤ (6 + 2 · 2) · 2β of the linear colour, added to item 8's; E as in 3.
/// That is under a quarter level: the GPU must give the CPU's byte wherever the exact value
/// lies farther than that from a rounding boundary.
#[test]
fn density_estimation_resolve_matches_cpu() {
    use nlifs::gpu::density_estimation::GpuDensityEstimation;
    use nlifs::resolve::density_estimation::estimate;
    use nlifs::scene::spec::DensityEstimation;
    let Some(ctx) = gpu() else { return };
    let acc = plant2(SplatMode::Density);
    let (w, h) = (acc.width, acc.height);
    let accum: Vec<[u32; 4]> = bytemuck::cast_slice(&acc.words).to_vec();
    let de = DensityEstimation { max_radius_px: 4.0, min_radius_px: 0.0, curve: 0.4 };
    let cpu = estimate(&accum, w, h, &de);
    let mut game = GpuChaosGame::new(&ctx.device, 1, w, h);
    ctx.queue.write_buffer(&game.accum, 0, bytemuck::cast_slice(&acc.words));
    game.generation = 1;
    let mut estimation = GpuDensityEstimation::new(&ctx.device);
    let n = (4 * (2 * 4 + 1) * (2 * 4 + 1) + 2) as f32;
    let u = 2f32.powi(-24);
    let beta = 2.0 * n * u / (1.0 - n * u);
    let tones = [
        Tone::NEUTRAL,
        Tone { exposure: 1.0, gamma: 2.2, vibrancy: 0.5, highlight_power: 2.0, ..Tone::NEUTRAL },
        Tone { exposure: 2.0, gamma: 1.8, density_scale: DensityScale::Absolute, ..Tone::NEUTRAL },
        // Mixed and toned in sRGB values, as an imported flame.
        Tone {
            exposure: 1.0,
            gamma: 4.0,
            vibrancy: 0.3,
            density_scale: DensityScale::Absolute,
            blend: BlendSpace::Srgb,
            ..Tone::NEUTRAL
        },
        // flam3's spatial filter over the estimate (`filtered_estimate`).
        Tone {
            exposure: 1.0,
            filter: Some(nlifs::scene::spec::PixelFilter {
                radius_px: 1.0,
                shape: nlifs::flame::FilterShape::Gaussian,
            }),
            ..Tone::NEUTRAL
        },
    ];
    for tone in tones {
        let args = ResolveArgs { tone, ..acc.args };
        let image = nlifs::gpu::readback::draw_offscreen(&ctx, w, h, |encoder, target, format| {
            estimation.encode(&ctx, encoder, &game.accum, w, h, &de);
            estimation.draw(&ctx, encoder, &args, target, format)
        })
        .unwrap();
        let p = args.params(w, h, true);
        let levels = Tolerance::of(&p).levels + 255.0 * 1.055 / 2.4 * (10.0 * 2.0 * beta);
        assert!(levels < 0.25, "the derived tolerance {levels} levels is too loose");
        let (mut differing, mut spread) = (0, 0);
        for (x, y, px) in image.enumerate_pixels() {
            let exact = cpu.fragment(&p, x, y).map(|v| v.clamp(0.0, 1.0) * 255.0);
            for (c, (&e, &g)) in exact.iter().zip(&px.0).enumerate() {
                let allowed = ((e - levels).max(0.0) + 0.5) as u8..=((e + levels).min(255.0) + 0.5) as u8;
                assert!(
                    allowed.contains(&g),
                    "{tone:?}: pixel ({x}, {y}) channel {c}: GPU {g} vs CPU {e:.3} levels (allowed {allowed:?})",
                );
                differing += (g != (e + 0.5) as u8) as u32;
            }
            let i = (y * w + x) as usize;
            spread += (accum[i][3] == 0 && cpu.sums[i][3] > 0.0) as u32;
        }
        assert!(spread > 100, "the estimate spread into only {spread} empty pixels");
        eprintln!("density estimation {de:?}, {tone:?}: {differing} channels differ by one level");
    }
}
