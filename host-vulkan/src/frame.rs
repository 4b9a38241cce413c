//! Rendering one frame on the device: the same passes as the CPU host (samples, cell means, fill and,
//! with temporal reuse, G-buffer, temporal and the history's resolve) plus the tone map, as dispatches
//! of the kernel's entry points.
use std::time::Instant;

use ash::vk;

use fovea_core::denoise::DenoiseTexel;
use fovea_core::foveation::fill::cell_buffer_len;
use fovea_core::foveation::regions::FOVEATION_OK;
use fovea_core::integrator::FrameParams;
use fovea_core::kernel_abi::*;
use fovea_core::passes::{frame_passes, FramePass, PassItems};
pub use fovea_core::passes::{FrameOutput, FrameRequest};
use fovea_core::temporal::{GBufferTexel, HistoryTexel, TemporalParams};
use fovea_frame::{FrameImage, RenderStats, RenderedFrame};

use crate::barrier::memory_barrier;
use crate::blocks::{
    block_buffer_contents, enumerate_blocks, plan_chunks, workgroups_2d, ChunkPlan,
};
use crate::buffer::GpuBuffer;
use crate::context::{VulkanContext, CHUNK_TIMEOUT, WARMUP_TIMEOUT};
use crate::error::{Result, VulkanError};
use crate::resources::{FrameResources, Sizes, TemporalBuffers, PIXEL};
use crate::scene::GpuScene;
use crate::timestamps;

/// What a GPU frame cost: the CPU host's statistics plus how the work was split.
#[derive(Clone, Debug, Default)]
pub struct GpuRenderStats {
    /// `render_ms` covers everything from the first dispatch to the end of the readback copies (not the
    /// first frame's warm-up, [`Self::warmup_ms`]).
    pub render: RenderStats,
    /// `render_samples` invocations with no sample to render (each chunk's last workgroup).
    pub idle_invocations: u64,
    /// `render_samples` + `reduce_blocks` pairs.
    pub chunks: u32,
    /// Queue submissions (one per chunk, plus one for the cell means, fill, tone map and readback).
    pub submissions: u32,
    /// Whether `render_ms` comes from GPU timestamps (else host wall time around the submissions).
    pub gpu_timestamps: bool,
    /// Host time to enumerate blocks and plan chunks.
    pub plan_ms: f64,
    /// Host wall time of the warm-up submission before the context's first frame: one empty workgroup
    /// per frame pipeline, which makes a driver that compiles shaders lazily (lavapipe: LLVM at the first
    /// dispatch) do so outside `render_ms`. Zero on later frames.
    pub warmup_ms: f64,
    /// With temporal reuse: the history held no previous frame (new buffers, a new size or a reset),
    /// so this frame started every pixel afresh.
    pub history_restarted: bool,
}

/// A frame planned and bound, ready for [`VulkanContext::dispatch_frame`].
struct PreparedFrame {
    plan: ChunkPlan,
    sizes: Sizes,
    blocks_per_region: [u64; 3],
    plan_ms: f64,
    warmup_ms: f64,
    /// With temporal reuse: the history holds no previous frame (new buffers, a new size or a reset).
    history_is_new: bool,
}

impl PreparedFrame {
    fn stats(&self, scene: &GpuScene, timing: FrameTiming) -> GpuRenderStats {
        let FrameTiming {
            render_ms,
            gpu_timestamps,
            submissions,
            passes,
        } = timing;
        let samples_per_region = self.plan.samples_per_region();
        GpuRenderStats {
            render: RenderStats {
                render_ms,
                primary_samples: samples_per_region.iter().sum(),
                samples_per_region,
                blocks_per_region: self.blocks_per_region,
                path_features: scene.features.0,
                passes,
            },
            idle_invocations: self.plan.idle_invocations(),
            chunks: self.plan.chunks.len() as u32,
            submissions,
            gpu_timestamps,
            plan_ms: self.plan_ms,
            warmup_ms: self.warmup_ms,
            history_restarted: false,
        }
    }
}

