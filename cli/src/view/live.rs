//! The live view's renderer: a frame on the CPU host or the Vulkan kernel, added to each pixel's
//! history, tone-mapped, overlaid and presented to the window through the Vulkan context (which owns
//! the window's surface in both cases). An adapter around the hosts: the history, tone map and overlay
//! are core functions.
use rayon::prelude::*;

use fovea_core::foveation::overlay::overlay_rgba8;
use fovea_core::integrator::FrameParams;
use fovea_core::post::tonemap::tonemap_to_rgba8;
use fovea_core::scene::FeatureFlags;
use fovea_cpu::{render_frame_with_history, FrameImage, RenderStats, TemporalHistory};
use fovea_scene::pack::PackedScene;
use fovea_vulkan::{
    ContextOptions, GpuScene, HudOverlay, PresentOutcome, PresentSource, VulkanContext,
    WindowHandles,
};
use glam::Vec3;

use crate::error::{FoveaError, Result};

/// Where frames are rendered.
enum LiveBackend {
    /// The CPU host; the history, its image and the presented RGBA8 image live on the host.
    Cpu {
        pool: rayon::ThreadPool,
        features: FeatureFlags,
        history: Box<TemporalHistory>,
        mean: Option<FrameImage>,
        rgba: Vec<u32>,
    },
    /// The Vulkan kernel; everything stays on the device.
    Vulkan { scene: Box<GpuScene> },
}

/// A renderer that presents to one window.
pub struct LiveRenderer {
    // Field order: the scene's device buffers go before the context.
    backend: LiveBackend,
    ctx: VulkanContext,
    /// "cpu" or "vulkan".
    pub backend_name: &'static str,
    /// The rendering device: the CPU model, or the Vulkan device and driver.
    pub device: String,
    /// The Vulkan device that presents (the same as `device` on the Vulkan backend).
    pub present_device: String,
    /// Host time to upload the scene (Vulkan).
    pub upload_ms: f64,
}

fn vulkan_error(e: fovea_vulkan::VulkanError) -> FoveaError {
    FoveaError::View(format!("Vulkan: {e}"))
}

impl LiveRenderer {
    /// A Vulkan context on `window` (the device `device_index`, or the best one), rendering on it
    /// (`use_gpu`) or on the CPU with `threads` workers.
    pub fn new(
        window: WindowHandles,
        device_index: Option<usize>,
        traversal: crate::args::Traversal,
        use_gpu: bool,
        threads: Option<usize>,
        packed: &PackedScene,
        specialize: bool,
    ) -> Result<Self> {
        let options = ContextOptions {
            device_index,
            validation: fovea_vulkan::validation_requested(),
            window: Some(window),
            // The CPU backend only presents: no acceleration structures for it.
            traversal: if use_gpu {
                traversal.into()
            } else {
                fovea_vulkan::Traversal::Software
            },
        };
        let mut ctx = VulkanContext::new(&options).map_err(|e| {
            FoveaError::View(format!(
                "cannot present to the window through Vulkan: {e} (the view needs a Vulkan driver even \
                 with --backend cpu; lavapipe, Debian's mesa-vulkan-drivers, is enough)"
            ))
        })?;
        let present_device = ctx.device_description();
        if use_gpu {
            let start = std::time::Instant::now();
            let mut scene = ctx.upload_scene(packed).map_err(vulkan_error)?;
            if !specialize {
                scene.features = FeatureFlags::ALL;
            }
            Ok(Self {
                backend: LiveBackend::Vulkan {
                    scene: Box::new(scene),
                },
                ctx,
                backend_name: "vulkan",
                device: present_device.clone(),
                present_device,
                upload_ms: start.elapsed().as_secs_f64() * 1e3,
            })
        } else {
            let pool = crate::backend::cpu_pool(threads)?;
            let device = crate::stats::cpu_device_name(pool.current_num_threads());
            Ok(Self {
                backend: LiveBackend::Cpu {
                    pool,
                    features: if specialize {
                        packed.features()
                    } else {
                        FeatureFlags::ALL
                    },
                    history: Box::default(),
                    mean: None,
                    rgba: Vec::new(),
                },
                ctx,
                backend_name: "cpu",
                device,
                present_device,
                upload_ms: 0.0,
            })
        }
    }

