//! The interface between the Vulkan host and the rust-gpu kernel: descriptor bindings and the push
//! constants of every entry point ([`crate::integrator::FrameParams`] travels in a buffer). Both sides import these definitions, so they cannot drift apart.
//!
//! All bindings are storage buffers in descriptor set 0 (std430 layout, so the `#[repr(C)]` types of
//! [`crate::scene::layout`] map one to one). Buffers a scene does not need are bound as small dummies.
use bytemuck::{Pod, Zeroable};


/// `SceneGlobals` (one element).
pub const BINDING_GLOBALS: u32 = 0;
/// `Bvh4Node` array.
pub const BINDING_NODES: u32 = 1;
/// `TrianglePositions` array.
pub const BINDING_TRIANGLES: u32 = 2;
/// `TriangleInfo` array.
pub const BINDING_TRIANGLE_INFO: u32 = 3;
/// Per-vertex normals `[f32; 4]`.
pub const BINDING_NORMALS: u32 = 4;
/// Per-vertex texture coordinates `[f32; 2]`.
pub const BINDING_UVS: u32 = 5;
/// `Material` array.
pub const BINDING_MATERIALS: u32 = 6;
/// `TextureInfo` array.
pub const BINDING_TEXTURES: u32 = 7;
/// RGBA8 texels, `u32` each.
pub const BINDING_TEXELS: u32 = 8;
/// `Light` array.
pub const BINDING_LIGHTS: u32 = 9;
/// Light-selection CDF, `f32`.
pub const BINDING_LIGHT_CDF: u32 = 10;
/// Triangle to light index, `u32`.
pub const BINDING_TRIANGLE_LIGHT: u32 = 11;
/// Environment texels `[f32; 4]`.
pub const BINDING_ENVIRONMENT_TEXELS: u32 = 12;
/// Environment marginal CDF, `f32`.
pub const BINDING_ENVIRONMENT_MARGINAL: u32 = 13;
/// Environment conditional CDFs, `f32`.
pub const BINDING_ENVIRONMENT_CONDITIONAL: u32 = 14;
/// The blocks of one dispatch chunk: `[origin_x, origin_y, size, region]` each ([`GpuBlock`]).
pub const BINDING_BLOCKS: u32 = 15;
/// One radiance estimate per sample of the chunk (`[f32; 4]`, rgb + unused).
pub const BINDING_SAMPLES: u32 = 16;
/// The replicated image: every pixel holds its block's mean (`[f32; 4]`, width × height).
pub const BINDING_REPLICATED: u32 = 17;
/// Cell means of every block size above one (see `foveation::fill`).
pub const BINDING_CELL_MEANS: u32 = 18;
/// The filled linear HDR image (`[f32; 4]`, width × height).
pub const BINDING_HDR: u32 = 19;
/// The tone-mapped image (RGBA8 packed in `u32`, width × height).
pub const BINDING_LDR: u32 = 20;
/// The frame's [`FrameParams`] (one element; a buffer rather than push constants because it is larger
/// than the 128 bytes of push constants Vulkan guarantees).
pub const BINDING_FRAME: u32 = 21;
/// Number of bindings.
pub const BINDING_COUNT: u32 = 22;

/// One block of a dispatch chunk (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuBlock {
    pub origin: [u32; 2],
    pub size: u32,
    pub region: u32,
}

/// Push constants of every entry point: what this dispatch covers (32 bytes). The frame itself is in
/// [`BINDING_FRAME`].
///
/// `render_samples` runs one invocation per sample: invocation `i < block_count · spp` renders sample
/// `i % spp` of block `i / spp` of the chunk (all blocks of a chunk belong to one region, so they share
/// `spp`). `reduce_blocks` runs one invocation per block of the chunk. `cell_means`, `fill` and `tonemap`
/// run one invocation per cell or pixel, `item_count` in all.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct KernelPushConstants {
    /// Blocks in this chunk (`render_samples`, `reduce_blocks`).
    pub block_count: u32,
    /// Samples per block in this chunk.
    pub spp: u32,
    /// Items for the per-cell and per-pixel kernels.
    pub item_count: u32,
    /// `FILL_BILINEAR` or `FILL_REPLICATE`.
    pub fill_mode: u32,
    /// Exposure compensation in EV for `tonemap`.
    pub exposure_ev: f32,
    pub _pad: [u32; 3],
}

/// Workgroup size of every entry point.
pub const WORKGROUP_SIZE: u32 = 64;
