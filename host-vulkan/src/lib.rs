//! # fovea-vulkan
//!
//! The ash Vulkan host of fovea: it uploads the packed scene of `fovea-scene` once per scene and runs the
//! rust-gpu kernel (`fovea-gpu-kernel`, built to SPIR-V by `host-vulkan/build.rs`) over it, with the
//! bindings and push constants of `fovea_core::kernel_abi`. A frame is core's pass list
//! (`fovea_core::passes::frame_passes`) as dispatches of the kernel entry each pass names, in the same
//! order as the CPU host runs them:
//!
//! 1. **Samples.** The host enumerates the blocks of each region (`owning_block(p).origin == p`) and splits
//!    them into chunks of at most [`blocks::DEFAULT_MAX_CHUNK_SAMPLES`] samples. Per chunk,
//!    `render_samples` runs one invocation per sample and `reduce_blocks` one per block (mean of its
//!    samples, written over the block's footprint of the replicated image). Each chunk is one submission
//!    waited on with a timeout, so no dispatch runs long and the samples buffer stays small.
//! 2. Every later pass (cell means, fill, with history the G-buffer, cell albedo, temporal and resolve,
//!    the denoiser's, the tone map, the view's overlay) runs one invocation per cell or pixel
//!    (`FramePass::items`), all in one submission, then the 8-bit (and optionally HDR) image is copied
//!    back.
//!
//! The live view (`fovea view`) keeps the image on the device and presents it to a window's swapchain
//! ([`present`]); the CPU backend's frames go through the same presenter from the host.
//!
//! `render_ms` comes from GPU timestamps around the whole frame (wall time where the queue has none).
//! With `FOVEA_VULKAN_VALIDATION=1` the Khronos validation layer is enabled and its warnings and errors are
//! collected ([`VulkanContext::validation_messages`]).
mod barrier;
pub mod blocks;
mod buffer;
pub mod context;
pub mod device;
pub mod error;
pub mod factory;
pub mod frame;
pub mod hardware;
pub mod instance;
pub mod kernel;
mod limits;
pub mod present;
pub mod probe;
mod resources;
pub mod scene;
pub mod spirv;
pub mod swapchain;
mod timestamps;
pub mod traversal;
#[cfg(feature = "xr")]
pub mod xr;

/// The `ash` Vulkan types (result codes for [`VulkanContext::inject_fault`]).
pub use ash::vk;
pub use context::{validation_requested, ContextOptions, VulkanContext};
pub use device::Device;
pub use error::VulkanError;
pub use fovea_frame::RenderedFrame;
pub use frame::{FrameOutput, FrameRequest, GpuRenderStats};
pub use instance::{list_devices, DeviceInfo};
pub use present::{HudOverlay, PresentOutcome, PresentSource, WindowHandles};
pub use scene::GpuScene;
pub use traversal::{resolve_traversal, RayQuerySupport, Traversal};
