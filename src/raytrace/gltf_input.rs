//! Reading third-party glTF 2.0 files (.gltf with external or `data:` buffers, and .glb) into
//! one triangle mesh in the file's own coordinates: the default scene's nodes with their
//! transforms, every triangle, strip and fan primitive. `mesh::load_gltf` fits the
//! result into the grid's box.
//!
//! Everything here reads untrusted files, so nothing is taken on trust: the JSON is parsed with
//! `gltf-json` but never validated by the `gltf` crate (its validation indexes accessors
//! unchecked and panics on a missing one), every index into the document is looked up with a
//! check, every accessor is checked against its buffer view and every view against its buffer
//! before a byte is read, and element counts are bounded before anything is allocated. Buffers
//! are loaded here too rather than by `gltf::import_buffers`: a `data:` URI is decoded, any other
//! scheme refused, and a relative URI is percent-decoded once, resolved against the model's
//! folder, canonicalized and required to stay inside it, name a regular file and hold the
//! buffer's `byteLength`. Each problem is a sentence naming the mesh, primitive, accessor,
//! buffer view, buffer or node it is about.

use std::borrow::Cow;
use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DMat4, DQuat, DVec3};
use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

/// The largest glTF file or external buffer read: 2 GiB, ten times a 10 M-triangle mesh.
pub const MAX_MESH_BYTES: u64 = 2 << 30;

/// The most elements one accessor may have, and the most vertices (and triangles) the placed
/// meshes may add up to: 2²⁶, about 67 M, 1.6 GB of f64 positions (a 10 M-triangle mesh has
/// about 5 M vertices).
pub const MAX_ELEMENTS: u64 = 1 << 26;

/// Required extensions that change nothing about the geometry nlifs reads (materials,
/// textures, lights), and KHR_mesh_quantization, whose integer positions are read.
fn extension_is_harmless(name: &str) -> bool {
    name == "KHR_mesh_quantization"
        || name == "KHR_lights_punctual"
        || name.starts_with("KHR_materials_")
        || name.starts_with("KHR_texture_")
        || name.starts_with("EXT_texture_")
}

/// An indexed triangle mesh as the file gives it (`mesh::Mesh` is made of it, which keeps this
/// module below `mesh`).
#[derive(Default)]
pub struct Triangles {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The triangle mesh of the glTF or GLB file at `path`, in the file's coordinates.
pub fn read_mesh(path: &Path) -> Result<Triangles, String> {
    let bytes = read_capped(path)?;
    let (json_bytes, bin) = if bytes.starts_with(b"glTF") { split_glb(&bytes)? } else { (&bytes[..], None) };
    check_head(json_bytes)?;
    let root: json::Root = serde_json::from_slice(json_bytes).map_err(|e| format!("not a glTF 2.0 document: {e}"))?;
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let folder =
        std::fs::canonicalize(folder).map_err(|e| format!("cannot resolve the folder {}: {e}", folder.display()))?;
    let declared: u64 = root.buffers.iter().map(|b| b.byte_length.0.min(MAX_MESH_BYTES)).sum();
    let mut model = Model {
        buffers: vec![None; root.buffers.len()],
        root,
        folder,
        bin,
        model_bytes: bytes.len() as u64 + declared,
    };
    model.read_scene()
}

/// Refuses what is not a regular file of at most [`MAX_MESH_BYTES`].
fn check_mesh_file(path: &Path) -> Result<std::fs::Metadata, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > MAX_MESH_BYTES {
        return Err(format!("{} bytes, more than the {MAX_MESH_BYTES} a mesh may have", meta.len()));
    }
    Ok(meta)
}

/// The bytes of a regular file of at most [`MAX_MESH_BYTES`] (the read is capped too, in case
/// the file grows meanwhile).
fn read_capped(path: &Path) -> Result<Vec<u8>, String> {
    check_mesh_file(path)?;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_MESH_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_MESH_BYTES {
        return Err(format!("more than the {MAX_MESH_BYTES} bytes a mesh may have"));
    }
    Ok(bytes)
}

