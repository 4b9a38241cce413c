//! The loaded, not yet packed scene.
//!
//! Both loaders ([`crate::gltf_loader`], [`crate::obj_loader`]) produce a [`LoadedScene`]: flat world-space
//! vertex arrays, indexed triangles with a material each, materials in `fovea_core`'s GPU layout, decoded
//! textures, punctual lights and an optional camera. [`crate::load::load_scene`] picks the loader by file extension.
use std::path::{Path, PathBuf};

use fovea_core::scene::{Light, Material, INVALID_INDEX};
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
    /// Most vertices a scene may have (default 2^28). Checked before the vertex arrays are allocated, so
    /// that a small file declaring a huge sparse glTF accessor cannot exhaust memory.
    pub max_vertices: u64,
    /// Most triangles a scene may have (default 2^28; the BVH needs fewer than 2^31).
    pub max_triangles: u64,
    /// OBJ only: the diffuse lobe of purely diffuse MTL materials (see [`MtlDiffuse`]).
    pub mtl_diffuse: MtlDiffuse,
}

/// How an OBJ scene's purely diffuse MTL materials reflect: those with `Ks 0 0 0` given explicitly and
/// none of the PBR keys `Pm`, `Pr`, `Ps`, `Pc`, `aniso`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MtlDiffuse {
    /// Burley's diffuse of the Disney BRDF, the paper's model (retro-reflective at grazing angles).
    #[default]
    Disney,
    /// Lambertian ([`fovea_core::scene::MATERIAL_LAMBERTIAN`]): what Mitsuba's and pbrt's `diffuse`
    /// material is, so that such a scene is the same scene to them.
    Lambert,
}

/// Default of [`LoadOptions::max_vertices`] and [`LoadOptions::max_triangles`].
pub const DEFAULT_MAX_ELEMENTS: u64 = 1 << 28;

impl Default for LoadOptions {
    fn default() -> Self {
        let limits = TextureLimits::default();
        Self {
            mtl_override: None,
            max_texture_dimension: limits.max_dimension,
            max_texture_bytes: limits.max_bytes,
            max_vertices: DEFAULT_MAX_ELEMENTS,
            max_triangles: DEFAULT_MAX_ELEMENTS,
            mtl_diffuse: MtlDiffuse::Disney,
        }
    }
}

impl LoadOptions {
    /// [`SceneError::TooLarge`] if `vertices` or `triangles` exceed the limits (or 32-bit vertex indices, or
    /// the BVH builder's [`crate::bvh::MAX_TRIANGLES`]).
    pub fn check_size(&self, file: &Path, vertices: u64, triangles: u64) -> Result<(), SceneError> {
        let max_vertices = self.max_vertices.min(u64::from(u32::MAX));
        let max_triangles = self.max_triangles.min(crate::bvh::MAX_TRIANGLES - 1);
        if vertices > max_vertices {
            return Err(SceneError::TooLarge {
                path: file.to_owned(),
                message: format!("{vertices} vertices; the limit is {max_vertices}"),
            });
        }
        if triangles > max_triangles {
            return Err(SceneError::TooLarge {
                path: file.to_owned(),
                message: format!("{triangles} triangles; the limit is {max_triangles}"),
            });
        }
        Ok(())
    }

    /// The texture decoding limits of these options.
    #[must_use]
    pub fn texture_limits(&self) -> TextureLimits {
        TextureLimits {
            max_dimension: self.max_texture_dimension,
            max_bytes: self.max_texture_bytes,
        }
    }
}

/// `tangent` (`xyz`, handedness `w`) with a unit `xyz` and a handedness of ±1, or `None` if its `xyz` is
/// zero or not finite, or its `w` not finite.
pub(crate) fn unit_tangent(tangent: [f32; 4]) -> Option<[f32; 4]> {
    let [x, y, z, w] = tangent;
    let v = Vec3::new(x, y, z);
    if !(v.is_finite() && v != Vec3::ZERO && w.is_finite()) {
        return None;
    }
    // Scaled first so that huge or tiny (finite) vectors do not overflow or underflow.
    let v = (v / v.abs().max_element()).normalize_or_zero();
    (v != Vec3::ZERO).then_some([v.x, v.y, v.z, if w < 0.0 { -1.0 } else { 1.0 }])
}

