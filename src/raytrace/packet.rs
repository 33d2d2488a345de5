//! Packet searches: up to [`PACKET`] coherent rays (neighbouring samples of a run of pixels)
//! traverse the wide nodes together, so that popping a node, reading its lanes and ordering
//! and pushing its entered children is done once for the packet rather than once per ray.
//!
//! How it works. A stack entry carries, besides the node, the rays that entered it (a bit
//! mask) and the nearest of their entries. A popped node is tested by the rays of its mask
//! whose best hit so far lies beyond that entry, each with its own lane pass ([`Lanes`]), and
//! its entered lanes are pushed once with the union of the rays that entered each, nearest
//! first. Each ray's lane passes are those of the one-ray search with the same shrinking
//! t_max, so each ray's nearest hit (and whether a shadow ray is blocked) is the one-ray
//! search's; only between leaves at exactly the same t can the packet keep another one.

use super::geometry::{Hit, NodeKind, Ray};
use super::hierarchy::Hierarchy;
use super::search::{Scratch, TILE};
#[cfg(target_arch = "x86_64")]
use super::wide::Avx512;
#[cfg(target_arch = "x86_64")]
use super::wide::Simd;
use super::wide::{Beam, LANES, Lanes, Portable, Projected};

/// Most rays of a packet (a bit each in the stack entries' masks).
pub const PACKET: usize = 16;
const _: () = assert!(LANES <= 32 && PACKET <= 32, "lane and ray masks fit in u32");

