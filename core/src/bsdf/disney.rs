//! The Disney principled BRDF (Burley 2012).
use glam::Vec3;

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
