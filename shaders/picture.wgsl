// Draws a picture resolved on the CPU (`src/gpu/picture.rs`: the live view on an adapter without
// compute shaders, a browser's WebGL2) into the accumulation's rectangle of the target: the
// texture has that rectangle's size, and `origin` is where its pixel (0, 0) sits in the target
// (the pass's viewport covers the rectangle). The texture holds sRGB-encoded bytes, as the
// resolve's unorm targets do; for an sRGB target it is an sRGB texture, which decodes them
// where the target encodes again.

struct Placement {
    origin: vec2<u32>,
    pad: vec2<u32>,
}

@group(0) @binding(0) var picture: texture_2d<f32>;
@group(0) @binding(1) var<uniform> placement: Placement;

// `VertexOutput` and the vertex stage `fullscreen`: fullscreen.wgsl, prepended.

@fragment
fn picture_fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let at = vec2<i32>(in.position.xy) - vec2<i32>(placement.origin);
    return vec4<f32>(textureLoad(picture, at, 0).rgb, 1.0);
}
