//! Each pixel's history and how a frame joins it: the "reproject and accumulate" pass.
//!
//! **Samples land on pixels.** Each of a block's samples lands in one pixel of the block
//! ([`crate::foveation::landing`]), and the samples pass sums them per pixel. A pixel's history takes
//! exactly the samples that landed in it, each worth one sample of that pixel: the fovea's 32 a frame,
//! the intermediate ring's 4, and one every other frame in the paper's periphery, whose 8 samples per
//! 4 × 4 block visit every pixel of the block in two frames. What is kept is therefore always at the
//! pixel's own resolution; a region's block size decides only how many samples a pixel gets per frame.
//! No change of region resets a history: when the fovea arrives over a pixel, its 32 samples a frame
//! join what the periphery left there and soon outweigh it; when the fovea leaves, the pixel keeps its
//! fine history and adds the periphery's occasional samples to it, each at its real weight. Only a
//! disocclusion (reprojection finds nothing), the neighbourhood clamp, a new image size or a reset
//! start a pixel afresh.
//!
//! **Lighting, not texture.** The history keeps each pixel's *lighting*: its samples' mean divided by
//! its own albedo ([`super::albedo::demodulation_albedo`] of its G-buffer texel, the mean over the
//! pixel that its jittered samples saw). What is shown is the history's lighting, or where it is not
//! yet confident the frame's block reconstruction, times the pixel's albedo ([`super::resolve`]).
//!
//! **Following the camera.** The history is reprojected ([`super::reproject`]) and its weight scaled by
//! its validity. While the camera moves, its colour is clamped to the box `μ ± γσ` around this frame's
//! filled values at the pixel and its eight neighbours ([`neighbourhood_box`]), so that what the camera
//! uncovered does not ghost; a pixel that got no sample this frame is clamped too. The neighbours are
//! adjacent pixels even in coarse blocks: their bilinear fill makes them alike, so the box is tight
//! where the image is smooth, which is what stops a bright object's blur, which coarse blocks spread
//! over their neighbours, from staying behind it. It is never tighter than the spread of the samples
//! that landed there this frame: a box narrower than the frame's own noise would pull the history to
//! the block means' error. While the camera rests nothing is clamped and the mean converges as a plain
//! running mean.
//!
//! **History length.** The history's weight is capped at `(N − 1)` frames (of the larger of the frame's
//! weight and the history's mean weight per frame), so a frame like the history's count at least
//! `1 / N`: `N` = [`TemporalParams::max_frames_moving`] (16 by default) while the camera moves,
//! [`TemporalParams::max_frames_resting`] (4096) while it rests. While the camera moves the weight is
//! also capped at [`TemporalParams::max_weight_moving`] samples of the pixel (128): each reprojection
//! blurs the history a little, and a pixel whose frames already bring many samples (the fovea's 32)
//! gains less from more frames than it loses to their blur (docs/performance.md, "A dense history
//! stays short"). Frames without a sample for the pixel do not count.
//!
//! **Bad samples.** A non-finite sample mean never joins the history (the pixel keeps what it had); a
//! finite one is clamped to [`HISTORY_SAMPLE_MAX`], so one huge sample cannot dominate a mean forever.
use glam::{Vec3, Vec4};

use super::albedo::{demodulation_albedo, filled_albedo};
use super::gbuffer::GBufferTexel;
use super::params::{TemporalParams, TEMPORAL_CAMERA_MOVED};
use super::reproject::reproject_history;
use super::texel::{HistoryTexel, HISTORY_SAMPLE_MAX};
use crate::foveation::owning_block;
use crate::integrator::FrameParams;
use crate::math::color::{is_finite3, luminance};
use crate::math::float::{abs, sqrt};
use crate::math::vec3_from;

/// This frame's samples of one pixel, as they join its history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSample {
    /// Their mean radiance divided by the pixel's albedo.
    pub lighting: Vec3,
    /// How many samples landed in the pixel (0: none, or a non-finite mean).
    pub weight: f32,
}

