//! [`GpuScene`]: the arrays of a `PackedScene` as device-local buffers, uploaded once per scene.
use std::sync::Arc;

use ash::vk;
use fovea_core::kernel_abi::{
    BINDING_GLOBALS, BINDING_HARDWARE_TRAVERSAL, BINDING_MATERIALS, BINDING_NODES, BINDING_NORMALS,
    BINDING_TEXELS, BINDING_TEXTURES, BINDING_TRIANGLE_BLOCKS, BINDING_TRIANGLE_INFO,
    BINDING_TRIANGLE_LANES, BINDING_TRIANGLE_LIGHT, BINDING_UVS, BINDING_VERTEX_COLORS,
};
use fovea_core::scene::{FeatureFlags, SceneGlobals, TexelOffsets, INVALID_INDEX};
use fovea_scene::pack::{ArrayRead, PackedScene};

use crate::buffer::GpuBuffer;
use crate::context::VulkanContext;
use crate::error::{Result, VkContext, VulkanError};
use crate::instance::Shared;

/// Descriptor range of an empty array: 4 bytes, so the kernel's `OpArrayLength` is 0 for every element type
/// of 8 bytes or more (an empty array must look empty: core tests `normals.is_empty()`, `uvs.is_empty()`,
/// `nodes.is_empty()`). Buffers themselves are at least 16 bytes.
const EMPTY_RANGE: u64 = 4;

/// Where one binding of the scene points: `buffers[buffer]`, from `offset`, over `range` bytes.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct BufferRange {
    buffer: usize,
    offset: u64,
    range: u64,
}

/// A packed scene on the device.
///
/// The arrays core reads through `SceneSource` (BVH nodes, triangles, triangle info, normals, texture
/// coordinates, materials, texture infos, texels) share one buffer, each from an offset aligned for
/// storage-buffer bindings: the kernel reads it whole as a storage texel buffer
/// ([`fovea_core::scene::source`], binding `BINDING_SCENE_TEXELS`), and the arrays' own bindings bind
/// their parts as storage buffers (the kernel still reads their lengths). Every other array has a
/// buffer of its own.
pub struct GpuScene {
    pub(crate) buffers: Vec<GpuBuffer>,
    /// Where each scene binding points: `(binding, range)`.
    bindings: Vec<(u32, BufferRange)>,
    /// The scene texel buffer as `R32G32B32A32_UINT` texels.
    texel_view: TexelView,
    /// Bytes uploaded.
    pub bytes: u64,
    /// The features `render_samples` is specialised for when rendering this scene: the scene's own
    /// (`PackedScene::features`) after upload; set [`FeatureFlags::ALL`] for the general kernel.
    pub features: FeatureFlags,
    /// The acceleration structures, on a context with hardware traversal.
    pub hardware: Option<crate::hardware::HardwareScene>,
}

/// A buffer view, destroyed on drop.
struct TexelView {
    shared: Arc<Shared>,
    view: vk::BufferView,
}

impl Drop for TexelView {
    fn drop(&mut self) {
        // SAFETY: the host waits for all GPU work before it drops a scene (see `GpuBuffer`'s Drop).
        unsafe { self.shared.device.destroy_buffer_view(self.view, None) };
    }
}

/// `value` rounded up to a multiple of `align` (a power of two).
fn align_up(value: u64, align: u64) -> u64 {
    value.div_ceil(align) * align
}

impl GpuScene {
    /// An error unless this scene's buffers live on the device of `shared` (a scene uploaded to one
    /// context cannot be bound in another).
    pub(crate) fn check_uploaded_to(&self, shared: &Arc<Shared>) -> Result<()> {
        if !self.buffers.iter().all(|b| b.same_device(shared)) {
            return Err(VulkanError::Invalid(
                "the scene was uploaded to another Vulkan context".into(),
            ));
        }
        Ok(())
    }