/// What a frame's dispatches took.
struct FrameTiming {
    /// GPU time from the first dispatch to the end (host wall time where the device has no
    /// timestamps).
    render_ms: f64,
    gpu_timestamps: bool,
    submissions: u32,
    /// Each pass's GPU milliseconds (named by [`FramePass::name`], then `read_back`), empty
    /// without timestamps.
    passes: Vec<(&'static str, f64)>,
}

/// The pipelines (indices into [`VulkanContext::pipelines`]) that run `pass`, in dispatch order: those
/// of its [`FramePass::kernel_entries`], by their place in core's one list of entries.
#[must_use]
pub(crate) const fn pass_pipelines(pass: FramePass) -> std::ops::Range<usize> {
    pass.kernel_entry_range()
}

/// Which images a frame copies back to the host: (the 8-bit one, the HDR one).
fn read_back(output: FrameOutput) -> (bool, bool) {
    match output {
        FrameOutput::Hdr => (false, true),
        FrameOutput::ReadBack { want_hdr, .. } => (true, want_hdr),
        FrameOutput::Present { .. } => (false, false),
    }
}

/// Records one compute dispatch over `items` invocations: binds `pipeline` and `set` (with the one dynamic
/// offset the layout has), pushes `pc` and dispatches enough workgroups (2D above the x limit). Frames,
/// the warm-up and probes all record through this.
#[allow(clippy::too_many_arguments)]
pub(crate) fn record_dispatch(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    set: vk::DescriptorSet,
    dynamic_offset: u32,
    pc: &KernelPushConstants,
    items: u64,
    max_workgroups_x: u32,
) {
    let [x, y] = workgroups_2d(items, max_workgroups_x);
    // SAFETY: valid pipeline, layout and set, one dynamic offset for the one dynamic binding, and a
    // push-constant range that matches the layout's.
    unsafe {
        device.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, pipeline);
        device.cmd_bind_descriptor_sets(
            cb,
            vk::PipelineBindPoint::COMPUTE,
            layout,
            0,
            &[set],
            &[dynamic_offset],
        );
        device.cmd_push_constants(
            cb,
            layout,
            vk::ShaderStageFlags::COMPUTE,
            0,
            bytemuck::bytes_of(pc),
        );
        device.cmd_dispatch(cb, x, y, 1);
    }
}

/// Makes the transfer writes before it visible to host reads after the submission's fence.
fn host_read_barrier(device: &ash::Device, cb: vk::CommandBuffer) {
    memory_barrier(
        device,
        cb,
        (
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
        ),
        (vk::PipelineStageFlags::HOST, vk::AccessFlags::HOST_READ),
    );
}

/// A buffer handle with its size in bytes, as [`record_copy`] takes it.
type SizedBuffer = (vk::Buffer, u64);

/// Records a copy of the first `bytes` bytes of `src` into `dst`; the caller orders it against the
/// passes around it with barriers. Panics if either buffer is smaller than `bytes`.
fn record_copy(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    src: SizedBuffer,
    dst: SizedBuffer,
    bytes: u64,
) {
    assert!(
        bytes <= src.1 && bytes <= dst.1,
        "a copy past a buffer's end"
    );
    // SAFETY: both buffers hold at least `bytes` bytes (checked above) and outlive the submission
    // the command buffer belongs to, which the caller waits for.
    unsafe {
        device.cmd_copy_buffer(cb, src.0, dst.0, &[vk::BufferCopy::default().size(bytes)]);
    }
}

/// The descriptor write of the scene texel buffer (`BINDING_SCENE_TEXELS`) of `set`.
pub(crate) fn scene_texels_write<'a>(
    set: vk::DescriptorSet,
    view: &'a [vk::BufferView; 1],
) -> vk::WriteDescriptorSet<'a> {
    vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(fovea_core::kernel_abi::BINDING_SCENE_TEXELS)
        .descriptor_type(vk::DescriptorType::STORAGE_TEXEL_BUFFER)
        .texel_buffer_view(view)
}

/// A memory barrier after a dispatch: its writes (and reads, for buffers reused next) before the next
/// dispatch (`COMPUTE_SHADER`) or the readback copies (`TRANSFER`).
fn barrier(device: &ash::Device, cb: vk::CommandBuffer, dst_stage: vk::PipelineStageFlags) {
    let dst_access = if dst_stage == vk::PipelineStageFlags::TRANSFER {
        vk::AccessFlags::TRANSFER_READ
    } else {
        vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE
    };
    memory_barrier(
        device,
        cb,
        (
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::SHADER_READ,
        ),
        (dst_stage, dst_access),
    );
}

