//! Host side of `shaders/chaos_game.wgsl`: the persistent point buffer, the compiled IFS in
//! storage buffers (the same [`KernelFunction`], [`Cell`], coordinate and threshold layout as
//! the CPU model in `src/chaos_game.rs`), the accumulation buffer, and the dispatch of one
//! frame. Buffers are created when sizes grow (new scene, resize, point count), never per frame.
//!
//! The tables are bound as uniform buffers when they fit their fixed capacities (program
//! `chaos_game`, `shaders/ifs_tables_uniform.wgsl`), else as storage buffers (program
//! `chaos_game_storage`); the buffers are the same bytes either way. The flame functions' table
//! ([`CompiledIfs::flame_ops`], `shaders/variations.wgsl`) is a storage buffer in both.

use wgpu::util::DeviceExt;

use crate::chaos_game::{Cell, CompiledIfs, KIND_MULTILINEAR, KernelFunction};
use crate::flame::variations::FlameOp;
use crate::scene::spec::SplatMode;
use crate::splat::SplatView;

/// Workgroups per dispatch row; rows extend the dispatch past the 65535-workgroup limit.
pub const GROUPS_PER_ROW: u32 = 4096;
pub const WORKGROUP_SIZE: u32 = 64;
/// Threads per dispatch row (the shader's `threads_per_row`).
pub const THREADS_PER_ROW: u32 = GROUPS_PER_ROW * WORKGROUP_SIZE;

/// Bytes of each IFS table binding in the uniform program (functions, coordinates, cells,
/// thresholds, colours). Mirrors the capacities in `shaders/ifs_tables_uniform.wgsl`.
pub const UNIFORM_CAPACITY: [u64; 5] = [256 * 96, 4096 * 16, 512 * 128, 4096 * 16, 256 * 16];

/// Per-frame uniforms. Mirrors `struct ChaosParams` in `shaders/chaos_game.wgsl`: keep in sync.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ChaosParams {
    pub pixel_from_world: [[f32; 4]; 4],
    pub background: [f32; 4],
    pub domain_lo: [f32; 4],
    pub domain_hi: [f32; 4],
    pub selection_lo: [f32; 4],
    pub selection_inv_cell: [f32; 4],
    pub selection_cells: [u32; 4],
    pub seed: u32,
    pub frame: u32,
    pub steps: u32,
    pub skip_steps: u32,
    pub point_count: u32,
    pub width: u32,
    pub height: u32,
    pub mode: u32,
    pub dimension: u32,
    pub restart: u32,
    pub threads_per_row: u32,
    // Shadows (`super::shadow`).
    /// The shadow map's side in texels (0: no shadow map).
    pub shadow_side: u32,
    /// Rows: texel x, texel y, depth fraction, 1 (`ShadowView::map_from_world`).
    pub shadow_from_world: [[f32; 4]; 4],
    // Depth of field.
    /// [`crate::splat::Lens::uniform`].
    pub lens: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<ChaosParams>() == 288);

/// The shader's number for a splat mode.
pub fn mode_index(mode: SplatMode) -> u32 {
    match mode {
        SplatMode::Closest => 0,
        SplatMode::Average => 1,
        SplatMode::Density => 2,
    }
}

