//! OBJ/MTL loading.
//!
//! Geometry comes from tobj with `triangulate` (polygons become fans) and `single_index` (one index per
//! vertex for position, normal and UV). OBJ has no node hierarchy, cameras or punctual lights; positions
//! are taken as world space. Texture coordinates are converted to the glTF convention (v' = 1 - v, so that
//! (0, 0) is the top-left of the image). A face index that names no element (0, a relative index before
//! the first element, or one past the file's last) is an error naming its line, found in a pass of our
//! own before tobj parses the file (tobj 4.0.5 overflows on such indices; the pass adds about 20 ms to
//! Conference's 27 MB, 110 -> 132 ms of loading). Vertex colours written as `v x y z r g b` (a common
//! extension) multiply the base colour, like glTF's `COLOR_0`.
//!
//! Materials come from the MTL file(s) the OBJ names with `mtllib`, or only from
//! [`LoadOptions::mtl_override`] when that is set (e.g. Lost Empire's torch-emissive variant). Mapping
//! onto the Disney parameters of `fovea_core::scene::Material`:
//!
//! | MTL | fovea |
//! |---|---|
//! | `Kd` | `base_color` (linear RGB; default 0.8 grey) |
//! | `Ke` | `emission` (radiance) |
//! | `map_Kd` | `base_color_texture` (sRGB); the texture *replaces* `Kd` (factor 1), because exporters (e.g. the McGuire archive's Lost Empire) write the texture's average colour into `Kd` and multiplying would square it. If the file is missing, `Kd` is used |
//! | `map_d` | `alpha_texture` (opacity from the image's alpha channel, else, or if that alpha is 255 everywhere, its luminance; stored in A) with `MATERIAL_ALPHA_CUTOUT`, cutoff 0.5 |
//! | `d` < 1 without `map_d` | warning (no transparency support), kept opaque |
//! | `Pr` | `roughness` |
//! | no `Pr` | from the Phong exponent by the Beckmann-Phong correspondence (Walter et al. 2007): α = √(2 / (Ns + 2)), roughness = √α (GGX α = roughness²), clamped to [0, 1]; no `Ns`: 1 |
//! | `Pm` | `metallic` |
//! | no `Pm` | heuristic: metallic = lum(Ks) / (lum(Ks) + lum(Kd)) if lum(Ks) > 0, else 0; base colour = lerp(Kd, Ks, metallic). A mirror with Ks .95, Kd 0 becomes a metal of base colour .95 |
//! | `Ps`, `Pc`, `Pcr`, `aniso` | `sheen`, `clearcoat`, `clearcoat_gloss` = 1 - Pcr, `anisotropic` |
//! | `map_Ke` | `emission_texture` (sRGB), times `Ke` (1 if `Ke` is absent) |
//! | `map_Pr`, `map_Pm` | one `metallic_roughness_texture` built at load (G = the roughness map, B = the metallic map, as glTF packs them; the metallic map is resampled to the roughness map's size), times `Pr`/`Pm` (1 if absent) |
//! | `norm`, or `map_Bump`/`bump` | `normal_texture` (linear). A `map_Bump` image is taken for a tangent-space normal map when its mean colour is bluish-neutral (mean B > 0.6, R and G within 0.2 of 0.5); otherwise it holds heights and is converted to a normal map with its `-bm` multiplier ([`crate::bump`]) |
//! | `map_Ka`, `Ka`, `Ni`, `illum`, `Tf`, `Tr` | not used, and named per file in [`LoadedScene::unused`] (a `Tr` above 0 is warned about, as `d` below 1) |
//! | `Pm`, `Pr`, `Ps`, `Pc`, `Pcr`, `aniso` outside 0..1; a negative `Ke` | clamped, with a warning naming the value used |
//!
//! `specular` is 0.5 (an index of refraction of 1.5), except 0 when the material gives `Ks 0 0 0`
//! explicitly and no `Pm` (no specular reflection at all: a pure diffuse material, as Mitsuba's `diffuse`
//! for the same MTL); `specular_tint` is 0 for every material. Such a material that has none of the
//! PBR keys `Pm`, `Pr`, `Ps`, `Pc`, `aniso` either is *purely diffuse*: with [`LoadOptions::mtl_diffuse`]
//! [`MtlDiffuse::Lambert`] it gets `MATERIAL_LAMBERTIAN`, a Lambertian diffuse lobe instead of Burley's,
//! and is then the very BRDF of Mitsuba's `diffuse`. Faces without a (known) material get a
//! default grey diffuse material named `default`. Texture paths are relative to the MTL file; MTL texture
//! options (`-bm 1 file.png`) are skipped by taking the last token. Emission is single-sided (front face),
//! as OBJ has no double-sided flag.
use std::cell::RefCell;
use std::collections::HashMap;
use std::io::{Cursor, Read};
use std::path::{Path, PathBuf};

use fovea_core::scene::{Material, INVALID_INDEX, MATERIAL_ALPHA_CUTOUT, MATERIAL_LAMBERTIAN};
use glam::Vec3;
use rayon::prelude::*;

use crate::error::SceneError;
use crate::mesh::{LoadOptions, LoadedScene, MtlDiffuse};
use crate::source::{FileSource, Filesystem};
use crate::texture::{load_texture_from, Texture, TextureRole};

/// Rec. 709 luminance.
#[inline]
#[must_use]
fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Perceptual roughness from a Phong exponent: α = √(2 / (Ns + 2)) (Beckmann-Phong correspondence,
/// Walter et al. 2007, eq. 30), roughness = √α, clamped to [0, 1].
#[inline]
#[must_use]
pub fn roughness_from_phong_exponent(ns: f32) -> f32 {
    let alpha = (2.0 / (ns.max(0.0) + 2.0)).sqrt();
    alpha.sqrt().clamp(0.0, 1.0)
}

/// The material loader's bookkeeping: where each successfully read MTL lives and how many materials it
/// contributed (materials are appended in load order), plus warnings and the first parse error.
#[derive(Default)]
struct MtlLog {
    loaded: Vec<(PathBuf, usize)>,
    warnings: Vec<String>,
    error: Option<SceneError>,
    calls: usize,
}

/// Checks the colour statements (`Ka`, `Kd`, `Ks`, `Ke`) of an MTL file before tobj parses it: tobj
/// panics on fewer than three values. One value is the MTL shorthand for grey (`Kd 0.5` = `Kd 0.5 0.5
/// 0.5`) and is expanded; none or two values are an error naming the line.
fn check_mtl_colors(text: &str) -> Result<std::borrow::Cow<'_, str>, String> {
    let is_color = |t: &str| matches!(t, "Ka" | "Kd" | "Ks" | "Ke");
    let mut expanded: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let values: Vec<&str> = if is_color(key) {
            words.collect()
        } else {
            Vec::new()
        };
        let replacement = match values.len() {
            _ if !is_color(key) => None,
            0 | 2 => {
                return Err(format!(
                    "line {}: {key} needs 3 numbers (or 1 for grey), got {:?}",
                    i + 1,
                    line.trim()
                ))
            }
            1 => Some(format!("{key} {0} {0} {0}", values[0])),
            _ => None,
        };
        if replacement.is_some() && expanded.is_none() {
            // Copy the lines before this one on the first change.
            let mut out = String::with_capacity(text.len() + 64);
            for l in text.lines().take(i) {
                out.push_str(l);
                out.push('\n');
            }
            expanded = Some(out);
        }
        if let Some(out) = &mut expanded {
            out.push_str(replacement.as_deref().unwrap_or(line));
            out.push('\n');
        }
    }
    Ok(match expanded {
        Some(s) => std::borrow::Cow::Owned(s),
        None => std::borrow::Cow::Borrowed(text),
    })
}

/// Reads one MTL file for tobj, logging what happened.
fn read_mtl(source: &dyn FileSource, file: &Path, log: &RefCell<MtlLog>) -> tobj::MTLLoadResult {
    let result = match source.read(file) {
        Ok(bytes) => {
            // Not UTF-8 (e.g. Latin-1 names or comments): replace the odd bytes rather than fail.
            let text = String::from_utf8_lossy(&bytes);
            match check_mtl_colors(&text) {
                Ok(text) => tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes())),
                Err(message) => {
                    let mut log = log.borrow_mut();
                    if log.error.is_none() {
                        log.error = Some(SceneError::Mtl {
                            path: file.to_owned(),
                            message,
                        });
                    }
                    return Err(tobj::LoadError::MaterialParseError);
                }
            }
        }
        Err(e) => {
            log.borrow_mut().warnings.push(format!(
                "{}: material library not found or unreadable ({e}); default materials used",
                file.display()
            ));
            return Err(tobj::LoadError::OpenFileFailed);
        }
    };
    let mut log = log.borrow_mut();
    match &result {
        Ok((materials, _)) => log.loaded.push((file.to_owned(), materials.len())),
        Err(e) => {
            if log.error.is_none() {
                log.error = Some(SceneError::Mtl {
                    path: file.to_owned(),
                    message: e.to_string(),
                });
            }
        }
    }
    result
}

/// Loads an `.obj` file and its materials.
pub fn load_obj(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    load_obj_from(&Filesystem, path, options)
}

