//! The frame as one list of passes, which both hosts run in this order.
//!
//! Each pass is a core function over one element (a block, a cell, a pixel). The CPU host runs a pass as
//! one rayon loop over the core function (`fovea_cpu`); the Vulkan host as dispatches of the kernel
//! entry points that call it (`fovea_vulkan`). Neither host keeps its own order: both walk
//! [`frame_passes`] and `match` each [`FramePass`] to their step, and both time the passes under
//! [`FramePass::name`] (`--stats`' `pass_ms`, the view's HUD). Adding a pass (the denoiser's, for
//! example) is one variant here, one core function, one CPU step, one kernel entry and a test that the
//! two backends agree on it (docs/architecture.md, "Adding a pass"); the CPU host's `match` does not
//! compile until it has its step, and the Vulkan host indexes its pipelines by [`KERNEL_ENTRIES`] and
//! sizes each dispatch by [`FramePass::items`], with no list of its own.
//!
//! Host-side only: the kernel runs one entry point per dispatch and has no use for the list (nor for
//! its `&str` names), so the module is not built for SPIR-V.

/// One pass of a frame, in the order of [`FramePass::ALL`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FramePass {
    /// Every block's samples and their mean, written to each pixel of the block (the replicated
    /// image): [`crate::integrator::block_sample_sum`] and [`crate::foveation::block_mean`].
    Samples,
    /// The mean of each cell of the fill's coarse grids: [`crate::foveation::cell_mean_at`].
    CellMeans,
    /// Each pixel of a coarse block interpolated between cell means, in place:
    /// [`crate::foveation::fill_value`].
    Fill,
    /// Each pixel's first hit (distance, normal, albedo): [`crate::temporal::first_hit_gbuffer`].
    GBuffer,
    /// The mean G-buffer albedo of each cell of the fill's grids, over the cell means (which the fill
    /// no longer needs): [`crate::temporal::albedo::cell_albedo_at`]. The temporal pass and the
    /// denoiser divide by its bilinear blend ([`crate::temporal::albedo::filled_albedo`]).
    CellAlbedo,
    /// The frame reprojected into each pixel's history and accumulated:
    /// [`crate::temporal::temporal_accumulate`].
    Temporal,
    /// The history's mean as the frame's HDR image: [`crate::temporal::HistoryTexel::displayed`].
    ResolveHistory,
    /// The denoiser's input: the HDR image demodulated, with a variance and a strength per pixel:
    /// [`crate::denoise::denoise_input`].
    DenoiseInput,
    /// The denoiser's à-trous steps, [`FramePass::repeats`] times: [`crate::denoise::denoise_atrous`].
    DenoiseAtrous,
    /// The denoised HDR image, remodulated: [`crate::denoise::denoise_output`].
    DenoiseOutput,
    /// HDR to RGBA8 (exposure, Reinhard, sRGB): [`crate::post::tonemap::tonemap_to_rgba8`].
    ToneMap,
    /// The regions' outlines over the RGBA8 image (`fovea view`):
    /// [`crate::foveation::overlay::overlay_rgba8`].
    Overlay,
}

/// What a frame needs beyond the foveated image itself; it decides which passes run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameSetup {
    /// Temporal reuse: the G-buffer, temporal and resolve passes (`fovea view`, `render --history`).
    pub history: bool,
    /// An 8-bit image for display or a PNG (the tone map).
    pub tonemap: bool,
    /// The regions drawn over the 8-bit image (the view's overlay key); needs `tonemap`.
    pub overlay: bool,
    /// The denoiser's passes (and the G-buffer they read).
    pub denoise: bool,
}

/// Where a frame's image goes once its passes have run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameOutput {
    /// The linear HDR image only, no 8-bit one (references, tests, benchmarks).
    Hdr,
    /// Back to the host (`render`, `report`): the 8-bit image and, with `want_hdr`, the HDR one;
    /// with `want_raw` also the HDR image as it was before the denoiser's passes (`render
    /// --keep-raw`).
    ReadBack { want_hdr: bool, want_raw: bool },
    /// To the window (`view`): the 8-bit image, with the regions drawn over it if `overlay`; it stays
    /// with the host that rendered it.
    Present { overlay: bool },
}

