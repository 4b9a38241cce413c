//! The Disney principled BRDF (Burley 2012, "Physically-Based Shading at Disney", §5 and the BRDF
//! Explorer `disney.brdf`): retro-reflective diffuse, sheen, anisotropic GGX specular and a GTR1
//! clearcoat, combined by energy-conserving albedo scaling (below). No subsurface; transmission is a rough
//! dielectric mixed in by [`DisneyAtWo`] ([`crate::bsdf::dielectric`]).
//!
//! Conventions of [`crate::bsdf`]: local frame with `z` the shading normal, `wo` and `wi` away from the
//! surface, `f` without the cosine, solid-angle pdf over `wi`. Both directions must be above the
//! surface (`z > 0`); otherwise `f = 0` and `pdf = 0` (the integrator flips the frame to `wo`'s side).
//!
//! Importance sampling picks one of three lobes (diffuse with sheen: cosine hemisphere; specular: GGX
//! visible normals; clearcoat: GTR1 half vectors) with probabilities proportional to albedo estimates,
//! and reports the one-sample-MIS mixture pdf Σ p_lobe pdf_lobe, so `eval`, `pdf` and `sample` agree
//! exactly.
//!
//! # Energy conservation
//!
//! Burley's model sums its lobes, and its diffuse term's retro-reflection (FD90 up to 2.5) gains energy:
//! with a white base colour the directional albedo reaches 1.76 at grazing angles (white furnace test
//! below). fovea layers the lobes instead, with the albedo scaling of Kulla and Conty (2017, "Revisiting
//! Physically Based Shading at Imageworks", layering section; also the approach of Dassault's Enterprise
//! PBR and of OpenPBR), made reciprocal:
//!
//! f = f_cc + t_cc (f_spec + t_spec f_base / N),
//! t_x = 1 - max(Ê_x(wo), Ê_x(wi)),  N = max(1, A_base(wo), A_base(wi)),
//!
//! where Ê_x(w) bounds the directional albedo of layer x from above (clearcoat: 0.25 · clearcoat ·
//! Schlick(0.04, cos θ); specular: Schlick(cspec0, cos θ), per channel) and A_base is the directional
//! albedo of the diffuse-plus-sheen base (the diffuse part in closed form, `diffuse_albedo`). Taking
//! the max over both directions keeps f symmetric in wo and wi, and for every wo
//! ∫ f cos θi dωi ≤ Ê_cc + (1 - Ê_cc) (Ê_spec + (1 - Ê_spec) · 1) = 1. Materials whose base albedo is
//! below one everywhere (any base colour up to about 0.64 at roughness 1, up to 1 at roughness 0) keep
//! Burley's diffuse and sheen unchanged apart from the layer weights t.
//!
//! [`DisneyParams::lambertian`] swaps Burley's diffuse for a Lambertian one (albedo exactly the colour),
//! so that a purely diffuse OBJ material can be the very BRDF that Mitsuba's and pbrt's `diffuse` is.
use crate::math::color::luminance;
use crate::math::float::{cos, ln, powf, sin, sqr, sqrt, INV_PI, PI};
use crate::sampling::ggx_vndf::{ggx_d, normalize_or_zero, sample_ggx_vndf, smith_g1_over_2cos};
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::scene::features::{
    FEATURE_LOBE_ANISOTROPY, FEATURE_LOBE_CLEARCOAT, FEATURE_LOBE_METALLIC, FEATURE_LOBE_SHEEN,
    FEATURE_LOBE_SPECULAR, FEATURE_LOBE_TRANSMISSION,
};
use crate::scene::{FeatureFlags, Features};
use glam::{Vec2, Vec3};

use super::dielectric::RoughDielectric;
use super::sample::BsdfSample;
pub use crate::sampling::ggx_vndf::ALPHA_MIN;

/// The largest f32 below 1: a rescaled random number stays in [0, 1).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Disney BRDF parameters at a shading point (after textures are applied).
#[derive(Clone, Copy, Debug)]
pub struct DisneyParams {
    /// Linear RGB base colour.
    pub base_color: Vec3,
    pub metallic: f32,
    /// Perceptual roughness; GGX alpha = roughness².
    pub roughness: f32,
    pub anisotropic: f32,
    /// The dielectric reflectance at normal incidence over 0.08 (Burley: 0.5 is an index of 1.5),
    /// 0 to [`SPECULAR_MAX`]; above Burley's 1 for indices above 1.78, and at the maximum for glTF's
    /// `ior: 0` (an infinite index: F0 = 1, and the layering leaves the base nothing).
    pub specular: f32,
    pub specular_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    /// The diffuse lobe is Lambertian (`base_color · (1 - metallic) / π`) instead of Burley's diffuse with
    /// its roughness-dependent retro-reflection: what Mitsuba's and pbrt's `diffuse` material is, for
    /// comparisons with renderers that model a purely diffuse surface that way. The other lobes and the
    /// layering are unchanged (a Lambertian base's albedo is exactly its colour).
    pub lambertian: bool,
    /// Weight of the rough dielectric interface ([`crate::bsdf::dielectric`]) in the non-metallic part
    /// of the material: with `w = transmission · (1 - metallic)`, the BSDF is `(1 - w) f_disney' + w
    /// f_dielectric`, `f_disney'` with metallic `metallic / (1 - w)` so that the metal keeps its share
    /// (see [`DisneyAtWo`]). Sheen and clearcoat belong to the Disney part and fade with `1 - w`. 0:
    /// reflection only.
    pub transmission: f32,
    /// Index of refraction of the inside (the back side of the geometric normal) over the outside.
    pub ior: f32,
    /// The transmission is a thin wall's (straight through, `MATERIAL_THIN_WALLED`).
    pub thin_walled: bool,
}

/// Relative weight of the sheen lobe's albedo against the diffuse lobe's when choosing a lobe; it only
/// keeps sheen on black base colours sampled by the cosine lobe.
const SHEEN_SAMPLING_WEIGHT: f32 = 0.1;

/// Lobe indices of [`DisneyParams::sample`]'s one-sample mixture.
const LOBE_DIFFUSE: u32 = 0;
const LOBE_SPECULAR: u32 = 1;
const LOBE_CLEARCOAT: u32 = 2;

/// Schlick's weight (1 - cos θ)⁵, with cos θ clamped to [0, 1].
#[inline]
#[must_use]
fn schlick_weight(cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Directional albedo ∫ f_d cos θi dωi / base of Burley's diffuse term
/// f_d = base / π · (1 + (FD90 - 1) F_L)(1 + (FD90 - 1) F_V), FD90 = 0.5 + 2 r cos²θd, seen from
/// cos θo = `mu`, in closed form. With cos²θd = (1 + wo·wi) / 2, FD90 - 1 = r (1 + wo·wi) - 1/2 is a
/// polynomial in wo·wi, and the moments (1/π) ∫ (wo·wi)^k F_L cos θi dωi are Beta integrals
/// (F_L = (1 - cos θi)⁵): 1/21 (k = 0), μ/84 (k = 1), (11 - 9μ²)/504 (k = 2); without F_L, 1 and 2μ/3.
#[inline]
#[must_use]
fn diffuse_albedo(mu: f32, roughness: f32) -> f32 {
    let r = roughness;
    let fv = schlick_weight(mu);
    // (1/π) ∫ (FD90 - 1) cos θi dωi and (1/π) ∫ (FD90 - 1) F_L cos θi dωi.
    let a1 = r * (1.0 + 2.0 * mu / 3.0) - 0.5;
    let a_l = (r - 0.5) * (1.0 / 21.0) + r * mu * (1.0 / 84.0);
    // (1/π) ∫ (FD90 - 1)² F_L cos θi dωi, with (FD90 - 1)² = r²(1 + x)² - r(1 + x) + 1/4, x = wo·wi.
    let m0 = 1.0 / 21.0;
    let m1 = mu * (1.0 / 84.0);
    let m2 = (11.0 - 9.0 * mu * mu) * (1.0 / 504.0);
    let a_ll = r * r * (m0 + 2.0 * m1 + m2) - r * (m0 + m1) + 0.25 * m0;
    1.0 + a_l + fv * (a1 + a_ll)
}

/// Upper bound of the directional albedo ∫ F_H cos θi dωi of the sheen term (F_H = (1 - cos θd)⁵) seen
/// from cos θo = `mu`: 0.0035 + 0.088 (1 - μ)², a fit above the quadrature values (0.0003 head-on,
/// 0.088 at grazing; checked by a test).
#[inline]
#[must_use]
fn sheen_albedo_bound(mu: f32) -> f32 {
    0.0035 + 0.088 * sqr(1.0 - mu.clamp(0.0, 1.0))
}

/// Berry's GTR1 distribution ("generalized Trowbridge-Reitz" with γ = 1; Burley 2012, specular D) for
/// the unit half vector `h`; `alpha` in (0, 1).
///
/// sin²θh is taken from `h.x² + h.y²`, not `1 - cos²θh`: near the pole the latter is quantised in
/// steps of 1.2e-7, which at gloss 1 (alpha² = 1e-6) moved the peak's density in steps of 12 % (found by
/// the chi-square test of the clearcoat lobe).
#[inline]
#[must_use]
fn gtr1_d(h: Vec3, alpha: f32) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    // 1 + (a² - 1) cos² = sin² + a² cos².
    let t = (h.x * h.x + h.y * h.y) + a2 * h.z * h.z;
    (a2 - 1.0) / (PI * ln(a2) * t.max(1e-30))
}

