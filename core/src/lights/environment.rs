//! The environment: light from infinitely far away, either a constant radiance or an equirectangular HDR
//! map importance-sampled by its luminance × sin θ (pbrt-v4 §12.5).
//!
//! Map convention: `+y` is up; texel row `v = θ / π` (θ from `+y`), column `u = (φ + π) / 2π` with
//! `φ = atan2(z, x)`; row 0 is the top of the image.
use glam::{Vec2, Vec3};

use crate::lights::sample::{LightSample, INFINITE_DISTANCE};
use crate::math::float::{atan2, cos, safe_sqrt, sin, INV_2PI, INV_PI, PI};
use crate::math::vec3_from;
use crate::sampling::distribution::{pdf_2d, sample_2d};
use crate::sampling::warp::{square_to_uniform_sphere, UNIFORM_SPHERE_PDF};
use crate::scene::features::{FEATURE_ENVIRONMENT_CONSTANT, FEATURE_ENVIRONMENT_MAP};
use crate::scene::{Features, SceneView, ENVIRONMENT_CONSTANT, ENVIRONMENT_MAP};

/// Map coordinates in [0, 1)² of unit direction `d`.
#[inline]
#[must_use]
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = (atan2(d.z, d.x) + PI) * INV_2PI;
    // atan2 rather than acos: acos(y) loses precision near the poles, where sin θ (the Jacobian) is small.
    let v = atan2(safe_sqrt(d.x * d.x + d.z * d.z), d.y) * INV_PI;
    Vec2::new(u.clamp(0.0, 0.999_999_9), v.clamp(0.0, 0.999_999_9))
}

/// Unit direction of map coordinates `uv` (inverse of [`direction_to_uv`]).
#[inline]
#[must_use]
pub fn uv_to_direction(uv: Vec2) -> Vec3 {
    let phi = uv.x * 2.0 * PI - PI;
    let theta = uv.y * PI;
    let s = sin(theta);
    Vec3::new(s * cos(phi), cos(theta), s * sin(phi))
}

/// Radiance arriving from direction `d` (unit, pointing away from the scene).
#[must_use]
pub fn radiance<F: Features>(scene: &SceneView<F>, d: Vec3) -> Vec3 {
    let g = &scene.globals;
    let scale = vec3_from(g.environment_radiance);
    if scene.features.has(FEATURE_ENVIRONMENT_CONSTANT)
        && g.environment_kind == ENVIRONMENT_CONSTANT
    {
        scale
    } else if scene.features.has(FEATURE_ENVIRONMENT_MAP) && g.environment_kind == ENVIRONMENT_MAP {
        let uv = direction_to_uv(d);
        let x = ((uv.x * g.environment_width as f32) as u32).min(g.environment_width - 1);
        let y = ((uv.y * g.environment_height as f32) as u32).min(g.environment_height - 1);
        let texel = scene.environment.texels[(y * g.environment_width + x) as usize];
        scale * Vec3::new(texel[0], texel[1], texel[2])
    } else {
        Vec3::ZERO
    }
}

/// Solid-angle density of [`sample`] for direction `d`, without the light-selection probability.
#[must_use]
pub fn pdf<F: Features>(scene: &SceneView<F>, d: Vec3) -> f32 {
    let g = &scene.globals;
    if scene.features.has(FEATURE_ENVIRONMENT_CONSTANT)
        && g.environment_kind == ENVIRONMENT_CONSTANT
    {
        UNIFORM_SPHERE_PDF
    } else if scene.features.has(FEATURE_ENVIRONMENT_MAP) && g.environment_kind == ENVIRONMENT_MAP {
        let uv = direction_to_uv(d);
        let sin_theta = sin(uv.y * PI);
        if !(sin_theta > 0.0) {
            return 0.0;
        }
        let p = pdf_2d(
            scene.environment.marginal_cdf,
            scene.environment.conditional_cdf,
            g.environment_width,
            g.environment_height,
            uv,
        );
        p / (2.0 * PI * PI * sin_theta)
    } else {
        0.0
    }
}

