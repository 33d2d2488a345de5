//! The orbit camera shared by the CPU renderer, the viewer and the ray tracer: a target, yaw
//! and pitch about it (y up), a distance, a vertical field of view, perspective or parallel
//! projection. Parallel projection shows the same height at the target as perspective does.

use glam::camera::rh::proj::directx as proj;
use glam::{DVec3, Mat4, Vec3};

// WebGPU's clip space is DirectX's: y up, depth in [0, 1].

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    Perspective,
    Parallel,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: Vec3,
    pub yaw_deg: f32,
    pub pitch_deg: f32,
    pub distance: f32,
    pub fov_y_deg: f32,
    pub projection: Projection,
}

impl OrbitCamera {
    /// A camera that frames the box `bounds`: 2D scenes seen from +z in parallel projection,
    /// 3D scenes from a three-quarter view in perspective.
    pub fn framing(bounds: (DVec3, DVec3), dim: usize) -> Self {
        let centre = (0.5 * (bounds.0 + bounds.1)).as_vec3();
        let mut cam = if dim == 2 {
            Self {
                target: centre,
                yaw_deg: 0.0,
                pitch_deg: 0.0,
                distance: 1.0,
                fov_y_deg: 30.0,
                projection: Projection::Parallel,
            }
        } else {
            Self {
                target: centre,
                yaw_deg: 35.0,
                pitch_deg: 20.0,
                distance: 1.0,
                fov_y_deg: 30.0,
                projection: Projection::Perspective,
            }
        };
        cam.distance = cam.framing_distance(bounds);
        cam
    }

