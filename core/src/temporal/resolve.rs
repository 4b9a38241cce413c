//! What the eye sees of a pixel with history: its own samples where they are trusted, the block
//! reconstruction (the fill, averaged over frames) where they are not, blended by confidence as
//! temporal upsampling does (Yang et al. 2009, "Amortized supersampling"; TAAU).
//!
//! A pixel's history holds two estimates ([`super::history`]): the mean `L_o` of the samples that
//! landed in it (32 a frame in the paper's fovea, one every other frame in its periphery), unbiased but
//! noisy while they are few, and the mean `L_f` of the frame's fill at the pixel, which blends whole
//! blocks' samples: less noisy, but blurred over the blocks. What is shown is `s · L_o + (1 − s) · L_f`,
//! the two weighted by the inverse of their errors (in luminance). With `σ²` the variance of one
//! sample (from the spread of the pixel's own samples, shrunk towards a relative spread of
//! [`RESOLVE_PRIOR_SPREAD`] while they are few), the own mean's error is its noise `n_o = σ² / w`
//! (`w` samples), the fill's is its noise `n_f = σ² b² / (τ F)` (`τ` samples per block of `b × b`
//! pixels and frame, `F` frames) plus its blur `β²`, the part of the squared difference of the two
//! means beyond two standard errors (`β² = max(0, (L_o − L_f)² − 4 (n_o + n_f))`, so that one outlying
//! sample is not taken for detail, and what is shown does not jump where the difference crosses them):
//!
//! `s = min((β² + n_f) / (β² + n_f + n_o), w / (w + κ))`,
//!
//! The fill's noise is counted at `b²` times the variance of its mean because it is one error shared by
//! the block's `b²` pixels: the pixels' own errors are independent and average out over the block, the
//! fill's does not, and it shows as a block-sized blotch that changes from frame to frame. Counted as
//! `σ² / (τ F)`, as it was until 2026-12-02, a resting periphery showed the fill over most of its
//! pixels: it had less relMSE than uniform 1 spp + history but 0.14 JOD less in FovVideoVDP over
//! frames 15-60 (docs/performance.md, 2026-12-02, evening).
//!
//! the second bound ([`RESOLVE_MIN_SAMPLES`] = `κ`) keeping a pixel's first few samples, which no
//! variance estimate can yet tell from outliers, from showing alone: they would flicker.
//!
//! Where the fill is right (a flat, evenly lit surface) the pixel shows the fill's average while it has
//! fewer samples of its own than the fill has per pixel of its block, and its own history as it gets
//! more; where the fill is blurred (an edge, a shadow's border), the pixel's own samples take over as
//! soon as they are precise enough to show the difference. A resting eye and camera converge to them. When the fovea leaves a pixel, its 32 samples a frame outweigh the new
//! coarse fill. A pixel of a one-pixel block (the paper's fovea) shows its own history: its fill is its
//! own samples. Both are lighting; the pixel's own albedo multiplies the result back
//! ([`super::albedo`]).
use glam::Vec3;

use super::albedo::demodulation_albedo;
use super::gbuffer::GBufferTexel;
use super::history::fill_sample;
use super::texel::HistoryTexel;
use crate::foveation::{owning_block, samples_in_block};
use crate::integrator::FrameParams;
use crate::math::color::luminance;

/// Pseudo-frames of the prior spread that a pixel's few samples' variance is shrunk towards.
pub const RESOLVE_PRIOR_FRAMES: f32 = 2.0;
/// The prior relative spread (standard deviation over the mean) of one path-traced sample.
pub const RESOLVE_PRIOR_SPREAD: f32 = 2.0;
/// `κ`: a pixel's own samples show at most `w / (w + κ)` of it.
pub const RESOLVE_MIN_SAMPLES: f32 = 8.0;

