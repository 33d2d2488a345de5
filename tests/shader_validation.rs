//! Every WGSL program parses and validates with naga (no GPU needed), every file under
//! `shaders/` belongs to a program, and every WGSL struct's size matches its one `#[repr(C)]`
//! mirror in Rust.

use nlifs::chaos_game::{Cell, KernelFunction};
use nlifs::flame::variations::FlameOp;
use nlifs::gpu::chaos_game::ChaosParams;
use nlifs::gpu::shaders::{PROGRAMS, program};
use nlifs::resolve::ResolveParams;

/// (program, WGSL struct, size of its Rust mirror). Shader-interface structs (vertex outputs)
/// have no memory layout and no mirror.
const MIRRORS: [(&str, &str, usize); 12] = [
    ("chaos_game", "KernelFunction", size_of::<KernelFunction>()),
    ("chaos_game", "Cell", size_of::<Cell>()),
    ("chaos_game", "ChaosParams", size_of::<ChaosParams>()),
    ("chaos_game_storage", "KernelFunction", size_of::<KernelFunction>()),
    ("chaos_game_storage", "Cell", size_of::<Cell>()),
    ("chaos_game_storage", "ChaosParams", size_of::<ChaosParams>()),
    ("chaos_game", "FlameOp", size_of::<FlameOp>()),
    ("chaos_game_storage", "FlameOp", size_of::<FlameOp>()),
    ("resolve", "ResolveParams", size_of::<ResolveParams>()),
    ("density_estimation", "ResolveParams", size_of::<ResolveParams>()),
    ("picture", "Placement", size_of::<nlifs::gpu::picture::Placement>()),
    (
        "density_estimation",
        "DensityEstimationParams",
        size_of::<nlifs::gpu::density_estimation::DensityEstimationParams>(),
    ),
];
const INTERFACE_STRUCTS: [&str; 1] = ["VertexOutput"];

fn validate(name: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let source = program(name);
    let module =
        naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    (module, info)
}

#[test]
fn every_program_validates() {
    for (name, _) in PROGRAMS {
        validate(name);
    }
}

#[test]
fn every_shader_file_is_in_a_program() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    for f in &files {
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        let included = PROGRAMS.iter().flat_map(|(_, parts)| parts.iter()).find(|(n, _)| n == f);
        let (_, embedded) =
            included.unwrap_or_else(|| panic!("shaders/{f} is not part of any program in src/gpu/shaders.rs"));
        assert_eq!(*embedded, text, "shaders/{f}: embedded text differs (rebuild)");
    }
}

#[test]
fn struct_sizes_match_rust_mirrors() {
    for (name, _) in PROGRAMS {
        let (module, _) = validate(name);
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        for (handle, ty) in module.types.iter() {
            let naga::TypeInner::Struct { .. } = ty.inner else { continue };
            let struct_name = ty.name.clone().unwrap_or_default();
            if INTERFACE_STRUCTS.contains(&struct_name.as_str()) {
                continue;
            }
            let mirrors: Vec<_> = MIRRORS.iter().filter(|(p, s, _)| *p == name && *s == struct_name).collect();
            assert_eq!(mirrors.len(), 1, "{name}: struct {struct_name} needs exactly one Rust mirror");
            let wgsl_size = layouter[handle].size as usize;
            assert_eq!(
                wgsl_size, mirrors[0].2,
                "{name}: struct {struct_name} is {wgsl_size} bytes in WGSL, its mirror {} bytes",
                mirrors[0].2
            );
        }
    }
    // Every mirror names a struct that exists.
    for (p, s, _) in MIRRORS {
        let (module, _) = validate(p);
        assert!(module.types.iter().any(|(_, t)| t.name.as_deref() == Some(s)), "{p}: no struct {s}");
    }
}

/// The uniform tables of program `chaos_game` (bindings 1..=5) are exactly the sizes the host
/// binds (`UNIFORM_CAPACITY`), and the resolve's colour table is as large as the chaos game's.
#[test]
fn uniform_table_sizes_match_host_capacities() {
    use nlifs::gpu::chaos_game::UNIFORM_CAPACITY;
    let (module, _) = validate("chaos_game");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    for (binding, capacity) in (1..=5).zip(UNIFORM_CAPACITY) {
        let var = module
            .global_variables
            .iter()
            .map(|(_, v)| v)
            .find(|v| v.binding.as_ref().is_some_and(|b| b.group == 0 && b.binding == binding))
            .unwrap_or_else(|| panic!("chaos_game: no binding {binding}"));
        assert_eq!(var.space, naga::AddressSpace::Uniform, "chaos_game: binding {binding} is not a uniform");
        assert_eq!(layouter[var.ty].size as u64, capacity, "chaos_game: binding {binding} ({:?})", var.name);
    }
    let (module, _) = validate("resolve");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let colors = module
        .global_variables
        .iter()
        .map(|(_, v)| v)
        .find(|v| v.name.as_deref() == Some("colors"))
        .expect("resolve: colors");
    assert_eq!(layouter[colors.ty].size as u64, UNIFORM_CAPACITY[4], "resolve: colors");
}

/// WGSL forbids a constant expression whose value is infinite or NaN, and browsers' compilers
/// (Chromium's Tint) refuse such a module where naga accepts it: the whole chaos game then draws
/// nothing in the page. The one way this code writes such a value by hand, a bitcast of literal
/// bits with the f32 exponent all ones, is looked for in every shader file.
#[test]
fn no_constant_infinity_or_nan() {
    for (_, parts) in PROGRAMS {
        for (file, text) in parts.iter() {
            for (i, line) in text.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                let mut rest = code;
                while let Some(at) = rest.find("bitcast<f32>(") {
                    let arg = &rest[at + "bitcast<f32>(".len()..];
                    let literal: String = arg.chars().take_while(|c| c.is_ascii_alphanumeric()).collect();
                    let closes = arg[literal.len()..].starts_with(')');
                    let bits = literal.strip_prefix("0x").map(|h| u32::from_str_radix(h.trim_end_matches('u'), 16));
                    if let (true, Some(Ok(bits))) = (closes, bits) {
                        assert!(
                            f32::from_bits(bits).is_finite(),
                            "shaders/{file}:{}: `bitcast<f32>({literal})` is a constant infinity or NaN, which \
                             browsers refuse; make it from a runtime value",
                            i + 1
                        );
                    }
                    rest = &arg[literal.len()..];
                }
            }
        }
    }
}
