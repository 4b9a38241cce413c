//! Exposure compensation and Reinhard tone mapping to 8-bit sRGB (Mohanto et al. 2023, section 3.4).
//!
//! The global Reinhard operator on luminance (Reinhard et al. 2002, eq. 3, without the white point):
//! with `c` the exposed linear colour and `L` its Rec.709 luminance, `c' = c / (1 + L)`. This is the form
//! of the paper's public code; fovea makes the exposure (`2^EV`, their code hard-wires 2^4) a parameter.
//! Inputs are guarded first: NaN and negative channels become 0 and `+inf` a large finite value, so every
//! input maps to a finite, in-range output.
use glam::Vec3;

use crate::math::color::{linear_to_srgb, luminance};
use crate::math::float::{exp2, is_finite};

/// Largest channel value tone mapping works with; larger (and `+inf`) inputs are clamped to it. Its
/// luminance and `1 + L` stay finite in `f32`.
pub const HDR_MAX: f32 = 1.0e30;

/// The exposure factor `2^ev` for an exposure compensation of `ev` stops; a non-finite `ev` counts as 0.
#[inline]
#[must_use]
pub fn exposure_scale(ev: f32) -> f32 {
    if is_finite(ev) {
        exp2(ev)
    } else {
        1.0
    }
}

/// One channel guarded for tone mapping: NaN and negatives to 0, `+inf` and huge values to [`HDR_MAX`].
#[inline]
#[must_use]
fn sanitize_channel(x: f32) -> f32 {
    if is_finite(x) {
        x.clamp(0.0, HDR_MAX)
    } else if x > 0.0 {
        HDR_MAX
    } else {
        // NaN (every comparison is false) or -inf.
        0.0
    }
}

/// `c` with every channel in [0, [`HDR_MAX`]]: NaN and negative channels become 0, `+inf` [`HDR_MAX`].
#[inline]
#[must_use]
pub fn sanitize_hdr(c: Vec3) -> Vec3 {
    Vec3::new(
        sanitize_channel(c.x),
        sanitize_channel(c.y),
        sanitize_channel(c.z),
    )
}

/// Reinhard's global operator on luminance: `c / (1 + L(c))`, for non-negative finite `c`. Grey maps
/// into [0, 1); saturated colours can exceed 1 in one channel and are clamped by [`tonemap_linear`].
#[inline]
#[must_use]
pub fn reinhard(c: Vec3) -> Vec3 {
    c / (1.0 + luminance(c))
}

/// Guarded, exposed and Reinhard-tone-mapped linear colour, each channel in [0, 1].
#[inline]
#[must_use]
pub fn tonemap_linear(hdr: Vec3, exposure_ev: f32) -> Vec3 {
    let exposed = sanitize_hdr(sanitize_hdr(hdr) * exposure_scale(exposure_ev));
    reinhard(exposed).clamp(Vec3::ZERO, Vec3::ONE)
}

/// A value in [0, 1] quantised to 0..=255 (round to nearest); out-of-range and NaN inputs are clamped
/// (NaN to 0).
#[inline]
#[must_use]
pub fn unorm8(v: f32) -> u32 {
    let v = if is_finite(v) { v.clamp(0.0, 1.0) } else { 0.0 };
    (v * 255.0 + 0.5) as u32
}

/// Packs 8-bit channels into RGBA8 with R in the low byte and A = 255 (little-endian `R, G, B, A` bytes).
#[inline]
#[must_use]
pub fn pack_rgba8(r: u32, g: u32, b: u32) -> u32 {
    (r & 0xff) | ((g & 0xff) << 8) | ((b & 0xff) << 16) | (0xff << 24)
}

/// The full post-process of one pixel: exposure, Reinhard, sRGB encoding, quantisation and packing.
#[inline]
#[must_use]
pub fn tonemap_to_rgba8(hdr: Vec3, exposure_ev: f32) -> u32 {
    let c = tonemap_linear(hdr, exposure_ev);
    pack_rgba8(
        unorm8(linear_to_srgb(c.x)),
        unorm8(linear_to_srgb(c.y)),
        unorm8(linear_to_srgb(c.z)),
    )
}

