//! Emissive triangles: uniform area sampling converted to solid angle, and the emitted radiance seen along
//! a ray.
use glam::{Vec2, Vec3};

use crate::geometry::offset::{offset_ray_origin, triangle_magnitude};
use crate::geometry::triangle::{scaled_geometric_normal, triangle_vertices};
use crate::lights::sample::LightSample;
use crate::material::alpha::interpolate_uv;
use crate::material::texture::sample_texture;
use crate::math::vec3_from;
use crate::sampling::warp::square_to_uniform_triangle;
use crate::scene::features::{FEATURE_EMISSION_TEXTURE, FEATURE_EMISSIVE_TRIANGLES};
use crate::scene::{
    Features, SceneSource, SceneView, INVALID_INDEX, MATERIAL_DOUBLE_SIDED_EMISSION,
};

/// Radiance emitted by `triangle` at barycentrics (`b1`, `b2`) towards direction `w` (unit, pointing away
/// from the surface). Zero on the back face of one-sided emitters.
#[must_use]
pub fn emitted_radiance<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    b1: f32,
    b2: f32,
    w: Vec3,
    ng: Vec3,
) -> Vec3 {
    if !scene.features.has(FEATURE_EMISSIVE_TRIANGLES) {
        return Vec3::ZERO;
    }
    let material = &source.material(scene, source.triangle_info(scene, triangle).material);
    if !material.is_emissive() {
        return Vec3::ZERO;
    }
    if material.flags & MATERIAL_DOUBLE_SIDED_EMISSION == 0 && ng.dot(w) <= 0.0 {
        return Vec3::ZERO;
    }
    let mut radiance = vec3_from(material.emission);
    if scene.features.has(FEATURE_EMISSION_TEXTURE) && material.emission_texture != INVALID_INDEX {
        let uv = interpolate_uv(scene, source, triangle, b1, b2);
        radiance *= sample_texture(scene, source, material.emission_texture, uv).truncate();
    }
    radiance
}

/// Solid-angle density, without the light-selection probability, of sampling point `q` on `triangle`
/// from `p` by uniform area sampling: `|p - q|² / (|cos θ_q| · area)`.
#[inline]
#[must_use]
pub fn solid_angle_pdf<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    p: Vec3,
    q: Vec3,
) -> f32 {
    let v = triangle_vertices(scene, source, triangle);
    let n2 = scaled_geometric_normal(&v);
    let double_area = n2.length();
    let to_p = p - q;
    let dist2 = to_p.length_squared();
    // |cos θ_q| · area = |n2 · to_p| / (2 |to_p|).
    let cos_area = n2.dot(to_p).abs() * 0.5 / crate::math::float::sqrt(dist2);
    if !(double_area > 0.0) || !(cos_area > 0.0) {
        return 0.0;
    }
    dist2 / cos_area
}

