//! The anisotropic GGX (Trowbridge-Reitz) microfacet distribution: its normal distribution `D`, Smith's
//! masking function, and sampling of its distribution of visible normals (VNDF).
//!
//! Local frame, `z` = macro-surface normal; `ax` and `ay` are the roughnesses along `x` and `y`, clamped
//! below to [`ALPHA_MIN`]. References: Walter et al. 2007 (GGX), Heitz 2014 ("Understanding the Masking-
//! Shadowing Function in Microfacet-Based BRDFs"), Dupuy and Benyoub 2023 ("Sampling Visible GGX Normals
//! with Spherical Caps").
use crate::math::float::{cos, safe_sqrt, sin, sqrt, INV_PI, PI};
use glam::{Vec2, Vec3};

/// Smallest GGX alpha used anywhere: roughness 0 becomes a near-mirror with alpha 1e-4 instead of a
/// delta distribution, so that `D`, the pdf and the BRDF stay finite (D ≤ 1 / (π · 1e-8) ≈ 3.2e7).
pub const ALPHA_MIN: f32 = 1e-4;

/// `v / |v|`, or zero for a (near-)zero vector. Vectors already of unit length (±1e-5 in squared length)
/// pass through unchanged, so normalising twice gives bit-identical results.
#[inline]
#[must_use]
pub(crate) fn normalize_or_zero(v: Vec3) -> Vec3 {
    let l2 = v.length_squared();
    if (l2 - 1.0).abs() <= 1e-5 {
        return v;
    }
    // Scale by the largest component first so that huge or tiny vectors neither overflow nor underflow.
    let m = v.x.abs().max(v.y.abs()).max(v.z.abs());
    if m <= 1e-30 {
        return Vec3::ZERO;
    }
    let s = v * (1.0 / m);
    s * (1.0 / sqrt(s.length_squared()))
}

/// `ax² x² + ay² y²`: the part of the Smith masking term that depends on the direction's azimuth.
#[inline]
#[must_use]
fn tangent_term(w: Vec3, ax: f32, ay: f32) -> f32 {
    let x = ax * w.x;
    let y = ay * w.y;
    x * x + y * y
}

/// GGX normal distribution D(m) (Walter et al. 2007, eq. 33, anisotropic form), for unit `m`; zero for
/// `m.z <= 0`.
#[inline]
#[must_use]
pub fn ggx_d(m: Vec3, ax: f32, ay: f32) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let ax = ax.max(ALPHA_MIN);
    let ay = ay.max(ALPHA_MIN);
    let x = m.x / ax;
    let y = m.y / ay;
    // For unit m this is at least min(1, 1/ax², 1/ay²); the floor only guards degenerate input.
    let k = (x * x + y * y + m.z * m.z).max(1e-6);
    INV_PI / (ax * ay * k * k)
}

/// Smith's Λ(w) for GGX (Heitz 2014, eq. 86): `(sqrt(1 + (ax² x² + ay² y²) / z²) - 1) / 2`. `w` need not
/// be unit; Λ is infinite at the horizon, where a large finite value is returned.
#[inline]
#[must_use]
pub fn smith_lambda(w: Vec3, ax: f32, ay: f32) -> f32 {
    let w = normalize_or_zero(w);
    let t = tangent_term(w, ax.max(ALPHA_MIN), ay.max(ALPHA_MIN));
    let z = w.z.abs();
    // (sqrt(z² + t) - z) / (2z), rewritten without cancellation.
    let r = sqrt(z * z + t);
    t / (2.0 * z * (r + z)).max(1e-30)
}

/// Smith's masking function G1(w) = 1 / (1 + Λ(w)) (Heitz 2014, eq. 43); zero at the horizon.
#[inline]
#[must_use]
pub fn smith_g1(w: Vec3, ax: f32, ay: f32) -> f32 {
    // 2z / (z + sqrt(z² + t)): the same as 1 / (1 + Λ), scale-invariant and free of divisions by zero.
    let z = w.z.abs();
    let r = sqrt(z * z + tangent_term(w, ax.max(ALPHA_MIN), ay.max(ALPHA_MIN)));
    let d = z + r;
    if d <= 0.0 {
        return 0.0;
    }
    2.0 * z / d
}

