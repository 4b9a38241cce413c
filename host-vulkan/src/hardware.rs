//! Hardware traversal (`--traversal hardware`): the driver's acceleration structures over the packed
//! scene's triangles, which the ray-query kernel module traverses (core's `bvh::hardware`).
//!
//! One bottom-level structure per scene, built from the same packed triangles the software BVH holds
//! (`PackedScene::triangle`, vertices in the triangle's own order), in two geometries: the triangles of
//! opaque materials (flagged `OPAQUE`: the hardware commits their hits without asking the kernel) and
//! those whose material has an alpha cut-out (not opaque: each candidate goes back to core's alpha test).
//! It is built for fast tracing, then compacted. A top-level structure holds one instance of it with the
//! identity transform. The kernel finds both through one storage buffer
//! ([`fovea_core::kernel_abi::BINDING_HARDWARE_TRAVERSAL`]): the top-level structure's device address,
//! the number of opaque triangles, and for each triangle of the structure (opaque ones first) the scene
//! triangle it is.
use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use gpu_allocator::MemoryLocation;

use fovea_core::scene::MATERIAL_ALPHA_CUTOUT;
use fovea_scene::pack::PackedScene;

use crate::buffer::GpuBuffer;
use crate::context::CHUNK_TIMEOUT;
use crate::device::Device;
use crate::error::{Result, VkContext};
use crate::instance::Shared;

/// Words before the triangle map in the hardware-traversal buffer (core's `HARDWARE_HEADER_WORDS`).
const HEADER_WORDS: usize = 4;

/// What the acceleration structures cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HardwareStats {
    /// Host wall time of the whole build: inputs, bottom level, compaction, top level.
    pub build_ms: f64,
    /// The bottom-level structure before and after compaction.
    pub blas_bytes_uncompacted: u64,
    pub blas_bytes: u64,
    pub tlas_bytes: u64,
    /// The buffer the kernel reads (header and triangle map).
    pub map_bytes: u64,
    pub opaque_triangles: u64,
    pub cutout_triangles: u64,
}

/// An acceleration structure with its buffer.
struct Accel {
    handle: vk::AccelerationStructureKHR,
    /// The storage the structure lives in (kept alive with it).
    _buffer: GpuBuffer,
}

/// A scene's acceleration structures and the kernel's map buffer, destroyed with the scene.
pub struct HardwareScene {
    shared: Arc<Shared>,
    loader: ash::khr::acceleration_structure::Device,
    blas: Option<Accel>,
    tlas: Option<Accel>,
    /// Header and triangle map (binding `BINDING_HARDWARE_TRAVERSAL`).
    pub(crate) map: GpuBuffer,
    pub stats: HardwareStats,
}

impl Drop for HardwareScene {
    fn drop(&mut self) {
        // SAFETY: the host waits for all GPU work before it drops a scene; the structures' buffers are
        // freed after them (fields drop after this body).
        unsafe {
            for a in [self.tlas.take(), self.blas.take()].into_iter().flatten() {
                self.loader.destroy_acceleration_structure(a.handle, None);
            }
        }
        let _ = &self.shared;
    }
}

/// Whether a material index names a cut-out material.
fn is_cutout(packed: &PackedScene, material: u32) -> bool {
    packed
        .materials
        .list
        .get(material as usize)
        .is_some_and(|m| m.flags & MATERIAL_ALPHA_CUTOUT != 0)
}

/// The BLAS inputs: vertices (three per triangle, opaque triangles first) and the scene triangle of each.
fn triangle_order(packed: &PackedScene) -> (Vec<[f32; 3]>, Vec<u32>, u64) {
    let n = packed.triangle_count();
    let mut opaque: Vec<u32> = Vec::with_capacity(n);
    let mut cutout: Vec<u32> = Vec::new();
    for t in 0..n {
        if is_cutout(packed, packed.geometry.triangle_info[t].material) {
            cutout.push(t as u32);
        } else {
            opaque.push(t as u32);
        }
    }
    let n_opaque = opaque.len() as u64;
    opaque.extend(cutout);
    let mut vertices = Vec::with_capacity(3 * n);
    for &t in &opaque {
        let p = packed.triangle(t as usize);
        for v in [p.v0, p.v1, p.v2] {
            vertices.push([v.x, v.y, v.z]);
        }
    }
    (vertices, opaque, n_opaque)
}

