//! [`Device`]: the logical device fovea renders on, with its one queue, the command buffer every
//! submission records into (each waited on before the next), the timestamp pool, and what makes it
//! unusable (a device loss or timeout). The kernel's pipelines ([`crate::kernel::Kernel`]), a frame's
//! buffers ([`crate::resources::FrameResources`]), a scene's acceleration structures
//! ([`crate::hardware::HardwareScene`]) and the window's swapchain ([`crate::swapchain::Presenter`])
//! are each made on it and hold their own state.
use std::sync::Arc;
use std::time::Duration;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::buffer::GpuBuffer;
use crate::context::CHUNK_TIMEOUT;
use crate::error::{Result, VkContext, VulkanError};
use crate::instance::{DeviceInfo, MessageLog, Shared};
use crate::limits::Limits;

/// A logical device and its queue.
pub struct Device {
    pub(crate) shared: Arc<Shared>,
    pub(crate) info: DeviceInfo,
    pub(crate) limits: Limits,
    pub(crate) queue: vk::Queue,
    /// The queue's family (an OpenXR session is told it).
    #[cfg_attr(not(feature = "xr"), allow(dead_code))]
    pub(crate) queue_family: u32,
    pub(crate) command_pool: vk::CommandPool,
    pub(crate) command_buffer: vk::CommandBuffer,
    pub(crate) fence: vk::Fence,
    /// Two timestamps per frame; null when the queue has no timestamp bits.
    pub(crate) query_pool: vk::QueryPool,
    /// Nanoseconds per timestamp tick.
    pub(crate) timestamp_period: f32,
    /// Mask of the valid timestamp bits.
    pub(crate) timestamp_mask: u64,
    /// `minAccelerationStructureScratchOffsetAlignment` (hardware traversal).
    pub(crate) hardware_scratch_alignment: u32,
    pub(crate) poisoned: bool,
    /// A failure the next submission reports instead of submitting ([`Self::inject_fault`]).
    pub(crate) injected_fault: Option<vk::Result>,
}

