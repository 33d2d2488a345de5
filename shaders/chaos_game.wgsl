// The chaos game on the GPU, twin of `src/chaos_game.rs` (the map, the function selection and
// the start point) fused with the splat, twin of `src/splat.rs` (`Framebuffer::consume`).
// Prepended with `rng.wgsl`, one of `ifs_tables_uniform.wgsl` / `ifs_tables_storage.wgsl` (the
// compiled IFS tables and their accessors) and the flame functions' xforms (`variations.wgsl`,
// `variations_basic.wgsl`, `variations_plugins.wgsl`) by `src/gpu/shaders.rs`.
//
// Every invocation owns one persistent point (xyz, w: the function that mapped it last, or with
// `PALETTE` its colour coordinate). Per
// frame it draws from stream (seed, frame, thread), advances `steps` times and splats every step
// from `skip_steps` on into the accumulation buffer: closest mode keeps the minimum of
// (depth24 << 8) | function per pixel, average and density modes add depth-cued colour × 255 and
// a count. Points are restarted at a random point of the domain on `restart` or when they have
// left the finite floats.

// Mirrors `KernelFunction` in src/chaos_game.rs: keep the two in sync.
struct KernelFunction {
    lo: vec4<f32>,
    hi: vec4<f32>,
    inv_bin: vec4<f32>,
    // xyz: cells per axis; w: first cell in the cell pool.
    cells: vec4<u32>,
    // xyz: offset of each axis in the coordinate pool; w: kind.
    coord_offset: vec4<u32>,
    julia: vec4<f32>,
}

// Mirrors `Cell` in src/chaos_game.rs.
struct Cell {
    coef: array<vec4<f32>, 8>,
}

// Mirrors `ChaosParams` in src/gpu/chaos_game.rs.
struct ChaosParams {
    // Rows: pixel x · w, pixel y · w, view distance, w (as `SplatView::pixel_from_world`).
    pixel_from_world: mat4x4<f32>,
    // rgb: linear background; w: depth cue.
    background: vec4<f32>,
    // xyz: domain box; w: near (lo) and far (hi) view distances.
    domain_lo: vec4<f32>,
    domain_hi: vec4<f32>,
    selection_lo: vec4<f32>,
    selection_inv_cell: vec4<f32>,
    // xyz: coarse selection cells per axis; w: function count.
    selection_cells: vec4<u32>,
    seed: u32,
    frame: u32,
    steps: u32,
    skip_steps: u32,
    point_count: u32,
    width: u32,
    height: u32,
    mode: u32,
    dimension: u32,
    restart: u32,
    threads_per_row: u32,
    // Shadows: the shadow map's side in texels, and its projection (rows: texel x, texel y,
    // depth fraction from the light, 1; `ShadowView::map_from_world` in src/splat/shadow.rs).
    shadow_side: u32,
    shadow_from_world: mat4x4<f32>,
    // Depth of field (`Lens::uniform` in src/splat/lens.rs): x: lens radius in pixels, y: 1 /
    // focus distance, z: 1 in perspective, 0 in parallel projection, w: the seed's bits.
    lens: vec4<f32>,
}