impl VulkanContext {
    /// Uploads `packed` (see [`GpuScene::upload`]).
    pub fn upload_scene(&mut self, packed: &fovea_scene::pack::PackedScene) -> Result<GpuScene> {
        GpuScene::upload(self, packed)
    }

    /// Renders one frame of `scene` (see [`Self::render_frame_with_progress`]).
    pub fn render_frame(
        &mut self,
        scene: &GpuScene,
        frame: &FrameParams,
        fill_mode: u32,
        exposure_ev: f32,
        want_hdr: bool,
    ) -> Result<(RenderedFrame, GpuRenderStats)> {
        self.render_frame_with_progress(scene, frame, fill_mode, exposure_ev, want_hdr, &|_| {})
    }

    /// Renders one frame: enumerates the blocks on the host, dispatches `render_samples` and
    /// `reduce_blocks` per chunk (one submission each, each waited on with a timeout), then `cell_means`,
    /// `fill`, `tonemap` and the readback. `progress` receives the samples of each finished chunk.
    pub fn render_frame_with_progress(
        &mut self,
        scene: &GpuScene,
        frame: &FrameParams,
        fill_mode: u32,
        exposure_ev: f32,
        want_hdr: bool,
        progress: &dyn Fn(u64),
    ) -> Result<(RenderedFrame, GpuRenderStats)> {
        self.render_frame_and_history(
            scene,
            frame,
            fill_mode,
            exposure_ev,
            want_hdr,
            false,
            progress,
        )
    }

    /// Forgets the history of every view: the next frame with temporal reuse starts every pixel
    /// afresh.
    pub fn reset_history(&mut self) {
        let parked = self.parked_views.iter_mut().map(|p| &mut p.frame);
        for frame in std::iter::once(&mut self.frame).chain(parked) {
            if let Some(t) = frame.as_mut().and_then(|f| f.temporal.as_mut()) {
                t.previous = None;
            }
        }
    }

    /// Makes `view`'s buffers (its history, G-buffer and per-frame buffers) the ones the passes
    /// use, parking the active view's.
    fn select_view(&mut self, view: u32) -> Result<()> {
        if view >= fovea_core::passes::MAX_VIEWS {
            return Err(VulkanError::Invalid(format!(
                "view {view}: a frame holds at most {} views",
                fovea_core::passes::MAX_VIEWS
            )));
        }
        if view == self.active_view {
            return Ok(());
        }
        let needed = view.max(self.active_view) as usize + 1;
        if self.parked_views.len() < needed {
            self.parked_views
                .resize_with(needed, crate::resources::ParkedView::default);
        }
        self.parked_views[self.active_view as usize] = crate::resources::ParkedView {
            frame: self.frame.take(),
            size: self.last_frame_size.take(),
        };
        let chosen = std::mem::take(&mut self.parked_views[view as usize]);
        self.frame = chosen.frame;
        self.last_frame_size = chosen.size;
        self.active_view = view;
        Ok(())
    }

    /// [`Self::render_frame_with_progress`], with temporal reuse where `history` holds (see
    /// [`FrameRequest::history`]); the images read back are then the history's mean.
    #[allow(clippy::too_many_arguments)]
    pub fn render_frame_and_history(
        &mut self,
        scene: &GpuScene,
        frame: &FrameParams,
        fill_mode: u32,
        exposure_ev: f32,
        want_hdr: bool,
        history: bool,
        progress: &dyn Fn(u64),
    ) -> Result<(RenderedFrame, GpuRenderStats)> {
        let output = FrameOutput::ReadBack {
            want_hdr,
            want_raw: false,
        };
        let request = FrameRequest::new(fill_mode, exposure_ev, history, false, output);
        self.render(scene, frame, &request, progress)
    }