/// [`tonemap_to_rgba8`] as 8-bit sRGB channels (host helper; kernels use the packed form).
#[inline]
#[must_use]
pub fn tonemap_to_srgb8(hdr: Vec3, exposure_ev: f32) -> [u8; 3] {
    let p = tonemap_to_rgba8(hdr, exposure_ev);
    [p as u8, (p >> 8) as u8, (p >> 16) as u8]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_is_a_power_of_two() {
        assert_eq!(exposure_scale(0.0), 1.0);
        assert!((exposure_scale(4.0) - 16.0).abs() < 1e-5);
        assert!((exposure_scale(-1.0) - 0.5).abs() < 1e-7);
        assert_eq!(exposure_scale(f32::NAN), 1.0);
        // Exposure commutes with scaling the input.
        assert_eq!(
            tonemap_to_rgba8(Vec3::splat(0.5), 1.0),
            tonemap_to_rgba8(Vec3::splat(1.0), 0.0)
        );
    }

    #[test]
    fn zero_maps_to_black_and_grey_one_to_half() {
        assert_eq!(tonemap_linear(Vec3::ZERO, 0.0), Vec3::ZERO);
        assert_eq!(tonemap_to_srgb8(Vec3::ZERO, 4.0), [0, 0, 0]);
        assert_eq!(tonemap_to_rgba8(Vec3::ZERO, 0.0), 0xff00_0000);
        // L = 1 → 0.5 linear → sRGB 0.7354 → 188.
        let c = tonemap_linear(Vec3::ONE, 0.0);
        assert!((c - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert_eq!(tonemap_to_srgb8(Vec3::ONE, 0.0), [188, 188, 188]);
    }

    #[test]
    fn monotone_in_luminance() {
        let tints = [
            Vec3::ONE,
            Vec3::new(1.0, 0.5, 0.25),
            Vec3::new(0.1, 0.2, 1.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        for tint in tints {
            let mut prev_l = -1.0;
            let mut prev_8 = [0u8; 3];
            let mut k = 1.0e-4f32;
            while k < 1.0e7 {
                let c = tonemap_linear(tint * k, 0.0);
                let l = luminance(c);
                // Up to float rounding of the luminance (relative 1e-6) near saturation.
                assert!(l >= prev_l * (1.0 - 1e-6), "{tint} × {k}: {l} < {prev_l}");
                let q = tonemap_to_srgb8(tint * k, 0.0);
                for i in 0..3 {
                    assert!(q[i] >= prev_8[i]);
                }
                prev_l = l;
                prev_8 = q;
                k *= 1.1;
            }
        }
    }

    #[test]
    fn huge_values_stay_below_one() {
        for v in [10.0f32, 1.0e3, 1.0e6] {
            let c = tonemap_linear(Vec3::splat(v), 0.0);
            assert!(c.max_element() < 1.0, "{v}: {c}");
        }
        for v in [1.0e20f32, f32::MAX] {
            let c = tonemap_linear(Vec3::splat(v), 10.0);
            assert!(c.is_finite() && c.max_element() <= 1.0, "{v}: {c}");
            assert_eq!(tonemap_to_srgb8(Vec3::splat(v), 10.0), [255, 255, 255]);
        }
    }

    #[test]
    fn invalid_inputs_give_finite_outputs() {
        let bad = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -1.0,
            -1.0e30,
            0.5,
        ];
        for x in bad {
            for y in bad {
                for ev in [0.0, 4.0, f32::NAN, f32::INFINITY, -200.0, 200.0] {
                    let c = tonemap_linear(Vec3::new(x, y, 0.25), ev);
                    assert!(c.is_finite(), "{x} {y} {ev}: {c}");
                    assert!(c.min_element() >= 0.0 && c.max_element() <= 1.0);
                    let p = tonemap_to_rgba8(Vec3::new(x, y, 0.25), ev);
                    assert_eq!(p >> 24, 0xff);
                }
            }
        }
        // NaN and negatives are black, +inf is white.
        assert_eq!(
            tonemap_to_srgb8(Vec3::new(f32::NAN, -3.0, 0.0), 0.0),
            [0, 0, 0]
        );
        assert_eq!(
            tonemap_to_srgb8(Vec3::splat(f32::INFINITY), 0.0),
            [255, 255, 255]
        );
        assert_eq!(unorm8(f32::NAN), 0);
        assert_eq!(unorm8(2.0), 255);
        assert_eq!(unorm8(-2.0), 0);
    }

    #[test]
    fn packing_order() {
        assert_eq!(pack_rgba8(1, 2, 3), 0xff03_0201);
        assert_eq!(pack_rgba8(255, 0, 0).to_le_bytes(), [255, 0, 0, 255]);
        assert_eq!(unorm8(0.5), 128);
    }
}
