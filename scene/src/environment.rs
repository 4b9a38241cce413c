//! Environment lighting: none, a constant radiance, or an equirectangular HDR map with the tables that
//! importance-sample it (`fovea_core::lights::environment` reads them).
use std::path::Path;

use fovea_core::lights::environment::uv_to_direction;
use fovea_core::math::color::luminance;
use glam::{Vec2, Vec3};

use crate::error::SceneError;
use crate::texture::TextureLimits;

/// Default decoding limits of environment maps: 16384 texels per side, 2 GiB.
pub const ENVIRONMENT_MAP_LIMITS: TextureLimits = TextureLimits {
    max_dimension: 16384,
    max_bytes: 2 << 30,
};

/// What lights the scene from infinitely far away.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Environment {
    /// Nothing: escaping rays see black.
    #[default]
    None,
    /// The same radiance from every direction (the paper's "sky").
    Constant([f32; 3]),
    /// An equirectangular map (row 0 at the top, `+y` up), multiplied by `scale`.
    Map {
        width: u32,
        height: u32,
        texels: Vec<[f32; 4]>,
        scale: [f32; 3],
    },
}

/// Sampling tables of an environment map: a marginal table over rows and one conditional table per row,
/// proportional to luminance × sin θ, and the integral that normalises them.
pub struct EnvironmentTables {
    pub marginal_cdf: Vec<f32>,
    pub conditional_cdf: Vec<f32>,
    pub integral: f32,
}

/// Builds a normalised cumulative table from non-negative weights (uniform when they sum to zero).
/// Returns the table (`weights.len() + 1` entries) and the weights' sum.
pub fn build_cdf(weights: &[f64]) -> (Vec<f32>, f64) {
    let total: f64 = weights.iter().map(|w| w.max(0.0)).sum();
    let n = weights.len().max(1);
    let mut cdf = Vec::with_capacity(n + 1);
    cdf.push(0.0f32);
    let mut acc = 0.0f64;
    for (i, w) in weights.iter().enumerate() {
        acc += if total > 0.0 {
            w.max(0.0) / total
        } else {
            1.0 / n as f64
        };
        cdf.push(if i + 1 == weights.len() {
            1.0
        } else {
            acc.min(1.0) as f32
        });
    }
    if weights.is_empty() {
        cdf.push(1.0);
    }
    (cdf, total)
}

impl EnvironmentTables {
    /// Tables for a `width` × `height` map.
    pub fn build(width: u32, height: u32, texels: &[[f32; 4]]) -> Self {
        let (w, h) = (width as usize, height as usize);
        let mut conditional = Vec::with_capacity(h * (w + 1));
        let mut row_weights = Vec::with_capacity(h);
        for y in 0..h {
            let sin_theta = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
            let weights: Vec<f64> = (0..w)
                .map(|x| {
                    let t = texels[y * w + x];
                    luminance(Vec3::new(t[0], t[1], t[2])).max(0.0) as f64 * sin_theta
                })
                .collect();
            let (cdf, sum) = build_cdf(&weights);
            conditional.extend_from_slice(&cdf);
            row_weights.push(sum);
        }
        let (marginal, total) = build_cdf(&row_weights);
        Self {
            marginal_cdf: marginal,
            conditional_cdf: conditional,
            integral: (total / (w * h) as f64) as f32,
        }
    }
}

impl Environment {
    /// Loads an equirectangular map in any format the `image` crate is built with here (Radiance `.hdr`,
    /// OpenEXR `.exr`; PNG, JPEG, TGA and BMP are read as linear values in [0, 1]), decoded under
    /// [`ENVIRONMENT_MAP_LIMITS`].
    pub fn load_map(path: &Path, scale: [f32; 3]) -> Result<Self, SceneError> {
        Self::load_map_with_limits(path, scale, &ENVIRONMENT_MAP_LIMITS)
    }

