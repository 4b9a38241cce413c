//! Scalar float functions for core code on both targets (instead of `f32::sin` &c., which need `std`).
//!
//! `sqrt`, `floor` and `abs` go through `libm`, which rustc_codegen_spirv maps to GLSL.std.450
//! instructions; those are exactly rounded on both backends. The transcendental functions are the
//! portable polynomials of [`super::transcendental`], so that the CPU and a Vulkan driver agree to the
//! bit (the GPU's own `Sin`, `Log`, `Pow` differ from `libm` by an ulp here and there).

use super::transcendental;

/// π.
pub const PI: f32 = core::f32::consts::PI;
/// 1 / π.
pub const INV_PI: f32 = core::f32::consts::FRAC_1_PI;
/// 1 / (2π).
pub const INV_2PI: f32 = 0.5 * core::f32::consts::FRAC_1_PI;
/// 1 / (4π).
pub const INV_4PI: f32 = 0.25 * core::f32::consts::FRAC_1_PI;

#[inline]
#[must_use]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// `sqrt(max(x, 0))`: total for inputs that rounding pushed slightly below zero.
#[inline]
#[must_use]
pub fn safe_sqrt(x: f32) -> f32 {
    libm::sqrtf(x.max(0.0))
}

#[inline]
#[must_use]
pub fn sin(x: f32) -> f32 {
    transcendental::sin_cos(x).0
}

#[inline]
#[must_use]
pub fn cos(x: f32) -> f32 {
    transcendental::sin_cos(x).1
}

#[inline]
#[must_use]
pub fn tan(x: f32) -> f32 {
    transcendental::tan(x)
}

/// `acos` of `x` clamped to [-1, 1].
#[inline]
#[must_use]
pub fn safe_acos(x: f32) -> f32 {
    let x = x.clamp(-1.0, 1.0);
    transcendental::atan2(safe_sqrt((1.0 - x) * (1.0 + x)), x)
}

#[inline]
#[must_use]
pub fn atan2(y: f32, x: f32) -> f32 {
    transcendental::atan2(y, x)
}

#[inline]
#[must_use]
pub fn exp(x: f32) -> f32 {
    transcendental::exp(x)
}

#[inline]
#[must_use]
pub fn ln(x: f32) -> f32 {
    transcendental::ln(x)
}

#[inline]
#[must_use]
pub fn powf(x: f32, y: f32) -> f32 {
    transcendental::powf(x, y)
}

/// `2^x`, exact for whole `x`.
#[inline]
#[must_use]
pub fn exp2(x: f32) -> f32 {
    transcendental::exp2(x)
}

/// `(sin x, cos x)` with one range reduction.
#[inline]
#[must_use]
pub fn sin_cos(x: f32) -> (f32, f32) {
    transcendental::sin_cos(x)
}

#[inline]
#[must_use]
pub fn floor(x: f32) -> f32 {
    libm::floorf(x)
}

#[inline]
#[must_use]
pub fn abs(x: f32) -> f32 {
    libm::fabsf(x)
}

/// `x²`.
#[inline]
#[must_use]
pub fn sqr(x: f32) -> f32 {
    x * x
}

/// Whether `x` is neither NaN nor infinite.
#[inline]
#[must_use]
pub fn is_finite(x: f32) -> bool {
    // Bit test: GPU compilers may fold `x == x` away under fast-math assumptions.
    (x.to_bits() & 0x7f80_0000) != 0x7f80_0000
}
