//! The loaded, not yet packed scene.
//!
//! Both loaders ([`crate::gltf_loader`], [`crate::obj_loader`]) produce a [`LoadedScene`]: flat world-space
//! vertex arrays, indexed triangles with a material each, materials in `fovea_core`'s GPU layout, decoded
//! textures, punctual lights and an optional camera. [`load_scene`] picks the loader by file extension.
use std::path::{Path, PathBuf};

use fovea_core::scene::{Light, Material};
use glam::Vec3;

use crate::error::SceneError;
pub use crate::texture::Texture;
use crate::texture::TextureLimits;

/// A perspective camera found in the scene file (glTF only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// World-space eye position.
    pub position: [f32; 3],
    /// Unit viewing direction (the camera node's -Z in world space).
    pub forward: [f32; 3],
    /// Unit up direction (the camera node's +Y in world space).
    pub up: [f32; 3],
    /// Vertical field of view.
    pub yfov_radians: f32,
    /// Width / height, if the file gives one.
    pub aspect_ratio: Option<f32>,
}

/// How to load a scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadOptions {
    /// OBJ only: load this MTL file instead of the one(s) the OBJ names with `mtllib`.
    pub mtl_override: Option<PathBuf>,
    /// Largest accepted texture width/height (default 16384).
    pub max_texture_dimension: u32,
    /// Largest allocation an image decoder may make and largest RGBA8 texture, in bytes (default 1 GiB).
    pub max_texture_bytes: u64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        let limits = TextureLimits::default();
        Self {
            mtl_override: None,
            max_texture_dimension: limits.max_dimension,
            max_texture_bytes: limits.max_bytes,
        }
    }
}

impl LoadOptions {
    /// The texture decoding limits of these options.
    #[must_use]
    pub fn texture_limits(&self) -> TextureLimits {
        TextureLimits {
            max_dimension: self.max_texture_dimension,
            max_bytes: self.max_texture_bytes,
        }
    }
}

/// A scene as loaded from a file, before BVH construction and packing.
///
/// Invariants after a successful load: every triangle index is `< positions.len()`, every material index
/// is `< materials.len()`, `triangle_materials.len() == triangles.len()`, every position, normal and UV is
/// finite, `normals` and `uvs` are empty or as long as `positions`, non-zero normals are unit length, and
/// every texture index in a material is `< textures.len()` or `INVALID_INDEX`.
#[derive(Clone, Debug, Default)]
pub struct LoadedScene {
    /// Per vertex, world space.
    pub positions: Vec<[f32; 3]>,
    /// Per vertex (same length as `positions`) or empty if the file has none; `[0, 0, 0]` = "no normal here".
    pub normals: Vec<[f32; 3]>,
    /// Per vertex or empty; glTF convention, (0, 0) = top-left of the image (OBJ's v is flipped).
    pub uvs: Vec<[f32; 2]>,
    /// Vertex indices, counter-clockwise = front.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle, index into `materials`.
    pub triangle_materials: Vec<u32>,
    pub materials: Vec<Material>,
    /// Per material (same length as `materials`).
    pub material_names: Vec<String>,
    pub textures: Vec<Texture>,
    /// Lights of kind `LIGHT_POINT` / `LIGHT_SPOT` / `LIGHT_DIRECTIONAL`; `pmf` is left 0 (the packer sets
    /// it).
    pub punctual_lights: Vec<Light>,
    pub camera: Option<CameraDesc>,
    /// Human-readable problems that were worked around, each naming the file.
    pub warnings: Vec<String>,
}

