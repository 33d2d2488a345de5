// Resolve of the accumulation buffer to the screen. Its CPU twin is `src/resolve.rs` (same
// constants, parameters and loop shape; keep in sync), its host side `src/gpu/resolve.rs`, and
// `tests/resolve.rs` compares the two. Closest keys become depth-cued function colours, sums
// become average colours, and density mode scales the average by log(1 + count) / log(1 + max
// count). The max count comes from `max_count`, a workgroup reduction run before the draw.
//
// Optional screen-space shading (closest mode): normals from the depth of the neighbouring
// pixels' keys, lit by a head light, so that 3D point sets read as solids.

// Mirrors `ResolveParams` in src/resolve.rs (one mirror, used by both resolves): keep in sync.
struct ResolveParams {
    // rgb: linear background; w: depth cue.
    background: vec4<f32>,
    width: u32,
    height: u32,
    mode: u32,
    // 1: write sRGB-encoded values (unorm target); 0: linear (sRGB target encodes).
    encode_srgb: u32,
    // 0: flat colours; 1: full screen-space shading.
    shading: f32,
    // View-space depth range of the keys (near, far), for normals from depth.
    near: f32,
    far: f32,
    // World units per pixel at unit view distance (perspective) or per pixel (parallel).
    pixel_size: f32,
    perspective: u32,
    // Closest mode: each pixel shows the nearest key within this radius (point size).
    point_radius_px: u32,
    // Target pixel of the accumulation's pixel (0, 0): the draw's viewport origin (the view
    // right of the viewer's side panel), so fragment positions map back to accumulation pixels.
    origin_x: u32,
    origin_y: u32,
}

// Pipeline constants (src/gpu/resolve.rs makes one pipeline per target format, mode and
// shading on/off). The mode, the shading and the sRGB encoding as constants rather than
// uniforms let the compiler drop the branches not taken: a SIMD software rasterizer runs both
// sides of a branch it cannot prove uniform, storage loads and all (the dead branches were most
// of the resolve's cost on lavapipe). The uniforms of the same names stay for the values.
override RESOLVE_MODE: u32 = 0u;
override SHADED: bool = false;
override ENCODE_SRGB: bool = false;

const MODE_CLOSEST: u32 = 0u;
const MODE_AVERAGE: u32 = 1u;
const EMPTY: u32 = 0xffffffffu;
const DEPTH_SCALE: f32 = 16777215.0;
const COLOR_SCALE: f32 = 255.0;

@group(0) @binding(0) var<uniform> params: ResolveParams;
// The accumulation buffer of `chaos_game.wgsl`, read-only here: one key per pixel (closest) or
// four u32 per pixel (r, g, b, count).
@group(0) @binding(1) var<storage, read> accum: array<u32>;
// Linear RGB per compiled function (at most 256: the key keeps 8 bits of function index). A
// uniform buffer: on lavapipe a storage load with a per-pixel index is a scalar loop over the
// SIMD lanes, a uniform load one gather.
@group(0) @binding(2) var<uniform> colors: array<vec4<f32>, 256>;
// [0]: the maximum count over the pixels (written by `max_count`).
@group(0) @binding(3) var<storage, read> stats: array<u32>;

@group(1) @binding(0) var<storage, read_write> stats_out: array<atomic<u32>>;

var<workgroup> group_max: atomic<u32>;

@compute @workgroup_size(256)
fn max_count(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32, @builtin(num_workgroups) groups: vec3<u32>) {
    let pixel = id.x + id.y * groups.x * 256u;
    var n = 0u;
    if pixel < params.width * params.height {
        n = accum[4u * pixel + 3u];
    }
    atomicMax(&group_max, n);
    workgroupBarrier();
    if local == 0u {
        atomicMax(&stats_out[0], atomicLoad(&group_max));
    }
}

// `VertexOutput` and the vertex stage `fullscreen`: fullscreen.wgsl, prepended.