    /// Renders `frame`, adds it to each pixel's history (`accumulated_before` frames since the last
    /// reset; 0 resets it), tone-maps the history's mean with `exposure_ev` and draws the region overlay
    /// if asked. Returns the frame's statistics and the number of earlier frames actually in the
    /// history (0 where it had to restart, e.g. after a resize).
    pub fn render(
        &mut self,
        packed: &PackedScene,
        frame: &FrameParams,
        fill_mode: u32,
        exposure_ev: f32,
        accumulated_before: u32,
        overlay: bool,
    ) -> Result<(RenderStats, u32)> {
        match &mut self.backend {
            LiveBackend::Cpu {
                pool,
                features,
                history,
                mean,
                rgba,
            } => {
                let view = packed.view().with_features(*features);
                let resized = mean
                    .as_ref()
                    .is_none_or(|m| m.width != frame.width || m.height != frame.height);
                let before = if resized { 0 } else { accumulated_before };
                if before == 0 {
                    history.reset();
                }
                let (image, stats) = pool.install(|| {
                    render_frame_with_history(&view, frame, fill_mode, history, &|_| {})
                });
                let mean = mean.insert(image);
                let (w, fov) = (mean.width, frame.foveation);
                rgba.resize(mean.pixels.len(), 0);
                pool.install(|| {
                    rgba.par_iter_mut()
                        .zip(mean.pixels.par_iter())
                        .enumerate()
                        .for_each(|(i, (out, p))| {
                            let c = tonemap_to_rgba8(Vec3::new(p[0], p[1], p[2]), exposure_ev);
                            *out = if overlay {
                                overlay_rgba8(c, i as u32 % w, i as u32 / w, &fov)
                            } else {
                                c
                            };
                        });
                });
                Ok((stats, before))
            }
            LiveBackend::Vulkan { scene } => {
                let (stats, before) = self
                    .ctx
                    .render_live_frame(
                        scene,
                        frame,
                        fill_mode,
                        exposure_ev,
                        accumulated_before,
                        overlay,
                    )
                    .map_err(vulkan_error)?;
                Ok((stats.render, before))
            }
        }
    }

    /// Presents the last frame with `hud` over its top-left corner.
    pub fn present(
        &mut self,
        hud: Option<HudOverlay<'_>>,
        window_size: [u32; 2],
    ) -> Result<PresentOutcome> {
        let source = match &self.backend {
            LiveBackend::Cpu {
                mean: Some(m),
                rgba,
                ..
            } => PresentSource::Host {
                pixels: rgba,
                width: m.width,
                height: m.height,
            },
            LiveBackend::Cpu { mean: None, .. } => {
                return Err(FoveaError::View("nothing rendered to present".into()))
            }
            LiveBackend::Vulkan { .. } => PresentSource::LastFrame,
        };
        self.ctx
            .present(source, hud, window_size)
            .map_err(vulkan_error)
    }

    /// The running mean (linear HDR) of the last frame, for a screenshot.
    pub fn mean_hdr(&mut self) -> Result<FrameImage> {
        match &self.backend {
            LiveBackend::Cpu { mean: Some(m), .. } => Ok(m.clone()),
            LiveBackend::Cpu { mean: None, .. } => {
                Err(FoveaError::View("nothing rendered to save".into()))
            }
            LiveBackend::Vulkan { .. } => self.ctx.read_back_hdr().map_err(vulkan_error),
        }
    }

    /// Everything the Vulkan validation layer reported (with `FOVEA_VULKAN_VALIDATION=1`).
    pub fn validation_messages(&self) -> Vec<String> {
        self.ctx.validation_messages()
    }
}