impl FrameSample {
    /// No sample.
    pub const NONE: Self = Self {
        lighting: Vec3::ZERO,
        weight: 0.0,
    };
}

/// The samples that landed in pixel (`x`, `y`) this frame, from the samples pass's per-pixel sums
/// (`pixel_samples`: `[r, g, b, count]`, [`crate::integrator::add_to_pixel_sum`]), demodulated by the
/// pixel's own albedo in `gbuffer`. A non-finite mean weighs 0; a finite one is clamped to
/// `[0, HISTORY_SAMPLE_MAX]`, before and after the division.
#[inline]
#[must_use]
pub fn frame_sample(
    frame: &FrameParams,
    pixel_samples: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    x: u32,
    y: u32,
) -> FrameSample {
    let p = (y * frame.width + x) as usize;
    let Some(mean) = landed_mean(pixel_samples[p]) else {
        return FrameSample::NONE;
    };
    let max = Vec3::splat(HISTORY_SAMPLE_MAX);
    FrameSample {
        lighting: (mean / demodulation_albedo(&gbuffer[p])).min(max),
        weight: pixel_samples[p][3],
    }
}

/// The mean radiance of the samples in one pixel's sum (`[r, g, b, count]`), clamped to
/// `[0, HISTORY_SAMPLE_MAX]`; `None` where none landed or the mean is not finite.
#[inline]
#[must_use]
fn landed_mean(sum: [f32; 4]) -> Option<Vec3> {
    if !(sum[3] > 0.0) {
        return None;
    }
    let mean = vec3_from(sum) / sum[3];
    if !is_finite3(mean) {
        return None;
    }
    Some(mean.clamp(Vec3::ZERO, Vec3::splat(HISTORY_SAMPLE_MAX)))
}

/// The box `(μ − γσ, μ + γσ)` at pixel (`x`, `y`) and its eight neighbours `step` pixels apart
/// (clamped to the image), per channel: `μ` the mean of the frame's filled values there, `σ` the
/// larger of their spread and the spread of the means of the samples that landed there this frame
/// (`pixel_samples`, where at least two of the nine pixels have one). Non-finite values are left out.
///
/// The filled values are smooth in coarse blocks (the nine pixels blend one to four block means), so
/// their spread does not show the frame's noise, and a box of it alone pulls a history that is more
/// precise than the frame's block means to their error: a new block-sized error every frame while the
/// camera moves (docs/performance.md, 2026-12-03). The landed samples' spread is the frame's noise at
/// the pixel's own sampling density, as uniform sampling's box sees it; where every pixel takes its
/// samples (uniform, the fovea) the two are the same values and the box is unchanged. The centre stays
/// the fill's, which sees every sample of the blocks.
#[must_use]
pub fn neighbourhood_box(
    frame: &FrameParams,
    filled: &[[f32; 4]],
    pixel_samples: &[[f32; 4]],
    x: u32,
    y: u32,
    step: u32,
    gamma: f32,
) -> ClampBox {
    let max = Vec3::splat(HISTORY_SAMPLE_MAX);
    let mut fill = Moments3::ZERO;
    let mut landed = Moments3::ZERO;
    let mut k = 0u32;
    while k < 9 {
        let ox = (k % 3) as i32 - 1;
        let oy = (k / 3) as i32 - 1;
        let nx = (x as i32 + ox * step as i32).clamp(0, frame.width as i32 - 1) as u32;
        let ny = (y as i32 + oy * step as i32).clamp(0, frame.height as i32 - 1) as u32;
        let p = (ny * frame.width + nx) as usize;
        let c = vec3_from(filled[p]);
        if is_finite3(c) {
            fill.add(c.clamp(Vec3::ZERO, max));
        }
        if let Some(m) = landed_mean(pixel_samples[p]) {
            landed.add(m);
        }
        k += 1;
    }
    if fill.n == 0.0 {
        return ClampBox::NONE;
    }
    let mean = fill.mean();
    let var = if landed.n >= 2.0 {
        fill.variance().max(landed.variance())
    } else {
        fill.variance()
    };
    let sigma = Vec3::new(sqrt(var.x), sqrt(var.y), sqrt(var.z)) * gamma;
    ClampBox {
        lo: mean - sigma,
        hi: mean + sigma,
    }
}