    /// The distance at which the box `bounds`, seen from this camera's direction, fits the
    /// vertical field of view (and the same angle horizontally) with a 6% margin.
    pub fn framing_distance(&self, bounds: (DVec3, DVec3)) -> f32 {
        let tan_half = (0.5 * self.fov_y_deg.to_radians()).max(1e-3).tan();
        let back = self.eye_direction();
        let right = Vec3::Y.cross(back).try_normalize().unwrap_or(Vec3::X);
        let up = back.cross(right);
        let (lo, hi) = (bounds.0.as_vec3(), bounds.1.as_vec3());
        let mut need = 1e-6f32;
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ) - self.target;
            let lateral = c.dot(right).abs().max(c.dot(up).abs()) * 1.06;
            need = need.max(match self.projection {
                // The corner must lie inside the cone: distance ≥ its depth towards the eye plus
                // its lateral offset over tan(half angle).
                Projection::Perspective => c.dot(back) + lateral / tan_half,
                Projection::Parallel => lateral / tan_half,
            });
        }
        need
    }

    /// Re-targets and re-distances the camera (keeping its angles and field of view) so that
    /// `points` fill an image of aspect `aspect` with a 5% margin: tighter than framing a
    /// bounding box, whose corners an attractor rarely fills.
    pub fn fit_points(&mut self, points: &[Vec3], aspect: f32) {
        let pts: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
        if pts.is_empty() {
            return;
        }
        let back = self.eye_direction();
        let right = Vec3::Y.cross(back).try_normalize().unwrap_or(Vec3::X);
        let up = back.cross(right);
        let (mut r0, mut r1, mut u0, mut u1, mut d0, mut d1) =
            (f32::MAX, f32::MIN, f32::MAX, f32::MIN, f32::MAX, f32::MIN);
        for p in &pts {
            let (r, u, d) = (p.dot(right), p.dot(up), p.dot(back));
            (r0, r1, u0, u1, d0, d1) = (r0.min(r), r1.max(r), u0.min(u), u1.max(u), d0.min(d), d1.max(d));
        }
        self.target = 0.5 * (r0 + r1) * right + 0.5 * (u0 + u1) * up + 0.5 * (d0 + d1) * back;
        let tan_y = (0.5 * self.fov_y_deg.to_radians()).max(1e-3).tan();
        let tan_x = tan_y * aspect.max(1e-3);
        let margin = 1.05;
        self.distance = match self.projection {
            Projection::Parallel => margin * (0.5 * (u1 - u0) / tan_y).max(0.5 * (r1 - r0) / tan_x).max(1e-6),
            Projection::Perspective => {
                let mut need = 1e-6f32;
                for p in &pts {
                    let c = *p - self.target;
                    let depth = c.dot(back);
                    need = need
                        .max(depth + margin * c.dot(right).abs() / tan_x)
                        .max(depth + margin * c.dot(up).abs() / tan_y);
                }
                need
            }
        };
    }

    /// Unit vector from the target towards the eye.
    pub fn eye_direction(&self) -> Vec3 {
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.to_radians());
        Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos())
    }

    pub fn eye(&self) -> Vec3 {
        self.target + self.distance * self.eye_direction()
    }

    pub fn view_from_world(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
    }

    /// Half the visible height at the target (used for parallel projection and panning).
    pub fn half_height_at_target(&self) -> f32 {
        self.distance * (0.5 * self.fov_y_deg.to_radians()).tan()
    }

    /// Projection with depth mapped to [0, 1] between `near` and `far` (view-space distances).
    pub fn clip_from_view(&self, aspect: f32, near: f32, far: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective => proj::perspective(self.fov_y_deg.to_radians(), aspect, near.max(1e-4), far),
            Projection::Parallel => {
                let h = self.half_height_at_target();
                proj::orthographic(-h * aspect, h * aspect, -h, h, near, far)
            }
        }
    }

    /// Near and far view distances that enclose `bounds`, for depth cueing and clipping.
    pub fn depth_range(&self, bounds: (DVec3, DVec3)) -> (f32, f32) {
        let view = self.view_from_world();
        let (lo, hi) = (bounds.0.as_vec3(), bounds.1.as_vec3());
        let mut near = f32::INFINITY;
        let mut far = f32::NEG_INFINITY;
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let d = -view.transform_point3(c).z;
            near = near.min(d);
            far = far.max(d);
        }
        let pad = 1e-3 * (far - near).max(1e-3);
        // A flat scene (a flame) seen from farther than 32 has its near and far within
        // an f32 step of each other, and 1e-6 of padding rounds away: 1 / (far − near)
        // infinite, every depth fraction NaN and the picture black. Two steps at the larger
        // distance keep them apart (below a distance of about 4 they are less than 1e-6, and
        // the padding is as it was).
        let pad = pad.max(2.0 * f32::EPSILON * near.abs().max(far.abs()));
        let near = match self.projection {
            Projection::Perspective => (near - pad).max(far * 1e-4).max(1e-4),
            Projection::Parallel => near - pad,
        };
        (near, far + pad)
    }

    /// Orbits by a drag of (dx, dy) pixels in a window `height_px` tall.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw_deg -= dx * 0.3;
        self.pitch_deg = (self.pitch_deg + dy * 0.3).clamp(-89.0, 89.0);
    }

    /// Pans the target by a drag of (dx, dy) pixels in a window `height_px` tall.
    pub fn pan(&mut self, dx: f32, dy: f32, height_px: f32) {
        let world_per_px = 2.0 * self.half_height_at_target() / height_px.max(1.0);
        let view = self.view_from_world();
        let right = Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let up = Vec3::new(view.x_axis.y, view.y_axis.y, view.z_axis.y);
        self.target += (-dx * right + dy * up) * world_per_px;
    }

    /// Zooms by `steps` wheel notches (positive: closer).
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).max(1e-4);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat scene far away (an imported flame whose view is wide: distance 67 and more) keeps
    /// a depth range whose inverse is finite, so its points get depth fractions in [0, 1], not
    /// NaN (which drew them black).
    #[test]
    fn a_flat_scene_far_away_has_finite_depth_fractions() {
        let bounds = (DVec3::new(-50.0, -30.0, 0.0), DVec3::new(50.0, 30.0, 0.0));
        for distance in [0.5f32, 3.0, 37.4, 67.2, 1000.0, 1.0e6] {
            for projection in [Projection::Perspective, Projection::Parallel] {
                let mut cam = OrbitCamera::framing(bounds, 2);
                (cam.projection, cam.distance) = (projection, distance);
                let (near, far) = cam.depth_range(bounds);
                let inv_range = 1.0 / (far - near);
                assert!(inv_range.is_finite() && near < far, "{projection:?} at {distance}: {near}..{far}");
                let view = cam.view_from_world();
                for p in [Vec3::ZERO, Vec3::new(49.0, -29.0, 0.0), Vec3::new(-13.0, 7.0, 0.0)] {
                    let t = (-view.transform_point3(p).z - near) * inv_range;
                    assert!((0.0..=1.0).contains(&t), "{projection:?} at {distance}: t = {t} for {p}");
                }
            }
        }
    }

    #[test]
    fn framing_sees_all_corners() {
        let bounds = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(100.0, 100.0, 100.0));
        for projection in [Projection::Perspective, Projection::Parallel] {
            let mut cam = OrbitCamera::framing(bounds, 3);
            cam.projection = projection;
            cam.distance = cam.framing_distance(bounds);
            let (near, far) = cam.depth_range(bounds);
            let clip = cam.clip_from_view(1.0, near, far) * cam.view_from_world();
            for k in 0..8 {
                let c = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32) * 100.0;
                let p = clip.project_point3(c);
                assert!(p.x.abs() <= 1.0 && p.y.abs() <= 1.0, "{projection:?} corner {k} at {p}");
                assert!((-1e-4..=1.0001).contains(&p.z), "{projection:?} depth {}", p.z);
            }
        }
    }
}
