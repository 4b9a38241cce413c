//! Choosing and driving a backend: the CPU host, or (with the `vulkan` feature) the Vulkan host.
use fovea_core::integrator::FrameParams;
use fovea_cpu::{FrameImage, RenderStats, RenderedFrame};
use fovea_scene::pack::PackedScene;

use crate::args::Backend;
use crate::error::{FoveaError, Result};
use crate::stats::cpu_device_name;

/// One rendered frame, as the backend produced it.
pub struct Rendered {
    /// Its images: linear HDR when asked for ([`FrameOutput::ReadBack`]'s `want_hdr`; the CPU has it
    /// anyway), the tone-mapped 8-bit one with [`FrameOutput::ReadBack`], and the HDR image before
    /// the denoiser (`want_raw`, with the denoiser). Nothing with [`FrameOutput::Present`]: the
    /// frame stays with the backend.
    pub image: RenderedFrame,
    pub stats: RenderStats,
    /// With history: this frame started every pixel's history afresh (the first frame, a reset, a
    /// new size).
    #[cfg_attr(not(feature = "vulkan"), allow(dead_code))]
    // the live view's, which needs Vulkan
    pub history_restarted: bool,
    /// Backend-specific figures for the stats JSON.
    pub extra: Option<serde_json::Value>,
}

/// How to render a frame and where it goes: core's one request, the same on every backend. With
/// [`FrameOutput::Present`] the backend keeps the frame for [`Renderer::presented_rgba8`] and
/// [`Renderer::last_hdr`]; with history it keeps each pixel's history ([`Renderer::reset_history`]
/// forgets it).
pub use fovea_core::passes::{FrameOutput, FrameRequest};

/// A ready backend: the one type `render`, `report` and `view` drive.
pub enum Renderer {
    Cpu(CpuRenderer),
    #[cfg(feature = "vulkan")]
    Vulkan(Box<VulkanRenderer>),
}

/// The CPU host's worker threads and whether it runs the scene's specialised path.
pub struct CpuRenderer {
    pool: rayon::ThreadPool,
    /// The features the CPU path is specialised for: the scene's, derived once in `set_scene`, or
    /// every feature (`--no-specialize`).
    features: fovea_core::scene::FeatureFlags,
    /// Each view's pixel histories, for frames rendered with temporal reuse (indexed by
    /// [`FrameRequest::view`], made on a view's first frame).
    histories: Vec<fovea_cpu::TemporalHistory>,
    /// The last frame rendered for the window ([`FrameOutput::Present`]).
    presented: Option<RenderedFrame>,
}

impl CpuRenderer {
    fn new(threads: Option<usize>) -> Result<Self> {
        Ok(Self {
            pool: cpu_pool(threads)?,
            features: fovea_core::scene::FeatureFlags::ALL,
            histories: Vec::new(),
            presented: None,
        })
    }
}

/// View `view`'s history among `histories` (see [`FrameRequest::view`]), made on its first frame.
fn view_history(
    histories: &mut Vec<fovea_cpu::TemporalHistory>,
    view: u32,
) -> Result<&mut fovea_cpu::TemporalHistory> {
    if view >= fovea_core::passes::MAX_VIEWS {
        return Err(FoveaError::Backend(format!(
            "view {view}: a frame holds at most {} views",
            fovea_core::passes::MAX_VIEWS
        )));
    }
    let index = view as usize;
    if histories.len() <= index {
        histories.resize_with(index + 1, fovea_cpu::TemporalHistory::new);
    }
    Ok(&mut histories[index])
}

/// The Vulkan context and the scene uploaded to it.
#[cfg(feature = "vulkan")]
pub struct VulkanRenderer {
    // Field order: the scene's buffers go before the context.
    scene: Option<fovea_vulkan::GpuScene>,
    ctx: fovea_vulkan::VulkanContext,
    upload_ms: f64,
}

/// Why `--backend auto` did not pick Vulkan, or `None` when it should.
#[cfg(feature = "vulkan")]
pub(crate) fn auto_vulkan_refusal() -> Option<String> {
    match fovea_vulkan::list_devices() {
        Err(e) => Some(e.to_string()),
        Ok(devices) => {
            let usable: Vec<_> = devices.iter().filter(|d| d.unsuitable.is_none()).collect();
            if usable.is_empty() {
                Some("no suitable Vulkan device".into())
            } else if usable.iter().all(|d| d.device_type == "cpu") {
                Some(format!(
                    "only a software Vulkan driver ({}), which is slower than the CPU host; --backend vulkan forces it",
                    usable[0].name
                ))
            } else {
                None
            }
        }
    }
}