/// Loads an `.obj` file and its materials, reading the OBJ, its MTL libraries and textures from
/// `source` (paths as for [`load_obj`]: MTL files relative to the OBJ, textures relative to their MTL).
///
/// Long because it is the OBJ load in order (tobj's parse with the MTL log, the vertex arrays, the
/// faces with their index checks, the materials), each step reading the locals of the one before.
pub fn load_obj_from(
    source: &dyn FileSource,
    path: &Path,
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    let bytes = source
        .read(path)
        .map_err(|e| SceneError::from_io(path, e))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // `..Default::default()` keeps this compiling when tobj's optional `merging`/`reordering` features
    // (more fields) are enabled by another crate.
    #[allow(clippy::needless_update)]
    let load_options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let log = RefCell::new(MtlLog::default());
    // Not UTF-8 (e.g. Latin-1 names or comments): replace the odd bytes rather than fail.
    let text = match String::from_utf8_lossy(&bytes) {
        std::borrow::Cow::Borrowed(_) => String::from_utf8(bytes).unwrap_or_default(),
        std::borrow::Cow::Owned(s) => s,
    };
    // tobj resolves an out-of-range index to a huge one and then overflows computing its offset (a
    // panic in checked builds); such faces are refused here, before tobj sees them.
    if let Some((line, content, problem)) = find_bad_face_reference(&text) {
        return Err(SceneError::FaceIndexOutOfRange {
            path: path.to_owned(),
            message: format!("{problem} at line {line}: {content:?}"),
        });
    }
    // An explicitly requested MTL must exist (one that `mtllib` names is only a warning).
    if let Some(mtl) = &options.mtl_override {
        if let Err(e) = source.read(mtl) {
            return Err(SceneError::from_io(mtl, e));
        }
    }
    let parse = |text: &str| {
        let mut obj_reader = Cursor::new(text.as_bytes());
        match &options.mtl_override {
            Some(mtl) => {
                // Load the override exactly once, as if the OBJ began with `mtllib <override>`, and ignore the
                // OBJ's own `mtllib` lines.
                let mut reader = Cursor::new(&b"mtllib fovea-mtl-override\n"[..]).chain(obj_reader);
                tobj::load_obj_buf(&mut reader, &load_options, |_| {
                    let first = {
                        let mut l = log.borrow_mut();
                        l.calls += 1;
                        l.calls == 1
                    };
                    if first {
                        read_mtl(source, mtl, &log)
                    } else {
                        Ok((Vec::new(), Default::default()))
                    }
                })
            }
            None => tobj::load_obj_buf(&mut obj_reader, &load_options, |name| {
                let name = name.to_string_lossy().replace('\\', "/");
                if name.trim().is_empty() || name.ends_with('/') {
                    log.borrow_mut().warnings.push(format!(
                        "{}: `mtllib` without a file name ({name:?}); ignored",
                        path.display()
                    ));
                    return Err(tobj::LoadError::OpenFileFailed);
                }
                read_mtl(source, &dir.join(name), &log)
            }),
        }
    };
    let mut result = parse(&text);
    // tobj refuses a file whose `v` lines carry colours on only some vertices; such a file is read
    // again without them, with a warning, rather than refused.
    let mut colours_dropped = false;
    if matches!(result, Err(tobj::LoadError::FaceColorOutOfBounds)) {
        *log.borrow_mut() = MtlLog::default();
        result = parse(&without_vertex_colours(&text));
        colours_dropped = true;
    }
    let log = log.into_inner();
    let (models, materials) = result.map_err(|e| {
        // tobj does not say where; find the first line that fails the same way.
        let message = match locate_obj_error(&text, &e) {
            Some((line, content)) => format!("{e} at line {line}: {content:?}"),
            None => e.to_string(),
        };
        let path = path.to_owned();
        match e {
            tobj::LoadError::FaceVertexOutOfBounds
            | tobj::LoadError::FaceNormalOutOfBounds
            | tobj::LoadError::FaceTexCoordOutOfBounds
            | tobj::LoadError::FaceColorOutOfBounds => {
                SceneError::FaceIndexOutOfRange { path, message }
            }
            tobj::LoadError::ReadError => SceneError::Io { path, message },
            _ => SceneError::Obj { path, message },
        }
    })?;
    if let Some(e) = log.error {
        return Err(e);
    }
    let mut scene = LoadedScene {
        warnings: log.warnings,
        ..LoadedScene::default()
    };
    if colours_dropped {
        scene.warnings.push(format!(
            "{}: only some `v` lines have a vertex colour (`v x y z r g b`); all vertex colours ignored",
            path.display()
        ));
    }
    // tobj reports a failed library only when no material at all was loaded; the log has it already.
    let materials = materials.unwrap_or_default();

    // Which MTL file each material came from (for messages and relative texture paths).
    let mut material_files: Vec<PathBuf> = Vec::with_capacity(materials.len());
    for (file, count) in &log.loaded {
        material_files.extend(std::iter::repeat_n(file.clone(), *count));
    }
    material_files.resize(materials.len(), path.to_owned());

    convert_materials(source, &materials, &material_files, options, &mut scene)?;
    scene.unused = unused_mtl_values(&materials, &material_files);
    let default_material = scene.materials.len() as u32;
    let mut default_triangles = 0usize;

    // Geometry.
    let total_vertices: usize = models.iter().map(|m| m.mesh.positions.len() / 3).sum();
    let total_triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    options.check_size(path, total_vertices as u64, total_triangles as u64)?;
    let any_normals = models.iter().any(|m| !m.mesh.normals.is_empty());
    let any_uvs = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    // Vertex colours: the common extension `v x y z r g b` (MeshLab, ZBrush and others write it), read
    // as linear 0..1 RGB with alpha 1, as Mitsuba reads it.
    let any_colors = models.iter().any(|m| !m.mesh.vertex_color.is_empty());
    // Positions in f64 until the scene's origin is known (`crate::rebase`).
    let mut world_positions: Vec<[f64; 3]> = Vec::with_capacity(total_vertices);
    scene.triangles.reserve_exact(total_triangles);
    scene.triangle_materials.reserve_exact(total_triangles);
    if any_normals {
        scene.normals.reserve_exact(total_vertices);
    }
    if any_uvs {
        scene.uvs.reserve_exact(total_vertices);
    }
    if any_colors {
        scene.colors.reserve_exact(total_vertices);
    }
    let mut mismatched_normals = 0usize;
    let mut mismatched_uvs = 0usize;
    let mut mismatched_colors = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let base = world_positions.len() as u32;
        let n = mesh.positions.len() / 3;
        world_positions.extend(mesh.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        if any_normals {
            if mesh.normals.len() == 3 * n {
                scene.normals.extend(
                    mesh.normals
                        .chunks_exact(3)
                        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]),
                );
            } else {
                if !mesh.normals.is_empty() {
                    mismatched_normals += 1;
                }
                scene.normals.resize(world_positions.len(), [0.0; 3]);
            }
        }
        if any_uvs {
            if mesh.texcoords.len() == 2 * n {
                scene.uvs.extend(
                    mesh.texcoords
                        .chunks_exact(2)
                        .map(|t| [t[0] as f32, 1.0 - t[1] as f32]),
                );
            } else {
                if !mesh.texcoords.is_empty() {
                    mismatched_uvs += 1;
                }
                scene.uvs.resize(world_positions.len(), [0.0; 2]);
            }
        }
        if any_colors {
            if mesh.vertex_color.len() == 3 * n {
                scene.colors.extend(
                    mesh.vertex_color
                        .chunks_exact(3)
                        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]),
                );
            } else {
                if !mesh.vertex_color.is_empty() {
                    mismatched_colors += 1;
                }
                // An object without colours is white (no change to its base colour).
                scene.colors.resize(world_positions.len(), [1.0; 4]);
            }
        }
        let material = match mesh.material_id {
            Some(id) if id < materials.len() => id as u32,
            _ => {
                default_triangles += mesh.indices.len() / 3;
                default_material
            }
        };
        for t in mesh.indices.chunks_exact(3) {
            if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
                return Err(SceneError::FaceIndexOutOfRange {
                    path: path.to_owned(),
                    message: format!("object {:?} uses vertex {bad} of {n}", model.name),
                });
            }
            scene
                .triangles
                .push([base + t[0], base + t[1], base + t[2]]);
        }
        scene
            .triangle_materials
            .resize(scene.triangles.len(), material);
    }
    if mismatched_normals > 0 {
        scene.warnings.push(format!(
            "{}: {mismatched_normals} objects have normals on only some faces; their normals are ignored",
            path.display()
        ));
    }
    if mismatched_uvs > 0 {
        scene.warnings.push(format!(
            "{}: {mismatched_uvs} objects have texture coordinates on only some faces; they are ignored",
            path.display()
        ));
    }
    if mismatched_colors > 0 {
        scene.warnings.push(format!(
            "{}: {mismatched_colors} objects have vertex colours on only some vertices; their colours are ignored",
            path.display()
        ));
    }
    if any_colors {
        let first_outside = scene
            .colors
            .iter()
            .find(|c| !c.iter().all(|v| (0.0..=1.0).contains(v)))
            .copied();
        let outside = crate::mesh::clamp_colors(&mut scene.colors);
        if let Some(c) = first_outside {
            let hint = if c[..3].iter().all(|v| (0.0..=255.0).contains(v)) {
                " (fovea reads 0 to 1; this file may use 0 to 255)"
            } else {
                ""
            };
            scene.warnings.push(format!(
                "{}: {outside} vertex colours outside 0 to 1, clamped (the first: {} {} {}){hint}",
                path.display(),
                c[0],
                c[1],
                c[2]
            ));
        }
    }
    if default_triangles > 0 {
        scene.warnings.push(format!(
            "{}: {default_triangles} triangles have no material or an unknown one; default grey used",
            path.display()
        ));
        scene.materials.push(Material {
            base_color: [0.8, 0.8, 0.8, 1.0],
            roughness: 1.0,
            ..Material::default()
        });
        scene.material_names.push("default".to_owned());
    }
    scene.origin = crate::rebase::scene_origin(&world_positions, &scene.triangles);
    scene.positions = world_positions
        .iter()
        .map(|&p| crate::rebase::to_local(p, scene.origin))
        .collect();
    drop(world_positions);
    scene.validate(path)?;
    Ok(scene)
}