/// The structure of a compiled IFS that a chaos-game pipeline is specialized for (the shader's
/// pipeline constants `SHARED_CELLS_*`, `FUNCTION_COUNT`, `SINGLE_SELECTION_CELL`). Known to the
/// compiler, table reads at indices that depend only on it become scalar loads instead of
/// per-lane gathers on a SIMD software rasterizer, and the cell search on one-cell axes vanishes
/// (chaos game about −30% process CPU on lavapipe, docs/performance.md). Edits that move grid
/// points keep the shape (and the pipeline); enabling a function or changing the grid makes a
/// new pipeline on first use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IfsShape {
    /// Cells per axis when every function is a grid map on one grid: the same clamp box, bins,
    /// cell counts and axis coordinates, the coordinate pool starting with function 0's axes
    /// and function f's cells starting at f × cells per function. None otherwise.
    pub shared_cells: Option<[u32; 3]>,
    pub function_count: u32,
    /// The selection table has one coarse cell (explicit or contractivity probabilities).
    pub single_selection_cell: bool,
    /// The selection rows are by the previous function (the shader's `XAOS`).
    pub xaos: bool,
    // Palette colour (`src/chaos_game/color_coord.rs`):
    /// The points carry a colour coordinate (the shader's `PALETTE`).
    pub palette: bool,
    /// Their palette entries are flam3's linear interpolation, dithered (`PALETTE_LINEAR`).
    pub palette_linear: bool,
    // Flame functions (`src/chaos_game/flame.rs`):
    /// Some function is a flame (the shader's `HAS_FLAMES`).
    pub flames: bool,
    /// The colour coordinate steps with per-function colour speeds (`COLOR_SPEEDS`).
    pub color_speeds: bool,
    /// A final xform maps the drawn points (`HAS_FINAL`).
    pub final_xform: bool,
    /// The variations the flame functions use: bit v % 32 of word v / 32 (the shader's
    /// `FLAME_VARIATIONS_*`; the others are compiled out). Adding a variation to a flame in
    /// the viewer makes a new pipeline.
    pub flame_variations: [u32; 4],
}

impl IfsShape {
    pub fn of(ifs: &CompiledIfs) -> Self {
        Self {
            shared_cells: shared_cells(ifs),
            function_count: ifs.selection.function_count,
            single_selection_cell: ifs.selection.cells == [1, 1, 1] && !ifs.selection.xaos,
            xaos: ifs.selection.xaos,
            palette: ifs.color_coords.is_some(),
            palette_linear: ifs.color_coords.is_some() && ifs.palette_linear,
            flames: ifs.has_flames(),
            color_speeds: ifs.color_speeds.is_some(),
            final_xform: ifs.has_final_xform(),
            flame_variations: flame_variations(ifs),
        }
    }

    /// The shader's pipeline constants for this shape.
    fn constants(&self) -> [(&'static str, f64); 15] {
        let [x, y, z] = self.shared_cells.unwrap_or([0; 3]);
        [
            ("SHARED_CELLS_X", x as f64),
            ("SHARED_CELLS_Y", y as f64),
            ("SHARED_CELLS_Z", z as f64),
            ("FUNCTION_COUNT", self.function_count as f64),
            ("SINGLE_SELECTION_CELL", self.single_selection_cell as u32 as f64),
            ("XAOS", self.xaos as u32 as f64),
            ("PALETTE", self.palette as u32 as f64),
            ("PALETTE_LINEAR", self.palette_linear as u32 as f64),
            ("HAS_FLAMES", self.flames as u32 as f64),
            ("COLOR_SPEEDS", self.color_speeds as u32 as f64),
            ("HAS_FINAL", self.final_xform as u32 as f64),
            ("FLAME_VARIATIONS_0", self.flame_variations[0] as f64),
            ("FLAME_VARIATIONS_1", self.flame_variations[1] as f64),
            ("FLAME_VARIATIONS_2", self.flame_variations[2] as f64),
            ("FLAME_VARIATIONS_3", self.flame_variations[3] as f64),
        ]
    }
}

/// See [`IfsShape::flame_variations`]: the variation numbers of the flame table's terms.
fn flame_variations(ifs: &CompiledIfs) -> [u32; 4] {
    let mut words = [0u32; 4];
    if ifs.has_flames() {
        for op in ifs.flame_ops() {
            if op.kind < 128 {
                words[op.kind as usize / 32] |= 1 << (op.kind % 32);
            }
        }
    }
    words
}

/// See [`IfsShape::shared_cells`]: the shared shader path reads function 0's record and axes
/// for every function, so every field it reads must be equal, bit for bit.
fn shared_cells(ifs: &CompiledIfs) -> Option<[u32; 3]> {
    let f0 = ifs.functions.first()?;
    let n = [f0.cells[0], f0.cells[1], f0.cells[2]];
    let per_function = n.iter().product::<u32>();
    let axis_offsets = [0, n[0] + 1, n[0] + n[1] + 2];
    if f0.coord_offset[..3] != axis_offsets {
        return None;
    }
    let axes = |f: &KernelFunction| -> Option<Vec<[u32; 2]>> {
        (0..3)
            .map(|a| ifs.coords.get(f.coord_offset[a] as usize..(f.coord_offset[a] + n[a] + 1) as usize))
            .collect::<Option<Vec<_>>>()
            .map(|slices| slices.concat().iter().map(|c| c.map(f32::to_bits)).collect())
    };
    let bits = |v: &[f32; 4]| v.map(f32::to_bits);
    let axes0 = axes(f0)?;
    let same = ifs.functions.iter().enumerate().all(|(i, f)| {
        f.coord_offset[3] == KIND_MULTILINEAR
            && f.cells[..3] == n
            && f.cells[3] == i as u32 * per_function
            && bits(&f.lo) == bits(&f0.lo)
            && bits(&f.hi) == bits(&f0.hi)
            && bits(&f.inv_bin) == bits(&f0.inv_bin)
            && axes(f).as_ref() == Some(&axes0)
    });
    same.then_some(n)
}

/// What one frame of the chaos game does.
#[derive(Clone, Copy, Debug)]
pub struct FrameArgs<'a> {
    pub view: &'a SplatView,
    pub seed: u32,
    pub frame: u32,
    /// Steps every point advances.
    pub steps: u32,
    /// Steps at the start of the frame that are not splatted (transient after a change).
    pub skip_steps: u32,
    /// Restart every point at a random point of the domain first.
    pub restart: bool,
    /// Empty the accumulation buffer first.
    pub clear: bool,
}

