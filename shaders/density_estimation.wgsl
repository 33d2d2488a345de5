// flam3's adaptive density estimation on the GPU: the twin of `src/resolve/density_estimation.rs`
// (host side `src/gpu/density_estimation.rs`); keep the two in sync. The program is
// `fullscreen.wgsl` + `resolve.wgsl` + this file: it reads the accumulation (`accum`, four u32
// per pixel: r, g, b sums and the count) and the resolve's parameters and tone map (`params`,
// `toned`) from `resolve.wgsl`, and adds its own bindings in group 1 from binding 8 on.
//
// The CPU twin scatters each pixel over a disc; a GPU has no float atomics, so this file
// gathers the same sums: output pixel t receives w · a from every source s and tap offset d with
// reflect(s + d) = t, |d| ≤ the source's reach. Per axis, reflect(v) = t exactly for the images
// v = t + 2nk and v = −1 − t + 2nk; those within [−reach_max, n − 1 + reach_max] are the ones a
// tap can land on. The kernels (weights, reaches) and the choice of kernel per count come as
// tables the CPU twin builds (`KernelTables`), so they are its bytes; the f32 sums differ only
// in their order.
//
// Most pixels need few of the sources within reach_max: the background has none, a dense
// region's sources reach a pixel or two. So `kernel_index` also records per tile of TILE×TILE
// pixels the largest reach of its sources (plus one; 0: no source), and the gather visits only
// the tiles, and within them the rows and columns, that reach the image position.
//
// Passes: `kernel_index` (each pixel's kernel step from its count), `estimate` (the gather,
// and the largest estimated count as bits: for non-negative floats the u32 order of the bits
// is the float order, so atomicMax finds it), with a spatial filter `filter_estimate` (once per
// estimate), then the full-screen `resolve_estimated` (`resolve_filtered_estimate` with the
// filter), the density branch of `resolve` with float sums and counts (`Estimated::fragment` on
// the CPU), into a picture that `shaders/picture.wgsl` copies into each frame's target.

// Mirrors `DensityEstimationParams` in `src/gpu/density_estimation.rs`: keep in sync.
struct DensityEstimationParams {
    width: u32,
    height: u32,
    reach_max: u32,
    // Index of the last kernel step (the first_count and kernels tables hold last_step + 1).
    last_step: u32,
}

// A pixel without points has no kernel.
const NO_KERNEL: u32 = 0xffffffffu;
// Side of the tiles whose largest reach the gather consults (`TILE` in the host side).
const TILE: u32 = 8u;

// Storage rather than uniform, as `params` in resolve.wgsl (lavapipe's inlined uniforms leak).
@group(1) @binding(8) var<storage, read> de: DensityEstimationParams;
// Per kernel step: the smallest count whose step is ≤ it (falls with the step).
@group(1) @binding(9) var<storage, read> first_count: array<u32>;
// Per kernel step: its first weight's index and its reach r ((2r + 1)² weights, row by row).
@group(1) @binding(10) var<storage, read> kernels: array<vec2<u32>>;
@group(1) @binding(11) var<storage, read> weights: array<f32>;
@group(1) @binding(12) var<storage, read_write> kernel_of: array<u32>;
@group(1) @binding(13) var<storage, read_write> estimated: array<vec4<f32>>;
// [0]: bits of the largest estimated count.
@group(1) @binding(14) var<storage, read_write> estimated_max: array<atomic<u32>>;
// The draw reads what the compute passes wrote (the same buffers, bound read-only).
@group(1) @binding(15) var<storage, read> estimated_in: array<vec4<f32>>;
@group(1) @binding(16) var<storage, read> estimated_max_in: array<u32>;
// Per tile (row by row, ⌈width / TILE⌉ per row): 1 + the largest reach of its sources, 0 none.
@group(1) @binding(17) var<storage, read_write> tile_reach: array<atomic<u32>>;
// The spatial filter over the estimate (FILTER_TAPS > 0): each pixel's filtered average colour
// and linear density, written once per estimate by `filter_estimate`, read by every draw.
@group(1) @binding(18) var<storage, read_write> filtered_out: array<vec4<f32>>;
@group(1) @binding(19) var<storage, read> filtered_in: array<vec4<f32>>;

