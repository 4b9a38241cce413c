//! The kernel's `probe` entry point on the device: evaluates one core function per item (selectors and
//! record layouts: `fovea_core::kernel_abi::PROBE_*`), so the cross-backend tests can compare single
//! functions compiled to SPIR-V with the same functions compiled for the CPU (`kernel_abi::probe_eval`).
//!
//! A probe owns its buffers and its own descriptor set (same layout as the frame's), so it never
//! disturbs the buffers of the last frame.
use ash::vk;
use gpu_allocator::MemoryLocation;

use fovea_core::integrator::FrameParams;
use fovea_core::kernel_abi::{
    KernelPushConstants, BINDING_CELL_MEANS, BINDING_FRAME, BINDING_PROBE_INPUT,
    BINDING_PROBE_OUTPUT, BINDING_REPLICATED, PROBE_INPUT_RECORDS, PROBE_OUTPUT_RECORDS,
};

use crate::buffer::GpuBuffer;
use crate::context::CHUNK_TIMEOUT;
use crate::device::Device;
use crate::error::{Result, VkContext, VulkanError};
use crate::kernel::create_compute_pipelines;
use crate::kernel::Kernel;
use crate::scene::GpuScene;
use crate::spirv;

pub use crate::spirv::{PROBE_ENTRY_POINT, PROBE_SCENE_ENTRY_POINT};

/// Which probe entry point a dispatch runs (index into `Kernel::probe_pipelines`).
#[derive(Clone, Copy)]
enum ProbeEntry {
    Functions = 0,
    Scene = 1,
}

impl ProbeEntry {
    fn name(self) -> &'static str {
        match self {
            Self::Functions => PROBE_ENTRY_POINT,
            Self::Scene => PROBE_SCENE_ENTRY_POINT,
        }
    }
}

/// The probe entry points on a device's kernel ([`crate::VulkanContext::probes`]): the CPU/GPU probe
/// tables run core's functions through them.
pub struct Probes<'a> {
    pub(crate) device: &'a mut Device,
    pub(crate) kernel: &'a mut Kernel,
}