/// The scene-dependent part of the uniforms, kept from the last upload.
#[derive(Clone, Copy, Debug)]
struct IfsUniforms {
    domain_lo: [f32; 3],
    domain_hi: [f32; 3],
    selection_lo: [f32; 3],
    selection_inv_cell: [f32; 3],
    selection_cells: [u32; 4],
    dimension: u32,
}

/// A table buffer: bindable as storage or uniform, at least its uniform capacity.
fn table(device: &wgpu::Device, label: &str, capacity: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: capacity,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn storage(device: &wgpu::Device, label: &str, size: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

/// Writes `data` to `buffer`, replacing the buffer with a bigger one when it does not fit.
/// Returns true when the buffer was replaced (bind groups must be rebuilt).
fn upload(device: &wgpu::Device, queue: &wgpu::Queue, buffer: &mut wgpu::Buffer, label: &str, data: &[u8]) -> bool {
    if data.len() as u64 > buffer.size() {
        *buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &[data, &vec![0u8; data.len().next_multiple_of(16) - data.len()]].concat(),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        true
    } else {
        if !data.is_empty() {
            queue.write_buffer(buffer, 0, data);
        }
        false
    }
}

/// The bind group layout and pipelines of one of the two chaos-game programs: the clear, and
/// the chaos game specialized (pipeline constants) per splat mode and Julia functions present,
/// made on first use.
struct Program {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    clear_pipeline: wgpu::ComputePipeline,
    chaos_pipelines: Vec<(PipelineKey, wgpu::ComputePipeline)>,
    /// Empties the shadow map.
    clear_shadow_pipeline: wgpu::ComputePipeline,
}

/// What a chaos-game pipeline is specialized for: splat mode (shader number), Julia functions
/// present, IFS shape, shadow map splatted, depth of field on.
type PipelineKey = (u32, bool, IfsShape, bool, bool);

impl Program {
    fn new(device: &wgpu::Device, name: &str, tables: wgpu::BufferBindingType) -> Self {
        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let write = wgpu::BufferBindingType::Storage { read_only: false };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(name),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, tables),
                entry(2, tables),
                entry(3, tables),
                entry(4, tables),
                entry(5, tables),
                entry(6, write),
                entry(7, write),
                entry(8, write),
                entry(9, wgpu::BufferBindingType::Storage { read_only: true }),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(name),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = super::shaders::module(device, name);
        let clear_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("clear"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("clear"),
            compilation_options: Default::default(),
            cache: None,
        });
        let clear_shadow_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("clear_shadow"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("clear_shadow"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self { layout, pipeline_layout, module, clear_pipeline, chaos_pipelines: Vec::new(), clear_shadow_pipeline }
    }

    /// Index of the chaos-game pipeline for `key`.
    fn chaos_pipeline(&mut self, device: &wgpu::Device, key: PipelineKey) -> usize {
        if let Some(i) = self.chaos_pipelines.iter().position(|(k, _)| *k == key) {
            return i;
        }
        let (mode, has_julia, shape, shadowed, lens) = key;
        let constants: Vec<(&str, f64)> = [("SPLAT_MODE", mode as f64), ("HAS_JULIA", has_julia as u32 as f64)]
            .into_iter()
            .chain(shape.constants())
            .chain([("SHADOWED", shadowed as u32 as f64), ("LENS", lens as u32 as f64)])
            .collect();
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("chaos_game"),
            layout: Some(&self.pipeline_layout),
            module: &self.module,
            entry_point: Some("chaos_game"),
            compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
            cache: None,
        });
        self.chaos_pipelines.push((key, pipeline));
        self.chaos_pipelines.len() - 1
    }
}

