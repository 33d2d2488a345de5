//! Files from other tools: glTF models as initial objects A, and PNGs as `nlifs info` reads them.
//! Each test writes its fixture (a .gltf with its buffers, a .glb, a PNG with text chunks) into
//! a temporary folder and runs the `nlifs` binary on it: a broken file must exit with code 2
//! and a message naming the file and what is wrong with it (never a panic, exit 101, or an
//! abort); a valid one must give the mesh the file describes, read back from `export mesh`.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::{Value, json};

/// A 3D scene with one function, a uniform scale by 1/2 (which keeps windings and area ratios).
const SCENE: &str = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\nz = [0, 1]\n\
[[function]]\nkind = \"builder\"\nsteps = [{ op = \"scale\", by = 0.5 }]\n";

struct Case {
    dir: common::TempDir,
}

impl Case {
    fn new(name: &str) -> Self {
        let dir = common::temp_dir(&format!("gltf-input-{name}"));
        std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
        Case { dir }
    }

    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let path = self.dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    fn write_json(&self, name: &str, doc: &Value) -> PathBuf {
        self.write(name, doc.to_string().as_bytes())
    }

    /// `nlifs export mesh scene.toml --initial MODEL --depth 1 -o out.glb`.
    fn export(&self, model: &Path) -> Output {
        let scene = self.dir.join("scene.toml");
        let out = self.dir.join("out.glb");
        let _ = std::fs::remove_file(&out);
        common::run_nlifs(&[
            "export",
            "mesh",
            scene.to_str().unwrap(),
            "--initial",
            model.to_str().unwrap(),
            "--depth",
            "1",
            "-o",
            out.to_str().unwrap(),
        ])
    }

    /// Exit code 2 with a message naming the model that contains every one of `words`.
    fn refused(&self, model: &Path, words: &[&str]) -> String {
        let out = self.export(model);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{}: {:?}\n{err}", model.display(), out.status);
        assert_clean(&err);
        let name = model.file_name().unwrap().to_str().unwrap();
        assert!(err.contains(name), "the message does not name {name}:\n{err}");
        for w in words {
            assert!(err.contains(w), "`{w}` missing in:\n{err}");
        }
        assert!(!self.dir.join("out.glb").exists(), "an output was written");
        err
    }

    /// The triangles of W^1(A) (positions of their corners) for a model that must load.
    fn triangles(&self, model: &Path) -> Vec<[[f32; 3]; 3]> {
        let out = self.export(model);
        assert!(out.status.success(), "{}: {:?}\n{}", model.display(), out.status, stderr(&out));
        let (doc, buffers, _) = gltf::import(self.dir.join("out.glb")).unwrap();
        let mut triangles = Vec::new();
        for mesh in doc.meshes() {
            for prim in mesh.primitives() {
                let reader = prim.reader(|b| Some(&buffers[b.index()]));
                let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
                let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
                triangles.extend(indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| positions[t[k] as usize])));
            }
        }
        triangles
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// No panic, no abort, no Rust internals in a message meant for the user.
fn assert_clean(err: &str) {
    for word in ["panicked", "RUST_BACKTRACE", "memory allocation", "could not completely read"] {
        assert!(!err.contains(word), "`{word}` in:\n{err}");
    }
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Positions of one triangle (0,0,0), (1,0,0), (0,1,0), then indices 0 1 2: 48 bytes.
fn triangle_bin() -> Vec<u8> {
    let mut bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bin
}

/// One triangle from buffer 0 (`uri`, 48 bytes: [`triangle_bin`]).
fn triangle_doc(uri: &str) -> Value {
    json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
        "buffers": [{"byteLength": 48, "uri": uri}]
    })
}

/// The gltf crate's validation indexed the accessor list with POSITION's index unchecked and
/// panicked (exit 101) before nlifs could look.
#[test]
fn a_missing_position_accessor_is_an_error() {
    let case = Case::new("missing-accessor");
    case.write("tri.bin", &triangle_bin());
    let mut doc = triangle_doc("tri.bin");
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    let model = case.write_json("missing.gltf", &doc);
    case.refused(&model, &["mesh 0 primitive 0", "POSITION accessor 7", "does not exist"]);
    // The same for an index accessor.
    let mut doc = triangle_doc("tri.bin");
    doc["meshes"][0]["primitives"][0]["indices"] = json!(9);
    let model = case.write_json("missing-indices.gltf", &doc);
    case.refused(&model, &["index accessor 9", "does not exist"]);
}

