//! The G-buffer: what the camera ray through a pixel's centre hits first. Reprojection checks history
//! against it (a tap whose surface is not this pixel's is disoccluded, [`super::reproject`]); a denoiser
//! demodulates by its albedo and stops its filter at its depth and normal edges.
//!
//! One un-jittered camera ray per pixel, traced to its first hit only (no shading, no light sample), in
//! every region: the fovea's samples are per pixel, but a periphery block's samples say nothing about
//! which of its 16 pixels sees which surface. It is the only ray fovea traverses the scene with outside
//! the blocks' samples (about 1 / (1 + 4 · spp) of a block's rays with 3 bounces).
//!
//! Its albedo is the mean over the pixel ([`footprint_albedo`]): a denoiser and the history divide the
//! pixel's radiance by it and multiply it back after filtering, so it must be what the pixel's jittered
//! samples saw on average, a box filter of the texture over the pixel, not the texture at one point.
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::bvh::closest_hit_with;
use crate::geometry::triangle::WatertightRay;
use crate::geometry::Hit;
use crate::integrator::{pixel_cone_spread, FrameParams};
use crate::lights::INFINITE_DISTANCE;
use crate::material::alpha::{interpolate_uv, is_cut_out};
use crate::material::shading::{base_color_at, surface_point_lod, SurfacePoint};
use crate::scene::{Features, SceneSource, SceneView, MATERIAL_ALPHA_CUTOUT};

/// Albedo points per pixel edge: [`footprint_albedo`] averages the base colour over a
/// `GBUFFER_ALBEDO_GRID`² grid of the pixel, each point's texture read over its own part of the
/// footprint. Against one read at the centre at the whole footprint's mip level, a 2 × 2 grid took the
/// denoised 4/2/1 fovea's FLIP on Lost Empire from 0.131 to 0.099 (raw 32/16/8: 0.123;
/// docs/performance.md, "The G-buffer's albedo over the pixel").
pub const GBUFFER_ALBEDO_GRID: u32 = 2;

/// A pixel's first hit (32 bytes, GPU layout): `normal_distance` = (unit shading normal facing the
/// camera xyz, distance from the camera), `albedo` = (the base colour's mean over the pixel on the hit's
/// triangle, [`footprint_albedo`], rgb, 1). A ray that hits nothing (the
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
/// pixel's centre (alpha cut-outs let it through, as they do the samples), with the albedo averaged
/// over the pixel on the hit's triangle ([`footprint_albedo`]).
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
    let cone_width = pixel_cone_spread(frame) * hit.t;
    let surface = surface_point_lod(scene, source, &hit, ray.direction, cone_width);
    let mut normal = surface.frame.z;
    if normal.dot(ray.direction) > 0.0 {
        normal = -normal;
    }
    let c = footprint_albedo(scene, source, frame, &hit, &surface, x, y);
    GBufferTexel {
        // The hit's distance from the camera (the ray direction is unit), the quantity the previous
        // frame's texel is compared with.
        normal_distance: [normal.x, normal.y, normal.z, hit.t.max(f32::MIN_POSITIVE)],
        albedo: [c.x, c.y, c.z, 1.0],
    }
}

/// The mean base colour of the surface that the centre ray found (its `hit` and shading point
/// `surface`), over pixel (`x`, `y`): a
/// [`GBUFFER_ALBEDO_GRID`]² grid of camera rays through the pixel, each intersected with the hit's
/// triangle alone (no traversal) and its textures read at the level of its part of the pixel's ray
/// cone. Points off the triangle or in a cut-out's hole are left out; the centre's own albedo (read
/// at the whole footprint's mip level) where none is left. A point that something nearer hides still
/// counts: without a traversal it cannot be told, and at such a silhouette the pixel's samples mix two
/// surfaces that no one albedo stands for.
///
/// The pixel's samples average radiance over the pixel, so they saw this albedo on average. One read
/// at the centre, at the whole footprint's mip level, is a different filter: mip levels are box
/// filters aligned to the texture's grid, which blur a minified texture more than the pixel does and,
/// in an atlas, mix neighbouring tiles in at the surface's edges.
#[must_use]
pub fn footprint_albedo<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    frame: &FrameParams,
    hit: &Hit,
    surface: &SurfacePoint,
    x: u32,
    y: u32,
) -> Vec3 {
    let triangle = source.triangle(scene, hit.triangle);
    let material = source.material(scene, source.triangle_info(scene, hit.triangle).material);
    let cut_out_material = material.flags & MATERIAL_ALPHA_CUTOUT != 0;
    let k = GBUFFER_ALBEDO_GRID;
    // Each point's part of the footprint: 1/k of the pixel's, on the same triangle.
    let footprint_uv = surface.footprint_uv / k as f32;
    let (mut sum, mut count) = (Vec3::ZERO, 0u32);
    let mut i = 0;
    while i < k * k {
        let point = Vec2::new(
            x as f32 + ((i % k) as f32 + 0.5) / k as f32,
            y as f32 + ((i / k) as f32 + 0.5) / k as f32,
        );
        let ray = frame.camera.generate_ray(point, frame.width, frame.height);
        let on = WatertightRay::new(&ray).intersect(&triangle, INFINITE_DISTANCE);
        let hole = cut_out_material && is_cut_out(scene, source, hit.triangle, on.b1, on.b2);
        if on.hit && !hole {
            let uv = interpolate_uv(scene, source, hit.triangle, on.b1, on.b2);
            let b = [on.b1, on.b2];
            sum += base_color_at(scene, source, hit.triangle, &material, uv, b, footprint_uv);
            count += 1;
        }
        i += 1;
    }
    if count == 0 {
        return surface.params.base_color;
    }
    sum / count as f32
}
