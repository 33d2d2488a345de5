// The compiled IFS tables of `chaos_game.wgsl` in storage buffers: any size, the layout of
// `CompiledIfs` in src/chaos_game.rs. Used when the tables exceed the capacities of
// `ifs_tables_uniform.wgsl` (the two files define the same accessors).

@group(0) @binding(1) var<storage, read> functions: array<KernelFunction>;
@group(0) @binding(2) var<storage, read> coords: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read> cells: array<Cell>;
@group(0) @binding(4) var<storage, read> thresholds: array<u32>;
// Linear RGB per compiled function (w unused).
@group(0) @binding(5) var<storage, read> colors: array<vec4<f32>>;

fn function_at(i: u32) -> KernelFunction {
    return functions[i];
}

// (coordinate, 1 / cell width) of entry `i` of the coordinate pool.
fn coord_at(i: u32) -> vec2<f32> {
    return coords[i];
}

fn cell_coef(cell: u32, k: u32) -> vec3<f32> {
    return cells[cell].coef[k].xyz;
}

fn threshold_at(i: u32) -> u32 {
    return thresholds[i];
}

fn color_at(i: u32) -> vec3<f32> {
    return colors[i].rgb;
}

// The colour coordinate c_i of function `i` (palette colour; 0 in function colour).
fn color_coord_at(i: u32) -> f32 {
    return colors[i].w;
}