/// `text` with every `v` line cut to its position (`v x y z r g b` becomes `v x y z`); a `v` line with
/// fewer than six numbers (a position, or a position and `w`) is kept as it is.
fn without_vertex_colours(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        if words.next() == Some("v") {
            let numbers: Vec<&str> = words.collect();
            if numbers.len() >= 6 {
                out.push_str("v ");
                out.push_str(&numbers[..3].join(" "));
                out.push('\n');
                continue;
            }
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// The first face of an OBJ (its 1-based line, text, and what is wrong) whose vertex, texture coordinate or
/// normal index cannot name an element of the file: 0, a relative (negative) index reaching before the
/// first element defined so far, or an index beyond the last one in the file. (tobj itself takes forward
/// references within a group, so positive indices are checked against the whole file.) Indices that do
/// not parse are left to tobj, which reports a malformed face.
///
/// One pass over the lines (a second only to locate a too-large index).
fn find_bad_face_reference(text: &str) -> Option<(usize, String, String)> {
    let mut largest = [0i64; 3];
    let (first_bad, total) = scan_face_references(text, |k, x, defined_before| {
        largest[k] = largest[k].max(x);
        x == 0 || -x > defined_before
    });
    let found = match first_bad {
        Some(found) => found,
        // Only when some index is beyond the file: find its line.
        None if (0..3).any(|k| largest[k] > total[k]) => {
            scan_face_references(text, |k, x, _| x > total[k]).0?
        }
        None => return None,
    };
    let (line_number, line, k, x, defined_before) = found;
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let problem = if x == 0 {
        format!("{} index 0 (OBJ counts from 1)", KINDS[k])
    } else if x < 0 {
        format!(
            "relative {} index {x} with {defined_before} defined before it",
            KINDS[k]
        )
    } else {
        format!("{} index {x} with {} in the file", KINDS[k], total[k])
    };
    let mut content: String = line.trim().chars().take(80).collect();
    if line.trim().chars().count() > 80 {
        content.push_str("...");
    }
    Some((line_number, content, problem))
}

/// Which statement an OBJ line is: 0 `v`, 1 `vt`, 2 `vn`, 3 `f`, `None` for any other; with the rest
/// of the line after the keyword.
#[inline]
fn statement_kind(line: &[u8]) -> Option<(usize, &[u8])> {
    let start = line.iter().position(|b| !b.is_ascii_whitespace())?;
    let line = &line[start..];
    let end = line
        .iter()
        .position(u8::is_ascii_whitespace)
        .unwrap_or(line.len());
    let kind = match &line[..end] {
        b"v" => 0,
        b"vt" => 1,
        b"vn" => 2,
        b"f" => 3,
        _ => return None,
    };
    Some((kind, &line[end..]))
}

/// A face index [`scan_face_references`] stopped at: the 1-based line number, the line, the kind (0
/// vertex, 1 texture coordinate, 2 normal), the index and the count of that kind defined before the line.
type FaceReference<'a> = (usize, &'a str, usize, i64, i64);

/// Calls `bad(kind, index, defined_before)` for every integer index of every face and stops at the
/// first for which it is true; returns it (if any) with the counts of `v`, `vt` and `vn` statements
/// before it (the whole file's if none). Parts that are not integers are skipped (tobj reports them);
/// out-of-range integers saturate.
fn scan_face_references(
    text: &str,
    mut bad: impl FnMut(usize, i64, i64) -> bool,
) -> (Option<FaceReference<'_>>, [i64; 3]) {
    let mut so_far = [0i64; 3];
    for (i, line) in text.lines().enumerate() {
        match statement_kind(line.as_bytes()) {
            Some((k @ 0..=2, _)) => so_far[k] += 1,
            Some((_, vertices)) => {
                let mut indices = FaceIndices::default();
                // A trailing space ends the last part like the others.
                for &b in vertices.iter().chain(b" ") {
                    if let Some((k, x)) = indices.push(b) {
                        if bad(k, x, so_far[k]) {
                            return (Some((i + 1, line, k, x, so_far[k])), so_far);
                        }
                    }
                }
            }
            None => {}
        }
    }
    (None, so_far)
}

/// Reads the indices of a face's vertices (`v`, `v/vt`, `v//vn`, `v/vt/vn`) a byte at a time.
#[derive(Default)]
struct FaceIndices {
    /// Which index of the vertex the current part is (0 `v`, 1 `vt`, 2 `vn`; more is malformed).
    kind: usize,
    value: i64,
    negative: bool,
    digits: bool,
    /// The part has a byte that is neither a sign nor a digit (tobj reports it).
    malformed: bool,
}

impl FaceIndices {
    /// Takes the next byte; at the end of a part that is an integer (saturated to `i64`), returns its
    /// kind and value.
    #[inline]
    fn push(&mut self, b: u8) -> Option<(usize, i64)> {
        match b {
            b'0'..=b'9' => {
                self.value = self
                    .value
                    .saturating_mul(10)
                    .saturating_add(i64::from(b - b'0'));
                self.digits = true;
                None
            }
            b'-' if !self.digits && !self.negative => {
                self.negative = true;
                None
            }
            b'/' | b' ' | b'\t' | b'\r' => {
                let part = (self.digits && !self.malformed && self.kind < 3).then(|| {
                    let x = if self.negative {
                        -self.value
                    } else {
                        self.value
                    };
                    (self.kind, x)
                });
                let kind = if b == b'/' { self.kind + 1 } else { 0 };
                *self = Self {
                    kind,
                    ..Self::default()
                };
                part
            }
            _ => {
                self.malformed = true;
                None
            }
        }
    }
}

/// The first line (1-based, with its text) of an OBJ that tobj rejects with `error`, if it can be found
/// again: a `v`/`vt`/`vn` statement whose numbers do not parse, a face with a malformed vertex, or a
/// face referring to a vertex, texture coordinate or normal that is not (yet) defined.
fn locate_obj_error(text: &str, error: &tobj::LoadError) -> Option<(usize, String)> {
    use tobj::LoadError as E;
    let numbers_ok = |words: &[&str], counts: &[usize]| {
        counts.contains(&words.len()) && words.iter().all(|w| w.parse::<f32>().is_ok())
    };
    let mut counts = [0usize; 3]; // v, vt, vn defined so far
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let rest: Vec<&str> = words.collect();
        let bad = match key {
            "v" => {
                counts[0] += 1;
                matches!(error, E::PositionParseError | E::ColorParseError)
                    && !numbers_ok(&rest, &[3, 4, 6])
            }
            "vt" => {
                counts[1] += 1;
                matches!(error, E::TexcoordParseError)
                    && !(rest.len() >= 2 && rest[..2].iter().all(|w| w.parse::<f32>().is_ok()))
            }
            "vn" => {
                counts[2] += 1;
                matches!(error, E::NormalParseError)
                    && !numbers_ok(&rest[..rest.len().min(3)], &[3])
            }
            "f" | "l" => rest.iter().any(|vertex| {
                let parts: Vec<&str> = vertex.split('/').collect();
                if parts.len() > 3 {
                    return matches!(error, E::FaceParseError);
                }
                parts.iter().enumerate().any(|(k, p)| {
                    if p.is_empty() {
                        return false;
                    }
                    match p.parse::<i64>() {
                        Err(_) => matches!(error, E::FaceParseError),
                        Ok(x) => {
                            let n = counts[k] as i64;
                            let out = x == 0 || x > n || x < -n;
                            out && matches!(
                                (k, error),
                                (0, E::FaceVertexOutOfBounds | E::FaceColorOutOfBounds)
                                    | (1, E::FaceTexCoordOutOfBounds)
                                    | (2, E::FaceNormalOutOfBounds)
                            )
                        }
                    }
                })
            }),
            _ => false,
        };
        if bad {
            let mut content: String = line.trim().chars().take(80).collect();
            if line.trim().chars().count() > 80 {
                content.push_str("...");
            }
            return Some((i + 1, content));
        }
    }
    None
}

/// tobj's f64 colour (it is built with `use_f64` for the positions) as f32.
fn f64x3_to_f32(c: [f64; 3]) -> [f32; 3] {
    c.map(|v| v as f32)
}

