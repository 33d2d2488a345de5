// Composites the viewer's cached egui layer (premultiplied alpha, drawn into a texture of the
// window's size only when the UI changed) over the frame: a full-screen triangle, scissored by
// the host to where egui drew. `textureLoad` at the fragment's pixel: the layer has the
// target's size, so no filtering is needed (and unfiltered loads are the cheap ones on a
// software rasterizer).

@group(0) @binding(0) var layer: texture_2d<f32>;

// `VertexOutput` and the vertex stage `fullscreen`: fullscreen.wgsl, prepended.

@fragment
fn composite(in: VertexOutput) -> @location(0) vec4<f32> {
    return textureLoad(layer, vec2<i32>(in.position.xy), 0);
}