// `kernel_index` in the CPU twin: the smallest step whose first count is ≤ `count`.
fn kernel_step(count: u32) -> u32 {
    var lo = 0u;
    var hi = de.last_step;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if first_count[mid] <= count {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

@compute @workgroup_size(256)
fn kernel_index(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let pixel = id.x + id.y * groups.x * 256u;
    if pixel >= de.width * de.height {
        return;
    }
    let count = accum[4u * pixel + 3u];
    if count == 0u {
        kernel_of[pixel] = NO_KERNEL;
        return;
    }
    let k = kernel_step(count);
    kernel_of[pixel] = k;
    let x = pixel % de.width;
    let y = pixel / de.width;
    let tiles_x = (de.width + TILE - 1u) / TILE;
    atomicMax(&tile_reach[(y / TILE) * tiles_x + x / TILE], kernels[k].y + 1u);
}

// The first image b + 2nk (k an integer) at or after −reach.
fn first_image(b: i32, n: i32, reach: i32) -> i32 {
    let period = 2 * n;
    let d = -reach - b;
    // k = ⌈d / period⌉ (integer division truncates towards zero).
    let k = select(-((-d) / period), (d + period - 1) / period, d > 0);
    return b + period * k;
}

@compute @workgroup_size(8, 8)
fn estimate(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= de.width || id.y >= de.height {
        return;
    }
    let w = i32(de.width);
    let h = i32(de.height);
    let t = vec2<i32>(id.xy);
    var sum = vec4<f32>(0.0);
    for (var mirror_y = 0; mirror_y < 2; mirror_y += 1) {
        let base_y = select(t.y, -1 - t.y, mirror_y == 1);
        for (var vy = first_image(base_y, h, i32(de.reach_max)); vy <= h - 1 + i32(de.reach_max); vy += 2 * h) {
            for (var mirror_x = 0; mirror_x < 2; mirror_x += 1) {
                let base_x = select(t.x, -1 - t.x, mirror_x == 1);
                for (var vx = first_image(base_x, w, i32(de.reach_max)); vx <= w - 1 + i32(de.reach_max); vx += 2 * w) {
                    sum += gather_image(vec2<i32>(vx, vy));
                }
            }
        }
    }
    let pixel = id.y * de.width + id.x;
    estimated[pixel] = sum;
    atomicMax(&estimated_max[0], bitcast<u32>(sum.w));
}

// What lands on image position v (outside the image where it is a mirror image of the output
// pixel): w · a of every source s with |v − s| ≤ its reach, v − s being the tap's offset d.
// Tile by tile, within each tile's largest reach.
fn gather_image(v: vec2<i32>) -> vec4<f32> {
    let w = i32(de.width);
    let h = i32(de.height);
    let reach = i32(de.reach_max);
    let tile = i32(TILE);
    let tiles_x = (w + tile - 1) / tile;
    let tile_lo = vec2<i32>(max(v.x - reach, 0), max(v.y - reach, 0)) / tile;
    let tile_hi = vec2<i32>(min(v.x + reach, w - 1), min(v.y + reach, h - 1)) / tile;
    var sum = vec4<f32>(0.0);
    for (var ty = tile_lo.y; ty <= tile_hi.y; ty += 1) {
        for (var tx = tile_lo.x; tx <= tile_hi.x; tx += 1) {
            // −1: no source in the tile (the loops below are empty).
            let tile_r = i32(atomicLoad(&tile_reach[u32(ty * tiles_x + tx)])) - 1;
            let lo = max(max(vec2<i32>(tx, ty) * tile, v - vec2<i32>(tile_r)), vec2<i32>(0));
            let hi = min(min(vec2<i32>(tx, ty) * tile + tile - 1, v + vec2<i32>(tile_r)), vec2<i32>(w - 1, h - 1));
            for (var sy = lo.y; sy <= hi.y; sy += 1) {
                for (var sx = lo.x; sx <= hi.x; sx += 1) {
                    let s = u32(sy * w + sx);
                    let k = kernel_of[s];
                    if k == NO_KERNEL {
                        continue;
                    }
                    let kernel = kernels[k];
                    let r = i32(kernel.y);
                    let d = v - vec2<i32>(sx, sy);
                    if abs(d.x) > r || abs(d.y) > r {
                        continue;
                    }
                    let wgt = weights[kernel.x + u32((d.y + r) * (2 * r + 1) + d.x + r)];
                    let a = vec4<f32>(
                        f32(accum[4u * s]),
                        f32(accum[4u * s + 1u]),
                        f32(accum[4u * s + 2u]),
                        f32(accum[4u * s + 3u]),
                    );
                    sum += wgt * a;
                }
            }
        }
    }
    return sum;
}

// An estimated pixel's average colour and linear density (w; 0: no points).
fn sampled_estimate(x: i32, y: i32) -> vec4<f32> {
    let s = estimated_in[u32(y * i32(params.width) + x)];
    if s.w > 0.0 {
        let max_count = max(bitcast<f32>(estimated_max_in[0]), 1.0);
        return vec4<f32>(s.rgb / (s.w * COLOR_SCALE), log_density(s.w, max_count));
    }
    return vec4<f32>(0.0);
}

// `filtered` of resolve.wgsl over the estimate: the twin of `Estimated::fragment`'s call of
// `filter::gather`. The same loop as `filtered`'s, repeated: WGSL cannot pass it the sample
// function, and resolve.wgsl, compiled on its own too, cannot name `sampled_estimate`.
fn filtered_estimate(x: i32, y: i32) -> vec4<f32> {
    let half = FILTER_TAPS / 2;
    var sum = vec4<f32>(0.0);
    for (var j = 0; j < FILTER_TAPS; j += 1) {
        let sy = y + j - half;
        if sy < 0 || sy >= i32(params.height) {
            continue;
        }
        let wy = filter_weight(j);
        for (var i = 0; i < FILTER_TAPS; i += 1) {
            let sx = x + i - half;
            if sx < 0 || sx >= i32(params.width) {
                continue;
            }
            sum = filter_term(sum, sampled_estimate(sx, sy), wy * filter_weight(i));
        }
    }
    return filter_result(sum);
}

// Writes each pixel's `filtered_estimate` (the estimate and the parameters do not change between
// two estimates, so the draws in between read it instead of gathering the taps again).
@compute @workgroup_size(8, 8)
fn filter_estimate(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    filtered_out[id.y * params.width + id.x] = filtered_estimate(i32(id.x), i32(id.y));
}

// The output pixel of fragment position `position` in the accumulation (outside it where a
// coordinate is ≥ the size: the subtraction wraps).
fn estimate_pixel(position: vec4<f32>) -> vec2<u32> {
    return vec2<u32>(u32(position.x) - params.origin_x, u32(position.y) - params.origin_y);
}

// The drawn colour of a pixel whose average colour and linear density are `s` (w 0: the
// background), sRGB-encoded where the target is not an sRGB format.
fn estimate_color(s: vec4<f32>) -> vec4<f32> {
    var c = params.background.rgb;
    if s.w > 0.0 {
        c = toned(s.rgb, s.w, true);
    }
    return vec4<f32>(output_color(c), 1.0);
}

// The estimate without a spatial filter.
@fragment
fn resolve_estimated(in: VertexOutput) -> @location(0) vec4<f32> {
    let p = estimate_pixel(in.position);
    if p.x >= params.width || p.y >= params.height {
        return estimate_color(vec4<f32>(0.0));
    }
    return estimate_color(sampled_estimate(i32(p.x), i32(p.y)));
}

// The estimate with the spatial filter, as `filter_estimate` wrote it.
@fragment
fn resolve_filtered_estimate(in: VertexOutput) -> @location(0) vec4<f32> {
    let p = estimate_pixel(in.position);
    if p.x >= params.width || p.y >= params.height {
        return estimate_color(vec4<f32>(0.0));
    }
    return estimate_color(filtered_in[p.y * params.width + p.x]);
}