impl GpuBuffer {
    /// The buffer's device address (it must have `SHADER_DEVICE_ADDRESS` usage).
    pub(crate) fn device_address(&self, shared: &Shared) -> vk::DeviceAddress {
        // SAFETY: valid buffer of this device, created with SHADER_DEVICE_ADDRESS usage.
        unsafe {
            shared.device.get_buffer_device_address(
                &vk::BufferDeviceAddressInfo::default().buffer(self.buffer),
            )
        }
    }
}

/// A memory barrier between acceleration-structure builds (and copies) and what reads them next.
fn build_barrier(device: &ash::Device, cb: vk::CommandBuffer, dst_stage: vk::PipelineStageFlags) {
    crate::barrier::memory_barrier(
        device,
        cb,
        (
            vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
            vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR,
        ),
        (dst_stage, vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR),
    );
}

/// A buffer for an acceleration structure of `size` bytes and the structure in it.
fn create_accel(
    device: &Device,
    loader: &ash::khr::acceleration_structure::Device,
    what: &str,
    ty: vk::AccelerationStructureTypeKHR,
    size: u64,
) -> Result<Accel> {
    device.check_allocation(what, size)?;
    let buffer = GpuBuffer::new(
        &device.shared,
        what,
        size,
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
    )?;
    let info = vk::AccelerationStructureCreateInfoKHR::default()
        .buffer(buffer.buffer)
        .offset(0)
        .size(size)
        .ty(ty);
    // SAFETY: the buffer has ACCELERATION_STRUCTURE_STORAGE usage and `size` bytes at offset 0.
    let handle = unsafe { loader.create_acceleration_structure(&info, None) }
        .during("vkCreateAccelerationStructureKHR")?;
    Ok(Accel {
        handle,
        _buffer: buffer,
    })
}

/// A scratch buffer of at least `size` bytes and its address, aligned as the device requires.
fn scratch(device: &Device, size: u64) -> Result<(GpuBuffer, vk::DeviceAddress)> {
    let align = u64::from(device.hardware_scratch_alignment.max(1));
    let buffer = GpuBuffer::new(
        &device.shared,
        "acceleration-structure scratch",
        size + align,
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
    )?;
    let address = buffer.device_address(&device.shared).div_ceil(align) * align;
    Ok((buffer, address))
}

/// Sizes the build `info` (with `counts` primitives per geometry), creates its destination (guarded)
/// and scratch buffer, and points `info` at them; returns those and the structure's size in bytes.
fn prepare_build<'l, 'g>(
    device: &Device,
    loader: &'l ash::khr::acceleration_structure::Device,
    info: vk::AccelerationStructureBuildGeometryInfoKHR<'g>,
    counts: &[u32],
    what: &str,
) -> Result<(
    AccelGuard<'l>,
    GpuBuffer,
    vk::AccelerationStructureBuildGeometryInfoKHR<'g>,
    u64,
)> {
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: valid build info whose geometry count matches `counts`.
    unsafe {
        loader.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            counts,
            &mut sizes,
        )
    };
    let size = sizes.acceleration_structure_size.max(256);
    let accel = AccelGuard::new(loader, create_accel(device, loader, what, info.ty, size)?);
    let (scratch, scratch_address) = scratch(device, sizes.build_scratch_size)?;
    let info = info
        .dst_acceleration_structure(accel.handle())
        .scratch_data(vk::DeviceOrHostAddressKHR {
            device_address: scratch_address,
        });
    Ok((accel, scratch, info, sizes.acceleration_structure_size))
}

