//! Cosine-weighted hemisphere, uniform sphere, cone, disk and triangle warps (pbrt-v4 §A.5).
//!
//! Each warp maps `u` in [0, 1)² to a point or direction whose density is given by the matching `*_pdf`
//! function or constant. All of them return finite values for any finite `u`.
use crate::math::float::{cos, safe_sqrt, sin, INV_4PI, INV_PI, PI};
use glam::{Vec2, Vec3};

/// Solid-angle density of [`square_to_uniform_sphere`]: 1 / (4π).
pub const UNIFORM_SPHERE_PDF: f32 = INV_4PI;

/// Shirley and Chiu 1997 concentric map from the square to the unit disk (area-preserving up to a
/// constant, low distortion, continuous).
#[inline]
#[must_use]
pub fn square_to_concentric_disk(u: Vec2) -> Vec2 {
    let ox = 2.0 * u.x - 1.0;
    let oy = 2.0 * u.y - 1.0;
    if ox == 0.0 && oy == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if ox.abs() > oy.abs() {
        (ox, 0.25 * PI * (oy / ox))
    } else {
        (oy, 0.5 * PI - 0.25 * PI * (ox / oy))
    };
    Vec2::new(r * cos(theta), r * sin(theta))
}

/// Cosine-weighted direction on the +z hemisphere (Malley's method: a concentric disk point lifted onto
/// the hemisphere). Density [`cosine_hemisphere_pdf`].
#[inline]
#[must_use]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_concentric_disk(u);
    let z = safe_sqrt(1.0 - d.x * d.x - d.y * d.y);
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle density of [`square_to_cosine_hemisphere`]: cos θ / π, zero below the horizon.
#[inline]
#[must_use]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * INV_PI
}

/// Uniform direction on the unit sphere. Density [`UNIFORM_SPHERE_PDF`].
#[inline]
#[must_use]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * cos(phi), r * sin(phi), z)
}

/// Uniform direction inside the cone of half-angle θmax around +z (`cos_theta_max` is clamped to
/// [-1, 1]). Density [`uniform_cone_pdf`].
#[inline]
#[must_use]
pub fn square_to_uniform_cone(u: Vec2, cos_theta_max: f32) -> Vec3 {
    let c = cos_theta_max.clamp(-1.0, 1.0);
    // 1 - cos θ, kept separately so that narrow cones keep their precision.
    let one_minus_cos = u.x * (1.0 - c);
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta)
}

/// Solid-angle density of [`square_to_uniform_cone`]: 1 / (2π (1 - cos θmax)). A degenerate cone
/// (`cos_theta_max >= 1`) gets a large finite density instead of infinity.
#[inline]
#[must_use]
pub fn uniform_cone_pdf(cos_theta_max: f32) -> f32 {
    let solid_angle = 2.0 * PI * (1.0 - cos_theta_max.clamp(-1.0, 1.0));
    1.0 / solid_angle.max(1e-30)
}