/// A sparse accessor without a buffer view was expanded to `count` zero vertices before any
/// check: a 600-byte file asked for 96 GB and aborted (SIGABRT).
#[test]
fn a_sparse_accessor_is_bounded_before_allocating() {
    let case = Case::new("sparse");
    // Sparse data: indices 0 1 2 (u32) then three positions, and the triangle's indices.
    let mut bin: Vec<u8> = [0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()).collect();
    bin.extend(f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]));
    bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    case.write("sparse.bin", &bin);
    let doc = |count: u64| {
        json!({
            "asset": {"version": "2.0"},
            "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "accessors": [
                {"componentType": 5126, "count": count, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0],
                 "sparse": {"count": 3, "indices": {"bufferView": 0, "componentType": 5125},
                            "values": {"bufferView": 1}}},
                {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"}
            ],
            "bufferViews": [{"buffer": 0, "byteLength": 12}, {"buffer": 0, "byteOffset": 12, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
            "buffers": [{"byteLength": 60, "uri": "sparse.bin"}]
        })
    };
    let huge = case.write_json("huge.gltf", &doc(8_000_000_000));
    assert!(std::fs::metadata(&huge).unwrap().len() < 1000);
    case.refused(&huge, &["POSITION accessor 0", "8000000000 elements", "more than the 67108864"]);
    // Under the element cap, but far more zeros than the whole model's 700-odd bytes.
    let large = case.write_json("large.gltf", &doc(1_000_000));
    case.refused(&large, &["1000000 elements without a buffer view", "bytes of the whole model"]);
    // Three elements, all set by the sparse values: the triangle.
    let ok = case.write_json("ok.gltf", &doc(3));
    assert_eq!(case.triangles(&ok).len(), 1);
}

/// URIs were checked raw and read percent-decoded, `file:` URIs accepted and `../` or absolute
/// ones followed out of the model's folder.
#[test]
fn buffer_uris_stay_in_the_models_folder() {
    let case = Case::new("uris");
    let models = case.dir.join("models");
    std::fs::create_dir_all(models.join("folder.bin")).unwrap();
    std::fs::write(case.dir.join("outside.bin"), triangle_bin()).unwrap();
    let write = |name: &str, uri: &str| {
        let path = models.join(name);
        std::fs::write(&path, triangle_doc(uri).to_string()).unwrap();
        path
    };
    let refusals: [(&str, &str, &[&str]); 9] = [
        ("encoded.gltf", "%2Fdev%2Fzero", &["not a path relative to the model's folder"]),
        ("file.gltf", "file:/dev/zero", &["file: URIs are not supported"]),
        ("file2.gltf", "file:///dev/zero", &["file:// is not supported"]),
        ("http.gltf", "http://example.com/tri.bin", &["http:// is not supported"]),
        ("absolute.gltf", "/etc/passwd", &["not a path relative to the model's folder"]),
        ("proc.gltf", "/proc/self/environ", &["not a path relative to the model's folder"]),
        ("parent.gltf", "../outside.bin", &["lies outside the model's folder"]),
        ("parent-encoded.gltf", "..%2Foutside.bin", &["lies outside the model's folder"]),
        ("folder.gltf", "folder.bin", &["not a regular file"]),
    ];
    for (name, uri, words) in refusals {
        let err = case.refused(&write(name, uri), words);
        assert!(err.contains("buffer 0"), "{err}");
        assert!(!err.contains("root:") && !err.contains("PATH="), "file contents leak into:\n{err}");
    }
    // A link inside the folder to a file outside it is outside too.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/dev/zero", models.join("zero.bin")).unwrap();
        case.refused(&write("link.gltf", "zero.bin"), &["lies outside the model's folder"]);
    }
    // A missing file says so, naming the decoded path.
    case.refused(&write("missing.gltf", "no%20such.bin"), &["cannot open no such.bin"]);
    // Shorter than its byteLength.
    std::fs::write(models.join("short.bin"), &triangle_bin()[..40]).unwrap();
    case.refused(&write("short.gltf", "short.bin"), &["declares 48 bytes", "has 40"]);
    // `Box%200.bin` names the file `Box 0.bin`, decoded once; a subfolder is inside.
    std::fs::write(models.join("Box 0.bin"), triangle_bin()).unwrap();
    assert_eq!(case.triangles(&write("box.gltf", "Box%200.bin")).len(), 1);
    std::fs::create_dir_all(models.join("sub")).unwrap();
    std::fs::write(models.join("sub/tri.bin"), triangle_bin()).unwrap();
    assert_eq!(case.triangles(&write("sub.gltf", "sub/tri.bin")).len(), 1);
    // Decoded exactly once: `%2520` is the file `%20`, not ` `.
    std::fs::write(models.join("a%20b.bin"), triangle_bin()).unwrap();
    assert_eq!(case.triangles(&write("twice.gltf", "a%2520b.bin")).len(), 1);
    // A data: URI in base64.
    let data = format!("data:application/octet-stream;base64,{}", base64_encode(&triangle_bin()));
    assert_eq!(case.triangles(&write("data.gltf", &data)).len(), 1);
}

