//! Portable sin, cos, tan, atan2, exp, exp2 and ln built only from `+`, `-`, `*`, `/`, `floor` and bit
//! casts, so that the CPU host and a Vulkan driver compute the same bits, or nearly.
//!
//! Why: `libm` on the CPU and the GPU's `GLSL.std.450` instructions (which rust-gpu maps `libm` calls to)
//! are both accurate to a few ulp but not to the *same* ulp; one ulp in a sampled direction flips a
//! branch further down a path, and the two backends' images then differ in whole pixels (issue 3's frame
//! diff). IEEE `+ - * /` and `floor` are exactly rounded everywhere, so these polynomial versions agree
//! on the CPU and on lavapipe (which executes spirv-opt's fused `Fma` as a separate multiply and add):
//! for the arguments core gives them, 98 % of sin/cos/atan2 results bit for bit and the rest within 2 ulp
//! (`cross_backend_probe`). What remains is the driver's compiler regrouping sums of products (NIR
//! treats float operations without `NoContraction`, which rust-gpu does not emit, as reassociable); it
//! is why [`ln`] takes `e · ln 2` as one product. A GPU that fuses multiply-adds differs by rounding only.
//!
//! The range reductions and minimax polynomials are Stephen Moshier's Cephes single-precision ones
//! (`sinf.c`, `atanf.c`, `expf.c`, `logf.c`); the tests below measure the error against `f64` references.
//! Domains: `sin`/`cos`/`tan` are accurate for `|x| < 8192` (every angle core computes is within a few
//! multiples of 2π); the others over all finite inputs.

// The exactly rounded operations straight from `libm` (as `super::float` has them), so that this
// module, which `float` builds on, does not import it back.
use libm::{fabsf as abs, floorf as floor};

/// 2/π.
const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
/// π/2 split in three parts (Cody–Waite) so that `k · PIO2_1` and `k · PIO2_2` are exact for `|k| < 2¹²`:
/// together they are within 2e-15 of π/2.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_79e-8;

/// `x = k · π/2 + r` with `|r| ≤ π/4`; returns `(k mod 4, r)`.
#[inline]
fn reduce_half_pi(x: f32) -> (u32, f32) {
    let k = floor(x * FRAC_2_PI + 0.5);
    let r = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
    // Two's complement: `-1 & 3 == 3`, the quadrant of -π/2.
    ((k as i32 & 3) as u32, r)
}

/// `sin r` for `|r| ≤ π/4` (Cephes `sinf` polynomial).
#[inline]
fn sin_kernel(r: f32) -> f32 {
    let z = r * r;
    ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * r + r
}

/// `cos r` for `|r| ≤ π/4` (Cephes `cosf` polynomial).
#[inline]
fn cos_kernel(r: f32) -> f32 {
    let z = r * r;
    ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0
}