/// Uniform point on a triangle as barycentrics `(b1, b2)` of its vertices `v1` and `v2` (`b0 = 1 - b1 -
/// b2`), with Heitz's low-distortion square-to-triangle map (Heitz 2019, "A Low-Distortion Map Between
/// Triangle and Square"; pbrt-v4 `SampleUniformTriangle`). Density 1 / area.
#[inline]
#[must_use]
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let (a, b) = if u.x < u.y {
        let a = 0.5 * u.x;
        (a, u.y - a)
    } else {
        let b = 0.5 * u.y;
        (u.x - b, b)
    };
    Vec2::new(a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_support::XorShift32 as Rng;

    #[test]
    fn concentric_disk_stays_in_disk_and_is_uniform() {
        let mut rng = Rng(7);
        let n = 200_000;
        let mut inner = 0u32;
        let mut mean = Vec2::ZERO;
        for _ in 0..n {
            let p = square_to_concentric_disk(rng.vec2());
            assert!(p.length() <= 1.0 + 1e-6);
            if p.length_squared() < 0.25 {
                inner += 1;
            }
            mean += p;
        }
        // The disk of radius 1/2 holds a quarter of the area.
        let frac = inner as f32 / n as f32;
        assert!((frac - 0.25).abs() < 0.005, "{frac}");
        assert!((mean / n as f32).length() < 0.01);
        assert_eq!(square_to_concentric_disk(Vec2::splat(0.5)), Vec2::ZERO);
    }

    #[test]
    fn cosine_hemisphere_is_unit_and_has_right_mean() {
        let mut rng = Rng(11);
        let n = 200_000;
        let mut mean_z = 0.0f64;
        for _ in 0..n {
            let w = square_to_cosine_hemisphere(rng.vec2());
            assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0);
            mean_z += w.z as f64;
        }
        // E[cos θ] under cos θ / π is 2/3.
        assert!((mean_z / n as f64 - 2.0 / 3.0).abs() < 3e-3);
        assert_eq!(cosine_hemisphere_pdf(-0.5), 0.0);
        assert!((cosine_hemisphere_pdf(1.0) - INV_PI).abs() < 1e-7);
    }

    #[test]
    fn uniform_sphere_is_unit_and_balanced() {
        let mut rng = Rng(3);
        let n = 200_000;
        let mut mean = Vec3::ZERO;
        let mut upper = 0u32;
        for _ in 0..n {
            let w = square_to_uniform_sphere(rng.vec2());
            assert!((w.length() - 1.0).abs() < 1e-5);
            mean += w;
            if w.z > 0.5 {
                upper += 1;
            }
        }
        assert!((mean / n as f32).length() < 0.01);
        // The cap z > 1/2 is a quarter of the sphere.
        assert!((upper as f32 / n as f32 - 0.25).abs() < 0.005);
        assert!((UNIFORM_SPHERE_PDF * 4.0 * PI - 1.0).abs() < 1e-6);
    }

    #[test]
    fn uniform_cone_stays_in_cone() {
        let mut rng = Rng(5);
        for &c in &[0.99f32, 0.5, 0.0, -0.7, 1.0, 0.999_999] {
            let mut mean_z = 0.0f64;
            let n = 50_000;
            for _ in 0..n {
                let w = square_to_uniform_cone(rng.vec2(), c);
                assert!((w.length() - 1.0).abs() < 1e-5);
                assert!(w.z >= c - 1e-6);
                mean_z += w.z as f64;
            }
            // z is uniform on [c, 1].
            let expect = 0.5 * (1.0 + c as f64);
            assert!((mean_z / n as f64 - expect).abs() < 0.01 * (1.0 - c as f64) + 1e-6);
            assert!(uniform_cone_pdf(c).is_finite() && uniform_cone_pdf(c) > 0.0);
        }
        assert!((uniform_cone_pdf(-1.0) - UNIFORM_SPHERE_PDF).abs() < 1e-7);
    }

    #[test]
    fn triangle_barycentrics_are_valid_and_uniform() {
        let mut rng = Rng(9);
        let n = 300_000;
        let mut mean = Vec2::ZERO;
        // Split the triangle into its 4 midpoint sub-triangles: each must get a quarter.
        let mut counts = [0u32; 4];
        for _ in 0..n {
            let b = square_to_uniform_triangle(rng.vec2());
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            mean += b;
            let b0 = 1.0 - b.x - b.y;
            let k = if b0 > 0.5 {
                0
            } else if b.x > 0.5 {
                1
            } else if b.y > 0.5 {
                2
            } else {
                3
            };
            counts[k] += 1;
        }
        let m = mean / n as f32;
        assert!((m.x - 1.0 / 3.0).abs() < 3e-3 && (m.y - 1.0 / 3.0).abs() < 3e-3);
        for c in counts {
            assert!((c as f32 / n as f32 - 0.25).abs() < 5e-3, "{counts:?}");
        }
    }

    /// Histogram check of the cosine-hemisphere warp against `cosine_hemisphere_pdf` on a (cos θ, φ)
    /// grid: a chi-square statistic well below what a wrong density produces.
    #[test]
    fn cosine_hemisphere_histogram_matches_pdf() {
        const NT: usize = 8;
        const NP: usize = 16;
        let mut counts = [[0u32; NP]; NT];
        let mut rng = Rng(1234);
        let n = 400_000u32;
        for _ in 0..n {
            let w = square_to_cosine_hemisphere(rng.vec2());
            let t = ((w.z * NT as f32) as usize).min(NT - 1);
            let phi = libm::atan2f(w.y, w.x) + PI;
            let p = ((phi / (2.0 * PI) * NP as f32) as usize).min(NP - 1);
            counts[t][p] += 1;
        }
        let mut chi2 = 0.0f64;
        for (t, row) in counts.iter().enumerate() {
            // ∫ cos θ / π dω over z in [z0, z1], one φ bin: (z1² - z0²) / 2 / NP · 2π / π.
            let z0 = t as f64 / NT as f64;
            let z1 = (t + 1) as f64 / NT as f64;
            let expect = (z1 * z1 - z0 * z0) / NP as f64 * n as f64;
            for &c in row {
                let d = c as f64 - expect;
                chi2 += d * d / expect;
            }
        }
        // 127 degrees of freedom: mean 127, a 5-sigma bound is about 207.
        assert!(chi2 < 220.0, "chi2 = {chi2}");
    }

    /// Chi-square test of the cosine-hemisphere warp against `cosine_hemisphere_pdf` on a 32 × 64
    /// (cos θ, φ) grid of the hemisphere (see [`crate::test_support::chi2`]); also `z >= 0` always.
    #[test]
    fn chi2_cosine_hemisphere() {
        use crate::test_support::chi2::{chi2_test, family_share, sample_count, Grid};
        assert_eq!(family_share("cosine hemisphere"), 1);
        let n = sample_count(1_000_000, 10_000_000);
        let grid = Grid::hemisphere(32, 64).clip(Vec3::Z);
        chi2_test(
            "cosine hemisphere",
            &grid,
            n,
            0xC05,
            |rng| {
                let u = Vec2::new(rng.uniform(), rng.uniform());
                Some(square_to_cosine_hemisphere(u))
            },
            |w| cosine_hemisphere_pdf(w.z) as f64,
        )
        .check();
    }
}
