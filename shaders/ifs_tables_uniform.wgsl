// The compiled IFS tables of `chaos_game.wgsl` in uniform buffers, for IFS that fit (the usual
// case; `src/gpu/chaos_game.rs` picks this program when they do, else `ifs_tables_storage.wgsl`).
// Same bytes as the storage layout: coordinates are packed two per vec4, thresholds four per
// vec4<u32>. Why uniform: on Mesa's lavapipe a storage-buffer load runs a scalar loop over the
// SIMD lanes with a branch per lane and component, while a uniform load with a per-lane index
// is one branch-free gather, which made the chaos game 20-30% faster there (docs/performance.md).
// GPUs serve small tables indexed by a few distinct values from the constant cache as well.

// Capacities (each binding at most 64 KiB, the WebGPU default limit). Keep in sync with
// `UNIFORM_CAPACITY` in src/gpu/chaos_game.rs.
const FUNCTION_CAPACITY: u32 = 256u;
const COORD_VEC4_CAPACITY: u32 = 4096u;
const CELL_CAPACITY: u32 = 512u;
const THRESHOLD_VEC4_CAPACITY: u32 = 4096u;

@group(0) @binding(1) var<uniform> functions: array<KernelFunction, FUNCTION_CAPACITY>;
@group(0) @binding(2) var<uniform> coords: array<vec4<f32>, COORD_VEC4_CAPACITY>;
@group(0) @binding(3) var<uniform> cells: array<Cell, CELL_CAPACITY>;
@group(0) @binding(4) var<uniform> thresholds: array<vec4<u32>, THRESHOLD_VEC4_CAPACITY>;
// Linear RGB per compiled function (w unused).
@group(0) @binding(5) var<uniform> colors: array<vec4<f32>, FUNCTION_CAPACITY>;

fn function_at(i: u32) -> KernelFunction {
    return functions[i];
}

// (coordinate, 1 / cell width) of entry `i` of the coordinate pool.
fn coord_at(i: u32) -> vec2<f32> {
    let pair = coords[i >> 1u];
    return select(pair.xy, pair.zw, (i & 1u) == 1u);
}

fn cell_coef(cell: u32, k: u32) -> vec3<f32> {
    return cells[cell].coef[k].xyz;
}

fn threshold_at(i: u32) -> u32 {
    return thresholds[i >> 2u][i & 3u];
}

fn color_at(i: u32) -> vec3<f32> {
    return colors[i].rgb;
}

// The colour coordinate c_i of function `i` (palette colour; 0 in function colour).
fn color_coord_at(i: u32) -> f32 {
    return colors[i].w;
}
