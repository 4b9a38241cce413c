//! Each pixel's history and how a frame joins it: the "reproject and accumulate" pass.
//!
//! **Lighting, not texture.** The history keeps each pixel's *lighting*: the frame's filled value divided
//! by the albedo its samples saw (its block's mean, [`super::albedo`]). The displayed pixel is that
//! lighting times the pixel's own albedo ([`HistoryTexel::displayed`]). Resampling the history while the
//! camera moves then blurs only lighting, which is smooth, while the texture comes sharp from this
//! frame's G-buffer; and a periphery pixel converges to its block's lighting under its own texture, not
//! to the block's blur.
//!
//! **Weights that respect the footprint.** A frame's filled value at a pixel comes from `spp` samples
//! spread over its block's `b × b` pixels: it is worth `spp / b²` samples of that pixel (32 in the
//! paper's fovea, 4 in the intermediate ring, 0.5 in the periphery), and it estimates the pixel blurred
//! over `b` pixels. The history keeps the weighted mean of its frames' footprints, `f`, and:
//!
//! - *the fovea arrives* (a frame finer than the history, `b < f − 1/2`): the history was built from
//!   blurred estimates and yields; the frame starts it afresh (no blur trail, no block pattern left in
//!   the fovea);
//! - *the fovea leaves* (a frame coarser than the history, `b > f`): the frame counts `(f / b)²` of its
//!   weight, so a periphery frame adds 1/16 of 0.5 samples to a fovea history and the fine history is
//!   not overwritten by coarse samples.
//!
//! **Following the camera.** The history is reprojected ([`super::reproject`]) and its weight scaled by
//! its validity. While the camera moves, its colour is clamped to the box `μ ± γσ` of this frame's
//! filled values at the pixel and its eight neighbours, so that what the camera uncovered does not
//! ghost. The neighbours are adjacent pixels even in coarse blocks: their bilinear fill makes them
//! alike, so the box is tight, which is what stops a bright object's blur, which coarse blocks spread
//! over their neighbours, from staying behind it (neighbours one block apart let a thin bright bar's
//! blur stay 2.4x above the frame's own, `tests/tests/temporal.rs`). While the camera rests nothing is
//! clamped and the mean converges as the plain running mean did.
//!
//! **History length.** The history's weight is capped at `(N − 1)` frames (of the larger of the frame's
//! weight and the history's mean weight per frame), so a frame like the history's count at least
//! `1 / N`: `N` = [`TemporalParams::max_frames_moving`] (16 by default) while the camera moves,
//! [`TemporalParams::max_frames_resting`] (4096) while it rests. While the camera moves the weight is
//! also capped at [`TemporalParams::max_weight_moving`] samples of the pixel (128): each reprojection
//! blurs the history a little, and a pixel whose frames already bring many samples (the fovea's 32)
//! gains less from more frames than it loses to their blur, so it keeps four frames while the
//! periphery's half a sample a frame keeps sixteen (docs/performance.md, "A dense history stays short").
//!
//! **Bad samples.** A non-finite frame value never joins the history (the pixel keeps what it had); a
//! finite one is clamped to [`HISTORY_SAMPLE_MAX`], so one huge sample cannot dominate a mean forever.
use glam::{Vec3, Vec4};

use super::albedo::filled_albedo;
use super::gbuffer::GBufferTexel;
use super::params::{TemporalParams, TEMPORAL_CAMERA_MOVED};
use super::reproject::reproject_history;
use super::texel::{HistoryTexel, HISTORY_SAMPLE_MAX};
use crate::foveation::{owning_block, samples_in_block};
use crate::integrator::FrameParams;
use crate::math::color::{is_finite3, luminance};
use crate::math::float::sqrt;
use crate::math::vec3_from;

/// A frame's value at one pixel, as it joins the history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSample {
    /// The filled radiance divided by `albedo`.
    pub lighting: Vec3,
    /// The albedo its samples saw ([`filled_albedo`]).
    pub albedo: Vec3,
    /// Samples of this pixel it is worth (`spp / b²`).
    pub weight: f32,
    /// Its footprint: the block edge `b`.
    pub footprint: f32,
}