/// Standard base64 with padding (the test's own, so it checks the decoder against the RFC).
fn base64_encode(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            out.push(if k <= chunk.len() { ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' });
        }
    }
    out
}

/// A primitive whose POSITION ran past its buffer was dropped silently: one of two meshes was
/// drawn and the command exited 0.
#[test]
fn positions_past_their_buffer_are_an_error() {
    let case = Case::new("past-buffer");
    case.write("tri.bin", &triangle_bin());
    let mut doc = triangle_doc("tri.bin");
    doc["meshes"] = json!([
        {"name": "first", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
        {"name": "second", "primitives": [{"attributes": {"POSITION": 2}}]}
    ]);
    doc["nodes"] = json!([{"mesh": 0}, {"mesh": 1}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    doc["accessors"].as_array_mut().unwrap().push(
        json!({"bufferView": 0, "componentType": 5126, "count": 100, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}),
    );
    let model = case.write_json("past.gltf", &doc);
    case.refused(&model, &["mesh 1 (`second`) primitive 0", "POSITION accessor 2", "need 1200 bytes", "which has 36"]);
    // A view past its buffer.
    let mut doc = triangle_doc("tri.bin");
    doc["bufferViews"][0]["byteOffset"] = json!(40);
    let model = case.write_json("view.gltf", &doc);
    case.refused(&model, &["buffer view 0 spans bytes 40..76 of buffer 0, which has 48"]);
}

/// glTF 2.0 ignores the transform of a skinned mesh's node (its joints pose it): the Fox
/// sample took its parent's scale of 0.01 and came out a hundredth of its size.
#[test]
fn a_skinned_mesh_ignores_its_nodes_transform() {
    let case = Case::new("skin");
    case.write("tri.bin", &triangle_bin());
    let mut doc = triangle_doc("tri.bin");
    // Mesh 0 plain at the origin; mesh 1 the same triangle, skinned, under a node scaled by
    // 0.01 and moved by (2, 0, 0): drawn in its bind pose, at the origin and full size.
    doc["meshes"] = json!([
        {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
        {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}
    ]);
    doc["nodes"] = json!([
        {"mesh": 0, "translation": [0, 0, 1]},
        {"scale": [0.01, 0.01, 0.01], "translation": [2, 0, 0], "children": [2, 3]},
        {"mesh": 1, "skin": 0},
        {"name": "joint"}
    ]);
    doc["skins"] = json!([{"joints": [3]}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    let model = case.write_json("skinned.gltf", &doc);
    let triangles = case.triangles(&model);
    assert_eq!(triangles.len(), 2);
    let area = |t: &[[f32; 3]; 3]| {
        let [a, b, c] = t.map(glam::Vec3::from);
        (b - a).cross(c - a).length() / 2.0
    };
    let (a0, a1) = (area(&triangles[0]), area(&triangles[1]));
    // Both are the same triangle, fitted and mapped alike (f32 positions: 1e-4 relative).
    assert!((a0 - a1).abs() <= 1e-4 * a0.max(a1), "areas {a0} and {a1}: the skinned mesh was transformed");
    // And they lie one above the other (z 0 and 1 before the fit): same x and y.
    for k in 0..3 {
        let (p, q) = (triangles[0][k], triangles[1][k]);
        let same = triangles[1].iter().any(|q| (q[0] - p[0]).abs() < 1e-5 && (q[1] - p[1]).abs() < 1e-5);
        assert!(same, "corner {p:?} of one triangle has no partner above or below it in {q:?}'s triangle");
    }
}

/// Triangle strips and fans were refused; they are triangles in the spec's order and winding.
#[test]
fn triangle_strips_and_fans_are_read() {
    let case = Case::new("strips");
    // Strip: (0,0) (1,0) (0,1) (1,1); fan around (0,0): (1,0) (1,1) (0,1) (-1,1). All
    // counter-clockwise seen from +z, so every triangle's normal points along +z.
    let strip = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0];
    let fan = [0.0, 0.0, 0.5, 1.0, 0.0, 0.5, 1.0, 1.0, 0.5, 0.0, 1.0, 0.5, -1.0, 1.0, 0.5];
    let mut bin = f32_bytes(&strip);
    bin.extend(f32_bytes(&fan));
    case.write("strips.bin", &bin);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 5}, {"attributes": {"POSITION": 1}, "mode": 6}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC3", "min": [-1, 0, 0.5], "max": [1, 1, 0.5]}
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 60}],
        "buffers": [{"byteLength": 108, "uri": "strips.bin"}]
    });
    let model = case.write_json("strips.gltf", &doc);
    let triangles = case.triangles(&model);
    assert_eq!(triangles.len(), 2 + 3, "a strip of 4 vertices and a fan of 5");
    for t in &triangles {
        let [a, b, c] = t.map(glam::Vec3::from);
        let n = (b - a).cross(c - a);
        assert!(n.z > 0.0 && n.x.abs() < 1e-6 && n.y.abs() < 1e-6, "triangle {t:?} has normal {n}");
    }
}