    /// Renders one frame: plans its blocks on the host, then runs core's pass list
    /// ([`fovea_core::passes::frame_passes`] for [`FrameRequest::setup`]) as dispatches of the kernel's
    /// entry points: `render_samples` and `reduce_blocks` per chunk (one submission each, each waited
    /// on with a timeout), then one submission for every later pass and the read-back.
    /// `progress` receives the samples of each finished chunk.
    ///
    /// With [`FrameOutput::Hdr`] only the HDR image is read back (`rgba8` is `None`); with
    /// [`FrameOutput::Present`] nothing is (`rgba8` is `None`): [`Self::present`] shows the
    /// image and [`Self::read_back_hdr`] fetches its HDR for a screenshot.
    pub fn render(
        &mut self,
        scene: &GpuScene,
        frame: &FrameParams,
        request: &FrameRequest,
        progress: &dyn Fn(u64),
    ) -> Result<(RenderedFrame, GpuRenderStats)> {
        self.select_view(request.view)?;
        let prepared = self.prepare_frame(scene, frame, request)?;
        let timing = self.dispatch_frame(&prepared.plan, &prepared.sizes, request, progress)?;
        if request.history {
            self.history_advanced(frame);
        }
        let mut stats = prepared.stats(scene, timing);
        stats.history_restarted = request.history && prepared.history_is_new;

        let pixels = prepared.sizes.pixels as usize;
        let (w, h) = (frame.width, frame.height);
        let res = self.frame.as_mut().expect("frame resources exist");
        let (want_ldr, want_hdr) = read_back(request.output);
        let rgba8 = if want_ldr {
            Some(res.ldr_readback.read::<u32>(pixels)?)
        } else {
            None
        };
        let hdr = if want_hdr {
            Some(FrameImage {
                width: w,
                height: h,
                pixels: res.hdr_readback.read::<[f32; 4]>(pixels)?,
            })
        } else {
            None
        };
        let raw_hdr = match (
            &mut res.raw_readback,
            request.denoise && request.output.wants_raw(),
        ) {
            (Some(raw), true) => Some(FrameImage {
                width: w,
                height: h,
                pixels: raw.read::<[f32; 4]>(pixels)?,
            }),
            _ => None,
        };
        Ok((
            RenderedFrame {
                width: w,
                height: h,
                hdr,
                rgba8,
                raw_hdr,
            },
            stats,
        ))
    }

    /// After a frame with temporal reuse: its history and G-buffer become the previous ones.
    fn history_advanced(&mut self, frame: &FrameParams) {
        if let Some(t) = self.frame.as_mut().and_then(|f| f.temporal.as_mut()) {
            t.previous = Some((frame.camera, [frame.width, frame.height]));
            t.current = 1 - t.current;
        }
    }

    /// The HDR image of the last frame (with the live view, the running mean), copied to the host.
    pub fn read_back_hdr(&mut self) -> Result<FrameImage> {
        let (w, h) = self
            .last_frame_size
            .ok_or_else(|| VulkanError::Invalid("no frame has been rendered yet".into()))?;
        let pixels = u64::from(w) * u64::from(h);
        let res = self.frame.as_ref().expect("a rendered frame has resources");
        let src = (res.replicated.buffer, res.replicated.size);
        let dst = (res.hdr_readback.buffer, res.hdr_readback.size);
        self.device
            .submit_and_wait("the HDR read-back", CHUNK_TIMEOUT, |device, cb| {
                barrier(device, cb, vk::PipelineStageFlags::TRANSFER);
                record_copy(device, cb, src, dst, pixels * PIXEL);
                // The host barrier makes the copy visible to the mapped read after the fence.
                host_read_barrier(device, cb);
            })?;
        let res = self.frame.as_mut().expect("a rendered frame has resources");
        Ok(FrameImage {
            width: w,
            height: h,
            pixels: res.hdr_readback.read::<[f32; 4]>(pixels as usize)?,
        })
    }

    /// The device buffer holding the last frame's RGBA8 image (what the swapchain copy reads).
    pub(crate) fn last_ldr_buffer(&self) -> Option<(vk::Buffer, u32, u32)> {
        let (w, h) = self.last_frame_size?;
        self.frame.as_ref().map(|f| (f.ldr.buffer, w, h))
    }