/// The JSON chunk and the binary chunk (if any) of a GLB file: a 12-byte header (magic,
/// version 2, total length), then chunks of (length, type, data).
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let word = |at: usize| -> Option<u32> { Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?)) };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!("truncated GLB: its header needs 12 bytes, the file has {}", bytes.len()));
    };
    if version != 2 {
        return Err(format!("GLB version {version} is not supported (nlifs reads glTF 2.0)"));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!("truncated GLB: its header says {length} bytes, the file has {}", bytes.len()));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length {
        let (Some(chunk_length), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(format!(
                "truncated GLB: chunk {} at byte {at} needs an 8-byte header, {} bytes are left",
                chunks.len(),
                length - at
            ));
        };
        let start = at + 8;
        let end = start.checked_add(chunk_length as usize).filter(|&e| e <= length).ok_or_else(|| {
            format!(
                "truncated GLB: chunk {} at byte {at} says {chunk_length} bytes, {} are left",
                chunks.len(),
                length - start
            )
        })?;
        chunks.push((kind, &bytes[start..end]));
        // Chunks are padded to 4 bytes.
        at = end.next_multiple_of(4);
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(JSON, json)) => Ok((json, chunks.get(1).filter(|(kind, _)| *kind == BIN).map(|(_, data)| *data))),
        _ => Err("GLB without a JSON chunk first".into()),
    }
}

/// Checks the version and the required extensions before the whole document is parsed, so
/// that a Draco-compressed file says so rather than failing on its missing buffer views.
fn check_head(json_bytes: &[u8]) -> Result<(), String> {
    #[derive(serde::Deserialize)]
    struct Head {
        asset: Option<Asset>,
        #[serde(rename = "extensionsRequired", default)]
        extensions_required: Vec<serde_json::Value>,
    }
    #[derive(serde::Deserialize)]
    struct Asset {
        version: Option<serde_json::Value>,
    }
    let head: Head = serde_json::from_slice(json_bytes).map_err(|e| format!("not a glTF 2.0 document: {e}"))?;
    if let Some(version) = head.asset.and_then(|a| a.version) {
        let text = version.as_str().map_or_else(|| version.to_string(), str::to_owned);
        if !text.starts_with("2.") {
            return Err(format!("glTF version {} is not supported (nlifs reads glTF 2.0)", shown(&text)));
        }
    }
    for extension in &head.extensions_required {
        let name = extension.as_str().map_or_else(|| extension.to_string(), str::to_owned);
        if !extension_is_harmless(&name) {
            return Err(format!("requires the glTF extension {}, which nlifs does not support", shown(&name)));
        }
    }
    Ok(())
}

/// `text` as it may appear in a message: at most 80 characters (a `data:` URI can be
/// megabytes), control characters escaped ([`crate::io::printable`]).
fn shown(text: &str) -> String {
    let head: String = text.chars().take(80).collect();
    let mut out = crate::io::printable(&head, false).into_owned();
    if head.len() < text.len() {
        out.push('…');
    }
    out
}

/// A parsed document with its buffers, each loaded when an accessor first needs it (a model
/// whose animation buffer is missing still has its geometry).
struct Model<'a> {
    root: json::Root,
    /// The model's folder, canonical: external buffers must lie inside it.
    folder: PathBuf,
    /// The GLB's binary chunk.
    bin: Option<&'a [u8]>,
    buffers: Vec<Option<Cow<'a, [u8]>>>,
    /// The model file's size plus its buffers' declared sizes: accessors without a buffer view
    /// (all zeros but their sparse values) may not describe more bytes than this.
    model_bytes: u64,
}

