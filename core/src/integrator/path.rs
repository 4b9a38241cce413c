//! The per-sample path integrator (Kajiya 1986) with next-event estimation and BSDF sampling combined by
//! multiple importance sampling (Veach 1997, power heuristic).
//!
//! **What counts as a bounce.** A bounce is one scattering event at a surface. With `max_bounces = N`
//! a path has at most `N + 1` segments after the camera: camera → x₁ → … → x_{N+1}, where x_{N+1} only
//! contributes its emission (found by the BSDF-sampled ray from x_N, or by the light sample taken at x_N).
//! `max_bounces = 0` shows only emitters seen directly; the paper's "depth 3" is `max_bounces = 3`, the
//! same as Mitsuba's `max_depth = 4`. With Russian roulette off (the default) depth is exact.
//!
//! **Numerical guards.** GPU compilers may assume that no NaN or infinity occurs and fold NaN tests
//! away, so the estimate is kept finite by guarding the *inputs* of every risky operation rather than by
//! filtering results: every division is by a pdf tested `> 0` first (written `!(pdf > 0)` so a NaN
//! fails too), directions are normalised with fallbacks (`ggx_vndf::normalize_or_zero`,
//! `normalize_or`), cosines are tested against the shading and geometric normals before use, and MIS
//! weights are total ([`power_heuristic`]). The one remaining output guard is the final one at the end of
//! [`trace_path`]: a non-finite estimate becomes 0 and a finite one is capped at [`RADIANCE_LIMIT`]; it
//! is a bit test ([`is_finite3`]), which no compiler can fold away. `tests/tests/stability_*.rs` prove
//! that the guarded functions are finite without it, on the CPU and on the GPU
//! ([`INTEGRATOR_FLAG_NO_FINAL_GUARD`] switches it off).
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::bvh::{any_hit_with, closest_hit_with};
use crate::geometry::offset::{offset_ray_origin, SHADOW_RAY_T_MAX};
use crate::geometry::Ray;
use crate::lights::{
    environment, power_heuristic, sample_light, triangle::emitted_radiance,
    triangle::solid_angle_pdf, INFINITE_DISTANCE,
};
use crate::material::shading::surface_point_lod;
use crate::math::color::is_finite3;
use crate::math::Frame;
use crate::rng::SampleRng;
use crate::scene::features::{
    FEATURE_LOBE_TRANSMISSION, FEATURE_NORMAL_TEXTURE, FEATURE_VOLUME_ABSORPTION,
};
use crate::scene::{SceneSlices, SceneSource, SceneView, INVALID_INDEX};

/// [`IntegratorSettings::strategy`]: next-event estimation and BSDF sampling combined by MIS.
pub const STRATEGY_MIS: u32 = 0;
/// [`IntegratorSettings::strategy`]: next-event estimation alone (emitters hit by BSDF rays after the
/// first segment are ignored).
pub const STRATEGY_LIGHT_ONLY: u32 = 1;
/// [`IntegratorSettings::strategy`]: BSDF sampling alone (no shadow rays; delta lights are never found).
pub const STRATEGY_BSDF_ONLY: u32 = 2;

/// [`IntegratorSettings::flags`]: return the raw estimate, without the final guard of [`trace_path`]
/// (a diagnostic for the stability tests, which prove that the estimate is finite without it).
pub const INTEGRATOR_FLAG_NO_FINAL_GUARD: u32 = 1;

/// [`IntegratorSettings::texture_lod`]: every texture lookup reads mip level 0 (bilinear; the default).
pub const TEXTURE_LOD_OFF: u32 = 0;
/// [`IntegratorSettings::texture_lod`]: first hits read the level of their pixel's ray cone.
pub const TEXTURE_LOD_PIXEL: u32 = 1;
/// [`IntegratorSettings::texture_lod`]: first hits read the level of their *block's* ray cone, `s` times
/// a pixel's for an `s × s` block (see `crate::material::texture`).
pub const TEXTURE_LOD_BLOCK: u32 = 2;

