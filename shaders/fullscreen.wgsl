// One triangle covering the target: the vertex stage shared by the full-screen passes
// (`resolve.wgsl`, `composite.wgsl`), prepended to them by `src/gpu/shaders.rs`.

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
}

@vertex
fn fullscreen(@builtin(vertex_index) index: u32) -> VertexOutput {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VertexOutput;
    out.position = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}
