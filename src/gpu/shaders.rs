//! The one place WGSL enters the program. Every file under `shaders/` is included here, and a
//! program is the concatenation of its files in order (`rng.wgsl` holds functions only, shared
//! by the programs that draw random numbers; `fullscreen.wgsl` the vertex stage of the
//! full-screen passes; the three `variations*.wgsl` the flame functions of the chaos game). `tests/shader_validation.rs` validates every
//! program with naga and checks that every file under `shaders/` belongs to one.

pub const RNG: &str = include_str!("../../shaders/rng.wgsl");
pub const IFS_TABLES_UNIFORM: &str = include_str!("../../shaders/ifs_tables_uniform.wgsl");
pub const IFS_TABLES_STORAGE: &str = include_str!("../../shaders/ifs_tables_storage.wgsl");
pub const CHAOS_GAME: &str = include_str!("../../shaders/chaos_game.wgsl");
pub const VARIATIONS: &str = include_str!("../../shaders/variations.wgsl");
pub const VARIATIONS_BASIC: &str = include_str!("../../shaders/variations_basic.wgsl");
pub const VARIATIONS_PLUGINS: &str = include_str!("../../shaders/variations_plugins.wgsl");
pub const FULLSCREEN: &str = include_str!("../../shaders/fullscreen.wgsl");
pub const RESOLVE: &str = include_str!("../../shaders/resolve.wgsl");
pub const COMPOSITE: &str = include_str!("../../shaders/composite.wgsl");
pub const PICTURE: &str = include_str!("../../shaders/picture.wgsl");
pub const DENSITY_ESTIMATION: &str = include_str!("../../shaders/density_estimation.wgsl");

/// The programs: a name and the files it is made of, in order.
/// The chaos game comes in two programs that differ only in where the compiled IFS tables
/// live: uniform buffers (fast on lavapipe, fixed capacities) or storage buffers (any size).
pub const PROGRAMS: [(&str, &[(&str, &str)]); 7] = [
    ("rng", &[("rng.wgsl", RNG)]),
    (
        "chaos_game",
        &[
            ("rng.wgsl", RNG),
            ("ifs_tables_uniform.wgsl", IFS_TABLES_UNIFORM),
            ("variations.wgsl", VARIATIONS),
            ("variations_basic.wgsl", VARIATIONS_BASIC),
            ("variations_plugins.wgsl", VARIATIONS_PLUGINS),
            ("chaos_game.wgsl", CHAOS_GAME),
        ],
    ),
    (
        "chaos_game_storage",
        &[
            ("rng.wgsl", RNG),
            ("ifs_tables_storage.wgsl", IFS_TABLES_STORAGE),
            ("variations.wgsl", VARIATIONS),
            ("variations_basic.wgsl", VARIATIONS_BASIC),
            ("variations_plugins.wgsl", VARIATIONS_PLUGINS),
            ("chaos_game.wgsl", CHAOS_GAME),
        ],
    ),
    ("resolve", &[("fullscreen.wgsl", FULLSCREEN), ("resolve.wgsl", RESOLVE)]),
    ("composite", &[("fullscreen.wgsl", FULLSCREEN), ("composite.wgsl", COMPOSITE)]),
    ("picture", &[("fullscreen.wgsl", FULLSCREEN), ("picture.wgsl", PICTURE)]),
    // Density estimation reads the accumulation and draws with the resolve's tone map.
    (
        "density_estimation",
        &[("fullscreen.wgsl", FULLSCREEN), ("resolve.wgsl", RESOLVE), ("density_estimation.wgsl", DENSITY_ESTIMATION)],
    ),
];

/// The source text of program `name` (one of [`PROGRAMS`]); empty for an unknown name.
pub fn program(name: &str) -> String {
    PROGRAMS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, files)| files.iter().map(|(_, text)| *text).collect::<Vec<_>>().join("\n"))
        .unwrap_or_default()
}

pub fn module(device: &wgpu::Device, name: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(program(name).into()),
    })
}