// Pipeline constants (src/gpu/chaos_game.rs makes one pipeline per splat mode and per IFS
// structure, `IfsShape`). As constants the compiler drops the branches not taken; a SIMD
// software rasterizer would otherwise run both sides (atomics and table loads included) for
// every lane. `params.mode` stays for the clear.
override SPLAT_MODE: u32 = 0u;
override HAS_JULIA: bool = true;
// Cells per axis when every function is a grid map on one shared grid (0: they are not, each
// function's own grid is read from its record). Then the cell search reads the coordinates of
// function 0 at indices known to the compiler (scalar loads instead of per-lane gathers on
// lavapipe), one-cell axes need no search at all, and function `fi`'s cells start at
// fi × cells per function, so the function record is not read.
override SHARED_CELLS_X: u32 = 0u;
override SHARED_CELLS_Y: u32 = 0u;
override SHARED_CELLS_Z: u32 = 0u;
// The number of functions (0: read it from the uniforms), and whether the selection table has
// a single coarse cell: then the threshold reads are at constant indices too.
override FUNCTION_COUNT: u32 = 0u;
override SINGLE_SELECTION_CELL: bool = false;
// Xaos (`SelectionTable::xaos`): the selection row is the orbit's previous function + 1 (0 at a
// (re)start) instead of its coarse cell; the stored point's w then holds 2·row + c (c: the
// colour coordinate with PALETTE, else 0).
override XAOS: bool = false;
// Every splatted point also goes into the key light's shadow map (`splat_shadow`); off, the
// shadow map is neither read nor written.
override SHADOWED: bool = false;
// Depth of field on (aperture > 0): false compiles the pinhole splat.
override LENS: bool = false;
// Colour by the colour coordinate (`[render] color = "palette"`): the points carry c ← (c + c_i)
// / 2 and splat the palette entry ⌊256 c⌋ (255 for c = 1; `palette_entry`), the colour table
// being the palette; false
// compiles to function colour.
override PALETTE: bool = false;
// flam3's linear palette interpolation, dithered by the drawn point (`palette_entry_linear`);
// false: the step (`palette_entry`).
override PALETTE_LINEAR: bool = false;
// The palette entry of colour coordinate c in [0, 1]: the twin of `palette::index_of`.
fn palette_entry(c: f32) -> u32 {
    return min(u32(i32(c * 256.0)), 255u);
}

// flam3's linear palette entry of colour coordinate c, dithered: the twin of
// `palette::index_linear`.
fn palette_entry_linear(c: f32, dither: u32) -> u32 {
    let t = c * 256.0;
    let i = i32(t);
    if i >= 255 {
        return 255u;
    }
    let lower = max(i, 0);
    let f = t - f32(lower);
    return u32(lower) + select(0u, 1u, f32(dither >> 8u) < f * 16777216.0);
}

// The dither of a point at (x, y) with coordinate c: the twin of `palette::dither_of`.
fn dither_of(x: f32, y: f32, c: f32) -> u32 {
    let yb = bitcast<u32>(y);
    let cb = bitcast<u32>(c);
    var h = bitcast<u32>(x) ^ ((yb << 11u) | (yb >> 21u)) ^ ((cb << 22u) | (cb >> 10u));
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    h *= 0x846ca68bu;
    return h ^ (h >> 16u);
}

// The colour coordinate at a (re)start, `C_START` in src/chaos_game/color_coord.rs.
const C_START: f32 = 0.5;
// Some function is a flame (`kind = "flame"`, src/chaos_game/flame.rs): the functions whose
// flame-table header is an xform map by `apply_xform`; false compiles the flames out.
override HAS_FLAMES: bool = false;
// Palette colour with flame colour speeds (`CompiledIfs::color_speeds`): c ← s·c_i + (1 − s)·c
// with each function's speed s from its flame-table header, as the CPU's `step_color_speed`.
override COLOR_SPEEDS: bool = false;
// A final xform (`CompiledIfs::has_final_xform`): its header follows the functions' in the
// flame table (index `function_count()`), then a record of its opacity (`weight`); it maps each
// drawn point and its colour, not the orbit, with that chance.
override HAS_FINAL: bool = false;
// flam3's limit of a coordinate in the plane (`BAD_VALUE` in src/chaos_game/flame.rs).
const FLAME_BAD_VALUE: f32 = 1e10;

const KIND_JULIA: u32 = 1u;
const SELECT_BITS: u32 = 24u;
const MODE_CLOSEST: u32 = 0u;
const DEPTH_SCALE: f32 = 16777215.0; // 2^24 - 1
const COLOR_SCALE: f32 = 255.0;

@group(0) @binding(0) var<uniform> params: ChaosParams;
@group(0) @binding(6) var<storage, read_write> points: array<vec4<f32>>;
// Closest mode: one key per pixel (compact, for cache locality of the random splats);
// average and density modes: four u32 per pixel, r, g, b sums and the count.
@group(0) @binding(7) var<storage, read_write> accum: array<atomic<u32>>;
// The key light's shadow map: one closest key (depth24 << 8) per texel.
@group(0) @binding(8) var<storage, read_write> shadow_map: array<atomic<u32>>;