/// Storage buffers the storage-table program binds (the tables, points, accumulation, shadow
/// map and flame table): one more than WebGPU's default limit of eight.
pub const STORAGE_PROGRAM_BUFFERS: u32 = 9;

/// The colour table of `ifs`: linear RGB and, in w, function i's colour coordinate c_i in
/// palette colour (`color_coord_at`), else 0.
fn color_table(ifs: &CompiledIfs) -> Vec<[f32; 4]> {
    let coord = |i: usize| ifs.color_coords.as_ref().and_then(|c| c.get(i).copied()).unwrap_or(0.0);
    ifs.colors.iter().enumerate().map(|(i, c)| [c[0], c[1], c[2], coord(i)]).collect()
}

/// The table bytes of `ifs` with its colour table `colors`, in the order of
/// [`UNIFORM_CAPACITY`]: functions, coordinates, cells, thresholds, colours.
fn table_bytes<'a>(ifs: &'a CompiledIfs, colors: &'a [[f32; 4]]) -> [&'a [u8]; 5] {
    [
        bytemuck::cast_slice::<KernelFunction, u8>(&ifs.functions),
        bytemuck::cast_slice(&ifs.coords),
        bytemuck::cast_slice::<Cell, u8>(&ifs.cells),
        bytemuck::cast_slice(&ifs.selection.thresholds),
        bytemuck::cast_slice(colors),
    ]
}

/// Tables that fit the uniform program's capacities ([`UNIFORM_CAPACITY`]).
fn fit_uniforms(tables: &[&[u8]; 5]) -> bool {
    tables.iter().zip(UNIFORM_CAPACITY).all(|(t, capacity)| t.len() as u64 <= capacity)
}

/// The tables of `ifs` fit the uniform program's capacities ([`UNIFORM_CAPACITY`]).
pub fn tables_fit_uniforms(ifs: &CompiledIfs) -> bool {
    fit_uniforms(&table_bytes(ifs, &color_table(ifs)))
}

/// Why a device with `limits` cannot run the chaos game of `ifs`, if it cannot: its tables
/// need the storage program and the device binds fewer than [`STORAGE_PROGRAM_BUFFERS`]
/// storage buffers.
pub fn unable_to_run(limits: &wgpu::Limits, ifs: &CompiledIfs) -> Option<&'static str> {
    let storage = limits.max_storage_buffers_per_shader_stage >= STORAGE_PROGRAM_BUFFERS;
    (!storage && !tables_fit_uniforms(ifs)).then_some("tables past the uniform limits, too few storage buffers")
}

