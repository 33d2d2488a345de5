// Resolve of the accumulation buffer to the screen. Its CPU twin is `src/resolve.rs` (same
// constants, parameters and loop shape; keep in sync), its host side `src/gpu/resolve.rs`, and
// `tests/resolve.rs` compares the two. Closest keys become depth-cued function colours, sums
// become average colours, and density mode scales the average by log(1 + count) / log(1 + max
// count). The max count comes from `max_count`, a workgroup reduction run before the draw.
// Sums then go through flam3's tone map (`toned`, formula in src/resolve/tone.rs).
//
// The solid look (closest mode; `src/resolve.rs` explains it): normals from a weighted plane
// fit to the depths around each key, ambient + key light (Lambert and a Blinn-Phong highlight)
// + fill light fixed to the camera, and ambient occlusion from 16 samples in a fixed pattern.
// The light factors can instead come from `light_cache`, which the `light_pass` entry point
// fills (exact f32 bits), so that the live view recomputes them a band of rows per frame.

// Mirrors `ResolveParams` in src/resolve.rs (one mirror, used by both resolves): keep in sync.
struct ResolveParams {
    // rgb: linear background; w: depth cue.
    background: vec4<f32>,
    width: u32,
    height: u32,
    mode: u32,
    // 1: write sRGB-encoded values (unorm target); 0: linear (sRGB target encodes).
    encode_srgb: u32,
    // 0: flat colours; 1: fully lit.
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
    // Ambient occlusion strength: 0 none.
    occlusion: f32,
    // Pixels per unit of the occlusion samples' offsets.
    occlusion_step_px: u32,
    // The tone map (average and density modes; `toned` below): 2^exposure, 1 / gamma, the
    // gamma's linear threshold, vibrancy and highlight power.
    brightness: f32,
    inv_gamma: f32,
    gamma_threshold: f32,
    vibrancy: f32,
    highlight_power: f32,
    // Shadows (src/resolve/shadow.rs): strength (0: the map is not read), direction towards the
    // key light (view space), the map's projection from view space, its side in texels, the
    // world size of a texel and one over the world length of its depth range.
    shadows: f32,
    key_light: vec4<f32>,
    shadow_from_view: mat4x4<f32>,
    shadow_side_px: u32,
    shadow_texel_world: f32,
    shadow_inv_depth_world: f32,
    // The normal's plane fit reads the (2r + 1)² window of this radius (the pipeline constant
    // NORMAL_RADIUS_PX below holds the same value).
    normal_radius_px: u32,
    // Density mode: s of the absolute density log(1 + count · s); 0: relative to the densest
    // pixel (`log_density` below).
    count_scale: f32,
    // flam3's spatial filter (average and density modes, `filtered` below): the taps along each
    // axis (the pipeline constant FILTER_TAPS holds the same value) and their weights, four to
    // a vector.
    filter_taps: u32,
    // 1: the colours and background are sRGB-encoded values (the scene's `blend_space =
    // "srgb"`), which `output_color` takes as they are or decodes; 0: linear.
    blend_srgb: u32,
    pad0: u32,
    filter_weights: array<vec4<f32>, 4>,
}

// Pipeline constants (src/gpu/resolve.rs makes one pipeline per target format, mode and
// lighting on/off, SHADED being shading or occlusion on). The mode, the shading and the sRGB encoding as constants rather than
// uniforms let the compiler drop the branches not taken: a SIMD software rasterizer runs both
// sides of a branch it cannot prove uniform, storage loads and all (the dead branches were most
// of the resolve's cost on lavapipe). The uniforms of the same names stay for the values.
override RESOLVE_MODE: u32 = 0u;
override SHADED: bool = false;
override ENCODE_SRGB: bool = false;
// The light (normals, occlusion) comes from `light_cache`, which the `light` pass fills (the
// live view refreshes it a band of rows per frame at rest, see src/gpu/resolve.rs).
override LIGHT_CACHED: bool = false;
// Cast shadows: the shadow map is read (`shadow_at`).
override SHADOWS: bool = false;
// Ambient occlusion: its samples are taken (`occlusion_at`).
override OCCLUSION: bool = false;
// The radius of the normals' plane fit (`params.normal_radius_px`), a constant so that the
// window's loops unroll.
override NORMAL_RADIUS_PX: i32 = 2;
// The spatial filter's taps along each axis (`params.filter_taps`; 0: off), a constant so that
// the unfiltered resolve stays as it was and the filter's loops unroll.
override FILTER_TAPS: i32 = 0;

