//! The bounding hierarchy of the deterministic approximation W^n(A) (after Hart & DeFanti):
//! node w_i1∘…∘w_ik(A) has children w_i1∘…∘w_ik∘w_j(A), one per function j. Because every
//! w_j(A) ⊆ A, a child's geometry lies inside its parent's, so a ray only visits the children
//! of nodes whose bound it hits. With xaos only the compositions the chaos game applies are
//! built: a child j where w_ik may follow w_j, of the functions an orbit keeps applying
//! ([`Ifs::xaos_successors`], [`Ifs::recurrent_functions`]).
//!
//! How it works. Each node carries a sphere S(i1…ik) that contains its geometry, built the way
//! the paper builds W^{k+1}(A) from W^k(A): S(i1 i2…ik) = w_i1(S(i2…ik)), centre mapped, radius
//! times a guaranteed Lipschitz bound of w_i1 over the box around S(i2…ik). Leaves are those
//! spheres (sphere initial object) or the mapped meshes (mesh initial objects), whose triangles
//! are grouped into tiles under a small sphere tree. The traversal bound of an inner node is
//! then grown, bottom-up, to enclose its children's bounds, so the hierarchy is conservative
//! in floating point and returns exactly what testing every leaf returns.
//!
//! The nodes live in one flat array, children of a node contiguous and after it; the searches
//! (`search`) run over the nodes below the root collapsed into wide nodes (`wide`).

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::error::RaytraceError;
use super::geometry::{Hit, Node, NodeKind, Ray};
use super::mesh::Mesh;
use super::wide::{self, Simd, WideNode};
use crate::model::{Ifs, Map};

/// Most children a node may have (functions of the IFS; tile-tree fan-out is smaller).
pub const MAX_CHILDREN: usize = 16;
const TILE_TRIANGLES: usize = 16;
const TILE_FANOUT: usize = 4;

/// What A is.
#[derive(Clone, Debug)]
pub enum InitialObject {
    /// The sphere bounding the initial grid's box.
    Sphere,
    /// A triangle mesh (grid surface or glTF), in the scene's coordinates.
    Mesh(Mesh),
}

/// Where refinement stops.
#[derive(Clone, Copy, Debug)]
pub struct Stop {
    /// n of W^n(A): the fixed depth, or the cap of the adaptive stop.
    pub max_depth: u32,
    /// Adaptive stop (Hart & DeFanti): a node whose sphere projects smaller than one pixel is
    /// not refined further.
    pub pixel: Option<PixelFootprint>,
}

/// The size of a pixel: for perspective, the angle one pixel spans seen from `eye`; for
/// parallel projection, its world size.
#[derive(Clone, Copy, Debug)]
pub struct PixelFootprint {
    pub eye: Vec3,
    pub perspective: bool,
    /// Radians per pixel (perspective) or world units per pixel (parallel).
    pub per_pixel: f32,
}

impl PixelFootprint {
    fn below_pixel(&self, centre: Vec3, radius: f32) -> bool {
        let size = 2.0 * radius;
        if self.perspective {
            let distance = (centre - self.eye).length() - radius;
            distance > 0.0 && size / distance < self.per_pixel
        } else {
            size < self.per_pixel
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct DSphere {
    centre: DVec3,
    radius: f64,
}

/// Caches Lipschitz bounds per function and touched cell range (the bound depends on nothing
/// else), which makes building deep hierarchies cheap.
struct LipschitzCache<'a> {
    maps: &'a [&'a Map],
    cache: HashMap<(usize, [usize; 6], [bool; 3]), f64>,
}

impl LipschitzCache<'_> {
    fn bound(&mut self, f: usize, lo: DVec3, hi: DVec3) -> Result<f64, RaytraceError> {
        let map = self.maps[f];
        let Map::Grid(g) = map else {
            return map.lipschitz_bound_in_box(lo, hi).ok_or(RaytraceError::NoLipschitzBound(f));
        };
        let (a, b) = (g.grid.locate(lo).cell, g.grid.locate(hi).cell);
        let at_face = [0, 1, 2].map(|k| {
            let xs = &g.grid.axes[k];
            xs.len() >= 2 && a[k] > 0 && lo[k] <= xs[a[k]]
        });
        let key = (f, [a[0], a[1], a[2], b[0], b[1], b[2]], at_face);
        if let Some(l) = self.cache.get(&key) {
            return Ok(*l);
        }
        let l = g.lipschitz_bound_in_box(lo, hi);
        self.cache.insert(key, l);
        Ok(l)
    }