    /// The storage-buffer descriptors of the scene's bindings, `(binding, info)`.
    pub(crate) fn buffer_infos(&self) -> Vec<(u32, vk::DescriptorBufferInfo)> {
        self.bindings
            .iter()
            .map(|(b, r)| {
                let info = match (&self.hardware, *b == BINDING_HARDWARE_TRAVERSAL) {
                    (Some(h), true) => vk::DescriptorBufferInfo::default()
                        .buffer(h.map.buffer)
                        .offset(0)
                        .range(vk::WHOLE_SIZE),
                    _ => vk::DescriptorBufferInfo::default()
                        .buffer(self.buffers[r.buffer].buffer)
                        .offset(r.offset)
                        .range(r.range),
                };
                (*b, info)
            })
            .collect()
    }

    /// The scene texel buffer's view (binding `BINDING_SCENE_TEXELS`).
    pub(crate) fn texel_view(&self) -> vk::BufferView {
        self.texel_view.view
    }

    /// Uploads `packed` to `ctx`'s device. Every array must fit `maxStorageBufferRange` and
    /// `maxMemoryAllocationSize`, the scene texel buffer `maxTexelBufferElements` and
    /// `maxMemoryAllocationSize`, and all of them the largest device-local heap.
    ///
    /// An empty `triangle_light` of a scene with triangles is uploaded as `INVALID_INDEX` for every
    /// triangle (a 4-byte element cannot be made to look empty; "no triangle is a light" reads the same).
    ///
    /// Long because uploading is one sequence of buffer creations (each checked against the device's
    /// limits) followed by one staging copy.
    pub fn upload(ctx: &mut VulkanContext, packed: &PackedScene) -> Result<Self> {
        ctx.device.check_usable()?;
        let triangle_light: Vec<u32> =
            if packed.lights.triangle_light.is_empty() && packed.triangle_count() > 0 {
                vec![INVALID_INDEX; packed.triangle_count()]
            } else {
                packed.lights.triangle_light.clone()
            };

        // The scene texel buffer: the arrays core reads through `SceneSource`, each from an offset that
        // suits both a storage-buffer binding and a texel index (nodes first, at texel 0).
        let arrays = packed.gpu_arrays();
        let sourced: Vec<(u32, &str, &[u8])> = arrays
            .iter()
            .filter(|a| a.read == ArrayRead::Texels)
            .map(|a| (a.binding, a.name, a.bytes))
            .collect();
        debug_assert_eq!(sourced.first().map(|a| a.0), Some(BINDING_NODES));
        let align = ctx
            .device
            .limits
            .min_storage_buffer_offset_alignment
            .max(16);
        let mut offsets = vec![0u64; sourced.len()];
        let mut texels_size = 0u64;
        for (k, (_, what, data)) in sourced.iter().enumerate() {
            ctx.check_size(what, data.len() as u64)?;
            offsets[k] = align_up(texels_size, align);
            // Every array, even an empty one, gets 16 bytes, so its binding lies inside the buffer.
            texels_size = offsets[k] + (data.len() as u64).max(16);
        }
        // Whole texels: the last array may end inside one (the view would then cut off its tail, which
        // reads as zeros; the last texture's 1 × 1 mip level was lost that way).
        let texels_size = align_up(texels_size, 16);
        let texel_count = texels_size / 16;
        if texel_count > ctx.device.limits.max_texel_buffer_elements {
            return Err(VulkanError::TooLarge {
                what: "the scene's BVH, triangles, materials, vertex attributes and textures"
                    .into(),
                bytes: texels_size,
                limit_name: "maxTexelBufferElements (16-byte texels)",
                limit: ctx.device.limits.max_texel_buffer_elements * 16,
            });
        }
        ctx.device
            .check_allocation("the scene texel buffer", texels_size)?;
        // The first texel of the array bound at `binding`.
        let texel_offset = |binding: u32| {
            let k = sourced.iter().position(|(b, ..)| *b == binding);
            k.map_or(0, |k| (offsets[k] / 16) as u32)
        };

        let globals = [SceneGlobals {
            texel_offsets: TexelOffsets {
                blocks: texel_offset(BINDING_TRIANGLE_BLOCKS),
                triangle_lanes: texel_offset(BINDING_TRIANGLE_LANES),
                triangle_info: texel_offset(BINDING_TRIANGLE_INFO),
                normals: texel_offset(BINDING_NORMALS),
                uvs: texel_offset(BINDING_UVS),
                materials: texel_offset(BINDING_MATERIALS),
                textures: texel_offset(BINDING_TEXTURES),
                texels: texel_offset(BINDING_TEXELS),
                vertex_colors: texel_offset(BINDING_VERTEX_COLORS),
                _pad: [0; 3],
            },
            ..packed.globals
        }];
        // The other bindings, with buffers of their own.
        let mut own: Vec<(u32, &str, &[u8])> = vec![(
            BINDING_GLOBALS,
            "scene globals",
            bytemuck::cast_slice(&globals),
        )];
        own.extend(arrays.iter().filter(|a| a.read == ArrayRead::Storage).map(
            |a| match a.binding {
                BINDING_TRIANGLE_LIGHT => {
                    (a.binding, a.name, bytemuck::cast_slice(&triangle_light))
                }
                _ => (a.binding, a.name, a.bytes),
            },
        ));
        let mut total = texels_size;
        for (_, what, data) in &own {
            ctx.check_size(what, data.len() as u64)?;
            total += (data.len() as u64).max(16);
        }
        if total > ctx.device.limits.device_local_heap {
            return Err(VulkanError::TooLarge {
                what: "the scene".into(),
                bytes: total,
                limit_name: "device-local heap size",
                limit: ctx.device.limits.device_local_heap,
            });
        }

        // An empty array is bound over `EMPTY_RANGE` bytes, so that it looks empty to the kernel.
        let range_of = |len: usize| if len == 0 { EMPTY_RANGE } else { len as u64 };
        let parts: Vec<(u64, &[u8])> = sourced
            .iter()
            .zip(offsets.iter().copied())
            .map(|((_, _, data), offset)| (offset, *data))
            .collect();
        let mut buffers = vec![ctx.device.upload(
            "the scene texel buffer",
            &parts,
            texels_size,
            vk::BufferUsageFlags::STORAGE_TEXEL_BUFFER,
        )?];
        let mut bindings = Vec::with_capacity(sourced.len() + own.len() + 1);
        for (k, (binding, _, data)) in sourced.iter().enumerate() {
            let range = BufferRange {
                buffer: 0,
                offset: offsets[k],
                range: range_of(data.len()),
            };
            bindings.push((*binding, range));
        }
        for (binding, what, data) in &own {
            let range = BufferRange {
                buffer: buffers.len(),
                offset: 0,
                range: range_of(data.len()),
            };
            bindings.push((*binding, range));
            let size = (data.len() as u64).max(16);
            buffers.push(ctx.device.upload(
                what,
                &[(0, data)],
                size,
                vk::BufferUsageFlags::empty(),
            )?);
        }

        // Hardware traversal's map (the ray-query module reads it); the software module does not read
        // the binding, which then points at the globals.
        let hardware = if ctx.kernel.hardware_traversal {
            Some(crate::hardware::HardwareScene::build(
                &mut ctx.device,
                packed,
            )?)
        } else {
            None
        };
        let globals_range = bindings
            .iter()
            .find(|(b, _)| *b == BINDING_GLOBALS)
            .map(|(_, r)| *r)
            .expect("the globals are bound");
        bindings.push((BINDING_HARDWARE_TRAVERSAL, globals_range));

        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffers[0].buffer)
            .format(vk::Format::R32G32B32A32_UINT)
            .offset(0)
            .range(texel_count * 16);
        // SAFETY: the buffer was created with STORAGE_TEXEL_BUFFER usage and is `texel_count * 16` bytes
        // long, within maxTexelBufferElements (checked above).
        let view = unsafe { ctx.device.shared.device.create_buffer_view(&info, None) }
            .during("vkCreateBufferView")?;
        Ok(Self {
            buffers,
            bindings,
            texel_view: TexelView {
                shared: ctx.device.shared.clone(),
                view,
            },
            bytes: total,
            features: packed.features(),
            hardware,
        })
    }
}
