//! The searches over a built [`Hierarchy`]: the nearest hit (camera rays), any hit (shadow
//! rays), the hinted forms the tracer's caches use, and the brute-force oracle the tests
//! compare them with.
//!
//! How it works. Both searches are iterative with an explicit stack over the wide nodes
//! (pbrt's `BVHAggregate` habit); the nearest-hit search pushes the entered bounds so that the
//! nearest is popped first and skips every bound entered beyond the best hit so far. Each search
//! is compiled once per lane pass ([`Lanes`]) and the form that runs is chosen by the
//! hierarchy's [`Simd`].

use super::geometry::{Hit, NodeKind, Ray, sphere_surface};
use super::hierarchy::Hierarchy;
#[cfg(target_arch = "x86_64")]
use super::wide::Avx512;
#[cfg(target_arch = "x86_64")]
use super::wide::Simd;
use super::wide::{LANES, Lanes, Portable};

/// Marks a traversal stack entry as a triangle tile (a node index) rather than a wide node.
pub(super) const TILE: u32 = 1 << 31;

/// Traversal stacks, kept between rays to avoid allocating per ray.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    closest: Vec<(u32, f32)>,
    any: Vec<u32>,
    /// The packet searches' stacks (`packet`): node, nearest entry, rays that entered it.
    pub(super) packet_closest: Vec<(u32, f32, u32)>,
    pub(super) packet_any: Vec<(u32, u32)>,
}

impl Hierarchy {
    /// The nearest hit with t in (t_min, t_max).
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.intersect_with(ray, t_min, t_max, &mut Scratch::default())
    }

    /// [`Self::intersect`] with a reused traversal stack (the tracer keeps one per thread).
    pub fn intersect_with(&self, ray: &Ray, t_min: f32, t_max: f32, scratch: &mut Scratch) -> Option<Hit> {
        self.intersect_hinted(ray, t_min, t_max, u32::MAX, scratch)
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
        match self.simd() {
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
    pub(super) unsafe fn closest<L: Lanes>(
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
    pub(super) fn tile_closest(&self, ray: &Ray, index: u32, t_min: f32, best: &mut Hit) {
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
        match self.simd() {
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
}
