//! [`VulkanContext`]: instance, device, compute queue, the kernel's pipelines and the per-frame buffers.
use std::sync::Arc;
use std::time::Duration;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::{AllocationSizes, AllocatorDebugSettings, MemoryLocation};

use fovea_core::kernel_abi::{
    KernelPushConstants, BINDING_BLOCKS, BINDING_COUNT, BINDING_SCENE_TEXELS,
    SPEC_CONSTANT_FEATURES,
};
use fovea_core::passes::{FramePass, KERNEL_ENTRY_COUNT};
use fovea_core::scene::features::FEATURES_ALL;

use crate::blocks::{DEFAULT_MAX_CHUNK_SAMPLES, SOFTWARE_MAX_CHUNK_SAMPLES};
use crate::buffer::GpuBuffer;
use crate::error::{Result, VkContext, VulkanError};
use crate::instance::{choose_device, DeviceInfo, InstanceHandle, MessageLog, Shared};
use crate::limits::{query_limits, Limits};
use crate::resources::FrameResources;
use crate::spirv::{self, capability, ENTRY_POINTS};

/// How to set up a context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Device index in [`crate::list_devices`] order; `None` picks automatically (discrete, then
    /// integrated, then anything, e.g. lavapipe).
    pub device_index: Option<usize>,
    /// Enable `VK_LAYER_KHRONOS_validation` and record its messages.
    pub validation: bool,
    /// A window to present to (`fovea view`): the instance gets the window system's surface extensions,
    /// the device must present to the window's surface from its compute queue, and `VK_KHR_swapchain` is
    /// enabled.
    pub window: Option<crate::swapchain::WindowHandles>,
    /// Software or hardware traversal (the latter loads the ray-query kernel module).
    pub traversal: crate::traversal::Traversal,
    /// Only present host images to the window (`fovea view --backend cpu`): the kernel's module and
    /// pipelines are not created, which saves their compile (seconds on lavapipe, and half a minute
    /// more under the validation layer, which checks the whole module). Rendering then fails with
    /// an error that says so.
    pub present_only: bool,
}

impl ContextOptions {
    /// Automatic device; validation when the environment has `FOVEA_VULKAN_VALIDATION=1`.
    #[must_use]
    pub fn from_env() -> Self {
        Self {
            device_index: None,
            validation: validation_requested(),
            window: None,
            traversal: crate::traversal::Traversal::Auto,
            present_only: false,
        }
    }
}

/// Whether `FOVEA_VULKAN_VALIDATION` asks for the validation layer (`1`, `true`, `yes`).
#[must_use]
pub fn validation_requested() -> bool {
    matches!(
        std::env::var("FOVEA_VULKAN_VALIDATION").as_deref(),
        Ok("1" | "true" | "yes" | "on")
    )
}

/// The index in [`VulkanContext::pipelines`] of `render_samples`, the one pipeline specialised per
/// scene ([`VulkanContext::specialize_render_pipeline`]).
pub(crate) const RENDER_SAMPLES: usize = FramePass::Samples.first_kernel_entry();

/// Timeout of each fence wait per chunk of work.
pub const CHUNK_TIMEOUT: Duration = Duration::from_secs(60);

/// Timeout of each pipeline's warm-up dispatch: a software driver compiles the shader there (lavapipe:
/// LLVM), which for the general kernels takes tens of seconds alone and longer on a loaded machine.
pub const WARMUP_TIMEOUT: Duration = Duration::from_secs(300);