impl LoadedScene {
    /// Number of triangles.
    #[inline]
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Axis-aligned bounds `(min, max)` of the vertices the triangles use; both zero for an empty scene.
    #[must_use]
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        if self.triangles.is_empty() {
            return ([0.0; 3], [0.0; 3]);
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &self.triangles {
            for &v in t {
                let p = Vec3::from(self.positions[v as usize]);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo.to_array(), hi.to_array())
    }

    /// Number of triangles whose material emits light.
    #[must_use]
    pub fn emissive_triangle_count(&self) -> usize {
        self.triangle_materials
            .iter()
            .filter(|&&m| self.materials[m as usize].is_emissive())
            .count()
    }

    /// Checks and repairs freshly loaded geometry (shared by both loaders); `file` names the scene in
    /// warnings and errors.
    ///
    /// - an index `>= positions.len()` or a material index `>= materials.len()` is an error;
    /// - triangles with a non-finite vertex position are removed (one warning with the count) and the
    ///   non-finite positions, now unused, are zeroed;
    /// - non-finite normals and UVs become zero (one warning each with the count); other normals are
    ///   normalised;
    /// - zero-area triangles are kept, but counted in a warning if they are emissive;
    /// - a scene without any triangle left is [`SceneError::Empty`].
    pub fn validate(&mut self, file: &Path) -> Result<(), SceneError> {
        let n = self.positions.len();
        let name = file.display();
        if self.triangle_materials.len() != self.triangles.len() {
            return Err(SceneError::InvalidAccessor {
                path: file.to_owned(),
                message: format!(
                    "{} triangles but {} triangle materials",
                    self.triangles.len(),
                    self.triangle_materials.len()
                ),
            });
        }
        if let Some((i, t)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
        {
            return Err(SceneError::FaceIndexOutOfRange {
                path: file.to_owned(),
                message: format!(
                    "triangle {i} uses vertices {t:?} but there are only {n} vertices"
                ),
            });
        }
        if let Some(&m) = self
            .triangle_materials
            .iter()
            .find(|&&m| m as usize >= self.materials.len())
        {
            return Err(SceneError::InvalidAccessor {
                path: file.to_owned(),
                message: format!(
                    "a triangle uses material {m} but there are only {}",
                    self.materials.len()
                ),
            });
        }
        if !self.normals.is_empty() && self.normals.len() != n {
            self.warnings.push(format!(
                "{name}: {} normals for {n} vertices; normals ignored",
                self.normals.len()
            ));
            self.normals.clear();
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            self.warnings.push(format!(
                "{name}: {} texture coordinates for {n} vertices; texture coordinates ignored",
                self.uvs.len()
            ));
            self.uvs.clear();
        }

        // Non-finite positions: drop the triangles that use them, then zero the (now unused) positions.
        let finite = |p: &[f32; 3]| p.iter().all(|c| c.is_finite());
        if !self.positions.iter().all(finite) {
            let before = self.triangles.len();
            let keep: Vec<bool> = self
                .triangles
                .iter()
                .map(|t| t.iter().all(|&v| finite(&self.positions[v as usize])))
                .collect();
            let mut flags = keep.iter();
            self.triangles.retain(|_| *flags.next().unwrap_or(&false));
            let mut flags = keep.iter();
            self.triangle_materials
                .retain(|_| *flags.next().unwrap_or(&false));
            let skipped = before - self.triangles.len();
            let bad_vertices = self.positions.iter().filter(|p| !finite(p)).count();
            for p in &mut self.positions {
                if !finite(p) {
                    *p = [0.0; 3];
                }
            }
            self.warnings.push(format!(
                "{name}: {bad_vertices} vertices with non-finite positions; {skipped} triangles using them skipped"
            ));
        }

        let mut bad_normals = 0usize;
        for nrm in &mut self.normals {
            let v = Vec3::from(*nrm);
            if !v.is_finite() {
                bad_normals += 1;
                *nrm = [0.0; 3];
            } else if v != Vec3::ZERO {
                let len = v.length();
                *nrm = if len > 0.0 && len.is_finite() {
                    (v / len).to_array()
                } else {
                    [0.0; 3]
                };
            }
        }
        if bad_normals > 0 {
            self.warnings.push(format!(
                "{name}: {bad_normals} non-finite normals replaced by zero (no normal)"
            ));
        }
        let mut bad_uvs = 0usize;
        for uv in &mut self.uvs {
            if !(uv[0].is_finite() && uv[1].is_finite()) {
                bad_uvs += 1;
                *uv = [0.0; 2];
            }
        }
        if bad_uvs > 0 {
            self.warnings.push(format!(
                "{name}: {bad_uvs} non-finite texture coordinates replaced by zero"
            ));
        }

        let degenerate_emissive = self
            .triangles
            .iter()
            .zip(&self.triangle_materials)
            .filter(|(t, &m)| {
                if !self.materials[m as usize].is_emissive() {
                    return false;
                }
                let p0 = Vec3::from(self.positions[t[0] as usize]);
                let p1 = Vec3::from(self.positions[t[1] as usize]);
                let p2 = Vec3::from(self.positions[t[2] as usize]);
                (p1 - p0).cross(p2 - p0).length_squared() == 0.0
            })
            .count();
        if degenerate_emissive > 0 {
            self.warnings.push(format!(
                "{name}: {degenerate_emissive} emissive triangles have zero area (they emit nothing)"
            ));
        }

        if self.triangles.is_empty() {
            return Err(SceneError::Empty {
                path: file.to_owned(),
            });
        }
        Ok(())
    }
}

/// Loads a scene file, choosing the loader by extension (case-insensitive): `.gltf` / `.glb` →
/// [`crate::gltf_loader::load_gltf`], `.obj` → [`crate::obj_loader::load_obj`].
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match extension.as_str() {
        "gltf" | "glb" => crate::gltf_loader::load_gltf(path, options),
        "obj" => crate::obj_loader::load_obj(path, options),
        _ => Err(SceneError::UnknownExtension {
            path: path.to_owned(),
            extension,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_scene() -> LoadedScene {
        LoadedScene {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            normals: vec![[0.0, 0.0, 2.0]; 4],
            uvs: vec![[0.0, 0.0]; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            triangle_materials: vec![0, 0],
            materials: vec![Material::default()],
            material_names: vec!["m".into()],
            ..Default::default()
        }
    }

    #[test]
    fn validate_keeps_good_scene_and_normalises() {
        let mut s = quad_scene();
        s.validate(Path::new("q.obj")).unwrap();
        assert_eq!(s.triangle_count(), 2);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(s.normals[0], [0.0, 0.0, 1.0]);
        assert_eq!(s.bounds(), ([0.0, 0.0, 0.0], [1.0, 1.0, 0.0]));
    }

    #[test]
    fn validate_skips_nan_triangles_and_zeroes_bad_attributes() {
        let mut s = quad_scene();
        s.positions[3] = [f32::NAN, 0.0, 0.0];
        s.normals[1] = [f32::INFINITY, 0.0, 0.0];
        s.uvs[2] = [f32::NAN, 0.5];
        s.validate(Path::new("q.obj")).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2]]);
        assert_eq!(s.triangle_materials, vec![0]);
        assert_eq!(s.positions[3], [0.0; 3]);
        assert_eq!(s.normals[1], [0.0; 3]);
        assert_eq!(s.uvs[2], [0.0; 2]);
        assert_eq!(s.warnings.len(), 3, "{:?}", s.warnings);
        assert!(s.warnings[0].contains("q.obj") && s.warnings[0].contains("1 triangles"));
    }

    #[test]
    fn validate_errors() {
        let mut s = quad_scene();
        s.triangles[1] = [0, 2, 4];
        let e = s.validate(Path::new("q.obj")).unwrap_err();
        assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
        let mut s = quad_scene();
        s.positions[0] = [f32::NAN; 3];
        let e = s.validate(Path::new("q.obj")).unwrap_err();
        assert!(matches!(e, SceneError::Empty { .. }), "{e}");
        assert!(e.to_string().contains("q.obj"));
    }

    #[test]
    fn degenerate_emissive_triangles_are_counted() {
        let mut s = quad_scene();
        s.materials[0].emission = [1.0, 1.0, 1.0, 0.0];
        s.triangles.push([0, 0, 1]);
        s.triangle_materials.push(0);
        s.validate(Path::new("q.obj")).unwrap();
        assert_eq!(s.triangle_count(), 3);
        assert_eq!(s.emissive_triangle_count(), 3);
        assert!(s
            .warnings
            .iter()
            .any(|w| w.contains("1 emissive triangles have zero area")));
    }

    #[test]
    fn unknown_extension_is_an_error() {
        let e = load_scene(Path::new("/tmp/scene.PLY"), &LoadOptions::default()).unwrap_err();
        match e {
            SceneError::UnknownExtension { extension, .. } => assert_eq!(extension, "ply"),
            other => panic!("{other}"),
        }
    }
}
