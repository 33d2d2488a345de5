//! The traversal form of the W^k(A) hierarchy: its nodes collapsed into wide nodes of up to
//! [`LANES`] children, whose bounding spheres are stored lane by lane (structure of arrays) so
//! that one pass of vector instructions tests a ray against all of them.
//!
//! How it works. Each wide node stands for an inner node of the hierarchy in
//! [`super::hierarchy`]. Its lanes start as that node's children; then the inner child with the
//! largest sphere is replaced by its own children while they fit, so a wide node covers one or
//! more levels of W^k(A): with 4 functions (tapering) all 16 grandchildren, with 5 (plant2) 13
//! lanes of mixed depth. The lane bounds are the hierarchy's own spheres (grown bottom-up to
//! enclose their children), so the culling argument is unchanged: a skipped lane's bound holds
//! every leaf below it. The lane test computes the closest-approach roots exactly as
//! [`super::geometry::sphere_roots`] does, the same operations in the same order and no fused
//! multiply-add, so a leaf's t is bit for bit what the scalar test (and brute force) gives. A
//! miss leaves NaN roots, which fail every comparison, so no separate miss mask is needed.
//!
//! Two implementations of the lane pass ([`Lanes`]): [`Avx512`] with intrinsics, and
//! [`Portable`] loops over plain arrays for the compiler to vectorise (left to the compiler with
//! AVX-512 enabled they were no faster than the scalar search: it built the masks through
//! shuffles and spilled). The traversal in `search` is compiled once per form, chosen at run
//! time ([`Simd::detect`]): AVX-512F, AVX2 with the portable pass, or the baseline target.

use super::geometry::{Node, NodeKind};
use crate::simd::SimdLevel;

/// f32 lanes of one AVX-512 register.
const CHUNK: usize = 16;
/// Children per wide node, a multiple of [`CHUNK`]. 32 and 64 (fewer levels, more registers
/// per pass) measured slower on tapering and no faster on plant2.
pub const LANES: usize = CHUNK;
/// Lane mask of a wide node.
pub type Mask = u64;

/// Up to [`LANES`] child bounds. A lane is a leaf sphere, a triangle tile or a wide node; unused
/// lanes are in none of the masks.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct WideNode {
    pub centre_x: [f32; LANES],
    pub centre_y: [f32; LANES],
    pub centre_z: [f32; LANES],
    pub radius: [f32; LANES],
    /// Leaf sphere and tile lanes: the index in `Hierarchy::nodes` (what a hit reports); wide
    /// node lanes: the index in `Hierarchy::wide`.
    pub target: [u32; LANES],
    /// Lanes that are leaf spheres (the bound is the geometry).
    pub spheres: Mask,
    /// Lanes that are bounds to enter: wide nodes and triangle tiles.
    pub bounds: Mask,
    /// Of `bounds`, the triangle tiles.
    pub tiles: Mask,
}

impl WideNode {
    const EMPTY: WideNode = WideNode {
        centre_x: [0.0; LANES],
        centre_y: [0.0; LANES],
        centre_z: [0.0; LANES],
        radius: [0.0; LANES],
        target: [0; LANES],
        spheres: 0,
        bounds: 0,
        tiles: 0,
    };

    /// Both roots of the ray with every lane's sphere (NaN where it misses), as
    /// `sphere_roots` computes them.
    #[inline(always)]
    pub fn roots(&self, origin: [f32; 3], dir: [f32; 3]) -> ([f32; LANES], [f32; LANES]) {
        let mut t0 = [0.0f32; LANES];
        let mut t1 = [0.0f32; LANES];
        for i in 0..LANES {
            let ox = origin[0] - self.centre_x[i];
            let oy = origin[1] - self.centre_y[i];
            let oz = origin[2] - self.centre_z[i];
            let b = ox * dir[0] + oy * dir[1] + oz * dir[2];
            let lx = ox - b * dir[0];
            let ly = oy - b * dir[1];
            let lz = oz - b * dir[2];
            let r = self.radius[i];
            let s = (r * r - (lx * lx + ly * ly + lz * lz)).sqrt();
            t0[i] = -b - s;
            t1[i] = -b + s;
        }
        (t0, t1)
    }
}

/// What a lane pass gives the nearest-hit search.
#[derive(Clone, Copy, Debug)]
pub struct ClosestLanes {
    /// The nearest leaf sphere surface in (t_min, t_max), as (t, lane); ties to the lower lane.
    pub hit: Option<(f32, usize)>,
    /// Bound lanes that overlap (t_min, t_max), where t_max is lowered to the hit's t.
    pub enter: Mask,
    /// Where the ray enters each bound lane of `enter` (clamped to t_min).
    pub entry: [f32; LANES],
}

