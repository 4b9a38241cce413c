//! The per-frame buffers, sized for one frame layout and reused while a frame fits (see
//! `fovea_core::kernel_abi` for what each binding holds). Below the context, which keeps the last set.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use fovea_core::camera::Camera;
use fovea_core::denoise::DenoiseTexel;
use fovea_core::integrator::FrameParams;
use fovea_core::temporal::{GBufferTexel, HistoryTexel, TemporalParams};

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
    /// Each pixel's sum of the samples that landed in it (`BINDING_PIXEL_SAMPLES`).
    pub pixel_samples: GpuBuffer,
    pub cell_means: GpuBuffer,
    pub ldr: GpuBuffer,
    pub ldr_readback: GpuBuffer,
    pub hdr_readback: GpuBuffer,
    /// The HDR image before the denoiser, copied back (`render --keep-raw`); created by the first
    /// frame that asks for it.
    pub raw_readback: Option<GpuBuffer>,
    /// Temporal reuse's history and G-buffers, created by the first frame that asks for them.
    pub temporal: Option<TemporalBuffers>,
}

/// The buffers temporal reuse keeps from frame to frame, which the denoiser uses too: two histories
/// and two G-buffers, used in turn (this frame writes `[current]`, the previous frame's is
/// `[1 - current]`), and the denoiser's texels.
pub(crate) struct TemporalBuffers {
    pub history: [GpuBuffer; 2],
    pub gbuffer: [GpuBuffer; 2],
    /// The frame's [`TemporalParams`] (`BINDING_TEMPORAL`).
    pub params: GpuBuffer,
    /// The denoiser's two halves of texels (`BINDING_DENOISE`).
    pub denoise: GpuBuffer,
    /// Which of each pair the next frame writes.
    pub current: usize,
    /// The previous frame's camera and size; `None` when the buffers hold no frame yet (or a reset).
    pub previous: Option<(Camera, [u32; 2])>,
}

impl TemporalBuffers {
    pub fn new(shared: &Arc<Shared>, limits: &Limits, pixels: u64) -> Result<Self> {
        let history_bytes = pixels * std::mem::size_of::<HistoryTexel>() as u64;
        let gbuffer_bytes = pixels * std::mem::size_of::<GBufferTexel>() as u64;
        limits.check_size("the history", history_bytes)?;
        limits.check_size("the G-buffer", gbuffer_bytes)?;
        let denoise_bytes = 2 * pixels * std::mem::size_of::<DenoiseTexel>() as u64;
        limits.check_size("the denoiser's texels", denoise_bytes)?;
        let buffer = |what: &str, bytes: u64| {
            GpuBuffer::new(
                shared,
                what,
                bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )
        };
        Ok(Self {
            history: [
                buffer("history A", history_bytes)?,
                buffer("history B", history_bytes)?,
            ],
            gbuffer: [
                buffer("G-buffer A", gbuffer_bytes)?,
                buffer("G-buffer B", gbuffer_bytes)?,
            ],
            params: GpuBuffer::new(
                shared,
                "temporal parameters",
                std::mem::size_of::<TemporalParams>() as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::CpuToGpu,
            )?,
            denoise: buffer("denoiser texels", denoise_bytes)?,
            current: 0,
            previous: None,
        })
    }
}

/// The buffers of [`FrameResources`] sized by the image alone, which outlive a reallocation of the
/// others: the history must survive a frame whose gaze needs more blocks or cells than the last.
pub(crate) struct ImageBuffers {
    raw_readback: Option<GpuBuffer>,
    temporal: Option<TemporalBuffers>,
}

impl FrameResources {
    /// Forgets the buffers sized for the previous image (its history, its raw read-back).
    pub fn drop_image_buffers(&mut self) {
        self.raw_readback = None;
        self.temporal = None;
    }

    /// Frees every buffer but those sized by the image alone, which it returns.
    pub fn into_image_buffers(self) -> ImageBuffers {
        ImageBuffers {
            raw_readback: self.raw_readback,
            temporal: self.temporal,
        }
    }

    /// Takes over the image's buffers of the resources this set replaces (same image size).
    pub fn restore_image_buffers(&mut self, kept: ImageBuffers) {
        self.raw_readback = kept.raw_readback;
        self.temporal = kept.temporal;
    }

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
            pixel_samples: GpuBuffer::new(
                sh,
                "pixel sample sums",
                s.pixels * PIXEL,
                storage,
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
            raw_readback: None,
            temporal: None,
        })
    }
}

/// A view's buffers while another view renders (see `VulkanContext::select_view`).
#[derive(Default)]
pub(crate) struct ParkedView {
    pub(crate) frame: Option<FrameResources>,
    pub(crate) size: Option<(u32, u32)>,
}