/// A Vulkan device ready to run the fovea kernel: one compute queue, one pipeline per entry point (all from
/// the one SPIR-V module, each created when a frame first needs it), and the buffers of the last frame
/// size, reused across frames.
pub struct VulkanContext {
    pub(crate) shared: Arc<Shared>,
    pub(crate) info: DeviceInfo,
    pub(crate) limits: Limits,
    pub(crate) queue: vk::Queue,
    pub(crate) command_pool: vk::CommandPool,
    pub(crate) command_buffer: vk::CommandBuffer,
    pub(crate) fence: vk::Fence,
    pub(crate) set_layout: vk::DescriptorSetLayout,
    pub(crate) pipeline_layout: vk::PipelineLayout,
    /// One per kernel entry of core's passes ([`ENTRY_POINTS`], indexed by
    /// [`FramePass::kernel_entry_range`]), null until a frame first needs it
    /// ([`Self::ensure_pipelines`]): a render without history or denoiser never creates those passes'
    /// pipelines.
    pub(crate) pipelines: [vk::Pipeline; KERNEL_ENTRY_COUNT],
    /// The kernel module, kept for re-specialising `render_samples` per scene.
    pub(crate) module: vk::ShaderModule,
    /// The feature mask `pipelines[RENDER_SAMPLES]` was (or, while it is null, will be) specialised for.
    pub(crate) render_features: u32,
    /// The pipelines of the `probe` and `probe_scene` entry points, created on first use by
    /// [`VulkanContext::run_probe`] and [`VulkanContext::run_scene_probe`].
    pub(crate) probe_pipelines: [vk::Pipeline; 2],
    pub(crate) descriptor_pool: vk::DescriptorPool,
    pub(crate) descriptor_set: vk::DescriptorSet,
    /// Two timestamps per frame; null when the queue has no timestamp bits.
    pub(crate) query_pool: vk::QueryPool,
    /// Nanoseconds per timestamp tick.
    pub(crate) timestamp_period: f32,
    /// Mask of the valid timestamp bits.
    pub(crate) timestamp_mask: u64,
    /// The per-frame buffers of the view being rendered ([`Self::active_view`]).
    pub(crate) frame: Option<FrameResources>,
    /// Size of the last frame rendered (what [`Self::read_back_hdr`] and [`Self::present`] show).
    pub(crate) last_frame_size: Option<(u32, u32)>,
    /// The view whose buffers `frame` holds ([`fovea_core::passes::FrameRequest::view`]).
    pub(crate) active_view: u32,
    /// The other views' buffers and sizes (with their histories), indexed by view; the active
    /// view's slot is empty.
    pub(crate) parked_views: Vec<crate::resources::ParkedView>,
    /// The window's swapchain (live view), created by the first [`Self::present`].
    pub(crate) presenter: Option<crate::swapchain::Presenter>,
    pub(crate) poisoned: bool,
    /// A failure the next submission reports instead of submitting ([`Self::inject_fault`]).
    pub(crate) injected_fault: Option<vk::Result>,
    /// Bound on the samples of one `render_samples` dispatch (and one submission):
    /// [`DEFAULT_MAX_CHUNK_SAMPLES`], or [`SOFTWARE_MAX_CHUNK_SAMPLES`] on a software driver.
    pub max_chunk_samples: u32,
    /// Host time of every `vkCreateComputePipelines` of this context so far (lavapipe translates the
    /// module to NIR here; LLVM code generation waits for the first dispatch, see [`Self::warmed`]).
    pub pipeline_create_ms: f64,
    /// Which pipelines have been dispatched once (by the first frame that runs their pass, before its
    /// own dispatches, so that its `render_ms` excludes a driver's lazy shader compilation; frames that
    /// never run a pass never compile it).
    pub(crate) warmed: [bool; KERNEL_ENTRY_COUNT],
    /// Whether the kernel is the ray-query module (scenes get acceleration structures).
    pub(crate) hardware_traversal: bool,
    /// Why `Traversal::Auto` chose software, if it did.
    pub traversal_note: Option<String>,
    /// `minAccelerationStructureScratchOffsetAlignment` (hardware traversal).
    pub(crate) hardware_scratch_alignment: u32,
}

