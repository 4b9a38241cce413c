//! Colour helpers (linear Rec.709 / sRGB primaries).
use glam::Vec3;

/// Rec.709 relative luminance of linear RGB.
#[inline]
#[must_use]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// sRGB transfer function, linear in [0, 1] to encoded.
#[inline]
#[must_use]
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * super::float::powf(v, 1.0 / 2.4) - 0.055
    }
}

/// Whether all three channels are finite.
#[inline]
#[must_use]
pub fn is_finite3(c: Vec3) -> bool {
    super::float::is_finite(c.x) && super::float::is_finite(c.y) && super::float::is_finite(c.z)
}