/// `G1(w) / (2 w.z) = 1 / (w.z + sqrt(w.z² + ax² x² + ay² y²))` for unit `w` with `w.z > 0`: the form of
/// the masking term that appears in the microfacet BRDF (Burley's `smithG_GGX`), finite even at grazing
/// angles. Alphas must already be clamped.
#[inline]
#[must_use]
pub(crate) fn smith_g1_over_2cos(w: Vec3, ax: f32, ay: f32) -> f32 {
    let z = w.z;
    1.0 / (z + sqrt(z * z + tangent_term(w, ax, ay))).max(1e-30)
}

/// Samples a microfacet normal from the distribution of normals visible from `wo`,
/// D_wo(m) = G1(wo) max(0, wo·m) D(m) / wo.z (Heitz 2018), with Dupuy and Benyoub's spherical-cap method
/// (2023, listing 3). `wo` need not be unit. Density [`ggx_vndf_pdf`]. Returns a unit normal with
/// `m.z >= 0` (+z for degenerate input).
#[must_use]
pub fn sample_ggx_vndf(wo: Vec3, ax: f32, ay: f32, u: Vec2) -> Vec3 {
    let ax = ax.max(ALPHA_MIN);
    let ay = ay.max(ALPHA_MIN);
    // Warp to the hemisphere configuration (alpha = 1).
    let wh = normalize_or_zero(Vec3::new(ax * wo.x, ay * wo.y, wo.z));
    if wh == Vec3::ZERO {
        return Vec3::Z;
    }
    // Sample the spherical cap z in (-wh.z, 1] uniformly; adding wh gives the visible normal.
    let phi = 2.0 * PI * u.x;
    let z = (1.0 - u.y) * (1.0 + wh.z) - wh.z;
    let sin_theta = safe_sqrt(1.0 - z * z);
    let c = Vec3::new(sin_theta * cos(phi), sin_theta * sin(phi), z);
    let h = c + wh;
    // Warp back to the ellipsoid configuration (normals transform with the inverse transpose).
    let m = normalize_or_zero(Vec3::new(ax * h.x, ay * h.y, h.z.max(0.0)));
    if m == Vec3::ZERO {
        return Vec3::Z;
    }
    m
}