/// Clamps each channel of `colors` to `[0, 1]`, a NaN to 1 (no change to the colour it multiplies),
/// and returns how many colours had a channel outside.
pub(crate) fn clamp_colors(colors: &mut [[f32; 4]]) -> usize {
    let mut outside = 0;
    for color in colors {
        if !color.iter().all(|c| (0.0..=1.0).contains(c)) {
            outside += 1;
            *color = color.map(|c| if c.is_nan() { 1.0 } else { c.clamp(0.0, 1.0) });
        }
    }
    outside
}

/// A scene as loaded from a file, before BVH construction and packing.
///
/// Invariants after a successful load: every triangle index is `< positions.len()`, every material index
/// is `< materials.len()`, `triangle_materials.len() == triangles.len()`, every position, normal and UV is
/// finite, `normals`, `uvs`, `tangents` and `colors` are empty or as long as `positions`, non-zero
/// normals and tangents are unit length, colours are within `[0, 1]`, and
/// every texture index in a material is `< textures.len()` or `INVALID_INDEX`.
#[derive(Clone, Debug, Default)]
pub struct LoadedScene {
    /// The world position of this scene's origin: `positions`, the camera and the lights are relative
    /// to it, so that they stay small and precise in f32 wherever the scene sits ([`crate::rebase`]).
    /// Zero for a scene near the world origin.
    pub origin: [f64; 3],
    /// Per vertex, relative to `origin`.
    pub positions: Vec<[f32; 3]>,
    /// Per vertex (same length as `positions`) or empty if the file has none; `[0, 0, 0]` = "no normal here".
    pub normals: Vec<[f32; 3]>,
    /// Per vertex or empty; glTF convention, (0, 0) = top-left of the image (OBJ's v is flipped).
    pub uvs: Vec<[f32; 2]>,
    /// Per vertex or empty: unit tangent `xyz` and handedness `w` (±1, glTF `TANGENT`: the bitangent is
    /// `w · (n × t)`); `[0, 0, 0, 0]` = "no tangent here". The file's own, or MikkTSpace's for the
    /// normal-mapped and anisotropic triangles that lack one ([`crate::tangents`]).
    pub tangents: Vec<[f32; 4]>,
    /// Per vertex or empty: linear RGBA in `[0, 1]` that multiplies the base colour and its alpha
    /// (glTF `COLOR_0`, OBJ `v x y z r g b`; an RGB colour has alpha 1, a vertex without one is white).
    pub colors: Vec<[f32; 4]>,
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
    /// Values the file gives that fovea's mapping of its format does not use by design (OBJ's `Ka`,
    /// `illum`, ...: the loader's documentation), one line per file naming them and what is used
    /// instead: not problems, so not warnings, but never dropped without a word.
    pub unused: Vec<String>,
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
    /// - triangles using a vertex with a non-finite position, normal or texture coordinate are skipped
    ///   (one warning per kind with the counts) and those attributes, now unused, are zeroed; other
    ///   normals are normalised;
    /// - degenerate triangles (zero area, or an area that overflows `f32`) are skipped, with a warning
    ///   that counts them and how many of them were emitters;
    /// - non-finite or out-of-range material parameters are replaced by defaults, punctual lights with
    ///   non-finite or negative values are dropped, and an unusable camera is dropped (warnings);
    /// - a scene without any triangle left is [`SceneError::Empty`].
    ///
    /// Long because each check is one block over one array (positions, normals, texture coordinates,
    /// tangents, colours, triangles, materials, textures, lights, camera), in the order the
    /// documentation above lists them.
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
        if self.material_names.len() != self.materials.len() {
            self.material_names
                .resize(self.materials.len(), String::new());
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
        if !self.colors.is_empty() && self.colors.len() != n {
            self.warnings.push(format!(
                "{name}: {} vertex colours for {n} vertices; vertex colours ignored",
                self.colors.len()
            ));
            self.colors.clear();
        }
        // The loaders clamp the file's colours with a warning that names the mesh; this keeps the
        // invariant for scenes built in code.
        let outside = clamp_colors(&mut self.colors);
        if outside > 0 {
            self.warnings.push(format!(
                "{name}: {outside} vertex colours outside 0..1; clamped (NaN read as 1)"
            ));
        }
        if !self.tangents.is_empty() && self.tangents.len() != n {
            self.warnings.push(format!(
                "{name}: {} tangents for {n} vertices; tangents ignored (MikkTSpace's are used)",
                self.tangents.len()
            ));
            self.tangents.clear();
        }
        if self.normals.is_empty() {
            // glTF: without normals, tangents are ignored.
            self.tangents.clear();
        }
        // A tangent that is not finite or is zero is none (shading derives one); the rest are unit,
        // with a handedness of ±1.
        for t in &mut self.tangents {
            *t = unit_tangent(*t).unwrap_or([0.0; 4]);
        }
        self.sanitize_materials(file);
        self.sanitize_lights_and_camera(file);
        let total = self.triangles.len();

        // Per vertex: 0 = fine, 1 = non-finite position, 2 = normal, 3 = texture coordinate.
        let finite3 = |p: &[f32; 3]| p.iter().all(|c| c.is_finite());
        let mut bad = vec![0u8; n];
        let mut bad_vertices = [0usize; 4];
        for (i, flag) in bad.iter_mut().enumerate() {
            *flag = if !finite3(&self.positions[i]) {
                1
            } else if !self.normals.is_empty() && !finite3(&self.normals[i]) {
                2
            } else if !self.uvs.is_empty() && !self.uvs[i].iter().all(|c| c.is_finite()) {
                3
            } else {
                0
            };
            bad_vertices[*flag as usize] += 1;
        }
        let mut skipped = [0usize; 4];
        let mut degenerate = 0usize;
        let mut degenerate_emissive = 0usize;
        let mut keep = Vec::with_capacity(total);
        for (t, &m) in self.triangles.iter().zip(&self.triangle_materials) {
            // The worst (lowest non-zero) kind among the three vertices.
            let kind = t
                .iter()
                .map(|&v| bad[v as usize])
                .filter(|&k| k != 0)
                .min()
                .unwrap_or(0);
            if kind != 0 {
                skipped[kind as usize] += 1;
                keep.push(false);
                continue;
            }
            let p0 = Vec3::from(self.positions[t[0] as usize]);
            let p1 = Vec3::from(self.positions[t[1] as usize]);
            let p2 = Vec3::from(self.positions[t[2] as usize]);
            let cross = (p1 - p0).cross(p2 - p0);
            if cross == Vec3::ZERO || !cross.is_finite() {
                degenerate += 1;
                if self.materials[m as usize].is_emissive() {
                    degenerate_emissive += 1;
                }
                keep.push(false);
                continue;
            }
            keep.push(true);
        }
        if keep.iter().any(|&k| !k) {
            let mut flags = keep.iter();
            self.triangles.retain(|_| *flags.next().unwrap_or(&false));
            let mut flags = keep.iter();
            self.triangle_materials
                .retain(|_| *flags.next().unwrap_or(&false));
        }
        for (kind, what) in [(1, "positions"), (2, "normals"), (3, "texture coordinates")] {
            if bad_vertices[kind] > 0 {
                self.warnings.push(format!(
                    "{name}: {} vertices with non-finite {what}; {} triangles using them skipped",
                    bad_vertices[kind], skipped[kind]
                ));
            }
        }
        if degenerate > 0 {
            self.warnings.push(format!(
                "{name}: {degenerate} degenerate triangles (zero or non-finite area) skipped, \
                 {degenerate_emissive} of them emissive"
            ));
        }
        // Zero the non-finite attributes (no kept triangle uses them), normalise the rest.
        for (i, &flag) in bad.iter().enumerate() {
            if flag == 0 {
                continue;
            }
            if !finite3(&self.positions[i]) {
                self.positions[i] = [0.0; 3];
            }
            if let Some(nrm) = self.normals.get_mut(i) {
                if !finite3(nrm) {
                    *nrm = [0.0; 3];
                }
            }
            if let Some(uv) = self.uvs.get_mut(i) {
                if !uv.iter().all(|c| c.is_finite()) {
                    *uv = [0.0; 2];
                }
            }
        }
        for nrm in &mut self.normals {
            let v = Vec3::from(*nrm);
            if v != Vec3::ZERO {
                // Scale first so that huge or tiny (finite) normals do not overflow or underflow.
                let v = v / v.abs().max_element();
                let len = v.length();
                *nrm = if len > 0.0 && len.is_finite() {
                    (v / len).to_array()
                } else {
                    [0.0; 3]
                };
            }
        }

        if self.triangles.is_empty() {
            let detail = if total == 0 {
                String::new()
            } else {
                format!(
                    " (all {total} were skipped: {} with non-finite positions, {} normals, \
                     {} texture coordinates, {degenerate} degenerate)",
                    skipped[1], skipped[2], skipped[3]
                )
            };
            return Err(SceneError::Empty {
                path: file.to_owned(),
                detail,
            });
        }
        Ok(())
    }