/// Samples GTR1's half vector direction (cos θh, sin θh) with density ∝ D(h) cos θh (Burley 2012,
/// appendix B): cos²θh = (1 - a^(2(1-u))) / (1 - a²), and sin²θh = (a^(2(1-u)) - a²) / (1 - a²)
/// computed directly (not as 1 - cos²θh, which in f32 cannot represent θh below 3.5e-4 and so missed
/// most of the gloss-1 peak; found by the chi-square test of the clearcoat lobe).
#[inline]
#[must_use]
fn gtr1_sample(u: f32, alpha: f32) -> Vec2 {
    let a2 = alpha * alpha;
    let p = powf(a2, 1.0 - u);
    let inv = 1.0 / (1.0 - a2);
    let sin2 = ((p - a2) * inv).clamp(0.0, 1.0);
    let cos2 = ((1.0 - p) * inv).clamp(0.0, 1.0);
    Vec2::new(sqrt(cos2), sqrt(sin2))
}

/// Everything about the parameters that `eval`, `pdf` and `sample` share: clamped inputs, alphas,
/// tints, the layering terms at `wo`, and the lobe-selection probabilities for one `wo`.
struct Lobes {
    /// Diffuse colour: base colour × (1 - metallic).
    diffuse: Vec3,
    /// Sheen colour × (1 - metallic).
    sheen: Vec3,
    roughness: f32,
    /// [`DisneyParams::lambertian`]: the diffuse factor is 1 instead of Burley's `fd`, its albedo 1.
    lambertian: bool,
    ax: f32,
    ay: f32,
    cspec0: Vec3,
    /// Grazing Fresnel reflectance of the specular lobe: `min(1, 50 · max(cspec0))` (Schüler 2009,
    /// adopted by Frostbite, Lagarde & de Rousiers 2014): 1 for every real dielectric or metal (F0 >= 2%),
    /// fading to 0 for `specular` 0 (an index of refraction of 1 reflects nothing, not even at grazing
    /// angles, which canonical Schlick with F0 = 0 would still do).
    f90: f32,
    /// Whether the specular lobe can be non-zero (feature set and `cspec0`); else it is skipped.
    specular_on: bool,
    clearcoat: f32,
    cc_alpha: f32,
    /// Whether the feature set allows sheen / clearcoat at all (else `sheen` / `clearcoat` are zero and
    /// their terms are skipped).
    sheen_on: bool,
    clearcoat_on: bool,
    /// Ê_spec(wo), Ê_cc(wo) and A_base(wo) of the energy-conserving layering.
    spec_albedo_o: Vec3,
    cc_albedo_o: f32,
    base_albedo_o: f32,
    p_diffuse: f32,
    p_specular: f32,
    p_clearcoat: f32,
}

impl Lobes {
    /// Ê_spec(w): Schlick's Fresnel with cspec0 at the macro normal, per channel. For a smooth surface
    /// it is the specular albedo; for rough ones it exceeds it except near normal incidence, where
    /// shadowing removes more than the extra Fresnel of tilted facets adds (by at most 0.002 for F0 = 0,
    /// measured by the white furnace tests).
    #[inline]
    #[must_use]
    fn spec_albedo(&self, mu: f32) -> Vec3 {
        if !self.specular_on {
            return Vec3::ZERO;
        }
        (self.cspec0 + (Vec3::splat(self.f90) - self.cspec0) * schlick_weight(mu)).min(Vec3::ONE)
    }

    /// Ê_cc(w) = 0.25 · clearcoat · Schlick(0.04, cos θ): an upper bound of the clearcoat albedo (its
    /// GTR1 D with the fixed G of alpha 0.25 reflects at most 0.93 of this, by quadrature).
    #[inline]
    #[must_use]
    fn cc_albedo(&self, mu: f32) -> f32 {
        if !self.clearcoat_on {
            return 0.0;
        }
        (0.25 * self.clearcoat * (0.04 + 0.96 * schlick_weight(mu))).min(1.0)
    }

    /// A_base(w): the directional albedo of diffuse plus sheen (the largest channel), an exact value for
    /// the diffuse part and a bound for sheen.
    #[inline]
    #[must_use]
    fn base_albedo(&self, mu: f32) -> f32 {
        let diffuse = if self.lambertian {
            self.diffuse
        } else {
            self.diffuse * diffuse_albedo(mu, self.roughness)
        };
        if self.sheen_on {
            (diffuse + self.sheen * sheen_albedo_bound(mu)).max_element()
        } else {
            diffuse.max_element()
        }
    }
}

/// The largest [`DisneyParams::specular`]: F0 = 0.08 · specular reaches 1.
pub const SPECULAR_MAX: f32 = 12.5;

/// Clearcoat's fixed GGX alpha for masking-shadowing (Burley's `smithG_GGX(·, 0.25)`).
const CLEARCOAT_G_ALPHA: f32 = 0.25;

impl DisneyParams {
    /// A purely diffuse-looking dielectric: metallic 0, roughness 1, specular 0.5, everything else 0.
    #[inline]
    #[must_use]
    pub fn diffuse(base_color: Vec3) -> Self {
        Self {
            base_color,
            metallic: 0.0,
            roughness: 1.0,
            anisotropic: 0.0,
            specular: 0.5,
            specular_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            lambertian: false,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: false,
        }
    }

    /// GGX alphas (ax, ay) from roughness and anisotropy (Burley 2012, specular D):
    /// α = roughness², aspect = sqrt(1 - 0.9 anisotropic), ax = α / aspect, ay = α · aspect, both at least
    /// [`ALPHA_MIN`].
    #[inline]
    #[must_use]
    pub fn alphas(&self) -> Vec2 {
        let r = self.roughness.clamp(0.0, 1.0);
        let a = r * r;
        let aspect = sqrt(1.0 - 0.9 * self.anisotropic.clamp(0.0, 1.0));
        Vec2::new((a / aspect).max(ALPHA_MIN), (a * aspect).max(ALPHA_MIN))
    }

    /// Clamps the parameters and computes the layering terms and lobe probabilities for `cos_o = wo.z`.
    /// Lobes and parameters that `features` rules out (see [`crate::scene::features`]) are taken as
    /// zero without being computed; for materials that lack them the numbers are identical.
    #[inline]
    #[must_use]
    fn lobes<F: Features>(&self, cos_o: f32, features: F) -> Lobes {
        let base = self.base_color.max(Vec3::ZERO);
        let metallic = if features.has(FEATURE_LOBE_METALLIC) {
            self.metallic.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let one_minus_metallic = 1.0 - metallic;
        let lum = luminance(base);
        // Hue and saturation of the base colour, for the tints.
        let tint = if lum > 0.0 {
            base * (1.0 / lum)
        } else {
            Vec3::ONE
        };
        let specular_tint = self.specular_tint.clamp(0.0, 1.0);
        let specular_on = features.has(FEATURE_LOBE_SPECULAR);
        let cspec0 = if specular_on {
            (Vec3::ONE.lerp(tint, specular_tint) * (0.08 * self.specular.clamp(0.0, SPECULAR_MAX)))
                .lerp(base, metallic)
        } else {
            Vec3::ZERO
        };
        let f90 = (50.0 * cspec0.max_element()).min(1.0);
        let sheen_on = features.has(FEATURE_LOBE_SHEEN);
        let sheen = if sheen_on {
            Vec3::ONE.lerp(tint, self.sheen_tint.clamp(0.0, 1.0)) * self.sheen.clamp(0.0, 1.0)
        } else {
            Vec3::ZERO
        };
        let clearcoat_on = features.has(FEATURE_LOBE_CLEARCOAT);
        let clearcoat = if clearcoat_on {
            self.clearcoat.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let gloss = self.clearcoat_gloss.clamp(0.0, 1.0);
        let cc_alpha = 0.1 + (0.001 - 0.1) * gloss;
        let alphas = if features.has(FEATURE_LOBE_ANISOTROPY) {
            self.alphas()
        } else {
            // `alphas()` with anisotropic 0: the aspect is exactly 1.
            let r = self.roughness.clamp(0.0, 1.0);
            Vec2::splat((r * r).max(ALPHA_MIN))
        };
        let mut lobes = Lobes {
            diffuse: base * one_minus_metallic,
            sheen: sheen * one_minus_metallic,
            roughness: self.roughness.clamp(0.0, 1.0),
            lambertian: self.lambertian,
            ax: alphas.x,
            ay: alphas.y,
            cspec0,
            f90,
            specular_on: specular_on && f90 > 0.0,
            clearcoat,
            cc_alpha,
            sheen_on,
            clearcoat_on,
            spec_albedo_o: Vec3::ZERO,
            cc_albedo_o: 0.0,
            base_albedo_o: 0.0,
            p_diffuse: 1.0,
            p_specular: 0.0,
            p_clearcoat: 0.0,
        };
        lobes.spec_albedo_o = lobes.spec_albedo(cos_o);
        lobes.cc_albedo_o = lobes.cc_albedo(cos_o);
        lobes.base_albedo_o = lobes.base_albedo(cos_o);

        // Lobe selection ∝ the layers' albedo estimates at wo.
        let t_cc = 1.0 - lobes.cc_albedo_o;
        let w_s = luminance(lobes.spec_albedo_o) * t_cc;
        let w_c = lobes.cc_albedo_o;
        let w_d = luminance(lobes.diffuse + lobes.sheen * SHEEN_SAMPLING_WEIGHT)
            * (1.0 - luminance(lobes.spec_albedo_o))
            * t_cc
            / lobes.base_albedo_o.max(1.0);
        let total = w_d + w_s + w_c;
        if total > 0.0 {
            let inv = 1.0 / total;
            lobes.p_diffuse = w_d * inv;
            lobes.p_specular = w_s * inv;
            lobes.p_clearcoat = w_c * inv;
        }
        // Otherwise nothing reflects by the estimates (e.g. all-zero parameters seen head-on): the cosine
        // lobe, which covers the whole hemisphere, stays the only one.
        lobes
    }

    /// BRDF value f(wo, wi) without the cosine (Burley 2012, §5, layered as in the module docs): zero
    /// unless both directions are above the surface. Directions need not be unit.
    #[inline]
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.eval_and_pdf(wo, wi).0
    }

    /// Solid-angle density with which [`DisneyParams::sample`] produces `wi`: the lobe mixture
    /// Σ p_lobe pdf_lobe(wi). Zero unless both directions are above the surface.
    #[inline]
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.eval_and_pdf(wo, wi).1
    }