/// Density of [`sample_ggx_vndf`] over microfacet normals `m` (solid angle):
/// G1(wo) max(0, wo·m) D(m) / wo.z (Heitz 2018, eq. 1); zero for `wo.z <= 0`. `m` must be unit, `wo`
/// need not be.
#[inline]
#[must_use]
pub fn ggx_vndf_pdf(wo: Vec3, m: Vec3, ax: f32, ay: f32) -> f32 {
    if wo.z <= 0.0 {
        return 0.0;
    }
    let ax = ax.max(ALPHA_MIN);
    let ay = ay.max(ALPHA_MIN);
    let wo = normalize_or_zero(wo);
    // G1(wo) / wo.z = 2 · smith_g1_over_2cos(wo).
    2.0 * smith_g1_over_2cos(wo, ax, ay) * wo.dot(m).max(0.0) * ggx_d(m, ax, ay)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec;

    use crate::test_support::XorShift32 as Rng;

    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta))
    }

    /// ∫ f(m) dω over the upper hemisphere on a (θ, φ) grid with θ = (π/2) t⁴, which puts most nodes
    /// near the pole where narrow lobes live. Midpoint rule in (t, φ).
    fn integrate_hemisphere(nt: usize, np: usize, f: impl Fn(Vec3) -> f64) -> f64 {
        let half_pi = core::f64::consts::FRAC_PI_2;
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64;
            let theta = half_pi * t * t * t * t;
            let dtheta = half_pi * 4.0 * t * t * t / nt as f64;
            let w = theta.sin() * dtheta * (2.0 * core::f64::consts::PI / np as f64);
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * 2.0 * core::f64::consts::PI;
                sum += f(dir(theta as f32, phi as f32)) * w;
            }
        }
        sum
    }

    #[test]
    fn d_is_normalised_projected_area() {
        // ∫ D(m) m.z dω = 1 for any alphas.
        for &(ax, ay) in &[
            (0.5f32, 0.5f32),
            (0.1, 0.3),
            (1.0, 1.0),
            (0.01, 0.002),
            (2.0, 0.3),
        ] {
            let s = integrate_hemisphere(1500, 400, |m| ggx_d(m, ax, ay) as f64 * m.z as f64);
            assert!((s - 1.0).abs() < 2e-3, "ax {ax} ay {ay}: {s}");
        }
        assert_eq!(ggx_d(Vec3::new(0.0, 0.6, -0.8), 0.3, 0.3), 0.0);
        assert!(ggx_d(Vec3::Z, 0.0, 0.0).is_finite());
    }

    #[test]
    fn lambda_and_g1_agree_and_are_finite() {
        let mut rng = Rng(17);
        for _ in 0..1000 {
            let w = dir(rng.next() * 1.5, rng.next() * core::f32::consts::TAU);
            let (ax, ay) = (rng.next() + 0.01, rng.next() + 0.01);
            let l = smith_lambda(w, ax, ay);
            let g = smith_g1(w, ax, ay);
            assert!((g - 1.0 / (1.0 + l)).abs() < 1e-5);
            // Isotropic closed form: Λ = (sqrt(1 + α² tan²θ) - 1) / 2.
            let tan2 = (1.0 - w.z * w.z) / (w.z * w.z);
            let li = smith_lambda(w, ax, ax);
            assert!((li - 0.5 * ((1.0 + ax * ax * tan2).sqrt() - 1.0)).abs() < 1e-3 * (1.0 + li));
            // Scale invariance.
            assert!((smith_g1(w * 7.0, ax, ay) - g).abs() < 1e-5);
        }
        assert_eq!(smith_g1(Vec3::Z, 0.5, 0.5), 1.0);
        assert_eq!(smith_g1(Vec3::X, 0.5, 0.5), 0.0);
        assert!(smith_lambda(Vec3::X, 0.5, 0.5).is_finite());
        assert!(smith_lambda(Vec3::ZERO, 0.5, 0.5).is_finite());
        assert!(smith_g1(Vec3::ZERO, 0.5, 0.5).is_finite());
    }

    #[test]
    fn vndf_pdf_integrates_to_one() {
        let cases = [
            (Vec3::new(0.3, 0.2, 0.9), 0.5f32, 0.5f32),
            (Vec3::new(0.9, -0.1, 0.2), 0.3, 0.1),
            (Vec3::new(-0.5, 0.7, 0.05), 1.0, 0.8),
            (Vec3::new(0.6, 0.0, 0.8), 0.01, 0.01),
            (Vec3::new(0.99, 0.0, 0.01), 0.02, 0.005),
            (Vec3::new(0.1, 0.1, 0.98), ALPHA_MIN, ALPHA_MIN),
        ];
        for &(wo, ax, ay) in &cases {
            let wo = wo.normalize();
            let s = integrate_hemisphere(3000, 600, |m| ggx_vndf_pdf(wo, m, ax, ay) as f64);
            assert!((s - 1.0).abs() < 5e-3, "wo {wo} ax {ax} ay {ay}: {s}");
        }
    }

    #[test]
    fn vndf_samples_are_visible_unit_normals() {
        let mut rng = Rng(99);
        for _ in 0..20_000 {
            let wo = dir(rng.next() * 1.57, rng.next() * core::f32::consts::TAU);
            let ax = rng.next() * rng.next();
            let ay = rng.next();
            let m = sample_ggx_vndf(wo, ax, ay, rng.vec2());
            assert!((m.length() - 1.0).abs() < 1e-4 && m.z >= 0.0);
            assert!(wo.dot(m) >= -1e-4, "wo {wo} m {m}");
        }
        // Degenerate and grazing input stays finite.
        for wo in [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 1e-7),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::X * 1e30,
        ] {
            let m = sample_ggx_vndf(wo, 0.0, 0.0, Vec2::new(0.3, 0.9));
            assert!(m.is_finite() && (m.length() - 1.0).abs() < 1e-4);
            assert!(ggx_vndf_pdf(wo, m, 0.0, 0.0).is_finite());
        }
    }

    /// Histogram of sampled normals on a (cos θ, φ) grid against the pdf integrated over each bin.
    #[test]
    fn vndf_histogram_matches_pdf() {
        const NT: usize = 10;
        const NP: usize = 12;
        let cases = [
            (Vec3::new(0.5, 0.3, 0.81), 0.6f32, 0.6f32),
            (Vec3::new(0.8, -0.2, 0.3), 0.7, 0.25),
            (Vec3::new(-0.1, 0.95, 0.1), 0.4, 1.2),
        ];
        let mut rng = Rng(4321);
        for &(wo, ax, ay) in &cases {
            let wo = wo.normalize();
            let mut counts = vec![0u32; NT * NP];
            let n = 400_000u32;
            for _ in 0..n {
                let m = sample_ggx_vndf(wo, ax, ay, rng.vec2());
                let t = ((m.z * NT as f32) as usize).min(NT - 1);
                let phi = libm::atan2f(m.y, m.x) + PI;
                let p = ((phi / (2.0 * PI) * NP as f32) as usize).min(NP - 1);
                counts[t * NP + p] += 1;
            }
            // Expected counts: the pdf integrated over each bin with a 24x24 midpoint sub-grid in
            // (cos θ, φ) (dω = d cos θ dφ).
            const SUB: usize = 24;
            let mut chi2 = 0.0f64;
            let mut total_expect = 0.0f64;
            let mut dof = 0;
            for t in 0..NT {
                for p in 0..NP {
                    let mut e = 0.0f64;
                    for a in 0..SUB {
                        let z = (t as f64 + (a as f64 + 0.5) / SUB as f64) / NT as f64;
                        for b in 0..SUB {
                            let phi = (p as f64 + (b as f64 + 0.5) / SUB as f64) / NP as f64
                                * 2.0
                                * core::f64::consts::PI
                                - core::f64::consts::PI;
                            let s = (1.0 - z * z).max(0.0).sqrt();
                            let m =
                                Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                            e += ggx_vndf_pdf(wo, m, ax, ay) as f64;
                        }
                    }
                    let cell = (1.0 / NT as f64) * (2.0 * core::f64::consts::PI / NP as f64);
                    let e = e / (SUB * SUB) as f64 * cell * n as f64;
                    total_expect += e;
                    let o = counts[t * NP + p] as f64;
                    if e > 5.0 {
                        chi2 += (o - e) * (o - e) / e;
                        dof += 1;
                    } else {
                        // Sparse bins: only require that nothing lands where the pdf says it can't.
                        assert!(
                            o <= e + 5.0 * (e + 1.0).sqrt() + 5.0,
                            "bin ({t},{p}) {o} vs {e}"
                        );
                    }
                }
            }
            assert!(
                (total_expect / n as f64 - 1.0).abs() < 5e-3,
                "{total_expect}"
            );
            // Quadrature error of the sub-grid adds a little on top of the statistical spread, so the
            // bound is generous (about 2x the degrees of freedom), yet far below a wrong density.
            assert!(
                chi2 < 2.0 * dof as f64 + 40.0,
                "wo {wo} ax {ax} ay {ay}: chi2 {chi2} dof {dof}"
            );
        }
    }

    /// Incident directions of the chi-square and near-delta tests: θ = 0°, 30°, 60°, 85°, 89.9° at an
    /// azimuth of 0.3 rad (off the anisotropy axes).
    fn incident(theta_deg: f32) -> Vec3 {
        dir(theta_deg.to_radians(), 0.3)
    }

    const INCIDENT_DEG: [f32; 5] = [0.0, 30.0, 60.0, 85.0, 89.9];

    /// Chi-square tests of `sample_ggx_vndf` against `ggx_vndf_pdf` (isotropic alpha 0.01, 0.1, 0.5, 1 ×
    /// the incident angles above), over microfacet normals on the hemisphere. The pdf is zero below the
    /// horizon and for back-facing normals (wo · m < 0): both are clip planes. Narrow lobes (alpha <= 0.1)
    /// get rows spaced geometrically in θ from alpha / 20, so that the lobe spans about 20 rows.
    #[test]
    fn chi2_vndf() {
        use crate::test_support::chi2::{chi2_test, family_share, geometric, sample_count, Grid};
        let alphas = [0.01f32, 0.1, 0.5, 1.0];
        assert_eq!(
            family_share("ggx vndf"),
            (alphas.len() * INCIDENT_DEG.len()) as u32
        );
        let n = sample_count(1_000_000, 8_000_000);
        let half_pi = core::f64::consts::FRAC_PI_2;
        for (k, &a) in alphas.iter().enumerate() {
            for (j, &deg) in INCIDENT_DEG.iter().enumerate() {
                let wo = incident(deg);
                let grid = if a <= 0.1 {
                    Grid::new(Vec3::Z, geometric(a as f64 / 20.0, half_pi, 31, true), 64)
                } else {
                    Grid::hemisphere(32, 64)
                }
                .clip(Vec3::Z)
                .clip(wo);
                chi2_test(
                    &std::format!("ggx vndf alpha {a} incident {deg} deg"),
                    &grid,
                    n,
                    (k * 16 + j) as u64,
                    |rng| {
                        let u = Vec2::new(rng.uniform(), rng.uniform());
                        Some(sample_ggx_vndf(wo, a, a, u))
                    },
                    |m| ggx_vndf_pdf(wo, m, a, a) as f64,
                )
                .check();
            }
        }
    }

    /// Alpha 1e-4 ([`ALPHA_MIN`], roughness 0) is a near-delta: its lobe (about 1e-4 rad wide) sits at the
    /// limit of f32 directions, so a chi-square test is not meaningful. What is testable: the pdf integrates
    /// to at most 1 (and to 1 within 1e-3), and the samples concentrate around the normal as the GGX tail
    /// says: P(tan θm > k alpha) is 1 / (1 + k²) for the projected-area distribution, so beyond 100 alpha
    /// at most about 1e-4 of the samples (bounded here by 5e-4 for the visible-normal weighting and noise),
    /// and the median θm is of the order of alpha.
    #[test]
    fn near_delta_vndf_concentrates() {
        use crate::test_support::chi2::{chi2_test, geometric, Grid};
        let a = ALPHA_MIN;
        let half_pi = core::f64::consts::FRAC_PI_2;
        for (j, &deg) in INCIDENT_DEG.iter().enumerate() {
            let wo = incident(deg);
            let grid = Grid::new(Vec3::Z, geometric(a as f64 / 20.0, half_pi, 31, true), 64)
                .clip(Vec3::Z)
                .clip(wo);
            // Only the pdf integral is used from this run (no samples).
            let integral = chi2_test(
                "",
                &grid,
                0,
                0,
                |_| None,
                |m| ggx_vndf_pdf(wo, m, a, a) as f64,
            )
            .integral;
            let mut rng = crate::test_support::SplitMix64(j as u64);
            let n = 200_000;
            let mut thetas = std::vec::Vec::with_capacity(n);
            let mut far = 0;
            for _ in 0..n {
                let m = sample_ggx_vndf(wo, a, a, Vec2::new(rng.uniform(), rng.uniform()));
                let t = libm::atan2f(libm::hypotf(m.x, m.y), m.z);
                if t > 100.0 * a {
                    far += 1;
                }
                thetas.push(t);
            }
            thetas.sort_by(f32::total_cmp);
            let median = thetas[n / 2];
            std::println!(
                "near-delta vndf alpha {a} incident {deg}: pdf integral {integral:.6}, median θm {median:.3e}, \
                 fraction beyond 100 alpha {:.2e}",
                far as f64 / n as f64
            );
            assert!((1.0 - 1e-3..=1.0 + 1e-3).contains(&integral), "{integral}");
            assert!(far as f64 / n as f64 <= 5e-4, "{far}");
            assert!(median > 0.3 * a && median < 3.0 * a, "{median}");
        }
    }
}