impl Hierarchy {
    /// The nearest hit of each of `rays` with t in (t_min, t_max[i]), for rays that enter the
    /// root's bound at `root_entry[i]`; each ray first tries leaf `hint`. `hits[i]` is the
    /// result (`node == u32::MAX`: none).
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[expect(clippy::too_many_arguments, reason = "the one-ray search's arguments, per ray where they differ")]
    #[inline(always)]
    pub(super) unsafe fn closest_packet<L: Lanes>(
        &self,
        rays: &[Ray],
        t_min: f32,
        t_max: &[f32],
        root_entry: &[f32],
        hint: u32,
        scratch: &mut Scratch,
        hits: &mut [Hit],
    ) {
        let count = rays.len().min(PACKET);
        let none = Hit { t: 0.0, node: u32::MAX, triangle: u32::MAX, u: 0.0, v: 0.0 };
        for i in 0..count {
            hits[i] = Hit { t: t_max[i], ..none };
        }
        let Some(root) = self.nodes.first() else { return };
        if root.kind != NodeKind::Inner {
            for i in 0..count {
                // SAFETY: the caller guarantees L's instructions.
                hits[i] = unsafe { self.closest::<L>(&rays[i], t_min, t_max[i], root_entry[i], hint, scratch) }
                    .unwrap_or(Hit { t: t_max[i], ..none });
            }
            return;
        }
        if let Some(leaf) = self.nodes.get(hint as usize) {
            for i in 0..count {
                match leaf.kind {
                    NodeKind::Sphere => {
                        if let Some(t) =
                            super::geometry::sphere_surface(&rays[i], leaf.centre, leaf.radius, t_min, t_max[i])
                        {
                            hits[i] = Hit { t, node: hint, ..none };
                        }
                    }
                    NodeKind::Triangles => self.tile_closest(&rays[i], hint, t_min, &mut hits[i]),
                    NodeKind::Inner => {}
                }
            }
        }
        let origin: [[f32; 3]; PACKET] = std::array::from_fn(|i| rays.get(i).map_or([0.0; 3], |r| r.origin.to_array()));
        let dir: [[f32; 3]; PACKET] = std::array::from_fn(|i| rays.get(i).map_or([0.0; 3], |r| r.dir.to_array()));
        let all = if count == 32 { u32::MAX } else { (1u32 << count) - 1 };
        let entry0 = root_entry[..count].iter().copied().fold(f32::INFINITY, f32::min);
        let stack = &mut scratch.packet_closest;
        stack.clear();
        stack.push((0, entry0, all));
        let mut near = [(0u32, 0f32, 0u32); LANES];
        while let Some((id, t_enter, mask)) = stack.pop() {
            let mut active = 0u32;
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                active |= ((t_enter < hits[i].t) as u32) << i;
            }
            if active == 0 {
                continue;
            }
            if id & TILE != 0 {
                let mut m = active;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    self.tile_closest(&rays[i], id & !TILE, t_min, &mut hits[i]);
                }
                continue;
            }
            let w = &self.wide[id as usize];
            let mut entered: [u32; LANES] = [0; LANES];
            let mut entry = [f32::INFINITY; LANES];
            let mut union = 0u64;
            let mut m = active;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                // SAFETY: the caller guarantees L's instructions.
                let lanes = unsafe { L::closest(w, origin[i], dir[i], t_min, hits[i].t) };
                if let Some((t, lane)) = lanes.hit {
                    hits[i] = Hit { t, node: w.target[lane], ..none };
                }
                union |= lanes.enter;
                let (enter, bit) = (lanes.enter as u32, 1u32 << i);
                // Branch-free over u32 lanes, so that it is a few vector instructions.
                for l in 0..LANES {
                    let inside = ((enter >> l) & 1).wrapping_neg();
                    entered[l] |= inside & bit;
                    let nearer = lanes.entry[l] < entry[l];
                    entry[l] = if (inside != 0) & nearer { lanes.entry[l] } else { entry[l] };
                }
            }
            let mut found = 0usize;
            while union != 0 {
                let lane = union.trailing_zeros() as usize;
                union &= union - 1;
                let tag = if w.tiles & (1 << lane) != 0 { TILE } else { 0 };
                near[found] = (w.target[lane] | tag, entry[lane], entered[lane]);
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
    }

    /// Which of `rays` (all entering the root's bound) hit something with t in
    /// (t_min, t_max): bit i of the result for ray i. Each first tries leaf `hint` (the
    /// shadow cache); `last` becomes the last occluder found.
    ///
    /// # Safety
    /// The CPU must run the instructions of `L`.
    #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
    #[inline(always)]
    pub(super) unsafe fn occluded_packet<L: Lanes>(
        &self,
        rays: &[Ray],
        t_min: f32,
        t_max: f32,
        hint: u32,
        scratch: &mut Scratch,
        last: &mut u32,
    ) -> u32 {
        let count = rays.len().min(PACKET);
        let all = if count == 32 { u32::MAX } else { (1u32 << count) - 1 };
        let mut blocked = 0u32;
        if hint != u32::MAX {
            for (i, ray) in rays[..count].iter().enumerate() {
                if self.leaf_hit(hint, ray, t_min, t_max) {
                    blocked |= 1 << i;
                }
            }
        }
        if blocked == all {
            return blocked;
        }
        let Some(root) = self.nodes.first() else { return blocked };
        if root.kind != NodeKind::Inner {
            for (i, ray) in rays[..count].iter().enumerate() {
                if self.leaf_hit(0, ray, t_min, t_max) {
                    blocked |= 1 << i;
                    *last = 0;
                }
            }
            return blocked;
        }
        let origin: [[f32; 3]; PACKET] = std::array::from_fn(|i| rays.get(i).map_or([0.0; 3], |r| r.origin.to_array()));
        let dir: [[f32; 3]; PACKET] = std::array::from_fn(|i| rays.get(i).map_or([0.0; 3], |r| r.dir.to_array()));
        // Rays of one direction over (0, ∞), as a parallel light's shadow rays: each node's
        // lanes are culled for the packet without square roots, and only a ray that may meet
        // one of its leaf spheres runs the exact pass there.
        let parallel = t_min == 0.0 && t_max == f32::INFINITY && rays[..count].iter().all(|r| r.dir == rays[0].dir);
        let beam = parallel.then(|| {
            let reach =
                rays[..count].iter().map(|r| r.origin.length()).fold(root.centre.length() + root.radius, f32::max);
            Beam::new(dir[0], reach)
        });
        let at: [[f32; 3]; PACKET] =
            std::array::from_fn(|i| beam.as_ref().map_or([0.0; 3], |b| b.coordinates(origin[i])));
        let mut projected = Projected::EMPTY;
        let stack = &mut scratch.packet_any;
        stack.clear();
        stack.push((0, all & !blocked));
        while let Some((id, mask)) = stack.pop() {
            let mut active = mask & !blocked;
            if active == 0 {
                continue;
            }
            if id & TILE != 0 {
                while active != 0 {
                    let i = active.trailing_zeros() as usize;
                    active &= active - 1;
                    if self.leaf_hit(id & !TILE, &rays[i], t_min, t_max) {
                        blocked |= 1 << i;
                        *last = id & !TILE;
                    }
                }
                if blocked == all {
                    return blocked;
                }
                continue;
            }
            let w = &self.wide[id as usize];
            if let Some(beam) = &beam {
                // SAFETY: the caller guarantees L's instructions.
                unsafe { L::project(w, beam, &mut projected) };
            }
            let mut entered: [u32; LANES] = [0; LANES];
            let mut union = 0u64;
            while active != 0 {
                let i = active.trailing_zeros() as usize;
                active &= active - 1;
                let (hit, enter) = match beam {
                    Some(_) => {
                        // SAFETY: the caller guarantees L's instructions.
                        let kept = unsafe { L::cull(&projected, at[i]) };
                        if kept & w.spheres != 0 {
                            // SAFETY: as above.
                            unsafe { L::any(w, origin[i], dir[i], t_min, t_max) }
                        } else {
                            (None, kept & w.bounds)
                        }
                    }
                    // SAFETY: as above.
                    None => unsafe { L::any(w, origin[i], dir[i], t_min, t_max) },
                };
                if let Some(lane) = hit {
                    blocked |= 1 << i;
                    *last = w.target[lane];
                    continue;
                }
                union |= enter;
                let (lanes, bit) = (enter as u32, 1u32 << i);
                // Branch-free over u32 lanes, so that it is a few vector instructions.
                for (l, e) in entered.iter_mut().enumerate() {
                    *e |= ((lanes >> l) & 1).wrapping_neg() & bit;
                }
            }
            if blocked == all {
                return blocked;
            }
            while union != 0 {
                let lane = union.trailing_zeros() as usize;
                union &= union - 1;
                let tag = if w.tiles & (1 << lane) != 0 { TILE } else { 0 };
                stack.push((w.target[lane] | tag, entered[lane]));
            }
        }
        blocked
    }
}