/// The share `s` of the pixel's own samples in what is shown (see the module documentation), for a
/// pixel of a block `block_size` pixels wide taking `block_spp` samples a frame.
#[inline]
#[must_use]
pub fn own_share(history: &HistoryTexel, block_size: u32, block_spp: u32) -> f32 {
    if block_size <= 1 {
        return 1.0;
    }
    let w = history.weight();
    if !(w > 0.0) {
        return 0.0;
    }
    let fill_frames = history.fill_frames();
    if !(fill_frames > 0.0) {
        return 1.0;
    }
    let own = history.moments[0];
    let fill = luminance(history.fill_lighting());
    let frames = history.frames().max(1.0);
    let level = own.max(fill);
    // One sample's variance: the spread of the frames' means times the samples a frame brought,
    // shrunk towards a relative spread of 1 while there are few frames.
    let measured = history.luminance_variance() * (w / frames);
    let prior = RESOLVE_PRIOR_SPREAD * RESOLVE_PRIOR_SPREAD * level * level;
    let sigma2 = (measured * frames + prior * RESOLVE_PRIOR_FRAMES)
        / (frames + RESOLVE_PRIOR_FRAMES)
        + 1.0e-12;
    let noise_own = sigma2 / w;
    // The fill's error is one error for the whole block (and, bilinearly, its neighbours): it does
    // not average out over the block's pixels as their own samples' errors do.
    let noise_fill =
        sigma2 * (block_size * block_size) as f32 / (block_spp.max(1) as f32 * fill_frames);
    let d2 = (own - fill) * (own - fill);
    // The part of the difference beyond two standard errors, so that what is shown does not jump
    // where the difference crosses them.
    let blur = (d2 - 4.0 * (noise_own + noise_fill)).max(0.0);
    let weighted = (blur + noise_fill) / (blur + noise_fill + noise_own);
    weighted.min(w / (w + RESOLVE_MIN_SAMPLES))
}

/// The lighting shown at pixel (`x`, `y`) (see the module documentation). A pixel with neither its own
/// samples nor a fill average yet shows this frame's fill, `filled` (in fill mode `fill_mode`) over the
/// albedo its samples saw (`cell_albedo`: the cell-albedo pass's buffer); black where that is not
/// finite either.
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn resolved_lighting(
    frame: &FrameParams,
    history: &[HistoryTexel],
    filled: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    fill_mode: u32,
    x: u32,
    y: u32,
) -> Vec3 {
    let p = (y * frame.width + x) as usize;
    let h = history[p];
    if !(h.weight() > 0.0) && !(h.fill_frames() > 0.0) {
        return fill_sample(frame, filled, gbuffer, cell_albedo, fill_mode, x, y)
            .unwrap_or(Vec3::ZERO);
    }
    let block = owning_block(x, y, &frame.foveation);
    let s = own_share(&h, block.size, samples_in_block(&block, &frame.foveation));
    h.lighting() * s + h.fill_lighting() * (1.0 - s)
}

