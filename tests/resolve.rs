//! The GPU resolve (`shaders/resolve.wgsl`, host side `src/gpu/resolve.rs`) against its CPU twin
//! (`src/resolve.rs`): the same accumulation goes through both, for every splat mode, shading
//! off and on and point radius 0, 1 and 2, and the 8-bit images must agree within the tolerance
//! derived at [`Tolerance`]. Runs on any adapter (lavapipe in CI); without one it skips loudly,
//! unless NLIFS_REQUIRE_GPU=1, in which case it fails.

use nlifs::camera::Projection;
use nlifs::chaos_game::{self, CompiledIfs, run_chunk};
use nlifs::gpu::GpuContext;
use nlifs::gpu::chaos_game::GpuChaosGame;
use nlifs::gpu::resolve::GpuResolve;
use nlifs::resolve::{
    DEPTH_SCALE, EMPTY, ResolveArgs, ResolveInputs, ResolveParams, ResolveStyle, max_count, resolve_fragment,
};
use nlifs::scene::Scene;
use nlifs::scene::spec::SplatMode;
use nlifs::splat::{Framebuffer, SplatView};

fn gpu() -> Option<GpuContext> {
    match GpuContext::headless() {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var("NLIFS_REQUIRE_GPU").as_deref() == Ok("1") => panic!("NLIFS_REQUIRE_GPU=1 but {e}"),
        Err(e) => {
            eprintln!("\n*** SKIPPING GPU TEST: {e} ***\n");
            None
        }
    }
}

/// One accumulation in the GPU's layout with what the resolve needs to draw it.
struct Accumulation {
    name: String,
    width: u32,
    height: u32,
    words: Vec<u32>,
    colors: Vec<[f32; 3]>,
    /// The arguments with the style left at its default.
    args: ResolveArgs,
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
        args: ResolveArgs::new(&fb.view, &camera, &ResolveStyle::default()),
    }
}

/// A closest-mode depth field with known slopes: a plane tilted along x and y, a paraboloid bump
/// (slopes in every direction), a sharp step (a silhouette) and a roof, three functions, with
/// holes on a lattice (for the radius to fill) and an empty border.
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
            // Right of u = 0.75, a step towards the viewer and a roof with its crest on column 84:
            // exact depth ties that the shading's comparisons must break (exempt pixels).
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
            point_radius_px: 0,
            near,
            far,
            pixel_size,
            perspective,
            origin_px: [0, 0],
        },
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
    fn image(&mut self, acc: &Accumulation, args: &ResolveArgs) -> image::RgbImage {
        let ctx = &self.ctx;
        let mut game = GpuChaosGame::new(&ctx.device, 1, acc.width, acc.height);
        ctx.queue.write_buffer(&game.accum, 0, bytemuck::cast_slice(&acc.words));
        let colors: Vec<[f32; 4]> = acc.colors.iter().map(|c| [c[0], c[1], c[2], 0.0]).collect();
        ctx.queue.write_buffer(&game.colors, 0, bytemuck::cast_slice(&colors));
        // A new accumulation buffer each draw: a new generation, so that the resolve rebinds.
        self.draws += 1;
        game.generation = self.draws;
        let (width, height) = (acc.width + args.origin_px[0], acc.height + args.origin_px[1]);
        // The library's offscreen target and readback (RGBA8, rows padded), as the live view uses.
        nlifs::gpu::readback::draw_offscreen(ctx, width, height, |encoder, target, format| {
            self.resolve.draw(ctx, encoder, &game, args, target, format)
        })
        .unwrap()
    }
}