impl FrameOutput {
    /// Whether the HDR image before the denoiser is read back too (only where the denoiser runs).
    #[must_use]
    pub const fn wants_raw(&self) -> bool {
        matches!(self, Self::ReadBack { want_raw: true, .. })
    }
}

/// How to render a frame beyond its [`crate::integrator::FrameParams`]: the one request every host
/// and the command line use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRequest {
    /// `FILL_BILINEAR` or `FILL_REPLICATE`.
    pub fill_mode: u32,
    /// The tone map's exposure (stops).
    pub exposure_ev: f32,
    /// Temporal reuse: the frame joins each pixel's history, which the host keeps from one frame to
    /// the next, and the image is the history's mean.
    pub history: bool,
    /// The denoiser's passes after the history's (or the fill's) image.
    pub denoise: bool,
    pub output: FrameOutput,
    /// Which of the frame's views this is (0 for a single view; 0 and 1 the left and right eyes of
    /// a stereo frame), below [`MAX_VIEWS`]. Each view keeps its own history, G-buffer and per-frame
    /// buffers on the host; the scene and its upload are shared by all.
    pub view: u32,
}

/// The most views a frame holds: two eyes, or four for a headset with a high-resolution inset per
/// eye (OpenXR's quad views).
pub const MAX_VIEWS: u32 = 4;

/// The view names a stereo frame's outputs carry, in [`FrameRequest::view`] order.
pub const STEREO_VIEW_NAMES: [&str; 2] = ["left", "right"];

impl FrameRequest {
    /// A request for the single view 0 (the one constructor: hosts and the command line build
    /// their requests here).
    #[must_use]
    pub const fn new(
        fill_mode: u32,
        exposure_ev: f32,
        history: bool,
        denoise: bool,
        output: FrameOutput,
    ) -> Self {
        Self {
            fill_mode,
            exposure_ev,
            history,
            denoise,
            output,
            view: 0,
        }
    }

    /// The same request for view `view` of the frame (see [`Self::view`]).
    #[must_use]
    pub const fn for_view(self, view: u32) -> Self {
        Self { view, ..self }
    }

    /// The passes this request needs.
    #[must_use]
    pub const fn setup(&self) -> FrameSetup {
        FrameSetup {
            history: self.history,
            tonemap: !matches!(self.output, FrameOutput::Hdr),
            overlay: matches!(self.output, FrameOutput::Present { overlay: true }),
            denoise: self.denoise,
        }
    }

    /// [`crate::denoise::denoise_input`]'s flags for this request.
    #[must_use]
    pub const fn denoise_flags(&self) -> u32 {
        let history = if self.history {
            crate::denoise::DENOISE_WITH_HISTORY
        } else {
            0
        };
        let replicate = if self.fill_mode == crate::foveation::FILL_REPLICATE {
            crate::denoise::DENOISE_FILL_REPLICATE
        } else {
            0
        };
        history | replicate
    }
}

impl FramePass {
    /// Every pass, in the order a frame runs them.
    pub const ALL: [FramePass; 12] = [
        FramePass::Samples,
        FramePass::CellMeans,
        FramePass::Fill,
        FramePass::GBuffer,
        FramePass::CellAlbedo,
        FramePass::Temporal,
        FramePass::ResolveHistory,
        FramePass::DenoiseInput,
        FramePass::DenoiseAtrous,
        FramePass::DenoiseOutput,
        FramePass::ToneMap,
        FramePass::Overlay,
    ];

