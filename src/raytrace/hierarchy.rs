//! The bounding hierarchy of the deterministic approximation W^n(A) (after Hart & DeFanti):
//! node w_i1∘…∘w_ik(A) has children w_i1∘…∘w_ik∘w_j(A), one per function j. Because every
//! w_j(A) ⊆ A, a child's geometry lies inside its parent's, so a ray only visits the children
//! of nodes whose bound it hits.
//!
//! How it works. Each node carries a sphere S(i1…ik) that contains its geometry, built the way
//! the paper builds W^{k+1}(A) from W^k(A): S(i1 i2…ik) = w_i1(S(i2…ik)), centre mapped, radius
//! times a guaranteed Lipschitz bound of w_i1 over the box around S(i2…ik). Leaves are those
//! spheres (sphere initial object) or the mapped meshes (mesh initial objects), whose triangles
//! are grouped into tiles under a small sphere tree. The traversal bound of an inner node is
//! then grown, bottom-up, to enclose its children's bounds, so the hierarchy is conservative
//! in floating point and returns exactly what testing every leaf returns.
//!
//! The nodes live in one flat array, children of a node contiguous and after it; traversal is
//! iterative with an explicit stack, nearest child first (pbrt's `BVHAggregate` habit).

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::RaytraceError;
use super::mesh::Mesh;
#[cfg(target_arch = "x86_64")]
use super::wide::Avx512;
use super::wide::{self, LANES, Lanes, Portable, Simd, WideNode};
use crate::model::{Ifs, Map};

/// Most children a node may have (functions of the IFS; tile-tree fan-out is smaller).
pub const MAX_CHILDREN: usize = 16;
const TILE_TRIANGLES: usize = 16;
const TILE_FANOUT: usize = 4;
/// Marks a traversal stack entry as a triangle tile (a node index) rather than a wide node.
const TILE: u32 = 1 << 31;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum NodeKind {
    Inner = 0,
    /// A leaf sphere: the bound is the geometry.
    Sphere = 1,
    /// A tile of triangles `first..first + count`.
    Triangles = 2,
}

/// 32 bytes. `first`/`count` are children for inner nodes, triangles for tiles.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    pub centre: Vec3,
    pub radius: f32,
    pub first: u32,
    pub count: u16,
    pub kind: NodeKind,
    /// The outermost function i1 of the node's composition (the part of the attractor it is in).
    pub function: u8,
    pub depth: u8,
}

/// Traversal stacks, kept between rays to avoid allocating per ray.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    closest: Vec<(u32, f32)>,
    any: Vec<u32>,
}

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    /// Unit length.
    pub dir: Vec3,
}