fn complex_sqrt(re: f32, im: f32) -> vec2<f32> {
    let r = sqrt(re * re + im * im);
    let a = sqrt(max((r + re) * 0.5, 0.0));
    let b = sqrt(max((r - re) * 0.5, 0.0));
    return vec2<f32>(a, select(b, -b, im < 0.0));
}

// Cell index (bit pattern in x) and local coordinate (y) along one axis of a clamped
// coordinate `x` (`CompiledIfs::locate_axis`): `n` cells, the axis at `base` in the coordinate
// pool, first guess from the axis origin `lo` and bins per unit `inv_bin`. Scalars rather than
// the function struct so that nothing is indexed dynamically in private memory (slow on
// software rasterizers).
fn locate_axis(n: u32, base: u32, lo: f32, inv_bin: f32, x: f32) -> vec2<f32> {
    let guess = u32(max((x - lo) * inv_bin, 0.0));
    var i = min(guess, n - 1u);
    while i > 0u && x < coord_at(base + i).x {
        i -= 1u;
    }
    while i + 1u < n && x >= coord_at(base + i + 1u).x {
        i += 1u;
    }
    let c = coord_at(base + i);
    return vec2<f32>(bitcast<f32>(i), (x - c.x) * c.y);
}

// `locate_axis` on an axis of the shared grid: `n` cells (a pipeline constant) at `base` in the
// coordinate pool. The cell is the last one whose first coordinate is at or below `x`, the same
// cell as `locate_axis`'s walk finds (the coordinates increase strictly), found by comparing
// with every interior coordinate: no loop that depends on the lane, and every read at an index
// the compiler knows (scalar loads, not per-lane gathers, on lavapipe).
fn locate_shared_axis(n: u32, base: u32, x: f32) -> vec2<f32> {
    var i = 0u;
    var c = coord_at(base);
    for (var k = 1u; k < n; k += 1u) {
        let ck = coord_at(base + k);
        let above = x >= ck.x;
        i = select(i, k, above);
        c = select(c, ck, above);
    }
    return vec2<f32>(bitcast<f32>(i), (x - c.x) * c.y);
}

// The trilinear interpolant of `cell` at local coordinates (u, v, w).
fn interpolate(cell: u32, u: f32, v: f32, w: f32) -> vec3<f32> {
    // a + u b + v (c + u e) + w (d + u f + v (g + u h))
    let inner = cell_coef(cell, 3u) + u * cell_coef(cell, 5u) + v * (cell_coef(cell, 6u) + u * cell_coef(cell, 7u));
    return cell_coef(cell, 0u) + u * cell_coef(cell, 1u) + v * (cell_coef(cell, 2u) + u * cell_coef(cell, 4u)) + w * inner;
}

// `map_point` when all functions share one grid (SHARED_CELLS_X > 0): the same arithmetic on
// the same table values, function 0's clamp box and axes (the coordinate pool starts with them,
// n + 1 entries per axis).
fn map_point_shared(fi: u32, p: vec3<f32>) -> vec3<f32> {
    let f = function_at(0u);
    let lo = f.lo.xyz;
    let q = clamp(p, lo, f.hi.xyz);
    let lx = locate_shared_axis(SHARED_CELLS_X, 0u, q.x);
    let ly = locate_shared_axis(SHARED_CELLS_Y, SHARED_CELLS_X + 1u, q.y);
    let lz = locate_shared_axis(SHARED_CELLS_Z, SHARED_CELLS_X + SHARED_CELLS_Y + 2u, q.z);
    let local = (bitcast<u32>(lx.x) * SHARED_CELLS_Y + bitcast<u32>(ly.x)) * SHARED_CELLS_Z + bitcast<u32>(lz.x);
    let cell = fi * (SHARED_CELLS_X * SHARED_CELLS_Y * SHARED_CELLS_Z) + local;
    return interpolate(cell, lx.y, ly.y, lz.y);
}