/// Samples a direction towards the environment (pdf without the light-selection probability).
#[must_use]
pub fn sample<F: Features>(scene: &SceneView<F>, u: Vec2) -> LightSample {
    let g = &scene.globals;
    let (direction, pdf) = if g.environment_kind == ENVIRONMENT_CONSTANT {
        (square_to_uniform_sphere(u), UNIFORM_SPHERE_PDF)
    } else if g.environment_kind == ENVIRONMENT_MAP {
        let s = sample_2d(
            scene.environment.marginal_cdf,
            scene.environment.conditional_cdf,
            g.environment_width,
            g.environment_height,
            u,
        );
        let sin_theta = sin(s.uv.y * PI);
        if !(sin_theta > 0.0) || !(s.pdf > 0.0) {
            return LightSample::none();
        }
        (uv_to_direction(s.uv), s.pdf / (2.0 * PI * PI * sin_theta))
    } else {
        return LightSample::none();
    };
    LightSample {
        direction,
        target: direction * INFINITE_DISTANCE,
        is_infinite: true,
        radiance: radiance(scene, direction),
        pdf,
        is_delta: false,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn uv_mapping_round_trips() {
        for &(u, v) in &[(0.1f32, 0.2f32), (0.5, 0.5), (0.9, 0.95), (0.25, 0.01)] {
            let uv = direction_to_uv(uv_to_direction(Vec2::new(u, v)));
            assert!((uv - Vec2::new(u, v)).length() < 1e-4, "{uv:?} vs {u} {v}");
        }
        assert!(direction_to_uv(Vec3::Y).y < 1e-6, "up is the top row");
    }

    /// Normalised cumulative table of non-negative weights (as the host's `EnvironmentTables` builds it).
    fn cdf(weights: &[f64]) -> (std::vec::Vec<f32>, f64) {
        let total: f64 = weights.iter().sum();
        let mut out = std::vec![0.0f32];
        let mut acc = 0.0;
        for (i, w) in weights.iter().enumerate() {
            acc += w / total;
            out.push(if i + 1 == weights.len() {
                1.0
            } else {
                acc as f32
            });
        }
        (out, total)
    }

    /// Chi-square tests of environment-map sampling against `pdf` for two small synthetic HDR maps:
    /// 32 × 16 with a smooth sky and a bright spot (2 × 2 texels at 500× the sky), and 24 × 12 with a
    /// spot next to the pole and a black band (whose cells must never receive a sample). The grid is
    /// the map's own (θ from +y, φ), each texel split 2 × 2, so the density (constant over a texel in
    /// (u, v), ∝ 1 / sin θ per solid angle) is tested inside texels, not only per texel. Also checks that
    /// each sample's pdf and radiance equal `pdf` and `radiance` at its direction, and that the pdf
    /// follows luminance × sin θ(texel centre) / sin θ.
    #[test]
    fn chi2_environment_map() {
        use crate::scene::{EnvironmentArrays, SceneGlobals, ENVIRONMENT_MAP};
        use crate::test_support::chi2::{chi2_test, family_share, sample_count, Grid};
        let n = sample_count(1_000_000, 8_000_000);
        let pi = core::f64::consts::PI;
        // (width, height, texel radiance)
        type Texel = fn(u32, u32, u32, u32) -> [f32; 4];
        let maps: [(&str, u32, u32, Texel); 2] = [
            ("sky with a bright spot", 32, 16, |x, y, _, h| {
                let sky = 0.2 + 0.8 * (1.0 - y as f32 / h as f32);
                if (20..22).contains(&x) && (5..7).contains(&y) {
                    [500.0, 450.0, 400.0, 0.0]
                } else {
                    [sky, sky * 1.1, sky * 1.3, 0.0]
                }
            }),
            ("spot at the pole, black band", 24, 12, |x, y, _, _| {
                if y == 0 && x == 3 {
                    [50.0, 50.0, 50.0, 0.0]
                } else if (7..9).contains(&y) {
                    [0.0; 4]
                } else {
                    [0.5 + 0.05 * x as f32, 0.5, 0.4, 0.0]
                }
            }),
        ];
        // The family's "lights" part: these 2 maps and the 2 cases of the triangle-light test.
        assert_eq!(family_share("lights"), maps.len() as u32 + 2);
        for (k, (name, w, h, texel)) in maps.into_iter().enumerate() {
            let texels: std::vec::Vec<[f32; 4]> =
                (0..w * h).map(|i| texel(i % w, i / w, w, h)).collect();
            let mut conditional = std::vec::Vec::new();
            let mut rows = std::vec::Vec::new();
            for y in 0..h {
                let sin_theta = ((y as f64 + 0.5) / h as f64 * pi).sin();
                let weights: std::vec::Vec<f64> = (0..w)
                    .map(|x| {
                        let t = texels[(y * w + x) as usize];
                        crate::math::color::luminance(Vec3::new(t[0], t[1], t[2])) as f64
                            * sin_theta
                    })
                    .collect();
                let total: f64 = weights.iter().sum();
                if total > 0.0 {
                    conditional.extend(cdf(&weights).0);
                } else {
                    conditional.extend(cdf(&std::vec![1.0; w as usize]).0);
                }
                rows.push(total);
            }
            let (marginal, total) = cdf(&rows);
            let scene = SceneView {
                features: crate::scene::FeatureFlags::ALL,
                globals: SceneGlobals {
                    environment_radiance: [1.0, 1.0, 1.0, 0.0],
                    environment_kind: ENVIRONMENT_MAP,
                    environment_width: w,
                    environment_height: h,
                    light_count: 1,
                    environment_integral: total as f32,
                    environment_light: 0,
                    ..SceneGlobals::default()
                },
                environment: EnvironmentArrays {
                    texels: &texels,
                    marginal_cdf: &marginal,
                    conditional_cdf: &conditional,
                },
                ..SceneView::empty()
            };
            // Rows: θ edges at half texels. Columns: the grid's φ' around +y is -φ of the map, and
            // both are cut at multiples of 2π / (2 w), so the columns split texels in half.
            let edges = (0..=2 * h)
                .map(|i| i as f64 / (2 * h) as f64 * pi)
                .collect();
            let grid = Grid::new(Vec3::Y, edges, 2 * w as usize);
            let (mut max_rel, mut mismatched) = (0.0f32, 0usize);
            chi2_test(
                &std::format!("environment map: {name}"),
                &grid,
                n,
                500 + k as u64,
                |rng| {
                    let s = sample(&scene, Vec2::new(rng.uniform(), rng.uniform()));
                    if s.pdf <= 0.0 {
                        return None;
                    }
                    let rel = (pdf(&scene, s.direction) - s.pdf).abs() / s.pdf;
                    // A direction on a texel edge may round into the neighbouring texel.
                    if rel > 1e-3 {
                        mismatched += 1;
                    } else {
                        max_rel = max_rel.max(rel);
                        assert_eq!(s.radiance, radiance(&scene, s.direction));
                    }
                    Some(s.direction)
                },
                |d| pdf(&scene, d) as f64,
            )
            .check();
            std::println!(
                "environment map {name}: sample pdf vs pdf(direction): max relative difference {max_rel:e}, \
                 {mismatched} of {n} samples rounded into a neighbouring texel"
            );
            assert!(
                max_rel < 1e-3 && mismatched * 10_000 <= n,
                "{max_rel} {mismatched}"
            );
            // pdf = luminance(texel) sin θ(centre) / (integral 2π² sin θ) at a few directions.
            for &(u, v) in &[(0.3f32, 0.4f32), (0.66, 0.35), (0.1, 0.9), (0.11, 0.03)] {
                let d = uv_to_direction(Vec2::new(u, v));
                let (x, y) = ((u * w as f32) as u32, (v * h as f32) as u32);
                let t = texels[(y * w + x) as usize];
                let lum = crate::math::color::luminance(Vec3::new(t[0], t[1], t[2])) as f64;
                let sin_c = ((y as f64 + 0.5) / h as f64 * pi).sin();
                let expect =
                    lum * sin_c / (total / (w * h) as f64 * 2.0 * pi * pi * (v as f64 * pi).sin());
                let got = pdf(&scene, d) as f64;
                assert!(
                    (got - expect).abs() <= 1e-3 * expect + 1e-9,
                    "{name} {u} {v}: {got} vs {expect}"
                );
            }
        }
    }
}
