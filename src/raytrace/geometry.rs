//! The plain types the hierarchy's build, its wide form and its searches share: the flat node,
//! the ray, the hit, and the ray–sphere roots that the scalar test and every lane pass compute
//! the same way (so that a leaf's t is the same bits on every path). They sit below
//! `hierarchy` and `wide`, which both need them, so that neither needs the other's internals.

use glam::Vec3;

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
pub(super) fn sphere_surface(ray: &Ray, centre: Vec3, radius: f32, t_min: f32, t_max: f32) -> Option<f32> {
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
