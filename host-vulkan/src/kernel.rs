//! [`Kernel`]: the kernel's SPIR-V module on a device, its pipelines (one per entry point of core's
//! passes, each created when a frame first needs it, `render_samples` specialised per scene), the
//! descriptor set every dispatch binds, and which pipelines have run once (a driver compiles lazily).
use std::sync::Arc;

use ash::vk;

use fovea_core::kernel_abi::{
    KernelPushConstants, BINDING_BLOCKS, BINDING_COUNT, BINDING_SCENE_TEXELS,
    SPEC_CONSTANT_FEATURES,
};
use fovea_core::passes::{FramePass, KERNEL_ENTRY_COUNT};
use fovea_core::scene::features::FEATURES_ALL;

use crate::error::{Result, VkContext, VulkanError};
use crate::instance::Shared;
use crate::spirv::ENTRY_POINTS;

/// The index in [`Kernel::pipelines`] of `render_samples`, the one pipeline specialised per scene
/// ([`Kernel::specialize_render_pipeline`]).
pub(crate) const RENDER_SAMPLES: usize = FramePass::Samples.first_kernel_entry();

/// The kernel's module, layouts, descriptor set and pipelines on one device.
pub struct Kernel {
    shared: Arc<Shared>,
    pub(crate) set_layout: vk::DescriptorSetLayout,
    pub(crate) pipeline_layout: vk::PipelineLayout,
    /// One per kernel entry of core's passes ([`ENTRY_POINTS`], indexed by
    /// [`FramePass::kernel_entry_range`]), null until a frame first needs it
    /// ([`Self::ensure_pipelines`]): a render without history or denoiser never creates those passes'
    /// pipelines.
    pub(crate) pipelines: [vk::Pipeline; KERNEL_ENTRY_COUNT],
    /// The kernel module, kept for re-specialising `render_samples` per scene; null for a context
    /// that only presents host images.
    pub(crate) module: vk::ShaderModule,
    /// The feature mask `pipelines[RENDER_SAMPLES]` was (or, while it is null, will be) specialised for.
    pub(crate) render_features: u32,
    /// The pipelines of the `probe` and `probe_scene` entry points, created on first use
    /// (`crate::probe`).
    pub(crate) probe_pipelines: [vk::Pipeline; 2],
    pub(crate) descriptor_pool: vk::DescriptorPool,
    pub(crate) descriptor_set: vk::DescriptorSet,
    /// Host time of every `vkCreateComputePipelines` so far (lavapipe translates the module to NIR
    /// here; LLVM code generation waits for the first dispatch, see [`Self::warmed`]).
    pub pipeline_create_ms: f64,
    /// Which pipelines have been dispatched once (by the first frame that runs their pass, before its
    /// own dispatches, so that its `render_ms` excludes a driver's lazy shader compilation; frames that
    /// never run a pass never compile it).
    pub(crate) warmed: [bool; KERNEL_ENTRY_COUNT],
    /// Whether the module is the ray-query kernel (scenes get acceleration structures).
    pub(crate) hardware_traversal: bool,
}