/// The texture maps one MTL material names: indices into the decoded requests.
struct MaterialTextures {
    kd: Option<usize>,
    d: Option<usize>,
    ke: Option<usize>,
    /// The normal map, and whether it was given as such (`norm`) rather than as `map_Bump`.
    normal: Option<(usize, bool)>,
    roughness: Option<usize>,
    metallic: Option<usize>,
}

/// A material's key as text, if present (tobj keeps unknown keys as strings).
fn param_text<'a>(m: &'a tobj::Material, key: &str) -> Option<&'a String> {
    m.unknown_param.get(key)
}

/// The texture in `slot`, if it is one.
fn roughness_slot_texture(textures: &[Texture], slot: u32) -> Option<&Texture> {
    textures.get(slot as usize)
}

/// One glTF-style metallic-roughness texture (G = roughness, B = metallic, data) from separate OBJ
/// `map_Pr` and `map_Pm` images (their red channel; a missing one is 1, i.e. the factor alone). The
/// result has the roughness map's size (or the metallic map's, without one); the other is resampled to
/// it by nearest texel.
fn metallic_roughness_texture(roughness: Option<&Texture>, metallic: Option<&Texture>) -> Texture {
    let (width, height) = roughness
        .or(metallic)
        .map_or((1, 1), |t| (t.width, t.height));
    let red = |t: Option<&Texture>, x: u32, y: u32| -> u8 {
        t.map_or(255, |t| {
            let tx = (u64::from(x) * u64::from(t.width) / u64::from(width)) as usize;
            let ty = (u64::from(y) * u64::from(t.height) / u64::from(height)) as usize;
            t.texels[ty * t.width as usize + tx].to_le_bytes()[0]
        })
    };
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        for x in 0..width {
            texels.push(crate::texture::pack_rgba8([
                0,
                red(roughness, x, y),
                red(metallic, x, y),
                255,
            ]));
        }
    }
    let name = |t: Option<&Texture>| t.map_or("-".to_owned(), |t| t.name.clone());
    Texture::new(
        format!("{} + {}", name(roughness), name(metallic)),
        width,
        height,
        false,
        texels,
    )
}

/// Whether an image looks like a tangent-space normal map: mean blue above 0.6, red and green within
/// 0.2 of 0.5 (flat normals encode as (0.5, 0.5, 1)).
fn looks_like_normal_map(t: &Texture) -> bool {
    if t.texels.is_empty() {
        return false;
    }
    let mut sum = [0u64; 3];
    for &texel in &t.texels {
        let [r, g, b, _] = texel.to_le_bytes();
        sum[0] += u64::from(r);
        sum[1] += u64::from(g);
        sum[2] += u64::from(b);
    }
    let mean = sum.map(|v| v as f64 / (255.0 * t.texels.len() as f64));
    mean[2] > 0.6 && (mean[0] - 0.5).abs() < 0.2 && (mean[1] - 0.5).abs() < 0.2
}

/// Parses a numeric PBR-extension key (tobj keeps unknown keys as strings).
/// [`param`] for a value of 0..1 (`Pm`, `Pr`, `Ps`, `Pc`, `Pcr`, `aniso`): one outside is clamped,
/// with a warning naming what was used.
fn unit_param(
    m: &tobj::Material,
    key: &str,
    warnings: &mut Vec<String>,
    mtl: &Path,
) -> Option<f32> {
    let v = param(m, key, warnings, mtl)?;
    let used = v.clamp(0.0, 1.0);
    if used != v {
        warnings.push(format!(
            "{}: material {:?}: {key} {v} is outside 0..1 (used {used})",
            mtl.display(),
            m.name
        ));
    }
    Some(used)
}

/// The MTL statements fovea's mapping does not use (the module's table): per MTL file, each key and
/// how many materials give it, as one line per file for [`LoadedScene::unused`].
fn unused_mtl_values(materials: &[tobj::Material], files: &[PathBuf]) -> Vec<String> {
    const KEYS: [(&str, &str); 6] = [
        ("Ka", "no ambient term"),
        ("map_Ka", "no ambient term"),
        ("Ni", "the specular is 0.5, an index of refraction of 1.5"),
        ("illum", "every material is the Disney BSDF"),
        ("Tf", "no transmission"),
        ("Tr", "opaque"),
    ];
    let mut per_file: Vec<(PathBuf, [usize; 6])> = Vec::new();
    for (m, file) in materials.iter().zip(files) {
        let given = [
            m.ambient.is_some(),
            m.ambient_texture.is_some(),
            m.optical_density.is_some(),
            m.illumination_model.is_some(),
            m.unknown_param.contains_key("Tf"),
            m.unknown_param.contains_key("Tr"),
        ];
        if !given.contains(&true) {
            continue;
        }
        let counts = match per_file.iter_mut().find(|(f, _)| f == file) {
            Some((_, counts)) => counts,
            None => {
                per_file.push((file.clone(), [0; 6]));
                &mut per_file.last_mut().expect("just pushed").1
            }
        };
        for (count, g) in counts.iter_mut().zip(given) {
            *count += usize::from(g);
        }
    }
    per_file
        .into_iter()
        .map(|(file, counts)| {
            let keys: Vec<String> = KEYS
                .iter()
                .zip(counts)
                .filter(|(_, n)| *n > 0)
                .map(|((key, instead), n)| format!("{key} ({n} materials; {instead})"))
                .collect();
            format!("{}: not used: {}", file.display(), keys.join(", "))
        })
        .collect()
}

fn param(m: &tobj::Material, key: &str, warnings: &mut Vec<String>, mtl: &Path) -> Option<f32> {
    let text = m.unknown_param.get(key)?;
    match text
        .split_whitespace()
        .next()
        .and_then(|t| t.parse::<f32>().ok())
    {
        Some(v) if v.is_finite() => Some(v),
        _ => {
            warnings.push(format!(
                "{}: material {:?}: cannot parse {key} {text:?}; ignored",
                mtl.display(),
                m.name
            ));
            None
        }
    }
}

/// The file an MTL texture statement names: options (`-bm 1 x.png`) are skipped by taking the last token;
/// backslashes become slashes; relative paths are relative to the MTL file's directory.
fn texture_path(dir: &Path, statement: &str) -> PathBuf {
    let s = statement.trim();
    let name = if s.starts_with('-') {
        s.split_whitespace().last().unwrap_or(s)
    } else {
        s
    };
    dir.join(name.replace('\\', "/"))
}

