//! # fovea-cpu
//!
//! The CPU host: it schedules core's per-sample integrator over the foveated image with rayon and runs
//! core's block fill. It owns no rendering math: every value comes from a `fovea_core` function that the
//! GPU kernel calls too.
//!
//! A frame is core's pass list ([`fovea_core::passes::frame_passes`]) run in order by
//! [`render_frame_passes`], each pass one rayon loop over its core function:
//! 1. **Samples.** Rows are processed in bands as tall as the coarsest block, so no block straddles two
//!    bands and bands are independent. Each band's blocks (core's walk,
//!    [`fovea_core::foveation::for_each_block_in_rows`]) trace exactly their region's samples per pixel
//!    or block, and their mean is written to every pixel of the block (the "replicated" image). No ray
//!    is traced for a pixel that a block covers.
//! 2. **Cell means** for each block size above 1 ([`fovea_core::foveation::fill::cell_mean`]).
//! 3. **Fill**: every pixel of a coarse block interpolates bilinearly between neighbouring cell centres
//!    ([`fovea_core::foveation::fill::fill_value`], in place), or keeps the block value in replicate mode.
//! 4. With temporal reuse ([`temporal`]): the G-buffer, the reprojection and accumulation of each
//!    pixel's history, and its resolve into the HDR image.
//! 5. Where asked: the tone map to RGBA8 and the regions' overlay.
//!
//! A render split by samples (`fovea render --samples`, merged by `fovea merge`) runs the samples pass
//! alone over a range of sample indices ([`render_sample_range`]), and the merge runs the cell means and
//! fill on the parts' added sums ([`fill_from_sample_sums`]).
//!
//! Random numbers are keyed by block, frame and sample, and each block's samples are summed in a fixed
//! order, so the image does not depend on the number of threads.
pub mod render;
pub mod specialize;
pub mod temporal;

pub use render::{
    fill_from_sample_sums, render_frame, render_frame_passes, render_frame_with_history,
    render_sample_range, FrameImage, RenderStats, RenderedFrame, FRAME_BYTES_PER_PIXEL,
};
pub use temporal::TemporalHistory;