impl Probes<'_> {
    /// Runs the `probe` entry point with `selector` over `inputs.len() / PROBE_INPUT_RECORDS` items
    /// (item `i` reads `inputs[8 i .. 8 i + 8]`) and returns `PROBE_OUTPUT_RECORDS` records per item.
    /// The frame parameters are zero and the images empty (see [`Self::run_probe_with`]).
    pub fn run_probe(&mut self, selector: u32, inputs: &[[f32; 4]]) -> Result<Vec<[f32; 4]>> {
        let frame: FrameParams = bytemuck::Zeroable::zeroed();
        self.run_probe_with(selector, inputs, &frame, &[], &[])
    }

    /// [`Self::run_probe`] with the frame parameters (`PROBE_OWNING_BLOCK`, `PROBE_CELL_MEAN`,
    /// `PROBE_FILL_PIXEL`), the replicated image and the cell means those selectors read.
    pub fn run_probe_with(
        &mut self,
        selector: u32,
        inputs: &[[f32; 4]],
        frame: &FrameParams,
        replicated: &[[f32; 4]],
        cell_means: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>> {
        self.device.check_usable()?;
        self.kernel.check_kernel()?;
        let record = std::mem::size_of::<[f32; 4]>() as u64;
        for (what, n) in [
            ("the probe image", replicated.len()),
            ("the probe cell means", cell_means.len()),
        ] {
            self.device.check_size(what, n as u64 * record)?;
        }
        let host_buffer = |what: &str, data: &[u8]| -> Result<GpuBuffer> {
            let mut b = GpuBuffer::new(
                &self.device.shared,
                what,
                data.len() as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::CpuToGpu,
            )?;
            b.write(data)?;
            Ok(b)
        };
        let replicated_buf = host_buffer("probe image", bytemuck::cast_slice(replicated))?;
        let cell_means_buf = host_buffer("probe cell means", bytemuck::cast_slice(cell_means))?;
        let frame_buf = host_buffer("probe frame parameters", bytemuck::bytes_of(frame))?;
        let extra = [
            (BINDING_REPLICATED, whole(&replicated_buf)),
            (BINDING_CELL_MEANS, whole(&cell_means_buf)),
            (BINDING_FRAME, whole(&frame_buf)),
        ];
        self.dispatch_probe(ProbeEntry::Functions, selector, inputs, &extra, None)
    }

    /// Runs the `probe_scene` entry point with `selector` (a `PROBE_SCENE_*` selector) over `scene`, with
    /// the record layout of [`Self::run_probe`]. The scene must have been uploaded to this context.
    pub fn run_scene_probe(
        &mut self,
        scene: &GpuScene,
        selector: u32,
        inputs: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>> {
        self.device.check_usable()?;
        self.kernel.check_kernel()?;
        scene.check_uploaded_to(&self.device.shared)?;
        let extra = scene.buffer_infos();
        self.dispatch_probe(
            ProbeEntry::Scene,
            selector,
            inputs,
            &extra,
            Some(scene.texel_view()),
        )
    }

    /// Dispatches one probe entry point over `inputs` with its own descriptor set: the inputs and
    /// outputs plus `extra` bindings (binding, descriptor) and, for the scene probe, the scene texel
    /// buffer; returns the output records.
    fn dispatch_probe(
        &mut self,
        entry: ProbeEntry,
        selector: u32,
        inputs: &[[f32; 4]],
        extra: &[(u32, vk::DescriptorBufferInfo)],
        scene_texels: Option<vk::BufferView>,
    ) -> Result<Vec<[f32; 4]>> {
        let stride = PROBE_INPUT_RECORDS as usize;
        if !inputs.len().is_multiple_of(stride) {
            return Err(VulkanError::Invalid(format!(
                "probe inputs must be a multiple of {stride} records, got {}",
                inputs.len()
            )));
        }
        let items = inputs.len() / stride;
        if items == 0 {
            return Ok(Vec::new());
        }
        let item_count = u32::try_from(items)
            .map_err(|_| VulkanError::Invalid(format!("{items} probe items are too many")))?;
        let out_records = items * PROBE_OUTPUT_RECORDS as usize;
        let record = std::mem::size_of::<[f32; 4]>() as u64;
        for (what, n) in [
            ("the probe inputs", inputs.len()),
            ("the probe outputs", out_records),
        ] {
            self.device.check_size(what, n as u64 * record)?;
        }
        let pipeline = self.probe_pipeline(entry)?;

        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let mut input_buf = GpuBuffer::new(
            &self.device.shared,
            "probe inputs",
            inputs.len() as u64 * record,
            storage,
            MemoryLocation::CpuToGpu,
        )?;
        input_buf.write(inputs)?;
        let mut output_buf = GpuBuffer::new(
            &self.device.shared,
            "probe outputs",
            out_records as u64 * record,
            storage,
            MemoryLocation::GpuToCpu,
        )?;

        let set = ProbeSet::new(self.device, self.kernel)?;
        let mut bindings = vec![
            (BINDING_PROBE_INPUT, whole(&input_buf)),
            (BINDING_PROBE_OUTPUT, whole(&output_buf)),
        ];
        bindings.extend_from_slice(extra);
        let scene_texels: Vec<[vk::BufferView; 1]> =
            scene_texels.into_iter().map(|v| [v]).collect();
        let writes: Vec<vk::WriteDescriptorSet> = bindings
            .iter()
            .map(|(binding, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set.set)
                    .dst_binding(*binding)
                    .descriptor_type(crate::kernel::descriptor_type(*binding))
                    .buffer_info(std::slice::from_ref(info))
            })
            .chain(
                scene_texels
                    .iter()
                    .map(|v| crate::frame::scene_texels_write(set.set, v)),
            )
            .collect();
        // SAFETY: the set is new and unused; every buffer and view is alive.
        unsafe {
            self.device
                .shared
                .device
                .update_descriptor_sets(&writes, &[])
        };

        let pc = KernelPushConstants {
            block_count: 0,
            spp: selector,
            item_count,
            fill_mode: 0,
            exposure_ev: 0.0,
            pass: 0,
            flags: 0,
            _pad: 0,
        };
        let layout = self.kernel.pipeline_layout;
        let max_x = self.device.limits.max_workgroup_count_x;
        let descriptor_set = set.set;
        self.device
            .submit_and_wait("a probe", CHUNK_TIMEOUT, |device, cb| {
                crate::frame::record_dispatch(
                    device,
                    cb,
                    pipeline,
                    layout,
                    descriptor_set,
                    0,
                    &pc,
                    items as u64,
                    max_x,
                );
                // SAFETY: the barrier makes the shader writes visible to the mapped read after the fence.
                unsafe {
                    let to_host = [vk::MemoryBarrier::default()
                        .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                        .dst_access_mask(vk::AccessFlags::HOST_READ)];
                    device.cmd_pipeline_barrier(
                        cb,
                        vk::PipelineStageFlags::COMPUTE_SHADER,
                        vk::PipelineStageFlags::HOST,
                        vk::DependencyFlags::empty(),
                        &to_host,
                        &[],
                        &[],
                    );
                }
            })?;
        drop(set);
        output_buf.read::<[f32; 4]>(out_records)
    }

    /// The pipeline of a probe entry point, created on first use (the frame's pipelines do not include
    /// them).
    fn probe_pipeline(&mut self, entry: ProbeEntry) -> Result<vk::Pipeline> {
        let slot = entry as usize;
        if self.kernel.probe_pipelines[slot] != vk::Pipeline::null() {
            return Ok(self.kernel.probe_pipelines[slot]);
        }
        let code = spirv::load_kernel()?;
        let info = spirv::module_info(&code);
        let entry_name = entry.name();
        if !info.entry_points.iter().any(|e| e == entry_name) {
            return Err(VulkanError::KernelNotBuilt(format!(
                "the SPIR-V module has no entry point '{entry_name}' (it has {:?})",
                info.entry_points
            )));
        }
        let device = &self.device.shared.device;
        let name = std::ffi::CString::new(entry_name).expect("no NUL in the name");
        let create = [vk::ComputePipelineCreateInfo::default()
            .stage(
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::COMPUTE)
                    .module(self.kernel.module)
                    .name(&name),
            )
            .layout(self.kernel.pipeline_layout)];
        // SAFETY: the create info points at the context's live module, layout and `name`, all valid until
        // the call returns.
        self.kernel.probe_pipelines[slot] =
            unsafe { create_compute_pipelines(device, &create)? }[0];
        Ok(self.kernel.probe_pipelines[slot])
    }
}

