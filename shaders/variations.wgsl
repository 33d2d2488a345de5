// flam3's xforms on the GPU, twin of `CompiledXform::apply` in src/flame/variations.rs: the
// pre-affine, `pre_blur`, the point's shared quantities, the weighted variations in flam3's order
// (`variations_basic.wgsl`, `variations_plugins.wgsl`, twins of the Rust files of the same
// stems), then the post-affine. In f32 where the CPU twin is f64; the constants are the CPU's,
// prepared in f64 (`CompiledXform::gpu_ops`) and rounded once. Random draws come from the chain's
// PCG (`rng.wgsl`) in the CPU's order and number ([`flame_random`]).
//
// The table lives in a storage buffer, never a uniform one: the term loop and the variation
// switch branch on its values, and Mesa's lavapipe specializes (and leaks) a shader per draw on
// the uniform values its branches read (docs/viewer.md, "Drawing, memory and idle").

// Mirrors `FlameOp` in src/flame/variations.rs: keep the two in sync. Record i below the number
// of compiled functions is function i's header (FLAME_OP_XFORM or FLAME_OP_NONE); a header's
// `count` records from `first` on are its terms (`kind`: the variation's number) and its
// post-affine (FLAME_OP_POST).
struct FlameOp {
    kind: u32,
    // A term's weight; a header's `pre_blur` weight.
    weight: f32,
    first: u32,
    count: u32,
    // A term's constants; an affine map's a, b, c, d (k0) and e, f (k1.xy); a header's colour
    // speed in k1.z and plotted weight (the chance its points are drawn) in k1.w; the final
    // xform's header (after the functions') its colour coordinate in k1.w.
    k0: vec4<f32>,
    k1: vec4<f32>,
}

const FLAME_OP_XFORM: u32 = 1000u;
const FLAME_OP_NONE: u32 = 1001u;
const FLAME_OP_POST: u32 = 1002u;
// The first variation `variations_plugins.wgsl` evaluates (`plugins::FIRST`).
const FLAME_FIRST_PLUGIN: u32 = 50u;

// flam3's `EPS`, the guard added to denominators.
const EPS: f32 = 1e-10;
const PI: f32 = 3.14159265358979323846;
const FRAC_1_PI: f32 = 0.318309886183790671538;
const FRAC_2_PI: f32 = 0.636619772367581343076;
const FRAC_PI_2: f32 = 1.57079632679489661923;
const FRAC_PI_4: f32 = 0.785398163397448309616;

@group(0) @binding(9) var<storage, read> flame_ops: array<FlameOp>;

// Pipeline constants: the variations the IFS's flame functions use, bit v % 32 of word v / 32
// (`IfsShape::flame_variations` in src/gpu/chaos_game.rs). Every arm of the variation switches
// opens with `flame_uses`, so the compiler drops the arms of the variations not used: a SIMD
// software rasterizer (lavapipe) would otherwise run every arm, transcendental functions and
// all, for every term of every point (it runs both sides of a branch whose lanes differ).
override FLAME_VARIATIONS_0: u32 = 0xffffffffu;
override FLAME_VARIATIONS_1: u32 = 0xffffffffu;
override FLAME_VARIATIONS_2: u32 = 0xffffffffu;
override FLAME_VARIATIONS_3: u32 = 0xffffffffu;

// Whether variation `v` is used (a constant wherever `v` is one).
fn flame_uses(v: u32) -> bool {
    var word = FLAME_VARIATIONS_3;
    if v < 32u {
        word = FLAME_VARIATIONS_0;
    } else if v < 64u {
        word = FLAME_VARIATIONS_1;
    } else if v < 96u {
        word = FLAME_VARIATIONS_2;
    }
    return ((word >> (v & 31u)) & 1u) != 0u;
}

fn flame_op_at(i: u32) -> FlameOp {
    return flame_ops[i];
}

// Uniform in [0, 1): the CPU's `Pcg32::next_f64` (two draws, 53 bits) truncated to the 24 bits
// an f32 holds; the second draw only keeps the stream in step with the CPU's.
fn flame_random(rng: ptr<function, u32>) -> f32 {
    let hi = pcg_next_u32(rng) >> 8u;
    _ = pcg_next_u32(rng);
    return f32(hi) * (1.0 / 16777216.0);
}

// The sum of four uniform draws minus 2: flam3's pseudo-Gaussian in (−2, 2).
fn pseudo_gaussian(rng: ptr<function, u32>) -> f32 {
    return flame_random(rng) + flame_random(rng) + flame_random(rng) + flame_random(rng) - 2.0;
}

// C's conversion of a double to `int` as flam3's x86-64 builds do it (`basic::c_int`): toward
// zero, and i32::MIN for NaN and anything out of range (WGSL saturates instead).
fn c_int(v: f32) -> i32 {
    if v >= -2147483648.0 && v < 2147483648.0 {
        return i32(v);
    }
    return i32(-2147483647) - 1;
}

