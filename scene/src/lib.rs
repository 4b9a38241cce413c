//! # fovea-scene
//!
//! The host-side scene pipeline shared by both hosts: load glTF 2.0 and OBJ/MTL files ([`gltf_loader`],
//! [`obj_loader`]) into a [`mesh::LoadedScene`], decode textures ([`texture`]), build the BVH ([`bvh`]) and
//! pack everything into the flat arrays of `fovea_core::scene::layout` ([`pack`]) that the CPU host reads
//! directly and the Vulkan host uploads unchanged.
// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it is also true for NaN, so it guards
// inputs against NaN as well as against zero and negative values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
pub mod bump;
pub mod bvh;
pub mod environment;
pub mod error;
pub mod gltf_loader;
pub mod gltf_pbr;
pub mod load;
pub mod mesh;
pub mod obj_loader;
pub mod pack;
pub mod procedural;
pub mod rebase;
pub mod source;
pub mod tangents;
pub mod texture;

pub use load::{load_scene, load_scene_from};