/// Converts tobj materials (see the module table), decoding their textures in parallel.
///
/// Long because each MTL statement's mapping (the module's table) is a few lines of it, in the table's
/// order.
fn convert_materials(
    source: &dyn FileSource,
    materials: &[tobj::Material],
    mtl_files: &[PathBuf],
    options: &LoadOptions,
    scene: &mut LoadedScene,
) -> Result<(), SceneError> {
    // Unique texture requests first, so that shared atlases are decoded once and in parallel.
    let mut requests: Vec<(PathBuf, TextureRole)> = Vec::new();
    let mut request_index: HashMap<(PathBuf, TextureRole), usize> = HashMap::new();
    let mut request = |path: PathBuf, role: TextureRole| -> usize {
        *request_index
            .entry((path.clone(), role))
            .or_insert_with(|| {
                requests.push((path, role));
                requests.len() - 1
            })
    };
    let mut per_material: Vec<MaterialTextures> = Vec::with_capacity(materials.len());
    for (m, mtl) in materials.iter().zip(mtl_files) {
        let dir = mtl.parent().unwrap_or(Path::new(""));
        let mut data = |t: &str| request(texture_path(dir, t), TextureRole::Color { srgb: false });
        let normal = m
            .unknown_param
            .get("norm")
            .map(|t| (data(t), true))
            .or_else(|| m.normal_texture.as_deref().map(|t| (data(t), false)));
        let roughness = m.unknown_param.get("map_Pr").map(|t| data(t));
        let metallic = m.unknown_param.get("map_Pm").map(|t| data(t));
        let kd = m
            .diffuse_texture
            .as_deref()
            .map(|t| request(texture_path(dir, t), TextureRole::Color { srgb: true }));
        let d = m
            .dissolve_texture
            .as_deref()
            .map(|t| request(texture_path(dir, t), TextureRole::Opacity));
        let ke = m
            .unknown_param
            .get("map_Ke")
            .map(|t| request(texture_path(dir, t), TextureRole::Color { srgb: true }));
        per_material.push(MaterialTextures {
            kd,
            d,
            ke,
            normal,
            roughness,
            metallic,
        });
    }
    let limits = options.texture_limits();
    let decoded: Vec<Result<Texture, SceneError>> = requests
        .par_iter()
        .map(|(path, role)| load_texture_from(source, path, *role, &limits))
        .collect();
    let mut slots: Vec<u32> = Vec::with_capacity(decoded.len());
    let mut combined_slots: HashMap<(u32, u32), u32> = HashMap::new();
    // (height map slot, bump multiplier bits) → its normal map's slot.
    let mut bump_slots: HashMap<(u32, u32), u32> = HashMap::new();
    for (result, (path, _)) in decoded.into_iter().zip(&requests) {
        match result {
            Ok(t) => {
                scene.textures.push(t);
                slots.push((scene.textures.len() - 1) as u32);
            }
            Err(SceneError::MissingFile { .. }) => {
                scene.warnings.push(format!(
                    "{}: texture file not found; its materials fall back",
                    path.display()
                ));
                slots.push(INVALID_INDEX);
            }
            Err(e) => return Err(e),
        }
    }

    for ((m, mtl), maps) in materials.iter().zip(mtl_files).zip(per_material) {
        let MaterialTextures {
            kd: kd_tex,
            d: d_tex,
            ke: ke_tex,
            normal,
            roughness: roughness_tex,
            metallic: metallic_tex,
        } = maps;
        let mtl_name = mtl.display();
        let mut warnings = Vec::new();
        let kd = m.diffuse.map_or([0.8; 3], f64x3_to_f32);
        let ks = m.specular.map_or([0.0; 3], f64x3_to_f32);
        // `Ks 0 0 0` given explicitly (and no PBR `Pm`): the material has no specular reflection.
        let no_specular = m.specular == Some([0.0; 3]) && m.unknown_param.get("Pm").is_none();
        let base_texture = kd_tex.map_or(INVALID_INDEX, |i| slots[i]);
        let alpha_texture = d_tex.map_or(INVALID_INDEX, |i| slots[i]);
        let pm = unit_param(m, "Pm", &mut warnings, mtl);
        let (metallic, base) = match pm {
            Some(pm) => (pm, Vec3::from(kd)),
            None => {
                let (ls, ld) = (luminance(ks), luminance(kd));
                let metallic = if ls > 0.0 {
                    ls / (ls + ld.max(0.0))
                } else {
                    0.0
                };
                (metallic, Vec3::from(kd).lerp(Vec3::from(ks), metallic))
            }
        };
        let base = if base_texture != INVALID_INDEX {
            Vec3::ONE
        } else {
            base
        };
        let roughness = match unit_param(m, "Pr", &mut warnings, mtl) {
            Some(r) => r,
            None => m
                .shininess
                .map_or(1.0, |n| roughness_from_phong_exponent(n as f32)),
        };
        let e = m.emissive.map_or([0.0; 3], f64x3_to_f32);
        if e.iter().any(|&c| c < 0.0) {
            warnings.push(format!(
                "{mtl_name}: material {:?}: Ke {e:?} has negative components (used 0 for them)",
                m.name
            ));
        }
        let mut out = Material {
            base_color: [base.x, base.y, base.z, 1.0],
            emission: [e[0].max(0.0), e[1].max(0.0), e[2].max(0.0), 0.0],
            metallic,
            roughness,
            specular: if no_specular { 0.0 } else { 0.5 },
            base_color_texture: base_texture,
            ..Material::default()
        };
        if let Some(v) = unit_param(m, "Ps", &mut warnings, mtl) {
            out.sheen = v;
        }
        if let Some(v) = unit_param(m, "Pc", &mut warnings, mtl) {
            out.clearcoat = v;
        }
        if let Some(v) = unit_param(m, "Pcr", &mut warnings, mtl) {
            out.clearcoat_gloss = 1.0 - v;
        }
        if let Some(v) = unit_param(m, "aniso", &mut warnings, mtl) {
            out.anisotropic = v;
        }
        let pbr_keys = ["Pm", "Pr", "Ps", "Pc", "aniso", "map_Pm", "map_Pr", "norm"];
        let purely_diffuse =
            no_specular && !pbr_keys.iter().any(|k| m.unknown_param.contains_key(*k));
        if purely_diffuse && options.mtl_diffuse == MtlDiffuse::Lambert {
            out.flags |= MATERIAL_LAMBERTIAN;
        }
        let dissolve = m.dissolve.map_or(1.0, |d| d as f32);
        if alpha_texture != INVALID_INDEX {
            out.flags |= MATERIAL_ALPHA_CUTOUT;
            out.alpha_cutoff = 0.5;
            out.alpha_texture = alpha_texture;
            out.base_color[3] = if dissolve > 0.0 {
                dissolve.min(1.0)
            } else {
                1.0
            };
        } else if m.dissolve_texture.is_some() {
            warnings.push(format!(
                "{mtl_name}: material {:?}: map_d texture missing; kept opaque",
                m.name
            ));
        } else if dissolve < 1.0 {
            warnings.push(format!(
                "{mtl_name}: material {:?} has d {dissolve} (transparency is not supported); kept opaque",
                m.name
            ));
        } else if let Some(tr) = param(m, "Tr", &mut warnings, mtl).filter(|&tr| tr > 0.0) {
            warnings.push(format!(
                "{mtl_name}: material {:?} has Tr {tr} (transparency is not supported); kept opaque",
                m.name
            ));
        }
        // Emission, roughness/metallic and normal maps.
        if let Some(slot) = ke_tex.map(|i| slots[i]).filter(|&s| s != INVALID_INDEX) {
            out.emission_texture = slot;
            if m.emissive.is_none() {
                out.emission = [1.0, 1.0, 1.0, 0.0];
            }
        }
        let roughness_slot = roughness_tex.map_or(INVALID_INDEX, |i| slots[i]);
        let metallic_slot = metallic_tex.map_or(INVALID_INDEX, |i| slots[i]);
        if roughness_slot != INVALID_INDEX || metallic_slot != INVALID_INDEX {
            let key = (roughness_slot, metallic_slot);
            let slot = match combined_slots.get(&key) {
                Some(&slot) => slot,
                None => {
                    let combined = metallic_roughness_texture(
                        roughness_slot_texture(&scene.textures, roughness_slot),
                        roughness_slot_texture(&scene.textures, metallic_slot),
                    );
                    scene.textures.push(combined);
                    let slot = (scene.textures.len() - 1) as u32;
                    combined_slots.insert(key, slot);
                    slot
                }
            };
            out.metallic_roughness_texture = slot;
            if roughness_slot != INVALID_INDEX && param_text(m, "Pr").is_none() {
                out.roughness = 1.0;
            }
            if metallic_slot != INVALID_INDEX && param_text(m, "Pm").is_none() {
                out.metallic = 1.0;
                out.base_color = [kd[0], kd[1], kd[2], out.base_color[3]];
                if base_texture != INVALID_INDEX {
                    out.base_color = [1.0, 1.0, 1.0, out.base_color[3]];
                }
            }
        }
        if let Some((i, explicit)) = normal {
            let slot = slots[i];
            if slot != INVALID_INDEX {
                if explicit || looks_like_normal_map(&scene.textures[slot as usize]) {
                    out.normal_texture = slot;
                } else {
                    // A height map: converted to a normal map once per image and multiplier.
                    let statement = m.normal_texture.as_deref().unwrap_or("");
                    let strength = crate::bump::bump_multiplier(statement).unwrap_or_else(|| {
                        warnings.push(format!(
                            "{mtl_name}: material {:?}: cannot parse the -bm of {statement:?}; 1 is used",
                            m.name
                        ));
                        1.0
                    });
                    let key = (slot, strength.to_bits());
                    out.normal_texture = match bump_slots.get(&key) {
                        Some(&converted) => converted,
                        None => {
                            let normals = crate::bump::normal_map_from_heights(
                                &scene.textures[slot as usize],
                                strength,
                            );
                            scene.textures.push(normals);
                            let converted = (scene.textures.len() - 1) as u32;
                            bump_slots.insert(key, converted);
                            converted
                        }
                    };
                }
            }
        }
        scene.warnings.extend(warnings);
        scene.materials.push(out);
        scene.material_names.push(m.name.clone());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_scene;
    use fovea_core::scene::MATERIAL_DOUBLE_SIDED_EMISSION;

    /// The scenes the repository bundles.
    fn scenes() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets")
    }

    fn load_with(rel: &str, options: &LoadOptions) -> LoadedScene {
        load_scene(&scenes().join(rel), options).unwrap_or_else(|e| panic!("{e}"))
    }

    fn load(rel: &str) -> LoadedScene {
        load_with(rel, &LoadOptions::default())
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fovea_obj_test_{}_{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// `v x y z r g b` colours are read per vertex (alpha 1); values outside 0 to 1 are clamped with one
    /// warning that suspects 0-255 files; a file with colours on only some vertices is read without
    /// them; and a scene without any colour keeps none.
    #[test]
    fn vertex_colours_are_read_from_the_v_lines() {
        let dir = temp_dir("vertex_colors");
        let file = dir.join("c.obj");
        std::fs::write(
            &file,
            "o a\nv 0 0 0 1 0 0\nv 1 0 0 0 0.5 0\nv 0 1 0 0 0 255\nf 1 2 3\n\
             o b\nv 0 0 1 1 1 1\nv 1 0 1 1 1 1\nv 0 1 1 0.25 0.25 0.25\nf 4 5 6\n",
        )
        .unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert_eq!(s.colors.len(), s.positions.len());
        let colour_at = |p: [f32; 3]| {
            let v = s.positions.iter().position(|&q| q == p).unwrap();
            s.colors[v]
        };
        assert_eq!(colour_at([0.0, 0.0, 0.0]), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(colour_at([1.0, 0.0, 0.0]), [0.0, 0.5, 0.0, 1.0]);
        assert_eq!(colour_at([0.0, 1.0, 0.0]), [0.0, 0.0, 1.0, 1.0]);
        assert_eq!(colour_at([1.0, 0.0, 1.0]), [1.0; 4]);
        assert_eq!(colour_at([0.0, 1.0, 1.0]), [0.25, 0.25, 0.25, 1.0]);
        let clamped: Vec<&String> = s
            .warnings
            .iter()
            .filter(|w| w.contains("1 vertex colours outside 0 to 1, clamped (the first: 0 0 255)"))
            .collect();
        assert_eq!(clamped.len(), 1, "{:?}", s.warnings);
        assert!(clamped[0].contains("may use 0 to 255"), "{clamped:?}");
        // Colours on only some vertices (which tobj refuses): read without colours, with a warning.
        std::fs::write(
            &file,
            "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0\nf 1 2 3\nv 0 0 1 0.5 0.5 0.5\nf 1 2 4\n",
        )
        .unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert!(s.colors.is_empty());
        assert_eq!(s.triangles.len(), 2);
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("only some `v` lines have a vertex colour")),
            "{:?}",
            s.warnings
        );
        std::fs::write(&file, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert!(s.colors.is_empty());
        std::fs::remove_dir_all(dir).ok();
    }

    /// Every numeric MTL value fovea maps, loaded with a whole OBJ: inside its range it reaches the
    /// material unchanged and without a word; outside, the warning names the value used; the
    /// statements the mapping does not use are named in `unused`, not dropped silently.
    #[test]
    fn every_mtl_value_arrives_or_is_named() {
        use crate::load::load_scene_from;
        use crate::source::MemoryFiles;
        let load = |mtl: &str| {
            let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
            let files = MemoryFiles::new()
                .with("d/s.obj", obj)
                .with("d/m.mtl", format!("newmtl m\nKd 0.5 0.5 0.5\n{mtl}\n"));
            load_scene_from(&files, Path::new("d/s.obj"), &LoadOptions::default()).unwrap()
        };
        type Field = fn(&Material) -> f32;
        let fields: [(&str, Field); 6] = [
            ("Pm", |m| m.metallic),
            ("Pr", |m| m.roughness),
            ("Ps", |m| m.sheen),
            ("Pc", |m| m.clearcoat),
            ("Pcr", |m| 1.0 - m.clearcoat_gloss),
            ("aniso", |m| m.anisotropic),
        ];
        for (key, field) in fields {
            for v in [0.0f32, 0.3, 1.0] {
                let s = load(&format!("{key} {v}"));
                assert!(s.warnings.is_empty(), "{key} {v}: {:?}", s.warnings);
                let got = field(material(&s, "m"));
                assert!((got - v).abs() < 1e-6, "{key} {v} arrived as {got}");
            }
            for (v, used) in [(-1.0f32, 0.0f32), (2.0, 1.0)] {
                let s = load(&format!("{key} {v}"));
                assert_eq!(s.warnings.len(), 1, "{key} {v}: {:?}", s.warnings);
                assert!(
                    s.warnings[0].contains(&format!("{key} {v} is outside 0..1 (used {used})")),
                    "{:?}",
                    s.warnings
                );
                assert_eq!(field(material(&s, "m")), used);
            }
        }
        let s = load("Ke 2 -1 0.5");
        assert_eq!(&material(&s, "m").emission[..3], &[2.0, 0.0, 0.5]);
        assert!(
            s.warnings.len() == 1 && s.warnings[0].contains("negative components"),
            "{:?}",
            s.warnings
        );
        let s = load("Tr 0.4");
        assert!(
            s.warnings.len() == 1 && s.warnings[0].contains("Tr 0.4 (transparency"),
            "{:?}",
            s.warnings
        );
        let s = load("Ka 0.1 0.1 0.1\nNi 1.45\nillum 2\nTf 1 1 1");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(s.unused.len(), 1, "{:?}", s.unused);
        for key in ["Ka (1 materials", "Ni (1 materials", "illum (1", "Tf (1"] {
            assert!(s.unused[0].contains(key), "{key}: {:?}", s.unused);
        }
        assert!(load("Pm 0.5").unused.is_empty());
    }

    fn material<'a>(s: &'a LoadedScene, name: &str) -> &'a Material {
        let i = s
            .material_names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no {name}"));
        &s.materials[i]
    }

    #[test]
    fn phong_roughness() {
        assert_eq!(roughness_from_phong_exponent(0.0), 1.0);
        let r = roughness_from_phong_exponent(1000.0);
        assert!((r * r - (2.0f32 / 1002.0).sqrt()).abs() < 1e-6);
        assert!(roughness_from_phong_exponent(1e9) < 0.01);
    }

    #[test]
    fn cornell_box_original_obj() {
        let s = load("cornell_box/CornellBox-Original.obj");
        assert_eq!(s.triangle_count(), 36);
        let light = material(&s, "light");
        assert_eq!(&light.emission[..3], &[17.0, 12.0, 4.0]);
        assert_eq!(light.flags & MATERIAL_DOUBLE_SIDED_EMISSION, 0);
        assert_eq!(s.emissive_triangle_count(), 2);
        // The light quad faces down with counter-clockwise winding.
        let (t, _) = s
            .triangles
            .iter()
            .zip(&s.triangle_materials)
            .find(|(_, &m)| s.materials[m as usize].is_emissive())
            .unwrap();
        let p = t.map(|v| Vec3::from(s.positions[v as usize]));
        assert!((p[1] - p[0]).cross(p[2] - p[0]).y < 0.0);
        assert!(s.camera.is_none() && s.punctual_lights.is_empty());
        assert_eq!(s.materials.len(), s.material_names.len());
        assert!(!s.material_names.iter().any(|n| n == "default"));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        let (lo, hi) = s.bounds();
        assert!(lo[1] >= -0.01 && hi[1] <= 2.0);
    }

    #[test]
    fn cornell_stiff_obj_mirror_heuristic() {
        let s = load("cornell_stiff/cornell_stiff.obj");
        assert_eq!(s.triangle_count(), 36);
        let light = s.materials.iter().find(|m| m.is_emissive()).unwrap();
        assert_eq!(&light.emission[..3], &[1700.0, 1200.0, 400.0]);
        // Mirror: Ks .95, Kd .01 -> metallic .95 / .96, base colour ~ .95; Ns 10000 -> very smooth.
        let mirror = material(&s, "tallBox");
        assert!(
            (mirror.metallic - 0.95 / 0.96).abs() < 1e-3,
            "{}",
            mirror.metallic
        );
        let expected = 0.01 + (0.95 - 0.01) * mirror.metallic;
        assert!(
            (mirror.base_color[0] - expected).abs() < 1e-5,
            "{:?}",
            mirror.base_color
        );
        assert!(mirror.base_color[0] > 0.93);
        assert!((mirror.roughness - roughness_from_phong_exponent(10000.0)).abs() < 1e-6);
    }

    #[test]
    fn lost_empire() {
        let start = std::time::Instant::now();
        let s = load("lost_empire/lost_empire.obj");
        let elapsed = start.elapsed();
        eprintln!("lost_empire loaded in {elapsed:?}");
        assert_eq!(s.triangle_count(), 224_998);
        assert_eq!(s.positions.len(), 449_992);
        assert_eq!(s.uvs.len(), s.positions.len());
        // Three distinct atlases: RGB and RGBA colour, and the Alpha opacity mask.
        assert_eq!(s.textures.len(), 3);
        assert!(s
            .textures
            .iter()
            .all(|t| t.width == 2048 && t.height == 2048 && t.texels.len() == 2048 * 2048));
        assert_eq!(s.textures.iter().filter(|t| t.srgb).count(), 2);
        let cutouts: Vec<&Material> = s
            .materials
            .iter()
            .filter(|m| m.flags & MATERIAL_ALPHA_CUTOUT != 0)
            .collect();
        assert_eq!(cutouts.len(), 14);
        for m in &cutouts {
            assert_ne!(m.alpha_texture, INVALID_INDEX);
            assert_eq!(m.alpha_cutoff, 0.5);
            let t = &s.textures[m.alpha_texture as usize];
            assert!(!t.srgb);
            // The opacity mask has both holes and solid texels.
            assert!(
                t.texels.iter().any(|&x| x >> 24 == 0) && t.texels.iter().any(|&x| x >> 24 == 255)
            );
        }
        assert!(s
            .materials
            .iter()
            .all(|m| m.base_color_texture != INVALID_INDEX));
        assert_eq!(material(&s, "Stone").base_color, [1.0, 1.0, 1.0, 1.0]);
        assert_eq!(s.emissive_triangle_count(), 162);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // Release builds take well under a second; keep a generous bound for loaded test machines.
        assert!(elapsed.as_secs_f32() < 10.0, "{elapsed:?}");

        let torch = load_with(
            "lost_empire/lost_empire.obj",
            &LoadOptions {
                mtl_override: Some(scenes().join("lost_empire/lost_empire_torch_emissive.mtl")),
                ..LoadOptions::default()
            },
        );
        assert_eq!(torch.triangle_count(), 224_998);
        assert_eq!(torch.emissive_triangle_count(), 1636 + 162);
        assert_eq!(&material(&torch, "Torch").emission[..3], &[0.9, 0.9, 0.6]);
        assert_eq!(torch.textures.len(), 3);
    }

    #[test]
    fn conference_untextured() {
        // Conference (27 MB) does not ship with the repository: `$FOVEA_SCENES`, else
        // `../shared/scenes`; a missing file is skipped with a note, and fails under `CI=true`.
        let large = std::env::var_os("FOVEA_SCENES")
            .filter(|d| !d.is_empty())
            .map_or_else(
                || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes"),
                PathBuf::from,
            );
        let path = large.join("conference/conference.obj");
        if !path.exists() {
            let why = format!(
                "{} is missing (set FOVEA_SCENES to the folder of the large scenes)",
                path.display()
            );
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "CI=true: {why}"
            );
            eprintln!("skipping: {why}");
            return;
        }
        let s = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.triangle_count(), 331_179);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!(s.textures.is_empty());
        assert_eq!(s.emissive_triangle_count(), 0);
    }

    #[test]
    fn bad_obj_inputs() {
        let dir = temp_dir("bad");
        // Missing file.
        let e = load_scene(&dir.join("missing.obj"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
        assert!(e.to_string().contains("missing.obj"));
        // Unknown extension.
        std::fs::write(dir.join("scene.stl"), "solid").unwrap();
        let e = load_scene(&dir.join("scene.stl"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::UnknownExtension { .. }), "{e}");
        assert!(e.to_string().contains("scene.stl"));
        // Truncated file: a face refers to a vertex that was cut off.
        let file = dir.join("truncated.obj");
        std::fs::write(&file, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n").unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
        assert!(e.to_string().contains("truncated.obj"));
        // Garbage in a face.
        let file = dir.join("garbage.obj");
        std::fs::write(&file, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n").unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::Obj { .. }), "{e}");
        // No faces at all.
        let file = dir.join("empty.obj");
        std::fs::write(&file, "v 0 0 0\n").unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::Empty { .. }), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }

    /// `--mtl-diffuse lambert` makes exactly the purely diffuse materials Lambertian: `Ks 0 0 0` given
    /// and no PBR key; by default none is.
    #[test]
    fn purely_diffuse_materials_can_be_lambertian() {
        let dir = temp_dir("lambert");
        std::fs::write(
            dir.join("m.mtl"),
            "newmtl white\nKd 0.73 0.73 0.73\nKs 0 0 0\nNs 10\n\
             newmtl no_ks\nKd 0.5 0.5 0.5\n\
             newmtl shiny\nKd 0.5 0.5 0.5\nKs 0.1 0.1 0.1\n\
             newmtl rough_metal\nKd 0.9 0.8 0.3\nKs 0 0 0\nPm 1\n\
             newmtl sheen\nKd 0.5 0.5 0.5\nKs 0 0 0\nPs 1\n\
             newmtl light\nKe 15 15 15\nKd 0 0 0\nKs 0 0 0\n",
        )
        .unwrap();
        let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
        for name in ["white", "no_ks", "shiny", "rough_metal", "sheen", "light"] {
            obj.push_str(&format!("usemtl {name}\nf 1 2 3\n"));
        }
        std::fs::write(dir.join("a.obj"), obj).unwrap();
        let lambert = LoadOptions {
            mtl_diffuse: MtlDiffuse::Lambert,
            ..LoadOptions::default()
        };
        let with = load_scene(&dir.join("a.obj"), &lambert).unwrap();
        let without = load_scene(&dir.join("a.obj"), &LoadOptions::default()).unwrap();
        for (name, expected) in [
            ("white", true),
            ("no_ks", false),
            ("shiny", false),
            ("rough_metal", false),
            ("sheen", false),
            ("light", true),
        ] {
            let flag = |s: &LoadedScene| material(s, name).flags & MATERIAL_LAMBERTIAN != 0;
            assert_eq!(flag(&with), expected, "{name}");
            assert!(!flag(&without), "{name}");
            // Nothing else about the material changes.
            let mut m = *material(&with, name);
            m.flags &= !MATERIAL_LAMBERTIAN;
            assert_eq!(&m, material(&without, name), "{name}");
        }
        std::fs::remove_dir_all(dir).ok();
    }

    /// `map_Ke`, `map_Pr` + `map_Pm` (combined into one metallic-roughness texture, the metallic map
    /// resampled), `norm`, and `map_Bump` as a normal map or, when it is a height map, converted to one
    /// with its `-bm` (once per image and multiplier).
    #[test]
    fn emission_roughness_metallic_and_normal_maps() {
        let dir = temp_dir("maps");
        let png = |name: &str, w: u32, h: u32, rgba: [u8; 4]| {
            image::RgbaImage::from_pixel(w, h, image::Rgba(rgba))
                .save(dir.join(name))
                .unwrap();
        };
        png("ke.png", 2, 2, [255, 0, 0, 255]);
        png("pr.png", 4, 4, [64, 64, 64, 255]);
        png("pm.png", 2, 2, [200, 200, 200, 255]);
        png("n.png", 2, 2, [128, 128, 255, 255]);
        // Heights climbing 25 / 255 per texel along x.
        image::RgbaImage::from_fn(8, 4, |x, _| {
            let h = (x * 25) as u8;
            image::Rgba([h, h, h, 255])
        })
        .save(dir.join("height.png"))
        .unwrap();
        std::fs::write(
            dir.join("m.mtl"),
            "newmtl lamp\nKd 0.5 0.5 0.5\nmap_Ke ke.png\n\
             newmtl metal\nKd 0.9 0.8 0.2\nmap_Pr pr.png\nmap_Pm pm.png\nnorm n.png\n\
             newmtl bumpy\nKd 0.5 0.5 0.5\nPr 0.5\nmap_Bump n.png\n\
             newmtl heights\nKd 0.5 0.5 0.5\nbump -bm 2 height.png\n\
             newmtl same_heights\nKd 0.2 0.2 0.2\nmap_Bump -bm 2 height.png\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("s.obj"),
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
             usemtl lamp\nf 1/1 2/2 3/3\nusemtl metal\nf 1/1 2/2 3/3\n\
             usemtl bumpy\nf 1/1 2/2 3/3\nusemtl heights\nf 1/1 2/2 3/3\n\
             usemtl same_heights\nf 1/1 2/2 3/3\n",
        )
        .unwrap();
        let s = load_scene(&dir.join("s.obj"), &LoadOptions::default()).unwrap();
        let by_name = |n: &str| {
            let i = s.material_names.iter().position(|m| m == n).unwrap();
            s.materials[i]
        };
        let lamp = by_name("lamp");
        assert_eq!(lamp.emission, [1.0, 1.0, 1.0, 0.0]);
        let ke = &s.textures[lamp.emission_texture as usize];
        assert!(ke.srgb && ke.texels[0] == crate::texture::pack_rgba8([255, 0, 0, 255]));
        let metal = by_name("metal");
        assert_eq!((metal.roughness, metal.metallic), (1.0, 1.0));
        assert_eq!(metal.base_color, [0.9, 0.8, 0.2, 1.0]);
        let mr = &s.textures[metal.metallic_roughness_texture as usize];
        assert_eq!((mr.width, mr.height, mr.srgb), (4, 4, false));
        assert!(mr
            .texels
            .iter()
            .all(|&t| t.to_le_bytes()[1] == 64 && t.to_le_bytes()[2] == 200));
        assert_ne!(metal.normal_texture, INVALID_INDEX);
        let bumpy = by_name("bumpy");
        assert_ne!(
            bumpy.normal_texture, INVALID_INDEX,
            "a normal map given as map_Bump"
        );
        assert_eq!(bumpy.roughness, 0.5);
        let heights = by_name("heights");
        assert_ne!(heights.normal_texture, INVALID_INDEX);
        assert_eq!(
            by_name("same_heights").normal_texture,
            heights.normal_texture
        );
        let normals = &s.textures[heights.normal_texture as usize];
        assert_eq!((normals.width, normals.height, normals.srgb), (8, 4, false));
        // Inside the ramp the normal leans against it: normalize(-2 * 25 / 255, 0, 1).
        let [r, g, b, _] = normals.texels[8 + 3].to_le_bytes();
        let n = Vec3::new(f32::from(r), f32::from(g), f32::from(b)) / 127.5 - 1.0;
        let want = Vec3::new(-2.0 * 25.0 / 255.0, 0.0, 1.0).normalize();
        assert!((n - want).length() < 0.02, "{n} against {want}");
        assert!(
            s.warnings.iter().all(|w| !w.contains("height")),
            "{:?}",
            s.warnings
        );
        // What the materials read, and nothing else: the separate roughness and metallic images and
        // the height map were converted, so they are dropped (ke, n, the combined map, the normals).
        let names: Vec<&String> = s.textures.iter().map(|t| &t.name).collect();
        assert_eq!(s.textures.len(), 4, "{names:?}");
        for m in &s.materials {
            let mut m = *m;
            for index in m.texture_indices_mut() {
                assert!(*index == INVALID_INDEX || (*index as usize) < s.textures.len());
            }
        }
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn nan_vertex_missing_mtl_and_texture() {
        let dir = temp_dir("nan");
        std::fs::write(
            dir.join("m.mtl"),
            "newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd missing.png\nmap_d alpha_missing.png\nd 0.5\n\
             newmtl glass\nKd 1 1 1\nd 0.3\nNs 100\nPr 0.25\nPm 0.5\nPc 1\nPcr 0.2\nmap_Bump b.png\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("a.obj"),
            "mtllib m.mtl\nmtllib nothere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nvt 0 0.25\n\
             usemtl tex\nf 1/1 2/1 3/1\nf 1/1 2/1 4/1\nusemtl glass\nf 3/1 2/1 1/1\nusemtl unknown\nf 2/1 3/1 1/1\n",
        )
        .unwrap();
        let s = load_scene(&dir.join("a.obj"), &LoadOptions::default()).unwrap();
        assert_eq!(s.triangle_count(), 3, "the NaN triangle is skipped");
        let all = s.warnings.join("\n");
        assert!(all.contains("1 triangles using them skipped"), "{all}");
        assert!(all.contains("nothere.mtl"), "{all}");
        assert!(
            all.contains("missing.png") && all.contains("alpha_missing.png"),
            "{all}"
        );
        assert!(all.contains("b.png"), "{all}");
        assert!(all.contains("d 0.3"), "{all}");
        assert!(all.contains("1 triangles have no material"), "{all}");
        // Missing base colour texture: falls back to Kd; missing map_d: opaque.
        let tex = material(&s, "tex");
        assert_eq!(tex.base_color_texture, INVALID_INDEX);
        assert_eq!(&tex.base_color[..3], &[0.5, 0.5, 0.5]);
        assert_eq!(tex.flags & MATERIAL_ALPHA_CUTOUT, 0);
        let glass = material(&s, "glass");
        assert_eq!(
            (glass.roughness, glass.metallic, glass.clearcoat),
            (0.25, 0.5, 1.0)
        );
        assert!((glass.clearcoat_gloss - 0.8).abs() < 1e-6);
        assert_eq!(glass.flags & MATERIAL_ALPHA_CUTOUT, 0);
        // The face with an unknown material gets the default grey one.
        assert_eq!(s.material_names.last().unwrap(), "default");
        assert_eq!(
            *s.triangle_materials.last().unwrap() as usize,
            s.materials.len() - 1
        );
        // UVs are flipped to the glTF convention.
        assert_eq!(s.uvs[0], [0.0, 0.75]);
        std::fs::remove_dir_all(dir).ok();
    }

    /// Fuzz regression (obj crash-2f838015): tobj 4.0.5 panics on an MTL colour with fewer than three
    /// values (`parse_float3` unwraps).
    #[test]
    fn mtl_fuzz_regressions_are_errors_or_warnings_not_panics() {
        use crate::load::load_scene_from;
        use crate::source::MemoryFiles;
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        let load = |mtl: &str| {
            let files = MemoryFiles::new()
                .with("d/s.obj", obj)
                .with("d/m.mtl", mtl.to_owned());
            load_scene_from(&files, Path::new("d/s.obj"), &LoadOptions::default())
        };
        for (mtl, line) in [("newmtl a\nKs\n", 2), ("newmtl a\nKd 1 1 1\n  Ke 0 0\n", 3)] {
            let e = load(mtl).unwrap_err();
            assert!(matches!(e, SceneError::Mtl { .. }), "{e}");
            assert!(
                e.to_string()
                    .starts_with(&format!("d/m.mtl: malformed MTL: line {line}: K")),
                "{e}"
            );
        }
        // Fuzz regression (obj crash-386a6321): `mtllib ` without a name read the OBJ's folder as an MTL.
        let files = MemoryFiles::new().with("d/e.obj", format!("mtllib \n{obj}"));
        let s = load_scene_from(&files, Path::new("d/e.obj"), &LoadOptions::default()).unwrap();
        assert!(
            s.warnings[0].starts_with("d/e.obj: `mtllib` without a file name"),
            "{:?}",
            s.warnings
        );
        // One value is grey; Latin-1 bytes in names and comments are tolerated.
        let s = load("# caf\u{e9}\nnewmtl a\nKd 0.25\nKe 2\n").unwrap();
        assert_eq!(s.materials[0].base_color, [0.25, 0.25, 0.25, 1.0]);
        assert_eq!(&s.materials[0].emission[..3], &[2.0, 2.0, 2.0]);
        let files = MemoryFiles::new().with(
            "d/l.obj",
            b"# caf\xe9 (Latin-1)\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng \xe9\nf 1 2 3\n".to_vec(),
        );
        let s = load_scene_from(&files, Path::new("d/l.obj"), &LoadOptions::default()).unwrap();
        assert_eq!(s.triangle_count(), 1);
    }

    #[test]
    fn faces_naming_no_element_are_refused_before_tobj() {
        use crate::load::load_scene_from;
        use crate::source::MemoryFiles;
        let load = |obj: &str| {
            let files = MemoryFiles::new().with("d/f.obj", obj.to_owned());
            load_scene_from(&files, Path::new("d/f.obj"), &LoadOptions::default())
        };
        let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
        // Fuzz regression (obj crash-4d95050c): a relative texture-coordinate index before the first
        // one made tobj overflow computing its offset (a panic in checked builds).
        for (face, problem) in [
            (
                "f 1/-5 2/1 3/1",
                "relative texture coordinate index -5 with 1 defined before it",
            ),
            (
                "f 1 2 -4",
                "relative vertex index -4 with 3 defined before it",
            ),
            ("f 1//1 2//0 3//1", "normal index 0 (OBJ counts from 1)"),
            (
                "f 1 2 9223372036854775807",
                "vertex index 9223372036854775807 with 3 in the file",
            ),
            (
                "f 1/2 2/1 3/1",
                "texture coordinate index 2 with 1 in the file",
            ),
        ] {
            let e = load(&format!("{head}{face}\n")).unwrap_err();
            assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
            assert_eq!(
                e.to_string(),
                format!("d/f.obj: face index out of range: {problem} at line 6: {face:?}")
            );
        }
        // Relative indices within range, and a forward reference within the file, still load.
        let s = load(&format!(
            "{head}f -3/-1/-1 -2/1/1 -1/1/1\nf 1 2 4\nv 1 1 0\n"
        ))
        .unwrap();
        assert_eq!(s.triangle_count(), 2);
    }

    #[test]
    fn obj_errors_name_the_line() {
        use tobj::LoadError as E;
        let text = "v 0 0 0\nv 1 0 0\nvt 0 x\nvn 0 0\nf 1 2 -3\nf 1/5 2/1 1/1\nf 1//2 2//1 1//1\n";
        let at = |e: E| locate_obj_error(text, &e).map(|(l, _)| l);
        assert_eq!(at(E::TexcoordParseError), Some(3));
        assert_eq!(at(E::NormalParseError), Some(4));
        assert_eq!(at(E::FaceVertexOutOfBounds), Some(5));
        assert_eq!(at(E::FaceTexCoordOutOfBounds), Some(6));
        assert_eq!(at(E::FaceNormalOutOfBounds), Some(7));
        assert_eq!(at(E::FaceParseError), None);
        let (line, content) = locate_obj_error("f 1 2 3/4/5/6", &E::FaceParseError).unwrap();
        assert_eq!((line, content.as_str()), (1, "f 1 2 3/4/5/6"));
    }

    #[test]
    fn map_d_from_luminance_and_override_without_mtllib() {
        let dir = temp_dir("mapd");
        let mut img = image::GrayImage::new(2, 1);
        img.put_pixel(0, 0, image::Luma([0]));
        img.put_pixel(1, 0, image::Luma([255]));
        img.save(dir.join("mask.png")).unwrap();
        std::fs::write(
            dir.join("o.mtl"),
            "newmtl leaf\nKd 0.2 0.6 0.2\nmap_d -clamp on mask.png\nKe 0 0 0\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("b.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl leaf\nf 1 2 3\n",
        )
        .unwrap();
        let options = LoadOptions {
            mtl_override: Some(dir.join("o.mtl")),
            ..LoadOptions::default()
        };
        let s = load_scene(&dir.join("b.obj"), &options).unwrap();
        let leaf = material(&s, "leaf");
        assert_ne!(leaf.flags & MATERIAL_ALPHA_CUTOUT, 0);
        let t = &s.textures[leaf.alpha_texture as usize];
        assert_eq!((t.texel(0, 0)[3], t.texel(1, 0)[3]), (0, 255));
        assert!(s.uvs.is_empty() && s.normals.is_empty());
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // A missing override is an error (a missing `mtllib` only a warning).
        let missing = LoadOptions {
            mtl_override: Some(dir.join("absent.mtl")),
            ..LoadOptions::default()
        };
        let e = load_scene(&dir.join("b.obj"), &missing).unwrap_err();
        assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
        assert!(e.to_string().contains("absent.mtl: file not found"), "{e}");
        // A malformed MTL is an error naming it.
        std::fs::write(dir.join("o.mtl"), "newmtl leaf\nKd 0.2 zz\n").unwrap();
        let e = load_scene(&dir.join("b.obj"), &options).unwrap_err();
        assert!(matches!(e, SceneError::Mtl { .. }), "{e}");
        assert!(e.to_string().contains("o.mtl"));
        std::fs::remove_dir_all(dir).ok();
    }
}