/// The backend a part of a split render runs on (`render --samples`, `report --reference-part`): the CPU,
/// the one host that renders a range of samples. `auto` becomes `cpu`; a Vulkan choice (`--backend
/// vulkan`, `--device`, `--traversal hardware`) is refused, naming `option`.
pub fn cpu_target_for_parts(
    target: &crate::args::BackendArgs,
    option: &'static str,
) -> Result<crate::args::BackendArgs> {
    if target.backend == Backend::Vulkan
        || target.device.is_some()
        || target.traversal == crate::args::Traversal::Hardware
    {
        return Err(FoveaError::option(
            option,
            "renders on the CPU backend (--backend cpu or auto); the Vulkan host cannot render a \
             range of samples yet",
        ));
    }
    Ok(crate::args::BackendArgs {
        backend: Backend::Cpu,
        ..*target
    })
}

/// The CPU host's worker threads (`--threads`, default all cores).
pub fn cpu_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 || n > 1024 {
            return Err(FoveaError::option("--threads", "must be 1 to 1024"));
        }
        pool = pool.num_threads(n);
    }
    pool.build()
        .map_err(|e| FoveaError::Backend(format!("cannot start worker threads: {e}")))
}

impl Renderer {
    /// Sets up the backend `choice` asks for. `auto` uses Vulkan when a hardware device is available
    /// (or `--device` names one), else the CPU with a note on stderr (unless `quiet`).
    pub fn new(target: &crate::args::BackendArgs, quiet: bool) -> Result<Self> {
        let crate::args::BackendArgs {
            backend: choice,
            device,
            traversal,
            threads,
        } = *target;
        if choice == Backend::Cpu && traversal == crate::args::Traversal::Hardware {
            return Err(FoveaError::option(
                "--traversal",
                "hardware traversal runs on a Vulkan device; use it with --backend vulkan or auto",
            ));
        }
        if choice == Backend::Cpu && device.is_some() {
            return Err(FoveaError::option(
                "--device",
                "selects a Vulkan device; use it with --backend vulkan or auto",
            ));
        }
        let want_vulkan = match choice {
            Backend::Cpu => false,
            Backend::Vulkan => true,
            Backend::Auto => {
                if device.is_some() {
                    true
                } else {
                    match Self::auto_refusal() {
                        None => true,
                        Some(why) => {
                            if !quiet {
                                eprintln!("note: rendering on the CPU: {why}");
                            }
                            false
                        }
                    }
                }
            }
        };
        if !want_vulkan {
            return Ok(Self::Cpu(CpuRenderer::new(threads)?));
        }
        Self::vulkan(
            device,
            choice == Backend::Auto,
            traversal,
            threads,
            quiet,
            None,
        )
    }

    #[cfg(feature = "vulkan")]
    fn auto_refusal() -> Option<String> {
        auto_vulkan_refusal()
    }

    #[cfg(not(feature = "vulkan"))]
    fn auto_refusal() -> Option<String> {
        Some(
            "this build of fovea has no Vulkan backend (built without the `vulkan` feature)".into(),
        )
    }

    /// The live view's backend on `window`: the Vulkan device that presents renders too (`use_gpu`),
    /// or the CPU renders and a Vulkan context only presents (returned beside it).
    #[cfg(feature = "vulkan")]
    pub fn for_window(
        window: fovea_vulkan::WindowHandles,
        device: Option<usize>,
        traversal: crate::args::Traversal,
        use_gpu: bool,
        threads: Option<usize>,
    ) -> Result<(Self, Option<fovea_vulkan::VulkanContext>)> {
        if use_gpu {
            return Ok((
                Self::vulkan(device, false, traversal, threads, true, Some(window))?,
                None,
            ));
        }
        let options = fovea_vulkan::ContextOptions {
            device_index: device,
            validation: fovea_vulkan::validation_requested(),
            window: Some(window),
            // The CPU backend only presents: no kernel and no acceleration structures for it.
            traversal: fovea_vulkan::Traversal::Software,
            present_only: true,
            factory: None,
        };
        let presenter = fovea_vulkan::VulkanContext::new(&options).map_err(|e| {
            FoveaError::View(format!(
                "cannot present to the window through Vulkan: {e} (the view needs a Vulkan driver even \
                 with --backend cpu; lavapipe, Debian's mesa-vulkan-drivers, is enough)"
            ))
        })?;
        Ok((Self::Cpu(CpuRenderer::new(threads)?), Some(presenter)))
    }