// Maps `p` by compiled function `fi` (`CompiledIfs::map`).
fn map_point(fi: u32, p: vec3<f32>) -> vec3<f32> {
    if SHARED_CELLS_X > 0u {
        return map_point_shared(fi, p);
    }
    let f = function_at(fi);
    if HAS_JULIA && f.coord_offset.w == KIND_JULIA {
        let julia = f.julia;
        let z = complex_sqrt(p.x - julia.x, p.y - julia.y);
        return vec3<f32>(julia.z * z.x, julia.z * z.y, 0.0);
    }
    let lo = f.lo.xyz;
    let inv_bin = f.inv_bin.xyz;
    let n = f.cells;
    let base = f.coord_offset.xyz;
    let q = clamp(p, lo, f.hi.xyz);
    let lx = locate_axis(n.x, base.x, lo.x, inv_bin.x, q.x);
    let ly = locate_axis(n.y, base.y, lo.y, inv_bin.y, q.y);
    let lz = locate_axis(n.z, base.z, lo.z, inv_bin.z, q.z);
    let ix = bitcast<u32>(lx.x);
    let iy = bitcast<u32>(ly.x);
    let iz = bitcast<u32>(lz.x);
    let u = lx.y;
    let v = ly.y;
    let w = lz.y;
    let cell = n.w + (ix * n.y + iy) * n.z + iz;
    return interpolate(cell, u, v, w);
}

// Coarse selection cell of `p` (`SelectionTable::cell_of`).
fn selection_cell(p: vec3<f32>) -> u32 {
    let n = params.selection_cells.xyz;
    if SINGLE_SELECTION_CELL || all(n == vec3<u32>(1u)) {
        return 0u;
    }
    let q = (p - params.selection_lo.xyz) * params.selection_inv_cell.xyz;
    let ix = min(u32(max(q.x, 0.0)), n.x - 1u);
    let iy = min(u32(max(q.y, 0.0)), n.y - 1u);
    let iz = min(u32(max(q.z, 0.0)), n.z - 1u);
    return (ix * n.y + iy) * n.z + iz;
}

// The number of functions: the pipeline's constant, else the uniforms'.
fn function_count() -> u32 {
    return select(params.selection_cells.w, FUNCTION_COUNT, FUNCTION_COUNT > 0u);
}

// The function chosen by random bits `r` in coarse cell `cell` (`SelectionTable::select`).
fn select_function(cell: u32, r: u32) -> u32 {
    let n = function_count();
    let first = select(cell * n, 0u, SINGLE_SELECTION_CELL);
    let r24 = r >> (32u - SELECT_BITS);
    var chosen = 0u;
    for (var k = 0u; k + 1u < n; k += 1u) {
        chosen += select(0u, 1u, threshold_at(first + k) <= r24);
    }
    return chosen;
}

// Random start point in the domain box (`CompiledIfs::start_point`).
fn start_point(rng: ptr<function, u32>) -> vec3<f32> {
    let tx = pcg_next_f32(rng);
    let ty = pcg_next_f32(rng);
    var tz = 0.0;
    if params.dimension == 3u {
        tz = pcg_next_f32(rng);
    }
    let lo = params.domain_lo.xyz;
    return lo + vec3<f32>(tx, ty, tz) * (params.domain_hi.xyz - lo);
}

fn is_finite3(p: vec3<f32>) -> bool {
    // NaN fails every comparison.
    return all(abs(p) < vec3<f32>(3.0e38));
}

// Depth of field, twin of src/splat/lens.rs (`lens_sample`, `project_through_lens`).
const LENS_TRIES: u32 = 16u;

// The lens sample of point `p`: a point of the unit disk drawn by rejection from a PCG seeded
// with a hash of the point's bits and the seed.
fn lens_sample(seed: u32, p: vec3<f32>) -> vec2<f32> {
    var rng = pcg_hash(bitcast<u32>(p.z) ^ pcg_hash(bitcast<u32>(p.y) ^ pcg_hash(bitcast<u32>(p.x) ^ pcg_hash(seed))));
    for (var k = 0u; k < LENS_TRIES; k += 1u) {
        let u = 2.0 * pcg_next_f32(&rng) - 1.0;
        let v = 2.0 * pcg_next_f32(&rng) - 1.0;
        if u * u + v * v <= 1.0 {
            return vec2<f32>(u, v);
        }
    }
    return vec2<f32>(0.0);
}