/// The frame's value of pixel (`x`, `y`): `filled` (in fill mode `fill_mode`) at the pixel over the
/// albedo its samples saw in `gbuffer` (`cell_albedo`: [`super::albedo::cell_albedo_at`]'s buffer), weighted by its block's samples and footprint. A non-finite
/// value weighs 0; a finite one is clamped to `[0, HISTORY_SAMPLE_MAX]`, before and after the division.
#[inline]
#[must_use]
pub fn frame_sample(
    frame: &FrameParams,
    filled: &[[f32; 4]],
    gbuffer: &[GBufferTexel],
    cell_albedo: &[[f32; 4]],
    fill_mode: u32,
    x: u32,
    y: u32,
) -> FrameSample {
    let block = owning_block(x, y, &frame.foveation);
    let b = block.size.max(1) as f32;
    let c = vec3_from(filled[(y * frame.width + x) as usize]);
    let finite = is_finite3(c);
    let albedo = filled_albedo(frame, gbuffer, cell_albedo, fill_mode, x, y);
    let max = Vec3::splat(HISTORY_SAMPLE_MAX);
    FrameSample {
        lighting: if finite {
            (c.clamp(Vec3::ZERO, max) / albedo).min(max)
        } else {
            Vec3::ZERO
        },
        albedo,
        weight: if finite {
            samples_in_block(&block, &frame.foveation) as f32 / (b * b)
        } else {
            0.0
        },
        footprint: b,
    }
}