/// Integrator settings (20 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct IntegratorSettings {
    /// Maximum number of bounces (see the module documentation); the paper uses 3.
    pub max_bounces: u32,
    /// Russian roulette starts at this bounce; 0 turns it off (the default).
    pub russian_roulette_start: u32,
    /// `STRATEGY_*`.
    pub strategy: u32,
    /// `INTEGRATOR_FLAG_*` bits; 0 by default.
    pub flags: u32,
    /// `TEXTURE_LOD_*`: which mip level a first hit's texture lookups read.
    pub texture_lod: u32,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            max_bounces: 3,
            russian_roulette_start: 0,
            strategy: STRATEGY_MIS,
            flags: 0,
            texture_lod: TEXTURE_LOD_OFF,
        }
    }
}

/// Largest radiance a single sample may return, a guard against overflow (not a clamp of fireflies:
/// real estimates stay far below it).
pub const RADIANCE_LIMIT: f32 = 1.0e30;

/// Traces one camera path and returns its radiance estimate.
#[must_use]
pub fn trace_path<F: crate::scene::Features>(
    scene: &SceneView<F>,
    camera_ray: Ray,
    rng: &mut SampleRng,
    settings: &IntegratorSettings,
) -> Vec3 {
    trace_path_with(scene, &SceneSlices, camera_ray, rng, settings)
}

/// [`trace_path`] reading the scene's large arrays from `source` (the GPU's texel buffer).
#[must_use]
pub fn trace_path_with<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    camera_ray: Ray,
    rng: &mut SampleRng,
    settings: &IntegratorSettings,
) -> Vec3 {
    trace_path_impl(scene, source, camera_ray, 0.0, None, rng, settings)
}

/// [`trace_path_with`] for a camera ray whose cone has spread angle `cone_spread` (radians; 0: no
/// texture level of detail), which picks the first hit's mip levels (`crate::material::texture`).
#[must_use]
pub fn trace_camera_path<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    camera_ray: Ray,
    cone_spread: f32,
    rng: &mut SampleRng,
    settings: &IntegratorSettings,
) -> Vec3 {
    trace_path_impl(scene, source, camera_ray, cone_spread, None, rng, settings)
}

/// [`trace_path_with`] given the camera ray's closest hit, `first_hit` (what
/// [`closest_hit_with`] returns for it; the CPU finds a block's first hits as one packet,
/// [`crate::bvh::packet`]).
#[must_use]
pub fn trace_path_from_hit<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    camera_ray: Ray,
    cone_spread: f32,
    first_hit: crate::bvh::Hit,
    rng: &mut SampleRng,
    settings: &IntegratorSettings,
) -> Vec3 {
    trace_path_impl(
        scene,
        source,
        camera_ray,
        cone_spread,
        Some(first_hit),
        rng,
        settings,
    )
}

/// Beer–Lambert transmittance `exp(−σₐ d)` of a segment of length `distance` inside a medium with
/// absorption coefficient `absorption` (glTF `KHR_materials_volume`). The path tracks one medium at a
/// time (entered by refracting through a front face, left through a back face), which holds for closed,
/// non-nested volumes; nested media would need a stack of interiors (pbrt-v4's `MediumInterface`), and a
/// camera inside a volume starts outside it.
#[inline]
#[must_use]
pub fn transmittance(absorption: Vec3, distance: f32) -> Vec3 {
    use crate::math::float::exp;
    Vec3::new(
        exp(-absorption.x * distance),
        exp(-absorption.y * distance),
        exp(-absorption.z * distance),
    )
}

/// Whether `triangle`'s material is unlit (`MATERIAL_UNLIT`, glTF `KHR_materials_unlit`): its emission is
/// its look, seen by camera rays only, so it neither lights the scene nor shows in reflections.
#[inline]
fn is_unlit<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
) -> bool {
    let material = source.material(scene, source.triangle_info(scene, triangle).material);
    material.flags & crate::scene::MATERIAL_UNLIT != 0
}