const MODE_CLOSEST: u32 = 0u;
const MODE_AVERAGE: u32 = 1u;
const EMPTY: u32 = 0xffffffffu;
const DEPTH_SCALE: f32 = 16777215.0;
const COLOR_SCALE: f32 = 255.0;

// The solid look: see the constants of the same names in src/resolve.rs (KEY_LIGHT is the
// default of `params.key_light`).
const KEY_LIGHT: vec3<f32> = vec3<f32>(-0.4511292, 0.5513802, 0.7017566);
const FILL_LIGHT: vec3<f32> = vec3<f32>(0.6115766, -0.2038589, 0.7644708);
const AMBIENT: f32 = 0.15;
const KEY: f32 = 0.9;
const FILL: f32 = 0.25;
const SPECULAR: f32 = 0.2;
const SLOPE_SCALE: f32 = 2.0;
const RIDGE: f32 = 1.0;
const SLOPE_MAX: f32 = 8.0;
const OCCLUSION_RINGS: i32 = 2;
const OCCLUSION_DIRECTIONS: i32 = 8;
const INV_LENGTH_3_0: f32 = 0.33333334;
const INV_LENGTH_2_2: f32 = 0.35355338;
const INV_LENGTH_6_3: f32 = 0.1490712;
const OCCLUSION_FALLOFF: f32 = 3.0;
const INV_OCCLUSION_FALLOFF: f32 = 1.0 / OCCLUSION_FALLOFF;
const OCCLUSION_BIAS: f32 = 0.1;
const OCCLUSION_GAIN: f32 = 2.0;
const SHADOW_PCF_RADIUS: i32 = 1;
const SHADOW_BIAS_TEXELS: f32 = 1.5;
const SHADOW_BIAS_SLOPE: f32 = 1.0;
const SHADOW_SLOPE_MAX: f32 = 4.0;

// A read-only storage buffer, not a uniform one: Mesa's lavapipe (22.3, Debian 12) specializes a
// large shader on the values of the uniforms that steer its branches and loops at every draw
// ("inlined uniforms") and leaks each specialization, about 0.4 MB a draw for this one (the
// viewer grew 10-25 MB a second); values read from storage are never inlined.
@group(0) @binding(0) var<storage, read> params: ResolveParams;
// The accumulation buffer of `chaos_game.wgsl`, read-only here: one key per pixel (closest) or
// four u32 per pixel (r, g, b, count).
@group(0) @binding(1) var<storage, read> accum: array<u32>;
// Linear RGB per compiled function (at most 256: the key keeps 8 bits of function index). A
// uniform buffer: on lavapipe a storage load with a per-pixel index is a scalar loop over the
// SIMD lanes, a uniform load one gather.
@group(0) @binding(2) var<uniform> colors: array<vec4<f32>, 256>;
// [0]: the maximum count over the pixels (written by `max_count`).
@group(0) @binding(3) var<storage, read> stats: array<u32>;

// Per pixel the bits of the light factors (factor · visible, specular · shading · visible) of
// its key, as the `light` pass wrote them (exact f32 through a Rg32Uint texture).
@group(0) @binding(4) var light_cache: texture_2d<u32>;

// The key light's shadow map of `chaos_game.wgsl`: one closest key per texel.
@group(0) @binding(5) var<storage, read> shadow_map: array<u32>;

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

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        return v / 12.92;
    }
    return pow((v + 0.055) / 1.055, 2.4);
}

// A resolved colour (in the blend space) as the target takes it: sRGB-encoded where the
// target is not an sRGB format, else linear. The twin of `output_color` in src/resolve.rs.
fn output_color(c: vec3<f32>) -> vec3<f32> {
    if params.blend_srgb != 0u {
        let s = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
        if ENCODE_SRGB {
            return s;
        }
        return vec3<f32>(srgb_to_linear(s.x), srgb_to_linear(s.y), srgb_to_linear(s.z));
    }
    if ENCODE_SRGB {
        return vec3<f32>(linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z));
    }
    return c;
}