/// Samples a point on `triangle` uniformly by area, as seen from `p`.
#[must_use]
pub fn sample<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    p: Vec3,
    u: Vec2,
) -> LightSample {
    let v = triangle_vertices(scene, source, triangle);
    let n2 = scaled_geometric_normal(&v);
    let b = square_to_uniform_triangle(u);
    let q = v[0] * (1.0 - b.x - b.y) + v[1] * b.x + v[2] * b.y;
    let to_p = p - q;
    let dist2 = to_p.length_squared();
    let double_area = n2.length();
    if !(dist2 > 0.0) || !(double_area > 0.0) {
        return LightSample::none();
    }
    let dist = crate::math::float::sqrt(dist2);
    let w = to_p / dist;
    let ng = n2 / double_area;
    let cos_q = ng.dot(w);
    let radiance = emitted_radiance(scene, source, triangle, b.x, b.y, w, ng);
    let cos_area = cos_q.abs() * 0.5 * double_area;
    if !(cos_area > 0.0) || radiance == Vec3::ZERO {
        return LightSample::none();
    }
    // Leave the light's surface on the side of p so the shadow ray can end exactly there.
    let side = if cos_q >= 0.0 { ng } else { -ng };
    LightSample {
        direction: -w,
        target: offset_ray_origin(q, side, triangle_magnitude(&v)),
        is_infinite: false,
        radiance,
        pdf: dist2 / cos_area,
        is_delta: false,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::math::pack_vec3;
    use crate::scene::{
        GeometryArrays, Material, MaterialArrays, SceneSlices, TriangleBlock, TriangleInfo,
        TrianglePositions,
    };
    use crate::test_support::chi2::{
        chi2_test, family_share, geometric, join, sample_count, uniform_cos, Grid,
    };
    use crate::test_support::one_triangle_per_block;
    use std::vec::Vec;

    /// A scene of one emissive triangle (front face towards +z for counter-clockwise `v`).
    fn scene<'a>(
        (blocks, triangle_lanes): &'a (Vec<TriangleBlock>, Vec<u32>),
        info: &'a [TriangleInfo],
        materials: &'a [Material],
    ) -> SceneView<'a> {
        SceneView {
            geometry: GeometryArrays {
                blocks,
                triangle_lanes,
                triangle_info: info,
                ..GeometryArrays::default()
            },
            materials: MaterialArrays {
                list: materials,
                ..MaterialArrays::default()
            },
            ..SceneView::empty()
        }
    }

    /// Where the ray from `p` along `w` meets the triangle `v` (f64 Möller-Trumbore), if it does, with
    /// barycentrics allowed `eps` outside [0, 1] (f32 rounding of directions to points on an edge).
    fn hit(v: &[Vec3; 3], p: Vec3, w: Vec3, eps: f64) -> Option<Vec3> {
        let f = |a: Vec3| [a.x as f64, a.y as f64, a.z as f64];
        let (a, b, c, o, d) = (f(v[0]), f(v[1]), f(v[2]), f(p), f(w));
        let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
        let cross = |x: [f64; 3], y: [f64; 3]| {
            [
                x[1] * y[2] - x[2] * y[1],
                x[2] * y[0] - x[0] * y[2],
                x[0] * y[1] - x[1] * y[0],
            ]
        };
        let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        let (e1, e2) = (sub(b, a), sub(c, a));
        let pv = cross(d, e2);
        let det = dot(e1, pv);
        if det.abs() < 1e-300 {
            return None;
        }
        let tv = sub(o, a);
        let u = dot(tv, pv) / det;
        let qv = cross(tv, e1);
        let vv = dot(d, qv) / det;
        let t = dot(e2, qv) / det;
        if u < -eps || vv < -eps || u + vv > 1.0 + eps || t <= 0.0 {
            return None;
        }
        Some(Vec3::new(
            (o[0] + t * d[0]) as f32,
            (o[1] + t * d[1]) as f32,
            (o[2] + t * d[2]) as f32,
        ))
    }

    /// Chi-square tests of triangle-light sampling (uniform by area, converted to solid angle) against
    /// `solid_angle_pdf` from a shading point: a large triangle seen obliquely from close by (the density
    /// varies by about 30x across it) and a small distant one (a narrow cone: rows geometric in θ' around
    /// the direction to its centroid). The three edges of the spherical triangle are clip planes, so
    /// the pdf is smooth on every quadrature piece and any sample outside is a hard failure. Also checks
    /// that each sample's pdf and radiance equal `solid_angle_pdf` and the emission for its direction
    /// (relative 1e-4: the test recomputes the hit point in f64 from the f32 direction).
    #[test]
    fn chi2_triangle_light() {
        let n = sample_count(1_000_000, 8_000_000);
        let pi = core::f64::consts::PI;
        let cases = [
            (
                "large oblique triangle",
                [
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(3.0, -0.5, 0.0),
                    Vec3::new(-0.5, 2.5, 0.0),
                ],
                Vec3::new(1.5, 1.2, 0.4),
            ),
            (
                "small distant triangle",
                [
                    Vec3::new(10.0, 0.0, 0.0),
                    Vec3::new(10.3, 0.1, 0.05),
                    Vec3::new(10.1, 0.25, 0.0),
                ],
                Vec3::new(0.0, 0.5, 3.0),
            ),
        ];
        // The family's "lights" part: these 2 cases and the 2 maps of the environment test.
        assert_eq!(family_share("lights"), cases.len() as u32 + 2);
        let mut max_rel = 0.0f32;
        for (k, (name, v, p)) in cases.into_iter().enumerate() {
            let tris = [TrianglePositions {
                v0: v[0].extend(0.0),
                v1: v[1].extend(0.0),
                v2: v[2].extend(0.0),
            }];
            let info = [TriangleInfo {
                vertices: [0, 1, 2],
                material: 0,
            }];
            let emission = Vec3::new(3.0, 2.0, 1.0);
            let mats = [Material {
                emission: pack_vec3(emission, 0.0),
                flags: crate::scene::MATERIAL_DOUBLE_SIDED_EMISSION,
                ..Material::default()
            }];
            let packed = one_triangle_per_block(&tris, &[]);
            let sc = scene(&packed, &info, &mats);
            let centroid = (v[0] + v[1] + v[2]) / 3.0;
            let axis = (centroid - p).normalize();
            // Half-angle of the cone around the axis that holds the triangle.
            let mut cone = 0.0f64;
            for vk in v {
                cone = cone.max(
                    ((vk - p).normalize().dot(axis) as f64)
                        .clamp(-1.0, 1.0)
                        .acos(),
                );
            }
            let edges = if cone < 0.2 {
                join(
                    geometric(cone / 200.0, cone * 1.05, 32, true),
                    uniform_cos(cone * 1.05, pi, 2),
                )
            } else {
                uniform_cos(0.0, pi, 64)
            };
            let mut grid = Grid::new(axis, edges, 64);
            for e in 0..3 {
                let (a, b) = (v[e] - p, v[(e + 1) % 3] - p);
                let nrm = a.cross(b);
                let inside = if nrm.dot(centroid - p) > 0.0 {
                    nrm
                } else {
                    -nrm
                };
                grid = grid.clip(inside);
            }
            chi2_test(
                &std::format!("triangle light: {name}"),
                &grid,
                n,
                77 + k as u64,
                |rng| {
                    let s = sample(
                        &sc,
                        &SceneSlices,
                        0,
                        p,
                        Vec2::new(rng.uniform(), rng.uniform()),
                    );
                    if s.pdf <= 0.0 {
                        return None;
                    }
                    let q = hit(&v, p, s.direction, 1e-5)
                        .expect("sampled direction misses the triangle");
                    let pdf = solid_angle_pdf(&sc, &SceneSlices, 0, p, q);
                    max_rel = max_rel.max((pdf - s.pdf).abs() / s.pdf);
                    assert_eq!(s.radiance, emission);
                    Some(s.direction)
                },
                |w| match hit(&v, p, w, 0.0) {
                    Some(q) => solid_angle_pdf(&sc, &SceneSlices, 0, p, q) as f64,
                    None => 0.0,
                },
            )
            .check();
        }
        std::println!(
            "triangle light: max relative difference of sample pdf vs solid_angle_pdf {max_rel:e}"
        );
        assert!(max_rel < 1e-4, "{max_rel}");
    }
}