/// `(sin x, cos x)` from one range reduction.
#[inline]
#[must_use]
pub fn sin_cos(x: f32) -> (f32, f32) {
    let (quadrant, r) = reduce_half_pi(x);
    let (s, c) = (sin_kernel(r), cos_kernel(r));
    match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `tan x` as `sin x / cos x` (both from one reduction).
#[inline]
#[must_use]
pub fn tan(x: f32) -> f32 {
    let (s, c) = sin_cos(x);
    s / c
}

/// tan(π/8).
const TAN_PI_8: f32 = 0.414_213_57;

/// `atan t` for `0 ≤ t ≤ 1` (Cephes `atanf`: one reduction at tan(π/8), then a degree-9 odd polynomial).
#[inline]
fn atan_unit(t: f32) -> f32 {
    let (base, t) = if t > TAN_PI_8 {
        (core::f32::consts::FRAC_PI_4, (t - 1.0) / (t + 1.0))
    } else {
        (0.0, t)
    };
    let z = t * t;
    base + (((8.053_745e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * t
        + t
}

/// `atan2(y, x)` in `[-π, π]`. `atan2(0, 0) = 0`; the sign of a zero `y` is ignored (`atan2(-0, -1) = π`).
#[inline]
#[must_use]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (abs(x), abs(y));
    let steep = ay > ax;
    let (num, den) = if steep { (ax, ay) } else { (ay, ax) };
    // `num ≤ den`, so the ratio is in [0, 1] and cannot overflow.
    let t = if den > 0.0 { num / den } else { 0.0 };
    let mut a = atan_unit(t);
    if steep {
        a = core::f32::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = core::f32::consts::PI - a;
    }
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// `2^k` for an integer `k` in `[-126, 127]`, built from the exponent bits.
#[inline]
fn pow2i(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// `p · 2^k` for `k` in `[-252, 254]`, in two normal steps so that neither factor over- or underflows
/// on its own.
#[inline]
fn scale_by_pow2(p: f32, k: i32) -> f32 {
    let half = k / 2;
    p * pow2i(half) * pow2i(k - half)
}

/// Above this `e^x` overflows to infinity (ln of `f32::MAX`).
const EXP_MAX_ARG: f32 = 88.722_83;
/// Below this `e^x` is below the smallest subnormal.
const EXP_MIN_ARG: f32 = -103.972_08;
/// ln 2 split (Cody–Waite): `k · LN2_HI` is exact for `|k| < 2¹⁵`.
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;

/// `e^r` for `|r| ≤ ln2 / 2` (Cephes `expf` polynomial).
#[inline]
fn exp_kernel(r: f32) -> f32 {
    let z = r * r;
    let p = ((((1.987_569_1e-4 * r + 1.398_2e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 1.666_666_5e-1)
        * r
        + 5.0e-1;
    p * z + r + 1.0
}

/// `e^x`; `+∞` above `EXP_MAX_ARG`, `0` below `EXP_MIN_ARG`, NaN for NaN.
#[inline]
#[must_use]
pub fn exp(x: f32) -> f32 {
    if x > EXP_MAX_ARG {
        return f32::INFINITY;
    }
    if x < EXP_MIN_ARG {
        return 0.0;
    }
    let k = floor(x * core::f32::consts::LOG2_E + 0.5);
    let r = (x - k * LN2_HI) - k * LN2_LO;
    scale_by_pow2(exp_kernel(r), k as i32)
}

/// `2^x`, exact for integer `x` (the exposure factor `2^EV` of a whole-stop EV is exact).
#[inline]
#[must_use]
pub fn exp2(x: f32) -> f32 {
    if x >= 128.0 {
        return f32::INFINITY;
    }
    if x < -150.0 {
        return 0.0;
    }
    let k = floor(x + 0.5);
    // Exact: `x` and `k` are within a factor of two of each other or `|x| < 1`.
    let r = x - k;
    scale_by_pow2(exp_kernel(r * core::f32::consts::LN_2), k as i32)
}

/// √½.
const SQRT_HALF: f32 = core::f32::consts::FRAC_1_SQRT_2;

/// `ln x`; `-∞` for `x = 0`, NaN for `x < 0` or NaN, `+∞` for `+∞`. Subnormal inputs are scaled first,
/// so a GPU that flushes them still gets the same answer for normal inputs.
#[inline]
#[must_use]
pub fn ln(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 {
        return f32::NEG_INFINITY;
    }
    if x == f32::INFINITY {
        return f32::INFINITY;
    }
    let (x, e_bias) = if x < f32::MIN_POSITIVE {
        (x * 33_554_432.0, 25) // 2^25
    } else {
        (x, 0)
    };
    let bits = x.to_bits();
    // x = m · 2^e with m in [0.5, 1).
    let mut e = ((bits >> 23) & 0xff) as i32 - 126 - e_bias;
    let m = f32::from_bits((bits & 0x807f_ffff) | 0x3f00_0000);
    // Centre the mantissa on 1: m in [√½, √2), then f = m - 1.
    let f = if m < SQRT_HALF {
        e -= 1;
        m + m - 1.0
    } else {
        m - 1.0
    };
    let z = f * f;
    let mut y = ((((((((7.037_683_6e-2 * f - 1.151_461e-1) * f + 1.167_699_9e-1) * f
        - 1.242_014_1e-1)
        * f
        + 1.424_932_3e-1)
        * f
        - 1.666_805_8e-1)
        * f
        + 2.000_071_4e-1)
        * f
        - 2.499_999_4e-1)
        * f
        + 3.333_333e-1)
        * f
        * z;
    y -= 0.5 * z;
    // `e · ln 2` in one rounded product (Cephes splits ln 2 in two for another few tenths of an ulp, but
    // a GPU compiler may regroup the two products, as lavapipe did: `pow` then differed by up to 175 ulp).
    // Inputs near 1 have `e = 0`, so the product costs accuracy only where `|ln x| >= ln 2 / 2`, at most
    // half an ulp of the result.
    (f + y) + e as f32 * core::f32::consts::LN_2
}

/// `x^y` for `x ≥ 0` as `e^(y ln x)`: `0^y` is 0 for `y > 0`, `+∞` for `y < 0`; `x^0 = 1^y = 1`; NaN
/// for negative `x`. Relative error grows with `|y ln x|` (about `|y ln x| · 2⁻²³`).
#[inline]
#[must_use]
pub fn powf(x: f32, y: f32) -> f32 {
    if y == 0.0 || x == 1.0 {
        return 1.0;
    }
    if x == 0.0 {
        return if y > 0.0 { 0.0 } else { f32::INFINITY };
    }
    exp(y * ln(x))
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// Distance in units in the last place between `a` and the correctly rounded `exact`.
    fn ulps(a: f32, exact: f64) -> f64 {
        let e = exact as f32;
        if a == e {
            return 0.0;
        }
        let ulp = (f32::from_bits(e.abs().to_bits() + 1) - e.abs()) as f64;
        (a as f64 - exact).abs() / ulp
    }

    /// Evenly spaced points in `[lo, hi]`.
    fn sweep(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
        (0..=n).map(move |i| (lo + (hi - lo) * i as f64 / n as f64) as f32)
    }

    /// Log-spaced positive points in `[lo, hi]`.
    fn log_sweep(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
        let (a, b) = (lo.ln(), hi.ln());
        (0..=n).map(move |i| (a + (b - a) * i as f64 / n as f64).exp() as f32)
    }

    fn max_ulps(xs: impl Iterator<Item = f32>, f: impl Fn(f32) -> (f32, f64)) -> f64 {
        xs.map(|x| {
            let (got, exact) = f(x);
            ulps(got, exact)
        })
        .fold(0.0, f64::max)
    }

    #[test]
    fn reduction_constants_sum_to_half_pi() {
        let sum = PIO2_1 as f64 + PIO2_2 as f64 + PIO2_3 as f64;
        assert!((sum - core::f64::consts::FRAC_PI_2).abs() < 2e-15, "{sum}");
        // The leading parts have few mantissa bits, so their products with the quotient `k` are exact.
        assert_eq!(PIO2_1.to_bits() & 0xfff, 0);
        assert_eq!(PIO2_2.to_bits() & 0xfff, 0);
        assert_eq!(LN2_HI.to_bits() & 0x7fff, 0);
    }

    #[test]
    fn sin_cos_are_within_two_ulps_for_sampling_angles() {
        // Absolute error near zeros of sin/cos (where ulps are tiny) is what matters there.
        let xs = || {
            sweep(
                -4.0 * core::f64::consts::PI,
                4.0 * core::f64::consts::PI,
                1 << 20,
            )
        };
        let mut worst_abs: f64 = 0.0;
        let mut worst_ulps: f64 = 0.0;
        for x in xs() {
            let (s, c) = sin_cos(x);
            let (es, ec) = ((x as f64).sin(), (x as f64).cos());
            worst_abs = worst_abs
                .max((s as f64 - es).abs())
                .max((c as f64 - ec).abs());
            if es.abs() > 1e-3 {
                worst_ulps = worst_ulps.max(ulps(s, es));
            }
            if ec.abs() > 1e-3 {
                worst_ulps = worst_ulps.max(ulps(c, ec));
            }
        }
        assert!(worst_abs < 1.2e-7, "abs {worst_abs}");
        assert!(worst_ulps <= 2.0, "ulps {worst_ulps}");
        // Small arguments keep full relative precision.
        let small = max_ulps(log_sweep(1e-30, 1e-2, 4096), |x| {
            (sin_cos(x).0, (x as f64).sin())
        });
        assert!(small <= 1.0, "small-argument sin {small} ulps");
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        assert!(sin_cos(f32::NAN).0.is_nan() && sin_cos(f32::INFINITY).1.is_nan());
    }

    #[test]
    fn tan_matches_for_camera_and_display_angles() {
        let worst = max_ulps(sweep(-1.5, 1.5, 1 << 18), |x| (tan(x), (x as f64).tan()));
        assert!(worst <= 3.0, "tan {worst} ulps");
    }

    #[test]
    fn atan2_is_within_four_ulps_on_every_quadrant() {
        let mut worst: f64 = 0.0;
        for i in 0..4096 {
            let phi =
                -core::f64::consts::PI + 2.0 * core::f64::consts::PI * (i as f64 + 0.5) / 4096.0;
            for r in [1e-20, 1e-3, 1.0, 7.5, 1e20] {
                let (y, x) = ((r * phi.sin()) as f32, (r * phi.cos()) as f32);
                worst = worst.max(ulps(atan2(y, x), (y as f64).atan2(x as f64)));
            }
        }
        // Measured 3.2 (Cephes quotes 1.9e-7 relative): the reduced argument `(t - 1) / (t + 1)` rounds.
        assert!(worst <= 4.0, "atan2 {worst} ulps");
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(atan2(0.0, -1.0), core::f32::consts::PI);
        assert_eq!(atan2(1.0, 0.0), core::f32::consts::FRAC_PI_2);
        assert_eq!(atan2(-1.0, 0.0), -core::f32::consts::FRAC_PI_2);
        assert_eq!(atan2(f32::INFINITY, 1.0), core::f32::consts::FRAC_PI_2);
    }

    #[test]
    fn exp_and_exp2_are_within_two_ulps() {
        let e = max_ulps(sweep(-87.0, 88.7, 1 << 20), |x| (exp(x), (x as f64).exp()));
        assert!(e <= 2.0, "exp {e} ulps");
        let e2 = max_ulps(sweep(-125.0, 127.9, 1 << 20), |x| {
            (exp2(x), (x as f64).exp2())
        });
        assert!(e2 <= 2.0, "exp2 {e2} ulps");
        for k in -126..=127 {
            assert_eq!(exp2(k as f32), (k as f64).exp2() as f32, "2^{k} is exact");
        }
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(100.0), f32::INFINITY);
        assert_eq!(exp(-200.0), 0.0);
        assert_eq!(exp2(200.0), f32::INFINITY);
        assert!(exp(f32::NAN).is_nan());
    }

    #[test]
    fn ln_is_within_two_ulps_from_subnormals_to_max() {
        let worst = max_ulps(log_sweep(1e-44, 3.4e38, 1 << 20), |x| {
            (ln(x), (x as f64).ln())
        });
        assert!(worst <= 2.0, "ln {worst} ulps");
        // Near 1, where ln x → 0 and relative error is hardest.
        let near_one = max_ulps(sweep(0.5, 2.0, 1 << 20), |x| (ln(x), (x as f64).ln()));
        assert!(near_one <= 2.0, "ln near 1: {near_one} ulps");
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert!(ln(-1.0).is_nan() && ln(f32::NAN).is_nan());
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn powf_matches_for_srgb_and_gtr1_exponents() {
        // `e^(y ln x)` turns the rounding of `ln x` (up to about one ulp of `|ln x|`) into a relative
        // error of `|y ln x| · 2⁻²³`-ish: allow two ulps plus four times `|y ln x|` ulps.
        for y in [2.4, 1.0 / 2.4, 0.25, 0.9] {
            for x in log_sweep(1e-8, 4.0, 1 << 16) {
                let exact = (x as f64).powf(y as f64);
                let bound = 2.0 + 4.0 * (y as f64 * (x as f64).ln()).abs();
                let u = ulps(powf(x, y), exact);
                assert!(u <= bound, "{x}^{y}: {u} ulps (bound {bound})");
            }
        }
        assert_eq!(powf(0.0, 2.0), 0.0);
        assert_eq!(powf(0.0, -1.0), f32::INFINITY);
        assert_eq!(powf(5.0, 0.0), 1.0);
        assert_eq!(powf(1.0, 1e30), 1.0);
        assert!(powf(-2.0, 0.5).is_nan());
    }
}