/// How far the GPU's 8-bit image may be from the CPU twin's, derived from WGSL's accuracy rules
/// (the CPU twin's f32 operations are correctly rounded, 0.5 ULP, and count as exact here).
///
/// 1. Key depths. t = (key >> 8) / 16777215: WGSL's f32 division is within 2.5 ULP, and t ≤ 1
///    has an ULP of at most 2^-24, one key depth unit (1 / 16777215). So t is off by ≤ 2.5
///    units and a one-sided difference tr − t by ≤ 5.5 (½ for its own rounding). `shade`
///    compares |tr − t| with |tl − t| (and down with up): the two sides may choose differently
///    only where those magnitudes are within 2 · 5.5 = 11 units ([`TIE_UNITS`]). Where the two
///    one-sided differences then also differ by more than 2 · 11 units (a crest or a valley,
///    not a plane), the other choice is another normal and any colour: such pixels are exempt
///    and counted ([`ambiguous_pixels`]); they come from exact depth ties in the input, not
///    from either resolve, and are few. Elsewhere the depth differences the normals are made of
///    agree within 2 · 11 + 5.5 units, plus the rounding of the view depth
///    near + t · (far − near) (one ULP of `far` ≤ far · 2^-23 either way, whether or not the GPU
///    fuses the multiply-add).
/// 2. Normals. A depth difference off by Δ over a pixel footprint F (pixel_size · near at the
///    smallest in perspective, pixel_size in parallel projection) tilts the normal by ≤ Δ / F
///    radians, which moves the Lambert factor |cos| by as much and the shade factor
///    f = 0.25 + 0.75 · Lambert by ≤ 0.75 Δ / F. The linear colour c = cue(base · f, t) is a
///    convex combination of base · f and the background, so it moves by ≤ c · Δf / f ≤ 4 c Δf:
///    a relative error ρ_shade = 3 Δ / F.
/// 3. The other float operations of the fragment (view positions and their differences, whose
///    cancellation over ≤ width / 2 pixels costs ≤ 7 bits, cross, inverseSqrt-based normalize
///    at 2 ULP, the colour divisions at 2.5 ULP, density's log at 3 ULP, the convex cue and
///    density blends): a relative error ρ_ops below 2^-16 of c, generously.
/// 4. The sRGB encode. Its slope times its argument, s'(c) · c, is ≤ 1.055 / 2.4 on [0, 1]
///    (≤ 12.92 · 0.0031308 on the linear segment), so a relative error ρ of c moves the encoded
///    value by ≤ 0.44 ρ. WGSL's pow (via exp2(y · log2 x), log2 off by ≤ 3 ULP of |log2 x|
///    ≤ 8.4, exp2 by ≤ 3 + 2 · 3.5 ULP) adds ≤ 2e-6 of the value.
///
/// So the encoded value is off by E ≤ 255 · (0.44 · (ρ_shade + ρ_ops) + 1.055 · 2e-6) levels,
/// E ≪ 1 here. The target's float-to-unorm conversion rounds to nearest (which Vulkan asks of
/// implementations, and lavapipe does), so a channel may differ only where the CPU's exact
/// value lies within E of a rounding boundary (k + ½ levels), and then by one level: the
/// differing channels are a subset of those near-boundary channels.
struct Tolerance {
    /// E: the float error of an encoded channel, in 8-bit levels.
    levels: f32,
}

/// Depth units within which the two sides may order |tr − t| and |tl − t| differently.
const TIE_UNITS: i64 = 11;

impl Tolerance {
    fn of(p: &ResolveParams) -> Self {
        let unit = 2f32.powi(-24) * (p.far - p.near);
        let depth_error = (2 * TIE_UNITS) as f32 * unit + 5.5 * unit + p.far.abs() * 2f32.powi(-23);
        let footprint = if p.perspective != 0 { p.pixel_size * p.near } else { p.pixel_size };
        let rho_shade = if p.shading > 0.0 { 3.0 * depth_error / footprint } else { 0.0 };
        Self { levels: 255.0 * (1.055 / 2.4 * (rho_shade + 2f32.powi(-16)) + 1.055 * 2e-6) }
    }
}

/// Pixels whose shading the two sides may legitimately compute from different one-sided
/// differences (item 1 of [`Tolerance`]): any key within the point radius (the key the pixel
/// shows is one of them) has left and right (or down and up) depth differences of magnitudes
/// within [`TIE_UNITS`] that differ as differences by more than twice that.
fn ambiguous_pixels(acc: &Accumulation, p: &ResolveParams) -> Vec<bool> {
    let (w, h) = (p.width as i64, p.height as i64);
    let depth = |x: i64, y: i64| -> Option<i64> {
        let inside = x >= 0 && y >= 0 && x < w && y < h;
        let key = if inside { acc.words[(y * w + x) as usize] } else { EMPTY };
        (key != EMPTY).then_some((key >> 8) as i64)
    };
    let tie_at = |x: i64, y: i64| -> bool {
        let Some(d) = depth(x, y) else { return false };
        let tie = |a: Option<i64>, b: Option<i64>| {
            let (a, b) = (a.unwrap_or(d) - d, d - b.unwrap_or(d));
            (a.abs() - b.abs()).abs() <= TIE_UNITS && (a - b).abs() > 2 * TIE_UNITS
        };
        tie(depth(x + 1, y), depth(x - 1, y)) || tie(depth(x, y + 1), depth(x, y - 1))
    };
    let r = p.point_radius_px as i64;
    let mut out = vec![false; (w * h) as usize];
    if p.mode != 0 || p.shading <= 0.0 {
        return out;
    }
    for y in 0..h {
        for x in 0..w {
            out[(y * w + x) as usize] =
                (-r..=r).any(|dy| (-r..=r).any(|dx| dx * dx + dy * dy <= r * r && tie_at(x + dx, y + dy)));
        }
    }
    out
}

