//! W^n(A) out of the program: a glTF 2.0 binary with one mesh primitive per function (spheres
//! as merged low-poly icospheres, mesh leaves as their mapped triangles), and a POV-Ray 3.7
//! scene of the leaf spheres with the tracer's camera, lights and ground (for the benchmark).

use std::io::Write;

use super::hierarchy::Hierarchy;
use super::tracer::Shading;
use crate::camera::OrbitCamera;

pub fn write_glb_mesh(_w: &mut dyn Write, _h: &Hierarchy, _colors: &[[f32; 3]], _names: &[String]) -> std::io::Result<()> {
    Err(std::io::Error::other("todo"))
}

pub fn write_pov(_w: &mut dyn Write, _h: &Hierarchy, _camera: &OrbitCamera, _shading: &Shading) -> std::io::Result<()> {
    Err(std::io::Error::other("todo"))
}