impl Kernel {
    /// The descriptor set layout and set, the pipeline layout and, given the kernel's `code`, its
    /// module (a context that only presents has none); `hardware`: `code` is the ray-query module.
    pub(crate) fn new(shared: Arc<Shared>, code: Option<&[u32]>, hardware: bool) -> Result<Self> {
        let mut kernel = Self {
            shared,
            set_layout: vk::DescriptorSetLayout::null(),
            pipeline_layout: vk::PipelineLayout::null(),
            pipelines: [vk::Pipeline::null(); KERNEL_ENTRY_COUNT],
            module: vk::ShaderModule::null(),
            render_features: FEATURES_ALL,
            probe_pipelines: [vk::Pipeline::null(); 2],
            descriptor_pool: vk::DescriptorPool::null(),
            descriptor_set: vk::DescriptorSet::null(),
            pipeline_create_ms: 0.0,
            warmed: [false; KERNEL_ENTRY_COUNT],
            hardware_traversal: hardware,
        };
        let device = &kernel.shared.device;
        // SAFETY: (whole block) every create call gets a valid create info whose pointers live until
        // the call returns; the handles are stored in `kernel` at once, so its Drop destroys them.
        unsafe {
            let bindings: Vec<vk::DescriptorSetLayoutBinding> = (0..BINDING_COUNT)
                .map(|b| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b)
                        .descriptor_type(descriptor_type(b))
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            kernel.set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .during("vkCreateDescriptorSetLayout")?;
            let push = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .offset(0)
                .size(std::mem::size_of::<KernelPushConstants>() as u32)];
            let set_layouts = [kernel.set_layout];
            kernel.pipeline_layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
                        .set_layouts(&set_layouts)
                        .push_constant_ranges(&push),
                    None,
                )
                .during("vkCreatePipelineLayout")?;
            let pool_sizes = descriptor_pool_sizes();
            kernel.descriptor_pool = device
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&pool_sizes),
                    None,
                )
                .during("vkCreateDescriptorPool")?;
            kernel.descriptor_set = device
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(kernel.descriptor_pool)
                        .set_layouts(&set_layouts),
                )
                .during("vkAllocateDescriptorSets")?[0];
            if let Some(code) = code {
                kernel.module = device
                    .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(code), None)
                    .during("vkCreateShaderModule")?;
            }
        }
        Ok(kernel)
    }

    /// Creates those of the pipelines `which` (indices into [`Self::pipelines`]) that do not exist yet,
    /// in one call; `render_samples` specialised for [`Self::render_features`]. Creating only what a
    /// frame uses matters where creation is slow: the validation layer spent about 40 s on all 13
    /// pipelines of the kernel on lavapipe, and a render without history or denoiser uses 6.
    pub(crate) fn ensure_pipelines(&mut self, which: &[usize]) -> Result<()> {
        self.check_kernel()?;
        if which.contains(&RENDER_SAMPLES) && self.pipelines[RENDER_SAMPLES] == vk::Pipeline::null()
        {
            self.specialize_render_pipeline(self.render_features)?;
        }
        let missing: Vec<usize> = which
            .iter()
            .copied()
            .filter(|&p| self.pipelines[p] == vk::Pipeline::null())
            .collect();
        if missing.is_empty() {
            return Ok(());
        }
        let names: Vec<std::ffi::CString> = missing.iter().map(|&p| entry_point_name(p)).collect();
        let infos: Vec<vk::ComputePipelineCreateInfo> = names
            .iter()
            .map(|name| self.kernel_pipeline_info(name, None))
            .collect();
        let start = std::time::Instant::now();
        // SAFETY: every create info and what it points to live until the call returns; the handles
        // are stored in `self` at once, so Drop destroys them.
        let created = unsafe { create_compute_pipelines(&self.shared.device, &infos)? };
        self.pipeline_create_ms += start.elapsed().as_secs_f64() * 1e3;
        for (&p, pipeline) in missing.iter().zip(created) {
            self.pipelines[p] = pipeline;
        }
        Ok(())
    }

    /// Fails on a present-only context ([`ContextOptions::present_only`]), which has no kernel.
    pub(crate) fn check_kernel(&self) -> Result<()> {
        if self.module == vk::ShaderModule::null() {
            Err(VulkanError::Invalid(
                "this Vulkan context was created to present host images only; it has no kernel to \
                 render with"
                    .into(),
            ))
        } else {
            Ok(())
        }
    }

    /// Makes `render_samples` the pipeline specialised for the feature mask `features` (its
    /// specialization constant [`SPEC_CONSTANT_FEATURES`]), so that the driver compiles out the code of
    /// features the scene lacks. Created on first use, re-created only when the mask changes; nothing is
    /// in flight between frames. The next frame warms the new pipeline up again.
    pub(crate) fn specialize_render_pipeline(&mut self, features: u32) -> Result<()> {
        self.check_kernel()?;
        if features == self.render_features
            && self.pipelines[RENDER_SAMPLES] != vk::Pipeline::null()
        {
            return Ok(());
        }
        let name = entry_point_name(RENDER_SAMPLES);
        let spec_data = features.to_ne_bytes();
        let spec_entries = features_map_entry();
        let spec = vk::SpecializationInfo::default()
            .map_entries(&spec_entries)
            .data(&spec_data);
        let create = [self.kernel_pipeline_info(&name, Some(&spec))];
        let device = &self.shared.device;
        let start = std::time::Instant::now();
        // SAFETY: the create info and everything it points to live until the call returns; the old
        // pipeline is not in use (every submission was waited on) and is destroyed only after the new
        // one exists.
        unsafe {
            let created = create_compute_pipelines(device, &create)?;
            device.destroy_pipeline(self.pipelines[RENDER_SAMPLES], None);
            self.pipelines[RENDER_SAMPLES] = created[0];
        }
        self.pipeline_create_ms += start.elapsed().as_secs_f64() * 1e3;
        self.render_features = features;
        self.warmed[RENDER_SAMPLES] = false;
        Ok(())
    }

    /// The feature mask the current `render_samples` pipeline was specialised for.
    pub fn render_features(&self) -> u32 {
        self.render_features
    }

    /// The create info of the kernel module's compute pipeline for entry point `name`, with the
    /// context's layout, specialised by `spec` where given.
    fn kernel_pipeline_info<'a>(
        &self,
        name: &'a std::ffi::CStr,
        spec: Option<&'a vk::SpecializationInfo<'a>>,
    ) -> vk::ComputePipelineCreateInfo<'a> {
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(self.module)
            .name(name);
        if let Some(spec) = spec {
            stage = stage.specialization_info(spec);
        }
        vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(self.pipeline_layout)
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let device = &self.shared.device;
        // SAFETY: the context waits for the device before its kernel is dropped, so no pipeline is in
        // use; null handles are skipped by the Vulkan destroy functions.
        unsafe {
            for p in self.pipelines.into_iter().chain(self.probe_pipelines) {
                device.destroy_pipeline(p, None);
            }
            device.destroy_shader_module(self.module, None);
            device.destroy_pipeline_layout(self.pipeline_layout, None);
            device.destroy_descriptor_pool(self.descriptor_pool, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Descriptor type of each binding: the chunk's block list is bound with a dynamic offset, the scene
/// texels as a storage texel buffer, everything else as a plain storage buffer.
pub(crate) fn descriptor_type(binding: u32) -> vk::DescriptorType {
    if binding == BINDING_BLOCKS {
        vk::DescriptorType::STORAGE_BUFFER_DYNAMIC
    } else if binding == BINDING_SCENE_TEXELS {
        vk::DescriptorType::STORAGE_TEXEL_BUFFER
    } else {
        vk::DescriptorType::STORAGE_BUFFER
    }
}

/// Descriptors of each type in one set of the kernel's layout (for descriptor pools).
pub(crate) fn descriptor_pool_sizes() -> Vec<vk::DescriptorPoolSize> {
    let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
    for b in 0..BINDING_COUNT {
        let ty = descriptor_type(b);
        match sizes.iter_mut().find(|s| s.ty == ty) {
            Some(s) => s.descriptor_count += 1,
            None => sizes.push(vk::DescriptorPoolSize::default().ty(ty).descriptor_count(1)),
        }
    }
    sizes
}

/// `vkCreateComputePipelines` for `infos`; on failure the pipelines that were created are destroyed and
/// the error names the call.
///
/// # Safety
/// Every create info and everything it points to must be valid for `device` until the call returns.
pub(crate) unsafe fn create_compute_pipelines(
    device: &ash::Device,
    infos: &[vk::ComputePipelineCreateInfo],
) -> Result<Vec<vk::Pipeline>> {
    // SAFETY: the caller guarantees valid create infos; partially created pipelines are destroyed before
    // anything else can use them.
    unsafe {
        device
            .create_compute_pipelines(vk::PipelineCache::null(), infos, None)
            .map_err(|(created, r)| {
                for p in created {
                    if p != vk::Pipeline::null() {
                        device.destroy_pipeline(p, None);
                    }
                }
                VulkanError::vk("vkCreateComputePipelines", r)
            })
    }
}

/// The one specialization constant of `render_samples`: the feature mask, a `u32` at offset 0.
fn features_map_entry() -> [vk::SpecializationMapEntry; 1] {
    [vk::SpecializationMapEntry::default()
        .constant_id(SPEC_CONSTANT_FEATURES)
        .offset(0)
        .size(4)]
}

/// The kernel entry point of pipeline `index` ([`ENTRY_POINTS`]) as a C string.
fn entry_point_name(index: usize) -> std::ffi::CString {
    std::ffi::CString::new(ENTRY_POINTS[index]).expect("entry point names have no NUL")
}