/// The path loop of [`trace_path_with`] and [`trace_path_from_hit`]: the camera ray's hit is traced at
/// the top of the first iteration unless `first_hit` gives it, so that the GPU kernel, which never
/// gives it, keeps a single inlined copy of the traversal (with a second one its SPIR-V grew from 668
/// to 721 kB and lavapipe frames were 6 % slower). Long because of that: one loop, one copy of the
/// traversal, the bounce's shading, light sampling and MIS inside it.
#[inline(always)]
fn trace_path_impl<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    camera_ray: Ray,
    cone_spread: f32,
    first_hit: Option<crate::bvh::Hit>,
    rng: &mut SampleRng,
    settings: &IntegratorSettings,
) -> Vec3 {
    let mis = settings.strategy == STRATEGY_MIS;
    let use_nee = settings.strategy != STRATEGY_BSDF_ONLY;
    let use_bsdf_hits = settings.strategy != STRATEGY_LIGHT_ONLY;

    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let mut ray = camera_ray;
    // Solid-angle pdf of the BSDF sample that produced `ray` (unused for the camera ray).
    let mut bsdf_pdf = 0.0f32;
    let mut bounce = 0u32;
    // The absorption coefficient of the volume the path is in (zero outside any): set when it refracts
    // into a front face of an absorbing material, cleared when it refracts out through a back face.
    let mut medium = Vec3::ZERO;
    loop {
        let hit = match first_hit {
            Some(hit) if bounce == 0 => hit,
            _ => closest_hit_with(scene, source, &ray, INFINITE_DISTANCE),
        };
        if !hit.is_hit() {
            let le = environment::radiance(scene, ray.direction);
            if bounce == 0 {
                radiance += throughput * le;
            } else if use_bsdf_hits && le != Vec3::ZERO {
                let mut weight = 1.0;
                if mis && scene.globals.environment_light != INVALID_INDEX {
                    let light_pdf = scene.lights.list[scene.globals.environment_light as usize].pmf
                        * environment::pdf(scene, ray.direction);
                    weight = power_heuristic(bsdf_pdf, light_pdf);
                }
                radiance += throughput * le * weight;
            }
            break;
        }

        // The camera ray's cone picks the first hit's mip levels; later hits read level 0.
        let cone_width = if bounce == 0 {
            cone_spread * hit.t
        } else {
            0.0
        };
        let surface = surface_point_lod(scene, source, &hit, ray.direction, cone_width);
        let wo_world = -ray.direction;
        if scene.features.has(FEATURE_VOLUME_ABSORPTION) && medium != Vec3::ZERO {
            // The segment ran inside an absorbing material.
            throughput *= transmittance(medium, hit.t * ray.direction.length());
        }

        // Emission found by this ray.
        let le = emitted_radiance(
            scene,
            source,
            hit.triangle,
            hit.b1,
            hit.b2,
            wo_world,
            surface.geometric_normal,
        );
        if le != Vec3::ZERO {
            if bounce == 0 {
                radiance += throughput * le;
            } else if use_bsdf_hits && !is_unlit(scene, source, hit.triangle) {
                let mut weight = 1.0;
                if mis && !scene.lights.triangle_light.is_empty() {
                    let light = scene.lights.triangle_light[hit.triangle as usize];
                    if light != INVALID_INDEX {
                        let light_pdf = scene.lights.list[light as usize].pmf
                            * solid_angle_pdf(
                                scene,
                                source,
                                hit.triangle,
                                ray.origin,
                                surface.position,
                            );
                        weight = power_heuristic(bsdf_pdf, light_pdf);
                    }
                }
                radiance += throughput * le * weight;
            }
        }

        if bounce >= settings.max_bounces {
            break;
        }

        // Two-sided shading: put both normals on the side the path arrives from (which, for a
        // transmissive material, says whether the path is outside or inside).
        let mut frame = surface.frame;
        let mut ng = surface.geometric_normal;
        let front = !(ng.dot(wo_world) < 0.0);
        if !front {
            ng = -ng;
            frame.x = -frame.x;
            frame.z = -frame.z;
        }
        let mut wo = frame.to_local(wo_world);
        if !(wo.z > 0.0) && scene.features.has(FEATURE_NORMAL_TEXTURE) {
            // A normal map turned the shading normal away from the viewer (at grazing views of
            // steep bumps): shade with the interpolated normal instead, losing the map's detail there
            // rather than the light.
            let n = surface.unmapped_normal;
            frame = Frame::from_normal_tangent(if front { n } else { -n }, frame.x);
            wo = frame.to_local(wo_world);
        }
        if !(wo.z > 0.0) {
            // The shading normal faces away from the viewer although the geometric one does not.
            break;
        }
        let bsdf = surface.params.at_wo_facing(scene.features, wo, front);
        let origin = offset_ray_origin(surface.position, ng, surface.magnitude);
        // A transmissive material also sends light through the surface: such rays leave from the
        // other side.
        let transmits = scene.features.has(FEATURE_LOBE_TRANSMISSION) && bsdf.transmits();
        let origin_below = if transmits {
            offset_ray_origin(surface.position, -ng, surface.magnitude)
        } else {
            origin
        };

        // Next-event estimation.
        if use_nee {
            let u_select = rng.next_1d();
            let u_light = rng.next_2d();
            let ls = sample_light(scene, source, surface.position, u_select, u_light);
            let light_below = !(ls.direction.dot(ng) > 0.0);
            if ls.pdf > 0.0 && (!light_below || transmits) {
                let wi = frame.to_local(ls.direction);
                let (f, pdf_b) = bsdf.eval_and_pdf(wi);
                // The shading frame must agree with the geometric side the light is on.
                let same_side = if light_below { wi.z < 0.0 } else { wi.z > 0.0 };
                if same_side && f != Vec3::ZERO {
                    let from = if light_below { origin_below } else { origin };
                    let shadow = if ls.is_infinite {
                        Ray::new(from, ls.direction)
                    } else {
                        Ray::new(from, ls.target - from)
                    };
                    let t_max = if ls.is_infinite {
                        INFINITE_DISTANCE
                    } else {
                        SHADOW_RAY_T_MAX
                    };
                    if !any_hit_with(scene, source, &shadow, t_max) {
                        let weight = if ls.is_delta || !mis {
                            1.0
                        } else {
                            power_heuristic(ls.pdf, pdf_b)
                        };
                        radiance += throughput * f * ls.radiance * (wi.z.abs() * weight / ls.pdf);
                    }
                }
            }
        } else {
            // Keep the random-number layout identical across strategies.
            let _ = rng.next_u32x4();
            let _ = rng.next_u32x4();
        }

        // BSDF sampling for the next segment.
        let s = bsdf.sample(rng.next_3d());
        if !(s.pdf > 0.0) {
            break;
        }
        let wi_world = frame.to_world(s.wi);
        // Refracted (below the shading surface: transmissive materials only) or reflected.
        let refracted = s.wi.z < 0.0;
        let leaks = if refracted {
            !(wi_world.dot(ng) < 0.0)
        } else {
            wi_world.dot(ng) <= 0.0
        };
        if leaks {
            // On the other geometric side than the shading one: the sample would leak.
            break;
        }
        // `s.pdf > 0` and `0 < |s.wi.z| <= 1` (unit), so the factor is finite unless the pdf is
        // denormal; no finiteness test here (see the module documentation, "Numerical guards").
        throughput *= s.f * (s.wi.z.abs() / s.pdf);
        if throughput == Vec3::ZERO {
            break;
        }
        bsdf_pdf = s.pdf;

        if settings.russian_roulette_start > 0 && bounce + 1 >= settings.russian_roulette_start {
            let survive = throughput.max_element().min(0.95);
            if rng.next_1d() >= survive {
                break;
            }
            throughput /= survive;
        }

        if scene.features.has(FEATURE_VOLUME_ABSORPTION) && refracted {
            medium = if front {
                surface.absorption
            } else {
                Vec3::ZERO
            };
        }
        ray = Ray::new(if refracted { origin_below } else { origin }, wi_world);
        bounce += 1;
    }
    if settings.flags & INTEGRATOR_FLAG_NO_FINAL_GUARD != 0 {
        radiance
    } else if is_finite3(radiance) {
        radiance.min(Vec3::splat(RADIANCE_LIMIT))
    } else {
        Vec3::ZERO
    }
}