    /// The pass's name in statistics (`pass_ms` in `--stats`, the HUD).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            FramePass::Samples => "samples",
            FramePass::CellMeans => "cell_means",
            FramePass::Fill => "fill",
            FramePass::GBuffer => "gbuffer",
            FramePass::CellAlbedo => "cell_albedo",
            FramePass::Temporal => "temporal",
            FramePass::ResolveHistory => "resolve_history",
            FramePass::DenoiseInput => "denoise_input",
            FramePass::DenoiseAtrous => "denoise_atrous",
            FramePass::DenoiseOutput => "denoise_output",
            FramePass::ToneMap => "tonemap",
            FramePass::Overlay => "overlay",
        }
    }

    /// The kernel entry points that run the pass on the Vulkan host, in dispatch order. The samples
    /// take two per dispatch chunk: the samples, spread over invocations, then each block's mean.
    #[must_use]
    pub const fn kernel_entries(self) -> &'static [&'static str] {
        match self {
            FramePass::Samples => &["render_samples", "reduce_blocks"],
            FramePass::CellMeans => &["cell_means"],
            FramePass::Fill => &["fill"],
            FramePass::GBuffer => &["gbuffer"],
            FramePass::CellAlbedo => &["cell_albedo"],
            FramePass::Temporal => &["temporal"],
            FramePass::ResolveHistory => &["resolve_history"],
            FramePass::DenoiseInput => &["denoise_input"],
            FramePass::DenoiseAtrous => &["denoise_atrous"],
            FramePass::DenoiseOutput => &["denoise_output"],
            FramePass::ToneMap => &["tonemap"],
            FramePass::Overlay => &["overlay_regions"],
        }
    }

    /// What one invocation of the pass's kernel entries works on, which sizes its dispatches.
    #[must_use]
    pub const fn items(self) -> PassItems {
        match self {
            FramePass::Samples => PassItems::BlockChunks,
            FramePass::CellMeans | FramePass::CellAlbedo => PassItems::Cells,
            FramePass::Fill
            | FramePass::GBuffer
            | FramePass::Temporal
            | FramePass::ResolveHistory
            | FramePass::DenoiseInput
            | FramePass::DenoiseAtrous
            | FramePass::DenoiseOutput
            | FramePass::ToneMap
            | FramePass::Overlay => PassItems::Pixels,
        }
    }

    /// The index of the pass's first kernel entry in [`KERNEL_ENTRIES`]; its entries follow it in
    /// [`Self::kernel_entries`]' order.
    #[must_use]
    pub const fn first_kernel_entry(self) -> usize {
        let mut index = 0;
        let mut k = 0;
        while k < FramePass::ALL.len() {
            if FramePass::ALL[k] as u32 == self as u32 {
                break;
            }
            index += FramePass::ALL[k].kernel_entries().len();
            k += 1;
        }
        index
    }

    /// The indices in [`KERNEL_ENTRIES`] of the pass's kernel entries, in dispatch order.
    #[must_use]
    pub const fn kernel_entry_range(self) -> core::ops::Range<usize> {
        let first = self.first_kernel_entry();
        first..first + self.kernel_entries().len()
    }

    /// How many times a frame runs the pass in a row (the k-th run is step `k`): the denoiser's
    /// [`crate::denoise::DENOISE_MAX_PASSES`] à-trous steps, every other pass once.
    #[must_use]
    pub const fn repeats(self) -> u32 {
        match self {
            FramePass::DenoiseAtrous => crate::denoise::DENOISE_MAX_PASSES,
            FramePass::Samples
            | FramePass::CellMeans
            | FramePass::Fill
            | FramePass::GBuffer
            | FramePass::CellAlbedo
            | FramePass::Temporal
            | FramePass::ResolveHistory
            | FramePass::DenoiseInput
            | FramePass::DenoiseOutput
            | FramePass::ToneMap
            | FramePass::Overlay => 1,
        }
    }

    /// Whether a frame with `setup` runs this pass.
    #[must_use]
    pub const fn runs_in(self, setup: FrameSetup) -> bool {
        match self {
            FramePass::Samples | FramePass::CellMeans | FramePass::Fill => true,
            FramePass::GBuffer | FramePass::CellAlbedo => setup.history || setup.denoise,
            FramePass::Temporal | FramePass::ResolveHistory => setup.history,
            FramePass::DenoiseInput | FramePass::DenoiseAtrous | FramePass::DenoiseOutput => {
                setup.denoise
            }
            FramePass::ToneMap => setup.tonemap,
            FramePass::Overlay => setup.tonemap && setup.overlay,
        }
    }
}

