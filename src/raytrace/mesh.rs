//! Triangle meshes used as initial objects A of the deterministic algorithm: the initial grid
//! box's outer surface (the paper's "tessellated outer surface of the grid") and meshes read
//! from glTF files, fitted into the grid's box. A leaf w_i1∘…∘w_ik(A) of the hierarchy is such a
//! mesh with every vertex mapped; its smooth normals are recomputed from the mapped triangles.

use std::path::Path;

use glam::{DVec3, Vec3};

use super::error::RaytraceError;
pub use super::gltf_input::MAX_MESH_BYTES;

/// An indexed triangle mesh in the scene's coordinates (f64 so that deep compositions of maps
/// stay accurate before they are rounded for tracing).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The outer surface of the box [lo, hi], each face cut into `subdivisions`² quads (two
    /// triangles each). Faces do not share vertices, so the box's edges stay creased after
    /// smoothing. A flat box (2D grid, zero extent along z) gives one double-sided rectangle.
    /// Triangles are emitted in 2×2-quad blocks so that consecutive runs are compact tiles.
    pub fn box_surface(lo: DVec3, hi: DVec3, subdivisions: usize) -> Self {
        let s = subdivisions.max(1);
        let mut mesh = Mesh::default();
        let flat_z = (hi.z - lo.z).abs() < 1e-12;
        // (fixed axis, side, u axis, v axis) with u × v pointing outwards.
        let faces: &[(usize, bool, usize, usize)] = if flat_z {
            &[(2, true, 0, 1)]
        } else {
            &[(0, false, 2, 1), (0, true, 1, 2), (1, false, 0, 2), (1, true, 2, 0), (2, false, 1, 0), (2, true, 0, 1)]
        };
        for &(axis, high, ua, va) in faces {
            let base = mesh.positions.len() as u32;
            for i in 0..=s {
                for j in 0..=s {
                    let mut p = DVec3::ZERO;
                    p[axis] = if high { hi[axis] } else { lo[axis] };
                    p[ua] = lo[ua] + (hi[ua] - lo[ua]) * i as f64 / s as f64;
                    p[va] = lo[va] + (hi[va] - lo[va]) * j as f64 / s as f64;
                    mesh.positions.push(p);
                }
            }
            let at = |i: usize, j: usize| base + (i * (s + 1) + j) as u32;
            for bi in (0..s).step_by(2) {
                for bj in (0..s).step_by(2) {
                    for i in bi..(bi + 2).min(s) {
                        for j in bj..(bj + 2).min(s) {
                            mesh.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                            mesh.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                        }
                    }
                }
            }
        }
        mesh
    }

    /// Axis-aligned bounds of the vertices.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
    }

    /// Reorders the triangles along a Morton (Z-order) curve of their centroids, so that every
    /// run of consecutive triangles, which the hierarchy cuts into tiles, is spatially compact.
    /// A file's triangle order can be anything (a shuffled 10⁶-triangle sphere made every tile
    /// span the whole mesh and every ray test every tile); after this the tracing cost follows
    /// the mesh's size. O(n log n); vertices keep their order.
    pub fn order_along_curve(&mut self) {
        let (lo, hi) = self.bounds();
        let scale = (hi - lo).max(DVec3::splat(1e-300)).recip() * 1023.0;
        let key = |t: &[u32; 3]| {
            let centroid = t.iter().map(|&i| self.positions[i as usize]).sum::<DVec3>() / 3.0;
            let q = ((centroid - lo) * scale).clamp(DVec3::ZERO, DVec3::splat(1023.0)).as_uvec3();
            spread_bits(q.x) | spread_bits(q.y) << 1 | spread_bits(q.z) << 2
        };
        let mut keyed: Vec<(u32, [u32; 3])> = self.triangles.iter().map(|t| (key(t), *t)).collect();
        keyed.sort_by_key(|(k, _)| *k);
        self.triangles = keyed.into_iter().map(|(_, t)| t).collect();
    }

    /// Area-weighted vertex normals of the mesh with its vertices replaced by `positions`.
    pub fn vertex_normals(&self, positions: &[Vec3]) -> Vec<Vec3> {
        let mut normals = vec![Vec3::ZERO; positions.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let n = (b - a).cross(c - a);
            for i in t {
                normals[*i as usize] += n;
            }
        }
        normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Y)).collect()
    }
}

