//! Pipeline barriers the host records between its passes (compute, transfer, acceleration-structure
//! builds, host reads).
use ash::vk;

/// Records one global memory barrier: `src_access` at `src_stage` before `dst_access` at `dst_stage`.
pub(crate) fn memory_barrier(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    (src_stage, src_access): (vk::PipelineStageFlags, vk::AccessFlags),
    (dst_stage, dst_access): (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let b = [vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)];
    // SAFETY: recording into a command buffer in the recording state (every caller records there).
    unsafe {
        device.cmd_pipeline_barrier(
            cb,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &b,
            &[],
            &[],
        );
    }
}

/// Records image layout transitions `images` between `src_stage` and `dst_stage`.
pub(crate) fn image_barrier(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    (src_stage, dst_stage): (vk::PipelineStageFlags, vk::PipelineStageFlags),
    images: &[vk::ImageMemoryBarrier<'_>],
) {
    // SAFETY: recording into a command buffer in the recording state (every caller records there),
    // with barriers on images of this device.
    unsafe {
        device.cmd_pipeline_barrier(
            cb,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            images,
        );
    }
}