    /// `fovea xr`'s backend, on the Vulkan device an OpenXR runtime makes through `factory`: it
    /// renders there (`use_gpu`: the Vulkan backend), or the CPU renders and a context on that device
    /// only copies its images into the headset's swapchain (returned beside it). The runtime chooses
    /// the device, so `--device` is refused.
    #[cfg(feature = "vulkan")]
    pub fn for_headset(
        factory: fovea_vulkan::factory::SharedFactory,
        target: &crate::args::BackendArgs,
    ) -> Result<(Self, Option<fovea_vulkan::VulkanContext>)> {
        if target.device.is_some() {
            return Err(FoveaError::option(
                "--device",
                "the OpenXR runtime chooses the Vulkan device of its headset",
            ));
        }
        let use_gpu = target.backend != Backend::Cpu;
        if !use_gpu && target.traversal == crate::args::Traversal::Hardware {
            return Err(FoveaError::option(
                "--traversal",
                "hardware traversal runs on a Vulkan device; use it with --backend vulkan or auto",
            ));
        }
        let options = fovea_vulkan::ContextOptions {
            device_index: None,
            validation: fovea_vulkan::validation_requested(),
            window: None,
            traversal: if use_gpu {
                target.traversal.into()
            } else {
                fovea_vulkan::Traversal::Software
            },
            present_only: !use_gpu,
            factory: Some(factory),
        };
        let ctx = fovea_vulkan::VulkanContext::new(&options).map_err(|e| {
            FoveaError::Backend(format!(
                "OpenXR: the runtime's Vulkan device cannot run fovea: {e}"
            ))
        })?;
        if use_gpu {
            Ok((
                Self::Vulkan(Box::new(VulkanRenderer {
                    scene: None,
                    ctx,
                    upload_ms: 0.0,
                })),
                None,
            ))
        } else {
            Ok((Self::Cpu(CpuRenderer::new(target.threads)?), Some(ctx)))
        }
    }

    #[cfg(feature = "vulkan")]
    fn vulkan(
        device: Option<usize>,
        auto: bool,
        traversal: crate::args::Traversal,
        threads: Option<usize>,
        quiet: bool,
        window: Option<fovea_vulkan::WindowHandles>,
    ) -> Result<Self> {
        let presents = window.is_some();
        let options = fovea_vulkan::ContextOptions {
            device_index: device,
            validation: fovea_vulkan::validation_requested(),
            window,
            traversal: traversal.into(),
            present_only: false,
            factory: None,
        };
        match fovea_vulkan::VulkanContext::new(&options) {
            Ok(ctx) => {
                if let (Some(note), false) = (&ctx.traversal_note, quiet) {
                    eprintln!("note: {note}");
                }
                Ok(Self::Vulkan(Box::new(VulkanRenderer {
                    scene: None,
                    ctx,
                    upload_ms: 0.0,
                })))
            }
            // `auto` without an explicit device falls back; anything explicit is an error.
            Err(e) if auto && device.is_none() => {
                if !quiet {
                    eprintln!("note: rendering on the CPU: Vulkan failed: {e}");
                }
                Ok(Self::Cpu(CpuRenderer::new(threads)?))
            }
            Err(e) if presents => Err(FoveaError::View(format!(
                "cannot present to the window through Vulkan: {e}"
            ))),
            Err(e) => Err(FoveaError::Backend(format!("Vulkan backend: {e}"))),
        }
    }

    #[cfg(not(feature = "vulkan"))]
    fn vulkan(
        _: Option<usize>,
        _: bool,
        _: crate::args::Traversal,
        _: Option<usize>,
        _: bool,
        _: Option<()>,
    ) -> Result<Self> {
        Err(FoveaError::Backend(
            "this build of fovea has no Vulkan backend (built without the `vulkan` feature); use --backend cpu"
                .into(),
        ))
    }

    /// Whether this backend traverses the CPU's 8-wide tree (the Vulkan device traverses the 4-wide
    /// one only, so the packer need not build the other).
    pub fn wants_wide_bvh(&self) -> bool {
        matches!(self, Self::Cpu(_))
    }