/// Running sums of a few colours, for their mean and (population) variance per channel.
#[derive(Clone, Copy)]
struct Moments3 {
    sum: Vec3,
    sum_sq: Vec3,
    n: f32,
}

impl Moments3 {
    const ZERO: Self = Self {
        sum: Vec3::ZERO,
        sum_sq: Vec3::ZERO,
        n: 0.0,
    };

    fn add(&mut self, c: Vec3) {
        self.sum += c;
        self.sum_sq += c * c;
        self.n += 1.0;
    }

    fn mean(&self) -> Vec3 {
        self.sum / self.n
    }

    fn variance(&self) -> Vec3 {
        let mean = self.mean();
        (self.sum_sq / self.n - mean * mean).max(Vec3::ZERO)
    }
}

/// A per-channel box the history's colour is clamped into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClampBox {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl ClampBox {
    /// No clamp: every value the history can hold is inside.
    pub const NONE: Self = Self {
        lo: Vec3::ZERO,
        hi: Vec3::splat(HISTORY_SAMPLE_MAX),
    };

    /// The box of radiance values as a box of lighting under `albedo` (each channel positive).
    #[inline]
    #[must_use]
    pub fn demodulated(self, albedo: Vec3) -> Self {
        Self {
            lo: self.lo / albedo,
            hi: self.hi / albedo,
        }
    }
}

/// The history's caps: `frames` in frames of the larger of the frame's weight and the history's mean
/// weight per frame, `weight` in samples of the pixel (the new frame's included).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HistoryCap {
    pub frames: f32,
    pub weight: f32,
}

impl HistoryCap {
    /// A cap of `frames` frames and no weight cap.
    #[inline]
    #[must_use]
    pub const fn frames(frames: f32) -> Self {
        Self {
            frames,
            weight: f32::MAX,
        }
    }
}

/// `history` with its colours (its own samples' and its fill's) clamped into `clamp`, the luminance
/// moments kept consistent with the first (the mean's luminance moves; the spread of the samples
/// around it is kept).
#[must_use]
fn clamped(history: &HistoryTexel, clamp: ClampBox) -> HistoryTexel {
    let fill = history.fill_lighting().max(clamp.lo).min(clamp.hi);
    let mut out = HistoryTexel {
        fill: [fill.x, fill.y, fill.z, history.fill_frames()],
        ..*history
    };
    let old = history.lighting();
    let c = old.max(clamp.lo).min(clamp.hi);
    if c != old {
        let l = luminance(c);
        let variance = history.luminance_variance();
        out.mean = [c.x, c.y, c.z, history.weight()];
        out.moments[0] = l;
        out.moments[1] = l * l + variance;
    }
    out
}

/// The frame's fill at pixel (`x`, `y`) as lighting: the filled value (in fill mode `fill_mode`) over
/// the albedo its samples saw (`cell_albedo`: [`super::albedo::cell_albedo_at`]'s buffer), clamped to
/// `[0, HISTORY_SAMPLE_MAX]`; `None` where it is not finite.
#[allow(clippy::too_many_arguments)]
#[inline]
#[must_use]
pub fn fill_sample(
    frame: &FrameParams,
    filled: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    fill_mode: u32,
    x: u32,
    y: u32,
) -> Option<Vec3> {
    let c = vec3_from(filled[(y * frame.width + x) as usize]);
    if !is_finite3(c) {
        return None;
    }
    let max = Vec3::splat(HISTORY_SAMPLE_MAX);
    let albedo = filled_albedo(frame, gbuffer, cell_albedo, fill_mode, x, y);
    Some((c.clamp(Vec3::ZERO, max) / albedo).min(max))
}

/// Frames of a fill average that a fill of another block edge keeps: the old average blurs over other
/// blocks, but it is far less noisy than one new frame, so it yields over a few frames rather than at
/// once (the eye's saccades move region borders over many pixels at every fixation).
pub const FILL_CARRY_FRAMES: f32 = 4.0;

