//! [`VulkanContext`]: instance, device, compute queue, the kernel's pipelines and the per-frame buffers.
use std::sync::Arc;
use std::time::Duration;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::{AllocationSizes, AllocatorDebugSettings};

use crate::blocks::{DEFAULT_MAX_CHUNK_SAMPLES, SOFTWARE_MAX_CHUNK_SAMPLES};
use crate::device::Device;
use crate::error::{Result, VkContext, VulkanError};
use crate::instance::{choose_device, DeviceInfo, InstanceHandle, MessageLog, Shared};
use crate::kernel::Kernel;
use crate::resources::FrameResources;
use crate::spirv::{self, capability, ENTRY_POINTS};
use crate::swapchain::Presenter;

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
    /// Who creates the instance and device (`None`: fovea itself; an OpenXR session's runtime for
    /// `fovea xr`, see [`crate::factory`]).
    pub factory: Option<crate::factory::SharedFactory>,
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
            factory: None,
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

/// Timeout of each fence wait per chunk of work.
pub const CHUNK_TIMEOUT: Duration = Duration::from_secs(60);

/// Timeout of each pipeline's warm-up dispatch: a software driver compiles the shader there (lavapipe:
/// LLVM), which for the general kernels takes tens of seconds alone and longer on a loaded machine.
pub const WARMUP_TIMEOUT: Duration = Duration::from_secs(300);

/// A Vulkan device ready to run the fovea kernel: the device and its queue ([`Device`]), the kernel's
/// pipelines ([`Kernel`]), each view's per-frame buffers ([`FrameResources`]) and the window's
/// swapchain ([`Presenter`]), each a type with its own state; the context renders frames with them
/// (`crate::frame`). Fields drop in declaration order, after [`Drop`] has waited for the device: the
/// swapchain, the frames' buffers, the pipelines, then the device's own objects.
pub struct VulkanContext {
    /// The window's swapchain (live view), created by the first [`Self::present`].
    pub(crate) presenter: Option<Presenter>,
    /// The per-frame buffers of the view being rendered ([`Self::active_view`]).
    pub(crate) frame: Option<FrameResources>,
    /// Size of the last frame rendered (what [`Self::read_back_hdr`] and [`Self::present`] show).
    pub(crate) last_frame_size: Option<(u32, u32)>,
    /// The view whose buffers `frame` holds ([`fovea_core::passes::FrameRequest::view`]).
    pub(crate) active_view: u32,
    /// The other views' buffers and sizes (with their histories), indexed by view; the active
    /// view's slot is empty.
    pub(crate) parked_views: Vec<crate::resources::ParkedView>,
    pub(crate) kernel: Kernel,
    pub(crate) device: Device,
    /// Bound on the samples of one `render_samples` dispatch (and one submission):
    /// [`DEFAULT_MAX_CHUNK_SAMPLES`], or [`SOFTWARE_MAX_CHUNK_SAMPLES`] on a software driver.
    pub max_chunk_samples: u32,
    /// Why `Traversal::Auto` chose software, if it did.
    pub traversal_note: Option<String>,
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

