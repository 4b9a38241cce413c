//! # fovea-core
//!
//! The one place where fovea's rendering math lives: camera, ray-triangle test, BVH traversal, the Disney
//! BRDF, light sampling, multiple importance sampling, the per-sample path integrator, foveation (regions,
//! block ownership, block fill) and post-processing.
//!
//! The crate is `no_std` and written in the subset of Rust that rust-gpu compiles to SPIR-V: no recursion,
//! no function pointers or `dyn`, no iterators over local arrays, no `Option<&T>`, no `static mut`, no
//! `bool` in buffer types and no `f64`. The CPU host calls these functions natively; the GPU kernel calls the
//! very same functions compiled to SPIR-V, so the two backends can be diffed against each other.
//!
//! Types shared with the GPU live in [`scene::layout`]; they are `#[repr(C)]`, [`bytemuck::Pod`] and made of
//! 4-byte scalars and `[f32; 4]` / `[u32; 4]` arrays only (never `glam::Vec3`, whose size differs between
//! the CPU and rust-gpu).
#![no_std]
#![deny(unsafe_code)]
// spirv-std's `ray_query!` (hardware traversal, `bvh::hardware`) declares its query with inline SPIR-V.
#![cfg_attr(
    all(target_arch = "spirv", feature = "ray-query"),
    feature(asm_experimental_arch)
)]
#![allow(clippy::too_many_arguments)]
// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it is also true for NaN, so it guards
// inputs against NaN as well as against zero and negative values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

// The CPU host's square root and fused multiply-add from the standard library (`math::float`); the math
// stays `no_std`.
#[cfg(feature = "std")]
extern crate std;

pub mod bsdf;
pub mod bvh;
pub mod camera;
pub mod denoise;
pub mod foveation;
pub mod geometry;
pub mod integrator;
pub mod kernel_abi;
pub mod lights;
pub mod material;
pub mod math;
// Host-side scheduling: names and kernel entry points as `&str`, which the kernel has no use for.
#[cfg(not(target_arch = "spirv"))]
pub mod passes;
pub mod post;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod temporal;
#[cfg(test)]
mod test_support;

pub use glam;