    /// [`DisneyParams::eval`] and [`DisneyParams::pdf`] in one pass (next-event estimation needs both).
    #[inline]
    #[must_use]
    pub fn eval_and_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        self.eval_and_pdf_with(FeatureFlags::ALL, wo, wi)
    }

    /// [`DisneyParams::eval_and_pdf`] for a material within `features` (lobes outside it are skipped).
    #[must_use]
    pub fn eval_and_pdf_with<F: Features>(&self, features: F, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        self.at_wo(features, wo).eval_and_pdf(wi)
    }

    /// The BRDF with everything that depends on `wo` alone computed once (clamped parameters, layering
    /// terms, lobe-selection probabilities), for a path vertex that both evaluates a light sample and
    /// samples the next direction. Gives the same numbers as [`DisneyParams::eval_and_pdf_with`] and
    /// [`DisneyParams::sample_with`], which call it.
    #[inline]
    #[must_use]
    pub fn at_wo<F: Features>(&self, features: F, wo: Vec3) -> DisneyAtWo {
        self.at_wo_facing(features, wo, true)
    }

    /// [`DisneyParams::at_wo`] for a `wo` on the front (`front`, outside) or back (inside) side of the
    /// geometric normal, which decides which way a transmissive material's index of refraction points.
    /// The local frame has `z` on `wo`'s side either way.
    #[inline]
    #[must_use]
    pub fn at_wo_facing<F: Features>(&self, features: F, wo: Vec3, front: bool) -> DisneyAtWo {
        let wo = normalize_or_zero(wo);
        // Below the surface nothing reflects (`eval_and_pdf` and `sample` then return zero without
        // looking at the lobes); `cos_o` is clamped so that the lobes, computed anyway, stay within the
        // albedo fits' domain.
        let mut transmission_weight = 0.0;
        let mut eta = 1.0;
        // Which part of the material each BSDF carries (glTF's model): metal `m`, the opaque dielectric
        // `(1 - m)(1 - t)` and the transmissive dielectric `w = (1 - m) t`. The Disney part, weighted
        // `1 - w`, is evaluated with metallic `m / (1 - w)`, so that its metal share is `m` exactly.
        let mut metallic = self.metallic;
        if features.has(FEATURE_LOBE_TRANSMISSION) && self.transmission > 0.0 {
            let m = if features.has(FEATURE_LOBE_METALLIC) {
                self.metallic.clamp(0.0, 1.0)
            } else {
                0.0
            };
            transmission_weight = self.transmission.min(1.0) * (1.0 - m);
            let rest = 1.0 - transmission_weight;
            metallic = if rest > 0.0 { (m / rest).min(1.0) } else { 0.0 };
            // An index at or below 1 (or NaN) would refract along a degenerate half vector: at least
            // 1.01.
            let ior = if crate::math::float::is_finite(self.ior) {
                self.ior.max(1.01)
            } else {
                1.5
            };
            eta = if front { ior } else { 1.0 / ior };
        }
        let lobes = if metallic == self.metallic {
            self.lobes(wo.z.max(0.0), features)
        } else {
            DisneyParams { metallic, ..*self }.lobes(wo.z.max(0.0), features)
        };
        let dielectric = RoughDielectric {
            eta,
            ax: lobes.ax,
            ay: lobes.ay,
            tint: self.base_color.clamp(Vec3::ZERO, Vec3::ONE),
            thin: self.thin_walled,
        };
        DisneyAtWo {
            lobes,
            wo,
            transmission_weight,
            dielectric,
        }
    }

    /// [`DisneyParams::eval_and_pdf`] for unit `wo`, `wi` above the surface and `lobes` of `wo.z`.
    #[must_use]
    fn eval_and_pdf_unit(lobes: &Lobes, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let (f, pdfs) = Self::eval_lobes_unit(lobes, wo, wi);
        let pdf = lobes.p_diffuse * pdfs.x + lobes.p_specular * pdfs.y + lobes.p_clearcoat * pdfs.z;
        (f, pdf)
    }

    /// The layered BRDF value and the three lobe pdfs (diffuse, specular, clearcoat) at unit `wo`, `wi`
    /// above the surface.
    #[must_use]
    fn eval_lobes_unit(lobes: &Lobes, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
        let hv = wo + wi;
        let l2 = hv.length_squared();
        if l2 <= 1e-30 {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let len = sqrt(l2);
        let h = hv * (1.0 / len);
        // cos θd = wo·h = wi·h = |wo + wi| / 2 for unit directions: symmetric in wo and wi.
        let cos_d = (0.5 * len).min(1.0);

        // Base: diffuse (Burley's, with retro-reflection, or Lambertian) and sheen, both already
        // scaled by 1 - metallic, normalised so that its albedo is at most 1 from both directions.
        let fh = schlick_weight(cos_d);
        let fd = if lobes.lambertian {
            1.0
        } else {
            let fl = schlick_weight(wi.z);
            let fv = schlick_weight(wo.z);
            let fd90 = 0.5 + 2.0 * lobes.roughness * cos_d * cos_d;
            (1.0 + (fd90 - 1.0) * fl) * (1.0 + (fd90 - 1.0) * fv)
        };
        let norm = lobes.base_albedo_o.max(lobes.base_albedo(wi.z)).max(1.0);
        let mut f_base = lobes.diffuse * (INV_PI * fd);
        if lobes.sheen_on {
            f_base += lobes.sheen * fh;
        }
        let f_base = f_base * (1.0 / norm);

        // Specular: D F G1(wo) G1(wi) / (4 cos θo cos θi), with G1 / (2 cos) kept together. Without a
        // specular lobe (F0 = F90 = 0) it and its pdf are exactly zero and are skipped.
        let mut f = f_base;
        let mut pdf_s = 0.0;
        if lobes.specular_on {
            let d_s = ggx_d(h, lobes.ax, lobes.ay);
            let g_o = smith_g1_over_2cos(wo, lobes.ax, lobes.ay);
            let g_i = smith_g1_over_2cos(wi, lobes.ax, lobes.ay);
            let f_s = lobes.cspec0 + (Vec3::splat(lobes.f90) - lobes.cspec0) * fh;
            let t_spec = Vec3::ONE - lobes.spec_albedo_o.max(lobes.spec_albedo(wi.z));
            f = f_s * (d_s * g_o * g_i) + t_spec * f_base;
            // D_wo(h) / (4 wo·h) = G1(wo) D(h) / (4 wo.z) = g_o D / 2.
            pdf_s = 0.5 * g_o * d_s;
        }

        // Clearcoat: 0.25 · clearcoat · GTR1 · Schlick(0.04) · G(0.25) / (4 cos θo cos θi), on top.
        // GTR1 needs a logarithm: skip it for the (common) materials without clearcoat, whose clearcoat
        // probability and weight are zero too.
        let mut d_c = 0.0;
        if lobes.clearcoat_on && lobes.clearcoat > 0.0 {
            d_c = gtr1_d(h, lobes.cc_alpha);
            let f_c = 0.04 + 0.96 * fh;
            let g_c = smith_g1_over_2cos(wo, CLEARCOAT_G_ALPHA, CLEARCOAT_G_ALPHA)
                * smith_g1_over_2cos(wi, CLEARCOAT_G_ALPHA, CLEARCOAT_G_ALPHA);
            let t_cc = 1.0 - lobes.cc_albedo_o.max(lobes.cc_albedo(wi.z));
            f = f * t_cc + Vec3::splat(0.25 * lobes.clearcoat * d_c * f_c * g_c);
        }

        // Lobe pdfs (specular above). Clearcoat: D(h) cos θh / (4 wo·h).
        let pdf_d = wi.z * INV_PI;
        let pdf_c = d_c * h.z / (4.0 * cos_d);
        (f, Vec3::new(pdf_d, pdf_s, pdf_c))
    }

    /// Samples a direction from lobe `lobe` (`LOBE_*`) alone, for unit `wo` above the surface; the result
    /// may lie below the surface (the caller rejects it).
    #[must_use]
    fn sample_lobe(lobes: &Lobes, wo: Vec3, lobe: u32, uv: Vec2) -> Vec3 {
        if lobe == LOBE_DIFFUSE {
            return square_to_cosine_hemisphere(uv);
        }
        let m = if lobe == LOBE_CLEARCOAT {
            let cs = gtr1_sample(uv.x, lobes.cc_alpha);
            let phi = 2.0 * PI * uv.y;
            Vec3::new(cs.y * cos(phi), cs.y * sin(phi), cs.x)
        } else {
            sample_ggx_vndf(wo, lobes.ax, lobes.ay, uv)
        };
        // Mirror wo about the microfacet normal.
        normalize_or_zero(m * (2.0 * wo.dot(m)) - wo)
    }

    /// Importance-samples `wi`: `u.x` picks the lobe, `u.yz` the direction. Returns `f` and the mixture
    /// pdf at the sampled direction (identical to [`DisneyParams::eval_and_pdf`] there), or `pdf = 0`
    /// when the sample falls below the surface or the input is degenerate.
    #[inline]
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: Vec3) -> BsdfSample {
        self.sample_with(FeatureFlags::ALL, wo, u)
    }

    /// [`DisneyParams::sample`] for a material within `features` (lobes outside it are skipped).
    #[must_use]
    pub fn sample_with<F: Features>(&self, features: F, wo: Vec3, u: Vec3) -> BsdfSample {
        self.at_wo(features, wo).sample(u)
    }
}

