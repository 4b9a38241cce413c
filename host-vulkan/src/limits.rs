//! The device limits the host checks its buffers against, read once per context; a check that fails
//! names the limit.
use ash::vk;

use crate::error::{Result, VulkanError};
use crate::instance::Shared;

/// Device limits the host checks buffers against.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    pub max_storage_buffer_range: u64,
    pub min_storage_buffer_offset_alignment: u64,
    pub max_texel_buffer_elements: u64,
    pub max_workgroup_count_x: u32,
    pub max_memory_allocation_size: u64,
    /// Size of the largest device-local heap.
    pub device_local_heap: u64,
}

impl Limits {
    /// Checks a buffer of `bytes` that is bound as a storage buffer against `maxStorageBufferRange` and
    /// `maxMemoryAllocationSize`.
    pub fn check_size(&self, what: &str, bytes: u64) -> Result<()> {
        if bytes > self.max_storage_buffer_range {
            return Err(VulkanError::TooLarge {
                what: what.into(),
                bytes,
                limit_name: "maxStorageBufferRange",
                limit: self.max_storage_buffer_range,
            });
        }
        self.check_allocation(what, bytes)
    }

    /// Checks a buffer of `bytes` against `maxMemoryAllocationSize`.
    pub fn check_allocation(&self, what: &str, bytes: u64) -> Result<()> {
        if bytes > self.max_memory_allocation_size {
            return Err(VulkanError::TooLarge {
                what: what.into(),
                bytes,
                limit_name: "maxMemoryAllocationSize",
                limit: self.max_memory_allocation_size,
            });
        }
        Ok(())
    }
}

/// Reads the limits of the shared device.
pub(crate) fn query_limits(shared: &Shared) -> Limits {
    let instance = &shared.instance.instance;
    let pd = shared.physical_device;
    let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
    // SAFETY: valid physical device and property chain.
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let limits = props2.properties.limits;
    // SAFETY: as above.
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    let device_local_heap = heaps
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or_else(|| heaps.iter().map(|h| h.size).max().unwrap_or(0));
    Limits {
        max_storage_buffer_range: u64::from(limits.max_storage_buffer_range),
        min_storage_buffer_offset_alignment: limits.min_storage_buffer_offset_alignment.max(1),
        max_texel_buffer_elements: u64::from(limits.max_texel_buffer_elements),
        max_workgroup_count_x: limits.max_compute_work_group_count[0],
        max_memory_allocation_size: maintenance3.max_memory_allocation_size,
        device_local_heap,
    }
}