/// A descriptor for the whole of `buffer`.
fn whole(buffer: &GpuBuffer) -> vk::DescriptorBufferInfo {
    vk::DescriptorBufferInfo::default()
        .buffer(buffer.buffer)
        .offset(0)
        .range(vk::WHOLE_SIZE)
}

/// A descriptor pool with one set of the kernel's layout, destroyed on drop.
struct ProbeSet {
    device: ash::Device,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
}

impl ProbeSet {
    fn new(owner: &Device, kernel: &Kernel) -> Result<Self> {
        let device = owner.shared.device.clone();
        let sizes = crate::kernel::descriptor_pool_sizes();
        // SAFETY: valid create info.
        let pool = unsafe {
            device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(1)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .during("vkCreateDescriptorPool")?;
        let layouts = [kernel.set_layout];
        // SAFETY: the pool has room for one set of this layout.
        let set = unsafe {
            device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(pool)
                    .set_layouts(&layouts),
            )
        };
        match set {
            Ok(s) => Ok(Self {
                device,
                pool,
                set: s[0],
            }),
            Err(r) => {
                // SAFETY: the pool is unused.
                unsafe { device.destroy_descriptor_pool(pool, None) };
                Err(VulkanError::vk("vkAllocateDescriptorSets", r))
            }
        }
    }
}

impl Drop for ProbeSet {
    fn drop(&mut self) {
        // SAFETY: every submission using the set was waited on before the set is dropped (or the
        // context is poisoned after a timeout, where nothing better can be done).
        unsafe { self.device.destroy_descriptor_pool(self.pool, None) };
    }
}
