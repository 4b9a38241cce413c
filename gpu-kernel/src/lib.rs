//! rust-gpu compute entry points of fovea.
//!
//! This crate will hold only entry points that map storage buffers and invocation ids to calls into
//! `fovea-core` (the per-sample integrator, region ownership, block fill, tone mapping); no shading math
//! lives here. It is built to SPIR-V by spirv-builder in the Vulkan issue; until then it is empty.
#![no_std]
