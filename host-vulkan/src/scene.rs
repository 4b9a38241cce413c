//! [`GpuScene`]: the arrays of a `PackedScene` as device-local storage buffers, uploaded once per scene.
use fovea_core::scene::{FeatureFlags, INVALID_INDEX};
use fovea_scene::pack::PackedScene;

use crate::buffer::GpuBuffer;
use crate::context::VulkanContext;
use crate::error::{Result, VulkanError};

/// Number of scene bindings (`BINDING_GLOBALS` ..= `BINDING_ENVIRONMENT_CONDITIONAL`).
pub const SCENE_BINDINGS: usize = 15;

/// Descriptor range of an empty array: 4 bytes, so the kernel's `OpArrayLength` is 0 for every element type
/// of 8 bytes or more (an empty array must look empty: core tests `normals.is_empty()`, `uvs.is_empty()`,
/// `nodes.is_empty()`). Buffers themselves are at least 16 bytes.
const EMPTY_RANGE: u64 = 4;

/// A packed scene on the device. Binding `b` of the kernel ABI is `buffers[b]`, bound over `ranges[b]`
/// bytes.
pub struct GpuScene {
    pub(crate) buffers: Vec<GpuBuffer>,
    pub(crate) ranges: [u64; SCENE_BINDINGS],
    /// Bytes uploaded.
    pub bytes: u64,
    /// The features `render_samples` is specialised for when rendering this scene: the scene's own
    /// (`PackedScene::features`) after upload; set [`FeatureFlags::ALL`] for the general kernel.
    pub features: FeatureFlags,
}

impl GpuScene {
    /// An error unless this scene's buffers live on the device of `shared` (a scene uploaded to one
    /// context cannot be bound in another).
    pub(crate) fn check_uploaded_to(
        &self,
        shared: &std::sync::Arc<crate::instance::Shared>,
    ) -> Result<()> {
        if self.buffers.len() != SCENE_BINDINGS
            || !self.buffers.iter().all(|b| b.same_device(shared))
        {
            return Err(VulkanError::Invalid(
                "the scene was uploaded to another Vulkan context".into(),
            ));
        }
        Ok(())
    }

    /// Uploads `packed` to `ctx`'s device. Every array must fit `maxStorageBufferRange` and
    /// `maxMemoryAllocationSize`, and all of them the largest device-local heap.
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
        let globals = [packed.globals];
        let arrays: [(&str, &[u8]); SCENE_BINDINGS] = [
            ("scene globals", bytemuck::cast_slice(&globals)),
            ("BVH nodes", bytemuck::cast_slice(&packed.nodes)),
            ("triangles", bytemuck::cast_slice(&packed.triangles)),
            ("triangle info", bytemuck::cast_slice(&packed.triangle_info)),
            ("normals", bytemuck::cast_slice(&packed.normals)),
            ("texture coordinates", bytemuck::cast_slice(&packed.uvs)),
            ("materials", bytemuck::cast_slice(&packed.materials)),
            ("texture infos", bytemuck::cast_slice(&packed.textures)),
            ("texels", bytemuck::cast_slice(&packed.texels)),
            ("lights", bytemuck::cast_slice(&packed.lights)),
            ("light CDF", bytemuck::cast_slice(&packed.light_cdf)),
            ("triangle lights", bytemuck::cast_slice(&triangle_light)),
            (
                "environment texels",
                bytemuck::cast_slice(&packed.environment_texels),
            ),
            (
                "environment marginal CDF",
                bytemuck::cast_slice(&packed.environment_marginal_cdf),
            ),
            (
                "environment conditional CDF",
                bytemuck::cast_slice(&packed.environment_conditional_cdf),
            ),
        ];
        let mut total = 0u64;
        for (what, data) in &arrays {
            ctx.check_size(what, data.len() as u64)?;
            total += (data.len() as u64).max(16);
        }
        if total > ctx.limits.device_local_heap {
            return Err(VulkanError::TooLarge {
                what: "the scene".into(),
                bytes: total,
                limit_name: "device-local heap size",
                limit: ctx.limits.device_local_heap,
            });
        }
        let mut buffers = Vec::with_capacity(SCENE_BINDINGS);
        let mut ranges = [0u64; SCENE_BINDINGS];
        for (i, (what, data)) in arrays.iter().enumerate() {
            let size = (data.len() as u64).max(16);
            buffers.push(ctx.upload(what, data, size)?);
            ranges[i] = if data.is_empty() {
                EMPTY_RANGE
            } else {
                data.len() as u64
            };
        }
        Ok(Self {
            buffers,
            ranges,
            bytes: total,
            features: packed.features(),
        })
    }
}