    /// The sphere that contains w_f of everything `s` contains.
    fn map_sphere(&mut self, f: usize, s: DSphere) -> Result<DSphere, RaytraceError> {
        let r = DVec3::splat(s.radius);
        let l = self.bound(f, s.centre - r, s.centre + r)?;
        Ok(DSphere { centre: self.maps[f].eval(s.centre), radius: l * s.radius })
    }
}

/// The built hierarchy with its leaf geometry.
#[derive(Clone, Debug, Default)]
pub struct Hierarchy {
    pub nodes: Vec<Node>,
    /// Mapped mesh vertices and smooth normals (mesh initial objects only).
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Number of W^n(A) leaves (spheres or mapped meshes).
    pub leaf_count: usize,
    /// Deepest leaf.
    pub max_depth: u32,
    /// Axis-aligned bounds of the leaf geometry.
    pub bounds: (Vec3, Vec3),
    /// The nodes below the root collapsed into wide nodes, what the searches traverse (empty
    /// when the root is a leaf).
    pub wide: Vec<WideNode>,
    simd: Simd,
}

/// Rounds a sphere to f32 so that it still contains the f64 one.
fn to_f32(s: DSphere) -> (Vec3, f32) {
    let c = s.centre.as_vec3();
    let slack = (c.as_dvec3() - s.centre).length() + s.radius * 1e-6 + s.centre.abs().max_element() * 1e-6;
    (c, (s.radius + slack) as f32)
}

impl Hierarchy {
    /// Builds W^n(A) for the enabled functions of `ifs`.
    pub fn build(ifs: &Ifs, initial: &InitialObject, stop: Stop) -> Result<Self, RaytraceError> {
        let active = ifs.active();
        if active.is_empty() {
            return Err(RaytraceError::NoFunctions);
        }
        if active.len() > MAX_CHILDREN {
            return Err(RaytraceError::TooManyFunctions(active.len()));
        }
        let maps: Vec<&Map> = active.iter().map(|&i| &ifs.functions[i].map).collect();
        let m = maps.len();
        // Xaos: the children of a node whose innermost function is k (None at the root).
        let successors = ifs.xaos_successors();
        let recurrent = ifs.recurrent_functions(successors.as_deref());
        let children_of = |k: Option<u8>| -> Vec<usize> {
            (0..m)
                .filter(|&j| recurrent.contains(&active[j]))
                .filter(|&j| k.is_none_or(|k| successors.as_ref().is_none_or(|s| s[active[j]][active[k as usize]])))
                .collect()
        };
        let children: Vec<Vec<usize>> =
            std::iter::once(None).chain((0..m).map(|k| Some(k as u8))).map(children_of).collect();
        let (lo, hi) = (ifs.domain.min(), ifs.domain.max());
        let sphere_a = match initial {
            InitialObject::Sphere => DSphere { centre: 0.5 * (lo + hi), radius: 0.5 * (hi - lo).length() },
            InitialObject::Mesh(mesh) => {
                let (mlo, mhi) = mesh.bounds();
                let c = 0.5 * (mlo + mhi);
                let r = mesh.positions.iter().map(|p| (*p - c).length()).fold(0.0, f64::max);
                DSphere { centre: c, radius: r }
            }
        };
        let mut h = Hierarchy::default();
        // Paths of the nodes of the current level, in node order (outermost function first).
        let mut level: Vec<(u32, Vec<u8>)> = vec![(0, Vec::new())];
        h.nodes.push(Node {
            centre: Vec3::ZERO,
            radius: 0.0,
            first: 0,
            count: 0,
            kind: NodeKind::Inner,
            function: 0,
            depth: 0,
        });
        let mut leaves: Vec<(u32, Vec<u8>)> = Vec::new();
        const NODE_LIMIT: usize = 8_000_000;
        // Spheres of the previous level, in path-number order when that level is complete (no
        // adaptive leaf above it), so that S(i1 i2…ik) = w_i1(S(i2…ik)) costs one map.
        let mut prev: Option<Vec<DSphere>> = None;
        while !level.is_empty() {
            let depth = level[0].1.len();
            let complete = (m as f64).powi(depth as i32) == level.len() as f64;
            let spheres: Vec<DSphere> = level
                .par_iter()
                .map_init(
                    || LipschitzCache { maps: &maps, cache: HashMap::new() },
                    |lip, (_, path)| {
                        let Some((&first, rest)) = path.split_first() else { return Ok(sphere_a) };
                        if let Some(prev) = &prev {
                            let q = rest.iter().fold(0usize, |q, &f| q * m + f as usize);
                            return lip.map_sphere(first as usize, prev[q]);
                        }
                        path.iter().rev().try_fold(sphere_a, |s, &f| lip.map_sphere(f as usize, s))
                    },
                )
                .collect::<Result<_, _>>()?;
            let mut next = Vec::new();
            for ((index, path), s) in level.into_iter().zip(spheres.iter().copied()) {
                let (centre, radius) = to_f32(s);
                let depth = path.len() as u32;
                let node = &mut h.nodes[index as usize];
                node.centre = centre;
                node.radius = radius;
                node.depth = depth as u8;
                node.function = path.first().copied().unwrap_or(0);
                let small = stop.pixel.is_some_and(|p| p.below_pixel(centre, radius));
                if depth >= stop.max_depth || small {
                    leaves.push((index, path));
                    continue;
                }
                let first = h.nodes.len() as u32;
                let children = &children[path.last().map_or(0, |&k| k as usize + 1)];
                h.nodes[index as usize].first = first;
                h.nodes[index as usize].count = children.len() as u16;
                for &j in children {
                    let mut child = path.clone();
                    child.push(j as u8);
                    next.push((h.nodes.len() as u32, child));
                    h.nodes.push(Node {
                        centre,
                        radius,
                        first: 0,
                        count: 0,
                        kind: NodeKind::Inner,
                        function: 0,
                        depth: 0,
                    });
                }
                if h.nodes.len() > NODE_LIMIT {
                    // Only an adaptive build has a pixel size to raise (`export mesh` has none).
                    let advice =
                        if stop.pixel.is_some() { "lower --depth or raise --stop-pixels" } else { "lower --depth" };
                    return Err(RaytraceError::TooLarge(format!("more than {NODE_LIMIT} nodes; {advice}")));
                }
            }
            level = next;
            prev = complete.then_some(spheres);
        }
        h.leaf_count = leaves.len();
        h.max_depth = leaves.iter().map(|(_, p)| p.len() as u32).max().unwrap_or(0);
        match initial {
            InitialObject::Sphere => {
                for (index, _) in &leaves {
                    h.nodes[*index as usize].kind = NodeKind::Sphere;
                }
            }
            InitialObject::Mesh(mesh) => {
                let total = leaves.len() * mesh.triangles.len();
                if total > 30_000_000 {
                    return Err(RaytraceError::TooLarge(format!("{total} triangles; lower --depth")));
                }
                for (index, path) in &leaves {
                    h.add_mesh_leaf(*index, path, mesh, &maps);
                }
            }
        }
        h.fit_bounds();
        if h.nodes[0].kind == NodeKind::Inner {
            h.wide = wide::collapse(&h.nodes);
        }
        h.simd = Simd::detect();
        Ok(h)
    }

