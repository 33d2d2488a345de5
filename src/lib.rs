//! nlifs: modeling and rendering of nonlinear iterated function systems whose functions are
//! given by distorting a regular grid (E. Gröller, "Modeling and Rendering of Nonlinear Iterated
//! Function Systems"). The library holds the model, the scene format, the camera and the CPU
//! chaos game; the binary in `main.rs` is a thin command line on top of it.

pub mod bench;
pub mod camera;
pub mod chaos_game;
pub mod color;
pub mod cpu_time;
pub mod edit;
pub mod export;
pub mod flame;
pub mod gpu;
pub mod io;
pub mod live;
pub mod model;
pub mod output;
pub mod palette;
pub mod platform;
pub mod raytrace;
pub mod record;
pub mod render;
pub mod resolve;
pub mod rng;
pub mod scene;
pub mod shot;
pub mod simd;
pub mod splat;
pub mod viewer;
#[cfg(target_arch = "wasm32")]
pub mod web;