impl HardwareScene {
    /// Builds the acceleration structures of `packed` (see the module documentation).
    ///
    /// Long because building the acceleration structures is one sequence of dependent Vulkan calls
    /// (geometry buffers, sizes, the bottom-level build, the instance, the top-level build, one
    /// submission).
    pub(crate) fn build(device: &mut Device, packed: &PackedScene) -> Result<Self> {
        let start = Instant::now();
        let loader = ash::khr::acceleration_structure::Device::new(
            &device.shared.instance.instance,
            &device.shared.device,
        );
        let (vertices, order, n_opaque) = triangle_order(packed);
        let n = order.len() as u64;
        let n_cutout = n - n_opaque;
        let input_usage = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let mut stats = HardwareStats {
            opaque_triangles: n_opaque,
            cutout_triangles: n_cutout,
            ..HardwareStats::default()
        };

        // The bottom level: one geometry per kind of triangle that occurs.
        let blas = if n == 0 {
            None
        } else {
            let vertex_bytes: &[u8] = bytemuck::cast_slice(&vertices);
            let vertex_buffer = device.upload(
                "acceleration-structure vertices",
                &[(0, vertex_bytes)],
                vertex_bytes.len() as u64,
                input_usage,
            )?;
            let base = vertex_buffer.device_address(&device.shared);
            let stride = 12u64;
            let geometry = |first: u64, count: u64, opaque: bool| {
                let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
                    .vertex_format(vk::Format::R32G32B32_SFLOAT)
                    .vertex_stride(stride)
                    .vertex_data(vk::DeviceOrHostAddressConstKHR {
                        device_address: base + first * 3 * stride,
                    })
                    .max_vertex((count * 3).saturating_sub(1) as u32)
                    .index_type(vk::IndexType::NONE_KHR);
                let flags = if opaque {
                    vk::GeometryFlagsKHR::OPAQUE
                } else {
                    vk::GeometryFlagsKHR::empty()
                };
                (
                    vk::AccelerationStructureGeometryKHR::default()
                        .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
                        .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
                        .flags(flags),
                    vk::AccelerationStructureBuildRangeInfoKHR::default()
                        .primitive_count(count as u32),
                )
            };
            let mut geometries = Vec::new();
            let mut ranges = Vec::new();
            for (first, count, opaque) in [(0, n_opaque, true), (n_opaque, n_cutout, false)] {
                if count > 0 {
                    let (g, r) = geometry(first, count, opaque);
                    geometries.push(g);
                    ranges.push(r);
                }
            }
            let counts: Vec<u32> = ranges.iter().map(|r| r.primitive_count).collect();
            let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
                .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                .flags(
                    vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
                        | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION,
                )
                .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
                .geometries(&geometries);
            let (full, _scratch, info, full_size) = prepare_build(
                device,
                &loader,
                info,
                &counts,
                "bottom-level acceleration structure",
            )?;
            // SAFETY: valid device and create info; the pool is destroyed below.
            let pool = unsafe {
                device.shared.device.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                        .query_count(1),
                    None,
                )
            }
            .during("vkCreateQueryPool")?;
            let handle = full.handle();
            let loader_ref = &loader;
            let built = device.submit_and_wait(
                "the bottom-level acceleration structure build",
                CHUNK_TIMEOUT,
                |device, cb| {
                    // SAFETY: the build inputs, scratch and destination are alive until the wait
                    // returns; the barrier orders the build before the size query.
                    unsafe {
                        device.cmd_reset_query_pool(cb, pool, 0, 1);
                        loader_ref.cmd_build_acceleration_structures(cb, &[info], &[&ranges]);
                        build_barrier(
                            device,
                            cb,
                            vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                        );
                        loader_ref.cmd_write_acceleration_structures_properties(
                            cb,
                            &[handle],
                            vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                            pool,
                            0,
                        );
                    }
                },
            );
            let mut compacted = [0u64; 1];
            let read = built.and_then(|()| {
                // SAFETY: the query was written by the submission just waited on.
                unsafe {
                    device.shared.device.get_query_pool_results(
                        pool,
                        0,
                        &mut compacted,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )
                }
                .during("vkGetQueryPoolResults")
            });
            // SAFETY: nothing uses the pool any more.
            unsafe { device.shared.device.destroy_query_pool(pool, None) };
            read?;
            stats.blas_bytes_uncompacted = full_size;
            let size = compacted[0].clamp(1, full_size);
            let compact = create_accel(
                device,
                &loader,
                "compacted bottom-level acceleration structure",
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                size,
            )?;
            let compact = AccelGuard::new(&loader, compact);
            let copy = vk::CopyAccelerationStructureInfoKHR::default()
                .src(full.handle())
                .dst(compact.handle())
                .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
            device.submit_and_wait(
                "the acceleration structure compaction",
                CHUNK_TIMEOUT,
                |device, cb| {
                    // SAFETY: both structures are alive until the wait returns.
                    unsafe {
                        loader_ref.cmd_copy_acceleration_structure(cb, &copy);
                        build_barrier(
                            device,
                            cb,
                            vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                        );
                    }
                },
            )?;
            stats.blas_bytes = size;
            drop(full);
            Some(compact.into_inner())
        };

