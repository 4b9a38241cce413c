//! What sampling a light gives a shading point ([`LightSample`]), shared by every kind of light.
use glam::Vec3;

/// Farthest distance a shadow ray towards an infinitely distant light travels.
pub const INFINITE_DISTANCE: f32 = 3.0e38;

/// A sampled light contribution towards a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub direction: Vec3,
    /// For area lights, the point on the light, already offset off its surface towards the shading
    /// point, so a shadow ray can stop exactly there; for infinitely distant lights unused.
    pub target: Vec3,
    /// Whether the light is infinitely far away (shadow rays go to [`INFINITE_DISTANCE`]).
    pub is_infinite: bool,
    /// Radiance (area and environment lights) or irradiance-like intensity (delta lights) arriving along
    /// `-direction`, not yet divided by `pdf`.
    pub radiance: Vec3,
    /// Solid-angle density of the sample including the light-selection probability; for delta lights the
    /// selection probability alone. 0 means no contribution.
    pub pdf: f32,
    /// Delta lights (point, spot, directional) cannot be hit by BSDF sampling: no MIS weight.
    pub is_delta: bool,
}

impl LightSample {
    /// A sample that contributes nothing.
    #[inline]
    #[must_use]
    pub fn none() -> Self {
        Self {
            direction: Vec3::Z,
            target: Vec3::ZERO,
            is_infinite: true,
            radiance: Vec3::ZERO,
            pdf: 0.0,
            is_delta: false,
        }
    }
}