fn cue(color: vec3<f32>, t: f32) -> vec3<f32> {
    let k = params.background.w * t;
    return color + (params.background.rgb - color) * k;
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

// Offset i (0..8) of ring `ring` (0..2) of the occlusion samples in steps (xy) and one over its
// length (z): the ring's two base offsets turned by i / 2 quarter turns.
fn occlusion_offset(ring: i32, i: i32) -> vec3<f32> {
    let odd = i % 2 == 1;
    var o = vec2<i32>(6, 3);
    var inv_length = INV_LENGTH_6_3;
    if ring == 0 {
        if odd {
            o = vec2<i32>(2, 2);
            inv_length = INV_LENGTH_2_2;
        } else {
            o = vec2<i32>(3, 0);
            inv_length = INV_LENGTH_3_0;
        }
    } else if odd {
        o = vec2<i32>(3, 6);
    }
    for (var turn = 0; turn < i / 2; turn += 1) {
        o = vec2<i32>(-o.y, o.x);
    }
    return vec3<f32>(f32(o.x), f32(o.y), inv_length);
}

// View depth per key depth unit, in footprints (the view-space size of a pixel at the key's
// depth).
fn footprints_per_unit(key: u32) -> f32 {
    let d = params.near + depth_of(key) * (params.far - params.near);
    var footprint = params.pixel_size;
    if params.perspective != 0u {
        footprint = params.pixel_size * d;
    }
    return (params.far - params.near) / DEPTH_SCALE / footprint;
}

// Slopes (depth change per pixel step right and down, in footprints) of the weighted
// least-squares plane through the keys of the window around (x, y).
fn fitted_slopes(x: i32, y: i32, key: u32) -> vec2<f32> {
    let z_per_unit = footprints_per_unit(key);
    let depth0 = i32(key >> 8u);
    var sw = 1.0;
    var sx = 0.0;
    var sy = 0.0;
    var sz = 0.0;
    var sxx = 0.0;
    var sxy = 0.0;
    var syy = 0.0;
    var sxz = 0.0;
    var syz = 0.0;
    for (var dy = -NORMAL_RADIUS_PX; dy <= NORMAL_RADIUS_PX; dy += 1) {
        for (var dx = -NORMAL_RADIUS_PX; dx <= NORMAL_RADIUS_PX; dx += 1) {
            let k = key_at(x + dx, y + dy);
            if k != EMPTY && (dx != 0 || dy != 0) {
                let z = f32(i32(k >> 8u) - depth0) * z_per_unit;
                let fx = f32(dx);
                let fy = f32(dy);
                // 1 / (1 + q² / r²) with one division.
                let q = z / SLOPE_SCALE;
                let r2 = fx * fx + fy * fy;
                let w = r2 / (q * q + r2);
                sw += w;
                sx += w * fx;
                sy += w * fy;
                sz += w * z;
                sxx += w * fx * fx;
                sxy += w * fx * fy;
                syy += w * fy * fy;
                sxz += w * fx * z;
                syz += w * fy * z;
            }
        }
    }
    let inv_sw = 1.0 / sw;
    let cxx = sxx - sx * sx * inv_sw + RIDGE;
    let cyy = syy - sy * sy * inv_sw + RIDGE;
    let cxy = sxy - sx * sy * inv_sw;
    let cxz = sxz - sx * sz * inv_sw;
    let cyz = syz - sy * sz * inv_sw;
    let inv_det = 1.0 / (cxx * cyy - cxy * cxy);
    let slope_x = clamp((cyy * cxz - cxy * cyz) * inv_det, -SLOPE_MAX, SLOPE_MAX);
    let slope_y = clamp((cxx * cyz - cxy * cxz) * inv_det, -SLOPE_MAX, SLOPE_MAX);
    return vec2<f32>(slope_x, slope_y);
}

// The fraction of the light the occlusion takes away at strength 1.
fn occlusion_at(x: i32, y: i32, key: u32, slopes: vec2<f32>) -> f32 {
    let z_per_unit = footprints_per_unit(key);
    let depth0 = i32(key >> 8u);
    let step = i32(params.occlusion_step_px);
    let inv_step = 1.0 / f32(step);
    var occluded = 0.0;
    var samples = 0.0;
    for (var ring = 0; ring < OCCLUSION_RINGS; ring += 1) {
        for (var i = 0; i < OCCLUSION_DIRECTIONS; i += 1) {
            let o = occlusion_offset(ring, i);
            let ox = i32(o.x) * step;
            let oy = i32(o.y) * step;
            let k = key_at(x + ox, y + oy);
            if k != EMPTY {
                let z = f32(i32(k >> 8u) - depth0) * z_per_unit;
                let above = slopes.x * f32(ox) + slopes.y * f32(oy) - z;
                let e = max(above * (o.z * inv_step) - OCCLUSION_BIAS, 0.0);
                let f = e * INV_OCCLUSION_FALLOFF;
                occluded += e / ((1.0 + e) * (1.0 + f * f));
                samples += 1.0;
            }
        }
    }
    if samples > 0.0 {
        return min(OCCLUSION_GAIN * occluded / samples, 1.0);
    }
    return 0.0;
}

// The view-space position of `key` seen at (x, y): on the pixel centre's ray at its depth.
fn view_position(x: i32, y: i32, key: u32) -> vec3<f32> {
    let d = params.near + depth_of(key) * (params.far - params.near);
    let sx_screen = (f32(x) + 0.5 - 0.5 * f32(params.width)) * params.pixel_size;
    let sy_screen = (0.5 * f32(params.height) - (f32(y) + 0.5)) * params.pixel_size;
    if params.perspective != 0u {
        return vec3<f32>(sx_screen * d, sy_screen * d, -d);
    }
    return vec3<f32>(sx_screen, sy_screen, -d);
}

// The shadowed fraction of `key` at (x, y) with unit `normal`: percentage-closer filtering of
// the (2 SHADOW_PCF_RADIUS + 1)² texels around it against the receiver's plane, less a bias.
fn shadow_at(x: i32, y: i32, key: u32, normal: vec3<f32>) -> f32 {
    let m = params.shadow_from_view;
    let q = m * vec4<f32>(view_position(x, y, key), 1.0);
    let to_light = params.key_light.xyz;
    let cos_l = max(dot(normal, to_light), 1.0 / SHADOW_SLOPE_MAX);
    let tan_l = min(sqrt(max(1.0 - cos_l * cos_l, 0.0)) / cos_l, SHADOW_SLOPE_MAX);
    let texel_depth = params.shadow_texel_world * params.shadow_inv_depth_world;
    // Rows 0 and 1 of the matrix (WGSL indexes columns).
    let row0 = vec3<f32>(m[0].x, m[1].x, m[2].x) * params.shadow_texel_world;
    let row1 = vec3<f32>(m[0].y, m[1].y, m[2].y) * params.shadow_texel_world;
    let gradient_x = clamp(dot(normal, row0) / cos_l, -SHADOW_SLOPE_MAX, SHADOW_SLOPE_MAX) * texel_depth;
    let gradient_y = clamp(dot(normal, row1) / cos_l, -SHADOW_SLOPE_MAX, SHADOW_SLOPE_MAX) * texel_depth;
    let d = params.near + depth_of(key) * (params.far - params.near);
    var footprint = params.pixel_size;
    if params.perspective != 0u {
        footprint = params.pixel_size * d;
    }
    let bias = (SHADOW_BIAS_TEXELS + SHADOW_BIAS_SLOPE * tan_l) * max(params.shadow_texel_world, footprint)
        * params.shadow_inv_depth_world;
    let side = i32(params.shadow_side_px);
    let cx = i32(floor(q.x));
    let cy = i32(floor(q.y));
    let t0 = q.z + gradient_x * (f32(cx) + 0.5 - q.x) + gradient_y * (f32(cy) + 0.5 - q.y) - bias;
    var occluded = 0.0;
    var taps = 0.0;
    for (var j = -SHADOW_PCF_RADIUS; j <= SHADOW_PCF_RADIUS; j += 1) {
        for (var i = -SHADOW_PCF_RADIUS; i <= SHADOW_PCF_RADIUS; i += 1) {
            let tx = cx + i;
            let ty = cy + j;
            if tx >= 0 && ty >= 0 && tx < side && ty < side {
                let k = shadow_map[u32(ty * side + tx)];
                let t = t0 + gradient_x * f32(i) + gradient_y * f32(j);
                if k != EMPTY && depth_of(k) < t {
                    occluded += 1.0;
                }
            }
            taps += 1.0;
        }
    }
    return occluded / taps;
}

// The solid look's light on `key` at (x, y): the factor of the albedo and the white added.
fn light_factors(x: i32, y: i32, key: u32) -> vec2<f32> {
    let slopes = fitted_slopes(x, y, key);
    let sx_screen = (f32(x) + 0.5 - 0.5 * f32(params.width)) * params.pixel_size;
    let sy_screen = (0.5 * f32(params.height) - (f32(y) + 0.5)) * params.pixel_size;
    var ray = vec3<f32>(0.0, 0.0, -1.0);
    if params.perspective != 0u {
        ray = vec3<f32>(sx_screen, sy_screen, -1.0);
    }
    let tangent_x = ray * slopes.x + vec3<f32>(1.0, 0.0, 0.0);
    let tangent_y = ray * slopes.y - vec3<f32>(0.0, 1.0, 0.0);
    let normal = normalize(cross(tangent_y, tangent_x));
    let to_eye = normalize(-ray);
    let key_light = params.key_light.xyz;
    var key_visible = 1.0;
    if SHADOWS && params.shadows > 0.0 {
        key_visible = 1.0 - params.shadows * shadow_at(x, y, key, normal);
    }
    let key_diffuse = KEY * max(dot(normal, key_light), 0.0) * key_visible;
    let diffuse = AMBIENT + key_diffuse + FILL * max(dot(normal, FILL_LIGHT), 0.0);
    let s1 = max(dot(normal, normalize(key_light + to_eye)), 0.0);
    let s2 = s1 * s1;
    let s4 = s2 * s2;
    let s8 = s4 * s4;
    let s16 = s8 * s8;
    let specular = SPECULAR * (s16 * s16) * key_visible;
    var visible = 1.0;
    if OCCLUSION && params.occlusion > 0.0 {
        visible = 1.0 - params.occlusion * occlusion_at(x, y, key, slopes);
    }
    let factor = (1.0 - params.shading) + diffuse * params.shading;
    return vec2<f32>(factor * visible, specular * params.shading * visible);
}

// The solid look's colour of `key` with colour `albedo` at (x, y), before the depth cue.
fn light(x: i32, y: i32, key: u32, albedo: vec3<f32>) -> vec3<f32> {
    var f = vec2<f32>(0.0);
    if LIGHT_CACHED {
        f = bitcast<vec2<f32>>(textureLoad(light_cache, vec2<i32>(x, y), 0).xy);
    } else {
        f = light_factors(x, y, key);
    }
    return albedo * f.x + vec3<f32>(f.y);
}

// The light pass: the light factors of each pixel's key (the nearest within the point radius),
// at the key's own pixel, as `light` reads them back (target: Rg32Uint, the accumulation's size).
@fragment
fn light_pass(in: VertexOutput) -> @location(0) vec4<u32> {
    let x = i32(in.position.x);
    let y = i32(in.position.y);
    let key = key_at(x, y);
    var f = vec2<f32>(1.0, 0.0);
    if key != EMPTY {
        f = light_factors(x, y, key);
    }
    return vec4<u32>(bitcast<vec2<u32>>(f), 0u, 0u);
}

// x^g for x > 0 (0 otherwise); x itself when g = 1.
fn power(x: f32, g: f32) -> f32 {
    if g == 1.0 {
        return x;
    }
    if x > 0.0 {
        return pow(x, g);
    }
    return 0.0;
}

// The gamma with flam3's linear ramp below the threshold.
fn gamma_ramp(x: f32) -> f32 {
    let g = params.inv_gamma;
    let tau = params.gamma_threshold;
    if g == 1.0 {
        return x;
    }
    if x < tau {
        let frac = x / tau;
        return (1.0 - frac) * x * (power(tau, g) / tau) + frac * power(x, g);
    }
    return power(x, g);
}

// The toned colour of average colour `avg` and linear density `a0` (src/resolve/tone.rs).
// Density mode's linear density of a pixel with `count` points, the largest being `max_count`
// (≥ 1): log(1 + count) / log(1 + max count), or log(1 + count · s) on the absolute scale
// (params.count_scale s > 0). The twin of `log_density` in src/resolve.rs.
fn log_density(count: f32, max_count: f32) -> f32 {
    if params.count_scale > 0.0 {
        return log_1p(count * params.count_scale);
    }
    return log(1.0 + count) / log(1.0 + max_count);
}

// log(1 + x) for x ≥ 0 to a few ULP also where x is small: below 1/8 its series to x⁸ (WGSL's
// log is held to 2^-21 absolute near 1), log(1 + x) above. The twin of `log_1p` in
// src/resolve.rs (the same terms in the same order).
fn log_1p(x: f32) -> f32 {
    if x < 0.125 {
        var sum = -1.0 / 8.0;
        for (var k = 7; k >= 1; k--) {
            let term = 1.0 / f32(k);
            sum = select(-term, term, k % 2 == 1) + x * sum;
        }
        return x * sum;
    }
    return log(1.0 + x);
}

fn toned(avg: vec3<f32>, a0: f32, density: bool) -> vec3<f32> {
    let a = a0 * params.brightness;
    let alpha = gamma_ramp(a);
    let m = max(max(avg.x, avg.y), avg.z);
    var c = avg;
    if params.highlight_power >= 0.0 && m * alpha > 1.0 {
        let r = pow(1.0 / (m * alpha), params.highlight_power);
        c = (vec3<f32>(1.0) - (vec3<f32>(1.0) - avg / m) * r) / alpha;
    }
    var out = c * alpha;
    if density && alpha <= 1.0 {
        out = params.background.rgb + (c - params.background.rgb) * alpha;
    }
    if params.vibrancy != 1.0 {
        let t = avg * a;
        let g = params.inv_gamma;
        let per_channel = vec3<f32>(power(t.x, g), power(t.y, g), power(t.z, g));
        out += (1.0 - params.vibrancy) * (per_channel - c * alpha);
    }
    return clamp(out, vec3<f32>(0.0), vec3<f32>(1.0));
}

// The spatial filter's weight of tap i along an axis.
fn filter_weight(i: i32) -> f32 {
    return params.filter_weights[i / 4][i % 4];
}

// A pixel's average colour and linear density (w; 0: no points) from the accumulation.
fn sampled(x: i32, y: i32) -> vec4<f32> {
    let slot = 4u * u32(y * i32(params.width) + x);
    let count = accum[slot + 3u];
    if count == 0u {
        return vec4<f32>(0.0);
    }
    let n = f32(count) * COLOR_SCALE;
    let avg = vec3<f32>(f32(accum[slot]), f32(accum[slot + 1u]), f32(accum[slot + 2u])) / n;
    if RESOLVE_MODE == MODE_AVERAGE {
        return vec4<f32>(avg, 1.0);
    }
    return vec4<f32>(avg, log_density(f32(count), f32(max(stats[0], 1u))));
}

// Adds a pixel's average colour and linear density `s` (from `sampled`) with weight `wgt` to
// the filter's sum of colour times density and density.
fn filter_term(sum: vec4<f32>, s: vec4<f32>, wgt: f32) -> vec4<f32> {
    if s.w == 0.0 {
        return sum;
    }
    let q = s.w * wgt;
    return vec4<f32>(sum.x + s.x * q, sum.y + s.y * q, sum.z + s.z * q, sum.w + q);
}

// The filter's sum as an average colour and linear density (w ≤ 0: nothing drawn).
fn filter_result(sum: vec4<f32>) -> vec4<f32> {
    if sum.w > 0.0 {
        return vec4<f32>(sum.x / sum.w, sum.y / sum.w, sum.z / sum.w, sum.w);
    }
    return vec4<f32>(0.0);
}

// flam3's spatial filter at pixel (x, y): the twin of `filter::gather` in src/resolve/filter.rs,
// term by term.
fn filtered(x: i32, y: i32) -> vec4<f32> {
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
            sum = filter_term(sum, sampled(sx, sy), wy * filter_weight(i));
        }
    }
    return filter_result(sum);
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
                if SHADED && (params.shading > 0.0 || params.occlusion > 0.0) {
                    base = light(at.x, at.y, key, base);
                }
                c = cue(base, t);
            }
        } else if FILTER_TAPS > 0 {
            let f = filtered(i32(x), i32(y));
            if f.w > 0.0 {
                c = toned(f.rgb, f.w, RESOLVE_MODE != MODE_AVERAGE);
            }
        } else {
            let count = accum[slot + 3u];
            if count > 0u {
                let n = f32(count) * COLOR_SCALE;
                let avg = vec3<f32>(f32(accum[slot]), f32(accum[slot + 1u]), f32(accum[slot + 2u])) / n;
                if RESOLVE_MODE == MODE_AVERAGE {
                    c = toned(avg, 1.0, false);
                } else {
                    c = toned(avg, log_density(f32(count), f32(max(stats[0], 1u))), true);
                }
            }
        }
    }
    return vec4<f32>(output_color(c), 1.0);
}