// The pixel offset of point `p` (view depth `q_z`, 1 / w `inv_w`) seen through its lens sample.
fn lens_offset_px(p: vec3<f32>, q_z: f32, inv_w: f32) -> vec2<f32> {
    let lens = params.lens;
    let defocus = select(q_z * lens.y - 1.0, lens.y - inv_w, lens.z != 0.0);
    let r = lens.x * defocus;
    let s = lens_sample(bitcast<u32>(lens.w), p);
    // Pixel y grows downwards, the lens's v upwards.
    return vec2<f32>(s.x * r, -(s.y * r));
}

// Splats one point (`Framebuffer::consume` with `SplatView::project`, or
// `lens::project_through_lens` when LENS).
fn splat(p: vec3<f32>, fi: u32) {
    let q = params.pixel_from_world * vec4<f32>(p, 1.0);
    if !(q.w > 0.0) {
        return;
    }
    let inv_w = 1.0 / q.w;
    var x = q.x * inv_w;
    var y = q.y * inv_w;
    if LENS {
        let offset = lens_offset_px(p, q.z, inv_w);
        x += offset.x;
        y += offset.y;
    }
    if !(x >= 0.0 && y >= 0.0 && x < f32(params.width) && y < f32(params.height)) {
        return;
    }
    let near = params.domain_lo.w;
    let far = params.domain_hi.w;
    let t = clamp((q.z - near) * (1.0 / (far - near)), 0.0, 1.0);
    let pixel = u32(y) * params.width + u32(x);
    if SPLAT_MODE == MODE_CLOSEST {
        let slot = pixel;
        let key = (u32(t * DEPTH_SCALE) << 8u) | fi;
        // Most splats of a converging image lose: test with a plain load first, as atomics
        // are slow (serialized per lane on software rasterizers). The result is the same min.
        if key < atomicLoad(&accum[slot]) {
            atomicMin(&accum[slot], key);
        }
    } else {
        let slot = 4u * pixel;
        let c = color_at(fi) * COLOR_SCALE;
        let bg = params.background.rgb * COLOR_SCALE;
        let k = params.background.w * t;
        let v = c + (bg - c) * k + 0.5;
        atomicAdd(&accum[slot], u32(v.x));
        atomicAdd(&accum[slot + 1u], u32(v.y));
        atomicAdd(&accum[slot + 2u], u32(v.z));
        atomicAdd(&accum[slot + 3u], 1u);
    }
}

// The twin of `splat_shadow` in src/splat/shadow.rs: the point's key in the shadow map
// (orthographic: no division), kept if it is the nearest to the light.
fn splat_shadow(p: vec3<f32>) {
    let q = params.shadow_from_world * vec4<f32>(p, 1.0);
    let side = f32(params.shadow_side);
    if !(q.x >= 0.0 && q.y >= 0.0 && q.x < side && q.y < side) {
        return;
    }
    let t = clamp(q.z, 0.0, 1.0);
    let texel = u32(q.y) * params.shadow_side + u32(q.x);
    let key = u32(t * DEPTH_SCALE) << 8u;
    if key < atomicLoad(&shadow_map[texel]) {
        atomicMin(&shadow_map[texel], key);
    }
}