/// Rays that share one direction d (the shadow rays of a parallel light), seen along it: an
/// orthonormal basis (u, v, d) in which a ray is a point (its origin's u and v) and a sphere a
/// disc, so that a lane pass needs no square root and a node's half of it is done once per
/// packet ([`Lanes::project`], [`Lanes::cull`]).
///
/// The pass it gives is a conservative cull, not the decision: the radii grow by `margin`
/// (10^-5 of the largest coordinate's size, a hundred times the rounding of either form), so
/// every lane that the exact pass ([`Lanes::any`]) finds hit or entered is kept, and a
/// kept leaf lane is decided by the exact pass. The searches' answers are the exact pass's.
#[derive(Clone, Copy, Debug)]
pub struct Beam {
    pub u: [f32; 3],
    pub v: [f32; 3],
    pub d: [f32; 3],
    pub margin: f32,
}

impl Beam {
    /// The basis of direction `d` (unit length) for coordinates of size up to `extent`.
    pub fn new(d: [f32; 3], extent: f32) -> Self {
        let dir = glam::Vec3::from_array(d);
        // Duff et al.'s branch-free orthonormal basis.
        let sign = 1.0f32.copysign(dir.z);
        let a = -1.0 / (sign + dir.z);
        let b = dir.x * dir.y * a;
        let u = glam::Vec3::new(1.0 + sign * dir.x * dir.x * a, sign * b, -sign * dir.x);
        let v = glam::Vec3::new(b, sign + dir.y * dir.y * a, -dir.y);
        Self { u: u.to_array(), v: v.to_array(), d, margin: 1e-5 * extent }
    }

    /// A point's coordinates in the basis.
    #[inline(always)]
    pub fn coordinates(&self, p: [f32; 3]) -> [f32; 3] {
        let dot = |a: [f32; 3]| a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
        [dot(self.u), dot(self.v), dot(self.d)]
    }
}

/// A wide node's lanes in a [`Beam`]'s basis: the centres' u and v, their d plus the margin,
/// and the grown radius squared.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Projected {
    pub u: [f32; LANES],
    pub v: [f32; LANES],
    pub d: [f32; LANES],
    pub r2: [f32; LANES],
}

impl Projected {
    pub const EMPTY: Projected = Projected { u: [0.0; LANES], v: [0.0; LANES], d: [0.0; LANES], r2: [0.0; LANES] };
}