    /// Maps the mesh through the leaf's composition and hangs its tiles under node `index`.
    fn add_mesh_leaf(&mut self, index: u32, path: &[u8], mesh: &Mesh, maps: &[&Map]) {
        let base = self.positions.len() as u32;
        let mapped: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| path.iter().rev().fold(*p, |q, &f| maps[f as usize].eval(q)).as_vec3())
            .collect();
        self.normals.extend(mesh.vertex_normals(&mapped));
        self.positions.extend(&mapped);
        let first_triangle = self.triangles.len();
        self.triangles.extend(mesh.triangles.iter().map(|t| t.map(|i| base + i)));
        let tiles: Vec<(u32, u16)> = (first_triangle..self.triangles.len())
            .step_by(TILE_TRIANGLES)
            .map(|s| (s as u32, (self.triangles.len() - s).min(TILE_TRIANGLES) as u16))
            .collect();
        let (function, depth) = (self.nodes[index as usize].function, self.nodes[index as usize].depth);
        self.tile_tree(index, &tiles, function, depth);
    }

    /// Makes node `index` the root of a sphere tree over `tiles` (fan-out ≤ TILE_FANOUT, split
    /// by the median of tile centres along the widest axis).
    fn tile_tree(&mut self, index: u32, tiles: &[(u32, u16)], function: u8, depth: u8) {
        let template =
            Node { centre: Vec3::ZERO, radius: 0.0, first: 0, count: 0, kind: NodeKind::Triangles, function, depth };
        if tiles.len() == 1 {
            let (first, count) = tiles[0];
            let n = &mut self.nodes[index as usize];
            *n = Node { first, count, ..template };
            return;
        }
        let centre_of = |h: &Self, (first, count): (u32, u16)| {
            let tris = &h.triangles[first as usize..first as usize + count as usize];
            let sum: Vec3 = tris.iter().flatten().map(|&i| h.positions[i as usize]).sum();
            sum / (3 * tris.len()) as f32
        };
        let mut order: Vec<(Vec3, (u32, u16))> = tiles.iter().map(|&t| (centre_of(self, t), t)).collect();
        let mut groups: Vec<&mut [(Vec3, (u32, u16))]> = vec![&mut order[..]];
        while groups.len() < TILE_FANOUT && groups.iter().any(|g| g.len() > 1) {
            let widest = (0..groups.len()).max_by_key(|&k| groups[k].len()).unwrap_or(0);
            let g = groups.swap_remove(widest);
            let (lo, hi) =
                g.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (c, _)| (lo.min(*c), hi.max(*c)));
            let axis = (hi - lo).max_position();
            g.sort_by(|a, b| a.0[axis].total_cmp(&b.0[axis]));
            let (a, b) = g.split_at_mut(g.len() / 2);
            groups.push(a);
            groups.push(b);
        }
        let parts: Vec<Vec<(u32, u16)>> = groups.into_iter().map(|g| g.iter().map(|(_, t)| *t).collect()).collect();
        let first = self.nodes.len() as u32;
        self.nodes[index as usize] = Node { first, count: parts.len() as u16, kind: NodeKind::Inner, ..template };
        for _ in &parts {
            self.nodes.push(template);
        }
        for (k, part) in parts.iter().enumerate() {
            self.tile_tree(first + k as u32, part, function, depth);
        }
    }

    /// Sets tile spheres from their vertices and grows every inner bound, children first, to
    /// enclose its children's bounds; computes the geometry's bounds.
    fn fit_bounds(&mut self) {
        let mut lo = Vec3::INFINITY;
        let mut hi = Vec3::NEG_INFINITY;
        for k in (0..self.nodes.len()).rev() {
            let n = self.nodes[k];
            match n.kind {
                NodeKind::Sphere => {
                    lo = lo.min(n.centre - n.radius);
                    hi = hi.max(n.centre + n.radius);
                }
                NodeKind::Triangles => {
                    let tris = &self.triangles[n.first as usize..n.first as usize + n.count as usize];
                    let (tlo, thi) = tris
                        .iter()
                        .flatten()
                        .map(|&i| self.positions[i as usize])
                        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
                    lo = lo.min(tlo);
                    hi = hi.max(thi);
                    let c = 0.5 * (tlo + thi);
                    let r =
                        tris.iter().flatten().map(|&i| (self.positions[i as usize] - c).length()).fold(0.0, f32::max);
                    self.nodes[k].centre = c;
                    self.nodes[k].radius = r * (1.0 + 1e-5) + c.abs().max_element() * 1e-6;
                }
                NodeKind::Inner => {
                    let children = &self.nodes[n.first as usize..n.first as usize + n.count as usize];
                    // Centre: the node's own sphere centre, or for tile groups the mean of the
                    // children; radius: the farthest child bound, with slack for rounding.
                    let (blo, bhi) = children.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), ch| {
                        (lo.min(ch.centre - ch.radius), hi.max(ch.centre + ch.radius))
                    });
                    let enclose =
                        |c: Vec3| children.iter().map(|ch| (ch.centre - c).length() + ch.radius).fold(0.0, f32::max);
                    let box_centre = 0.5 * (blo + bhi);
                    let (c, r) = if n.radius > 0.0 && enclose(n.centre) < enclose(box_centre) {
                        (n.centre, enclose(n.centre))
                    } else {
                        (box_centre, enclose(box_centre))
                    };
                    self.nodes[k].centre = c;
                    self.nodes[k].radius = r * (1.0 + 1e-5) + c.abs().max_element() * 1e-6;
                }
            }
        }
        self.bounds = (lo, hi);
    }

    /// Which compiled form of the traversal runs ([`Simd::detect`] after a build).
    pub fn simd(&self) -> Simd {
        self.simd
    }

    /// Runs the traversal compiled for `simd`, or for the widest form this CPU runs if that is
    /// narrower (to compare the forms against each other and against brute force).
    pub fn set_simd(&mut self, simd: Simd) {
        self.simd = simd.min(Simd::detect());
    }

    /// Geometric data of a hit: position, unit normal facing the ray, the leaf node.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> (Vec3, Vec3) {
        let p = ray.origin + hit.t * ray.dir;
        let n = if hit.triangle == u32::MAX {
            let node = &self.nodes[hit.node as usize];
            (p - node.centre).try_normalize().unwrap_or(Vec3::Y)
        } else {
            let [a, b, c] = self.triangles[hit.triangle as usize].map(|i| self.normals[i as usize]);
            ((1.0 - hit.u - hit.v) * a + hit.u * b + hit.v * c).try_normalize().unwrap_or(Vec3::Y)
        };
        (p, if n.dot(ray.dir) > 0.0 { -n } else { n })
    }

    /// The leaf sphere nodes (sphere initial object), in node order: for a fixed depth, in path
    /// order with the outermost function most significant.
    pub fn leaf_spheres(&self) -> impl Iterator<Item = &Node> {
        self.nodes.iter().filter(|n| n.kind == NodeKind::Sphere)
    }
}