/// A [`DisneyParams`] prepared for one outgoing direction by [`DisneyParams::at_wo`].
///
/// A transmissive material (weight `w` = [`DisneyParams::transmission`] × (1 − metallic) > 0) is the
/// one-sample mixture `(1 - w) f_disney + w f_dielectric`: both reflect into the upper hemisphere, only
/// the dielectric refracts into the lower one; `sample` picks the dielectric with probability `w` and
/// returns the mixture's value and pdf. With `w = 0` every number is the Disney BRDF's alone, computed
/// as before (the random numbers are used unchanged), so opaque materials keep their exact images.
pub struct DisneyAtWo {
    lobes: Lobes,
    /// The unit outgoing direction (zero if degenerate).
    wo: Vec3,
    /// `w` above; 0 for opaque materials and feature sets without transmission.
    transmission_weight: f32,
    dielectric: RoughDielectric,
}

impl DisneyAtWo {
    /// Whether the material refracts (so that a direction below the surface can carry light).
    #[inline]
    #[must_use]
    pub fn transmits(&self) -> bool {
        self.transmission_weight > 0.0
    }

    /// [`DisneyParams::eval_and_pdf`] at this `wo`; for a transmissive material also below the surface.
    #[inline]
    #[must_use]
    pub fn eval_and_pdf(&self, wi: Vec3) -> (Vec3, f32) {
        let wi = normalize_or_zero(wi);
        let w = self.transmission_weight;
        if w > 0.0 && self.wo.z > 0.0 {
            let (f_t, pdf_t) = self.dielectric.eval_and_pdf(self.wo, wi);
            if !(wi.z > 0.0) {
                return (f_t * w, pdf_t * w);
            }
            let (f_d, pdf_d) = DisneyParams::eval_and_pdf_unit(&self.lobes, self.wo, wi);
            return (f_d * (1.0 - w) + f_t * w, pdf_d * (1.0 - w) + pdf_t * w);
        }
        if !(self.wo.z > 0.0 && wi.z > 0.0) {
            return (Vec3::ZERO, 0.0);
        }
        DisneyParams::eval_and_pdf_unit(&self.lobes, self.wo, wi)
    }

    /// [`DisneyParams::sample`] at this `wo`; a transmissive material picks the dielectric with
    /// probability `w` (see the type's documentation).
    #[must_use]
    pub fn sample(&self, u: Vec3) -> BsdfSample {
        let w = self.transmission_weight;
        if w > 0.0 {
            let s = if u.x < w {
                self.dielectric
                    .sample(self.wo, Vec3::new(u.x / w, u.y, u.z))
            } else {
                let rest = ((u.x - w) / (1.0 - w)).min(ONE_MINUS_EPSILON);
                self.sample_disney(Vec3::new(rest, u.y, u.z))
            };
            if !(s.pdf > 0.0) {
                return BsdfSample::failed();
            }
            let (f, pdf) = self.eval_and_pdf(s.wi);
            if !(pdf > 0.0) {
                return BsdfSample::failed();
            }
            return BsdfSample { wi: s.wi, f, pdf };
        }
        self.sample_disney(u)
    }

