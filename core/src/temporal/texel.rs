//! One pixel's history as it is kept between frames (GPU layout): its mean lighting, weight,
//! luminance moments, footprint and frame count ([`super::history`] says how a frame joins it).
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

use super::albedo::demodulation_albedo;
use super::gbuffer::GBufferTexel;
use crate::math::vec3_from;

/// The largest channel value a frame may add to the history; larger finite values are clamped to it.
pub const HISTORY_SAMPLE_MAX: f32 = 1.0e6;

/// One pixel's history (32 bytes, GPU layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HistoryTexel {
    /// rgb: the mean lighting (radiance over the albedo the samples saw); w: its weight, in samples of
    /// this pixel.
    pub mean: [f32; 4],
    /// x: the lighting's mean luminance, y: its mean squared luminance (the second moment, for a variance), z: the
    /// footprint (weighted mean block edge of the samples), w: frames in the history (capped).
    pub moments: [f32; 4],
}

impl HistoryTexel {
    /// No history.
    pub const EMPTY: Self = Self {
        mean: [0.0; 4],
        moments: [0.0; 4],
    };

    /// The mean lighting: radiance divided by the albedo its samples saw.
    #[inline]
    #[must_use]
    pub fn lighting(&self) -> Vec3 {
        vec3_from(self.mean)
    }

    /// The pixel as displayed, over the G-buffer texel `g` of this frame: the mean lighting times the
    /// pixel's own albedo, alpha 1 (the HDR image's layout).
    #[inline]
    #[must_use]
    pub fn displayed(&self, g: &GBufferTexel) -> [f32; 4] {
        let c = self.lighting() * demodulation_albedo(g);
        [c.x, c.y, c.z, 1.0]
    }

    /// The weight (samples of this pixel behind the mean).
    #[inline]
    #[must_use]
    pub fn weight(&self) -> f32 {
        self.mean[3]
    }

    /// The footprint: the weighted mean block edge of the samples, in pixels.
    #[inline]
    #[must_use]
    pub fn footprint(&self) -> f32 {
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
        }
    }

    /// Every field times `s`.
    #[inline]
    #[must_use]
    pub fn scaled(&self, s: f32) -> Self {
        Self::EMPTY.add_scaled(self, s)
    }
}