// `FramePass::ALL` holds each pass once, in the order the enum declares them (a pass declared but
// left out of the list, or listed twice, fails to compile here).
const _: () = {
    let mut k = 0;
    while k < FramePass::ALL.len() {
        assert!(
            FramePass::ALL[k] as usize == k,
            "FramePass::ALL out of declaration order"
        );
        k += 1;
    }
    assert!(
        FramePass::Overlay as usize + 1 == FramePass::ALL.len(),
        "FramePass::Overlay is the last pass"
    );
};

/// What the invocations of a pass's dispatch each work on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassItems {
    /// The frame's blocks, dispatched chunk by chunk of the host's block plan (its samples, then each
    /// block's mean).
    BlockChunks,
    /// One cell of the fill's coarse grids each.
    Cells,
    /// One pixel each.
    Pixels,
}

/// How many kernel entries the passes have together.
pub const KERNEL_ENTRY_COUNT: usize = {
    let mut n = 0;
    let mut k = 0;
    while k < FramePass::ALL.len() {
        n += FramePass::ALL[k].kernel_entries().len();
        k += 1;
    }
    n
};

/// Every pass's kernel entries, pass after pass in [`FramePass::ALL`]'s order: the one list a host
/// indexes its pipelines by ([`FramePass::kernel_entry_range`]).
pub const KERNEL_ENTRIES: [&str; KERNEL_ENTRY_COUNT] = {
    let mut out = [""; KERNEL_ENTRY_COUNT];
    let mut n = 0;
    let mut k = 0;
    while k < FramePass::ALL.len() {
        let entries = FramePass::ALL[k].kernel_entries();
        let mut e = 0;
        while e < entries.len() {
            out[n] = entries[e];
            n += 1;
            e += 1;
        }
        k += 1;
    }
    out
};

/// The passes a frame with `setup` runs, in order. Both hosts schedule their frames from this list.
pub fn frame_passes(setup: FrameSetup) -> impl Iterator<Item = FramePass> {
    FramePass::ALL
        .into_iter()
        .filter(move |pass| pass.runs_in(setup))
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;

    #[test]
    fn the_foveated_image_is_always_made_and_history_adds_its_four_passes_before_the_tone_map() {
        let plain: Vec<_> = frame_passes(FrameSetup::default()).collect();
        assert_eq!(
            plain,
            [FramePass::Samples, FramePass::CellMeans, FramePass::Fill]
        );
        let live: Vec<_> = frame_passes(FrameSetup {
            history: true,
            tonemap: true,
            overlay: true,
            denoise: true,
        })
        .collect();
        assert_eq!(live, FramePass::ALL);
        // The denoiser alone still needs the G-buffer.
        let denoised: Vec<_> = frame_passes(FrameSetup {
            denoise: true,
            ..FrameSetup::default()
        })
        .collect();
        assert_eq!(
            denoised,
            [
                FramePass::Samples,
                FramePass::CellMeans,
                FramePass::Fill,
                FramePass::GBuffer,
                FramePass::CellAlbedo,
                FramePass::DenoiseInput,
                FramePass::DenoiseAtrous,
                FramePass::DenoiseOutput
            ]
        );
        // The overlay draws on the 8-bit image: no tone map, no overlay.
        let no_tonemap = FrameSetup {
            overlay: true,
            ..FrameSetup::default()
        };
        assert!(!FramePass::Overlay.runs_in(no_tonemap));
    }

    #[test]
    fn kernel_entries_list_every_pass_in_order_once() {
        let mut flat = Vec::new();
        for pass in FramePass::ALL {
            let range = pass.kernel_entry_range();
            assert_eq!(range.start, flat.len(), "{pass:?}");
            flat.extend_from_slice(pass.kernel_entries());
            assert_eq!(&KERNEL_ENTRIES[range], pass.kernel_entries(), "{pass:?}");
        }
        assert_eq!(flat, KERNEL_ENTRIES);
        for (i, a) in KERNEL_ENTRIES.iter().enumerate() {
            assert!(!KERNEL_ENTRIES[i + 1..].contains(a), "{a} twice");
        }
    }

    #[test]
    fn names_are_unique_and_every_pass_has_a_kernel_entry() {
        for (i, a) in FramePass::ALL.iter().enumerate() {
            assert!(!a.kernel_entries().is_empty());
            for b in &FramePass::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
            }
        }
    }
}