@compute @workgroup_size(64)
fn chaos_game(@builtin(global_invocation_id) id: vec3<u32>) {
    let thread = id.x + id.y * params.threads_per_row;
    if thread >= params.point_count {
        return;
    }
    var rng = pcg_for_stream(params.seed, params.frame, thread);
    let stored = points[thread];
    var p = stored.xyz;
    var fi = u32(stored.w);
    // Xaos: w holds 2·row + c.
    var row = 0u;
    var stored_c = stored.w;
    if XAOS {
        row = min(u32(max(stored.w, 0.0) * 0.5), function_count());
        stored_c = stored.w - 2.0 * f32(row);
    }
    // Palette colour: w holds the colour coordinate c instead (src/chaos_game/color_coord.rs).
    var c = select(C_START, stored_c, stored_c >= 0.0 && stored_c <= 1.0);
    if params.restart != 0u || !is_finite3(p) {
        p = start_point(&rng);
        c = C_START;
        row = 0u;
    }
    for (var s = 0u; s < params.steps; s += 1u) {
        fi = select_function(select(selection_cell(p), row, XAOS), pcg_next_u32(&rng));
        row = fi + 1u;
        // False where a flame function's image left the plane: flam3 re-seeds the orbit at a
        // random point of [−1, 1]² and does not draw that step (`CompiledIfs::map_with_rng`).
        var shown = true;
        if HAS_FLAMES && flame_op_at(fi).kind == FLAME_OP_XFORM {
            let q = apply_xform(fi, p.xy, &rng);
            if abs(q.x) <= FLAME_BAD_VALUE && abs(q.y) <= FLAME_BAD_VALUE {
                p = vec3<f32>(q, p.z);
                // The plotted weight (`opacity`): the point is drawn with that chance.
                let weight = flame_op_at(fi).k1.w;
                if weight < 1.0 {
                    shown = flame_random(&rng) < weight;
                }
            } else {
                let x = flame_random(&rng) * 2.0 - 1.0;
                let y = flame_random(&rng) * 2.0 - 1.0;
                p = vec3<f32>(x, y, p.z);
                shown = false;
            }
        } else {
            p = map_point(fi, p);
        }
        if PALETTE {
            if COLOR_SPEEDS {
                let speed = flame_op_at(fi).k1.z;
                c = speed * color_coord_at(fi) + (1.0 - speed) * c;
            } else {
                c = (c + color_coord_at(fi)) * 0.5;
            }
        }
        // The point drawn and its colour coordinate: the orbit's, or their final xform's
        // images (`CompiledIfs::map_with_rng`, `ColorCoordSink`).
        var drawn = p;
        var drawn_c = c;
        if HAS_FINAL && shown && final_applies(&rng) {
            let q = apply_xform(function_count(), p.xy, &rng);
            if abs(q.x) <= FLAME_BAD_VALUE && abs(q.y) <= FLAME_BAD_VALUE {
                drawn = vec3<f32>(q, p.z);
            } else {
                let x = flame_random(&rng) * 2.0 - 1.0;
                let y = flame_random(&rng) * 2.0 - 1.0;
                drawn = vec3<f32>(x, y, p.z);
            }
            let header = flame_op_at(function_count());
            drawn_c = header.k1.z * header.k1.w + (1.0 - header.k1.z) * c;
        }
        if s >= params.skip_steps && shown {
            var entry = palette_entry(drawn_c);
            if PALETTE_LINEAR {
                entry = palette_entry_linear(drawn_c, dither_of(drawn.x, drawn.y, drawn_c));
            }
            splat(drawn, select(fi, entry, PALETTE));
            if SHADOWED {
                splat_shadow(drawn);
            }
        }
    }
    let w = select(f32(fi), c, PALETTE);
    points[thread] = vec4<f32>(p, select(w, 2.0 * f32(row) + select(0.0, c, PALETTE), XAOS));
}

// Whether the final xform maps this step's drawn point: always at opacity 1, else a draw
// (`final_applies` in src/chaos_game/flame.rs).
fn final_applies(rng: ptr<function, u32>) -> bool {
    let opacity = flame_op_at(function_count() + 1u).weight;
    return opacity >= 1.0 || flame_random(rng) < opacity;
}

// Empties the accumulation buffer: the closest key to u32::MAX, sums to zero.
@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = id.x + id.y * params.threads_per_row;
    if slot >= 4u * params.width * params.height {
        return;
    }
    let empty = select(0u, 0xffffffffu, params.mode == MODE_CLOSEST);
    atomicStore(&accum[slot], empty);
}

// Empties the shadow map (every key to u32::MAX).
@compute @workgroup_size(64)
fn clear_shadow(@builtin(global_invocation_id) id: vec3<u32>) {
    let texel = id.x + id.y * params.threads_per_row;
    if texel >= params.shadow_side * params.shadow_side {
        return;
    }
    atomicStore(&shadow_map[texel], 0xffffffffu);
}
