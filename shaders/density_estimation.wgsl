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
// Passes: `kernel_index` (each pixel's kernel step from its count), `estimate` (the gather,
// and the largest estimated count as bits: for non-negative floats the u32 order of the bits
// is the float order, so atomicMax finds it), then the full-screen `resolve_estimated`, the
// density branch of `resolve` with float sums and counts (`Estimated::fragment` on the CPU).

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

@group(1) @binding(8) var<uniform> de: DensityEstimationParams;
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
    kernel_of[pixel] = select(kernel_step(count), NO_KERNEL, count == 0u);
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
    let reach = i32(de.reach_max);
    let t = vec2<i32>(id.xy);
    var sum = vec4<f32>(0.0);
    for (var mirror_y = 0; mirror_y < 2; mirror_y += 1) {
        let base_y = select(t.y, -1 - t.y, mirror_y == 1);
        for (var vy = first_image(base_y, h, reach); vy <= h - 1 + reach; vy += 2 * h) {
            for (var mirror_x = 0; mirror_x < 2; mirror_x += 1) {
                let base_x = select(t.x, -1 - t.x, mirror_x == 1);
                for (var vx = first_image(base_x, w, reach); vx <= w - 1 + reach; vx += 2 * w) {
                    // Sources within reach of the image (v − s is the tap's offset d).
                    for (var sy = max(vy - reach, 0); sy <= min(vy + reach, h - 1); sy += 1) {
                        for (var sx = max(vx - reach, 0); sx <= min(vx + reach, w - 1); sx += 1) {
                            let s = u32(sy * w + sx);
                            let k = kernel_of[s];
                            if k == NO_KERNEL {
                                continue;
                            }
                            let kernel = kernels[k];
                            let r = i32(kernel.y);
                            let dx = vx - sx;
                            let dy = vy - sy;
                            if abs(dx) > r || abs(dy) > r {
                                continue;
                            }
                            let wgt = weights[kernel.x + u32((dy + r) * (2 * r + 1) + dx + r)];
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
        }
    }
    let pixel = id.y * de.width + id.x;
    estimated[pixel] = sum;
    atomicMax(&estimated_max[0], bitcast<u32>(sum.w));
}

@fragment
fn resolve_estimated(in: VertexOutput) -> @location(0) vec4<f32> {
    let x = u32(in.position.x) - params.origin_x;
    let y = u32(in.position.y) - params.origin_y;
    var c = params.background.rgb;
    if x < params.width && y < params.height {
        let s = estimated_in[y * params.width + x];
        if s.w > 0.0 {
            let avg = s.rgb / (s.w * COLOR_SCALE);
            let max_count = max(bitcast<f32>(estimated_max_in[0]), 1.0);
            let a0 = log(1.0 + s.w) / log(1.0 + max_count);
            c = toned(avg, a0, true);
        }
    }
    if ENCODE_SRGB {
        c = vec3<f32>(linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z));
    }
    return vec4<f32>(c, 1.0);
}