/// One primitive's triangles in its mesh's coordinates.
struct Part {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

/// Where an accessor's elements lie: `bytes` of a view, the first at `offset`, then every
/// `stride` bytes.
struct Layout<'b> {
    bytes: &'b [u8],
    offset: usize,
    stride: usize,
}

impl<'a> Model<'a> {
    /// Every mesh of the default scene (or the first), placed by its nodes; every mesh as it
    /// is when the file has no scene.
    fn read_scene(&mut self) -> Result<Triangles, String> {
        let mut placed: Vec<(usize, DMat4)> = Vec::new();
        let scene = match self.root.scene {
            Some(s) => Some(
                self.root
                    .scenes
                    .get(s.value())
                    .ok_or_else(|| format!("the default scene {} does not exist", s.value()))?,
            ),
            None => self.root.scenes.first(),
        };
        match scene {
            Some(scene) => {
                let mut reached = vec![false; self.root.nodes.len()];
                let mut stack: Vec<(usize, DMat4)> =
                    scene.nodes.iter().rev().map(|n| (n.value(), DMat4::IDENTITY)).collect();
                while let Some((index, parent)) = stack.pop() {
                    let node = self.root.nodes.get(index).ok_or_else(|| format!("node {index} does not exist"))?;
                    if std::mem::replace(&mut reached[index], true) {
                        return Err(format!("node {index} is reached twice: the node hierarchy is not a tree"));
                    }
                    let world = parent * node_transform(node).map_err(|m| format!("node {index}: {m}"))?;
                    if let Some(mesh) = node.mesh {
                        // glTF 2.0: a skinned mesh is posed by its joints alone; the transform
                        // of the node that holds it is ignored. Without skinning, the mesh is
                        // drawn in its bind pose, in which joint × inverse bind matrix is the
                        // identity.
                        placed.push((mesh.value(), if node.skin.is_some() { DMat4::IDENTITY } else { world }));
                    }
                    stack.extend(node.children.iter().flatten().rev().map(|c| (c.value(), world)));
                }
            }
            None => placed.extend((0..self.root.meshes.len()).map(|m| (m, DMat4::IDENTITY))),
        }
        let mut parts: Vec<Option<Vec<Part>>> = (0..self.root.meshes.len()).map(|_| None).collect();
        let mut mesh = Triangles::default();
        for (m, world) in placed {
            if m >= parts.len() {
                return Err(format!("mesh {m} does not exist (the file has {})", parts.len()));
            }
            if parts[m].is_none() {
                parts[m] = Some(self.read_mesh(m)?);
            }
            for part in parts[m].iter().flatten() {
                let vertices = mesh.positions.len() as u64 + part.positions.len() as u64;
                let triangles = mesh.triangles.len() as u64 + part.triangles.len() as u64;
                if vertices > MAX_ELEMENTS || triangles > MAX_ELEMENTS {
                    return Err(format!(
                        "the scene places more than the {MAX_ELEMENTS} vertices or triangles nlifs reads"
                    ));
                }
                let base = mesh.positions.len() as u32;
                mesh.positions.extend(part.positions.iter().map(|&p| world.transform_point3(p)));
                mesh.triangles.extend(part.triangles.iter().map(|t| t.map(|i| base + i)));
            }
        }
        Ok(mesh)
    }

