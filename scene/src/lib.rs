//! # fovea-scene
//!
//! The host-side scene pipeline shared by both hosts: load glTF 2.0 and OBJ/MTL files ([`gltf_loader`],
//! [`obj_loader`]) into a [`mesh::LoadedScene`], decode textures ([`texture`]), build the BVH ([`bvh`]) and
//! pack everything into the flat arrays of `fovea_core::scene::layout` ([`pack`]) that the CPU host reads
//! directly and the Vulkan host uploads unchanged.
pub mod bvh;
pub mod environment;
pub mod error;
pub mod gltf_loader;
pub mod mesh;
pub mod obj_loader;
pub mod pack;
pub mod texture;