/// Compares the GPU resolve of `acc` with `args` to the CPU twin's fragments; returns the number
/// of pixels exempt for depth ties. Panics with the first channel outside the tolerance.
fn compare(gpu: &mut Gpu, acc: &Accumulation, args: &ResolveArgs) -> usize {
    let p = args.params(acc.width, acc.height, true);
    let max =
        if args.mode == SplatMode::Density { max_count(&acc.words, (acc.width * acc.height) as usize) } else { 0 };
    let inputs = ResolveInputs { accum: &acc.words, colors: &acc.colors, max_count: max };
    let tolerance = Tolerance::of(&p);
    assert!(tolerance.levels < 0.25, "{}: the derived tolerance {} levels is too loose", acc.name, tolerance.levels);
    let ambiguous = ambiguous_pixels(acc, &p);
    let exempt = ambiguous.iter().filter(|&&a| a).count();
    assert!(
        exempt * 10 <= ambiguous.len(),
        "{}: {exempt} pixels with depth ties, more than 10% of the input",
        acc.name
    );
    let image = gpu.image(acc, args);
    let [ox, oy] = args.origin_px;
    // Outside the accumulation's rectangle the target is cleared to black.
    for (x, y, px) in image.enumerate_pixels() {
        if x < ox || y < oy {
            assert_eq!(px.0, [0, 0, 0], "{}: pixel ({x}, {y}) outside the drawn rectangle", acc.name);
        }
    }
    let (mut differing, mut near_boundary, mut exempt_differing) = (0, 0, 0);
    for y in 0..acc.height {
        for x in 0..acc.width {
            let exact = resolve_fragment(&p, &inputs, x, y).map(|v| v.clamp(0.0, 1.0) * 255.0);
            let gpu = image.get_pixel(x + ox, y + oy).0;
            for c in 0..3 {
                let cpu = (exact[c] + 0.5) as u8;
                let near = ((exact[c] - exact[c].floor()) - 0.5).abs() <= tolerance.levels;
                near_boundary += near as usize;
                if gpu[c] == cpu {
                    continue;
                }
                if ambiguous[(y * acc.width + x) as usize] {
                    exempt_differing += 1;
                    continue;
                }
                differing += 1;
                assert!(
                    gpu[c].abs_diff(cpu) <= 1 && near,
                    "{}, shading {}, radius {}: pixel ({x}, {y}) channel {c}: GPU {} vs CPU {cpu} (exact {:.4} \
                     levels; the tolerance allows one level within {:.4} of a rounding boundary)",
                    acc.name,
                    p.shading,
                    p.point_radius_px,
                    gpu[c],
                    exact[c],
                    tolerance.levels
                );
            }
        }
    }
    eprintln!(
        "{}, shading {} (drawn {}), radius {} (drawn {}): {differing} channels differ by one level ({near_boundary} \
         within {:.4} levels of a boundary), {exempt_differing} differ in {exempt} pixels with depth ties",
        acc.name, args.shading, p.shading, args.point_radius_px, p.point_radius_px, tolerance.levels
    );
    exempt
}

#[test]
fn resolve_matches_cpu() {
    let Some(ctx) = gpu() else { return };
    let mut gpu = Gpu { resolve: GpuResolve::new(&ctx.device), ctx, draws: 0 };
    let mut accumulations: Vec<Accumulation> = SplatMode::ALL.into_iter().map(plant2).collect();
    accumulations.push(depth_field(true));
    accumulations.push(depth_field(false));
    for acc in &accumulations {
        for shading in [0.0, 1.0] {
            for point_radius_px in [0, 1, 2] {
                let exempt = compare(&mut gpu, acc, &ResolveArgs { shading, point_radius_px, ..acc.args });
                // The roof's crest is found (the exemption is not vacuous).
                if acc.name.starts_with("depth field") && shading > 0.0 {
                    assert!(exempt > 0, "{}: the roof's depth ties were not found", acc.name);
                }
            }
        }
    }
    // A draw placed off the target's origin (the viewer draws right of its side panel) reads the
    // same accumulation pixels.
    let field = &accumulations[3];
    compare(&mut gpu, field, &ResolveArgs { shading: 0.7, point_radius_px: 1, origin_px: [5, 3], ..field.args });
}