// C's atan2, which is 0 at the origin (WGSL leaves atan2(0, 0) undefined).
fn atan2_c(y: f32, x: f32) -> f32 {
    if x == 0.0 && y == 0.0 {
        return 0.0;
    }
    return atan2(y, x);
}

// C's pow for the non-negative bases the variations raise (WGSL leaves pow(0, y) undefined).
fn pow_c(x: f32, y: f32) -> f32 {
    if x == 0.0 {
        if y == 0.0 {
            return 1.0;
        }
        // +∞ for a negative exponent. Its bits are made from the runtime `y` (an `& 0u` that
        // changes nothing): a constant expression may not be infinite in WGSL, and browsers'
        // compilers (Chromium's Tint) refuse the module where naga accepts it.
        let inf = bitcast<f32>(0x7f800000u | (bitcast<u32>(y) & 0u));
        return select(0.0, inf, y < 0.0);
    }
    return pow(x, y);
}

// C's fmod: x − y·trunc(x / y), the sign of x (Rust's `%` on floats).
fn fmod_c(x: f32, y: f32) -> f32 {
    return x - y * trunc(x / y);
}

// flam3 coefficients: x' = a x + c y + e, y' = b x + d y + f.
fn apply_coefs(abcd: vec4<f32>, ef: vec2<f32>, p: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(abcd.x * p.x + abcd.z * p.y + ef.x, abcd.y * p.x + abcd.w * p.y + ef.y);
}

// `pre_blur`'s move of the affine image (`plugins::pre_blur_offset`).
fn pre_blur_offset(w: f32, rng: ptr<function, u32>) -> vec2<f32> {
    let g = w * pseudo_gaussian(rng);
    let a = flame_random(rng) * 2.0 * PI;
    return vec2<f32>(g * cos(a), g * sin(a));
}

// Whether a variation used reads atan2(tx, ty) (`NEEDS_ATAN_XY` in `basic::needs` and
// `plugins::needs`).
fn flame_needs_atan_xy() -> bool {
    return flame_uses(5u) || flame_uses(6u) || flame_uses(7u) || flame_uses(8u) || flame_uses(12u)
        || flame_uses(13u) || flame_uses(22u) || flame_uses(23u) || flame_uses(25u) || flame_uses(49u)
        || flame_uses(70u);
}

// Whether a variation used reads atan2(ty, tx) (`NEEDS_ATAN_YX`).
fn flame_needs_atan_yx() -> bool {
    return flame_uses(32u) || flame_uses(33u) || flame_uses(36u) || flame_uses(38u) || flame_uses(50u)
        || flame_uses(51u) || flame_uses(59u) || flame_uses(63u) || flame_uses(77u) || flame_uses(78u)
        || flame_uses(79u) || flame_uses(80u) || flame_uses(83u);
}

// The image of `p` under compiled function `fi`'s xform (its header at `fi`); may be NaN or
// huge: the chaos game re-seeds such points, as flam3 does.
fn apply_xform(fi: u32, p: vec2<f32>, rng: ptr<function, u32>) -> vec2<f32> {
    let x = flame_op_at(fi);
    var t = apply_coefs(x.k0, x.k1.xy, p);
    if x.weight != 0.0 {
        t += pre_blur_offset(x.weight, rng);
    }
    // The shared quantities (`Point`): t (tx, ty, tx² + ty², |t|) and the angles (atan2(tx, ty),
    // flam3's "sin" tx / |t| and "cos" ty / |t|, atan2(ty, tx)); the arctangents only where a
    // variation used reads them (`needs` in the Rust files; a constant condition).
    let sumsq = t.x * t.x + t.y * t.y;
    let r = sqrt(sumsq);
    let pt = vec4<f32>(t, sumsq, r);
    var angles = vec4<f32>(0.0, t.x / r, t.y / r, 0.0);
    if flame_needs_atan_xy() {
        angles.x = atan2_c(t.x, t.y);
    }
    if flame_needs_atan_yx() {
        angles.w = atan2_c(t.y, t.x);
    }
    var out = vec2<f32>(0.0);
    for (var i = x.first; i < x.first + x.count; i += 1u) {
        let op = flame_op_at(i);
        if op.kind == FLAME_OP_POST {
            out = apply_coefs(op.k0, op.k1.xy, out);
        } else if op.kind < FLAME_FIRST_PLUGIN {
            out += variation_basic(op.kind, op.weight, op.k0, op.k1, pt, angles, rng);
        } else {
            out += variation_plugin(op.kind, op.weight, op.k0, op.k1, pt, angles, rng);
        }
    }
    return out;
}