/// A compiled form of the lane pass. The decisions are those of `sphere_surface` (leaf
/// spheres) and of `Hierarchy::root_entry` (bounds: overlap with (t_min, t_max), entry clamped to t_min),
/// on bit-identical roots.
#[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
pub trait Lanes {
    /// The nearest-hit pass over `w`.
    ///
    /// # Safety
    /// The CPU must run the instructions of `Self` (see [`Simd::detect`]).
    unsafe fn closest(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> ClosestLanes;

    /// The any-hit pass over `w`: some leaf sphere lane hit in (t_min, t_max), and the bound
    /// lanes that overlap it.
    ///
    /// # Safety
    /// As for [`Lanes::closest`].
    unsafe fn any(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> (Option<usize>, Mask);

    /// `w`'s lanes in `beam`'s basis, into `out`.
    ///
    /// # Safety
    /// As for [`Lanes::closest`].
    unsafe fn project(w: &WideNode, beam: &Beam, out: &mut Projected);

    /// The lanes that a ray of the beam at `at` (its origin's [`Beam::coordinates`]) may meet
    /// at t > 0: every lane whose exact any-hit pass over (0, ∞) is a surface hit or an
    /// entered bound, and a few more within the margin.
    ///
    /// # Safety
    /// As for [`Lanes::closest`].
    unsafe fn cull(p: &Projected, at: [f32; 3]) -> Mask;
}

/// The cull's decision for one lane: the ray's line passes within the grown radius
/// (q ≥ 0, q = r² − distance²) and the sphere's far side lies ahead of the origin
/// (√q > b, b the centre's distance behind the origin less the margin).
#[inline(always)]
fn cull_lane(p: &Projected, i: usize, at: [f32; 3]) -> bool {
    let (du, dv) = (at[0] - p.u[i], at[1] - p.v[i]);
    let q = p.r2[i] - (du * du + dv * dv);
    let b = at[2] - p.d[i];
    (q >= 0.0) & ((b < 0.0) | (q > b * b))
}

#[inline(always)]
fn project_lanes(w: &WideNode, beam: &Beam, out: &mut Projected) {
    for i in 0..LANES {
        let c = [w.centre_x[i], w.centre_y[i], w.centre_z[i]];
        let [u, v, d] = beam.coordinates(c);
        let r = w.radius[i] + beam.margin;
        (out.u[i], out.v[i], out.d[i], out.r2[i]) = (u, v, d + beam.margin, r * r);
    }
}

/// Plain loops over the lane arrays, which the compiler vectorises for the target it compiles
/// the traversal for (the baseline or AVX2).
pub struct Portable;

#[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
impl Lanes for Portable {
    #[inline(always)]
    unsafe fn closest(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> ClosestLanes {
        let (t0, t1) = w.roots(origin, dir);
        let mut hit = None;
        let mut limit = t_max;
        for i in 0..LANES {
            let t = if t0[i] > t_min { t0[i] } else { t1[i] };
            if w.spheres & (1 << i) != 0 && t > t_min && t < limit {
                hit = Some((t, i));
                limit = t;
            }
        }
        let mut enter: Mask = 0;
        let mut entry = [0.0f32; LANES];
        for i in 0..LANES {
            enter |= ((t1[i] > t_min && t0[i] < limit) as Mask) << i;
            entry[i] = t0[i].max(t_min);
        }
        ClosestLanes { hit, enter: enter & w.bounds, entry }
    }

    #[inline(always)]
    unsafe fn any(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> (Option<usize>, Mask) {
        let (t0, t1) = w.roots(origin, dir);
        let mut surface: Mask = 0;
        let mut enter: Mask = 0;
        for i in 0..LANES {
            let t = if t0[i] > t_min { t0[i] } else { t1[i] };
            surface |= ((t > t_min && t < t_max) as Mask) << i;
            enter |= ((t1[i] > t_min && t0[i] < t_max) as Mask) << i;
        }
        let surface = surface & w.spheres;
        ((surface != 0).then(|| surface.trailing_zeros() as usize), enter & w.bounds)
    }

    #[inline(always)]
    unsafe fn project(w: &WideNode, beam: &Beam, out: &mut Projected) {
        project_lanes(w, beam, out);
    }

    #[inline(always)]
    unsafe fn cull(p: &Projected, at: [f32; 3]) -> Mask {
        let mut kept: Mask = 0;
        for i in 0..LANES {
            kept |= (cull_lane(p, i, at) as Mask) << i;
        }
        kept
    }
}

/// AVX-512F intrinsics: one 16-wide register per lane quantity, comparisons straight into
/// mask registers.
#[cfg(target_arch = "x86_64")]
pub struct Avx512;

#[cfg(target_arch = "x86_64")]
#[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
impl Lanes for Avx512 {
    #[inline(always)]
    unsafe fn closest(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> ClosestLanes {
        // SAFETY: the caller guarantees AVX-512F.
        unsafe { avx512::closest(w, origin, dir, t_min, t_max) }
    }

    #[inline(always)]
    unsafe fn any(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> (Option<usize>, Mask) {
        // SAFETY: the caller guarantees AVX-512F.
        unsafe { avx512::any(w, origin, dir, t_min, t_max) }
    }

    #[inline(always)]
    unsafe fn project(w: &WideNode, beam: &Beam, out: &mut Projected) {
        // Once per node and packet: the compiler's vector loop is enough.
        project_lanes(w, beam, out);
    }

    #[inline(always)]
    unsafe fn cull(p: &Projected, at: [f32; 3]) -> Mask {
        // SAFETY: the caller guarantees AVX-512F.
        unsafe { avx512::cull(p, at) }
    }
}

#[cfg(target_arch = "x86_64")]
#[expect(unsafe_code, reason = "entered after runtime CPU feature detection")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::{ClosestLanes, LANES, Mask, Projected, WideNode};

    const CHUNKS: usize = LANES / CHUNK;
    const _: () = assert!(LANES.is_multiple_of(CHUNK) && LANES <= 64, "whole __m512 chunks, masks fit in u64");

    use super::CHUNK;

    /// The roots of [`WideNode::roots`] for lanes `16 c .. 16 c + 16`, the same operations in
    /// the same order.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn roots(w: &WideNode, c: usize, origin: [f32; 3], dir: [f32; 3]) -> (__m512, __m512) {
        let at = c * CHUNK;
        assert!(at + CHUNK <= LANES);
        // SAFETY: lanes at..at + 16 are in bounds (asserted) and 64-byte aligned: the arrays
        // are 64-byte multiples at the start of the repr(C), align(64) `WideNode`.
        let (cx, cy, cz, r) = unsafe {
            (
                _mm512_load_ps(w.centre_x.as_ptr().add(at)),
                _mm512_load_ps(w.centre_y.as_ptr().add(at)),
                _mm512_load_ps(w.centre_z.as_ptr().add(at)),
                _mm512_load_ps(w.radius.as_ptr().add(at)),
            )
        };
        let (dx, dy, dz) = (_mm512_set1_ps(dir[0]), _mm512_set1_ps(dir[1]), _mm512_set1_ps(dir[2]));
        let ox = _mm512_sub_ps(_mm512_set1_ps(origin[0]), cx);
        let oy = _mm512_sub_ps(_mm512_set1_ps(origin[1]), cy);
        let oz = _mm512_sub_ps(_mm512_set1_ps(origin[2]), cz);
        let b = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(ox, dx), _mm512_mul_ps(oy, dy)), _mm512_mul_ps(oz, dz));
        let lx = _mm512_sub_ps(ox, _mm512_mul_ps(b, dx));
        let ly = _mm512_sub_ps(oy, _mm512_mul_ps(b, dy));
        let lz = _mm512_sub_ps(oz, _mm512_mul_ps(b, dz));
        let l2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(lx, lx), _mm512_mul_ps(ly, ly)), _mm512_mul_ps(lz, lz));
        let s = _mm512_sqrt_ps(_mm512_sub_ps(_mm512_mul_ps(r, r), l2));
        // −b by flipping the sign bit, as scalar negation does (0 − b would differ at b = 0).
        let minus_b = _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(b), _mm512_set1_epi32(i32::MIN)));
        (_mm512_sub_ps(minus_b, s), _mm512_add_ps(minus_b, s))
    }

    /// The lanes of one chunk, as a 16-bit mask.
    fn chunk_mask(mask: Mask, c: usize) -> u16 {
        (mask >> (c * CHUNK)) as u16
    }

    #[target_feature(enable = "avx512f")]
    #[inline]
    pub fn closest(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> ClosestLanes {
        let lo = _mm512_set1_ps(t_min);
        let mut t0 = [_mm512_setzero_ps(); CHUNKS];
        let mut t1 = [_mm512_setzero_ps(); CHUNKS];
        let mut hit = None;
        let mut limit = t_max;
        for c in 0..CHUNKS {
            (t0[c], t1[c]) = roots(w, c, origin, dir);
            // Nearer root above t_min, else the farther (NaN roots of a miss fail every test).
            let above = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(t0[c], lo);
            let t = _mm512_mask_blend_ps(above, t1[c], t0[c]);
            let ahead = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(chunk_mask(w.spheres, c), t, lo);
            let surface = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(ahead, t, _mm512_set1_ps(limit));
            if surface != 0 {
                // Strictly nearer than every earlier chunk's hit: ties stay with the lower lane.
                let nearest = _mm512_mask_reduce_min_ps(surface, t);
                let first = _mm512_mask_cmp_ps_mask::<_CMP_EQ_OQ>(surface, t, _mm512_set1_ps(nearest));
                hit = Some((nearest, c * CHUNK + first.trailing_zeros() as usize));
                limit = nearest;
            }
        }
        let mut enter: Mask = 0;
        let mut entry = [0.0f32; LANES];
        for c in 0..CHUNKS {
            let overlap = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(chunk_mask(w.bounds, c), t1[c], lo);
            let overlap = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(overlap, t0[c], _mm512_set1_ps(limit));
            enter |= (overlap as Mask) << (c * CHUNK);
            // SAFETY: entry[c * 16..c * 16 + 16] is in bounds (c < CHUNKS).
            unsafe { _mm512_storeu_ps(entry.as_mut_ptr().add(c * CHUNK), _mm512_max_ps(t0[c], lo)) };
        }
        ClosestLanes { hit, enter, entry }
    }

    #[target_feature(enable = "avx512f")]
    #[inline]
    pub fn any(w: &WideNode, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> (Option<usize>, Mask) {
        let (lo, hi) = (_mm512_set1_ps(t_min), _mm512_set1_ps(t_max));
        let mut enter: Mask = 0;
        for c in 0..CHUNKS {
            let (t0, t1) = roots(w, c, origin, dir);
            let above = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(t0, lo);
            let t = _mm512_mask_blend_ps(above, t1, t0);
            let ahead = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(chunk_mask(w.spheres, c), t, lo);
            let surface = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(ahead, t, hi);
            if surface != 0 {
                return (Some(c * CHUNK + surface.trailing_zeros() as usize), 0);
            }
            let overlap = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(chunk_mask(w.bounds, c), t1, lo);
            enter |= (_mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(overlap, t0, hi) as Mask) << (c * CHUNK);
        }
        (None, enter)
    }

    /// [`super::cull_lane`] for every lane.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub fn cull(p: &Projected, at: [f32; 3]) -> Mask {
        let mut kept: Mask = 0;
        let zero = _mm512_setzero_ps();
        for c in 0..CHUNKS {
            let i = c * CHUNK;
            // SAFETY: lanes i..i + 16 are in bounds and 64-byte aligned (repr(C), align(64)).
            let (u, v, d, r2) = unsafe {
                (
                    _mm512_load_ps(p.u.as_ptr().add(i)),
                    _mm512_load_ps(p.v.as_ptr().add(i)),
                    _mm512_load_ps(p.d.as_ptr().add(i)),
                    _mm512_load_ps(p.r2.as_ptr().add(i)),
                )
            };
            let du = _mm512_sub_ps(_mm512_set1_ps(at[0]), u);
            let dv = _mm512_sub_ps(_mm512_set1_ps(at[1]), v);
            let q = _mm512_sub_ps(r2, _mm512_add_ps(_mm512_mul_ps(du, du), _mm512_mul_ps(dv, dv)));
            let b = _mm512_sub_ps(_mm512_set1_ps(at[2]), d);
            let within = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(q, zero);
            let behind = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(b, zero);
            let reaches = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(q, _mm512_mul_ps(b, b));
            kept |= ((within & (behind | reaches)) as Mask) << i;
        }
        kept
    }
}

