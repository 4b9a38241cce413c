//! Temporal reuse: per-pixel history that a gaze move does not erase and that follows the camera.
//!
//! Each frame adds passes after the fill ([`crate::foveation::fill`]):
//!
//! 1. [`gbuffer`]: the first hit through each pixel's centre (distance, normal, albedo), which
//!    reprojection validates history with (and a denoiser guides its filter with), and each fill
//!    cell's mean albedo ([`albedo`]);
//! 2. [`history`]: each pixel's history is found where its surface was on the previous frame
//!    ([`reproject`], bilinear, each tap checked against the previous G-buffer), merged with the
//!    samples that landed in the pixel this frame ([`crate::foveation::landing`]), and written to the
//!    other history buffer (two, used in turn);
//! 3. [`resolve`]: what is shown, the pixel's history where it is confident and the frame's fill where
//!    it is not.
//!
//! The history holds what was learned, whatever the gaze did since: a gaze move changes where the next
//! samples go and how much they weigh, never what is already known.
pub mod albedo;
pub mod gbuffer;
pub mod history;
pub mod params;
pub mod reproject;
pub mod resolve;
pub mod texel;

pub use gbuffer::{first_hit_gbuffer, GBufferTexel};
pub use history::temporal_accumulate;
pub use params::{TemporalParams, TEMPORAL_CAMERA_MOVED, TEMPORAL_HISTORY_VALID};
pub use reproject::{reproject_history, Reprojected};
pub use resolve::resolve_pixel;
pub use texel::{HistoryTexel, HISTORY_SAMPLE_MAX};