/// Reads every surface primitive (triangles, strips, fans) of the default scene (or of all
/// meshes, when the file has no scene) with its node transforms (`gltf_input.rs`), and
/// fits the result into the box [lo, hi]: uniformly scaled to the box's largest extent that it
/// fits, centred. Any problem is an error, never a panic.
pub fn load_gltf(path: &Path, lo: DVec3, hi: DVec3) -> Result<Mesh, RaytraceError> {
    let bad = |message: String| RaytraceError::Gltf { path: path.display().to_string(), message };
    let read = super::gltf_input::read_mesh(path).map_err(bad)?;
    let mut mesh = Mesh { positions: read.positions, triangles: read.triangles };
    if mesh.triangles.is_empty() {
        return Err(bad("no triangle, strip or fan primitives with positions".into()));
    }
    let (mlo, mhi) = mesh.bounds();
    let extent = mhi - mlo;
    if !extent.is_finite() {
        return Err(bad("vertex positions are not finite".into()));
    }
    mesh.order_along_curve();
    let target = hi - lo;
    let scale = [0, 1, 2]
        .iter()
        .filter(|&&a| extent[a] > 1e-12 && target[a] > 1e-12)
        .map(|&a| target[a] / extent[a])
        .fold(f64::INFINITY, f64::min);
    let scale = if scale.is_finite() { scale } else { 1.0 };
    let (mc, tc) = (0.5 * (mlo + mhi), 0.5 * (lo + hi));
    for p in &mut mesh.positions {
        *p = tc + (*p - mc) * scale;
        // 2D grids: flatten into the grid's plane.
        if target.z.abs() < 1e-12 {
            p.z = lo.z;
        }
    }
    Ok(mesh)
}

/// The 10 low bits of `v` spread to every third bit (bit i to bit 3i), for Morton codes.
fn spread_bits(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_surface_is_closed_and_outward() {
        let mesh = Mesh::box_surface(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), 3);
        assert_eq!(mesh.triangles.len(), 6 * 9 * 2);
        // Divergence theorem: a closed outward surface encloses volume Σ (a · (b × c)) / 6.
        let volume: f64 = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!((volume - 6.0).abs() < 1e-9, "volume {volume}");
    }

    #[test]
    fn spread_bits_interleaves() {
        assert_eq!(spread_bits(0b1011), 0b001_000_001_001);
        assert_eq!(spread_bits(0x3ff), 0x0924_9249);
        assert_eq!(spread_bits(0x7ff), 0x0924_9249, "only 10 bits are kept");
    }

    /// Mean diagonal of the bounds of consecutive 16-triangle runs (the hierarchy's tiles).
    fn mean_tile_extent(mesh: &Mesh) -> f64 {
        let tiles: Vec<f64> = mesh
            .triangles
            .chunks(16)
            .map(|run| {
                let (lo, hi) = run
                    .iter()
                    .flatten()
                    .map(|&i| mesh.positions[i as usize])
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
                (hi - lo).length()
            })
            .collect();
        tiles.iter().sum::<f64>() / tiles.len() as f64
    }

    #[test]
    fn ordering_makes_shuffled_triangles_compact_tiles() {
        let mut mesh = Mesh::box_surface(DVec3::ZERO, DVec3::ONE, 32);
        let mut sorted_before = mesh.triangles.clone();
        // A deterministic shuffle (Fisher-Yates driven by an LCG): the order a file may have.
        let mut state = 12345u64;
        for i in (1..mesh.triangles.len()).rev() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            mesh.triangles.swap(i, (state >> 33) as usize % (i + 1));
        }
        let diagonal = 3f64.sqrt();
        assert!(mean_tile_extent(&mesh) > 0.5 * diagonal, "the shuffle should scatter tiles");
        mesh.order_along_curve();
        let extent = mean_tile_extent(&mesh);
        // 16 of the 6·32²·2 triangles cover about 1/768 of the surface: a compact tile spans a
        // few cells (cell 1/32 ≈ 0.03); allow ten times a cell.
        assert!(extent < 0.3, "mean tile extent {extent} after ordering");
        let mut sorted_after = mesh.triangles.clone();
        sorted_before.sort();
        sorted_after.sort();
        assert_eq!(sorted_before, sorted_after, "ordering only permutes triangles");
    }
}
