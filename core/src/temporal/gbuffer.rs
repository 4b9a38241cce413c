//! The G-buffer: what the camera ray through a pixel's centre hits first. Reprojection checks history
//! against it (a tap whose surface is not this pixel's is disoccluded, [`super::reproject`]); a denoiser
//! demodulates by its albedo and stops its filter at its depth and normal edges.
//!
//! One un-jittered camera ray per pixel, traced to its first hit only (no shading, no light sample), in
//! every region: the fovea's samples are per pixel, but a periphery block's samples say nothing about
//! which of its 16 pixels sees which surface. It is the only ray fovea casts outside the blocks'
//! samples (about 1 / (1 + 4 · spp) of a block's rays with 3 bounces).
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::bvh::closest_hit_with;
use crate::integrator::{pixel_cone_spread, FrameParams};
use crate::lights::INFINITE_DISTANCE;
use crate::material::shading::surface_point_lod;
use crate::scene::{Features, SceneSource, SceneView};

/// A pixel's first hit (32 bytes, GPU layout): `normal_distance` = (unit shading normal facing the
/// camera xyz, distance from the camera), `albedo` = (base colour rgb, 1). A ray that hits nothing (the
/// sky) has distance 0, normal 0 and albedo 1.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GBufferTexel {
    pub normal_distance: [f32; 4],
    pub albedo: [f32; 4],
}

impl GBufferTexel {
    /// The texel of a ray that leaves the scene.
    pub const SKY: Self = Self {
        normal_distance: [0.0; 4],
        albedo: [1.0, 1.0, 1.0, 1.0],
    };

    /// Whether the ray hit nothing.
    #[inline]
    #[must_use]
    pub fn is_sky(&self) -> bool {
        !(self.normal_distance[3] > 0.0)
    }

    /// Distance from the camera to the hit (0 for the sky).
    #[inline]
    #[must_use]
    pub fn distance(&self) -> f32 {
        self.normal_distance[3]
    }

    /// The unit shading normal, turned towards the camera (0 for the sky).
    #[inline]
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        crate::math::vec3_from(self.normal_distance)
    }
}

/// The G-buffer texel of pixel (`x`, `y`) of `frame`: the first hit of the camera ray through the
/// pixel's centre (alpha cut-outs let it through, as they do the samples).
#[must_use]
pub fn first_hit_gbuffer<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    frame: &FrameParams,
    x: u32,
    y: u32,
) -> GBufferTexel {
    let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let ray = frame.camera.generate_ray(centre, frame.width, frame.height);
    let hit = closest_hit_with(scene, source, &ray, INFINITE_DISTANCE);
    if !hit.is_hit() {
        return GBufferTexel::SKY;
    }
    // The albedo over the pixel's footprint (the mip level of its ray cone), not at its centre: the
    // pixel's samples are jittered over it, so this is the albedo they saw on average
    // (`super::albedo` divides their radiance by it). A point sample of a minified texture would be
    // noise against their mean.
    let cone_width = pixel_cone_spread(frame) * hit.t;
    let surface = surface_point_lod(scene, source, &hit, ray.direction, cone_width);
    let mut normal = surface.frame.z;
    if normal.dot(ray.direction) > 0.0 {
        normal = -normal;
    }
    let c = surface.params.base_color;
    GBufferTexel {
        // The hit's distance from the camera (the ray direction is unit), the quantity the previous
        // frame's texel is compared with.
        normal_distance: [normal.x, normal.y, normal.z, hit.t.max(f32::MIN_POSITIVE)],
        albedo: [c.x, c.y, c.z, 1.0],
    }
}
