//! The Disney principled BRDF (Burley 2012, "Physically-Based Shading at Disney", §5 and the BRDF
//! Explorer `disney.brdf`): retro-reflective diffuse, sheen, anisotropic GGX specular and a GTR1
//! clearcoat. Reflection only: no subsurface, no transmission.
//!
//! Conventions of [`crate::bsdf`]: local frame with `z` the shading normal, `wo` and `wi` away from the
//! surface, `f` without the cosine, solid-angle pdf over `wi`. Both directions must be above the
//! surface (`z > 0`); otherwise `f = 0` and `pdf = 0` (the integrator flips the frame to `wo`'s side).
//!
//! Importance sampling picks one of three lobes (diffuse with sheen: cosine hemisphere; specular: GGX
//! visible normals; clearcoat: GTR1 half vectors) with probabilities proportional to rough albedo
//! estimates, and reports the one-sample-MIS mixture pdf Σ p_lobe pdf_lobe, so `eval`, `pdf` and
//! `sample` agree exactly.
//!
//! Note that, like Burley's model, the BRDF is not energy-conserving everywhere: the retro-reflective
//! diffuse term gains energy at high roughness and grazing angles, and diffuse, sheen, specular and
//! clearcoat are summed without layering.
use crate::math::color::luminance;
use crate::math::float::{cos, ln, powf, safe_sqrt, sin, sqr, sqrt, INV_PI, PI};
use crate::sampling::ggx_vndf::{ggx_d, normalize_or_zero, sample_ggx_vndf, smith_g1_over_2cos};
use crate::sampling::warp::square_to_cosine_hemisphere;
use glam::{Vec2, Vec3};

pub use crate::sampling::ggx_vndf::ALPHA_MIN;

/// Disney BRDF parameters at a shading point (after textures are applied).
#[derive(Clone, Copy, Debug)]
pub struct DisneyParams {
    /// Linear RGB base colour.
    pub base_color: Vec3,
    pub metallic: f32,
    /// Perceptual roughness; GGX alpha = roughness².
    pub roughness: f32,
    pub anisotropic: f32,
    pub specular: f32,
    pub specular_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
}

/// The result of importance sampling the BRDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled incident direction (local frame, unit).
    pub wi: Vec3,
    /// BRDF value `f(wo, wi)` (no cosine).
    pub f: Vec3,
    /// Solid-angle pdf of `wi`; 0 means the sample failed and must be discarded.
    pub pdf: f32,
}

impl BsdfSample {
    /// A failed sample (`pdf = 0`).
    #[inline]
    #[must_use]
    pub fn failed() -> Self {
        Self {
            wi: Vec3::Z,
            f: Vec3::ZERO,
            pdf: 0.0,
        }
    }
}

/// Relative weight of the sheen lobe's albedo against the diffuse lobe's when choosing a lobe; it only
/// keeps sheen on black base colours sampled by the cosine lobe.
const SHEEN_SAMPLING_WEIGHT: f32 = 0.1;

