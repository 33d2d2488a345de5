//! W^n(A) out of the program: a glTF 2.0 binary with one mesh primitive per function (spheres
//! as merged low-poly icospheres, mesh leaves as their mapped triangles, smooth normals), and a
//! POV-Ray 3.7 scene of the leaf spheres with the tracer's camera, lights and ground, which the
//! benchmark renders side by side with our tracer.

use std::io::Write;

use glam::Vec3;

use super::geometry::NodeKind;
use super::hierarchy::Hierarchy;
use super::tracer::Shading;
use crate::camera::{OrbitCamera, Projection};
use crate::export::write_glb;

/// Unit icosphere: an icosahedron subdivided once (42 vertices, 80 triangles).
fn icosphere() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3::from(p).normalize())
    .to_vec();
    let faces: [[u32; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut mid = std::collections::BTreeMap::new();
    let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vec3>| -> u32 {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            v.push((v[a as usize] + v[b as usize]).normalize());
            v.len() as u32 - 1
        })
    };
    let mut tris = Vec::with_capacity(80);
    for [a, b, c] in faces {
        let (ab, bc, ca) = (midpoint(a, b, &mut v), midpoint(b, c, &mut v), midpoint(c, a, &mut v));
        tris.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    (v, tris)
}

#[derive(Default)]
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
}

/// W^n(A) as GLB: per function (in enabled order) one node, one mesh, one primitive with
/// POSITION, NORMAL, u32 indices and a material of the function's colour (linear RGB).
pub fn write_glb_mesh(w: &mut dyn Write, h: &Hierarchy, colors: &[[f32; 3]], names: &[String]) -> std::io::Result<()> {
    let mut parts: Vec<Part> = (0..colors.len().max(1)).map(|_| Part::default()).collect();
    let (ico_v, ico_t) = icosphere();
    let mut remap = vec![u32::MAX; h.positions.len()];
    for node in &h.nodes {
        let Some(part) = parts.get_mut(node.function as usize) else { continue };
        match node.kind {
            NodeKind::Sphere => {
                let base = part.positions.len() as u32;
                part.positions.extend(ico_v.iter().map(|d| node.centre + node.radius * *d));
                part.normals.extend(&ico_v);
                part.indices.extend(ico_t.iter().flatten().map(|i| base + i));
            }
            NodeKind::Triangles => {
                for t in &h.triangles[node.first as usize..node.first as usize + node.count as usize] {
                    for &i in t {
                        if remap[i as usize] == u32::MAX {
                            remap[i as usize] = part.positions.len() as u32;
                            part.positions.push(h.positions[i as usize]);
                            part.normals.push(h.normals[i as usize]);
                        }
                        part.indices.push(remap[i as usize]);
                    }
                }
            }
            NodeKind::Inner => {}
        }
    }
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes, mut materials) = (vec![], vec![], vec![], vec![], vec![]);
    for (f, part) in parts.iter().enumerate() {
        if part.indices.is_empty() {
            continue;
        }
        let (lo, hi) =
            part.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let mut view = |bytes: &[u8], target: u32, bin: &mut Vec<u8>| {
            let offset = bin.len();
            bin.extend_from_slice(bytes);
            views.push(
                serde_json::json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target }),
            );
            views.len() - 1
        };
        let pv = view(
            bytemuck::cast_slice(&part.positions.iter().map(|p| p.to_array()).collect::<Vec<_>>()),
            34962,
            &mut bin,
        );
        let nv = view(
            bytemuck::cast_slice(&part.normals.iter().map(|p| p.normalize_or(Vec3::Y).to_array()).collect::<Vec<_>>()),
            34962,
            &mut bin,
        );
        let iv = view(bytemuck::cast_slice(&part.indices), 34963, &mut bin);
        let a = accessors.len();
        accessors.push(serde_json::json!({ "bufferView": pv, "componentType": 5126, "count": part.positions.len(), "type": "VEC3", "min": lo.to_array(), "max": hi.to_array() }));
        accessors.push(
            serde_json::json!({ "bufferView": nv, "componentType": 5126, "count": part.normals.len(), "type": "VEC3" }),
        );
        accessors.push(serde_json::json!({ "bufferView": iv, "componentType": 5125, "count": part.indices.len(), "type": "SCALAR" }));
        let c = colors.get(f).copied().unwrap_or([0.7; 3]);
        let name = names.get(f).cloned().unwrap_or_else(|| format!("f{f}"));
        materials.push(serde_json::json!({ "name": name, "pbrMetallicRoughness": { "baseColorFactor": [c[0], c[1], c[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6 } }));
        meshes.push(serde_json::json!({ "name": name, "primitives": [ { "attributes": { "POSITION": a, "NORMAL": a + 1 }, "indices": a + 2, "material": materials.len() - 1, "mode": 4 } ] }));
        nodes.push(serde_json::json!({ "name": name, "mesh": meshes.len() - 1 }));
    }
    let mut json = serde_json::json!({
        "asset": { "version": "2.0", "generator": "nlifs raytrace export" },
        "scene": 0,
        "scenes": [ { "nodes": (0..nodes.len()).collect::<Vec<_>>() } ],
        "nodes": nodes,
    });
    if !meshes.is_empty() {
        json["meshes"] = meshes.into();
        json["materials"] = materials.into();
        json["accessors"] = accessors.into();
        json["bufferViews"] = views.into();
        json["buffers"] = serde_json::json!([ { "byteLength": bin.len() } ]);
    }
    write_glb(w, &json, &bin)
}