    /// Checks the frame, plans its blocks and chunks, makes sure the frame's buffers fit (with
    /// `temporal`, also the history and G-buffers, and writes the temporal parameters) and point the
    /// bindings at them, specialises and warms up the pipelines.
    fn prepare_frame(
        &mut self,
        scene: &GpuScene,
        frame: &FrameParams,
        request: &FrameRequest,
    ) -> Result<PreparedFrame> {
        let (temporal, denoise) = (request.history, request.denoise);
        self.device.check_usable()?;
        self.kernel.check_kernel()?;
        scene.check_uploaded_to(&self.device.shared)?;
        let (w, h) = (frame.width, frame.height);
        if w == 0 || h == 0 {
            return Err(VulkanError::Invalid("the image is empty".into()));
        }
        if frame.foveation.validate() != FOVEATION_OK {
            return Err(VulkanError::Invalid(
                "inconsistent foveation parameters".into(),
            ));
        }
        let plan_start = Instant::now();
        let fov = &frame.foveation;
        let blocks = enumerate_blocks(w, h, fov);
        let align_blocks = self
            .device
            .limits
            .min_storage_buffer_offset_alignment
            .div_ceil(16)
            .max(1);
        // Offsets must be multiples of the alignment; a 16-byte block list works when the alignment is a
        // power of two (Vulkan requires that).
        let plan = plan_chunks(
            &blocks,
            [fov.spp[0], fov.spp[1], fov.spp[2]],
            self.max_chunk_samples.max(1),
            align_blocks,
        );
        let block_data = block_buffer_contents(&blocks, &plan);
        let pixels = u64::from(w) * u64::from(h);
        let cells = u64::from(cell_buffer_len(w, h, fov));
        let sizes = Sizes {
            pixels,
            cells,
            block_buffer: plan.block_buffer_len,
            chunk_blocks: u64::from(plan.max_chunk_blocks.max(1)),
            chunk_samples: plan.max_chunk_samples.max(1),
        };
        let plan_ms = plan_start.elapsed().as_secs_f64() * 1e3;

        if self.last_frame_size != Some((w, h)) {
            // A history of another image size is not this image's.
            if let Some(res) = self.frame.as_mut() {
                res.drop_image_buffers();
            }
        }
        if !self.frame.as_ref().is_some_and(|f| sizes.fits_in(&f.sizes)) {
            // A moving gaze changes the block and cell counts, so the per-frame buffers grow now and
            // then; the image's own buffers (the history above all) carry over. The old buffers are
            // freed before the new ones are made.
            let kept = self.frame.take().map(FrameResources::into_image_buffers);
            let mut res = FrameResources::new(&self.device.shared, &self.device.limits, sizes)?;
            if let Some(kept) = kept {
                res.restore_image_buffers(kept);
            }
            self.frame = Some(res);
        }
        self.last_frame_size = Some((w, h));
        let mut history_is_new = false;
        {
            let res = self
                .frame
                .as_mut()
                .expect("frame resources were just created");
            if (temporal || denoise) && res.temporal.is_none() {
                res.temporal = Some(TemporalBuffers::new(
                    &self.device.shared,
                    &self.device.limits,
                    pixels,
                )?);
            }
            if denoise && request.output.wants_raw() && res.raw_readback.is_none() {
                res.raw_readback = Some(GpuBuffer::new(
                    &self.device.shared,
                    "raw HDR readback",
                    pixels * PIXEL,
                    vk::BufferUsageFlags::TRANSFER_DST,
                    gpu_allocator::MemoryLocation::GpuToCpu,
                )?);
            }
            if temporal {
                let t = res.temporal.as_mut().expect("just created");
                history_is_new = t.previous.is_none();
                t.params
                    .write(&[TemporalParams::after(t.previous, frame, request.fill_mode)])?;
            }
            res.frame.write(&[*frame])?;
            res.blocks.write(&block_data)?;
        }
        self.write_descriptors(scene, &sizes);
        self.kernel.specialize_render_pipeline(scene.features.0)?;
        let start = Instant::now();
        let cold: Vec<usize> = frame_passes(request.setup())
            .flat_map(pass_pipelines)
            .filter(|&p| !self.kernel.warmed[p])
            .collect();
        self.warm_up(&cold)?;
        let warmup_ms = start.elapsed().as_secs_f64() * 1e3;

        Ok(PreparedFrame {
            blocks_per_region: [
                blocks[0].len() as u64,
                blocks[1].len() as u64,
                blocks[2].len() as u64,
            ],
            plan,
            sizes,
            plan_ms,
            warmup_ms,
            history_is_new,
        })
    }