    /// The surface primitives (triangles, strips, fans) of mesh `m`; points and lines are
    /// skipped, having no surface.
    fn read_mesh(&mut self, m: usize) -> Result<Vec<Part>, String> {
        let mesh = &self.root.meshes[m];
        let label = match &mesh.name {
            Some(name) => format!("mesh {m} (`{}`)", shown(name)),
            None => format!("mesh {m}"),
        };
        let prims: Vec<(Checked<Mode>, Option<usize>, Option<usize>)> = mesh
            .primitives
            .iter()
            .map(|p| {
                let position = p.attributes.get(&Checked::Valid(Semantic::Positions)).map(|a| a.value());
                (p.mode, position, p.indices.map(|a| a.value()))
            })
            .collect();
        let mut parts = Vec::new();
        for (p, (mode, position, indices)) in prims.into_iter().enumerate() {
            let label = format!("{label} primitive {p}");
            let Checked::Valid(mode) = mode else { return Err(format!("{label}: unknown mode")) };
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                continue;
            }
            let Some(position) = position else { continue };
            let positions = self
                .read_accessor(position, Type::Vec3, &[], |v| DVec3::new(v[0], v[1], v[2]))
                .map_err(|e| format!("{label}: POSITION accessor {position}: {e}"))?;
            let n = positions.len() as u32;
            let indices: Vec<u32> = match indices {
                Some(a) => self
                    .read_accessor(a, Type::Scalar, &[ComponentType::U8, ComponentType::U16, ComponentType::U32], |v| {
                        v[0] as u32
                    })
                    .map_err(|e| format!("{label}: index accessor {a}: {e}"))?,
                None => (0..n).collect(),
            };
            if let Some(bad) = indices.iter().find(|&&i| i >= n) {
                return Err(format!(
                    "{label}: index {bad} out of range (POSITION accessor {position} has {n} vertices)"
                ));
            }
            parts.push(Part { positions, triangles: triangulate(mode, &indices) });
        }
        Ok(parts)
    }

    /// The elements of accessor `index`, which must be of type `ty` and (where `components`
    /// is not empty) one of those component types, each made by `make` from its components
    /// (integers normalized where the accessor says so), with its sparse values applied.
    fn read_accessor<T: Copy + Default>(
        &mut self,
        index: usize,
        ty: Type,
        components: &[ComponentType],
        make: impl Fn(&[f64]) -> T,
    ) -> Result<Vec<T>, String> {
        let accessor = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| format!("does not exist (the file has {} accessors)", self.root.accessors.len()))?;
        let Checked::Valid(found) = accessor.type_ else { return Err("unknown type".into()) };
        if found != ty {
            return Err(format!("of type {}, not {}", type_name(found), type_name(ty)));
        }
        let Checked::Valid(GenericComponentType(component)) = accessor.component_type else {
            return Err("unknown componentType".into());
        };
        if !components.is_empty() && !components.contains(&component) {
            return Err(format!("componentType {}, not an unsigned integer", component.as_gl_enum()));
        }
        let (count, normalized) = (accessor.count.0, accessor.normalized);
        let (view, byte_offset, sparse) = (accessor.buffer_view, accessor.byte_offset, accessor.sparse.clone());
        let element = ty.multiplicity() * component.size();
        if count > MAX_ELEMENTS {
            return Err(format!("{count} elements, more than the {MAX_ELEMENTS} nlifs reads"));
        }
        if view.is_none() && count * element as u64 > self.model_bytes {
            return Err(format!(
                "{count} elements without a buffer view ({} bytes of zeros), more than the {} bytes of the whole model",
                count * element as u64,
                self.model_bytes
            ));
        }
        let read = |layout: &Layout, k: usize| -> T {
            let at = layout.offset + k * layout.stride;
            let mut values = [0.0; 4];
            for (c, v) in values.iter_mut().enumerate().take(ty.multiplicity()) {
                let start = at + c * component.size();
                *v = component_value(&layout.bytes[start..start + component.size()], component, normalized);
            }
            make(&values)
        };
        let count = count as usize;
        // Every layout is checked (and its buffer loaded) before the elements are allocated.
        let offset = byte_offset.map_or(0, |o| o.0);
        if let Some(view) = view {
            self.load_view(view.value())?;
            self.layout(view.value(), offset, count, element, true)?;
        }
        let sparse = match sparse {
            None => None,
            Some(sparse) => {
                let sparse_count = sparse.count.0;
                if sparse_count > count as u64 {
                    return Err(format!("{sparse_count} sparse values for {count} elements"));
                }
                let Checked::Valid(IndexComponentType(index_component)) = sparse.indices.component_type else {
                    return Err("sparse indices of an unknown componentType".into());
                };
                let sparse_count = sparse_count as usize;
                let indices = (sparse.indices.buffer_view.value(), sparse.indices.byte_offset.0);
                let values = (sparse.values.buffer_view.value(), sparse.values.byte_offset.0);
                self.load_view(indices.0).map_err(|e| format!("sparse indices: {e}"))?;
                self.load_view(values.0).map_err(|e| format!("sparse values: {e}"))?;
                self.layout(indices.0, indices.1, sparse_count, index_component.size(), false)
                    .map_err(|e| format!("sparse indices: {e}"))?;
                self.layout(values.0, values.1, sparse_count, element, false)
                    .map_err(|e| format!("sparse values: {e}"))?;
                Some((sparse_count, index_component, indices, values))
            }
        };
        let mut out = vec![T::default(); count];
        if let Some(view) = view {
            let layout = self.layout(view.value(), offset, count, element, true)?;
            for (k, slot) in out.iter_mut().enumerate() {
                *slot = read(&layout, k);
            }
        }
        if let Some((sparse_count, index_component, (iv, io), (vv, vo))) = sparse {
            let indices = self.layout(iv, io, sparse_count, index_component.size(), false)?;
            let values = self.layout(vv, vo, sparse_count, element, false)?;
            for j in 0..sparse_count {
                let at = indices.offset + j * indices.stride;
                let target = component_value(&indices.bytes[at..at + index_component.size()], index_component, false);
                let target = target as usize;
                if target >= count {
                    return Err(format!("sparse index {target} out of range ({count} elements)"));
                }
                out[target] = read(&values, j);
            }
        }
        Ok(out)
    }

    /// Loads the buffer of buffer view `v`.
    fn load_view(&mut self, v: usize) -> Result<(), String> {
        let view =
            self.root.buffer_views.get(v).ok_or_else(|| {
                format!("buffer view {v} does not exist (the file has {})", self.root.buffer_views.len())
            })?;
        self.buffer(view.buffer.value())?;
        Ok(())
    }

    /// Checks that `count` elements of `element` bytes from `offset` in buffer view `v` lie
    /// inside the view, and the view inside its buffer (loaded by [`Self::load_view`]).
    /// `strided` views may set `byteStride`; sparse ones are tightly packed.
    fn layout(&self, v: usize, offset: u64, count: usize, element: usize, strided: bool) -> Result<Layout<'_>, String> {
        let Some(view) = self.root.buffer_views.get(v) else { return Err(format!("buffer view {v} does not exist")) };
        let (b, start, length) = (view.buffer.value(), view.byte_offset.map_or(0, |o| o.0), view.byte_length.0);
        let stride = match view.byte_stride {
            Some(s) if strided => s.0,
            _ => element,
        };
        if stride < element {
            return Err(format!(
                "buffer view {v} has a byteStride of {stride}, less than the element's {element} bytes"
            ));
        }
        let data = self.buffers.get(b).and_then(|d| d.as_deref()).unwrap_or_default();
        let end = start.checked_add(length).filter(|&e| e <= data.len() as u64).ok_or_else(|| {
            format!(
                "buffer view {v} spans bytes {start}..{} of buffer {b}, which has {}",
                start.saturating_add(length),
                data.len()
            )
        })?;
        let need = match count {
            0 => 0,
            _ => offset as u128 + (count as u128 - 1) * stride as u128 + element as u128,
        };
        if need > length as u128 {
            return Err(format!(
                "its {count} elements from byte {offset} need {need} bytes of buffer view {v}, which has {length}"
            ));
        }
        Ok(Layout { bytes: &data[start as usize..end as usize], offset: offset as usize, stride })
    }

    /// Loads buffer `b` unless it is loaded.
    fn buffer(&mut self, b: usize) -> Result<(), String> {
        let buffer = self
            .root
            .buffers
            .get(b)
            .ok_or_else(|| format!("buffer {b} does not exist (the file has {})", self.root.buffers.len()))?;
        if self.buffers[b].is_none() {
            let length = buffer.byte_length.0;
            if length > MAX_MESH_BYTES {
                return Err(format!(
                    "buffer {b} declares {length} bytes, more than the {MAX_MESH_BYTES} a mesh may have"
                ));
            }
            let data = match &buffer.uri {
                None => match (b, self.bin) {
                    (0, Some(bin)) if bin.len() as u64 >= length => Cow::Borrowed(&bin[..length as usize]),
                    (0, Some(bin)) => {
                        return Err(format!(
                            "buffer 0 declares {length} bytes, the GLB's binary chunk holds {}",
                            bin.len()
                        ));
                    }
                    _ => return Err(format!("buffer {b} has no uri and is not the GLB's binary chunk")),
                },
                Some(uri) => Cow::Owned(
                    self.read_uri(uri, length).map_err(|e| format!("buffer {b} (uri `{}`): {e}", shown(uri)))?,
                ),
            };
            self.buffers[b] = Some(data);
        }
        Ok(())
    }

    /// The first `length` bytes a buffer's URI names: a `data:` URI decoded, or a file inside
    /// the model's folder.
    fn read_uri(&self, uri: &str, length: u64) -> Result<Vec<u8>, String> {
        let too_short = |found: usize| format!("declares {length} bytes, the data holds {found}");
        if let Some(data) = uri.strip_prefix("data:") {
            let (header, payload) = data.split_once(',').ok_or("a data: URI without a comma")?;
            let bytes = if header.ends_with(";base64") {
                base64::decode(payload).map_err(|e| format!("bad base64 in the data: URI: {e}"))?
            } else {
                percent_encoding::percent_decode_str(payload).collect()
            };
            if (bytes.len() as u64) < length {
                return Err(too_short(bytes.len()));
            }
            return Ok(bytes[..length as usize].to_vec());
        }
        if let Some((scheme, rest)) = uri.split_once(':')
            && scheme.len() > 1
            && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
            && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        {
            let scheme = scheme.to_ascii_lowercase();
            return Err(if rest.starts_with("//") {
                format!("{scheme}:// is not supported: nlifs reads buffers from files beside the model and data: URIs")
            } else {
                format!("{scheme}: URIs are not supported: give the file's path relative to the model")
            });
        }
        let decoded = percent_encoding::percent_decode_str(uri)
            .decode_utf8()
            .map_err(|_| "not UTF-8 once percent-decoded".to_string())?;
        let relative = Path::new(decoded.as_ref());
        if decoded.contains('\0') || relative.is_absolute() || decoded.starts_with('\\') {
            return Err("not a path relative to the model's folder".into());
        }
        let file = std::fs::canonicalize(self.folder.join(relative))
            .map_err(|e| format!("cannot open {}: {e}", shown(&decoded)))?;
        if !file.starts_with(&self.folder) {
            return Err(format!("{} lies outside the model's folder {}", shown(&decoded), self.folder.display()));
        }
        let size = check_mesh_file(&file).map_err(|e| format!("{}: {e}", shown(&decoded)))?.len();
        if size < length {
            return Err(format!("declares {length} bytes, the file {} has {size}", shown(&decoded)));
        }
        let mut bytes = Vec::new();
        std::fs::File::open(&file)
            .and_then(|f| f.take(length).read_to_end(&mut bytes))
            .map_err(|e| format!("cannot read {}: {e}", shown(&decoded)))?;
        if (bytes.len() as u64) < length {
            return Err(too_short(bytes.len()));
        }
        Ok(bytes)
    }
}

