//! The CPU reference: the shaders' algorithms in plain Rust f32, function by function.
//!
//! Each file mirrors one WGSL file with the same function names (`rng.rs` <->
//! `shaders/shared/rng.wgsl`, ...), so the two can be read side by side. It draws the same
//! random numbers for the same sample, so GPU and CPU images agree up to floating-point
//! differences of the math library. Rayon parallelises over image rows.
//! This module reads `scene::records` and never the GPU backend.

pub mod bindings;
pub mod bsdf;
pub mod geometry;
pub mod intersect;
pub mod lights;
pub mod materials;
pub mod media;
pub mod path;
pub mod primitives;
pub mod rng;
pub mod samplers;
pub mod sampling;
pub mod textures;
pub mod trace;
pub mod types;

pub use trace::CpuRenderer;