/// A surface hit: `node` is the sphere leaf or triangle tile, `triangle` is `u32::MAX` for
/// spheres; (u, v) are barycentric coordinates on triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub node: u32,
    pub triangle: u32,
    pub u: f32,
    pub v: f32,
}

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
                h.nodes[index as usize].first = first;
                h.nodes[index as usize].count = active.len() as u16;
                for j in 0..active.len() {
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
                    return Err(RaytraceError::TooLarge(format!(
                        "more than {NODE_LIMIT} nodes; lower --depth or raise --stop-pixels"
                    )));
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

    /// The nearest hit with t in (t_min, t_max).
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.intersect_with(ray, t_min, t_max, &mut Scratch::default())
    }

    /// [`Self::intersect`] with a reused traversal stack (the tracer keeps one per thread).
    pub fn intersect_with(&self, ray: &Ray, t_min: f32, t_max: f32, scratch: &mut Scratch) -> Option<Hit> {
        self.intersect_hinted(ray, t_min, t_max, u32::MAX, scratch)
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

    /// [`Self::intersect_with`] that first tries leaf `hint` (the tracer passes the previous
    /// sample's leaf): a hit there shortens the ray before the search, which then skips every
    /// bound entered farther away. The result is the same nearest hit.
    pub fn intersect_hinted(&self, ray: &Ray, t_min: f32, t_max: f32, hint: u32, scratch: &mut Scratch) -> Option<Hit> {
        let entry = self.root_entry(ray, t_min, t_max);
        if entry == f32::INFINITY {
            return None;
        }
        self.intersect_entered(ray, t_min, t_max, entry, hint, scratch)
    }

    /// Where the ray enters the root's bound within (t_min, t_max) (clamped to t_min), or
    /// infinity where it does not and so hits nothing. Without branches, so that the tracer's
    /// tests of a pixel's rays overlap in the processor.
    #[inline]
    pub fn root_entry(&self, ray: &Ray, t_min: f32, t_max: f32) -> f32 {
        let Some(root) = self.nodes.first() else { return f32::INFINITY };
        let oc = ray.origin - root.centre;
        let b = oc.dot(ray.dir);
        let l = oc - b * ray.dir;
        // NaN where the line misses, so both comparisons below fail.
        let s = (root.radius * root.radius - l.dot(l)).sqrt();
        let (t0, t1) = (-b - s, -b + s);
        if (t1 > t_min) & (t0 < t_max) { t0.max(t_min) } else { f32::INFINITY }
    }

    /// [`Self::intersect_hinted`] for a ray whose [`Self::root_entry`] is `root_entry` (finite).
    pub fn intersect_entered(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        root_entry: f32,
        hint: u32,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        match self.simd {
            #[cfg(target_arch = "x86_64")]
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: `simd` is only ever set to a form that `Simd::detect` found the CPU runs.
            Simd::Avx512 => unsafe { self.closest_avx512(ray, t_min, t_max, root_entry, hint, scratch) },
            #[cfg(target_arch = "x86_64")]
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: as above.
            Simd::Avx2 => unsafe { self.closest_avx2(ray, t_min, t_max, root_entry, hint, scratch) },
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: the portable lanes use only the baseline target's instructions.
            _ => unsafe { self.closest::<Portable>(ray, t_min, t_max, root_entry, hint, scratch) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn closest_avx512(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        root_entry: f32,
        hint: u32,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: this function only runs where AVX-512F is enabled.
        unsafe {
            self.closest::<Avx512>(ray, t_min, t_max, root_entry, hint, scratch)
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn closest_avx2(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        root_entry: f32,
        hint: u32,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: the portable lanes need nothing beyond the baseline target.
        unsafe {
            self.closest::<Portable>(ray, t_min, t_max, root_entry, hint, scratch)
        }
    }

    /// The nearest-hit search over the wide nodes, nearest bound first, for a ray that enters
    /// the root's bound at `root_entry`.
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[inline(always)]
    unsafe fn closest<L: Lanes>(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        root_entry: f32,
        hint: u32,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        let mut best = Hit { t: t_max, node: u32::MAX, triangle: u32::MAX, u: 0.0, v: 0.0 };
        let root = self.nodes.first()?;
        match root.kind {
            NodeKind::Sphere => {
                return sphere_surface(ray, root.centre, root.radius, t_min, t_max).map(|t| Hit { t, node: 0, ..best });
            }
            NodeKind::Triangles => {
                self.tile_closest(ray, 0, t_min, &mut best);
                return (best.node != u32::MAX).then_some(best);
            }
            NodeKind::Inner => {}
        }
        if let Some(leaf) = self.nodes.get(hint as usize) {
            match leaf.kind {
                NodeKind::Sphere => {
                    if let Some(t) = sphere_surface(ray, leaf.centre, leaf.radius, t_min, t_max) {
                        best = Hit { t, node: hint, ..best };
                    }
                }
                NodeKind::Triangles => self.tile_closest(ray, hint, t_min, &mut best),
                NodeKind::Inner => {}
            }
        }
        let stack = &mut scratch.closest;
        stack.clear();
        stack.push((0, root_entry));
        let (origin, dir) = (ray.origin.to_array(), ray.dir.to_array());
        let mut near = [(0u32, 0f32); LANES];
        while let Some((id, t_enter)) = stack.pop() {
            if t_enter >= best.t {
                continue;
            }
            if id & TILE != 0 {
                self.tile_closest(ray, id & !TILE, t_min, &mut best);
                continue;
            }
            let w = &self.wide[id as usize];
            // SAFETY: the caller guarantees L's instructions.
            let lanes = unsafe { L::closest(w, origin, dir, t_min, best.t) };
            if let Some((t, lane)) = lanes.hit {
                best = Hit { t, node: w.target[lane], triangle: u32::MAX, u: 0.0, v: 0.0 };
            }
            let mut enter = lanes.enter;
            let mut found = 0usize;
            while enter != 0 {
                let lane = enter.trailing_zeros() as usize;
                enter &= enter - 1;
                let tag = if w.tiles & (1 << lane) != 0 { TILE } else { 0 };
                near[found] = (w.target[lane] | tag, lanes.entry[lane]);
                found += 1;
            }
            // Insertion sort by decreasing entry, pushed in that order so the nearest is
            // popped first.
            for i in 1..found {
                let e = near[i];
                let mut j = i;
                while j > 0 && near[j - 1].1 < e.1 {
                    near[j] = near[j - 1];
                    j -= 1;
                }
                near[j] = e;
            }
            stack.extend_from_slice(&near[..found]);
        }
        (best.node != u32::MAX).then_some(best)
    }

    /// Tests the triangles of tile `index` against `best`.
    #[inline]
    fn tile_closest(&self, ray: &Ray, index: u32, t_min: f32, best: &mut Hit) {
        let node = &self.nodes[index as usize];
        for tri in node.first..node.first + node.count as u32 {
            if let Some((t, u, v)) = self.triangle_hit(ray, tri, t_min, best.t) {
                *best = Hit { t, node: index, triangle: tri, u, v };
            }
        }
    }

    /// Whether anything is hit with t in (t_min, t_max) (shadow rays).
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluder(ray, t_min, t_max, &mut Scratch::default()).is_some()
    }

    /// Some leaf (sphere node or triangle tile) hit with t in (t_min, t_max), found by
    /// depth-first search without ordering (shadow rays need any hit, not the nearest).
    pub fn occluder(&self, ray: &Ray, t_min: f32, t_max: f32, scratch: &mut Scratch) -> Option<u32> {
        self.occluder_hinted(ray, t_min, t_max, u32::MAX, scratch)
    }

    /// [`Self::occluder`] that first tries leaf `hint` (the tracer's shadow cache, after
    /// Haines & Greenberg: the last occluder of a light), once the ray is known to enter the
    /// root's bound.
    pub fn occluder_hinted(&self, ray: &Ray, t_min: f32, t_max: f32, hint: u32, scratch: &mut Scratch) -> Option<u32> {
        if self.root_entry(ray, t_min, t_max) == f32::INFINITY {
            return None;
        }
        self.occluder_entered(ray, t_min, t_max, hint, scratch)
    }

    /// [`Self::occluder_hinted`] for a ray whose [`Self::root_entry`] is finite.
    pub fn occluder_entered(&self, ray: &Ray, t_min: f32, t_max: f32, hint: u32, scratch: &mut Scratch) -> Option<u32> {
        if hint != u32::MAX && self.leaf_hit(hint, ray, t_min, t_max) {
            return Some(hint);
        }
        match self.simd {
            #[cfg(target_arch = "x86_64")]
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: `simd` is only ever set to a form that `Simd::detect` found the CPU runs.
            Simd::Avx512 => unsafe { self.any_avx512(ray, t_min, t_max, scratch) },
            #[cfg(target_arch = "x86_64")]
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: as above.
            Simd::Avx2 => unsafe { self.any_avx2(ray, t_min, t_max, scratch) },
            #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
            // SAFETY: the portable lanes use only the baseline target's instructions.
            _ => unsafe { self.any::<Portable>(ray, t_min, t_max, scratch) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn any_avx512(&self, ray: &Ray, t_min: f32, t_max: f32, scratch: &mut Scratch) -> Option<u32> {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: this function only runs where AVX-512F is enabled.
        unsafe {
            self.any::<Avx512>(ray, t_min, t_max, scratch)
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn any_avx2(&self, ray: &Ray, t_min: f32, t_max: f32, scratch: &mut Scratch) -> Option<u32> {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: the portable lanes need nothing beyond the baseline target.
        unsafe {
            self.any::<Portable>(ray, t_min, t_max, scratch)
        }
    }

    /// The any-hit search over the wide nodes, for a ray that enters the root's bound.
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[inline(always)]
    unsafe fn any<L: Lanes>(&self, ray: &Ray, t_min: f32, t_max: f32, scratch: &mut Scratch) -> Option<u32> {
        let root = self.nodes.first()?;
        if root.kind != NodeKind::Inner {
            return self.leaf_hit(0, ray, t_min, t_max).then_some(0);
        }
        let (origin, dir) = (ray.origin.to_array(), ray.dir.to_array());
        let stack = &mut scratch.any;
        stack.clear();
        stack.push(0);
        while let Some(id) = stack.pop() {
            if id & TILE != 0 {
                if self.leaf_hit(id & !TILE, ray, t_min, t_max) {
                    return Some(id & !TILE);
                }
                continue;
            }
            let w = &self.wide[id as usize];
            // SAFETY: the caller guarantees L's instructions.
            let (hit, mut enter) = unsafe { L::any(w, origin, dir, t_min, t_max) };
            if let Some(lane) = hit {
                return Some(w.target[lane]);
            }
            while enter != 0 {
                let lane = enter.trailing_zeros() as usize;
                enter &= enter - 1;
                let tag = if w.tiles & (1 << lane) != 0 { TILE } else { 0 };
                stack.push(w.target[lane] | tag);
            }
        }
        None
    }

    /// Whether leaf `index` (a sphere or a triangle tile) is hit with t in (t_min, t_max); the
    /// tracer's shadow cache tries the last occluder this way before a full search.
    pub fn leaf_hit(&self, index: u32, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let node = &self.nodes[index as usize];
        match node.kind {
            NodeKind::Sphere => sphere_surface(ray, node.centre, node.radius, t_min, t_max).is_some(),
            NodeKind::Triangles => (node.first..node.first + node.count as u32)
                .any(|tri| self.triangle_hit(ray, tri, t_min, t_max).is_some()),
            NodeKind::Inner => false,
        }
    }

    /// The oracle: every leaf tested, nearest kept (ties to the lower index).
    pub fn intersect_brute_force(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let limit = |b: &Option<Hit>| b.map_or(t_max, |h| h.t);
        for (k, n) in self.nodes.iter().enumerate() {
            match n.kind {
                NodeKind::Sphere => {
                    if let Some(t) = sphere_surface(ray, n.centre, n.radius, t_min, limit(&best)) {
                        best = Some(Hit { t, node: k as u32, triangle: u32::MAX, u: 0.0, v: 0.0 });
                    }
                }
                NodeKind::Triangles => {
                    for tri in n.first..n.first + n.count as u32 {
                        if let Some((t, u, v)) = self.triangle_hit(ray, tri, t_min, limit(&best)) {
                            best = Some(Hit { t, node: k as u32, triangle: tri, u, v });
                        }
                    }
                }
                NodeKind::Inner => {}
            }
        }
        best
    }

    /// Möller–Trumbore, two-sided.
    #[inline]
    fn triangle_hit(&self, ray: &Ray, tri: u32, t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
        let [a, b, c] = self.triangles[tri as usize].map(|i| self.positions[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let p = ray.dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-20 {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.origin - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = ray.dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = e2.dot(q) * inv;
        (t > t_min && t < t_max).then_some((t, u, v))
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

/// The roots of |o + t d − c| = r, computed from the ray's closest approach to the centre so
/// that small far spheres stay accurate in f32 (Ray Tracing Gems, ch. 7).
#[inline(always)]
pub fn sphere_roots(ray: &Ray, centre: Vec3, radius: f32) -> Option<(f32, f32)> {
    let oc = ray.origin - centre;
    let b = oc.dot(ray.dir);
    let l = oc - b * ray.dir;
    let disc = radius * radius - l.dot(l);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    Some((-b - s, -b + s))
}

/// The visible surface of a solid sphere: the nearer root in range, else the farther one.
#[inline(always)]
fn sphere_surface(ray: &Ray, centre: Vec3, radius: f32, t_min: f32, t_max: f32) -> Option<f32> {
    let (t0, t1) = sphere_roots(ray, centre, radius)?;
    let t = if t0 > t_min { t0 } else { t1 };
    (t > t_min && t < t_max).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// Against the closed form: a ray at offset h from the centre of a sphere of radius r at
    /// distance D enters at D − √(r² − h²). Tolerance: a few f32 ulps of D.
    #[test]
    fn sphere_roots_match_closed_form() {
        for i in 0..1000u32 {
            let mut rng = Pcg32::for_stream(3, 0, i);
            let distance = 10.0 + 500.0 * rng.next_f32();
            let radius = 0.01 + 5.0 * rng.next_f32();
            let offset = radius * rng.next_f32();
            let ray = Ray { origin: Vec3::new(offset, 0.0, distance), dir: Vec3::NEG_Z };
            let (t0, t1) = sphere_roots(&ray, Vec3::ZERO, radius).expect("hits");
            let half = ((radius * radius - offset * offset) as f64).sqrt();
            let tol = 8.0 * f32::EPSILON as f64 * distance as f64;
            assert!((t0 as f64 - (distance as f64 - half)).abs() <= tol, "case {i}: t0 {t0}");
            assert!((t1 as f64 - (distance as f64 + half)).abs() <= tol, "case {i}: t1 {t1}");
            let miss = Ray { origin: Vec3::new(radius * 1.001, 0.0, distance), dir: Vec3::NEG_Z };
            assert!(sphere_roots(&miss, Vec3::ZERO, radius).is_none(), "case {i}: grazing miss");
        }
    }
}