    /// "cpu" or "vulkan".
    pub fn name(&self) -> &'static str {
        match self {
            Self::Cpu(_) => "cpu",
            #[cfg(feature = "vulkan")]
            Self::Vulkan(_) => "vulkan",
        }
    }

    /// The device for `--stats`: the CPU model and thread count, or the Vulkan device's name.
    pub fn device_name(&self) -> String {
        match self {
            Self::Cpu(cpu) => cpu_device_name(cpu.pool.current_num_threads()),
            #[cfg(feature = "vulkan")]
            Self::Vulkan(v) => v.ctx.device_description(),
        }
    }

    /// Makes `packed` available to the backend (a device upload on Vulkan). With `specialize`, frames
    /// leave out the features the scene lacks (the CPU's specialised path, the GPU's specialization
    /// constant); without, they run with every feature (`--no-specialize`). The images are identical.
    pub fn set_scene(&mut self, packed: &PackedScene, specialize: bool) -> Result<()> {
        match self {
            Self::Cpu(cpu) => {
                cpu.features = if specialize {
                    packed.features()
                } else {
                    fovea_core::scene::FeatureFlags::ALL
                };
                Ok(())
            }
            #[cfg(feature = "vulkan")]
            Self::Vulkan(v) => {
                let start = std::time::Instant::now();
                v.scene = None;
                let mut scene = v
                    .ctx
                    .upload_scene(packed)
                    .map_err(|e| FoveaError::Backend(format!("Vulkan backend: {e}")))?;
                if !specialize {
                    scene.features = fovea_core::scene::FeatureFlags::ALL;
                }
                v.scene = Some(scene);
                v.upload_ms = start.elapsed().as_secs_f64() * 1e3;
                Ok(())
            }
        }
    }

    /// Forgets the history: the next frame with temporal reuse starts every pixel afresh.
    pub fn reset_history(&mut self) {
        match self {
            Self::Cpu(cpu) => cpu.histories.iter_mut().for_each(|h| h.reset()),
            #[cfg(feature = "vulkan")]
            Self::Vulkan(v) => v.ctx.reset_history(),
        }
    }

    /// Renders one frame through core's pass list on this backend (see [`FrameRequest`]).
    pub fn render(
        &mut self,
        packed: &PackedScene,
        frame: &FrameParams,
        request: &FrameRequest,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Rendered> {
        match self {
            Self::Cpu(cpu) => {
                let view = packed.view().with_features(cpu.features);
                let history = view_history(&mut cpu.histories, request.view)?;
                let history_restarted = request.history && !history.continues(frame);
                let (image, stats) = cpu.pool.install(|| {
                    fovea_cpu::render_frame_passes(&view, frame, request, history, progress)
                });
                let image = match request.output {
                    FrameOutput::Hdr | FrameOutput::ReadBack { .. } => {
                        cpu.presented = None;
                        image
                    }
                    FrameOutput::Present { .. } => {
                        let kept = RenderedFrame {
                            width: image.width,
                            height: image.height,
                            hdr: None,
                            rgba8: None,
                            raw_hdr: None,
                        };
                        cpu.presented = Some(image);
                        kept
                    }
                };
                Ok(Rendered {
                    image,
                    stats,
                    history_restarted,
                    extra: None,
                })
            }
            #[cfg(feature = "vulkan")]
            Self::Vulkan(v) => {
                let scene = v
                    .scene
                    .as_ref()
                    .ok_or_else(|| FoveaError::Backend("no scene uploaded".into()))?;
                let (image, stats) = v
                    .ctx
                    .render(scene, frame, request, &|n| progress(n))
                    .map_err(|e| FoveaError::Backend(format!("Vulkan backend: {e}")))?;
                let messages = v.ctx.validation_messages();
                Ok(Rendered {
                    image,
                    history_restarted: stats.history_restarted,
                    extra: Some(serde_json::json!({
                        "chunks": stats.chunks,
                        "submissions": stats.submissions,
                        "idle_invocations": stats.idle_invocations,
                        "gpu_timestamps": stats.gpu_timestamps,
                        "plan_ms": stats.plan_ms,
                        "pipeline_create_ms": v.ctx.pipeline_create_ms(),
                        "warmup_ms": stats.warmup_ms,
                        "upload_ms": v.upload_ms,
                        "scene_upload_bytes": scene.bytes,
                        "traversal": if v.ctx.hardware_traversal() { "hardware" } else { "software" },
                        "traversal_note": v.ctx.traversal_note,
                        "acceleration_structures": scene.hardware.as_ref().map(|h| serde_json::json!({
                            "build_ms": h.stats.build_ms,
                            "blas_bytes": h.stats.blas_bytes,
                            "blas_bytes_uncompacted": h.stats.blas_bytes_uncompacted,
                            "tlas_bytes": h.stats.tlas_bytes,
                            "triangle_map_bytes": h.stats.map_bytes,
                            "opaque_triangles": h.stats.opaque_triangles,
                            "cutout_triangles": h.stats.cutout_triangles,
                        })),
                        "validation_messages": messages,
                    })),
                    stats: stats.render,
                })
            }
        }
    }

    /// Samples `range` of every block of `frame`, their sums and counts per pixel (a part of a render
    /// split by samples, `fovea_cpu::render_sample_range`). The CPU backend only.
    pub fn render_sample_range(
        &mut self,
        packed: &PackedScene,
        frame: &FrameParams,
        range: [u32; 2],
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<(FrameImage, RenderStats)> {
        match self {
            Self::Cpu(cpu) => {
                let view = packed.view().with_features(cpu.features);
                Ok(cpu
                    .pool
                    .install(|| fovea_cpu::render_sample_range(&view, frame, range, progress)))
            }
            #[cfg(feature = "vulkan")]
            Self::Vulkan(_) => Err(FoveaError::Backend(
                "the Vulkan host cannot render a range of samples yet; use --backend cpu".into(),
            )),
        }
    }

    /// The last frame rendered with [`FrameOutput::Present`]: on the CPU its RGBA8 pixels, width and
    /// height (for a presenting context to upload); `None` on Vulkan, where it stays on the device, or
    /// before the first such frame.
    #[cfg_attr(not(feature = "vulkan"), allow(dead_code))] // the live view's, which needs Vulkan
    pub fn presented_rgba8(&self) -> Option<(&[u32], u32, u32)> {
        match self {
            Self::Cpu(cpu) => cpu
                .presented
                .as_ref()
                .and_then(|f| f.rgba8.as_deref().map(|pixels| (pixels, f.width, f.height))),
            #[cfg(feature = "vulkan")]
            Self::Vulkan(_) => None,
        }
    }

    /// The HDR image of the last frame rendered with [`FrameOutput::Present`] (with history, its mean),
    /// for a screenshot.
    #[cfg_attr(not(feature = "vulkan"), allow(dead_code))] // the live view's, which needs Vulkan
    pub fn last_hdr(&mut self) -> Result<FrameImage> {
        match self {
            Self::Cpu(cpu) => cpu
                .presented
                .as_ref()
                .and_then(|f| f.hdr.clone())
                .ok_or_else(|| FoveaError::View("nothing rendered to save".into())),
            #[cfg(feature = "vulkan")]
            Self::Vulkan(v) => v
                .ctx
                .read_back_hdr()
                .map_err(|e| FoveaError::View(format!("Vulkan: {e}"))),
        }
    }

    /// Everything the Vulkan validation layer reported on the rendering device (none on the CPU).
    #[cfg_attr(not(feature = "vulkan"), allow(dead_code))] // the live view's, which needs Vulkan
    pub fn validation_messages(&self) -> Vec<String> {
        match self {
            Self::Cpu(_) => Vec::new(),
            #[cfg(feature = "vulkan")]
            Self::Vulkan(v) => v.ctx.validation_messages(),
        }
    }

    /// The Vulkan context that renders, if this backend is Vulkan.
    #[cfg(feature = "vulkan")]
    pub fn vulkan_context(&mut self) -> Option<&mut fovea_vulkan::VulkanContext> {
        match self {
            Self::Cpu(_) => None,
            Self::Vulkan(v) => Some(&mut v.ctx),
        }
    }
}

/// `fovea devices`: the CPU host, then every Vulkan device.
pub fn print_devices() {
    println!(
        "cpu       {}",
        cpu_device_name(rayon::current_num_threads())
    );
    print_vulkan_devices();
}

#[cfg(feature = "vulkan")]
fn print_vulkan_devices() {
    match fovea_vulkan::list_devices() {
        Ok(devices) if devices.is_empty() => println!("(no Vulkan devices)"),
        Ok(devices) => {
            for d in devices {
                let [major, minor, patch] = d.api_version;
                println!(
                    "vulkan {}  {}  [{}, Vulkan {major}.{minor}.{patch}]{}",
                    d.index,
                    d.description(),
                    d.device_type,
                    d.unsuitable
                        .map(|r| format!("  unusable: {r}"))
                        .unwrap_or_default()
                );
            }
        }
        Err(e) => println!("(no Vulkan: {e})"),
    }
}

#[cfg(not(feature = "vulkan"))]
fn print_vulkan_devices() {
    println!("(Vulkan devices: this build has no Vulkan backend)");
}