    /// The Disney BRDF's own sampling ([`DisneyParams::sample`]).
    #[must_use]
    fn sample_disney(&self, u: Vec3) -> BsdfSample {
        let (lobes, wo) = (&self.lobes, self.wo);
        if wo.z <= 0.0 {
            return BsdfSample::failed();
        }
        let lobe = if lobes.p_clearcoat > 0.0 && u.x >= lobes.p_diffuse + lobes.p_specular {
            LOBE_CLEARCOAT
        } else if lobes.p_specular > 0.0 && u.x >= lobes.p_diffuse {
            LOBE_SPECULAR
        } else {
            LOBE_DIFFUSE
        };
        let wi = DisneyParams::sample_lobe(lobes, wo, lobe, Vec2::new(u.y, u.z));
        if wi.z <= 0.0 {
            return BsdfSample::failed();
        }
        // The same numbers as `eval_and_pdf(wo, wi)`: `normalize_or_zero` passes unit vectors through.
        let (f, pdf) = DisneyParams::eval_and_pdf_unit(lobes, wo, wi);
        if pdf <= 0.0 {
            return BsdfSample::failed();
        }
        BsdfSample { wi, f, pdf }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::math::float::safe_sqrt;
    use std::vec::Vec;

    use crate::test_support::XorShift32 as Rng;

    /// Disney-specific draws on top of the shared test generator.
    trait DisneyDraws {
        fn upper_dir(&mut self) -> Vec3;
        fn params(&mut self) -> DisneyParams;
    }

    impl DisneyDraws for Rng {
        /// A direction above the surface, cos θ uniform in (0, 1].
        fn upper_dir(&mut self) -> Vec3 {
            let z = 1.0 - self.next();
            let s = safe_sqrt(1.0 - z * z);
            let phi = 2.0 * PI * self.next();
            Vec3::new(s * cos(phi), s * sin(phi), z)
        }
        fn params(&mut self) -> DisneyParams {
            DisneyParams {
                base_color: self.vec3(),
                metallic: self.next(),
                roughness: self.next(),
                anisotropic: self.next(),
                specular: self.next(),
                specular_tint: self.next(),
                sheen: self.next(),
                sheen_tint: self.next(),
                clearcoat: self.next(),
                clearcoat_gloss: self.next(),
                lambertian: false,
                transmission: 0.0,
                ior: 1.5,
                thin_walled: false,
            }
        }
    }

    /// The corners of the parameter space: metallic 0/1, roughness 0/1, anisotropic 0/0.99,
    /// specular 0/1, sheen 0/1, clearcoat off / on with gloss 0 / on with gloss 1.
    fn corners(base: Vec3) -> Vec<DisneyParams> {
        let mut out = Vec::new();
        for i in 0..96u32 {
            let (cc, gloss) = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)][(i / 32) as usize];
            out.push(DisneyParams {
                base_color: base,
                metallic: (i & 1) as f32,
                roughness: ((i >> 1) & 1) as f32,
                anisotropic: 0.99 * ((i >> 2) & 1) as f32,
                specular: ((i >> 3) & 1) as f32,
                specular_tint: 0.0,
                sheen: ((i >> 4) & 1) as f32,
                sheen_tint: 0.0,
                clearcoat: cc,
                clearcoat_gloss: gloss,
                lambertian: false,
                transmission: 0.0,
                ior: 1.5,
                thin_walled: false,
            });
        }
        out
    }

    /// The corners with a Lambertian diffuse lobe ([`DisneyParams::lambertian`]): those of [`corners`]
    /// with metallic 0 and no anisotropy (24), where the diffuse lobe matters.
    fn lambertian_corners(base: Vec3) -> Vec<DisneyParams> {
        corners(base)
            .into_iter()
            .filter(|p| p.metallic == 0.0 && p.anisotropic == 0.0)
            .map(|p| DisneyParams {
                lambertian: true,
                ..p
            })
            .collect()
    }

    /// Outgoing directions used throughout: head-on, oblique, grazing, nearly tangent, not unit.
    fn test_wos() -> [Vec3; 6] {
        [
            Vec3::Z,
            Vec3::new(0.3, -0.5, 0.81).normalize(),
            Vec3::new(-0.9, 0.3, 0.2).normalize(),
            Vec3::new(0.0, 1.0, 0.02).normalize(),
            Vec3::new(1.0, 0.0, 1e-7),
            Vec3::new(2.0, 3.0, 4.0),
        ]
    }

    fn rel_close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol * a.abs().max(b.abs()) + 1e-30
    }

    fn rel_close3(a: Vec3, b: Vec3, tol: f32) -> bool {
        rel_close(a.x, b.x, tol) && rel_close(a.y, b.y, tol) && rel_close(a.z, b.z, tol)
    }

    /// ∫ g(wi) dωi over the whole sphere on a grid in polar coordinates around `pole`, with
    /// θ = π t⁴ so that narrow lobes around the pole (mirror lobes with alpha down to 1e-4) are resolved.
    fn integrate_sphere(pole: Vec3, nt: usize, np: usize, mut g: impl FnMut(Vec3) -> f64) -> f64 {
        let frame = crate::math::Frame::from_normal(pole.normalize());
        let pi = core::f64::consts::PI;
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64;
            let theta = pi * t * t * t * t;
            let dtheta = pi * 4.0 * t * t * t / nt as f64;
            let w = theta.sin() * dtheta * (2.0 * pi / np as f64);
            let (st, ct) = (theta.sin(), theta.cos());
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * 2.0 * pi;
                let local = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32);
                sum += g(frame.to_world(local)) * w;
            }
        }
        sum
    }

    fn mirror(wo: Vec3) -> Vec3 {
        let wo = wo.normalize();
        Vec3::new(-wo.x, -wo.y, wo.z.max(1e-3)).normalize()
    }

    /// Burley's BRDF Explorer `disney.brdf`, transcribed literally in f64 (subsurface 0, our alphas and
    /// luminance), with the energy-conserving layering of the module docs on top, as an independent
    /// reference for `eval`.
    fn reference_eval(p: &DisneyParams, wo: Vec3, wi: Vec3) -> [f64; 3] {
        let unit = |w: Vec3| {
            let w = [w.x as f64, w.y as f64, w.z as f64];
            let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            [w[0] / n, w[1] / n, w[2] / n]
        };
        let v = unit(wo);
        let l = unit(wi);
        let (ndotl, ndotv) = (l[2], v[2]);
        if ndotl < 0.0 || ndotv < 0.0 {
            return [0.0; 3];
        }
        let hs = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
        let hn = (hs[0] * hs[0] + hs[1] * hs[1] + hs[2] * hs[2]).sqrt();
        let h = [hs[0] / hn, hs[1] / hn, hs[2] / hn];
        let ndoth = h[2];
        let ldoth = l[0] * h[0] + l[1] * h[1] + l[2] * h[2];
        let schlick = |u: f64| (1.0 - u).clamp(0.0, 1.0).powi(5);
        let pi = core::f64::consts::PI;
        let base = [
            p.base_color.x as f64,
            p.base_color.y as f64,
            p.base_color.z as f64,
        ];
        let lum = 0.2126 * base[0] + 0.7152 * base[1] + 0.0722 * base[2];
        let mix = |a: f64, b: f64, t: f64| a * (1.0 - t) + b * t;
        let fl = schlick(ndotl);
        let fv = schlick(ndotv);
        let fd90 = 0.5 + 2.0 * ldoth * ldoth * p.roughness as f64;
        let fd = mix(1.0, fd90, fl) * mix(1.0, fd90, fv);
        let a = p.alphas();
        let (ax, ay) = (a.x as f64, a.y as f64);
        let ds = 1.0
            / (pi * ax * ay * ((h[0] / ax).powi(2) + (h[1] / ay).powi(2) + ndoth * ndoth).powi(2));
        let fh = schlick(ldoth);
        let g_aniso = |w: [f64; 3]| {
            1.0 / (w[2] + ((w[0] * ax).powi(2) + (w[1] * ay).powi(2) + w[2] * w[2]).sqrt())
        };
        let gs = g_aniso(l) * g_aniso(v);
        let acc = mix(0.1, 0.001, p.clearcoat_gloss as f64);
        let a2 = acc * acc;
        let dr = (a2 - 1.0) / (pi * a2.ln() * (1.0 + (a2 - 1.0) * ndoth * ndoth));
        let fr = mix(0.04, 1.0, fh);
        let g_ggx = |nv: f64| {
            let a = 0.0625;
            let b = nv * nv;
            1.0 / (nv + (a + b - a * b).sqrt())
        };
        let gr = g_ggx(ndotl) * g_ggx(ndotv);
        // The layering of the module docs: base albedo (diffuse in closed form, sheen bound), N, t.
        let r = p.roughness as f64;
        let diffuse_albedo = |mu: f64| {
            let fv = schlick(mu);
            let a1 = r * (1.0 + 2.0 * mu / 3.0) - 0.5;
            let a_l = (r - 0.5) / 21.0 + r * mu / 84.0;
            let (m0, m1, m2) = (1.0 / 21.0, mu / 84.0, (11.0 - 9.0 * mu * mu) / 504.0);
            let a_ll = r * r * (m0 + 2.0 * m1 + m2) - r * (m0 + m1) + 0.25 * m0;
            1.0 + a_l + fv * (a1 + a_ll)
        };
        let sheen_bound = |mu: f64| 0.0035 + 0.088 * (1.0 - mu).powi(2);
        let mut base_albedo = [0.0f64; 2];
        let mut cspec0 = [0.0f64; 3];
        let mut csheen = [0.0f64; 3];
        for c in 0..3 {
            let tint = if lum > 0.0 { base[c] / lum } else { 1.0 };
            cspec0[c] = mix(
                p.specular as f64 * 0.08 * mix(1.0, tint, p.specular_tint as f64),
                base[c],
                p.metallic as f64,
            );
            csheen[c] = mix(1.0, tint, p.sheen_tint as f64) * p.sheen as f64;
            for (k, mu) in [ndotv, ndotl].into_iter().enumerate() {
                let a = (1.0 - p.metallic as f64)
                    * (base[c] * diffuse_albedo(mu) + csheen[c] * sheen_bound(mu));
                base_albedo[k] = base_albedo[k].max(a);
            }
        }
        let norm = base_albedo[0].max(base_albedo[1]).max(1.0);
        let cc_albedo = |mu: f64| 0.25 * p.clearcoat as f64 * mix(0.04, 1.0, schlick(mu));
        let t_cc = 1.0 - cc_albedo(ndotv).max(cc_albedo(ndotl));
        // Grazing reflectance min(1, 50 max F0) (Schüler 2009).
        let f90 = (50.0 * cspec0[0].max(cspec0[1]).max(cspec0[2])).min(1.0);
        let mut out = [0.0; 3];
        for c in 0..3 {
            let fs = mix(cspec0[c], f90, fh);
            let fsheen = fh * csheen[c];
            let spec_albedo = |mu: f64| mix(cspec0[c], f90, schlick(mu)).min(1.0);
            let t_spec = 1.0 - spec_albedo(ndotv).max(spec_albedo(ndotl));
            let f_base = ((1.0 / pi) * fd * base[c] + fsheen) * (1.0 - p.metallic as f64) / norm;
            out[c] =
                0.25 * p.clearcoat as f64 * gr * fr * dr + t_cc * (gs * fs * ds + t_spec * f_base);
        }
        out
    }

    #[test]
    fn eval_matches_burley_reference() {
        let mut rng = Rng(2024);
        let mut params = corners(Vec3::new(0.9, 0.5, 0.2));
        for _ in 0..200 {
            params.push(rng.params());
        }
        for p in &params {
            for _ in 0..20 {
                let wo = rng.upper_dir();
                let wi = rng.upper_dir();
                let f = p.eval(wo, wi);
                let r = reference_eval(p, wo, wi);
                for c in 0..3 {
                    let (a, b) = (f[c] as f64, r[c]);
                    assert!(
                        (a - b).abs() <= 2e-3 * b.abs() + 1e-6,
                        "{p:?} wo {wo} wi {wi}: {f} vs {r:?}"
                    );
                }
            }
        }
        // Head-on, specular 0, no sheen, base albedo below 1 (no normalisation): exactly Lambert base / π.
        let p = DisneyParams {
            specular: 0.0,
            ..DisneyParams::diffuse(Vec3::new(0.5, 0.25, 0.9))
        };
        let f = p.eval(Vec3::Z, Vec3::Z);
        assert!(
            (f - Vec3::new(0.5, 0.25, 0.9) * INV_PI).abs().max_element() < 1e-6,
            "{f}"
        );
        // A white rough base is normalised by its head-on albedo 1 + 1/42 + 1/84 = 1.0357.
        let p = DisneyParams {
            specular: 0.0,
            ..DisneyParams::diffuse(Vec3::ONE)
        };
        let f = p.eval(Vec3::Z, Vec3::Z);
        assert!(
            (f.x * PI * (1.0 + 1.0 / 42.0 + 1.0 / 84.0) - 1.0).abs() < 1e-5,
            "{f}"
        );
    }

    #[test]
    fn a_dielectric_of_infinite_index_reflects_like_a_white_metal() {
        // glTF's `ior: 0`: F0 = 1, so the base layer underneath gets nothing.
        let mut dielectric = DisneyParams::diffuse(Vec3::new(0.8, 0.3, 0.1));
        dielectric.roughness = 0.4;
        dielectric.specular = SPECULAR_MAX;
        let mut metal = DisneyParams::diffuse(Vec3::ONE);
        metal.roughness = 0.4;
        metal.metallic = 1.0;
        let mut rng = Rng(5);
        for _ in 0..50 {
            let (wo, wi) = (rng.upper_dir(), rng.upper_dir());
            let (a, b) = (dielectric.eval(wo, wi), metal.eval(wo, wi));
            assert!(
                (a - b).abs().max_element() <= 1e-5 * b.max_element().max(1.0),
                "{a} vs {b}"
            );
        }
    }

    #[test]
    fn below_horizon_is_zero() {
        let p = DisneyParams::diffuse(Vec3::ONE);
        let up = Vec3::new(0.2, 0.1, 0.9);
        let down = Vec3::new(0.2, 0.1, -0.9);
        for (wo, wi) in [
            (up, down),
            (down, up),
            (down, down),
            (up, Vec3::X),
            (Vec3::ZERO, up),
        ] {
            let (f, pdf) = p.eval_and_pdf(wo, wi);
            assert_eq!((f, pdf), (Vec3::ZERO, 0.0));
        }
        assert_eq!(p.sample(down, Vec3::splat(0.5)).pdf, 0.0);
    }

    /// Test 1: `sample` returns exactly `eval` and `pdf` at the sampled direction.
    #[test]
    fn sample_agrees_with_eval_and_pdf() {
        let mut rng = Rng(77);
        let mut params = corners(Vec3::ONE);
        params.extend(corners(Vec3::new(0.8, 0.1, 0.3)));
        params.extend(lambertian_corners(Vec3::new(0.8, 0.1, 0.3)));
        for _ in 0..300 {
            params.push(rng.params());
        }
        for p in &params {
            for (k, wo) in test_wos().into_iter().enumerate() {
                let mut ok = 0;
                let n = 64;
                for _ in 0..n {
                    let s = p.sample(wo, rng.vec3());
                    assert!(
                        s.wi.is_finite() && s.f.is_finite() && s.pdf.is_finite() && s.pdf >= 0.0
                    );
                    if s.pdf == 0.0 {
                        continue;
                    }
                    ok += 1;
                    assert!((s.wi.length() - 1.0).abs() < 1e-5 && s.wi.z > 0.0);
                    assert!(s.f.min_element() >= 0.0);
                    let f = p.eval(wo, s.wi);
                    let pdf = p.pdf(wo, s.wi);
                    let (f2, pdf2) = p.eval_and_pdf(wo, s.wi);
                    assert!(
                        rel_close3(f, s.f, 1e-4) && rel_close(pdf, s.pdf, 1e-4),
                        "{p:?} {wo}"
                    );
                    assert!(f == f2 && pdf == pdf2);
                }
                // Away from the horizon most samples succeed, except for very rough specular lobes (GGX
                // with alpha 1 seen head-on reflects half of its visible normals below the horizon).
                if k < 3 {
                    let smooth = p.alphas().max_element() <= 0.5;
                    assert!(
                        ok * if smooth { 2 } else { 8 } >= n,
                        "{p:?} wo {wo}: {ok}/{n}"
                    );
                }
            }
        }
    }

    /// Every entry point is finite (and non-negative) for degenerate and out-of-range input.
    #[test]
    fn degenerate_input_stays_finite() {
        let zero = DisneyParams {
            base_color: Vec3::ZERO,
            metallic: 0.0,
            roughness: 0.0,
            anisotropic: 0.0,
            specular: 0.0,
            specular_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            lambertian: false,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: false,
        };
        let wild = DisneyParams {
            base_color: Vec3::new(-1.0, 1e30, 3.0),
            metallic: -2.0,
            roughness: 7.0,
            anisotropic: 5.0,
            specular: -1.0,
            specular_tint: 9.0,
            sheen: 1e20,
            sheen_tint: -3.0,
            clearcoat: 4.0,
            clearcoat_gloss: -8.0,
            lambertian: false,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: false,
        };
        let mirror_like = DisneyParams {
            metallic: 1.0,
            roughness: 0.0,
            ..zero
        };
        let dirs = [
            Vec3::Z,
            Vec3::new(1.0, 0.0, 1e-7),
            Vec3::new(0.0, -1.0, 1e-7),
            Vec3::new(1e-30, 0.0, 1e-30),
            Vec3::new(3e37, -2e37, 1e37),
            Vec3::ZERO,
            Vec3::new(0.3, 0.3, -0.9),
            Vec3::new(1e-7, 0.0, 1.0),
        ];
        let mut rng = Rng(5);
        for p in [zero, wild, mirror_like, DisneyParams::diffuse(Vec3::ONE)] {
            for wo in dirs {
                for wi in dirs {
                    let (f, pdf) = p.eval_and_pdf(wo, wi);
                    assert!(
                        f.is_finite() && pdf.is_finite() && pdf >= 0.0,
                        "{p:?} {wo} {wi}"
                    );
                    assert!(f.min_element() >= 0.0);
                }
                for _ in 0..200 {
                    let s = p.sample(wo, rng.vec3());
                    assert!(
                        s.wi.is_finite() && s.f.is_finite() && s.pdf.is_finite(),
                        "{p:?} {wo}"
                    );
                }
                for u in [
                    Vec3::ZERO,
                    Vec3::splat(0.999_999_94),
                    Vec3::new(0.5, 0.5, 0.5),
                ] {
                    let s = p.sample(wo, u);
                    assert!(
                        s.wi.is_finite() && s.f.is_finite() && s.pdf.is_finite(),
                        "{p:?} {wo}"
                    );
                }
            }
        }
    }

    /// Test 4: reciprocity f(wo, wi) = f(wi, wo).
    #[test]
    fn eval_is_reciprocal() {
        let mut rng = Rng(31337);
        let mut params = corners(Vec3::new(0.7, 0.9, 0.2));
        params.extend(lambertian_corners(Vec3::new(0.7, 0.9, 0.2)));
        for _ in 0..300 {
            params.push(rng.params());
        }
        for p in &params {
            for _ in 0..30 {
                let a = rng.upper_dir();
                let b = rng.upper_dir();
                let f_ab = p.eval(a, b);
                let f_ba = p.eval(b, a);
                assert!(rel_close3(f_ab, f_ba, 1e-4), "{p:?} {a} {b}: {f_ab} {f_ba}");
            }
        }
    }

    /// A Lambertian material without specular, sheen or clearcoat is exactly Lambert's BRDF at every
    /// roughness: `f = base / π`, `pdf = cos θi / π` (cosine sampling), so every sample's weight
    /// `f cos θi / pdf` is the base colour; with a specular layer its albedo stays at most 1.
    #[test]
    fn lambertian_is_lambert() {
        let mut rng = Rng(4242);
        let base = Vec3::new(0.73, 0.065, 0.05);
        for roughness in [0.0, 0.5, 1.0] {
            let p = DisneyParams {
                roughness,
                specular: 0.0,
                lambertian: true,
                ..DisneyParams::diffuse(base)
            };
            for _ in 0..2_000 {
                let (wo, wi) = (rng.upper_dir(), rng.upper_dir());
                let (f, pdf) = p.eval_and_pdf(wo, wi);
                assert!(
                    rel_close3(f, base * INV_PI, 1e-6),
                    "{roughness} {wo} {wi}: {f}"
                );
                assert!(rel_close(pdf, wi.normalize().z * INV_PI, 1e-5), "{pdf}");
                let s = p.sample(wo, rng.vec3());
                if s.pdf > 0.0 {
                    assert!(rel_close3(s.f * (s.wi.z / s.pdf), base, 1e-5), "{s:?}");
                }
            }
            // Burley's diffuse at the same roughness differs (retro-reflection at grazing angles).
            let burley = DisneyParams {
                lambertian: false,
                ..p
            };
            let (wo, wi) = (Vec3::new(0.99, 0.0, 0.141).normalize(), Vec3::Z);
            assert!(burley.eval(wo, wi) != p.eval(wo, wi));
        }
    }

    /// Test 2: the mixture pdf integrates to at most 1 over the sphere (the sampler loses what the
    /// specular lobes reflect below the horizon) and to nearly 1 for rough diffuse materials.
    #[test]
    fn pdf_integrates_to_at_most_one() {
        let wos = [
            Vec3::Z,
            Vec3::new(0.3, -0.5, 0.81).normalize(),
            Vec3::new(-0.9, 0.3, 0.2).normalize(),
        ];
        for p in corners(Vec3::ONE).into_iter().filter(|p| p.sheen == 0.0) {
            for wo in wos {
                let s = integrate_sphere(mirror(wo), 800, 300, |wi| p.pdf(wo, wi) as f64);
                assert!(s <= 1.01, "{p:?} wo {wo}: {s}");
                // Even the roughest specular lobe keeps more than a quarter of its samples.
                assert!(s > 0.25, "{p:?} wo {wo}: {s}");
            }
        }
        let diffuse = DisneyParams::diffuse(Vec3::splat(0.8));
        // The lower bound leaves room for the specular lobe (chosen with probability ~5% head-on and
        // ~30% at 78°), whose alpha-1 samples land below the horizon 15-50% of the time.
        for (wo, lower) in wos.into_iter().zip([0.97, 0.97, 0.93]) {
            let s = integrate_sphere(mirror(wo), 800, 300, |wi| diffuse.pdf(wo, wi) as f64);
            assert!((lower..=1.01).contains(&s), "wo {wo}: {s}");
        }
        // Pure cosine lobe (no specular, no sheen, no clearcoat) seen head-on: exactly 1.
        let lambert = DisneyParams {
            specular: 0.0,
            ..diffuse
        };
        let s = integrate_sphere(Vec3::Z, 800, 300, |wi| lambert.pdf(Vec3::Z, wi) as f64);
        assert!((s - 1.0).abs() < 2e-3, "{s}");
    }

    /// Test 3: white furnace against quadrature. With base colour 1 the albedo estimated by importance
    /// sampling (mean of f cos θ / pdf) must agree with a quadrature of f cos θ (so the sampler is
    /// unbiased and its pdf covers f), and both must stay at most 1.01 (the layering of the module docs;
    /// before it, canonical Disney reached 1.76 at grazing angles). [`white_furnace_every_corner`] scans
    /// many more incident angles.
    #[test]
    fn white_furnace() {
        let wos = [
            Vec3::Z,
            Vec3::new(0.3, -0.5, 0.81).normalize(),
            Vec3::new(-0.9, 0.3, 0.2).normalize(),
            Vec3::new(0.0, 1.0, 0.02).normalize(),
        ];
        let mut rng = Rng(8);
        for p in corners(Vec3::ONE)
            .into_iter()
            .chain(lambertian_corners(Vec3::ONE))
        {
            for wo in wos {
                let n = 8_192;
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for _ in 0..n {
                    let s = p.sample(wo, rng.vec3());
                    if s.pdf > 0.0 {
                        let w = (s.f.y * s.wi.z / s.pdf) as f64;
                        sum += w;
                        sum2 += w * w;
                    }
                }
                let mean = sum / n as f64;
                let sigma = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                // Mirror-like lobes seen at grazing angles are squeezed azimuthally (by 2 wo·h) and
                // need a finer grid.
                let fine = wo.z < 0.1 && p.roughness == 0.0;
                let (nt, np) = if fine { (1000, 400) } else { (400, 160) };
                let quad =
                    integrate_sphere(mirror(wo), nt, np, |wi| (p.eval(wo, wi).y * wi.z) as f64);
                assert!(
                    (mean - quad).abs() <= 5.0 * sigma + 5e-3 * quad + 1e-3,
                    "{p:?} wo {wo}: IS {mean} ± {sigma}, quadrature {quad}"
                );
                assert!(
                    mean <= 1.01 && quad <= 1.01,
                    "{p:?} wo {wo}: IS {mean}, quad {quad}"
                );
            }
        }
        // A grey rough dielectric loses energy, never gains it, away from grazing angles.
        let grey = DisneyParams::diffuse(Vec3::splat(0.5));
        for wo in [Vec3::Z, Vec3::new(0.3, -0.5, 0.81).normalize()] {
            let quad = integrate_sphere(mirror(wo), 600, 240, |wi| {
                (grey.eval(wo, wi).y * wi.z) as f64
            });
            assert!(quad > 0.45 && quad < 0.6, "{quad}");
        }
    }

    /// The base layer's albedo terms: the closed form of the diffuse albedo against quadrature
    /// (roughness 0, 0.5, 1), the sheen bound above its quadrature, and the clearcoat bound Ê_cc above
    /// the clearcoat lobe's albedo (gloss 0 and 1).
    #[test]
    fn layer_albedo_terms() {
        // ∫ g(wi) cos θi dωi over the hemisphere, midpoint rule in (cos θ, φ).
        let quad = |g: &dyn Fn(Vec3) -> f64| {
            let (nt, np) = (600, 300);
            let mut sum = 0.0;
            for i in 0..nt {
                let mu = (i as f64 + 0.5) / nt as f64;
                let st = (1.0 - mu * mu).sqrt();
                for j in 0..np {
                    let phi = (j as f64 + 0.5) / np as f64 * 2.0 * core::f64::consts::PI;
                    let wi = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, mu as f32);
                    sum += g(wi) * mu;
                }
            }
            sum * 2.0 * core::f64::consts::PI / (nt * np) as f64
        };
        for &mu in &[1.0f32, 0.8, 0.5, 0.3, 0.1, 0.01] {
            let wo = Vec3::new(safe_sqrt(1.0 - mu * mu), 0.0, mu);
            for &r in &[0.0f32, 0.5, 1.0] {
                let q = quad(&|wi: Vec3| {
                    let cos_d = 0.5 * (wo + wi).length();
                    let fd90 = 0.5 + 2.0 * r * cos_d * cos_d;
                    let fd = (1.0 + (fd90 - 1.0) * schlick_weight(wi.z))
                        * (1.0 + (fd90 - 1.0) * schlick_weight(mu));
                    (fd * INV_PI) as f64
                });
                let closed = diffuse_albedo(mu, r) as f64;
                assert!(
                    (q - closed).abs() < 1e-3 * closed,
                    "mu {mu} r {r}: {q} vs {closed}"
                );
            }
            let sheen = quad(&|wi: Vec3| schlick_weight(0.5 * (wo + wi).length()) as f64);
            assert!(
                sheen <= sheen_albedo_bound(mu) as f64,
                "mu {mu}: sheen {sheen}"
            );
            for gloss in [0.0f32, 1.0] {
                let p = DisneyParams {
                    clearcoat: 1.0,
                    clearcoat_gloss: gloss,
                    ..DisneyParams::diffuse(Vec3::ONE)
                };
                let lobes = p.lobes(mu, FeatureFlags::ALL);
                // The clearcoat lobe alone (its weight without the layers below).
                let cc = quad(&|wi: Vec3| {
                    let hv = wo + wi;
                    let h = hv.normalize();
                    let f_c = 0.04 + 0.96 * schlick_weight(0.5 * hv.length());
                    let g_c = smith_g1_over_2cos(wo, CLEARCOAT_G_ALPHA, CLEARCOAT_G_ALPHA)
                        * smith_g1_over_2cos(wi, CLEARCOAT_G_ALPHA, CLEARCOAT_G_ALPHA);
                    (0.25 * gtr1_d(h, lobes.cc_alpha) * f_c * g_c) as f64
                });
                // Gloss 1 seen head-on is a 1e-3-wide peak the grid cannot resolve; skip it.
                if gloss == 0.0 || mu < 0.9 {
                    assert!(
                        cc <= lobes.cc_albedo(mu) as f64,
                        "mu {mu} gloss {gloss}: {cc}"
                    );
                }
            }
        }
    }

    /// White furnace at every corner (base colour 1): the directional albedo, estimated by importance
    /// sampling to a standard error of 0.002 (0.2 % of the bound 1; or at most 1 M samples;
    /// `FOVEA_HEAVY=1`: 0.001 and 16 M), is at
    /// most 1.01 for incident cos θ from 1 down to 1e-3 (anisotropic corners at two azimuths, along and
    /// across the anisotropy). Prints the maximum per corner.
    #[test]
    fn white_furnace_every_corner() {
        use crate::test_support::chi2::heavy;
        use crate::test_support::SplitMix64;
        let cosines = [
            1.0f32, 0.8, 0.6, 0.4, 0.25, 0.15, 0.1, 0.05, 0.02, 0.01, 3e-3, 1e-3,
        ];
        let (abs_err, max_n) = if heavy() {
            (1e-3, 16_000_000)
        } else {
            (2e-3, 1_000_000)
        };
        let mut total_samples = 0usize;
        let mut rng = SplitMix64(0xF0F);
        let mut overall = 0.0f64;
        for p in corners(Vec3::ONE) {
            let mut worst = (0.0f64, 0.0f64, 0.0f32, 0.0f32);
            for &mu in &cosines {
                for phi in [0.0f32, 0.5 * PI] {
                    if phi > 0.0 && p.anisotropic == 0.0 {
                        continue;
                    }
                    let s = safe_sqrt(1.0 - mu * mu);
                    let wo = Vec3::new(s * cos(phi), s * sin(phi), mu);
                    let (mut sum, mut sum2, mut n) = (0.0f64, 0.0f64, 0usize);
                    loop {
                        for _ in 0..8_192 {
                            let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                            let smp = p.sample(wo, u);
                            if smp.pdf > 0.0 {
                                let w = (smp.f.max_element() * smp.wi.z / smp.pdf) as f64;
                                sum += w;
                                sum2 += w * w;
                            }
                        }
                        n += 8_192;
                        let mean = sum / n as f64;
                        let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                        if se <= abs_err || n >= max_n {
                            total_samples += n;
                            if mean > worst.0 {
                                worst = (mean, se, mu, phi);
                            }
                            break;
                        }
                    }
                }
            }
            std::println!(
                "white furnace: metallic {} roughness {} anisotropic {} specular {} sheen {} clearcoat {} \
                 gloss {}: max albedo {:.4} ± {:.4} at cos θ {} φ {:.2}",
                p.metallic,
                p.roughness,
                p.anisotropic,
                p.specular,
                p.sheen,
                p.clearcoat,
                p.clearcoat_gloss,
                worst.0,
                worst.1,
                worst.2,
                worst.3
            );
            overall = overall.max(worst.0);
            assert!(worst.0 <= 1.01, "{p:?}: albedo {worst:?}");
        }
        std::println!(
            "white furnace: maximum over all corners {overall:.4} ({total_samples} samples in all)"
        );
    }

    /// Incident directions of the chi-square tests: θ = 0°, 30°, 60°, 85°, 89.9° at an azimuth of 0.3 rad
    /// (off the anisotropy axes).
    const INCIDENT_DEG: [f32; 5] = [0.0, 30.0, 60.0, 85.0, 89.9];

    fn incident(deg: f32) -> Vec3 {
        let t = deg.to_radians();
        Vec3::new(sin(t) * cos(0.3), sin(t) * sin(0.3), cos(t))
    }

    /// The mirror direction of `wo` about the normal: the axis of the chi-square grids.
    fn mirror_axis(wo: Vec3) -> Vec3 {
        Vec3::new(-wo.x, -wo.y, wo.z)
    }

    /// Chi-square tests of each lobe's sampler against its own pdf (`sample_lobe` against
    /// `eval_lobes_unit`): the specular lobe (GGX visible normals reflected about wo; roughness 1
    /// isotropic and anisotropic 0.99, roughness 0.5, roughness 0.3 anisotropic 0.99) and the clearcoat
    /// lobe (GTR1 alpha 0.1 and 0.001), each at incident 0°, 60° and 89.9°. The diffuse lobe is the cosine
    /// hemisphere ([`crate::sampling::warp`]'s chi-square test). Samples below the horizon are rejected
    /// (the lobe pdfs integrate to the kept fraction).
    #[test]
    fn chi2_lobes() {
        use crate::test_support::chi2::{
            chi2_test, family_share, geometric, join, sample_count, uniform_cos, Grid,
        };
        let pi = core::f64::consts::PI;
        let n = sample_count(500_000, 4_000_000);
        let angles = [0.0f32, 60.0, 89.9];
        // (roughness, anisotropic, clearcoat gloss, lobe)
        let cases = [
            (1.0f32, 0.0f32, 0.0f32, LOBE_SPECULAR),
            (1.0, 0.99, 0.0, LOBE_SPECULAR),
            (0.5, 0.0, 0.0, LOBE_SPECULAR),
            (0.3, 0.99, 0.0, LOBE_SPECULAR),
            (1.0, 0.0, 0.0, LOBE_CLEARCOAT),
            (1.0, 0.0, 1.0, LOBE_CLEARCOAT),
        ];
        assert_eq!(
            family_share("disney lobes"),
            (cases.len() * angles.len()) as u32
        );
        for (k, &(roughness, anisotropic, gloss, lobe)) in cases.iter().enumerate() {
            let p = DisneyParams {
                roughness,
                anisotropic,
                clearcoat: 1.0,
                clearcoat_gloss: gloss,
                ..DisneyParams::diffuse(Vec3::ONE)
            };
            for (j, &deg) in angles.iter().enumerate() {
                let wo = incident(deg);
                let lobes = p.lobes(wo.z, FeatureFlags::ALL);
                let narrow = if lobe == LOBE_CLEARCOAT {
                    lobes.cc_alpha as f64
                } else {
                    p.alphas().min_element() as f64
                };
                // Rows geometric in θ' from a tenth of the lobe's width around the mirror direction,
                // then uniform in cos θ' over the rest of the sphere.
                let edges = if narrow < 0.2 {
                    join(
                        geometric(0.1 * narrow, 0.5, 24, true),
                        uniform_cos(0.5, pi, 8),
                    )
                } else {
                    uniform_cos(0.0, pi, 32)
                };
                let grid = Grid::new(mirror_axis(wo), edges, 64).clip(Vec3::Z);
                let pick = if lobe == LOBE_CLEARCOAT { 2 } else { 1 };
                chi2_test(
                    &std::format!(
                        "disney {} lobe roughness {roughness} anisotropic {anisotropic} gloss {gloss} \
                         incident {deg}",
                        if lobe == LOBE_CLEARCOAT { "clearcoat" } else { "specular" }
                    ),
                    &grid,
                    n,
                    (k * 8 + j) as u64,
                    |rng| {
                        let uv = Vec2::new(rng.uniform(), rng.uniform());
                        let wi = DisneyParams::sample_lobe(&lobes, wo, lobe, uv);
                        (wi.z > 0.0).then_some(wi)
                    },
                    |wi| {
                        if wi.z <= 0.0 {
                            return 0.0;
                        }
                        DisneyParams::eval_lobes_unit(&lobes, wo, wi.normalize()).1[pick] as f64
                    },
                )
                .check();
            }
        }
    }

    /// Chi-square tests of the full BSDF sampler (`sample` against `pdf`) at the 96 corners, each at one
    /// incident angle (cycling through 0°, 30°, 60°, 85°, 89.9°), on a grid around the mirror direction.
    /// Every 8th sample also checks that `sample` returns exactly what `eval` and `pdf` give for its
    /// direction (the same f32 code path on the same unit vectors: relative 1e-6 allows for nothing but
    /// the reassociation of a renormalised direction).
    ///
    /// Roughness 0 means GGX alpha 1e-4, a near-delta that no fixed grid resolves: those corners exclude
    /// the cap of 0.01 rad around the mirror direction and test the rest conditionally; the 8 corners
    /// that are nothing but that near-delta (metallic 1, roughness 0, no clearcoat) are checked for
    /// concentration instead (all samples within 0.01 rad of the mirror direction but a GGX tail of
    /// at most 1e-3).
    #[test]
    fn chi2_full_bsdf_corners() {
        use crate::test_support::chi2::{
            chi2_test, family_share, geometric, sample_count, uniform_cos, Grid,
        };
        use crate::test_support::SplitMix64;
        let pi = core::f64::consts::PI;
        let n = sample_count(250_000, 2_000_000);
        let mut tested = 0;
        let mut max_rel = 0.0f32;
        let base = Vec3::new(0.9, 0.6, 0.3);
        for (k, p) in corners(base)
            .into_iter()
            .chain(lambertian_corners(base))
            .enumerate()
        {
            let deg = INCIDENT_DEG[k % INCIDENT_DEG.len()];
            let wo = incident(deg);
            let axis = mirror_axis(wo);
            if p.metallic == 1.0 && p.roughness == 0.0 && p.clearcoat == 0.0 {
                let mut rng = SplitMix64(k as u64);
                let mut far = 0;
                let m = 100_000;
                for _ in 0..m {
                    let s = p.sample(wo, Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()));
                    assert!(s.pdf > 0.0 || deg > 89.0, "{p:?}");
                    if s.pdf > 0.0 && s.wi.dot(axis) < cos(0.01) {
                        far += 1;
                    }
                }
                std::println!(
                    "near-delta corner metallic 1 roughness 0 anisotropic {} specular {} sheen {} \
                     incident {deg}: fraction beyond 0.01 rad of the mirror direction {:.1e}",
                    p.anisotropic,
                    p.specular,
                    p.sheen,
                    far as f64 / m as f64
                );
                assert!(far as f64 <= 1e-3 * m as f64, "{p:?}: {far}");
                continue;
            }
            tested += 1;
            let edges = if p.roughness == 0.0 {
                geometric(0.01, pi, 32, false)
            } else if p.clearcoat > 0.0 && p.clearcoat_gloss == 1.0 {
                geometric(2e-4, pi, 32, true)
            } else {
                uniform_cos(0.0, pi, 32)
            };
            let grid = Grid::new(axis, edges, 64).clip(Vec3::Z);
            let mut count = 0u32;
            chi2_test(
                &std::format!(
                    "disney corner metallic {} roughness {} anisotropic {} specular {} sheen {} \
                     clearcoat {} gloss {} incident {deg}",
                    p.metallic,
                    p.roughness,
                    p.anisotropic,
                    p.specular,
                    p.sheen,
                    p.clearcoat,
                    p.clearcoat_gloss
                ),
                &grid,
                n,
                1000 + k as u64,
                |rng| {
                    let s = p.sample(wo, Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()));
                    if s.pdf <= 0.0 {
                        return None;
                    }
                    count += 1;
                    if count.is_multiple_of(8) {
                        let (f, pdf) = p.eval_and_pdf(wo, s.wi);
                        let rel = (pdf - s.pdf).abs() / s.pdf;
                        let rel_f = (f - s.f).abs().max_element() / s.f.max_element().max(1e-30);
                        max_rel = max_rel.max(rel).max(rel_f);
                    }
                    Some(s.wi)
                },
                |wi| p.pdf(wo, wi) as f64,
            )
            .check();
        }
        std::println!("disney corners: max relative difference sample vs eval/pdf {max_rel:e}");
        assert!(max_rel <= 1e-6, "{max_rel}");
        assert_eq!(family_share("disney full bsdf"), tested);
    }
}