fn linear_to_srgb(v: f32) -> f32 {
    let x = clamp(v, 0.0, 1.0);
    if x <= 0.0031308 {
        return x * 12.92;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn cue(color: vec3<f32>, t: f32) -> vec3<f32> {
    let k = params.background.w * t;
    return color + (params.background.rgb - color) * k;
}

// View-space position of pixel (x, y) with key depth fraction t (for normals).
fn view_position(x: f32, y: f32, t: f32) -> vec3<f32> {
    let d = params.near + t * (params.far - params.near);
    let sx = (x - 0.5 * f32(params.width)) * params.pixel_size;
    let sy = (0.5 * f32(params.height) - y) * params.pixel_size;
    if params.perspective != 0u {
        return vec3<f32>(sx * d, sy * d, -d);
    }
    return vec3<f32>(sx, sy, -d);
}

fn key_at(x: i32, y: i32) -> u32 {
    if x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height) {
        return EMPTY;
    }
    return accum[u32(y) * params.width + u32(x)];
}

fn depth_of(key: u32) -> f32 {
    return f32(key >> 8u) / DEPTH_SCALE;
}

// Lambert head-light factor from the depths of the 4-neighbourhood (1 where undefined).
fn shade(x: i32, y: i32, t: f32) -> f32 {
    let p = view_position(f32(x) + 0.5, f32(y) + 0.5, t);
    var dx = vec3<f32>(0.0);
    var dy = vec3<f32>(0.0);
    let kr = key_at(x + 1, y);
    let kl = key_at(x - 1, y);
    let kd = key_at(x, y + 1);
    let ku = key_at(x, y - 1);
    // One-sided differences from the nearer neighbour avoid smearing across silhouettes.
    let tr = select(t, depth_of(kr), kr != EMPTY);
    let tl = select(t, depth_of(kl), kl != EMPTY);
    let td = select(t, depth_of(kd), kd != EMPTY);
    let tu = select(t, depth_of(ku), ku != EMPTY);
    if abs(tr - t) < abs(tl - t) {
        dx = view_position(f32(x) + 1.5, f32(y) + 0.5, tr) - p;
    } else {
        dx = p - view_position(f32(x) - 0.5, f32(y) + 0.5, tl);
    }
    if abs(td - t) < abs(tu - t) {
        dy = view_position(f32(x) + 0.5, f32(y) + 1.5, td) - p;
    } else {
        dy = p - view_position(f32(x) + 0.5, f32(y) - 0.5, tu);
    }
    let n = cross(dy, dx);
    let len = length(n);
    if !(len > 0.0) {
        return 1.0;
    }
    let to_eye = normalize(-p);
    let lambert = abs(dot(n / len, to_eye));
    return 0.25 + 0.75 * lambert;
}

@fragment
fn resolve(in: VertexOutput) -> @location(0) vec4<f32> {
    // Outside the viewport nothing is rasterized, so the subtraction does not wrap in practice;
    // if it did, the bounds check below would catch it.
    let x = u32(in.position.x) - params.origin_x;
    let y = u32(in.position.y) - params.origin_y;
    var c = params.background.rgb;
    if x < params.width && y < params.height {
        let pixel = y * params.width + x;
        let slot = 4u * pixel;
        if RESOLVE_MODE == MODE_CLOSEST {
            var key = accum[pixel];
            var at = vec2<i32>(i32(x), i32(y));
            let r = i32(params.point_radius_px);
            // r = 0 (the default) skips the loop: its bounds-checked neighbour reads cost as
            // much as the rest of the resolve on a software rasterizer.
            for (var dy = -r; dy <= r && r > 0; dy += 1) {
                for (var dx = -r; dx <= r; dx += 1) {
                    let k = key_at(i32(x) + dx, i32(y) + dy);
                    if dx * dx + dy * dy <= r * r && k < key {
                        key = k;
                        at = vec2<i32>(i32(x) + dx, i32(y) + dy);
                    }
                }
            }
            if key != EMPTY {
                let fi = key & 0xffu;
                let t = depth_of(key);
                var base = colors[fi].rgb;
                if SHADED && params.shading > 0.0 {
                    base *= mix(1.0, shade(at.x, at.y, t), params.shading);
                }
                c = cue(base, t);
            }
        } else {
            let count = accum[slot + 3u];
            if count > 0u {
                let n = f32(count) * COLOR_SCALE;
                let avg = vec3<f32>(f32(accum[slot]), f32(accum[slot + 1u]), f32(accum[slot + 2u])) / n;
                if RESOLVE_MODE == MODE_AVERAGE {
                    c = avg;
                } else {
                    let log_max = log(1.0 + f32(max(stats[0], 1u)));
                    let b = log(1.0 + f32(count)) / log_max;
                    c = params.background.rgb + (avg - params.background.rgb) * b;
                }
            }
        }
    }
    if ENCODE_SRGB {
        c = vec3<f32>(linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z));
    }
    return vec4<f32>(c, 1.0);
}