/// POV-Ray is left-handed: mirroring z in both the scene and the camera gives the same image.
fn pov(v: Vec3) -> String {
    format!("<{:.6}, {:.6}, {:.6}>", v.x, v.y, -v.z)
}

/// The leaf spheres as a POV-Ray 3.7 scene, one union per function, with the same camera,
/// directional lights (shadows on), ambient, ground plane and background as the tracer.
/// Differences: POV-Ray's ground does not fade into the background, and its anti-aliasing is
/// adaptive (the benchmark forces supersampling of every pixel that differs from a neighbour).
pub fn write_pov(w: &mut dyn Write, h: &Hierarchy, camera: &OrbitCamera, shading: &Shading) -> std::io::Result<()> {
    let (lo, hi) = h.bounds;
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let aspect = shading.width as f32 / shading.height as f32;
    let bg = shading.background;
    writeln!(w, "// W^{}(sphere) written by nlifs for the ray-tracing benchmark", h.max_depth)?;
    writeln!(w, "#version 3.7;")?;
    writeln!(w, "global_settings {{ assumed_gamma 1.0 max_trace_level 2 ambient_light rgb 1 }}")?;
    writeln!(w, "background {{ rgb <{}, {}, {}> }}", bg.x, bg.y, bg.z)?;
    let fov_y = camera.fov_y_deg.to_radians();
    match camera.projection {
        Projection::Perspective => {
            let fov_x = 2.0 * ((0.5 * fov_y).tan() * aspect).atan();
            writeln!(
                w,
                "camera {{ perspective location {} look_at {} right x*{aspect} up y angle {} }}",
                pov(camera.eye()),
                pov(camera.target),
                fov_x.to_degrees()
            )?;
        }
        Projection::Parallel => {
            let hh = camera.half_height_at_target();
            writeln!(
                w,
                "camera {{ orthographic location {} look_at {} right x*{} up y*{} }}",
                pov(camera.eye() + camera.eye_direction() * 4.0 * radius),
                pov(camera.target),
                2.0 * hh * aspect,
                2.0 * hh
            )?;
        }
    }
    for light in &shading.lights {
        let i = light.intensity;
        writeln!(
            w,
            "light_source {{ {} color rgb <{}, {}, {}> parallel point_at {} }}",
            pov(centre + light.to_light * 20.0 * radius),
            i.x,
            i.y,
            i.z,
            pov(centre)
        )?;
    }
    let finish = format!("finish {{ ambient {} diffuse 1 specular 0.25 roughness 0.03 }}", shading.ambient);
    if shading.ground {
        writeln!(
            w,
            "plane {{ y, {} texture {{ pigment {{ rgb 0.55 }} finish {{ ambient {} diffuse 1 }} }} }}",
            lo.y - 1e-3 * radius,
            shading.ambient
        )?;
    }
    for (f, c) in shading.function_colors.iter().enumerate() {
        let spheres: Vec<_> = h.leaf_spheres().filter(|n| n.function as usize == f).collect();
        if spheres.is_empty() {
            continue;
        }
        writeln!(w, "union {{")?;
        for s in spheres {
            writeln!(w, "  sphere {{ {}, {:.6} }}", pov(s.centre), s.radius)?;
        }
        writeln!(w, "  texture {{ pigment {{ rgb <{}, {}, {}> }} {finish} }}", c.x, c.y, c.z)?;
        writeln!(w, "}}")?;
    }
    Ok(())
}