    /// Drops the textures no material reads (the separate images an OBJ `map_Pr`/`map_Pm` pair or a
    /// `map_Bump` height map was converted from) and renumbers the materials' indices; returns how many
    /// were dropped.
    pub fn drop_unused_textures(&mut self) -> usize {
        let mut used = vec![false; self.textures.len()];
        for m in &mut self.materials {
            for index in m.texture_indices_mut() {
                if let Some(u) = used.get_mut(*index as usize) {
                    *u = true;
                }
            }
        }
        if used.iter().all(|&u| u) {
            return 0;
        }
        let mut renumbered = vec![INVALID_INDEX; self.textures.len()];
        let mut next = 0u32;
        for (r, &u) in renumbered.iter_mut().zip(&used) {
            if u {
                *r = next;
                next += 1;
            }
        }
        let mut keep = used.iter();
        self.textures.retain(|_| *keep.next().unwrap_or(&false));
        for m in &mut self.materials {
            for index in m.texture_indices_mut() {
                if let Some(&r) = renumbered.get(*index as usize) {
                    *index = r;
                }
            }
        }
        used.len() - self.textures.len()
    }

    /// Replaces non-finite material parameters by defaults and clamps the others to their ranges (one
    /// warning per material that needed it, naming each parameter's value and what replaced it).
    fn sanitize_materials(&mut self, file: &Path) {
        for (i, m) in self.materials.iter_mut().enumerate() {
            // (parameter, its value, what fovea used): the first of each parameter's channels.
            let mut fixed: Vec<(&str, f32, f32)> = Vec::new();
            let mut fix = |v: &mut f32, lo: f32, hi: f32, default: f32, what: &'static str| {
                let was = *v;
                if !v.is_finite() {
                    *v = default;
                } else if *v < lo || *v > hi {
                    *v = v.clamp(lo, hi);
                } else {
                    return;
                }
                if !fixed.iter().any(|f| f.0 == what) {
                    fixed.push((what, was, *v));
                }
            };
            for c in 0..3 {
                fix(&mut m.base_color[c], 0.0, f32::MAX, 0.8, "base colour");
                fix(&mut m.emission[c], 0.0, f32::MAX, 0.0, "emission");
            }
            fix(&mut m.base_color[3], 0.0, 1.0, 1.0, "opacity");
            fix(&mut m.metallic, 0.0, 1.0, 0.0, "metallic");
            fix(&mut m.roughness, 0.0, 1.0, 1.0, "roughness");
            fix(&mut m.anisotropic, 0.0, 1.0, 0.0, "anisotropic");
            // The renderer's range (`SPECULAR_MAX`: glTF's index of refraction reaches F0 = 1), not
            // Burley's 0..1, which undid `KHR_materials_ior` for indices above 1.78.
            fix(
                &mut m.specular,
                0.0,
                fovea_core::bsdf::disney::SPECULAR_MAX,
                0.5,
                "specular",
            );
            fix(&mut m.specular_tint, 0.0, 1.0, 0.0, "specular tint");
            fix(&mut m.sheen, 0.0, 1.0, 0.0, "sheen");
            fix(&mut m.sheen_tint, 0.0, 1.0, 0.0, "sheen tint");
            fix(&mut m.clearcoat, 0.0, 1.0, 0.0, "clearcoat");
            fix(&mut m.clearcoat_gloss, 0.0, 1.0, 0.0, "clearcoat gloss");
            fix(&mut m.alpha_cutoff, 0.0, 1.0, 0.5, "alpha cutoff");
            fix(&mut m.normal_scale, -1.0e6, 1.0e6, 1.0, "normal scale");
            fix(&mut m.transmission, 0.0, 1.0, 0.0, "transmission");
            if m.transmission > 0.0 {
                // The dielectric needs an index a little above 1 (`gltf_pbr`).
                fix(&mut m.ior, 1.01, 100.0, 1.5, "index of refraction");
            }
            for c in 0..3 {
                if m.absorption[c] == f32::INFINITY {
                    // Opaque: as much as f32 holds.
                    m.absorption[c] = f32::MAX;
                }
                fix(&mut m.absorption[c], 0.0, f32::MAX, 0.0, "absorption");
            }
            if !fixed.is_empty() {
                let label = self.material_names.get(i).map_or("", String::as_str);
                let list: Vec<String> = fixed
                    .iter()
                    .map(|(what, was, used)| format!("{what} {was} (used {used})"))
                    .collect();
                self.warnings.push(format!(
                    "{}: material {i} ({label:?}): invalid {}; replaced by defaults or clamped",
                    file.display(),
                    list.join(", ")
                ));
            }
        }
    }

    /// Drops punctual lights with non-finite or negative values and a camera with a non-finite pose or
    /// a field of view outside (0, 180) degrees (warnings).
    fn sanitize_lights_and_camera(&mut self, file: &Path) {
        let before = self.punctual_lights.len();
        self.punctual_lights.retain(|l| {
            let all = l
                .position
                .iter()
                .chain(&l.direction)
                .chain(&l.intensity)
                .all(|c| c.is_finite());
            all && l.intensity[..3].iter().all(|&c| c >= 0.0)
        });
        let dropped = before - self.punctual_lights.len();
        if dropped > 0 {
            self.warnings.push(format!(
                "{}: {dropped} lights with non-finite or negative values dropped",
                file.display()
            ));
        }
        if let Some(c) = &mut self.camera {
            let finite = c
                .position
                .iter()
                .chain(&c.forward)
                .chain(&c.up)
                .all(|v| v.is_finite());
            let fov_ok = c.yfov_radians > 0.0 && c.yfov_radians < std::f32::consts::PI;
            if !finite || !fov_ok || Vec3::from(c.forward) == Vec3::ZERO {
                self.warnings.push(format!(
                    "{}: the scene camera has a non-finite pose or a field of view outside (0, 180) \
                     degrees; ignored",
                    file.display()
                ));
                self.camera = None;
            } else if c.aspect_ratio.is_some_and(|a| !(a > 0.0 && a.is_finite())) {
                c.aspect_ratio = None;
            }
        }
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

    /// Two quads side by side: vertices 0-5, triangles 0-3.
    fn strip_scene() -> LoadedScene {
        let mut s = quad_scene();
        s.positions.extend([[2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]);
        s.normals.extend([[0.0, 0.0, 1.0]; 2]);
        s.uvs.extend([[0.0, 0.0]; 2]);
        s.triangles.extend([[1, 4, 5], [1, 5, 2]]);
        s.triangle_materials.extend([0, 0]);
        s
    }

    #[test]
    fn validate_skips_triangles_with_non_finite_attributes() {
        let mut s = strip_scene();
        s.positions[3] = [f32::NAN, 0.0, 0.0]; // triangle 1
        s.normals[4] = [f32::INFINITY, 0.0, 0.0]; // triangle 2
        s.uvs[5] = [0.5, f32::NEG_INFINITY]; // triangles 2 and 3 (2 is already counted for its normal)
        s.validate(Path::new("q.obj")).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2]]);
        assert_eq!(s.triangle_materials, vec![0]);
        assert_eq!(s.positions[3], [0.0; 3]);
        assert_eq!(s.normals[4], [0.0; 3]);
        assert_eq!(s.uvs[5], [0.0; 2]);
        assert_eq!(s.warnings.len(), 3, "{:?}", s.warnings);
        assert_eq!(
            s.warnings[0],
            "q.obj: 1 vertices with non-finite positions; 1 triangles using them skipped"
        );
        assert_eq!(
            s.warnings[1],
            "q.obj: 1 vertices with non-finite normals; 1 triangles using them skipped"
        );
        assert_eq!(
            s.warnings[2],
            "q.obj: 1 vertices with non-finite texture coordinates; 1 triangles using them skipped"
        );
        assert!(s
            .positions
            .iter()
            .chain(&s.normals)
            .all(|p| p.iter().all(|c| c.is_finite())));
    }

    #[test]
    fn validate_errors() {
        let mut s = quad_scene();
        s.triangles[1] = [0, 2, 4];
        let e = s.validate(Path::new("q.obj")).unwrap_err();
        assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
        let mut s = quad_scene();
        s.triangle_materials[0] = 1;
        let e = s.validate(Path::new("q.obj")).unwrap_err();
        assert!(e.to_string().contains("material 1"), "{e}");
        let mut s = quad_scene();
        s.positions[0] = [f32::NAN; 3];
        let e = s.validate(Path::new("q.obj")).unwrap_err();
        assert!(matches!(e, SceneError::Empty { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            "q.obj: the scene has no valid triangles (all 2 were skipped: 2 with non-finite \
             positions, 0 normals, 0 texture coordinates, 0 degenerate)"
        );
        let mut s = LoadedScene::default();
        let e = s.validate(Path::new("e.gltf")).unwrap_err();
        assert_eq!(e.to_string(), "e.gltf: the scene has no valid triangles");
    }

    #[test]
    fn degenerate_triangles_and_zero_area_emitters_are_skipped_and_counted() {
        let mut s = quad_scene();
        s.materials.push(Material {
            emission: [1.0, 1.0, 1.0, 0.0],
            ..Material::default()
        });
        s.material_names.push("light".into());
        // Repeated vertex, collinear vertices (an emitter), and an area that overflows f32.
        s.positions
            .extend([[2.0, 0.0, 0.0], [3e19, 0.0, 0.0], [0.0, 3e19, 0.0]]);
        s.normals.extend([[0.0, 0.0, 1.0]; 3]);
        s.uvs.extend([[0.0; 2]; 3]);
        s.triangles.extend([[0, 0, 1], [0, 1, 4], [0, 5, 6]]);
        s.triangle_materials.extend([0, 1, 0]);
        s.validate(Path::new("q.obj")).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(s.emissive_triangle_count(), 0);
        assert_eq!(
            s.warnings,
            vec![
                "q.obj: 3 degenerate triangles (zero or non-finite area) skipped, 1 of them emissive"
                    .to_owned()
            ]
        );
        // Only degenerate triangles: an empty scene that says why.
        let mut s = quad_scene();
        s.triangles = vec![[0, 0, 1]];
        s.triangle_materials = vec![0];
        let e = s.validate(Path::new("q.obj")).unwrap_err();
        assert!(e.to_string().contains("1 degenerate"), "{e}");
    }

    #[test]
    fn invalid_materials_lights_and_camera_are_repaired_or_dropped() {
        use fovea_core::scene::LIGHT_POINT;
        let mut s = quad_scene();
        s.materials[0].base_color = [f32::NAN, -1.0, 0.5, 2.0];
        s.materials[0].emission = [f32::INFINITY, 1.0, -3.0, 0.0];
        s.materials[0].roughness = 7.0;
        s.materials[0].transmission = 0.5;
        s.materials[0].ior = f32::NAN;
        s.materials[0].absorption = [1.0, -2.0, f32::NAN];
        s.punctual_lights = vec![
            Light {
                kind: LIGHT_POINT,
                intensity: [1.0, 1.0, 1.0, 0.0],
                ..Light::default()
            },
            Light {
                kind: LIGHT_POINT,
                position: [f32::NAN, 0.0, 0.0, 0.0],
                intensity: [1.0, 1.0, 1.0, 0.0],
                ..Light::default()
            },
            Light {
                kind: LIGHT_POINT,
                intensity: [-1.0, 1.0, 1.0, 0.0],
                ..Light::default()
            },
        ];
        s.camera = Some(CameraDesc {
            position: [0.0, 0.0, 5.0],
            forward: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            yfov_radians: 4.0,
            aspect_ratio: None,
        });
        s.validate(Path::new("q.obj")).unwrap();
        let m = &s.materials[0];
        assert_eq!(m.base_color, [0.8, 0.0, 0.5, 1.0]);
        assert_eq!(&m.emission[..3], &[0.0, 1.0, 0.0]);
        assert_eq!(m.roughness, 1.0);
        assert_eq!((m.transmission, m.ior), (0.5, 1.5));
        assert_eq!(m.absorption, [1.0, 0.0, 0.0]);
        assert_eq!(s.punctual_lights.len(), 1);
        assert!(s.camera.is_none());
        let all = s.warnings.join("\n");
        assert!(
            all.contains(
                "q.obj: material 0 (\"m\"): invalid base colour NaN (used 0.8), emission inf \
                 (used 0), opacity 2 (used 1), roughness 7 (used 1), index of refraction NaN (used \
                 1.5), absorption -2 (used 0)"
            ),
            "{all}"
        );
        assert!(
            all.contains("2 lights with non-finite or negative values dropped"),
            "{all}"
        );
        assert!(all.contains("camera"), "{all}");
    }

    #[test]
    fn size_limits_are_errors() {
        let options = LoadOptions {
            max_vertices: 10,
            max_triangles: 5,
            ..LoadOptions::default()
        };
        assert!(options.check_size(Path::new("a.obj"), 10, 5).is_ok());
        let e = options.check_size(Path::new("a.obj"), 11, 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.obj: scene too large: 11 vertices; the limit is 10"
        );
        let e = options.check_size(Path::new("a.obj"), 1, 6).unwrap_err();
        assert!(matches!(e, SceneError::TooLarge { .. }), "{e}");
    }
}