/// Collapses the hierarchy below its root (which must be an inner node) into wide nodes; the
/// root's wide node comes first.
pub fn collapse(nodes: &[Node]) -> Vec<WideNode> {
    let mut wide = vec![WideNode::EMPTY];
    // (wide node to fill, hierarchy node it stands for)
    let mut work = vec![(0usize, 0u32)];
    while let Some((slot, index)) = work.pop() {
        let children = |k: u32| {
            let n = &nodes[k as usize];
            n.first..n.first + n.count as u32
        };
        let mut lanes: Vec<u32> = children(index).collect();
        // Open the largest inner child whose children still fit (radius order: a big bound is
        // hit most often, so looking inside it at once saves the most visits).
        loop {
            let open = lanes
                .iter()
                .enumerate()
                .filter(|&(_, &k)| {
                    let n = &nodes[k as usize];
                    n.kind == NodeKind::Inner && lanes.len() - 1 + n.count as usize <= LANES
                })
                .max_by(|a, b| nodes[*a.1 as usize].radius.total_cmp(&nodes[*b.1 as usize].radius))
                .map(|(position, _)| position);
            let Some(position) = open else { break };
            let k = lanes.remove(position);
            lanes.extend(children(k));
        }
        debug_assert!(lanes.len() <= LANES, "a node has more than {LANES} children");
        let mut w = WideNode::EMPTY;
        for (lane, &k) in lanes.iter().enumerate() {
            let n = &nodes[k as usize];
            w.centre_x[lane] = n.centre.x;
            w.centre_y[lane] = n.centre.y;
            w.centre_z[lane] = n.centre.z;
            w.radius[lane] = n.radius;
            let bit: Mask = 1 << lane;
            match n.kind {
                NodeKind::Sphere => {
                    w.spheres |= bit;
                    w.target[lane] = k;
                }
                NodeKind::Triangles => {
                    w.bounds |= bit;
                    w.tiles |= bit;
                    w.target[lane] = k;
                }
                NodeKind::Inner => {
                    w.bounds |= bit;
                    w.target[lane] = wide.len() as u32;
                    work.push((wide.len(), k));
                    wide.push(WideNode::EMPTY);
                }
            }
        }
        wide[slot] = w;
    }
    wide
}

/// Which compiled form of the traversal runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum Simd {
    /// The baseline target (SSE2 on x86-64), or any other architecture.
    #[default]
    Baseline,
    /// x86-64 with AVX2: a lane pass is two 8-wide registers.
    Avx2,
    /// x86-64 with AVX-512F: a lane pass is one 16-wide register.
    Avx512,
}

impl Simd {
    /// The widest form this CPU runs.
    pub fn detect() -> Self {
        match SimdLevel::detect() {
            SimdLevel::Avx512 => Simd::Avx512,
            SimdLevel::Avx2 => Simd::Avx2,
            SimdLevel::Scalar => Simd::Baseline,
        }
    }
}