/// A GLB of the triangle: header, JSON chunk, BIN chunk (both padded to 4 bytes).
fn triangle_glb() -> Vec<u8> {
    let mut doc = triangle_doc("");
    doc["buffers"] = json!([{"byteLength": 48}]);
    let mut json = doc.to_string().into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin = triangle_bin();
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = b"glTF".to_vec();
    for word in [2, total as u32, json.len() as u32, 0x4E4F_534A] {
        glb.extend(word.to_le_bytes());
    }
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(0x004E_4942u32.to_le_bytes());
    glb.extend(&bin);
    glb
}

/// A truncated GLB said "could not completely read the object"; a required extension was
/// named at the end of a 4,000-character line of validation errors.
#[test]
fn truncated_glbs_and_required_extensions_say_so() {
    let case = Case::new("glb");
    let glb = triangle_glb();
    let whole = case.write("whole.glb", &glb);
    assert_eq!(case.triangles(&whole).len(), 1);
    let cut = glb.len() - 20;
    let truncated = case.write("truncated.glb", &glb[..cut]);
    case.refused(&truncated, &["truncated GLB", &format!("says {} bytes, the file has {cut}", glb.len())]);
    let header = case.write("header.glb", &glb[..10]);
    case.refused(&header, &["truncated GLB", "needs 12 bytes, the file has 10"]);
    // A chunk that claims more than the file holds (the header's total fixed up to match).
    let mut chunk = glb.clone();
    chunk[12..16].copy_from_slice(&100_000u32.to_le_bytes());
    let chunk = case.write("chunk.glb", &chunk);
    case.refused(&chunk, &["truncated GLB", "chunk 0 at byte 12 says 100000 bytes"]);

    let mut doc = triangle_doc("tri.bin");
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    // Draco primitives have accessors without views: the old message listed each of them.
    for k in 0..40 {
        doc["accessors"].as_array_mut().unwrap().push(json!({"componentType": 5126, "count": k + 1, "type": "VEC3"}));
    }
    let draco = case.write_json("draco.gltf", &doc);
    let err =
        case.refused(&draco, &["requires the glTF extension KHR_draco_mesh_compression, which nlifs does not support"]);
    assert!(err.len() < 300, "{} characters:\n{err}", err.len());
    // Extensions that change no geometry are fine.
    case.write("tri.bin", &triangle_bin());
    let mut doc = triangle_doc("tri.bin");
    doc["extensionsRequired"] = json!(["KHR_materials_unlit", "KHR_texture_transform"]);
    assert_eq!(case.triangles(&case.write_json("unlit.gltf", &doc)).len(), 1);
}