pub struct GpuChaosGame {
    uniform_program: Program,
    /// Made on first use: most IFS fit the uniform program, and this one binds
    /// [`STORAGE_PROGRAM_BUFFERS`] storage buffers; a device with fewer still runs every IFS
    /// that fits ([`unable_to_run`]).
    storage_program: Option<Program>,
    /// The tables fit the uniform program's capacities (set by `set_ifs`).
    uniform_tables: bool,
    /// Some compiled function is a Julia map (set by `set_ifs`).
    has_julia: bool,
    /// Use the storage program even when the tables fit (tests compare both programs).
    pub force_storage_tables: bool,
    /// The IFS structure the pipeline is specialized for (set by `set_ifs`).
    shape: IfsShape,
    /// Use the pipeline for any structure even when a specialized one applies (tests compare
    /// both).
    pub force_generic: bool,
    params: wgpu::Buffer,
    functions: wgpu::Buffer,
    coords: wgpu::Buffer,
    cells: wgpu::Buffer,
    thresholds: wgpu::Buffer,
    pub colors: wgpu::Buffer,
    /// The flame table (`CompiledIfs::flame_ops`; a storage buffer in both programs).
    flame_ops: wgpu::Buffer,
    pub points: wgpu::Buffer,
    pub accum: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
    ifs: Option<IfsUniforms>,
    pub point_count: u32,
    pub width: u32,
    pub height: u32,
    /// Bumped whenever `accum`, `colors` or `shadow` is replaced (the resolve pass rebinds).
    pub generation: u64,
    // Shadows (`super::shadow`).
    /// The key light's shadow map (one u32 when the view has none).
    pub shadow: wgpu::Buffer,
    /// The shadow map's side in texels (0: none).
    pub shadow_side: u32,
}

impl GpuChaosGame {
    pub fn new(device: &wgpu::Device, point_count: u32, width: u32, height: u32) -> Self {
        let uniform_program = Program::new(device, "chaos_game", wgpu::BufferBindingType::Uniform);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chaos_params"),
            size: std::mem::size_of::<ChaosParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let [functions, coords, cells, thresholds, colors] = UNIFORM_CAPACITY;
        Self {
            uniform_program,
            storage_program: None,
            uniform_tables: true,
            force_storage_tables: false,
            shape: IfsShape::default(),
            force_generic: false,
            has_julia: true,
            params,
            functions: table(device, "functions", functions),
            coords: table(device, "coords", coords),
            cells: table(device, "cells", cells),
            thresholds: table(device, "thresholds", thresholds),
            colors: table(device, "colors", colors),
            flame_ops: storage(device, "flame_ops", size_of::<FlameOp>() as u64, wgpu::BufferUsages::empty()),
            points: storage(device, "points", point_count as u64 * 16, wgpu::BufferUsages::COPY_SRC),
            accum: storage(device, "accum", width as u64 * height as u64 * 16, wgpu::BufferUsages::COPY_SRC),
            bind_group: None,
            ifs: None,
            point_count,
            width,
            height,
            generation: 0,
            shadow: super::shadow::shadow_buffer(device, 0),
            shadow_side: 0,
        }
    }

    /// Uploads a compiled IFS (the points are kept).
    pub fn set_ifs(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, ifs: &CompiledIfs) {
        let colors = color_table(ifs);
        let tables = table_bytes(ifs, &colors);
        let uniform_tables = !self.force_storage_tables && fit_uniforms(&tables);
        self.has_julia = ifs.functions.iter().any(|f| f.coord_offset[3] == crate::chaos_game::KIND_JULIA);
        self.shape = if self.force_generic {
            // The generic tables: no shared cells, any function count, the selection's cells read.
            IfsShape { shared_cells: None, function_count: 0, single_selection_cell: false, ..IfsShape::of(ifs) }
        } else {
            IfsShape::of(ifs)
        };
        let mut replaced = uniform_tables != self.uniform_tables;
        self.uniform_tables = uniform_tables;
        replaced |= upload(device, queue, &mut self.functions, "functions", tables[0]);
        replaced |= upload(device, queue, &mut self.coords, "coords", tables[1]);
        replaced |= upload(device, queue, &mut self.cells, "cells", tables[2]);
        replaced |= upload(device, queue, &mut self.thresholds, "thresholds", tables[3]);
        replaced |= upload(device, queue, &mut self.flame_ops, "flame_ops", bytemuck::cast_slice(&ifs.flame_ops()));
        let colors_replaced = upload(device, queue, &mut self.colors, "colors", tables[4]);
        if replaced || colors_replaced {
            self.bind_group = None;
        }
        if colors_replaced {
            self.generation += 1;
        }
        let s = &ifs.selection;
        self.ifs = Some(IfsUniforms {
            domain_lo: ifs.domain_lo.to_array(),
            domain_hi: ifs.domain_hi.to_array(),
            selection_lo: s.lo.to_array(),
            selection_inv_cell: s.inv_cell.to_array(),
            selection_cells: [s.cells[0], s.cells[1], s.cells[2], s.function_count],
            dimension: ifs.dimension as u32,
        });
    }