/// Merges the frame's fill lighting `fill` (of blocks `block` pixels wide) into the history's average
/// of it: a running mean over at most `max_frames` frames, or [`FILL_CARRY_FRAMES`] where the average
/// was of another block edge.
#[must_use]
pub fn blend_fill(
    history: &HistoryTexel,
    fill: Option<Vec3>,
    block: u32,
    max_frames: f32,
) -> HistoryTexel {
    let Some(f) = fill else {
        return *history;
    };
    let same_block = abs(history.fill_block() - block as f32) < 0.5;
    let cap = if same_block {
        max_frames - 1.0
    } else {
        FILL_CARRY_FRAMES
    };
    let n = history.fill_frames().min(cap.max(0.0));
    let a = 1.0 / (n + 1.0);
    let old = history.fill_lighting();
    let mean = old + (f - old) * a;
    let mut out = *history;
    out.fill = [mean.x, mean.y, mean.z, n + 1.0];
    out.moments[2] = block as f32;
    out
}

/// Merges `sample` into `history` (already reprojected, its weight scaled by its validity) after
/// clamping the history's colour into `clamp`, within the caps (see the module documentation). A
/// sample of weight 0 leaves the (clamped) history as it is.
#[must_use]
pub fn blend_history(
    history: &HistoryTexel,
    sample: &FrameSample,
    cap: HistoryCap,
    clamp: ClampBox,
) -> HistoryTexel {
    let history = clamped(history, clamp);
    if !(sample.weight > 0.0) {
        return history;
    }
    let max_frames = cap.frames;
    let w_sample = sample.weight;
    // The cap, in frames of the history's own weight per frame (a sparse frame on a dense history
    // must not shrink it to the sparse frame's scale).
    let per_frame = if history.frames() > 0.0 {
        history.weight() / history.frames()
    } else {
        w_sample
    };
    let w_history = history
        .weight()
        .min((max_frames - 1.0).max(0.0) * w_sample.max(per_frame))
        .min((cap.weight - w_sample).max(0.0));
    let total = w_history + w_sample;
    let a = w_sample / total;
    let old = history.lighting();
    let old_moments = Vec4::from(history.moments);
    let l = luminance(sample.lighting);
    let new_moments = Vec4::new(l, l * l, 0.0, 0.0);
    let mut moments = old_moments + (new_moments - old_moments) * a;
    moments.w = (if w_history > 0.0 {
        history.frames()
    } else {
        0.0
    } + 1.0)
        .min(max_frames);
    // The fill's block edge is not a moment.
    moments.z = history.moments[2];
    let mean = old + (sample.lighting - old) * a;
    HistoryTexel {
        mean: [mean.x, mean.y, mean.z, total],
        moments: moments.to_array(),
        fill: history.fill,
    }
}