/// An accessor type as glTF spells it.
fn type_name(ty: Type) -> &'static str {
    match ty {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// One component, little-endian; normalized integers map to [0, 1] or [-1, 1] as glTF says.
fn component_value(bytes: &[u8], component: ComponentType, normalized: bool) -> f64 {
    let b = |i: usize| bytes.get(i).copied().unwrap_or(0);
    let (value, scale) = match component {
        ComponentType::I8 => (b(0) as i8 as f64, 127.0),
        ComponentType::U8 => (b(0) as f64, 255.0),
        ComponentType::I16 => (i16::from_le_bytes([b(0), b(1)]) as f64, 32767.0),
        ComponentType::U16 => (u16::from_le_bytes([b(0), b(1)]) as f64, 65535.0),
        ComponentType::U32 => (u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64, u32::MAX as f64),
        ComponentType::F32 => return f32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64,
    };
    if normalized { (value / scale).max(-1.0) } else { value }
}

/// A node's local transform: its matrix, or translation × rotation × scale.
fn node_transform(node: &json::Node) -> Result<DMat4, String> {
    if let Some(m) = node.matrix {
        if !m.iter().all(|v| v.is_finite()) {
            return Err("its matrix is not finite".into());
        }
        return Ok(DMat4::from_cols_array(&m.map(f64::from)));
    }
    let translation = node.translation.unwrap_or([0.0; 3]);
    let rotation = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
    let scale = node.scale.unwrap_or([1.0; 3]);
    if !translation.iter().chain(&rotation).chain(&scale).all(|v| v.is_finite()) {
        return Err("its translation, rotation or scale is not finite".into());
    }
    let rotation = DQuat::from_array(rotation.map(f64::from));
    let length = rotation.length();
    if !(length > 1e-6) {
        return Err("its rotation is not a quaternion (length 0)".into());
    }
    Ok(DMat4::from_scale_rotation_translation(
        DVec3::from_array(scale.map(f64::from)),
        rotation / length,
        DVec3::from_array(translation.map(f64::from)),
    ))
}

/// The triangles of a primitive's vertex list: triangles in threes (an incomplete last one
/// dropped), strips and fans as the glTF 2.0 spec (§3.7.2.1) lists them, which keeps every
/// triangle's winding: strip triangle i is (i, i+1, i+2) for even i and (i, i+2, i+1) for odd
/// i; fan triangle i is (i+1, i+2, 0).
pub(super) fn triangulate(mode: Mode, v: &[u32]) -> Vec<[u32; 3]> {
    let runs = v.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..runs)
            .map(|i| if i % 2 == 0 { [v[i], v[i + 1], v[i + 2]] } else { [v[i], v[i + 2], v[i + 1]] })
            .collect(),
        Mode::TriangleFan => (0..runs).map(|i| [v[i + 1], v[i + 2], v[0]]).collect(),
        _ => v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_follow_the_spec() {
        let v = [10, 11, 12, 13, 14];
        assert_eq!(triangulate(Mode::TriangleStrip, &v), vec![[10, 11, 12], [11, 13, 12], [12, 13, 14]]);
        assert_eq!(triangulate(Mode::TriangleFan, &v), vec![[11, 12, 10], [12, 13, 10], [13, 14, 10]]);
        assert_eq!(triangulate(Mode::Triangles, &v), vec![[10, 11, 12]]);
        assert!(triangulate(Mode::TriangleStrip, &v[..2]).is_empty());
    }

    #[test]
    fn glb_lengths_are_checked() {
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&100u32.to_le_bytes());
        let e = split_glb(&glb).unwrap_err();
        assert!(e.contains("truncated") && e.contains("100") && e.contains("12"), "{e}");
    }

    #[test]
    fn shown_escapes_controls_and_shortens() {
        assert_eq!(shown("a\u{1b}[31mb\0"), "a\\u{1b}[31mb\\0");
        assert_eq!(shown(&"x".repeat(100)).chars().count(), 81);
    }
}