        let factory = options.factory.as_deref();
        let instance = match &options.window {
            None => InstanceHandle::with_extensions(options.validation, &[], factory)?,
            Some(window) => {
                let extensions = crate::swapchain::surface_extensions(window)?;
                let mut instance =
                    InstanceHandle::with_extensions(options.validation, &extensions, factory)?;
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
        let index = match factory
            .map(|f| f.physical_device(&instance.instance))
            .transpose()?
            .flatten()
        {
            // The factory's device (a headset's), wherever it is in the list.
            Some(pd) => {
                let index = physical.iter().position(|&p| p == pd).ok_or_else(|| {
                    VulkanError::NoDevice(
                        " (the device the OpenXR runtime chose is not listed)".into(),
                    )
                })?;
                if let Some(reason) = &infos[index].unsuitable {
                    return Err(VulkanError::UnsuitableDevice {
                        device: infos[index].name.clone(),
                        reason: reason.clone(),
                    });
                }
                index
            }
            None => choose_device(&infos, options.device_index)?,
        };
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
        } else if factory.is_some_and(|f| f.needs_graphics_queue()) {
            queue_families
                .iter()
                .position(|q| {
                    q.queue_flags
                        .contains(vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS)
                })
                .map(|i| i as u32)
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
        // The features as the structs Vulkan 1.2 promoted them from, not `Vulkan11Features` and
        // `Vulkan12Features`: an OpenXR runtime adds its own (timeline semaphores, 16-bit storage)
        // to the chain, and the two kinds must not be mixed (VUID-VkDeviceCreateInfo-pNext-02829/30).
        let mut storage16 = vk::PhysicalDevice16BitStorageFeatures::default()
            .storage_buffer16_bit_access(want11.storage_buffer16_bit_access == vk::TRUE);
        let mut variable_pointers = vk::PhysicalDeviceVariablePointersFeatures::default()
            .variable_pointers_storage_buffer(want11.variable_pointers_storage_buffer == vk::TRUE)
            .variable_pointers(want11.variable_pointers == vk::TRUE);
        let mut storage8 = vk::PhysicalDevice8BitStorageFeatures::default()
            .storage_buffer8_bit_access(want12.storage_buffer8_bit_access == vk::TRUE);
        let mut int8 = vk::PhysicalDeviceShaderFloat16Int8Features::default()
            .shader_int8(want12.shader_int8 == vk::TRUE);
        let mut memory_model = vk::PhysicalDeviceVulkanMemoryModelFeatures::default()
            .vulkan_memory_model(want12.vulkan_memory_model == vk::TRUE)
            .vulkan_memory_model_device_scope(want12.vulkan_memory_model_device_scope == vk::TRUE);
        let mut addresses = vk::PhysicalDeviceBufferDeviceAddressFeatures::default()
            .buffer_device_address(want12.buffer_device_address == vk::TRUE);
        let mut enabled = vk::PhysicalDeviceFeatures2::default()
            .features(want)
            .push_next(&mut storage16)
            .push_next(&mut variable_pointers)
            .push_next(&mut storage8)
            .push_next(&mut int8)
            .push_next(&mut memory_model)
            .push_next(&mut addresses);
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
        let device = match factory {
            Some(factory) => {
                // SAFETY: `pd` belongs to the instance; the create info and everything it points to
                // live until the call returns.
                unsafe { factory.create_device(&instance.entry, vk_instance, pd, &device_info) }?
            }
            // SAFETY: as above.
            None => unsafe { vk_instance.create_device(pd, &device_info, None) }
                .during("vkCreateDevice")?,
        };
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
        let device = Device::new(shared.clone(), info.clone(), family, timestamp_bits)?;
        let kernel = Kernel::new(
            shared,
            (!options.present_only).then_some(code.as_slice()),
            hardware,
        )?;
        Ok(Self {
            presenter: None,
            frame: None,
            last_frame_size: None,
            active_view: 0,
            parked_views: Vec::new(),
            kernel,
            device,
            max_chunk_samples: if info.device_type == "cpu" {
                SOFTWARE_MAX_CHUNK_SAMPLES
            } else {
                DEFAULT_MAX_CHUNK_SAMPLES
            },
            traversal_note,
        })
    }

    /// Whether rays are traced by the device's acceleration structures (`--traversal hardware`).
    #[must_use]
    pub fn hardware_traversal(&self) -> bool {
        self.kernel.hardware_traversal
    }

    /// The device the context renders on.
    #[must_use]
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The device, for submissions of its own (a headset's swapchain copies).
    #[cfg_attr(not(feature = "xr"), allow(dead_code))]
    pub(crate) fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// The chosen device.
    #[must_use]
    pub fn device_info(&self) -> &DeviceInfo {
        self.device.device_info()
    }

    /// The device's name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    #[must_use]
    pub fn device_name(&self) -> &str {
        self.device.device_name()
    }

    /// The device's name and its driver (see [`Device::device_description`]).
    #[must_use]
    pub fn device_description(&self) -> String {
        self.device.device_description()
    }

    /// Whether frame times come from GPU timestamps (else wall time around the submissions).
    #[must_use]
    pub fn has_timestamps(&self) -> bool {
        self.device.has_timestamps()
    }

    /// A snapshot of every warning and error the validation layer reported so far.
    #[must_use]
    pub fn validation_messages(&self) -> Vec<String> {
        self.device.validation_messages()
    }

    /// The live message list ([`Device::validation_log`]).
    #[must_use]
    pub fn validation_log(&self) -> MessageLog {
        self.device.validation_log()
    }

    /// Fault injection for tests ([`Device::inject_fault`]).
    #[doc(hidden)]
    pub fn inject_fault(&mut self, fault: vk::Result) {
        self.device.inject_fault(fault);
    }

    /// Host time of every `vkCreateComputePipelines` of this context so far.
    #[must_use]
    pub fn pipeline_create_ms(&self) -> f64 {
        self.kernel.pipeline_create_ms
    }

    /// The feature mask the current `render_samples` pipeline was specialised for.
    #[must_use]
    pub fn render_features(&self) -> u32 {
        self.kernel.render_features
    }

    /// Presents `source` with `hud` over its corner to the window, at `window_size` (the window's inner
    /// size in pixels, used where the surface leaves the size to the application). Creates the swapchain
    /// on first use and re-creates it after a resize. A minimised window presents nothing
    /// ([`crate::present`]).
    pub fn present(
        &mut self,
        source: crate::present::PresentSource<'_>,
        hud: Option<crate::present::HudOverlay<'_>>,
        window_size: [u32; 2],
    ) -> Result<crate::present::PresentOutcome> {
        let last_frame = self.last_ldr_buffer();
        crate::present::present(
            &mut self.device,
            &mut self.presenter,
            last_frame,
            source,
            hud,
            window_size,
        )
    }

    /// The kernel's probe entry points on this context's device ([`crate::probe`]).
    pub fn probes(&mut self) -> crate::probe::Probes<'_> {
        crate::probe::Probes {
            device: &mut self.device,
            kernel: &mut self.kernel,
        }
    }

    /// [`crate::probe::Probes::run_probe`] on this context.
    pub fn run_probe(&mut self, selector: u32, inputs: &[[f32; 4]]) -> Result<Vec<[f32; 4]>> {
        self.probes().run_probe(selector, inputs)
    }

    /// [`crate::probe::Probes::run_probe_with`] on this context.
    pub fn run_probe_with(
        &mut self,
        selector: u32,
        inputs: &[[f32; 4]],
        frame: &fovea_core::integrator::FrameParams,
        replicated: &[[f32; 4]],
        cell_means: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>> {
        self.probes()
            .run_probe_with(selector, inputs, frame, replicated, cell_means)
    }

    /// [`crate::probe::Probes::run_scene_probe`] on this context.
    pub fn run_scene_probe(
        &mut self,
        scene: &crate::GpuScene,
        selector: u32,
        inputs: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>> {
        self.probes().run_scene_probe(scene, selector, inputs)
    }

    /// Checks a buffer bound as a storage buffer against the device limits ([`Device::check_size`]).
    pub fn check_size(&self, what: &str, bytes: u64) -> Result<()> {
        self.device.check_size(what, bytes)
    }
}

impl Drop for VulkanContext {
    fn drop(&mut self) {
        // SAFETY: waiting for the device makes every object the fields hold unused before they drop
        // (in declaration order: the swapchain before the surface, which goes with the instance).
        unsafe {
            let _ = self.device.shared.device.device_wait_idle();
        }
    }
}