/// The pixel as displayed, alpha 1 (the HDR image's layout): [`resolved_lighting`] times the pixel's
/// own albedo.
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn resolve_pixel(
    frame: &FrameParams,
    history: &[HistoryTexel],
    filled: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    fill_mode: u32,
    x: u32,
    y: u32,
) -> [f32; 4] {
    let lighting = resolved_lighting(
        frame,
        history,
        filled,
        gbuffer,
        cell_albedo,
        fill_mode,
        x,
        y,
    );
    let c = lighting * demodulation_albedo(&gbuffer[(y * frame.width + x) as usize]);
    [c.x, c.y, c.z, 1.0]
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;

    use super::*;
    use crate::camera::Camera;
    use crate::foveation::{FoveationParams, FILL_BILINEAR};
    use crate::integrator::IntegratorSettings;
    use crate::temporal::albedo::test_support::cell_albedo_buffer;

    fn frame() -> FrameParams {
        // Gaze in the top-left corner of 8 × 8: the far corner is periphery (4 × 4 blocks).
        FrameParams {
            camera: Camera::default(),
            foveation: FoveationParams::paper([0.5, 0.5], 1.5, 3.0),
            integrator: IntegratorSettings::default(),
            width: 8,
            height: 8,
            frame_index: 0,
            seed: 0,
        }
    }

    /// A history whose samples have mean `own` and luminance variance `variance` over `frames` frames
    /// (one sample each), and whose fill average is `fill` over as many frames.
    fn texel(own: f32, frames: f32, variance: f32, fill: f32) -> HistoryTexel {
        HistoryTexel {
            mean: [own, own, own, frames],
            moments: [own, own * own + variance, 4.0, frames],
            fill: [fill, fill, fill, frames],
        }
    }

    #[test]
    fn where_the_fill_is_right_it_shows_while_the_pixel_has_few_samples() {
        // Own samples agree with the fill (no blur); the fill has 8 samples a frame behind it.
        let s = own_share(&texel(1.0, 2.0, 0.5, 1.0), 4, 8);
        assert!(s <= 0.2, "{s}");
    }

    #[test]
    fn a_fills_error_counts_once_for_its_whole_block() {
        // 40 frames of one sample a pixel, and a fill of a 4 x 4 block's 16 samples over as many
        // frames: the fill's error is shared by the 16 pixels, so at the block's scale it is as large as
        // the pixel's own, and each shows about half. (Counted as the variance of a 640-sample mean,
        // the fill took 94 % of the pixel.)
        let s = own_share(&texel(1.0, 40.0, 0.5, 1.0), 4, 16);
        assert!((0.45..0.55).contains(&s), "{s}");
        // A fill of more samples a pixel weighs more.
        assert!(own_share(&texel(1.0, 40.0, 0.5, 1.0), 4, 64) < 0.25);
    }

    #[test]
    fn what_is_shown_changes_smoothly_as_the_pixels_mean_leaves_the_fills() {
        // 64 frames, the κ bound (0.89) above the share: the share must not jump where the difference
        // of the two means passes two standard errors.
        let shares: std::vec::Vec<f32> = (0..10_000)
            .map(|i| own_share(&texel(1.0 + i as f32 * 1.0e-4, 64.0, 0.5, 1.0), 4, 8))
            .collect();
        let largest_step = shares
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0f32, f32::max);
        assert!(largest_step < 0.01, "{largest_step}");
        // It does take over: from the fill's share to the κ bound.
        assert!(
            shares[0] < 0.7 && shares[9999] > 0.85,
            "{} {}",
            shares[0],
            shares[9999]
        );
    }

    #[test]
    fn where_the_fill_is_blurred_the_pixel_takes_over_as_its_samples_arrive() {
        // The fill says 1, the pixel's samples 2 with a relative spread of 0.5: a visible blur.
        let shares: std::vec::Vec<f32> = [2.0f32, 8.0, 32.0, 128.0]
            .iter()
            .map(|&n| own_share(&texel(2.0, n, 1.0, 1.0), 4, 8))
            .collect();
        assert!(shares.windows(2).all(|w| w[1] >= w[0]), "{shares:?}");
        assert!(shares[0] < 0.5 && shares[3] > 0.9, "{shares:?}");
    }

    #[test]
    fn a_fine_history_outweighs_a_new_coarse_fill() {
        // The fovea left after 12 frames of 32 samples; the periphery's fill has 6 frames so far.
        let mut h = texel(1.0, 12.0, 0.02, 1.0);
        h.mean[3] = 384.0;
        h.fill[3] = 6.0;
        let s = own_share(&h, 4, 8);
        assert!(s > 0.8, "{s}");
    }

    #[test]
    fn a_fovea_pixel_shows_its_history_and_a_new_pixel_the_frame() {
        let f = frame();
        let sky = vec![GBufferTexel::SKY; 64];
        let cells = cell_albedo_buffer(&f, &sky);
        let filled = vec![[9.0f32, 9.0, 9.0, 1.0]; 64];
        let mut history = vec![HistoryTexel::EMPTY; 64];
        history[0] = texel(2.0, 32.0, 1.0, 9.0);
        let l = resolved_lighting(&f, &history, &filled, &sky, &cells, FILL_BILINEAR, 0, 0);
        assert_eq!(l.x, 2.0);
        // No history at all (a disocclusion): this frame's fill.
        let l = resolved_lighting(&f, &history, &filled, &sky, &cells, FILL_BILINEAR, 7, 7);
        assert_eq!(l.x, 9.0);
    }

    #[test]
    fn a_non_finite_fill_without_history_is_black() {
        let f = frame();
        let sky = vec![GBufferTexel::SKY; 64];
        let cells = cell_albedo_buffer(&f, &sky);
        let mut filled = vec![[1.0f32; 4]; 64];
        filled[63] = [f32::NAN, 1.0, 1.0, 1.0];
        let history = vec![HistoryTexel::EMPTY; 64];
        let l = resolved_lighting(&f, &history, &filled, &sky, &cells, FILL_BILINEAR, 7, 7);
        assert_eq!(l, Vec3::ZERO);
    }
}