impl Hierarchy {
    /// The nearest hit of each of `rays` with t in (t_min, t_max), traced as packets of up to
    /// [`PACKET`] rays by the compiled form [`Self::simd`] selects; what the tracer's primary
    /// rays run, here for rays from anywhere (the tests compare it with brute force).
    pub fn intersect_packets(&self, rays: &[Ray], t_min: f32, t_max: f32, scratch: &mut Scratch) -> Vec<Option<Hit>> {
        let mut out = vec![None; rays.len()];
        for (first, group) in rays.chunks(PACKET).enumerate() {
            let entry: Vec<f32> = group.iter().map(|r| self.root_entry(r, t_min, t_max)).collect();
            let members: Vec<usize> = (0..group.len()).filter(|&i| entry[i] != f32::INFINITY).collect();
            let packed: Vec<Ray> = members.iter().map(|&i| group[i]).collect();
            let entries: Vec<f32> = members.iter().map(|&i| entry[i]).collect();
            let limits = vec![t_max; packed.len()];
            let mut hits = vec![Hit { t: 0.0, node: u32::MAX, triangle: u32::MAX, u: 0.0, v: 0.0 }; packed.len()];
            match self.simd() {
                #[cfg(target_arch = "x86_64")]
                #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
                // SAFETY: `simd` is only ever set to a form that `Simd::detect` found the CPU runs.
                Simd::Avx512 => unsafe {
                    self.closest_packet_avx512(&packed, t_min, &limits, &entries, scratch, &mut hits)
                },
                #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
                // SAFETY: the portable lanes use only the baseline target's instructions.
                _ => unsafe {
                    self.closest_packet::<Portable>(&packed, t_min, &limits, &entries, u32::MAX, scratch, &mut hits)
                },
            }
            for (&i, hit) in members.iter().zip(hits) {
                out[first * PACKET + i] = (hit.node != u32::MAX).then_some(hit);
            }
        }
        out
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn closest_packet_avx512(
        &self,
        rays: &[Ray],
        t_min: f32,
        t_max: &[f32],
        entry: &[f32],
        scratch: &mut Scratch,
        hits: &mut [Hit],
    ) {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: this function only runs where AVX-512F is enabled.
        unsafe {
            self.closest_packet::<Avx512>(rays, t_min, t_max, entry, u32::MAX, scratch, hits)
        }
    }

    /// Whether each of `rays` hits anything with t in (t_min, t_max), traced as packets with
    /// leaf `hint` tried first (the shadow cache); what the tracer's shadow rays run.
    pub fn occluded_packets(
        &self,
        rays: &[Ray],
        t_min: f32,
        t_max: f32,
        hint: u32,
        scratch: &mut Scratch,
    ) -> Vec<bool> {
        let mut out = vec![false; rays.len()];
        for (first, group) in rays.chunks(PACKET).enumerate() {
            let members: Vec<usize> =
                (0..group.len()).filter(|&i| self.root_entry(&group[i], t_min, t_max) != f32::INFINITY).collect();
            let packed: Vec<Ray> = members.iter().map(|&i| group[i]).collect();
            let mut last = hint;
            let blocked = match self.simd() {
                #[cfg(target_arch = "x86_64")]
                #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
                // SAFETY: `simd` is only ever set to a form that `Simd::detect` found the CPU runs.
                Simd::Avx512 => unsafe { self.occluded_packet_avx512(&packed, t_min, t_max, hint, scratch, &mut last) },
                #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
                // SAFETY: the portable lanes use only the baseline target's instructions.
                _ => unsafe { self.occluded_packet::<Portable>(&packed, t_min, t_max, hint, scratch, &mut last) },
            };
            for (j, &i) in members.iter().enumerate() {
                out[first * PACKET + i] = blocked & (1 << j) != 0;
            }
        }
        out
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn occluded_packet_avx512(
        &self,
        rays: &[Ray],
        t_min: f32,
        t_max: f32,
        hint: u32,
        scratch: &mut Scratch,
        last: &mut u32,
    ) -> u32 {
        #[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
        // SAFETY: this function only runs where AVX-512F is enabled.
        unsafe {
            self.occluded_packet::<Avx512>(rays, t_min, t_max, hint, scratch, last)
        }
    }
}
