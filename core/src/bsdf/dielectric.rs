//! A rough dielectric interface: GGX microfacet reflection and refraction (Walter, Marschner, Li and
//! Torrance 2007, "Microfacet Models for Refraction through Rough Surfaces", eqs. 20-21 and 35-38),
//! sampled through the visible normals of `wo` (Heitz 2018) and split between reflection and refraction
//! by the Fresnel reflectance of the sampled microfacet, as pbrt-v4's `DielectricBxDF` does.
//!
//! Conventions of [`crate::bsdf`], with one addition: the frame's `z` is the normal on `wo`'s side
//! (`wo.z > 0`; below it nothing is returned), and `eta` is the index of refraction of the side below
//! over that of `wo`'s side (glass seen from outside: 1.5; from inside: 1 / 1.5). `wi.z > 0` is
//! reflection, `wi.z < 0` refraction. The refracted value is the radiance BTDF: it carries the
//! 1 / η² of radiance compression (Veach 1997, §5.2), so `f(wo, wi) / η_i² = f(wi, wo) / η_o²` with η_o,
//! η_i the indices on `wo`'s and `wi`'s sides (tested).
//!
//! Masking-shadowing is Smith's height-correlated G2 = 1 / (1 + Λ(wo) + Λ(wi)) (Heitz 2014, eq. 99),
//! reciprocal and correct for transmission. Refracted light is tinted by `tint` (the glTF base colour of
//! `KHR_materials_transmission`'s BTDF); reflection is not.
use crate::math::float::sqrt;
use crate::sampling::ggx_vndf::{
    ggx_d, ggx_vndf_pdf, normalize_or_zero, sample_ggx_vndf, smith_lambda,
};
use glam::{Vec2, Vec3};

use super::sample::BsdfSample;

/// Unpolarised Fresnel reflectance of a dielectric interface (Born and Wolf; pbrt-v4's `FrDielectric`)
/// for a ray arriving with `cos_i` (clamped to [0, 1], on the side the relative index `eta` is seen
/// from); 1 under total internal reflection.
#[inline]
#[must_use]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    fresnel_refraction(cos_i, sqrt((1.0 - sin2_t).max(0.0)), eta)
}

/// [`fresnel_dielectric`] for a refraction whose two cosines are both known (`cos_i` on the side `eta` is
/// seen from, `cos_t` on the other): no Snell's law, so no cancellation near the critical angle, and the
/// same value for the reverse path (`cos_t`, `cos_i`, `1 / eta`).
#[inline]
#[must_use]
fn fresnel_refraction(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r = 0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
    if r.is_nan() {
        1.0
    } else {
        r.clamp(0.0, 1.0)
    }
}

/// The direction `wo` (unit, `wo·m > 0`) refracts into through a microfacet of normal `m` with relative
/// index `eta`, and whether it does (false under total internal reflection).
#[inline]
#[must_use]
fn refract(wo: Vec3, m: Vec3, eta: f32) -> (Vec3, bool) {
    let cos_i = wo.dot(m);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return (Vec3::ZERO, false);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    (-wo * (1.0 / eta) + m * (cos_i / eta - cos_t), true)
}

/// A rough dielectric interface (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric {
    /// Index of refraction below over above (`wo`'s side).
    pub eta: f32,
    /// GGX alphas, each at least [`super::ALPHA_MIN`].
    pub ax: f32,
    pub ay: f32,
    /// Colour of refracted light.
    pub tint: Vec3,
    /// A thin wall (glTF `KHR_materials_transmission` without a volume): light passes through without
    /// bending, as through two parallel interfaces of no thickness. The transmitted lobe is the
    /// reflected one mirrored through the surface, weighted `1 - F` (as Filament and Enterprise PBR
    /// model thin transmission), with no radiance compression (it enters and leaves at once).
    pub thin: bool,
}

impl RoughDielectric {
    /// The half vector of `wo`, `wi` with the relative index `etap` of `wi`'s side (1 for reflection),
    /// turned to `+z`; zero if degenerate.
    #[inline]
    #[must_use]
    fn half_vector(wo: Vec3, wi: Vec3, etap: f32) -> Vec3 {
        let m = normalize_or_zero(wi * etap + wo);
        if m.z < 0.0 {
            -m
        } else {
            m
        }
    }