/// The box `(μ − γσ, μ + γσ)` of the frame's filled values at pixel (`x`, `y`) and its eight neighbours
/// `step` pixels apart (clamped to the image), per channel. Non-finite values are left out.
#[must_use]
pub fn neighbourhood_box(
    frame: &FrameParams,
    filled: &[[f32; 4]],
    x: u32,
    y: u32,
    step: u32,
    gamma: f32,
) -> ClampBox {
    let mut sum = Vec3::ZERO;
    let mut sum_sq = Vec3::ZERO;
    let mut n = 0.0f32;
    let mut k = 0u32;
    while k < 9 {
        let ox = (k % 3) as i32 - 1;
        let oy = (k / 3) as i32 - 1;
        let nx = (x as i32 + ox * step as i32).clamp(0, frame.width as i32 - 1) as u32;
        let ny = (y as i32 + oy * step as i32).clamp(0, frame.height as i32 - 1) as u32;
        let c = vec3_from(filled[(ny * frame.width + nx) as usize]);
        if is_finite3(c) {
            let c = c.clamp(Vec3::ZERO, Vec3::splat(HISTORY_SAMPLE_MAX));
            sum += c;
            sum_sq += c * c;
            n += 1.0;
        }
        k += 1;
    }
    if n == 0.0 {
        return ClampBox::NONE;
    }
    let mean = sum / n;
    let var = (sum_sq / n - mean * mean).max(Vec3::ZERO);
    let sigma = Vec3::new(sqrt(var.x), sqrt(var.y), sqrt(var.z)) * gamma;
    ClampBox {
        lo: mean - sigma,
        hi: mean + sigma,
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

/// Merges `sample` into `history` (already reprojected, its weight scaled by its validity): the
/// footprint rules, the caps and the clamp of the history's colour into `clamp` (see the module
/// documentation). A sample of weight 0 leaves the history as it is.
#[must_use]
pub fn blend_history(
    history: &HistoryTexel,
    sample: &FrameSample,
    cap: HistoryCap,
    clamp: ClampBox,
) -> HistoryTexel {
    let max_frames = cap.frames;
    if !(sample.weight > 0.0) {
        return *history;
    }
    let mut w_history = history.weight();
    let f = history.footprint();
    let mut w_sample = sample.weight;
    if w_history > 0.0 {
        if sample.footprint < f - 0.5 {
            // The fovea arrives: coarse history yields to finer samples.
            w_history = 0.0;
        } else if sample.footprint > f {
            // The fovea leaves: coarse samples barely touch fine history.
            let r = f / sample.footprint;
            w_sample *= r * r;
        }
    }
    // The cap, in frames of the history's own weight per frame (a coarse frame on a fine history
    // must not shrink it to the coarse frame's scale).
    let per_frame = if history.frames() > 0.0 {
        history.weight() / history.frames()
    } else {
        w_sample
    };
    w_history = w_history
        .min((max_frames - 1.0).max(0.0) * w_sample.max(per_frame))
        .min((cap.weight - w_sample).max(0.0));
    let mut old = history.lighting();
    let mut old_moments = Vec4::from(history.moments);
    let clamped = old.max(clamp.lo).min(clamp.hi);
    if clamped != old {
        // Keep the luminance moments consistent with the clamped colour.
        let l = luminance(clamped);
        old_moments.x = l;
        old_moments.y = l * l;
        old = clamped;
    }
    let total = w_history + w_sample;
    let a = w_sample / total;
    let l = luminance(sample.lighting);
    let new_moments = Vec4::new(l, l * l, sample.footprint, 0.0);
    let mut moments = old_moments + (new_moments - old_moments) * a;
    moments.w = (if w_history > 0.0 {
        history.frames()
    } else {
        0.0
    } + 1.0)
        .min(max_frames);
    let mean = old + (sample.lighting - old) * a;
    HistoryTexel {
        mean: [mean.x, mean.y, mean.z, total],
        moments: moments.to_array(),
    }
}

/// The temporal pass for pixel (`x`, `y`): the previous history reprojected to it, this frame's filled
/// value merged in, the pixel's new history returned ([`HistoryTexel::displayed`] is what is shown).
/// `cell_albedo` is the cell-albedo pass's buffer ([`super::albedo::cell_albedo_at`]).
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn temporal_accumulate(
    frame: &FrameParams,
    temporal: &TemporalParams,
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
    history.mean[3] *= reprojected.validity;
    let sample = frame_sample(
        frame,
        filled,
        gbuffer,
        cell_albedo,
        temporal.fill_mode,
        x,
        y,
    );
    let moved = temporal.flags & TEMPORAL_CAMERA_MOVED != 0;
    let (cap, clamp) = if moved {
        // The box is of the frame's radiance around the pixel; the history is compared with it as
        // this pixel's samples would see it.
        (
            HistoryCap {
                frames: temporal.max_frames_moving,
                weight: temporal.max_weight_moving,
            },
            neighbourhood_box(frame, filled, x, y, 1, temporal.clamp_gamma)
                .demodulated(sample.albedo),
        )
    } else {
        (
            HistoryCap::frames(temporal.max_frames_resting),
            ClampBox::NONE,
        )
    };
    blend_history(&history, &sample, cap, clamp)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::camera::Camera;
    use crate::foveation::{FoveationParams, FILL_BILINEAR};
    use crate::integrator::IntegratorSettings;

    /// `frame_sample` at (`x`, `y`) in bilinear fill, with the cell-albedo pass run over `gbuffer`.
    fn sample_at(
        frame: &FrameParams,
        filled: &[[f32; 4]],
        gbuffer: &[GBufferTexel],
        x: u32,
        y: u32,
    ) -> FrameSample {
        let cells = crate::temporal::albedo::test_support::cell_albedo_buffer(frame, gbuffer);
        frame_sample(frame, filled, gbuffer, &cells, FILL_BILINEAR, x, y)
    }

    fn sample(v: f32, weight: f32, footprint: f32) -> FrameSample {
        FrameSample {
            lighting: Vec3::splat(v),
            albedo: Vec3::ONE,
            weight,
            footprint,
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
        let samples: Vec<_> = values.iter().map(|&v| sample(v, 32.0, 1.0)).collect();
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
    fn the_fovea_arriving_replaces_coarse_history() {
        // 50 periphery frames of a blurred value, then one fovea frame.
        let mut samples = vec![sample(10.0, 0.5, 4.0); 50];
        samples.push(sample(2.0, 32.0, 1.0));
        let h = run(&samples, 4096.0);
        assert_eq!(h.lighting().x, 2.0, "no blur trail");
        assert_eq!(h.weight(), 32.0);
        assert_eq!(h.footprint(), 1.0);
        assert_eq!(h.frames(), 1.0);
    }

    #[test]
    fn the_fovea_leaving_does_not_overwrite_fine_history() {
        let mut samples = vec![sample(2.0, 32.0, 1.0); 10];
        samples.extend(vec![sample(10.0, 0.5, 4.0); 20]);
        let h = run(&samples, 4096.0);
        // 20 periphery frames worth 0.5/16 each against 320 fovea samples: 0.2 % of the mean.
        assert!(h.lighting().x < 2.02, "{h:?}");
        assert!(h.footprint() < 1.01);
        // And the fovea coming back merges with it rather than restarting it.
        let back = blend_history(
            &h,
            &sample(2.0, 32.0, 1.0),
            HistoryCap::frames(4096.0),
            ClampBox::NONE,
        );
        assert!(back.weight() > 350.0);
    }

    #[test]
    fn the_intermediate_ring_merges_with_its_own_footprint() {
        let samples = vec![sample(3.0, 4.0, 2.0); 8];
        let h = run(&samples, 4096.0);
        assert_eq!(h.weight(), 32.0);
        assert_eq!(h.footprint(), 2.0);
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
                h = blend_history(&h, &sample(0.0, w, 1.0), cap, ClampBox::NONE);
            }
            blend_history(&h, &sample(1.0, w, 1.0), cap, ClampBox::NONE)
        };
        // 32 samples a frame: the frame counts 1/4 (four frames of history).
        let fovea = blend(32.0);
        assert!((fovea.lighting().x - 0.25).abs() < 1e-6, "{fovea:?}");
        assert_eq!(fovea.weight(), 128.0);
        // Half a sample a frame: the frame cap (1/16) binds, not the weight's.
        let periphery = blend(0.5);
        assert!(
            (periphery.lighting().x - 1.0 / 16.0).abs() < 1e-6,
            "{periphery:?}"
        );
    }

    #[test]
    fn the_cap_keeps_each_frame_worth_one_nth() {
        let mut samples = vec![sample(0.0, 1.0, 1.0); 100];
        samples.push(sample(16.0, 1.0, 1.0));
        let h = run(&samples, 16.0);
        assert!((h.lighting().x - 1.0).abs() < 1e-5, "{h:?}");
        assert_eq!(h.weight(), 16.0);
        assert_eq!(h.frames(), 16.0);
    }

    #[test]
    fn the_clamp_pulls_ghosts_into_the_box() {
        let bright = run(&[sample(100.0, 1.0, 1.0); 8], 16.0);
        let clamp = ClampBox {
            lo: Vec3::splat(0.0),
            hi: Vec3::splat(1.0),
        };
        let h = blend_history(
            &bright,
            &sample(0.5, 1.0, 1.0),
            HistoryCap::frames(16.0),
            clamp,
        );
        assert!(h.lighting().x <= 1.0, "{h:?}");
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
        let mut filled = vec![[1.0f32, 1.0, 1.0, 1.0]; 64];
        filled[0] = [f32::NAN, 1.0, 1.0, 1.0];
        filled[1] = [f32::INFINITY, 1.0, 1.0, 1.0];
        filled[2] = [1.0e30, -5.0, 1.0, 1.0];
        assert_eq!(sample_at(&frame, &filled, &sky, 0, 0).weight, 0.0);
        assert_eq!(sample_at(&frame, &filled, &sky, 1, 0).weight, 0.0);
        let huge = sample_at(&frame, &filled, &sky, 2, 0);
        assert_eq!(huge.lighting, Vec3::new(HISTORY_SAMPLE_MAX, 0.0, 1.0));
        let h = run(&[sample(1.0, 32.0, 1.0)], 4096.0);
        let after = blend_history(
            &h,
            &sample_at(&frame, &filled, &sky, 0, 0),
            HistoryCap::frames(4096.0),
            ClampBox::NONE,
        );
        assert_eq!(after, h);
        // The neighbourhood box leaves them out.
        let b = neighbourhood_box(&frame, &filled, 1, 1, 1, 1.0);
        assert!(b.lo.is_finite() && b.hi.is_finite(), "{b:?}");
    }

    #[test]
    fn frame_samples_weigh_their_footprint() {
        // Gaze in a corner of an 8 x 8 image: the far corner is periphery (4 x 4 block, 8 spp).
        let frame = tiny_frame([0.5, 0.5]);
        let sky = vec![GBufferTexel::SKY; 64];
        let filled = vec![[1.0f32; 4]; 64];
        let fovea = sample_at(&frame, &filled, &sky, 0, 0);
        assert_eq!((fovea.weight, fovea.footprint), (32.0, 1.0));
        let periphery = sample_at(&frame, &filled, &sky, 7, 7);
        assert_eq!((periphery.weight, periphery.footprint), (0.5, 4.0));
    }

    #[test]
    fn history_keeps_lighting_and_shows_each_pixel_its_own_texture() {
        // The periphery's 4 x 4 block at (4, 4) sees a checker of albedos 0.2 and 0.8 (mean 0.5) lit
        // by 2: its filled value is 1 everywhere.
        let frame = tiny_frame([0.5, 0.5]);
        let wall = |a: f32| GBufferTexel {
            normal_distance: [0.0, 0.0, 1.0, 3.0],
            albedo: [a, a, a, 1.0],
        };
        let g: Vec<_> = (0..64u32)
            .map(|i| wall(if (i % 8 + i / 8) % 2 == 0 { 0.2 } else { 0.8 }))
            .collect();
        let filled = vec![[1.0f32; 4]; 64];
        let s = sample_at(&frame, &filled, &g, 6, 6);
        assert!((s.albedo.x - 0.5).abs() < 1e-6 && (s.lighting.x - 2.0).abs() < 1e-5);
        let h = blend_history(
            &HistoryTexel::EMPTY,
            &s,
            HistoryCap::frames(4096.0),
            ClampBox::NONE,
        );
        // Shown with the pixel's own albedo: the checker comes back at full resolution.
        assert!((h.displayed(&g[6 * 8 + 6])[0] - 0.4).abs() < 1e-5);
        assert!((h.displayed(&g[6 * 8 + 7])[0] - 1.6).abs() < 1e-5);
        // A box of radiance becomes a box of lighting under the albedo the samples saw.
        let b = ClampBox {
            lo: Vec3::splat(0.5),
            hi: Vec3::splat(1.0),
        }
        .demodulated(s.albedo);
        assert_eq!((b.lo.x, b.hi.x), (1.0, 2.0));
    }
}