    /// Points every binding at this frame's buffers (nothing is in flight: every submission was waited
    /// on).
    fn write_descriptors(&mut self, scene: &GpuScene, sizes: &Sizes) {
        let res = self.frame.as_ref().expect("frame resources exist");
        let mut infos = scene.buffer_infos();
        let frame_buffers = [
            (BINDING_BLOCKS, &res.blocks, sizes.chunk_blocks * 16),
            (BINDING_SAMPLES, &res.samples, sizes.chunk_samples * PIXEL),
            (BINDING_REPLICATED, &res.replicated, sizes.pixels * PIXEL),
            (
                BINDING_PIXEL_SAMPLES,
                &res.pixel_samples,
                sizes.pixels * PIXEL,
            ),
            (
                BINDING_CELL_MEANS,
                &res.cell_means,
                sizes.cells.max(1) * PIXEL,
            ),
            // The fill writes the HDR image over the replicated one, in place.
            (BINDING_HDR, &res.replicated, sizes.pixels * PIXEL),
            (BINDING_LDR, &res.ldr, sizes.pixels * 4),
            (
                BINDING_FRAME,
                &res.frame,
                std::mem::size_of::<FrameParams>() as u64,
            ),
        ];
        // Temporal reuse's buffers: this frame writes `[current]` and reads `[1 - current]`. Only frames
        // with temporal reuse (which create them) dispatch the passes that read them; until then the
        // bindings point at the cell means, so that every binding is valid.
        let placeholder = (&res.cell_means, sizes.cells.max(1) * PIXEL);
        let history_bytes = sizes.pixels * std::mem::size_of::<HistoryTexel>() as u64;
        let gbuffer_bytes = sizes.pixels * std::mem::size_of::<GBufferTexel>() as u64;
        let denoise_bytes = 2 * sizes.pixels * std::mem::size_of::<DenoiseTexel>() as u64;
        let temporal_buffers: [(u32, (&GpuBuffer, u64)); 6] = match &res.temporal {
            Some(t) => {
                let (now, before) = (t.current, 1 - t.current);
                [
                    (BINDING_HISTORY, (&t.history[now], history_bytes)),
                    (
                        BINDING_PREVIOUS_HISTORY,
                        (&t.history[before], history_bytes),
                    ),
                    (BINDING_GBUFFER, (&t.gbuffer[now], gbuffer_bytes)),
                    (
                        BINDING_PREVIOUS_GBUFFER,
                        (&t.gbuffer[before], gbuffer_bytes),
                    ),
                    (
                        BINDING_TEMPORAL,
                        (&t.params, std::mem::size_of::<TemporalParams>() as u64),
                    ),
                    (BINDING_DENOISE, (&t.denoise, denoise_bytes)),
                ]
            }
            None => [
                (BINDING_HISTORY, placeholder),
                (BINDING_PREVIOUS_HISTORY, placeholder),
                (BINDING_GBUFFER, placeholder),
                (BINDING_PREVIOUS_GBUFFER, placeholder),
                (BINDING_TEMPORAL, placeholder),
                (BINDING_DENOISE, placeholder),
            ],
        };
        let frame_buffers = frame_buffers
            .into_iter()
            .chain(temporal_buffers.map(|(binding, (buf, range))| (binding, buf, range)));
        for (binding, buf, range) in frame_buffers {
            infos.push((
                binding,
                vk::DescriptorBufferInfo::default()
                    .buffer(buf.buffer)
                    .offset(0)
                    .range(range),
            ));
        }
        let scene_texels = [scene.texel_view()];
        let writes: Vec<vk::WriteDescriptorSet> = infos
            .iter()
            .map(|(binding, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.kernel.descriptor_set)
                    .dst_binding(*binding)
                    .descriptor_type(crate::kernel::descriptor_type(*binding))
                    .buffer_info(std::slice::from_ref(info))
            })
            .chain(std::iter::once(scene_texels_write(
                self.kernel.descriptor_set,
                &scene_texels,
            )))
            .collect();
        // SAFETY: the set is not in use by any pending command buffer, and every buffer and view is alive.
        unsafe {
            self.device
                .shared
                .device
                .update_descriptor_sets(&writes, &[])
        };
    }

    /// Creates the pipelines `which` (indices into the frame pipelines) if they do not exist yet, then
    /// dispatches one workgroup of each with zero items (each returns at once), so that a driver's lazy
    /// shader compilation happens here; one submission each, so
    /// that each compilation has the whole timeout (lavapipe compiles the general ray-query kernels for
    /// tens of seconds each). The descriptors must already point at live buffers.
    fn warm_up(&mut self, which: &[usize]) -> Result<()> {
        self.kernel.ensure_pipelines(which)?;
        let layout = self.kernel.pipeline_layout;
        let set = self.kernel.descriptor_set;
        let pc = KernelPushConstants {
            block_count: 0,
            spp: 0,
            item_count: 0,
            fill_mode: 0,
            exposure_ev: 0.0,
            pass: 0,
            flags: 0,
            _pad: 0,
        };
        let max_x = self.device.limits.max_workgroup_count_x;
        for &p in which {
            let pipeline = self.kernel.pipelines[p];
            self.device
                .submit_and_wait("the pipeline warm-up", WARMUP_TIMEOUT, |device, cb| {
                    // Zero counts make every invocation return at once.
                    record_dispatch(device, cb, pipeline, layout, set, 0, &pc, 1, max_x);
                    barrier(device, cb, vk::PipelineStageFlags::COMPUTE_SHADER);
                })?;
            self.kernel.warmed[p] = true;
        }
        Ok(())
    }

    /// Records and submits all dispatches of a frame, pass by pass from core's list; returns what they
    /// took.
    ///
    /// Long because it records one frame's dispatches in core's pass order, one arm per pass of an
    /// exhaustive match, between the chunks' submissions and the read-back.
    fn dispatch_frame(
        &mut self,
        plan: &ChunkPlan,
        sizes: &Sizes,
        request: &FrameRequest,
        progress: &dyn Fn(u64),
    ) -> Result<FrameTiming> {
        let layout = self.kernel.pipeline_layout;
        let set = self.kernel.descriptor_set;
        let pipelines = self.kernel.pipelines;
        let query_pool = self.device.query_pool;
        let max_x = self.device.limits.max_workgroup_count_x;
        let timed = query_pool != vk::QueryPool::null();
        let dispatch = move |device: &ash::Device,
                             cb: vk::CommandBuffer,
                             p: usize,
                             offset: u32,
                             pc: &KernelPushConstants,
                             items: u64| {
            record_dispatch(
                device,
                cb,
                pipelines[p],
                layout,
                set,
                offset,
                pc,
                items,
                max_x,
            );
        };
        let base = KernelPushConstants {
            block_count: 0,
            spp: 0,
            item_count: 0,
            fill_mode: request.fill_mode,
            exposure_ev: request.exposure_ev,
            pass: 0,
            flags: 0,
            _pad: 0,
        };
        let passes: Vec<FramePass> = frame_passes(request.setup()).collect();
        let denoise_flags = request.denoise_flags();
        debug_assert_eq!(passes.first(), Some(&FramePass::Samples));

        let wall = Instant::now();
        let mut submissions = 0u32;
        // The samples pass: one submission per chunk, so that no submission runs long enough to trip a
        // driver's watchdog and the progress bar moves.
        let samples = pass_pipelines(FramePass::Samples);
        debug_assert_eq!(samples.len(), 2, "the samples pass is two dispatches");
        let (sample_pipeline, reduce_pipeline) = (samples.start, samples.start + 1);
        for (i, chunk) in plan.chunks.iter().enumerate() {
            let offset = ChunkPlan::block_offset(chunk) as u32;
            let pc = KernelPushConstants {
                block_count: chunk.block_count,
                spp: chunk.spp,
                ..base
            };
            let first = i == 0;
            let c = *chunk;
            self.device
                .submit_and_wait("a sample chunk", CHUNK_TIMEOUT, |device, cb| {
                    if first && timed {
                        timestamps::write_start(device, cb, query_pool);
                    }
                    dispatch(
                        device,
                        cb,
                        sample_pipeline,
                        offset,
                        &pc,
                        c.sample_invocations(),
                    );
                    barrier(device, cb, vk::PipelineStageFlags::COMPUTE_SHADER);
                    dispatch(
                        device,
                        cb,
                        reduce_pipeline,
                        offset,
                        &pc,
                        u64::from(c.block_count),
                    );
                    barrier(device, cb, vk::PipelineStageFlags::COMPUTE_SHADER);
                })?;
            submissions += 1;
            progress(chunk.samples());
        }

        // Every later pass, then the read-back, in one submission.
        let res = self.frame.as_ref().expect("frame resources exist");
        let sized = |b: &GpuBuffer| (b.buffer, b.size);
        let (ldr, ldr_rb, hdr, hdr_rb) = (
            sized(&res.ldr),
            sized(&res.ldr_readback),
            sized(&res.replicated),
            sized(&res.hdr_readback),
        );
        let raw_rb = res
            .raw_readback
            .as_ref()
            .filter(|_| request.output.wants_raw())
            .map(sized);
        let (pixels, cells) = (sizes.pixels, sizes.cells);
        let no_chunks = plan.chunks.is_empty();
        let output = request.output;
        self.device.submit_and_wait(
            "the passes after the samples",
            CHUNK_TIMEOUT,
            |device, cb| {
                if no_chunks && timed {
                    timestamps::write_start(device, cb, query_pool);
                }
                for &pass in &passes {
                    if let (FramePass::DenoiseInput, Some(raw_rb)) = (pass, raw_rb) {
                        // The image as the denoiser finds it, copied aside before its output pass
                        // overwrites it.
                        // The barriers order the copy after the passes that wrote the image and
                        // before the denoiser's output pass writes it again.
                        barrier(device, cb, vk::PipelineStageFlags::TRANSFER);
                        record_copy(device, cb, hdr, raw_rb, pixels * PIXEL);
                        memory_barrier(
                            device,
                            cb,
                            (
                                vk::PipelineStageFlags::TRANSFER,
                                vk::AccessFlags::TRANSFER_READ,
                            ),
                            (
                                vk::PipelineStageFlags::COMPUTE_SHADER,
                                vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
                            ),
                        );
                    }
                    // Each pass's items: its core function runs once per cell or per pixel.
                    let items = match pass.items() {
                        PassItems::BlockChunks => 0, // dispatched chunk by chunk above
                        PassItems::Cells => cells,
                        PassItems::Pixels => pixels,
                    };
                    if items > 0 {
                        // Step `k` of a repeated pass sees `pass: k`; the denoiser's output reads the
                        // half its last step wrote.
                        let first_pass = if pass == FramePass::DenoiseOutput {
                            FramePass::DenoiseAtrous.repeats()
                        } else {
                            0
                        };
                        for step in 0..pass.repeats() {
                            let pc = KernelPushConstants {
                                item_count: items as u32,
                                pass: first_pass + step,
                                flags: denoise_flags,
                                ..base
                            };
                            for p in pass_pipelines(pass) {
                                dispatch(device, cb, p, 0, &pc, items);
                                barrier(device, cb, vk::PipelineStageFlags::COMPUTE_SHADER);
                            }
                        }
                    }
                    if timed {
                        timestamps::write_after_pass(device, cb, query_pool, pass);
                    }
                }
                barrier(device, cb, vk::PipelineStageFlags::TRANSFER);
                // The host barrier makes the copies visible to the mapped reads after the fence.
                let (want_ldr, want_hdr) = read_back(output);
                if want_ldr {
                    record_copy(device, cb, ldr, ldr_rb, pixels * 4);
                }
                if want_hdr {
                    record_copy(device, cb, hdr, hdr_rb, pixels * PIXEL);
                }
                if want_ldr || want_hdr {
                    host_read_barrier(device, cb);
                }
                if timed {
                    timestamps::write_end(device, cb, query_pool);
                }
            },
        )?;
        submissions += 1;
        let wall_ms = wall.elapsed().as_secs_f64() * 1e3;

        if timed {
            let times = timestamps::read_frame(
                &self.device.shared.device,
                query_pool,
                &passes,
                read_back(output) != (false, false),
                self.device.timestamp_period,
                self.device.timestamp_mask,
            );
            if let Some((render_ms, passes)) = times {
                return Ok(FrameTiming {
                    render_ms,
                    gpu_timestamps: true,
                    submissions,
                    passes,
                });
            }
        }
        Ok(FrameTiming {
            render_ms: wall_ms,
            gpu_timestamps: false,
            submissions,
            passes: Vec::new(),
        })
    }
}
