//! What importance sampling a BSDF returns (the Disney BRDF and the rough dielectric alike).
use glam::Vec3;

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
