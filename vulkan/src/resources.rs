//! The per-frame buffers, sized for one frame layout and reused while a frame fits (see
//! `fovea_core::kernel_abi` for what each binding holds). Below the context, which keeps the last set.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use fovea_core::integrator::FrameParams;

use crate::buffer::GpuBuffer;
use crate::error::Result;
use crate::instance::Shared;
use crate::limits::Limits;

/// Bytes of one `[f32; 4]` pixel, sample or cell.
pub(crate) const PIXEL: u64 = 16;

/// Buffer sizes of one frame layout; buffers are reused while a frame fits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Sizes {
    pub pixels: u64,
    pub cells: u64,
    pub block_buffer: u64,
    pub chunk_blocks: u64,
    pub chunk_samples: u64,
}

impl Sizes {
    pub fn fits_in(&self, other: &Sizes) -> bool {
        self.pixels <= other.pixels
            && self.cells <= other.cells
            && self.block_buffer <= other.block_buffer
            && self.chunk_blocks <= other.chunk_blocks
            && self.chunk_samples <= other.chunk_samples
    }
}

/// The per-frame buffers (see `kernel_abi` for what each binding holds).
pub(crate) struct FrameResources {
    pub sizes: Sizes,
    pub frame: GpuBuffer,
    pub blocks: GpuBuffer,
    pub samples: GpuBuffer,
    /// The replicated image, which the fill overwrites with the HDR image (bindings 17 and 19).
    pub replicated: GpuBuffer,
    pub cell_means: GpuBuffer,
    pub ldr: GpuBuffer,
    pub ldr_readback: GpuBuffer,
    pub hdr_readback: GpuBuffer,
    /// The live view's running mean ([`BINDING_ACCUMULATION`]), created by the first live frame.
    pub accumulation: Option<GpuBuffer>,
}

impl FrameResources {
    pub fn new(shared: &Arc<Shared>, limits: &Limits, s: Sizes) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let src = vk::BufferUsageFlags::TRANSFER_SRC;
        let dst = vk::BufferUsageFlags::TRANSFER_DST;
        let sh = shared;
        for (what, bytes) in [
            ("the block list", s.block_buffer * 16),
            ("the samples buffer", s.chunk_samples * PIXEL),
            ("the HDR image", s.pixels * PIXEL),
            ("the cell means", s.cells * PIXEL),
        ] {
            limits.check_size(what, bytes)?;
        }
        Ok(Self {
            sizes: s,
            frame: GpuBuffer::new(
                sh,
                "frame parameters",
                std::mem::size_of::<FrameParams>() as u64,
                storage,
                MemoryLocation::CpuToGpu,
            )?,
            blocks: GpuBuffer::new(
                sh,
                "block list",
                s.block_buffer * 16,
                storage,
                MemoryLocation::CpuToGpu,
            )?,
            samples: GpuBuffer::new(
                sh,
                "samples",
                s.chunk_samples * PIXEL,
                storage,
                MemoryLocation::GpuOnly,
            )?,
            replicated: GpuBuffer::new(
                sh,
                "replicated and HDR image",
                s.pixels * PIXEL,
                storage | src,
                MemoryLocation::GpuOnly,
            )?,
            cell_means: GpuBuffer::new(
                sh,
                "cell means",
                s.cells.max(1) * PIXEL,
                storage,
                MemoryLocation::GpuOnly,
            )?,
            ldr: GpuBuffer::new(
                sh,
                "LDR image",
                s.pixels * 4,
                storage | src,
                MemoryLocation::GpuOnly,
            )?,
            ldr_readback: GpuBuffer::new(
                sh,
                "LDR readback",
                s.pixels * 4,
                dst,
                MemoryLocation::GpuToCpu,
            )?,
            hdr_readback: GpuBuffer::new(
                sh,
                "HDR readback",
                s.pixels * PIXEL,
                dst,
                MemoryLocation::GpuToCpu,
            )?,
            accumulation: None,
        })
    }
}
