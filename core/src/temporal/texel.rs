//! One pixel's history as it is kept between frames (GPU layout): its mean lighting, weight,
//! luminance moments and frame count ([`super::history`] says how a frame joins it, [`super::resolve`]
//! what is shown of it).
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

use crate::math::vec3_from;

/// The largest channel value a frame may add to the history; larger finite values are clamped to it.
pub const HISTORY_SAMPLE_MAX: f32 = 1.0e6;

/// One pixel's history (48 bytes, GPU layout): its own samples, and the frame's fill at the pixel
/// averaged over time (the stable block reconstruction [`super::resolve`] falls back on).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HistoryTexel {
    /// rgb: the mean lighting (the pixel's samples' radiance over its albedo); w: its weight, in samples
    /// of this pixel.
    pub mean: [f32; 4],
    /// x: the lighting's mean luminance, y: its mean squared luminance (the second moment, for a
    /// variance; each frame's samples enter as their mean), z: the block edge of the fill that `fill`
    /// averages, w: frames in the history (those with a sample of the pixel; capped).
    pub moments: [f32; 4],
    /// rgb: the frame's fill at the pixel (lighting: the filled value over the albedo its samples
    /// saw) averaged over frames; w: how many (capped). A new block size starts it afresh.
    pub fill: [f32; 4],
}

impl HistoryTexel {
    /// No history.
    pub const EMPTY: Self = Self {
        mean: [0.0; 4],
        moments: [0.0; 4],
        fill: [0.0; 4],
    };

    /// The mean lighting: the pixel's radiance divided by its albedo.
    #[inline]
    #[must_use]
    pub fn lighting(&self) -> Vec3 {
        vec3_from(self.mean)
    }

    /// The weight (samples of this pixel behind the mean).
    #[inline]
    #[must_use]
    pub fn weight(&self) -> f32 {
        self.mean[3]
    }

    /// The fill's lighting averaged over frames.
    #[inline]
    #[must_use]
    pub fn fill_lighting(&self) -> Vec3 {
        vec3_from(self.fill)
    }

    /// Frames in the fill's average.
    #[inline]
    #[must_use]
    pub fn fill_frames(&self) -> f32 {
        self.fill[3]
    }

    /// The block edge of the fill that [`Self::fill_lighting`] averages.
    #[inline]
    #[must_use]
    pub fn fill_block(&self) -> f32 {
        self.moments[2]
    }

    /// Frames in the history.
    #[inline]
    #[must_use]
    pub fn frames(&self) -> f32 {
        self.moments[3]
    }

    /// The luminance variance of the frames' lighting (second moment minus the squared mean).
    #[inline]
    #[must_use]
    pub fn luminance_variance(&self) -> f32 {
        (self.moments[1] - self.moments[0] * self.moments[0]).max(0.0)
    }

    /// `self + other · s`, every field (for blending taps).
    #[inline]
    #[must_use]
    pub fn add_scaled(&self, other: &Self, s: f32) -> Self {
        Self {
            mean: (Vec4::from(self.mean) + Vec4::from(other.mean) * s).to_array(),
            moments: (Vec4::from(self.moments) + Vec4::from(other.moments) * s).to_array(),
            fill: (Vec4::from(self.fill) + Vec4::from(other.fill) * s).to_array(),
        }
    }

    /// Every field times `s`.
    #[inline]
    #[must_use]
    pub fn scaled(&self, s: f32) -> Self {
        Self::EMPTY.add_scaled(self, s)
    }
}
