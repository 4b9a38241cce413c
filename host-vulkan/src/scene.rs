//! [`GpuScene`]: the arrays of a `PackedScene` as device-local buffers, uploaded once per scene.
use std::sync::Arc;

use ash::vk;
use fovea_core::kernel_abi::{BINDING_NODES, BINDING_TRIANGLES};
use fovea_core::scene::{FeatureFlags, SceneGlobals, INVALID_INDEX};
use fovea_scene::pack::PackedScene;

use crate::buffer::GpuBuffer;
use crate::context::VulkanContext;
use crate::error::{Result, VkContext, VulkanError};
use crate::instance::Shared;

/// Number of scene bindings (`BINDING_GLOBALS` ..= `BINDING_ENVIRONMENT_CONDITIONAL`).
pub const SCENE_BINDINGS: usize = 15;

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
/// The BVH nodes and the triangle positions share one buffer (the nodes, then the triangles from an
/// offset aligned for storage-buffer bindings): traversal reads it whole as a storage texel buffer
/// ([`fovea_core::bvh::source`], binding `BINDING_GEOMETRY`), and `BINDING_NODES` and
/// `BINDING_TRIANGLES` bind its two parts as storage buffers for the rest of the kernel. Every other
/// array has a buffer of its own.
pub struct GpuScene {
    pub(crate) buffers: Vec<GpuBuffer>,
    /// Binding `b` (`BINDING_GLOBALS` ..= `BINDING_ENVIRONMENT_CONDITIONAL`) is `bindings[b]`.
    bindings: [BufferRange; SCENE_BINDINGS],
    /// The geometry buffer as `R32G32B32A32_UINT` texels.
    geometry_view: TexelView,
    /// Bytes uploaded.
    pub bytes: u64,
    /// The features `render_samples` is specialised for when rendering this scene: the scene's own
    /// (`PackedScene::features`) after upload; set [`FeatureFlags::ALL`] for the general kernel.
    pub features: FeatureFlags,
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
            .enumerate()
            .map(|(b, r)| {
                let info = vk::DescriptorBufferInfo::default()
                    .buffer(self.buffers[r.buffer].buffer)
                    .offset(r.offset)
                    .range(r.range);
                (b as u32, info)
            })
            .collect()
    }

    /// The geometry texel buffer's view (binding `BINDING_GEOMETRY`).
    pub(crate) fn geometry_view(&self) -> vk::BufferView {
        self.geometry_view.view
    }

    /// Uploads `packed` to `ctx`'s device. Every array must fit `maxStorageBufferRange` and
    /// `maxMemoryAllocationSize`, the geometry buffer `maxTexelBufferElements`, and all of them the
    /// largest device-local heap.
    ///
    /// An empty `triangle_light` of a scene with triangles is uploaded as `INVALID_INDEX` for every
    /// triangle (a 4-byte element cannot be made to look empty; "no triangle is a light" reads the same).
    pub fn upload(ctx: &mut VulkanContext, packed: &PackedScene) -> Result<Self> {
        ctx.check_usable()?;
        let triangle_light: Vec<u32> =
            if packed.triangle_light.is_empty() && !packed.triangles.is_empty() {
                vec![INVALID_INDEX; packed.triangles.len()]
            } else {
                packed.triangle_light.clone()
            };

        // The geometry buffer: nodes, then triangles from an offset that suits both a storage-buffer
        // binding and a texel index.
        let node_bytes: &[u8] = bytemuck::cast_slice(&packed.nodes);
        let triangle_bytes: &[u8] = bytemuck::cast_slice(&packed.triangles);
        let triangle_offset = align_up(
            node_bytes.len() as u64,
            ctx.limits.min_storage_buffer_offset_alignment.max(16),
        );
        let geometry_size = triangle_offset + (triangle_bytes.len() as u64).max(16);
        let texels = geometry_size / 16;
        if texels > ctx.limits.max_texel_buffer_elements {
            return Err(VulkanError::TooLarge {
                what: "the BVH and triangles (one texel buffer)".into(),
                bytes: geometry_size,
                limit_name: "maxTexelBufferElements (16-byte texels)",
                limit: ctx.limits.max_texel_buffer_elements * 16,
            });
        }
        let triangle_texels = u32::try_from(triangle_offset / 16)
            .map_err(|_| VulkanError::Invalid("the BVH is too large to index".into()))?;
        let mut geometry = vec![0u8; geometry_size as usize];
        geometry[..node_bytes.len()].copy_from_slice(node_bytes);
        geometry[triangle_offset as usize..][..triangle_bytes.len()]
            .copy_from_slice(triangle_bytes);

        let globals = [SceneGlobals {
            triangle_texels,
            ..packed.globals
        }];
        // Binding order (`BINDING_GLOBALS` ..); the geometry's two bindings are `None` here.
        let arrays: [(&str, Option<&[u8]>); SCENE_BINDINGS] = [
            ("scene globals", Some(bytemuck::cast_slice(&globals))),
            ("BVH nodes", None),
            ("triangles", None),
            (
                "triangle info",
                Some(bytemuck::cast_slice(&packed.triangle_info)),
            ),
            ("normals", Some(bytemuck::cast_slice(&packed.normals))),
            (
                "texture coordinates",
                Some(bytemuck::cast_slice(&packed.uvs)),
            ),
            ("materials", Some(bytemuck::cast_slice(&packed.materials))),
            (
                "texture infos",
                Some(bytemuck::cast_slice(&packed.textures)),
            ),
            ("texels", Some(bytemuck::cast_slice(&packed.texels))),
            ("lights", Some(bytemuck::cast_slice(&packed.lights))),
            ("light CDF", Some(bytemuck::cast_slice(&packed.light_cdf))),
            (
                "triangle lights",
                Some(bytemuck::cast_slice(&triangle_light)),
            ),
            (
                "environment texels",
                Some(bytemuck::cast_slice(&packed.environment_texels)),
            ),
            (
                "environment marginal CDF",
                Some(bytemuck::cast_slice(&packed.environment_marginal_cdf)),
            ),
            (
                "environment conditional CDF",
                Some(bytemuck::cast_slice(&packed.environment_conditional_cdf)),
            ),
        ];
        ctx.check_size("BVH nodes", node_bytes.len() as u64)?;
        ctx.check_size("triangles", triangle_bytes.len() as u64)?;
        ctx.check_size("the BVH and triangles (one buffer)", geometry_size)?;
        let mut total = geometry_size;
        for (what, data) in &arrays {
            if let Some(data) = data {
                ctx.check_size(what, data.len() as u64)?;
                total += (data.len() as u64).max(16);
            }
        }
        if total > ctx.limits.device_local_heap {
            return Err(VulkanError::TooLarge {
                what: "the scene".into(),
                bytes: total,
                limit_name: "device-local heap size",
                limit: ctx.limits.device_local_heap,
            });
        }

        // An empty array is bound over `EMPTY_RANGE` bytes, so that it looks empty to the kernel.
        let range_of = |len: usize| if len == 0 { EMPTY_RANGE } else { len as u64 };
        let mut buffers = vec![ctx.upload(
            "the BVH and triangles",
            &geometry,
            geometry_size,
            vk::BufferUsageFlags::STORAGE_TEXEL_BUFFER,
        )?];
        let mut bindings = [BufferRange::default(); SCENE_BINDINGS];
        bindings[BINDING_NODES as usize] = BufferRange {
            buffer: 0,
            offset: 0,
            range: range_of(node_bytes.len()),
        };
        bindings[BINDING_TRIANGLES as usize] = BufferRange {
            buffer: 0,
            offset: triangle_offset,
            range: range_of(triangle_bytes.len()),
        };
        for (b, (what, data)) in arrays.iter().enumerate() {
            if let Some(data) = data {
                bindings[b] = BufferRange {
                    buffer: buffers.len(),
                    offset: 0,
                    range: range_of(data.len()),
                };
                let size = (data.len() as u64).max(16);
                buffers.push(ctx.upload(what, data, size, vk::BufferUsageFlags::empty())?);
            }
        }

        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffers[0].buffer)
            .format(vk::Format::R32G32B32A32_UINT)
            .offset(0)
            .range(texels * 16);
        // SAFETY: the buffer was created with STORAGE_TEXEL_BUFFER usage and is `texels * 16` bytes
        // long, within maxTexelBufferElements (checked above).
        let view = unsafe { ctx.shared.device.create_buffer_view(&info, None) }
            .during("vkCreateBufferView")?;
        Ok(Self {
            buffers,
            bindings,
            geometry_view: TexelView {
                shared: ctx.shared.clone(),
                view,
            },
            bytes: total,
            features: packed.features(),
        })
    }
}