/// The temporal pass for pixel (`x`, `y`): the previous history reprojected to it, the samples that
/// landed in the pixel this frame (`pixel_samples`, the samples pass's per-pixel sums) merged in, the
/// pixel's new history returned ([`super::resolve`] says what is shown). While the camera moves the
/// history is clamped to the neighbourhood of `filled` (the frame's filled image) divided by the
/// albedo its samples saw (`cell_albedo`: [`super::albedo::cell_albedo_at`]'s buffer).
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn temporal_accumulate(
    frame: &FrameParams,
    temporal: &TemporalParams,
    pixel_samples: &[[f32; 4]],
    filled: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    previous_gbuffer: &[GBufferTexel],
    previous_history: &[HistoryTexel],
    x: u32,
    y: u32,
) -> HistoryTexel {
    let reprojected = reproject_history(
        frame,
        temporal,
        gbuffer,
        previous_gbuffer,
        previous_history,
        x,
        y,
    );
    let mut history = reprojected.history;
    // The own samples' weight follows the reprojection's validity; the fill average, a smooth
    // estimate normalised over the valid taps, keeps its frame count (as the frame count does).
    history.mean[3] *= reprojected.validity;
    let sample = frame_sample(frame, pixel_samples, gbuffer, x, y);
    let moved = temporal.flags & TEMPORAL_CAMERA_MOVED != 0;
    let (cap, clamp) = if moved {
        // The box is of the frame's radiance around the pixel; the history is compared with it as
        // the filled values' samples saw it.
        let albedo = filled_albedo(frame, gbuffer, cell_albedo, temporal.fill_mode, x, y);
        (
            HistoryCap {
                frames: temporal.max_frames_moving,
                weight: temporal.max_weight_moving,
            },
            neighbourhood_box(frame, filled, pixel_samples, x, y, 1, temporal.clamp_gamma)
                .demodulated(albedo),
        )
    } else {
        (
            HistoryCap::frames(temporal.max_frames_resting),
            ClampBox::NONE,
        )
    };
    let history = blend_history(&history, &sample, cap, clamp);
    let fill = fill_sample(
        frame,
        filled,
        gbuffer,
        cell_albedo,
        temporal.fill_mode,
        x,
        y,
    );
    let block = owning_block(x, y, &frame.foveation).size;
    blend_fill(&history, fill, block, cap.frames)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::camera::Camera;
    use crate::foveation::FoveationParams;
    use crate::integrator::IntegratorSettings;

    fn sample(v: f32, weight: f32) -> FrameSample {
        FrameSample {
            lighting: Vec3::splat(v),
            weight,
        }
    }

    fn run(samples: &[FrameSample], max_frames: f32) -> HistoryTexel {
        let mut h = HistoryTexel::EMPTY;
        for s in samples {
            h = blend_history(&h, s, HistoryCap::frames(max_frames), ClampBox::NONE);
        }
        h
    }

    #[test]
    fn a_resting_pixel_keeps_the_weighted_mean() {
        let values = [1.0f32, 5.0, 2.0, 8.0, 4.0];
        let samples: Vec<_> = values.iter().map(|&v| sample(v, 32.0)).collect();
        let h = run(&samples, 4096.0);
        assert!((h.lighting().x - 4.0).abs() < 1e-5, "{h:?}");
        assert_eq!(h.weight(), 160.0);
        assert_eq!(h.frames(), 5.0);
        // Second moment: mean of squared luminances (grey: luminance = value).
        let m2 = values.iter().map(|v| v * v).sum::<f32>() / 5.0;
        assert!((h.moments[1] - m2).abs() < 1e-3);
        assert!((h.luminance_variance() - (m2 - 16.0)).abs() < 1e-3);
    }

    #[test]
    fn the_fovea_arriving_refines_the_history_the_periphery_left() {
        // 20 periphery frames, each pixel one sample every other frame (of value 10), then the fovea's
        // 32 a frame (of value 2): the history is not restarted, each sample counts once.
        let mut samples = Vec::new();
        for k in 0..20 {
            samples.push(sample(10.0, if k % 2 == 0 { 1.0 } else { 0.0 }));
        }
        samples.push(sample(2.0, 32.0));
        let h = run(&samples, 4096.0);
        assert_eq!(h.weight(), 42.0);
        assert!(
            (h.lighting().x - (10.0 * 10.0 + 2.0 * 32.0) / 42.0).abs() < 1e-4,
            "{h:?}"
        );
        // A few fovea frames more and the periphery's share is small.
        let mut more = samples.clone();
        more.extend(vec![sample(2.0, 32.0); 9]);
        let h = run(&more, 4096.0);
        assert!(h.lighting().x < 2.3, "{h:?}");
    }

    #[test]
    fn the_fovea_leaving_keeps_the_fine_history() {
        let mut samples = vec![sample(2.0, 32.0); 10];
        // The periphery then adds one sample every other frame, each worth one sample of the pixel.
        for k in 0..20 {
            samples.push(sample(10.0, if k % 2 == 0 { 1.0 } else { 0.0 }));
        }
        let h = run(&samples, 4096.0);
        assert_eq!(h.weight(), 330.0);
        assert!(
            (h.lighting().x - (2.0 * 320.0 + 100.0) / 330.0).abs() < 1e-4,
            "{h:?}"
        );
        // Frames without a sample do not count.
        assert_eq!(h.frames(), 20.0);
    }

    #[test]
    fn the_weight_cap_keeps_a_dense_history_short_and_a_sparse_one_long() {
        let cap = HistoryCap {
            frames: 16.0,
            weight: 128.0,
        };
        let blend = |w: f32| {
            let mut h = HistoryTexel::EMPTY;
            for _ in 0..40 {
                h = blend_history(&h, &sample(0.0, w), cap, ClampBox::NONE);
            }
            blend_history(&h, &sample(1.0, w), cap, ClampBox::NONE)
        };
        // 32 samples a frame: the frame counts 1/4 (four frames of history).
        let fovea = blend(32.0);
        assert!((fovea.lighting().x - 0.25).abs() < 1e-6, "{fovea:?}");
        assert_eq!(fovea.weight(), 128.0);
        // One sample a frame: the frame cap (1/16) binds, not the weight's.
        let periphery = blend(1.0);
        assert!(
            (periphery.lighting().x - 1.0 / 16.0).abs() < 1e-6,
            "{periphery:?}"
        );
    }

    #[test]
    fn the_cap_keeps_each_frame_worth_one_nth() {
        let mut samples = vec![sample(0.0, 1.0); 100];
        samples.push(sample(16.0, 1.0));
        let h = run(&samples, 16.0);
        assert!((h.lighting().x - 1.0).abs() < 1e-5, "{h:?}");
        assert_eq!(h.weight(), 16.0);
        assert_eq!(h.frames(), 16.0);
    }

    #[test]
    fn the_clamp_pulls_ghosts_into_the_box_even_without_a_sample_and_keeps_the_spread() {
        let mut bright = run(&[sample(90.0, 1.0), sample(110.0, 1.0)], 16.0);
        let spread = bright.luminance_variance();
        assert!(spread > 50.0, "{bright:?}");
        let clamp = ClampBox {
            lo: Vec3::splat(0.0),
            hi: Vec3::splat(1.0),
        };
        let h = blend_history(&bright, &sample(0.5, 1.0), HistoryCap::frames(16.0), clamp);
        assert!(h.lighting().x <= 1.0, "{h:?}");
        // A pixel that got no sample this frame is clamped all the same.
        bright.mean[3] = 2.0;
        let h = blend_history(&bright, &FrameSample::NONE, HistoryCap::frames(16.0), clamp);
        assert_eq!(h.lighting(), Vec3::ONE);
        assert_eq!(h.weight(), 2.0);
        // The clamp moves the mean, not the samples' spread around it.
        assert!(
            (h.luminance_variance() - spread).abs() < 1e-2 * spread,
            "{h:?}"
        );
    }

    fn tiny_frame(gaze: [f32; 2]) -> FrameParams {
        FrameParams {
            camera: Camera::default(),
            foveation: FoveationParams::paper(gaze, 1.5, 3.0),
            integrator: IntegratorSettings::default(),
            width: 8,
            height: 8,
            frame_index: 0,
            seed: 0,
        }
    }

    #[test]
    fn bad_samples_never_enter_the_history() {
        let frame = tiny_frame([0.5, 0.5]);
        let sky = vec![GBufferTexel::SKY; 64];
        let mut sums = vec![[1.0f32, 1.0, 1.0, 1.0]; 64];
        sums[0] = [f32::NAN, 1.0, 1.0, 1.0];
        sums[1] = [f32::INFINITY, 1.0, 1.0, 2.0];
        sums[2] = [2.0e30, -10.0, 2.0, 2.0];
        sums[3] = [5.0, 5.0, 5.0, 0.0];
        assert_eq!(frame_sample(&frame, &sums, &sky, 0, 0).weight, 0.0);
        assert_eq!(frame_sample(&frame, &sums, &sky, 1, 0).weight, 0.0);
        let huge = frame_sample(&frame, &sums, &sky, 2, 0);
        assert_eq!(huge.lighting, Vec3::new(HISTORY_SAMPLE_MAX, 0.0, 1.0));
        assert_eq!(huge.weight, 2.0);
        // No sample landed: nothing joins.
        assert_eq!(frame_sample(&frame, &sums, &sky, 3, 0), FrameSample::NONE);
        let h = run(&[sample(1.0, 32.0)], 4096.0);
        let after = blend_history(
            &h,
            &frame_sample(&frame, &sums, &sky, 0, 0),
            HistoryCap::frames(4096.0),
            ClampBox::NONE,
        );
        assert_eq!(after, h);
        // The neighbourhood box leaves them out.
        let b = neighbourhood_box(&frame, &sums, &sums, 1, 1, 1, 1.0);
        assert!(b.lo.is_finite() && b.hi.is_finite(), "{b:?}");
    }

    #[test]
    fn the_box_is_as_wide_as_the_frames_own_samples_vary() {
        let frame = tiny_frame([0.5, 0.5]);
        // A smooth fill (a coarse block's bilinear blend, all 1.0) over one sample a pixel, 0.5 and 1.5
        // in alternate columns: the box is the samples' spread (0.47 over the 3 x 3) around the fill,
        // not the fill's (0).
        let filled = vec![[1.0f32, 1.0, 1.0, 1.0]; 64];
        let sums: Vec<[f32; 4]> = (0..64u32)
            .map(|i| {
                let v = if i % 2 == 0 { 0.5 } else { 1.5 };
                [v, v, v, 1.0]
            })
            .collect();
        let b = neighbourhood_box(&frame, &filled, &sums, 6, 6, 1, 2.0);
        assert!((b.lo.x - (1.0 - 2.0 * 0.4714)).abs() < 1e-3, "{b:?}");
        assert!((b.hi.x - (1.0 + 2.0 * 0.4714)).abs() < 1e-3, "{b:?}");
        // Fewer than two of the nine pixels with a sample: the fill's spread alone.
        let mut sparse = vec![[0.0f32; 4]; 64];
        sparse[(6 * 8 + 6) as usize] = [9.0, 9.0, 9.0, 1.0];
        let b = neighbourhood_box(&frame, &filled, &sparse, 6, 6, 1, 2.0);
        assert_eq!((b.lo, b.hi), (Vec3::ONE, Vec3::ONE));
        // Where the filled values are the pixels' own samples (uniform, the fovea), the box is theirs.
        let b = neighbourhood_box(&frame, &sums, &sums, 6, 6, 1, 2.0);
        let fill_only = neighbourhood_box(&frame, &sums, &sparse, 6, 6, 1, 2.0);
        assert_eq!(b, fill_only);
    }

    #[test]
    fn a_pixel_takes_its_own_samples_under_its_own_albedo() {
        // A checker of albedos 0.2 and 0.8 lit by 2: each pixel's samples saw its own albedo.
        let frame = tiny_frame([0.5, 0.5]);
        let wall = |a: f32| GBufferTexel {
            normal_distance: [0.0, 0.0, 1.0, 3.0],
            albedo: [a, a, a, 1.0],
        };
        let g: Vec<_> = (0..64u32)
            .map(|i| wall(if (i % 8 + i / 8) % 2 == 0 { 0.2 } else { 0.8 }))
            .collect();
        let sums: Vec<[f32; 4]> = (0..64u32)
            .map(|i| {
                let a = if (i % 8 + i / 8) % 2 == 0 { 0.2 } else { 0.8 };
                // Three samples of radiance 2a each.
                [6.0 * a, 6.0 * a, 6.0 * a, 3.0]
            })
            .collect();
        for (x, y) in [(6, 6), (7, 6), (0, 0)] {
            let s = frame_sample(&frame, &sums, &g, x, y);
            assert!((s.lighting.x - 2.0).abs() < 1e-5, "{s:?}");
            assert_eq!(s.weight, 3.0);
        }
    }
}