impl VulkanContext {
    /// Loads Vulkan, picks a device and creates everything the kernel needs.
    ///
    /// Long because creating the device is one sequence of dependent calls (instance, device choice,
    /// traversal, queue family, the features the module's capabilities need, device, allocator, pools,
    /// layouts), each taking the handles made before it.
    pub fn new(options: &ContextOptions) -> Result<Self> {
        let code = spirv::load_kernel()?;
        let module_info = spirv::module_info(&code);
        for name in ENTRY_POINTS {
            if !module_info.entry_points.iter().any(|e| e == name) {
                return Err(VulkanError::KernelNotBuilt(format!(
                    "the SPIR-V module has no entry point '{name}' (it has {:?})",
                    module_info.entry_points
                )));
            }
        }

        let instance = match &options.window {
            None => InstanceHandle::new(options.validation)?,
            Some(window) => {
                let extensions = crate::swapchain::surface_extensions(window)?;
                let mut instance =
                    InstanceHandle::with_extensions(options.validation, &extensions)?;
                crate::swapchain::create_surface(&mut instance, window)?;
                instance
            }
        };
        let physical = instance.physical_devices()?;
        let mut infos: Vec<DeviceInfo> = physical
            .iter()
            .enumerate()
            .map(|(i, &pd)| instance.describe(i, pd))
            .collect();
        if instance.surface.is_some() {
            for (info, &pd) in infos.iter_mut().zip(&physical) {
                if info.unsuitable.is_none()
                    && crate::swapchain::present_queue_family(&instance, pd).is_none()
                {
                    info.unsuitable =
                        Some("no compute queue that can present to the window".into());
                }
            }
        }
        let index = choose_device(&infos, options.device_index)?;
        let pd = physical[index];
        let info = infos[index].clone();
        let vk_instance = &instance.instance;

        let support = crate::traversal::ray_query_support(&instance, pd);
        let (hardware, traversal_note) =
            crate::traversal::resolve_traversal(options.traversal, info.device_type, &support)
                .map_err(|reason| VulkanError::UnsuitableDevice {
                    device: info.name.clone(),
                    reason,
                })?;
        let code = if hardware {
            let rq = spirv::load_ray_query_kernel()?;
            let rq_info = spirv::module_info(&rq);
            for name in ENTRY_POINTS {
                if !rq_info.entry_points.iter().any(|e| e == name) {
                    return Err(VulkanError::KernelNotBuilt(format!(
                        "the ray-query SPIR-V module has no entry point '{name}'"
                    )));
                }
            }
            rq
        } else {
            code
        };
        let module_info = spirv::module_info(&code);

        // SAFETY: (this block and the queries below) `pd` belongs to `vk_instance`.
        let queue_families = unsafe { vk_instance.get_physical_device_queue_family_properties(pd) };
        // Prefer a compute-only queue family (async compute), else any with compute; with a window, the
        // first compute family that presents to it.
        let family = if instance.surface.is_some() {
            crate::swapchain::present_queue_family(&instance, pd)
        } else {
            queue_families
                .iter()
                .enumerate()
                .filter(|(_, q)| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .min_by_key(|(_, q)| q.queue_flags.contains(vk::QueueFlags::GRAPHICS))
                .map(|(i, _)| i as u32)
        }
        .ok_or_else(|| VulkanError::UnsuitableDevice {
            device: info.name.clone(),
            reason: "no compute queue".into(),
        })?;
        let timestamp_bits = queue_families[family as usize].timestamp_valid_bits;

        // Features the module's capabilities need.
        let mut supported11 = vk::PhysicalDeviceVulkan11Features::default();
        let mut supported12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut supported = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut supported11)
            .push_next(&mut supported12);
        // SAFETY: valid chain of feature structs.
        unsafe { vk_instance.get_physical_device_features2(pd, &mut supported) };
        let base = supported.features;
        let mut want = vk::PhysicalDeviceFeatures::default();
        let mut want11 = vk::PhysicalDeviceVulkan11Features::default();
        let mut want12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut missing = Vec::new();
        let mut need = |ok: vk::Bool32, name: &'static str| -> vk::Bool32 {
            if ok == vk::FALSE {
                missing.push(name);
            }
            vk::TRUE
        };
        for &cap in &module_info.capabilities {
            match cap {
                capability::VULKAN_MEMORY_MODEL => {
                    want12.vulkan_memory_model =
                        need(supported12.vulkan_memory_model, "vulkanMemoryModel")
                }
                capability::VULKAN_MEMORY_MODEL_DEVICE_SCOPE => {
                    want12.vulkan_memory_model_device_scope = need(
                        supported12.vulkan_memory_model_device_scope,
                        "vulkanMemoryModelDeviceScope",
                    )
                }
                capability::INT64 => want.shader_int64 = need(base.shader_int64, "shaderInt64"),
                capability::INT16 => want.shader_int16 = need(base.shader_int16, "shaderInt16"),
                capability::FLOAT64 => {
                    want.shader_float64 = need(base.shader_float64, "shaderFloat64")
                }
                capability::INT8 => {
                    want12.shader_int8 = need(supported12.shader_int8, "shaderInt8")
                }
                capability::STORAGE_BUFFER_8BIT_ACCESS => {
                    want12.storage_buffer8_bit_access = need(
                        supported12.storage_buffer8_bit_access,
                        "storageBuffer8BitAccess",
                    )
                }
                capability::STORAGE_BUFFER_16BIT_ACCESS => {
                    want11.storage_buffer16_bit_access = need(
                        supported11.storage_buffer16_bit_access,
                        "storageBuffer16BitAccess",
                    )
                }
                capability::VARIABLE_POINTERS_STORAGE_BUFFER => {
                    want11.variable_pointers_storage_buffer = need(
                        supported11.variable_pointers_storage_buffer,
                        "variablePointersStorageBuffer",
                    )
                }
                capability::VARIABLE_POINTERS => {
                    want11.variable_pointers_storage_buffer = need(
                        supported11.variable_pointers_storage_buffer,
                        "variablePointersStorageBuffer",
                    );
                    want11.variable_pointers =
                        need(supported11.variable_pointers, "variablePointers")
                }
                capability::PHYSICAL_STORAGE_BUFFER_ADDRESSES => {
                    want12.buffer_device_address =
                        need(supported12.buffer_device_address, "bufferDeviceAddress")
                }
                _ => {}
            }
        }
        if !missing.is_empty() {
            return Err(VulkanError::UnsuitableDevice {
                device: info.name.clone(),
                reason: format!("the kernel needs {}", missing.join(", ")),
            });
        }