impl Device {
    /// The queue `family`'s first queue on `shared`'s device, a resettable command buffer, a fence
    /// and, where the family has `timestamp_bits`, a timestamp pool.
    pub(crate) fn new(
        shared: Arc<Shared>,
        info: DeviceInfo,
        family: u32,
        timestamp_bits: u32,
    ) -> Result<Self> {
        let limits = crate::limits::query_limits(&shared);
        let pd = shared.physical_device;
        let hardware_scratch_alignment = crate::traversal::scratch_alignment(&shared.instance, pd);
        // SAFETY: `pd` belongs to the instance.
        let props = unsafe { shared.instance.instance.get_physical_device_properties(pd) };
        let mut device = Self {
            shared,
            info,
            limits,
            queue: vk::Queue::null(),
            queue_family: family,
            command_pool: vk::CommandPool::null(),
            command_buffer: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            query_pool: vk::QueryPool::null(),
            timestamp_period: props.limits.timestamp_period,
            timestamp_mask: if timestamp_bits >= 64 {
                u64::MAX
            } else {
                (1u64 << timestamp_bits) - 1
            },
            hardware_scratch_alignment,
            poisoned: false,
            injected_fault: None,
        };
        let d = &device.shared.device;
        // SAFETY: (whole block) every create call gets a valid create info whose pointers live until
        // the call returns; the handles are stored in `device` at once, so its Drop destroys them.
        unsafe {
            device.queue = d.get_device_queue(family, 0);
            device.command_pool = d
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .during("vkCreateCommandPool")?;
            device.command_buffer = d
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(device.command_pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
                .during("vkAllocateCommandBuffers")?[0];
            device.fence = d
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .during("vkCreateFence")?;
            if timestamp_bits > 0 {
                device.query_pool = d
                    .create_query_pool(
                        &vk::QueryPoolCreateInfo::default()
                            .query_type(vk::QueryType::TIMESTAMP)
                            .query_count(crate::timestamps::QUERIES),
                        None,
                    )
                    .during("vkCreateQueryPool")?;
            }
        }
        Ok(device)
    }

    /// The chosen device.
    #[must_use]
    pub fn device_info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The device's name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    #[must_use]
    pub fn device_name(&self) -> &str {
        &self.info.name
    }

    /// The device's name and its driver, e.g.
    /// "llvmpipe (LLVM 15.0.6, 256 bits); llvmpipe, Mesa 25.0.7 (LLVM 15.0.6)": what reports print,
    /// since lavapipe's speed depends on the Mesa version more than on the device.
    #[must_use]
    pub fn device_description(&self) -> String {
        self.info.description()
    }

    /// Whether frame times come from GPU timestamps (else wall time around the submissions).
    #[must_use]
    pub fn has_timestamps(&self) -> bool {
        self.query_pool != vk::QueryPool::null()
    }

    /// A snapshot of every warning and error the validation layer reported so far (empty without
    /// validation).
    #[must_use]
    pub fn validation_messages(&self) -> Vec<String> {
        self.shared
            .instance
            .log
            .lock()
            .map(|l| l.clone())
            .unwrap_or_default()
    }

    /// The live message list; it stays readable after the context is dropped (messages about leaked
    /// objects arrive during destruction).
    #[must_use]
    pub fn validation_log(&self) -> MessageLog {
        self.shared.instance.log.clone()
    }

    /// Fault injection for tests: the next submission fails with `fault` (e.g.
    /// `vk::Result::ERROR_DEVICE_LOST` or `ERROR_OUT_OF_DEVICE_MEMORY`) as if the driver had returned it,
    /// so the error paths that a real device loss takes can be tested on any device.
    #[doc(hidden)]
    pub fn inject_fault(&mut self, fault: vk::Result) {
        self.injected_fault = Some(fault);
    }

    /// Fails if an earlier device loss or timeout left the device in an unknown state.
    pub(crate) fn check_usable(&self) -> Result<()> {
        if self.poisoned {
            Err(VulkanError::Poisoned)
        } else {
            Ok(())
        }
    }

    /// Marks the context unusable after a fatal error and passes the error on.
    pub(crate) fn poison_on_fatal(&mut self, e: VulkanError) -> VulkanError {
        if e.is_fatal() {
            self.poisoned = true;
        }
        e
    }

    /// Records commands with `record`, submits them and waits up to `timeout`.
    pub(crate) fn submit_and_wait(
        &mut self,
        what: &'static str,
        timeout: Duration,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<()> {
        self.submit_and_wait_with(what, timeout, None, None, record)
    }

    /// [`Self::submit_and_wait`] whose submission first waits for `wait` (a semaphore, at a stage) and
    /// signals `signal` when done (the swapchain's acquire and present semaphores).
    pub(crate) fn submit_and_wait_with(
        &mut self,
        what: &'static str,
        timeout: Duration,
        wait: Option<(vk::Semaphore, vk::PipelineStageFlags)>,
        signal: Option<vk::Semaphore>,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<()> {
        self.check_usable()?;
        let device = &self.shared.device;
        let cb = self.command_buffer;
        // SAFETY: the command buffer is not in use (every submission is waited on before the next), and
        // the fence is unsignalled (reset after each wait).
        let result = unsafe {
            device
                .reset_command_buffer(cb, vk::CommandBufferResetFlags::empty())
                .during("vkResetCommandBuffer")
                .and_then(|()| {
                    device
                        .begin_command_buffer(
                            cb,
                            &vk::CommandBufferBeginInfo::default()
                                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                        )
                        .during("vkBeginCommandBuffer")
                })
                .and_then(|()| {
                    record(device, cb);
                    device.end_command_buffer(cb).during("vkEndCommandBuffer")
                })
                .and_then(|()| match self.injected_fault.take() {
                    Some(fault) => Err(VulkanError::vk("vkQueueSubmit (injected fault)", fault)),
                    None => Ok(()),
                })
                .and_then(|()| {
                    let cbs = [cb];
                    let wait_semaphores: Vec<vk::Semaphore> = wait.iter().map(|w| w.0).collect();
                    let wait_stages: Vec<vk::PipelineStageFlags> =
                        wait.iter().map(|w| w.1).collect();
                    let signal_semaphores: Vec<vk::Semaphore> = signal.into_iter().collect();
                    let submit = [vk::SubmitInfo::default()
                        .command_buffers(&cbs)
                        .wait_semaphores(&wait_semaphores)
                        .wait_dst_stage_mask(&wait_stages)
                        .signal_semaphores(&signal_semaphores)];
                    device
                        .queue_submit(self.queue, &submit, self.fence)
                        .during("vkQueueSubmit")
                })
                .and_then(|()| {
                    let nanos = u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX);
                    match device.wait_for_fences(&[self.fence], true, nanos) {
                        Ok(()) => Ok(()),
                        Err(vk::Result::TIMEOUT) => Err(VulkanError::Timeout {
                            what,
                            seconds: timeout.as_secs(),
                        }),
                        Err(r) => Err(VulkanError::vk("vkWaitForFences", r)),
                    }
                })
                .and_then(|()| device.reset_fences(&[self.fence]).during("vkResetFences"))
        };
        result.map_err(|e| self.poison_on_fatal(e))
    }

    /// A new device-local storage buffer of `size` bytes (with `extra_usage` besides) holding each
    /// `(offset, bytes)` part at its offset and zeros elsewhere, written straight into a staging buffer.
    pub(crate) fn upload(
        &mut self,
        what: &str,
        parts: &[(u64, &[u8])],
        size: u64,
        extra_usage: vk::BufferUsageFlags,
    ) -> Result<GpuBuffer> {
        let end = parts
            .iter()
            .map(|(offset, bytes)| offset + bytes.len() as u64)
            .max()
            .unwrap_or(0);
        let dst = GpuBuffer::new(
            &self.shared,
            what,
            size.max(end),
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | extra_usage,
            MemoryLocation::GpuOnly,
        )?;
        let mut staging = GpuBuffer::new(
            &self.shared,
            "staging",
            dst.size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.write_parts(parts)?;
        let (src_buf, dst_buf, n) = (staging.buffer, dst.buffer, dst.size);
        self.submit_and_wait("a scene upload", CHUNK_TIMEOUT, |device, cb| {
            let region = [vk::BufferCopy::default().size(n)];
            // SAFETY: both buffers are at least `n` bytes and alive until the wait returns.
            unsafe { device.cmd_copy_buffer(cb, src_buf, dst_buf, &region) };
        })?;
        Ok(dst)
    }

    /// Checks a buffer of `bytes` that is bound as a storage buffer against the device limits
    /// (`maxStorageBufferRange`, `maxMemoryAllocationSize`); the error names the limit.
    pub fn check_size(&self, what: &str, bytes: u64) -> Result<()> {
        self.limits.check_size(what, bytes)
    }

    /// Checks a buffer of `bytes` against `maxMemoryAllocationSize`; the error names the limit.
    pub fn check_allocation(&self, what: &str, bytes: u64) -> Result<()> {
        self.limits.check_allocation(what, bytes)
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        let device = &self.shared.device;
        // SAFETY: waiting for the device first makes the objects below unused; null handles (a
        // half-built device) are skipped by the Vulkan destroy functions.
        unsafe {
            let _ = device.device_wait_idle();
            device.destroy_query_pool(self.query_pool, None);
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.command_pool, None);
        }
    }
}