/// A 1×1 PNG with the given iTXt chunks, as nlifs writes its scenes.
fn png_with(chunks: &[(&str, &str)]) -> Vec<u8> {
    let mut plain = Vec::new();
    image::RgbImage::new(1, 1).write_to(&mut std::io::Cursor::new(&mut plain), image::ImageFormat::Png).unwrap();
    nlifs::output::png::with_text_chunks(&plain, chunks)
}

/// `nlifs info` printed the control bytes of an embedded scene's name and description raw
/// (terminal escape sequences, NUL) and a stored time of 1e308 as a 309-digit number.
#[test]
fn info_escapes_control_characters_and_checks_the_time() {
    use nlifs::output::png::{SCENE_KEYWORD, SETTINGS_KEYWORD};
    let case = Case::new("info");
    let toml = format!(
        "name = \"evil\\u001b]0;title\\u0007\\u001b[2J\\u0000\"\ndescription = \"line one\\nline\\r two \\u202e\"\n{SCENE}"
    );
    let png = case.write("scene.png", &png_with(&[(SCENE_KEYWORD, &toml), (SETTINGS_KEYWORD, "{\"t_secs\":1.5}")]));
    let out = common::run_nlifs(&["info", png.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{:?}\n{}", out.status, stderr(&out));
    for c in ['\u{1b}', '\u{7}', '\0', '\r', '\u{202e}'] {
        assert!(!text.contains(c), "{c:?} printed raw:\n{text}");
    }
    assert!(text.contains(r"evil\u{1b}]0;title\u{7}\u{1b}[2J\0"), "{text}");
    assert!(text.contains("line one\nline\\r two \\u{202e}"), "a description keeps its lines:\n{text}");
    assert!(text.contains("t = 1.5 s"), "{text}");

    for (t, shown) in [("1e308", "1e308"), ("-1", "-1e0"), ("\"soon\"", "\"soon\"")] {
        let settings = format!("{{\"t_secs\":{t}}}");
        let png = case.write("time.png", &png_with(&[(SCENE_KEYWORD, SCENE), (SETTINGS_KEYWORD, &settings)]));
        let out = common::run_nlifs(&["info", png.to_str().unwrap()]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "t_secs {t}: {:?}\n{err}", out.status);
        assert!(err.contains("time.png"), "{err}");
        assert!(err.contains(&format!("t_secs = {shown}, not a scene time (0 to 1e9 s)")), "{err}");
        assert!(err.len() < 300, "{err}");
        assert_clean(&err);
    }
}

/// Every byte of a small GLB replaced by a few values (digits make counts, offsets and indices
/// large): each load succeeds or is an error, never a panic (in process, so a panic fails the
/// test), and never an allocation past the caps (which would abort it).
#[test]
fn byte_changes_of_a_glb_never_panic() {
    let case = Case::new("mutations");
    let glb = triangle_glb();
    let path = case.dir.join("m.glb");
    let (mut loaded, mut refused) = (0, 0);
    for at in 0..glb.len() {
        for value in [0xffu8, b'9', b'"'] {
            let mut bytes = glb.clone();
            bytes[at] = value;
            std::fs::write(&path, &bytes).unwrap();
            match nlifs::raytrace::mesh::load_gltf(&path, glam::DVec3::ZERO, glam::DVec3::ONE) {
                Ok(_) => loaded += 1,
                Err(_) => refused += 1,
            }
        }
    }
    // Both outcomes occur: the loop reaches past the parser (e.g. a changed position or a
    // name), and the checks behind it.
    assert!(loaded > 0 && refused > 0, "{loaded} loaded, {refused} refused");
}
