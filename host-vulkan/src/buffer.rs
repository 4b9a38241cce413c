//! Buffers with memory from gpu-allocator; each holds the shared device, so it can free itself.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::{AllocationError, MemoryLocation};

use crate::error::{Result, VkContext, VulkanError};
use crate::instance::Shared;

/// A `VkBuffer` bound to its own allocation.
pub(crate) struct GpuBuffer {
    shared: Arc<Shared>,
    pub buffer: vk::Buffer,
    allocation: Option<Allocation>,
    /// Size in bytes the buffer was created with.
    pub size: u64,
}

/// Maps an allocator failure for `what` to a host error.
fn allocation_error(e: AllocationError, what: &str, bytes: u64) -> VulkanError {
    match e {
        AllocationError::OutOfMemory => VulkanError::OutOfDeviceMemory {
            what: what.to_string(),
            bytes,
        },
        other => VulkanError::Allocator(format!("{what}: {other}")),
    }
}

impl GpuBuffer {
    /// Creates a buffer of `size` bytes (at least 16) in `location`.
    pub fn new(
        shared: &Arc<Shared>,
        what: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(16);
        let device = &shared.device;
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let buffer = unsafe { device.create_buffer(&info, None) }.map_err(|r| match r {
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                VulkanError::OutOfDeviceMemory {
                    what: what.to_string(),
                    bytes: size,
                }
            }
            other => VulkanError::vk("vkCreateBuffer", other),
        })?;
        // SAFETY: `buffer` was just created on this device.
        let requirements = unsafe { device.get_buffer_memory_requirements(buffer) };
        let allocation = shared
            .allocator
            .lock()
            .map_err(|_| VulkanError::Allocator("allocator lock poisoned".into()))?
            .allocate(&AllocationCreateDesc {
                name: what,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer is unused and unbound.
                unsafe { device.destroy_buffer(buffer, None) };
                return Err(allocation_error(e, what, size));
            }
        };
        let out = Self {
            shared: shared.clone(),
            buffer,
            allocation: Some(allocation),
            size,
        };
        let a = out.allocation.as_ref().expect("allocation was just set");
        // SAFETY: the allocation satisfies the buffer's requirements and is bound once; on failure `out`'s
        // Drop destroys the buffer and frees the allocation.
        unsafe { device.bind_buffer_memory(buffer, a.memory(), a.offset()) }
            .during("vkBindBufferMemory")?;
        Ok(out)
    }

    /// The mapped bytes (host-visible buffers only).
    fn mapped(&mut self) -> Result<&mut [u8]> {
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| VulkanError::Allocator("buffer is not host-visible".into()))
    }

    /// Copies `data` to the start of a host-visible buffer.
    pub fn write<T: bytemuck::Pod>(&mut self, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mapped = self.mapped()?;
        if bytes.len() > mapped.len() {
            return Err(VulkanError::Invalid(format!(
                "{} bytes do not fit a {}-byte buffer",
                bytes.len(),
                mapped.len()
            )));
        }
        mapped[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// Copies each `(offset, bytes)` part of a host-visible buffer to its offset and fills the bytes no
    /// part covers with zeros (each byte is written once: scene uploads are up to gigabytes).
    pub fn write_parts(&mut self, parts: &[(u64, &[u8])]) -> Result<()> {
        let mapped = self.mapped()?;
        let len = mapped.len();
        if let Some((offset, bytes)) = parts
            .iter()
            .find(|(offset, bytes)| offset.saturating_add(bytes.len() as u64) > len as u64)
        {
            return Err(VulkanError::Invalid(format!(
                "{} bytes at {offset} do not fit a {len}-byte buffer",
                bytes.len()
            )));
        }
        let mut sorted: Vec<&(u64, &[u8])> = parts.iter().collect();
        sorted.sort_by_key(|(offset, _)| *offset);
        // `covered`: bytes below it are written (zeroed or copied).
        let mut covered = 0;
        for (offset, bytes) in sorted {
            let start = *offset as usize;
            if start > covered {
                mapped[covered..start].fill(0);
            }
            mapped[start..][..bytes.len()].copy_from_slice(bytes);
            covered = covered.max(start + bytes.len());
        }
        mapped[covered..].fill(0);
        Ok(())
    }

    /// Reads `count` elements from the start of a host-visible buffer.
    pub fn read<T: bytemuck::Pod>(&mut self, count: usize) -> Result<Vec<T>> {
        let n = count * std::mem::size_of::<T>();
        let mapped = self.mapped()?;
        if n > mapped.len() {
            return Err(VulkanError::Invalid(format!(
                "cannot read {n} bytes from a {}-byte buffer",
                mapped.len()
            )));
        }
        // The mapping may not be aligned for T: copy bytes into a T vector.
        let mut out = vec![T::zeroed(); count];
        bytemuck::cast_slice_mut::<T, u8>(&mut out).copy_from_slice(&mapped[..n]);
        Ok(out)
    }

    /// Whether `other` is the same device's buffer (used to reject scenes of another context).
    pub fn same_device(&self, shared: &Arc<Shared>) -> bool {
        Arc::ptr_eq(&self.shared, shared)
    }
}

impl Drop for GpuBuffer {
    fn drop(&mut self) {
        // SAFETY: the host waits for all GPU work before it drops buffers (every submission is waited on,
        // and a context that timed out waits for the device in `Shared::drop` only after its buffers are
        // gone, which is the best that can be done after a hang).
        unsafe { self.shared.device.destroy_buffer(self.buffer, None) };
        if let Some(a) = self.allocation.take() {
            if let Ok(mut alloc) = self.shared.allocator.lock() {
                let _ = alloc.free(a);
            }
        }
    }
}