        let mut device_extensions = Vec::new();
        if hardware {
            // Device addresses: the acceleration structures' inputs and the kernel's TLAS address.
            want12.buffer_device_address = vk::TRUE;
        }
        let mut want_accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
            .acceleration_structure(true);
        let mut want_ray_query = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let mut enabled = vk::PhysicalDeviceFeatures2::default()
            .features(want)
            .push_next(&mut want11)
            .push_next(&mut want12);
        if hardware {
            enabled = enabled
                .push_next(&mut want_accel)
                .push_next(&mut want_ray_query);
            device_extensions.extend(crate::traversal::DEVICE_EXTENSIONS.map(|e| e.as_ptr()));
        }
        if instance.surface.is_some() {
            crate::swapchain::check_swapchain_extension(&instance, pd, &info.name)?;
            device_extensions.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&device_extensions)
            .push_next(&mut enabled);
        // SAFETY: the create info and everything it points to live until the call returns.
        let device = unsafe { vk_instance.create_device(pd, &device_info, None) }
            .during("vkCreateDevice")?;
        let allocator = match Allocator::new(&AllocatorCreateDesc {
            instance: vk_instance.clone(),
            device: device.clone(),
            physical_device: pd,
            debug_settings: AllocatorDebugSettings::default(),
            buffer_device_address: hardware,
            allocation_sizes: AllocationSizes::default(),
        }) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: nothing was created on the device yet.
                unsafe { device.destroy_device(None) };
                return Err(VulkanError::Allocator(e.to_string()));
            }
        };
        let shared = Arc::new(Shared {
            device,
            allocator: std::mem::ManuallyDrop::new(std::sync::Mutex::new(allocator)),
            physical_device: pd,
            instance,
        });
        let limits = query_limits(&shared);
        let hardware_scratch_alignment = crate::traversal::scratch_alignment(&shared.instance, pd);
        // SAFETY: `pd` belongs to the instance.
        let props = unsafe { shared.instance.instance.get_physical_device_properties(pd) };

        let mut ctx = Self {
            shared,
            info: info.clone(),
            limits,
            queue: vk::Queue::null(),
            command_pool: vk::CommandPool::null(),
            command_buffer: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pipeline_layout: vk::PipelineLayout::null(),
            pipelines: [vk::Pipeline::null(); KERNEL_ENTRY_COUNT],
            module: vk::ShaderModule::null(),
            render_features: FEATURES_ALL,
            probe_pipelines: [vk::Pipeline::null(); 2],
            descriptor_pool: vk::DescriptorPool::null(),
            descriptor_set: vk::DescriptorSet::null(),
            query_pool: vk::QueryPool::null(),
            timestamp_period: props.limits.timestamp_period,
            timestamp_mask: if timestamp_bits >= 64 {
                u64::MAX
            } else {
                (1u64 << timestamp_bits) - 1
            },
            frame: None,
            last_frame_size: None,
            active_view: 0,
            parked_views: Vec::new(),
            presenter: None,
            poisoned: false,
            injected_fault: None,
            max_chunk_samples: if info.device_type == "cpu" {
                SOFTWARE_MAX_CHUNK_SAMPLES
            } else {
                DEFAULT_MAX_CHUNK_SAMPLES
            },
            pipeline_create_ms: 0.0,
            warmed: [false; KERNEL_ENTRY_COUNT],
            hardware_traversal: hardware,
            traversal_note,
            hardware_scratch_alignment,
        };
        // From here on, `ctx`'s Drop cleans up whatever was created if a step fails.
        let kernel = (!options.present_only).then_some(code.as_slice());
        ctx.create_objects(family, kernel, timestamp_bits > 0)?;
        Ok(ctx)
    }

    /// Queue, command buffer, fence, descriptor layout and set, pipelines and the timestamp pool.
    /// Creates the queue's command objects, the descriptor set and, given the kernel's `code`, its
    /// module and pipelines (a present-only context has none).
    fn create_objects(
        &mut self,
        family: u32,
        code: Option<&[u32]>,
        timestamps: bool,
    ) -> Result<()> {
        let device = &self.shared.device;
        // SAFETY: (whole function) every create call gets a valid create info whose pointers live until
        // the call returns; the handles are stored in `self` at once, so Drop destroys them.
        unsafe {
            self.queue = device.get_device_queue(family, 0);
            self.command_pool = device
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .during("vkCreateCommandPool")?;
            self.command_buffer = device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(self.command_pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
                .during("vkAllocateCommandBuffers")?[0];
            self.fence = device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .during("vkCreateFence")?;

            let bindings: Vec<vk::DescriptorSetLayoutBinding> = (0..BINDING_COUNT)
                .map(|b| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b)
                        .descriptor_type(descriptor_type(b))
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            self.set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .during("vkCreateDescriptorSetLayout")?;
            let push = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .offset(0)
                .size(std::mem::size_of::<KernelPushConstants>() as u32)];
            let set_layouts = [self.set_layout];
            self.pipeline_layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
                        .set_layouts(&set_layouts)
                        .push_constant_ranges(&push),
                    None,
                )
                .during("vkCreatePipelineLayout")?;
            let pool_sizes = descriptor_pool_sizes();
            self.descriptor_pool = device
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&pool_sizes),
                    None,
                )
                .during("vkCreateDescriptorPool")?;
            self.descriptor_set = device
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(self.descriptor_pool)
                        .set_layouts(&set_layouts),
                )
                .during("vkAllocateDescriptorSets")?[0];

            if timestamps {
                self.query_pool = device
                    .create_query_pool(
                        &vk::QueryPoolCreateInfo::default()
                            .query_type(vk::QueryType::TIMESTAMP)
                            .query_count(crate::timestamps::QUERIES),
                        None,
                    )
                    .during("vkCreateQueryPool")?;
            }
        }
        if let Some(code) = code {
            self.create_kernel_pipelines(code)?;
        }
        Ok(())
    }

    /// The kernel's module. Its pipelines are created when a frame first needs them
    /// ([`Self::ensure_pipelines`]).
    fn create_kernel_pipelines(&mut self, code: &[u32]) -> Result<()> {
        let device = &self.shared.device;
        // SAFETY: a valid create info whose code lives until the call returns; the handle is stored in
        // `self` at once, so Drop destroys it.
        self.module = unsafe {
            device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(code), None)
                .during("vkCreateShaderModule")?
        };
        Ok(())
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

    /// Whether rays are traced by the device's acceleration structures (`--traversal hardware`).
    #[must_use]
    pub fn hardware_traversal(&self) -> bool {
        self.hardware_traversal
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

impl VulkanContext {
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

/// The kernel entry point of pipeline `index` ([`ENTRY_POINTS`]) as a C string.
fn entry_point_name(index: usize) -> std::ffi::CString {
    std::ffi::CString::new(ENTRY_POINTS[index]).expect("entry point names have no NUL")
}

impl Drop for VulkanContext {
    fn drop(&mut self) {
        let device = &self.shared.device;
        // SAFETY: waiting for the device first makes every object below unused; null handles (a
        // half-built context) are skipped by the Vulkan destroy functions.
        unsafe {
            let _ = device.device_wait_idle();
            // The swapchain goes before the surface (with the instance, later).
            self.presenter = None;
            self.frame = None;
            self.parked_views.clear();
            for p in self.pipelines {
                device.destroy_pipeline(p, None);
            }
            for p in self.probe_pipelines {
                device.destroy_pipeline(p, None);
            }
            device.destroy_shader_module(self.module, None);
            device.destroy_pipeline_layout(self.pipeline_layout, None);
            device.destroy_descriptor_pool(self.descriptor_pool, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
            device.destroy_query_pool(self.query_pool, None);
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.command_pool, None);
        }
    }
}