    /// [`Self::load_map`] with explicit decoding limits (the decoder's allocations and the RGBA32F result
    /// count against `limits.max_bytes`).
    pub fn load_map_with_limits(
        path: &Path,
        scale: [f32; 3],
        limits: &TextureLimits,
    ) -> Result<Self, SceneError> {
        let bytes = std::fs::read(path).map_err(|e| SceneError::from_io(path, e))?;
        let mut reader = image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
            .with_guessed_format()
            .map_err(|e| SceneError::from_io(path, e))?;
        if reader.format().is_none() {
            return Err(SceneError::Texture {
                path: path.to_path_buf(),
                message: "unknown or unsupported image format for an environment map".to_owned(),
            });
        }
        let mut l = image::Limits::default();
        l.max_image_width = Some(limits.max_dimension);
        l.max_image_height = Some(limits.max_dimension);
        l.max_alloc = Some(limits.max_bytes);
        reader.limits(l);
        let image = reader.decode().map_err(|e| match e {
            image::ImageError::Limits(e) => SceneError::TextureTooLarge {
                path: path.to_path_buf(),
                message: crate::texture::limits_message(&bytes, limits, &e.to_string()),
            },
            e => SceneError::Texture {
                path: path.to_path_buf(),
                message: e.to_string(),
            },
        })?;
        let (width, height) = (image.width(), image.height());
        let rgba32f_bytes = u64::from(width) * u64::from(height) * 16;
        if width == 0 || height == 0 {
            return Err(SceneError::Texture {
                path: path.to_path_buf(),
                message: format!("image is {width}x{height}"),
            });
        }
        if rgba32f_bytes > limits.max_bytes {
            return Err(SceneError::TextureTooLarge {
                path: path.to_path_buf(),
                message: format!(
                    "{width}x{height} needs {rgba32f_bytes} bytes as RGBA32F; the limit is {} bytes",
                    limits.max_bytes
                ),
            });
        }
        let image = image.into_rgba32f();
        let (width, height) = image.dimensions();
        let texels = image
            .pixels()
            .map(|p| {
                let c = |v: f32| if v.is_finite() { v.max(0.0) } else { 0.0 };
                [c(p[0]), c(p[1]), c(p[2]), 0.0]
            })
            .collect();
        Ok(Self::Map {
            width,
            height,
            texels,
            scale,
        })
    }