        // The top level: one instance of the bottom level (none for an empty scene).
        let blas_address = blas.as_ref().map_or(0, |b| {
            // SAFETY: a live bottom-level structure of this device.
            unsafe {
                loader.get_acceleration_structure_device_address(
                    &vk::AccelerationStructureDeviceAddressInfoKHR::default()
                        .acceleration_structure(b.handle),
                )
            }
        });
        let instance_bytes = instance_record(blas_address);
        let mut instances = GpuBuffer::new(
            &device.shared,
            "acceleration-structure instance",
            instance_bytes.len() as u64,
            input_usage,
            MemoryLocation::CpuToGpu,
        )?;
        instances.write(&instance_bytes)?;
        let instance_count = u32::from(blas.is_some());
        let instance_data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR {
                device_address: instances.device_address(&device.shared),
            });
        let geometries = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                instances: instance_data,
            })];
        let ranges = [
            vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(instance_count)
        ];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometries);
        let (tlas, _scratch, info, tlas_size) = prepare_build(
            device,
            &loader,
            info,
            &[instance_count],
            "top-level acceleration structure",
        )?;
        let loader_ref = &loader;
        device.submit_and_wait(
            "the top-level acceleration structure build",
            CHUNK_TIMEOUT,
            |device, cb| {
                // SAFETY: the instance buffer, scratch and destination are alive until the wait
                // returns; host writes to the instance buffer are visible at submission.
                unsafe {
                    loader_ref.cmd_build_acceleration_structures(cb, &[info], &[&ranges]);
                    build_barrier(device, cb, vk::PipelineStageFlags::COMPUTE_SHADER);
                }
            },
        )?;
        stats.tlas_bytes = tlas_size;
        // SAFETY: a live top-level structure of this device.
        let tlas_address = unsafe {
            loader.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default()
                    .acceleration_structure(tlas.handle()),
            )
        };

        let mut words = Vec::with_capacity(HEADER_WORDS + order.len());
        words.extend([
            tlas_address as u32,
            (tlas_address >> 32) as u32,
            n_opaque as u32,
            0,
        ]);
        words.extend_from_slice(&order);
        let map_bytes: &[u8] = bytemuck::cast_slice(&words);
        device.check_size(
            "the hardware-traversal triangle map",
            map_bytes.len() as u64,
        )?;
        let map = device.upload(
            "hardware-traversal triangle map",
            &[(0, map_bytes)],
            map_bytes.len() as u64,
            vk::BufferUsageFlags::empty(),
        )?;
        stats.map_bytes = map_bytes.len() as u64;
        stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(HardwareScene {
            shared: device.shared.clone(),
            blas,
            tlas: Some(tlas.into_inner()),
            loader,
            map,
            stats,
        })
    }
}

/// One `VkAccelerationStructureInstanceKHR` (64 bytes): identity transform, custom index 0, mask 0xFF,
/// no shader-binding offset, culling off (rays see both faces, as the software test does), the bottom
/// level at `blas_address`.
fn instance_record(blas_address: vk::DeviceAddress) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(64);
    let transform: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    for v in transform {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let mask_and_index: u32 = 0xFF << 24;
    bytes.extend_from_slice(&mask_and_index.to_le_bytes());
    let flags = vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw();
    let flags_and_offset: u32 = (flags & 0xFF) << 24;
    bytes.extend_from_slice(&flags_and_offset.to_le_bytes());
    bytes.extend_from_slice(&blas_address.to_le_bytes());
    bytes
}

/// Destroys an acceleration structure on an early return.
struct AccelGuard<'a> {
    loader: &'a ash::khr::acceleration_structure::Device,
    accel: Option<Accel>,
}

impl<'a> AccelGuard<'a> {
    fn new(loader: &'a ash::khr::acceleration_structure::Device, accel: Accel) -> Self {
        Self {
            loader,
            accel: Some(accel),
        }
    }

    fn handle(&self) -> vk::AccelerationStructureKHR {
        self.accel
            .as_ref()
            .map_or(vk::AccelerationStructureKHR::null(), |a| a.handle)
    }

    fn into_inner(mut self) -> Accel {
        self.accel.take().expect("the guard holds a structure")
    }
}

impl Drop for AccelGuard<'_> {
    fn drop(&mut self) {
        if let Some(a) = self.accel.take() {
            // SAFETY: every submission using it was waited on (or never made).
            unsafe { self.loader.destroy_acceleration_structure(a.handle, None) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_instance_record_has_vulkans_layout() {
        let r = instance_record(0x1234_5678_9abc_def0);
        assert_eq!(
            r.len(),
            std::mem::size_of::<vk::AccelerationStructureInstanceKHR>()
        );
        assert_eq!(&r[56..64], &0x1234_5678_9abc_def0u64.to_le_bytes());
        assert_eq!(r[51], 0xFF, "mask");
        assert_eq!(r[55], 1, "TRIANGLE_FACING_CULL_DISABLE");
    }
}