    /// Resizes the accumulation buffer (its contents are lost: clear before the next frame).
    pub fn resize(&mut self, device: &wgpu::Device, width: u32, height: u32) {
        if (width, height) == (self.width, self.height) {
            return;
        }
        self.width = width;
        self.height = height;
        self.accum = storage(device, "accum", width as u64 * height as u64 * 16, wgpu::BufferUsages::COPY_SRC);
        self.bind_group = None;
        self.generation += 1;
    }

    /// Drops the bind group and bumps the generation (a buffer was replaced).
    pub(super) fn invalidate_bindings(&mut self) {
        self.bind_group = None;
        self.generation += 1;
    }

    /// Changes the number of points (they must be restarted before the next splat).
    pub fn set_point_count(&mut self, device: &wgpu::Device, point_count: u32) {
        if point_count == self.point_count {
            return;
        }
        self.point_count = point_count;
        self.points = storage(device, "points", point_count as u64 * 16, wgpu::BufferUsages::COPY_SRC);
        self.bind_group = None;
    }

    /// Writes the frame's uniforms and records the frame (clear, then the chaos game) into
    /// `encoder`. The uniforms are written through the queue, so submit `encoder` before
    /// recording the next frame. Does nothing before an IFS was uploaded.
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        args: &FrameArgs,
    ) {
        let Some(ifs) = self.ifs else { return };
        let v = args.view;
        self.fit_shadow(device, v.shadow.as_ref());
        let params = ChaosParams {
            pixel_from_world: v.pixel_from_world.to_cols_array_2d(),
            background: [v.background[0], v.background[1], v.background[2], v.depth_cue],
            domain_lo: [ifs.domain_lo[0], ifs.domain_lo[1], ifs.domain_lo[2], v.near],
            domain_hi: [ifs.domain_hi[0], ifs.domain_hi[1], ifs.domain_hi[2], v.far],
            selection_lo: [ifs.selection_lo[0], ifs.selection_lo[1], ifs.selection_lo[2], 0.0],
            selection_inv_cell: [ifs.selection_inv_cell[0], ifs.selection_inv_cell[1], ifs.selection_inv_cell[2], 0.0],
            selection_cells: ifs.selection_cells,
            seed: args.seed,
            frame: args.frame,
            steps: args.steps,
            skip_steps: args.skip_steps,
            point_count: self.point_count,
            width: self.width,
            height: self.height,
            mode: mode_index(v.mode),
            dimension: ifs.dimension,
            restart: args.restart as u32,
            threads_per_row: THREADS_PER_ROW,
            shadow_side: v.shadow.map_or(0, |s| s.side_px),
            shadow_from_world: v.shadow.map_or([[0.0; 4]; 4], |s| s.map_from_world.to_cols_array_2d()),
            lens: v.lens.uniform(),
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let program = if self.uniform_tables {
            &mut self.uniform_program
        } else {
            self.storage_program.get_or_insert_with(|| {
                Program::new(device, "chaos_game_storage", wgpu::BufferBindingType::Storage { read_only: true })
            })
        };
        let shadowed = v.shadow.is_some();
        let key = (mode_index(v.mode), self.has_julia, self.shape, shadowed, v.lens.is_on());
        let chaos_index = program.chaos_pipeline(device, key);
        let program = &*program;
        if self.bind_group.is_none() {
            let buffers = [
                &self.params,
                &self.functions,
                &self.coords,
                &self.cells,
                &self.thresholds,
                &self.colors,
                &self.points,
                &self.accum,
                &self.shadow,
                &self.flame_ops,
            ];
            let entries: Vec<wgpu::BindGroupEntry> = buffers
                .iter()
                .enumerate()
                .map(|(i, b)| {
                    // A uniform binding is exactly the shader's fixed-size array.
                    let size = (self.uniform_tables && (1..=5).contains(&i))
                        .then(|| wgpu::BufferSize::new(UNIFORM_CAPACITY[i - 1]))
                        .flatten();
                    wgpu::BindGroupEntry {
                        binding: i as u32,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: b, offset: 0, size }),
                    }
                })
                .collect();
            self.bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("chaos_game"),
                layout: &program.layout,
                entries: &entries,
            }));
        }
        let Some(bind_group) = &self.bind_group else { return };
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("chaos_game"), timestamp_writes: None });
        pass.set_bind_group(0, bind_group, &[]);
        if args.clear {
            pass.set_pipeline(&program.clear_pipeline);
            let per_pixel = if v.mode == SplatMode::Closest { 1 } else { 4 };
            let (x, y) = dispatch_size(per_pixel * self.width as u64 * self.height as u64);
            pass.dispatch_workgroups(x, y, 1);
            if shadowed {
                pass.set_pipeline(&program.clear_shadow_pipeline);
                let (x, y) = dispatch_size(self.shadow_side as u64 * self.shadow_side as u64);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        if args.steps > 0 {
            pass.set_pipeline(&program.chaos_pipelines[chaos_index].1);
            let (x, y) = dispatch_size(self.point_count as u64);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

// Shadows (`super::shadow`).
impl GpuChaosGame {
    /// Resizes the shadow map to `shadow`'s (its contents are lost: the frame must clear).
    pub fn fit_shadow(&mut self, device: &wgpu::Device, shadow: Option<&crate::splat::ShadowView>) {
        let side_px = shadow.map_or(0, |s| s.side_px);
        if side_px != self.shadow_side {
            self.shadow = super::shadow::shadow_buffer(device, side_px);
            self.shadow_side = side_px;
            self.invalidate_bindings();
        }
    }
}

/// Workgroups (x, y) covering `threads` with rows of [`THREADS_PER_ROW`].
pub fn dispatch_size(threads: u64) -> (u32, u32) {
    let groups = threads.div_ceil(WORKGROUP_SIZE as u64).max(1);
    let x = groups.min(GROUPS_PER_ROW as u64) as u32;
    let y = groups.div_ceil(GROUPS_PER_ROW as u64) as u32;
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn shape(file: &str) -> IfsShape {
        let path = format!("{}/scenes/{file}", env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::load(std::path::Path::new(&path)).unwrap();
        IfsShape::of(&CompiledIfs::new(&scene.at(0.0)).unwrap())
    }

    #[test]
    fn shapes_of_paper_scenes() {
        // plant2: 2×4×2 grid points, 1×3×1 cells, five functions on the scene's grid.
        assert_eq!(
            shape("plant2.toml"),
            IfsShape {
                shared_cells: Some([1, 3, 1]),
                function_count: 5,
                single_selection_cell: true,
                xaos: false,
                palette: false,
                palette_linear: false,
                flames: false,
                color_speeds: false,
                final_xform: false,
                flame_variations: [0; 4]
            }
        );
        // Julia maps have no grid.
        assert_eq!(shape("julia.toml").shared_cells, None);
    }

    #[test]
    fn a_function_on_another_grid_is_not_shared() {
        let path = format!("{}/scenes/plant2.toml", env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::load(std::path::Path::new(&path)).unwrap();
        let mut ifs = CompiledIfs::new(&scene.at(0.0)).unwrap();
        assert!(shared_cells(&ifs).is_some());
        // Function 1's y axis moved by one ulp: its cell search would differ.
        let i = (ifs.functions[1].coord_offset[1] + 1) as usize;
        ifs.coords[i][0] = f32::from_bits(ifs.coords[i][0].to_bits() + 1);
        assert_eq!(shared_cells(&ifs), None);
    }
}