    /// `f(wo, wi)` without the cosine and the solid-angle density with which [`Self::sample`] produces
    /// `wi`. Zero unless `wo.z > 0`; directions need not be unit.
    #[must_use]
    pub fn eval_and_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let wo = normalize_or_zero(wo);
        let wi = normalize_or_zero(wi);
        let (cos_o, cos_i) = (wo.z, wi.z);
        if !(cos_o > 0.0) || cos_i == 0.0 || !(self.eta > 0.0) {
            return (Vec3::ZERO, 0.0);
        }
        if self.thin && cos_i < 0.0 {
            // The mirror image of a reflection, carrying what the interface does not reflect.
            let mirrored = Vec3::new(wi.x, wi.y, -wi.z);
            let (f, pdf, fresnel) = self.microfacet_mirror(wo, mirrored);
            let transmitted = 1.0 - fresnel;
            return (self.tint * (f * transmitted), pdf * transmitted);
        }
        if cos_i > 0.0 {
            let (f, pdf, fresnel) = self.microfacet_mirror(wo, wi);
            return (Vec3::splat(f * fresnel), pdf * fresnel);
        }
        // Refraction.
        let etap = self.eta;
        let m = Self::half_vector(wo, wi, etap);
        let (o_m, i_m) = (wo.dot(m), wi.dot(m));
        // Microfacets seen from behind by either direction contribute nothing.
        if m == Vec3::ZERO || !(o_m > 0.0) || i_m * cos_i <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let fresnel = fresnel_refraction(o_m, -i_m, self.eta);
        let (d, g, d_wo) = self.microfacet_terms(wo, wi, m);
        // Walter et al. eq. 21 and the Jacobian of eq. 17 with etap = η_i / η_o.
        let denom = {
            let s = i_m + o_m / etap;
            s * s
        };
        if !(denom > 0.0) || d_wo == 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let transmitted = 1.0 - fresnel;
        let f = transmitted * d * g * (i_m * o_m).abs() / denom / (etap * etap);
        let pdf = transmitted * d_wo * i_m.abs() / denom;
        (self.tint * f, pdf)
    }

    /// `D(m)`, `G2 / (cos θo |cos θi|)` and the density `D_wo(m) = G1(wo) (wo·m) D(m) / wo.z` of
    /// sampling `m`, for unit `wo` above the surface; zeros where they are not finite.
    #[must_use]
    fn microfacet_terms(&self, wo: Vec3, wi: Vec3, m: Vec3) -> (f32, f32, f32) {
        let d = ggx_d(m, self.ax, self.ay);
        let g2 =
            1.0 / (1.0 + smith_lambda(wo, self.ax, self.ay) + smith_lambda(wi, self.ax, self.ay));
        // Divided one cosine at a time: near the horizon G2 falls as fast as the cosines, but their
        // product alone underflows.
        let g = g2 / wo.z / wi.z.abs();
        let d_wo = ggx_vndf_pdf(wo, m, self.ax, self.ay);
        if !(g.is_finite() && d_wo.is_finite()) {
            return (0.0, 0.0, 0.0);
        }
        (d, g, d_wo)
    }

    /// The mirror-microfacet terms at unit `wo`, `wi` above the surface: `D G / (4 cos θo cos θi)`, the
    /// density `D_wo(m) / (4 wo·m)` of sampling `wi` through its half vector, and the Fresnel reflectance
    /// `F` (reflection weighs both by `F`, a thin wall's transmission by `1 - F`); zeros if degenerate.
    #[must_use]
    fn microfacet_mirror(&self, wo: Vec3, wi: Vec3) -> (f32, f32, f32) {
        let m = Self::half_vector(wo, wi, 1.0);
        let o_m = wo.dot(m);
        let valid = m != Vec3::ZERO && o_m > 0.0 && wi.dot(m) > 0.0 && wo.z > 0.0 && wi.z > 0.0;
        if !valid {
            return (0.0, 0.0, 0.0);
        }
        let (d, g, d_wo) = self.microfacet_terms(wo, wi, m);
        (
            0.25 * d * g,
            d_wo / (4.0 * o_m),
            fresnel_dielectric(o_m, self.eta),
        )
    }

    /// Samples `wi`: `u.yz` picks a visible microfacet normal, `u.x` reflection (with probability the
    /// Fresnel reflectance) or refraction. Returns `f` and the pdf of [`Self::eval_and_pdf`] at the sampled
    /// direction, or `pdf = 0` when the sample fails.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: Vec3) -> BsdfSample {
        let wo = normalize_or_zero(wo);
        if !(wo.z > 0.0) || !(self.eta > 0.0) {
            return BsdfSample::failed();
        }
        let m = sample_ggx_vndf(wo, self.ax, self.ay, Vec2::new(u.y, u.z));
        let o_m = wo.dot(m);
        if !(o_m > 0.0) {
            return BsdfSample::failed();
        }
        let fresnel = fresnel_dielectric(o_m, self.eta);
        let wi = if u.x < fresnel {
            let wi = normalize_or_zero(m * (2.0 * o_m) - wo);
            if !(wi.z > 0.0) {
                return BsdfSample::failed();
            }
            wi
        } else if self.thin {
            // Through the thin wall: the reflected direction mirrored through the surface.
            let r = normalize_or_zero(m * (2.0 * o_m) - wo);
            if !(r.z > 0.0) {
                return BsdfSample::failed();
            }
            Vec3::new(r.x, r.y, -r.z)
        } else {
            let (wi, ok) = refract(wo, m, self.eta);
            let wi = normalize_or_zero(wi);
            if !ok || !(wi.z < 0.0) {
                return BsdfSample::failed();
            }
            wi
        };
        let (f, pdf) = self.eval_and_pdf(wo, wi);
        if !(pdf > 0.0) {
            return BsdfSample::failed();
        }
        BsdfSample { wi, f, pdf }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::bsdf::ALPHA_MIN;
    use crate::math::float::{cos, sin, PI};
    use crate::test_support::SplitMix64;

    fn incident(deg: f32) -> Vec3 {
        let t = deg.to_radians();
        Vec3::new(sin(t), 0.0, cos(t))
    }

    fn glass(roughness: f32, eta: f32) -> RoughDielectric {
        let a = (roughness * roughness).max(ALPHA_MIN);
        RoughDielectric {
            eta,
            ax: a,
            ay: a,
            tint: Vec3::ONE,
            thin: false,
        }
    }

    /// A thin wall: straight-through transmission, energy conserved without any radiance factor, the
    /// transmitted lobe the mirror image of the reflected one, and reciprocal.
    #[test]
    fn thin_wall_passes_light_straight_through() {
        let mut rng = SplitMix64(5);
        for roughness in [0.0f32, 0.3] {
            let d = RoughDielectric {
                thin: true,
                ..glass(roughness, 1.5)
            };
            for deg in [0.0f32, 40.0, 75.0] {
                let wo = incident(deg);
                let (mut energy, mut through, n) = (0.0f64, Vec3::ZERO, 20_000);
                for _ in 0..n {
                    let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                    let s = d.sample(wo, u);
                    if s.pdf > 0.0 {
                        energy += f64::from(s.f.x * s.wi.z.abs() / s.pdf);
                        if s.wi.z < 0.0 {
                            through += s.wi;
                        }
                    }
                }
                let e = energy / n as f64;
                // Smooth: exactly conserved; rough: single scattering loses a little.
                let tolerance = if roughness == 0.0 { 0.02 } else { 0.1 };
                assert!(
                    (e - 1.0).abs() < tolerance,
                    "roughness {roughness} incident {deg}: {e}"
                );
                // The mean transmitted direction continues the incident one: -wo.
                let mean = through.normalize();
                assert!(mean.dot(-wo) > 0.99, "{mean} vs {}", -wo);
            }
            // Reciprocity of the transmitted part: the reverse is seen from the other side.
            for _ in 0..1000 {
                let z = rng.uniform().max(1e-2);
                let phi = 2.0 * PI * rng.uniform();
                let wo = Vec3::new(
                    sqrt(1.0 - z * z) * cos(phi),
                    sqrt(1.0 - z * z) * sin(phi),
                    z,
                );
                let wi = Vec3::new(
                    rng.uniform() - 0.5,
                    rng.uniform() - 0.5,
                    -rng.uniform().max(1e-2),
                )
                .normalize();
                let flip = Vec3::new(1.0, 1.0, -1.0);
                let (f, _) = d.eval_and_pdf(wo, wi);
                let (f_rev, _) = d.eval_and_pdf(wi * flip, wo * flip);
                assert!(
                    (f.x - f_rev.x).abs() <= 1e-3 * f.x.max(f_rev.x) + 1e-6,
                    "{f} {f_rev}"
                );
            }
        }
    }

    #[test]
    fn fresnel_matches_known_values() {
        // Head-on glass: ((1.5 - 1) / (1.5 + 1))² = 0.04; from inside the same.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        // Grazing: everything reflects.
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // Total internal reflection beyond the critical angle asin(1 / 1.5) = 41.8°.
        assert_eq!(fresnel_dielectric(cos(45f32.to_radians()), 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric(cos(40f32.to_radians()), 1.0 / 1.5) < 1.0);
        // Index 1: nothing reflects.
        assert!(fresnel_dielectric(0.3, 1.0) < 1e-6);
    }

    /// f(wo, wi) / η_o² = f(wi, wo) / η_i² for refraction (the radiance BTDF's 1/η²), and plain symmetry
    /// for reflection, over random directions, roughnesses and both sides of the interface.
    #[test]
    fn generalised_reciprocity() {
        let mut rng = SplitMix64(7);
        let mut checked = 0;
        for _ in 0..20_000 {
            let roughness = 0.05 + 0.95 * rng.uniform();
            let eta = if rng.uniform() < 0.5 { 1.5 } else { 1.0 / 1.5 };
            let d = glass(roughness, eta);
            let dir = |rng: &mut SplitMix64, up: bool| {
                let z = rng.uniform().max(1e-3);
                let phi = 2.0 * PI * rng.uniform();
                let s = sqrt(1.0 - z * z);
                Vec3::new(s * cos(phi), s * sin(phi), if up { z } else { -z })
            };
            let wo = dir(&mut rng, true);
            let reflect = rng.uniform() < 0.5;
            let wi = dir(&mut rng, reflect);
            let (f, _) = d.eval_and_pdf(wo, wi);
            // The reverse: wi becomes the outgoing direction, seen in its own side's frame (z flipped
            // for refraction, with the reciprocal index).
            let (f_rev, _) = if reflect {
                d.eval_and_pdf(wi, wo)
            } else {
                let flip = Vec3::new(1.0, 1.0, -1.0);
                glass(roughness, 1.0 / eta).eval_and_pdf(wi * flip, wo * flip)
            };
            let (lhs, rhs) = if reflect {
                (f.x, f_rev.x)
            } else {
                // f(wo, wi) / η_o² = f(wi, wo) / η_i² with η_o = 1, η_i = eta (relative indices).
                (f.x * eta * eta, f_rev.x)
            };
            if lhs > 1e-6 || rhs > 1e-6 {
                checked += 1;
                assert!(
                    (lhs - rhs).abs() <= 2e-3 * lhs.max(rhs) + 1e-6,
                    "roughness {roughness} eta {eta} wo {wo} wi {wi}: {lhs} vs {rhs}"
                );
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    /// Finite, non-negative values and pdfs at grazing angles, extreme roughness (alpha 1e-4 to 1) and
    /// extreme indices, for evaluation and sampling.
    #[test]
    fn no_nan_on_grazing_and_extreme_inputs() {
        let mut rng = SplitMix64(3);
        let wos = [
            Vec3::Z,
            incident(89.99),
            Vec3::new(1.0, 0.0, 1e-7),
            Vec3::new(0.0, 1.0, 1e-30),
            Vec3::new(3.0, -2.0, 0.5),
        ];
        for roughness in [0.0f32, 1e-3, 0.5, 1.0] {
            for eta in [1.0001f32, 1.5, 1.0 / 1.5, 4.0, 0.25] {
                let d = glass(roughness, eta);
                for wo in wos {
                    for _ in 0..2_000 {
                        let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                        let s = d.sample(wo, u);
                        assert!(s.pdf.is_finite() && s.pdf >= 0.0, "{s:?}");
                        assert!(s.f.is_finite() && s.f.min_element() >= 0.0, "{s:?}");
                        let wi = Vec3::new(
                            rng.uniform() - 0.5,
                            rng.uniform() - 0.5,
                            rng.uniform() - 0.5,
                        );
                        let (f, pdf) = d.eval_and_pdf(wo, wi);
                        assert!(f.is_finite() && pdf.is_finite() && pdf >= 0.0 && f.x >= 0.0);
                    }
                }
            }
        }
    }

    /// White furnace of the interface alone: for a smooth interface (alpha 1e-4) the sampled weights
    /// f |cos| / pdf are exactly what the Fresnel split predicts, so the expected reflected plus
    /// transmitted energy, corrected for radiance compression, is one.
    #[test]
    fn smooth_interface_conserves_energy() {
        let mut rng = SplitMix64(11);
        for eta in [1.5f32, 1.0 / 1.5, 1.33] {
            let d = glass(0.0, eta);
            for deg in [0.0f32, 30.0, 60.0, 80.0] {
                let wo = incident(deg);
                let n = 20_000;
                let mut energy = 0.0f64;
                for _ in 0..n {
                    let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                    let s = d.sample(wo, u);
                    if s.pdf > 0.0 {
                        let w = f64::from(s.f.x * s.wi.z.abs() / s.pdf);
                        // Undo the 1/η² of radiance to count energy.
                        energy += if s.wi.z < 0.0 {
                            w * f64::from(eta * eta)
                        } else {
                            w
                        };
                    }
                }
                let e = energy / n as f64;
                assert!((e - 1.0).abs() < 0.02, "eta {eta} incident {deg}: {e}");
            }
        }
    }

    /// Chi-square tests of the sampler against its pdf over the whole sphere (reflection and
    /// refraction at once), for three roughnesses, two sides of the interface and three incident
    /// angles; every 8th sample also checks that `sample` returns what `eval_and_pdf` gives.
    #[test]
    fn chi2_rough_dielectric() {
        use crate::test_support::chi2::{chi2_test, family_share, sample_count, uniform_cos, Grid};
        let pi = core::f64::consts::PI;
        let n = sample_count(300_000, 2_000_000);
        let mut tested = 0;
        let mut max_rel = 0.0f32;
        for (k, &(roughness, eta)) in [(1.0f32, 1.5f32), (0.5, 1.5), (0.5, 1.0 / 1.5), (0.3, 1.33)]
            .iter()
            .enumerate()
        {
            let d = glass(roughness, eta);
            for (j, deg) in [0.0f32, 45.0, 80.0].into_iter().enumerate() {
                let wo = incident(deg);
                let grid = Grid::new(Vec3::NEG_Z, uniform_cos(0.0, pi, 48), 64);
                let mut count = 0u32;
                tested += 1;
                chi2_test(
                    &std::format!(
                        "rough dielectric roughness {roughness} eta {eta} incident {deg}"
                    ),
                    &grid,
                    n,
                    (100 + k * 8 + j) as u64,
                    |rng| {
                        let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                        let s = d.sample(wo, u);
                        if !(s.pdf > 0.0) {
                            return None;
                        }
                        count += 1;
                        if count.is_multiple_of(8) {
                            let (f, pdf) = d.eval_and_pdf(wo, s.wi);
                            let rel = (pdf - s.pdf).abs() / s.pdf;
                            let rel_f =
                                (f - s.f).abs().max_element() / s.f.max_element().max(1e-30);
                            max_rel = max_rel.max(rel).max(rel_f);
                        }
                        Some(s.wi)
                    },
                    |wi| f64::from(d.eval_and_pdf(wo, wi).1),
                )
                .check();
            }
        }
        assert!(max_rel <= 1e-6, "{max_rel}");
        assert_eq!(family_share("rough dielectric"), tested);
    }
}
