//! Scalar float functions for core code on both targets (instead of `f32::sin` &c., which need `std`).
//!
//! `sqrt`, `fma`, `floor` and `abs` go through `libm`, which rustc_codegen_spirv maps to GLSL.std.450
//! instructions; those are exactly rounded on both backends. On the CPU host (core's `std` feature)
//! `sqrt` and `fma` are the standard library's instead: the same bits, without libm's x86-64 `asm!`. The transcendental functions are the
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

/// The correctly rounded square root (IEEE 754), so the same bits on every backend.
///
/// With the `std` feature (the CPU host) it is `f32::sqrt`, which the compiler emits as `vsqrtss` in AVX
/// code. Without it (core alone, the SPIR-V kernel) it is `libm`'s `sqrtf`, which on x86-64 is an `asm!`
/// block of the legacy-encoded `sqrtss`: the compiler cannot schedule it, and in code that uses the
/// AVX-512 registers it cost a fifth of the à-trous step's time (`perf annotate`, docs/performance.md).
/// Both round exactly, so the results are the same bits.
#[inline]
#[must_use]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(feature = "std")]
    {
        x.sqrt()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sqrtf(x)
    }
}

/// `a * b + c` with one rounding (IEEE 754 fused multiply-add), so the same bits on every backend.
///
/// With the `std` feature it is `f32::mul_add`, one inlined `vfmadd` where the build has FMA (the
/// native and x86-64-v3 builds). Without it, `libm`'s `fmaf`, which on x86-64 picks its
/// implementation at run time and is called through a pointer, never inlined.
#[inline]
#[must_use]
pub fn fma(a: f32, b: f32, c: f32) -> f32 {
    #[cfg(feature = "std")]
    {
        a.mul_add(b, c)
    }
    #[cfg(not(feature = "std"))]
    {
        libm::fmaf(a, b, c)
    }
}

/// `sqrt(max(x, 0))`: total for inputs that rounding pushed slightly below zero.
#[inline]
#[must_use]
pub fn safe_sqrt(x: f32) -> f32 {
    sqrt(x.max(0.0))
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

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// Whichever square root the build picks (`f32::sqrt` with `std`, `libm` without), it is the
    /// correctly rounded one, bit for bit what the other build and libm give: the CPU host's switch to
    /// `std` changes no pixel. (An f32's root rounded through f64 is correctly rounded: 53 ≥ 2·24 + 2.)
    #[test]
    fn the_square_root_is_correctly_rounded_and_libms_bits() {
        let mut bits = 0u32;
        let mut checked = 0;
        while bits < 0x7f80_0000 {
            let x = f32::from_bits(bits);
            let exact = (f64::from(x)).sqrt() as f32;
            assert_eq!(sqrt(x).to_bits(), exact.to_bits(), "sqrt({x:e})");
            assert_eq!(
                sqrt(x).to_bits(),
                libm::sqrtf(x).to_bits(),
                "sqrt({x:e}) against libm"
            );
            bits += 0x7f7; // about 1.04 million inputs, every exponent, odd and even mantissas
            checked += 1;
        }
        assert!(checked > 1_000_000);
        assert_eq!(sqrt(f32::INFINITY), f32::INFINITY);
        assert_eq!(sqrt(-0.0).to_bits(), (-0.0f32).to_bits());
        assert!(sqrt(-1.0).is_nan());
        assert_eq!(safe_sqrt(-1.0e-9), 0.0);
    }

    /// The fused multiply-add rounds once, as libm's does, on both builds: `a·b − a·b` rounded
    /// separately is 0, fused it is the product's rounding error.
    #[test]
    fn the_fused_multiply_add_rounds_once_and_matches_libm() {
        let mut state = 0x9e37_79b9u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            // Either sign, magnitudes below 2 down to the subnormals: no product overflows.
            f32::from_bits(state & 0xbfff_ffff)
        };
        let mut recovered = 0;
        for _ in 0..200_000 {
            let (a, b, c) = (next(), next(), next());
            assert_eq!(
                fma(a, b, c).to_bits(),
                libm::fmaf(a, b, c).to_bits(),
                "fma({a:e}, {b:e}, {c:e})"
            );
            let p = a * b;
            if p.is_finite() && p != 0.0 {
                let exact = f64::from(a) * f64::from(b) - f64::from(p);
                assert_eq!(fma(a, b, -p), exact as f32, "the error of {a:e} * {b:e}");
                recovered += usize::from(exact != 0.0);
            }
        }
        assert!(
            recovered > 1000,
            "only {recovered} products had a rounding error to recover"
        );
    }
}