/// Schlick's weight (1 - cos θ)⁵, with cos θ clamped to [0, 1].
#[inline]
#[must_use]
fn schlick_weight(cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Berry's GTR1 distribution ("generalized Trowbridge-Reitz" with γ = 1; Burley 2012, specular D), as a
/// function of cos θh; `alpha` in (0, 1).
#[inline]
#[must_use]
fn gtr1_d(cos_h: f32, alpha: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let c2 = cos_h * cos_h;
    // 1 + (a² - 1) cos² = sin² + a² cos², without cancellation near the pole.
    let t = (1.0 - c2).max(0.0) + a2 * c2;
    (a2 - 1.0) / (PI * ln(a2) * t)
}

/// Samples GTR1's cos θh with density ∝ D(h) cos θh (Burley 2012, appendix B).
#[inline]
#[must_use]
fn gtr1_sample_cos(u: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    safe_sqrt((1.0 - powf(a2, 1.0 - u)) / (1.0 - a2)).min(1.0)
}

/// Everything about the parameters that `eval`, `pdf` and `sample` share: clamped inputs, alphas,
/// tints, and the lobe-selection probabilities for one `wo`.
struct Lobes {
    base: Vec3,
    one_minus_metallic: f32,
    roughness: f32,
    ax: f32,
    ay: f32,
    cspec0: Vec3,
    sheen: Vec3,
    clearcoat: f32,
    cc_alpha: f32,
    p_diffuse: f32,
    p_specular: f32,
    p_clearcoat: f32,
}

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

    /// Clamps the parameters and computes the lobe probabilities for `cos_o = wo.z`.
    #[inline]
    #[must_use]
    fn lobes(&self, cos_o: f32) -> Lobes {
        let base = self.base_color.max(Vec3::ZERO);
        let metallic = self.metallic.clamp(0.0, 1.0);
        let one_minus_metallic = 1.0 - metallic;
        let lum = luminance(base);
        // Hue and saturation of the base colour, for the tints.
        let tint = if lum > 0.0 {
            base * (1.0 / lum)
        } else {
            Vec3::ONE
        };
        let specular_tint = self.specular_tint.clamp(0.0, 1.0);
        let cspec0 = (Vec3::ONE.lerp(tint, specular_tint) * (0.08 * self.specular.clamp(0.0, 1.0)))
            .lerp(base, metallic);
        let sheen =
            Vec3::ONE.lerp(tint, self.sheen_tint.clamp(0.0, 1.0)) * self.sheen.clamp(0.0, 1.0);
        let clearcoat = self.clearcoat.clamp(0.0, 1.0);
        let gloss = self.clearcoat_gloss.clamp(0.0, 1.0);
        let cc_alpha = 0.1 + (0.001 - 0.1) * gloss;
        let alphas = self.alphas();

        // Lobe selection ∝ albedo estimates.
        let fo = schlick_weight(cos_o);
        let w_d = one_minus_metallic * (lum + SHEEN_SAMPLING_WEIGHT * luminance(sheen));
        let w_s = luminance(cspec0 + (Vec3::ONE - cspec0) * fo);
        let w_c = 0.25 * clearcoat * (0.04 + 0.96 * fo);
        let total = w_d + w_s + w_c;
        let (p_diffuse, p_specular, p_clearcoat) = if total > 0.0 {
            let inv = 1.0 / total;
            (w_d * inv, w_s * inv, w_c * inv)
        } else {
            // Nothing reflects by the estimates (e.g. all-zero parameters seen head-on): fall back to
            // the cosine lobe, which covers the whole hemisphere.
            (1.0, 0.0, 0.0)
        };
        Lobes {
            base,
            one_minus_metallic,
            roughness: self.roughness.clamp(0.0, 1.0),
            ax: alphas.x,
            ay: alphas.y,
            cspec0,
            sheen,
            clearcoat,
            cc_alpha,
            p_diffuse,
            p_specular,
            p_clearcoat,
        }
    }

    /// BRDF value f(wo, wi) without the cosine (Burley 2012, §5): zero unless both directions are
    /// above the surface. Directions need not be unit.
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
    #[must_use]
    pub fn eval_and_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let wo = normalize_or_zero(wo);
        let wi = normalize_or_zero(wi);
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return (Vec3::ZERO, 0.0);
        }
        Self::eval_and_pdf_unit(&self.lobes(wo.z), wo, wi)
    }

    /// [`DisneyParams::eval_and_pdf`] for unit `wo`, `wi` above the surface and `lobes` of `wo.z`.
    #[must_use]
    fn eval_and_pdf_unit(lobes: &Lobes, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let hv = wo + wi;
        let l2 = hv.length_squared();
        if l2 <= 1e-30 {
            return (Vec3::ZERO, 0.0);
        }
        let len = sqrt(l2);
        let h = hv * (1.0 / len);
        // cos θd = wo·h = wi·h = |wo + wi| / 2 for unit directions: symmetric in wo and wi.
        let cos_d = (0.5 * len).min(1.0);

        // Diffuse with retro-reflection and sheen, both scaled by 1 - metallic.
        let fl = schlick_weight(wi.z);
        let fv = schlick_weight(wo.z);
        let fh = schlick_weight(cos_d);
        let fd90 = 0.5 + 2.0 * lobes.roughness * cos_d * cos_d;
        let fd = (1.0 + (fd90 - 1.0) * fl) * (1.0 + (fd90 - 1.0) * fv);
        let mut f = (lobes.base * (INV_PI * fd) + lobes.sheen * fh) * lobes.one_minus_metallic;

        // Specular: D F G1(wo) G1(wi) / (4 cos θo cos θi), with G1 / (2 cos) kept together.
        let d_s = ggx_d(h, lobes.ax, lobes.ay);
        let g_o = smith_g1_over_2cos(wo, lobes.ax, lobes.ay);
        let g_i = smith_g1_over_2cos(wi, lobes.ax, lobes.ay);
        let f_s = lobes.cspec0 + (Vec3::ONE - lobes.cspec0) * fh;
        f += f_s * (d_s * g_o * g_i);

        // Clearcoat: 0.25 · clearcoat · GTR1 · Schlick(0.04) · G(0.25) / (4 cos θo cos θi).
        // GTR1 needs a logarithm: skip it for the (common) materials without clearcoat, whose clearcoat
        // probability is zero too.
        let mut d_c = 0.0;
        if lobes.clearcoat > 0.0 {
            d_c = gtr1_d(h.z, lobes.cc_alpha);
            let f_c = 0.04 + 0.96 * fh;
            let g_c = smith_g1_over_2cos(wo, CLEARCOAT_G_ALPHA, CLEARCOAT_G_ALPHA)
                * smith_g1_over_2cos(wi, CLEARCOAT_G_ALPHA, CLEARCOAT_G_ALPHA);
            f += Vec3::splat(0.25 * lobes.clearcoat * d_c * f_c * g_c);
        }

        // Mixture pdf. Specular: D_wo(h) / (4 wo·h) = G1(wo) D(h) / (4 wo.z) = g_o D / 2.
        // Clearcoat: D(h) cos θh / (4 wo·h).
        let pdf_d = wi.z * INV_PI;
        let pdf_s = 0.5 * g_o * d_s;
        let pdf_c = d_c * h.z / (4.0 * cos_d);
        let pdf = lobes.p_diffuse * pdf_d + lobes.p_specular * pdf_s + lobes.p_clearcoat * pdf_c;
        (f, pdf)
    }

    /// Importance-samples `wi`: `u.x` picks the lobe, `u.yz` the direction. Returns `f` and the mixture
    /// pdf at the sampled direction (identical to [`DisneyParams::eval_and_pdf`] there), or `pdf = 0`
    /// when the sample falls below the surface or the input is degenerate.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u: Vec3) -> BsdfSample {
        let wo_n = normalize_or_zero(wo);
        if wo_n.z <= 0.0 {
            return BsdfSample::failed();
        }
        let lobes = self.lobes(wo_n.z);
        let uv = Vec2::new(u.y, u.z);
        let choose_clearcoat = lobes.p_clearcoat > 0.0 && u.x >= lobes.p_diffuse + lobes.p_specular;
        let choose_specular = !choose_clearcoat && lobes.p_specular > 0.0 && u.x >= lobes.p_diffuse;
        let wi = if choose_clearcoat || choose_specular {
            let m = if choose_clearcoat {
                let cos_h = gtr1_sample_cos(uv.x, lobes.cc_alpha);
                let sin_h = safe_sqrt(1.0 - sqr(cos_h));
                let phi = 2.0 * PI * uv.y;
                Vec3::new(sin_h * cos(phi), sin_h * sin(phi), cos_h)
            } else {
                sample_ggx_vndf(wo_n, lobes.ax, lobes.ay, uv)
            };
            // Mirror wo about the microfacet normal.
            m * (2.0 * wo_n.dot(m)) - wo_n
        } else {
            square_to_cosine_hemisphere(uv)
        };
        let wi = normalize_or_zero(wi);
        if wi.z <= 0.0 {
            return BsdfSample::failed();
        }
        // The same numbers as `eval_and_pdf(wo, wi)`: `normalize_or_zero` passes unit vectors through.
        let (f, pdf) = Self::eval_and_pdf_unit(&lobes, wo_n, wi);
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
            });
        }
        out
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
    /// luminance), as an independent reference for `eval`.
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
        let mut out = [0.0; 3];
        for c in 0..3 {
            let tint = if lum > 0.0 { base[c] / lum } else { 1.0 };
            let cspec0 = mix(
                p.specular as f64 * 0.08 * mix(1.0, tint, p.specular_tint as f64),
                base[c],
                p.metallic as f64,
            );
            let csheen = mix(1.0, tint, p.sheen_tint as f64);
            let fs = mix(cspec0, 1.0, fh);
            let fsheen = fh * p.sheen as f64 * csheen;
            out[c] = ((1.0 / pi) * fd * base[c] + fsheen) * (1.0 - p.metallic as f64)
                + gs * fs * ds
                + 0.25 * p.clearcoat as f64 * gr * fr * dr;
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
        // Head-on, specular 0, no sheen: exactly Lambert base / π.
        let p = DisneyParams {
            specular: 0.0,
            ..DisneyParams::diffuse(Vec3::new(0.5, 0.25, 1.0))
        };
        let f = p.eval(Vec3::Z, Vec3::Z);
        assert!(
            (f - Vec3::new(0.5, 0.25, 1.0) * INV_PI).abs().max_element() < 1e-6,
            "{f}"
        );
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

    /// Test 3: white furnace. With base colour 1 the albedo estimated by importance sampling (mean of
    /// f cos θ / pdf) must agree with a quadrature of f cos θ (so the sampler is unbiased and its pdf
    /// covers f), and must stay at most 1.01 where the model conserves energy: the metallic corners
    /// without clearcoat (a GGX conductor with F = 1 and separable Smith G).
    ///
    /// Canonical Disney is *not* energy-conserving elsewhere, so 1.01 is not asserted there: the
    /// retro-reflective diffuse term (FD90 up to 2.5 at roughness 1) gains energy, and diffuse, sheen,
    /// specular and clearcoat are added without layering. Measured maxima at these corners: about 1.07
    /// head-on and 1.77 at grazing `wo` (metallic 0, roughness 1, specular 1, sheen 1, clearcoat 1); the
    /// test bounds them by 1.8 to catch regressions.
    #[test]
    fn white_furnace() {
        let wos = [
            Vec3::Z,
            Vec3::new(0.3, -0.5, 0.81).normalize(),
            Vec3::new(-0.9, 0.3, 0.2).normalize(),
            Vec3::new(0.0, 1.0, 0.02).normalize(),
        ];
        let mut rng = Rng(8);
        for p in corners(Vec3::ONE) {
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
                if p.metallic == 1.0 && p.clearcoat == 0.0 {
                    assert!(
                        mean <= 1.01 && quad <= 1.01,
                        "{p:?} wo {wo}: IS {mean}, quad {quad}"
                    );
                }
                assert!(
                    mean <= 1.8 && quad <= 1.8,
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
}