    /// Mean radiance over the sphere (for the light-selection power estimate).
    pub fn mean_radiance(&self) -> Vec3 {
        match self {
            Environment::None => Vec3::ZERO,
            Environment::Constant(c) => Vec3::from(*c),
            Environment::Map {
                width,
                height,
                texels,
                scale,
            } => {
                // Solid-angle weighted mean: rows weighted by sin θ.
                let (w, h) = (*width as usize, *height as usize);
                let mut sum = glam::DVec3::ZERO;
                let mut weight = 0.0f64;
                for y in 0..h {
                    let s = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
                    for x in 0..w {
                        let t = texels[y * w + x];
                        sum += glam::DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) * s;
                        weight += s;
                    }
                }
                let mean = if weight > 0.0 {
                    sum / weight
                } else {
                    glam::DVec3::ZERO
                };
                mean.as_vec3() * Vec3::from(*scale)
            }
        }
    }

    /// Direction of the brightest texel (handy for tests and for placing a sun).
    pub fn brightest_direction(&self) -> Vec3 {
        match self {
            Environment::Map {
                width,
                height,
                texels,
                ..
            } => {
                let (i, _) = texels
                    .iter()
                    .enumerate()
                    .fold((0, f32::MIN), |best, (i, t)| {
                        let l = luminance(Vec3::new(t[0], t[1], t[2]));
                        if l > best.1 {
                            (i, l)
                        } else {
                            best
                        }
                    });
                let (x, y) = (i as u32 % width, i as u32 / width);
                uv_to_direction(Vec2::new(
                    (x as f32 + 0.5) / *width as f32,
                    (y as f32 + 0.5) / *height as f32,
                ))
            }
            _ => Vec3::Y,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdf_is_normalised_and_handles_zero_weights() {
        let (cdf, total) = build_cdf(&[1.0, 0.0, 3.0]);
        assert_eq!(total, 4.0);
        assert_eq!(cdf, vec![0.0, 0.25, 0.25, 1.0]);
        let (cdf, _) = build_cdf(&[0.0, 0.0]);
        assert_eq!(cdf, vec![0.0, 0.5, 1.0]);
    }
}

#[cfg(test)]
mod sampling_tests {
    use super::*;
    use crate::pack::pack_scene;
    use fovea_core::lights::environment;
    use glam::Vec2;

    /// A small map with a bright spot, packed with one triangle so that a scene exists.
    fn packed_with_map() -> crate::pack::PackedScene {
        let (w, h) = (16u32, 8u32);
        let mut texels = vec![[0.1f32, 0.1, 0.1, 0.0]; (w * h) as usize];
        texels[(2 * w + 11) as usize] = [50.0, 40.0, 30.0, 0.0];
        texels[(6 * w + 3) as usize] = [0.0, 0.0, 0.0, 0.0];
        let loaded = crate::mesh::LoadedScene {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: Vec::new(),
            uvs: Vec::new(),
            tangents: Vec::new(),
            colors: Vec::new(),
            triangles: vec![[0, 1, 2]],
            triangle_materials: vec![0],
            materials: vec![fovea_core::scene::Material::default()],
            material_names: vec!["m".into()],
            textures: Vec::new(),
            punctual_lights: Vec::new(),
            camera: None,
            warnings: Vec::new(),
            unused: Vec::new(),
            origin: [0.0; 3],
        };
        let env = Environment::Map {
            width: w,
            height: h,
            texels,
            scale: [1.0; 3],
        };
        pack_scene(loaded, &env, &crate::bvh::BvhBuildOptions::default())
    }

    #[test]
    fn map_sampling_pdf_matches_lookup_and_integrates_to_one() {
        let packed = packed_with_map();
        let scene = packed.view();
        let mut state = 12345u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as f32 / 16_777_216.0
        };
        let mut bright = 0;
        let n = 20_000;
        for _ in 0..n {
            let s = environment::sample(&scene, Vec2::new(next(), next()));
            if s.pdf == 0.0 {
                continue;
            }
            let p = environment::pdf(&scene, s.direction);
            assert!(
                (p - s.pdf).abs() <= 1e-3 * s.pdf,
                "sampled pdf {} vs lookup {p}",
                s.pdf
            );
            if environment::radiance(&scene, s.direction).x > 10.0 {
                bright += 1;
            }
        }
        // The bright texel carries most of the luminance, so most samples go there.
        assert!(
            bright > n / 2,
            "{bright} of {n} samples hit the bright texel"
        );
        // ∫ pdf dω = 1, estimated with uniform sphere directions.
        let m = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..m {
            let d = fovea_core::sampling::warp::square_to_uniform_sphere(Vec2::new(next(), next()));
            sum += environment::pdf(&scene, d) as f64 * 4.0 * std::f64::consts::PI;
        }
        let integral = sum / m as f64;
        assert!(
            (integral - 1.0).abs() < 0.03,
            "pdf integrates to {integral}"
        );
        // A black texel is never sampled: its pdf is zero.
        let black = environment::uv_to_direction(Vec2::new(3.5 / 16.0, 6.5 / 8.0));
        assert_eq!(environment::pdf(&scene, black), 0.0);
    }
}

#[cfg(test)]
mod load_tests {
    use super::*;

    #[test]
    fn exr_and_hdr_maps_load_and_bad_ones_are_errors() {
        let dir = std::env::temp_dir().join(format!("fovea_env_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut img = image::Rgb32FImage::new(4, 2);
        img.put_pixel(1, 0, image::Rgb([8.0, 4.0, 2.0]));
        for name in ["m.exr", "m.hdr"] {
            let file = dir.join(name);
            image::DynamicImage::ImageRgb32F(img.clone())
                .save(&file)
                .unwrap();
            match Environment::load_map(&file, [1.0; 3]).unwrap_or_else(|e| panic!("{e}")) {
                Environment::Map {
                    width,
                    height,
                    texels,
                    ..
                } => {
                    assert_eq!((width, height), (4, 2));
                    assert!((texels[1][0] - 8.0).abs() < 0.1, "{name}: {:?}", texels[1]);
                }
                other => panic!("{other:?}"),
            }
        }
        let e = Environment::load_map(&dir.join("none.exr"), [1.0; 3]).unwrap_err();
        assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
        std::fs::write(dir.join("bad.hdr"), b"not an image").unwrap();
        let e = Environment::load_map(&dir.join("bad.hdr"), [1.0; 3]).unwrap_err();
        assert!(matches!(e, SceneError::Texture { .. }), "{e}");
        assert!(e.to_string().contains("bad.hdr"), "{e}");
        let small = TextureLimits {
            max_dimension: 2,
            max_bytes: 1 << 20,
        };
        let e =
            Environment::load_map_with_limits(&dir.join("m.exr"), [1.0; 3], &small).unwrap_err();
        assert!(matches!(e, SceneError::TextureTooLarge { .. }), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }
}
