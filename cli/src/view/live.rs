//! The live view's renderer: the one backend type ([`Renderer`]) rendering frames for a window, and
//! the Vulkan context that presents them (the rendering device itself on the Vulkan backend; a
//! present-only context when the CPU renders). The passes (samples to history to tone map and overlay)
//! are core's list, run by the backend.
use fovea_core::integrator::FrameParams;
use fovea_cpu::{FrameImage, RenderStats};
use fovea_scene::pack::PackedScene;
use fovea_vulkan::{HudOverlay, PresentOutcome, PresentSource, VulkanContext, WindowHandles};

use crate::backend::{FrameRequest, Renderer};
use crate::error::{FoveaError, Result};

/// A renderer that presents to one window.
pub struct LiveRenderer {
    renderer: Renderer,
    /// The context that presents the CPU's frames; `None` when the Vulkan backend presents its own.
    presenter: Option<VulkanContext>,
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
        let (mut renderer, mut presenter) =
            Renderer::for_window(window, device_index, traversal, use_gpu, threads)?;
        let start = std::time::Instant::now();
        renderer.set_scene(packed, specialize)?;
        let upload_ms = if use_gpu {
            start.elapsed().as_secs_f64() * 1e3
        } else {
            0.0
        };
        let present_device = match (presenter.as_mut(), renderer.vulkan_context()) {
            (Some(ctx), _) | (None, Some(ctx)) => ctx.device_description(),
            (None, None) => unreachable!("a live renderer always has a presenting context"),
        };
        Ok(Self {
            backend_name: renderer.name(),
            device: renderer.device_name(),
            renderer,
            presenter,
            present_device,
            upload_ms,
        })
    }

    /// Renders `frame` as `request` says (with history: the live view keeps one; its output goes to
    /// the window), after `accumulated_before` frames of history since the last reset (0 resets it).
    /// Returns the frame's statistics and the number of earlier frames actually in the history (0
    /// where it had to restart, e.g. after a resize).
    pub fn render(
        &mut self,
        packed: &PackedScene,
        frame: &FrameParams,
        request: &FrameRequest,
        accumulated_before: u32,
    ) -> Result<(RenderStats, u32)> {
        if accumulated_before == 0 {
            self.renderer.reset_history();
        }
        let rendered = self.renderer.render(packed, frame, request, &|_| {})?;
        let before = if rendered.history_restarted {
            0
        } else {
            accumulated_before
        };
        Ok((rendered.stats, before))
    }

    /// Presents the last frame with `hud` over its top-left corner.
    pub fn present(
        &mut self,
        hud: Option<HudOverlay<'_>>,
        window_size: [u32; 2],
    ) -> Result<PresentOutcome> {
        let outcome = match (self.presenter.as_mut(), self.renderer.presented_rgba8()) {
            (Some(ctx), Some((pixels, width, height))) => ctx.present(
                PresentSource::Host {
                    pixels,
                    width,
                    height,
                },
                hud,
                window_size,
            ),
            (Some(_), None) => return Err(FoveaError::View("nothing rendered to present".into())),
            (None, _) => self
                .renderer
                .vulkan_context()
                .expect("without a presenter the Vulkan backend presents")
                .present(PresentSource::LastFrame, hud, window_size),
        };
        outcome.map_err(vulkan_error)
    }

    /// The displayed HDR image (the history's mean) of the last frame, for a screenshot.
    pub fn mean_hdr(&mut self) -> Result<FrameImage> {
        self.renderer.last_hdr()
    }

    /// Everything the Vulkan validation layer reported (with `FOVEA_VULKAN_VALIDATION=1`).
    pub fn validation_messages(&self) -> Vec<String> {
        let mut messages = self
            .presenter
            .as_ref()
            .map(VulkanContext::validation_messages)
            .unwrap_or_default();
        messages.extend(self.renderer.validation_messages());
        messages
    }
}
