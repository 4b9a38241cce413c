//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`).
//!
//! The loader walks the default scene (or the first; without scenes, every root node) with node transforms
//! and flattens every TRIANGLES primitive into world space (TRIANGLE_STRIP and TRIANGLE_FAN are converted;
//! POINTS and LINES are skipped with a warning). Normals are transformed by the inverse transpose of the
//! node matrix and the winding is flipped where the matrix mirrors (negative determinant), so that
//! counter-clockwise stays the front face.
//!
//! Materials are glTF metallic-roughness (glTF 2.0 §3.9) mapped onto the Disney parameters of
//! `fovea_core::scene::Material`:
//!
//! | glTF | fovea |
//! |---|---|
//! | `baseColorFactor`, `baseColorTexture` | `base_color` (linear RGBA), texture sRGB |
//! | `metallicFactor`, `roughnessFactor`, `metallicRoughnessTexture` | `metallic`, `roughness`, texture linear (B = metallic, G = roughness) |
//! | `normalTexture` (+`scale`) | `normal_texture` (linear), `normal_scale` |
//! | `emissiveFactor` × `KHR_materials_emissive_strength`, `emissiveTexture` | `emission`, texture sRGB |
//! | `alphaMode` MASK (`alphaCutoff`) / BLEND | `MATERIAL_ALPHA_CUTOUT` with that cutoff / 0.5 (BLEND is approximated by a cut-out) |
//! | `doubleSided` | `MATERIAL_DOUBLE_SIDED_EMISSION` (only matters if the material emits) |
//! | - | `specular` 0.5, no specular tint, sheen, clearcoat or anisotropy, unless an extension sets them |
//!
//! A texture's sampler sets its wrap modes (repeat, clamp to edge, mirrored repeat, per axis), nearest or
//! linear magnification, and whether it gets mip levels (not for `minFilter` `NEAREST`/`LINEAR`). The PBR
//! extensions are mapped in [`crate::gltf_pbr`].
//!
//! Morph targets (positions, normals, tangents) are applied with the node's `weights`, else the
//! mesh's defaults, and skinned meshes are posed by their joints' node transforms (`JOINTS_0`,
//! `WEIGHTS_0`, inverse bind matrices; the mesh node's own transform ignored): the static pose the
//! file describes. `COLOR_0` (float, normalised unsigned byte or short; RGB or RGBA) multiplies the base
//! colour and its alpha; values outside 0..1 are clamped with a warning. Animations are not read, and
//! get a warning naming them.
//!
//! Only `TEXCOORD_0` is read (a texture asking for another set gets a warning and uses set 0);
//! `occlusionTexture` is ignored. Images are decoded by [`crate::texture`] with the option's limits: from a
//! buffer view, a data URI or an external file (missing file: a warning, and the material keeps its
//! factors only).
//!
//! `KHR_lights_punctual` lights are placed by their node's world transform. Their `intensity` is used
//! directly as a radiometric quantity: W/sr for point and spot lights, W/m² (irradiance) for directional
//! lights, times the linear `color`; `range` is ignored. The camera is the first node (in traversal order)
//! with a perspective camera.
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use fovea_core::scene::{
    Light, Material, INVALID_INDEX, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT,
    MATERIAL_ALPHA_CUTOUT, MATERIAL_DOUBLE_SIDED_EMISSION,
};
use glam::{DMat4, DVec3, Mat3, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use crate::error::SceneError;
use crate::mesh::{CameraDesc, LoadOptions, LoadedScene};
use crate::source::{FileSource, Filesystem};
use crate::texture::{decode_texture_bytes, load_texture_from, TextureLimits, TextureRole};

/// Where a primitive's vertices go: its node's world matrix, or one matrix per vertex (a skin's
/// blend of its joints).
enum VertexPlacement {
    Node { world: DMat4, normal_matrix: Mat3 },
    Skinned(Vec<DMat4>),
}

impl VertexPlacement {
    fn node(world: DMat4) -> Self {
        Self::Node {
            world,
            normal_matrix: Mat3::from_mat4(world.as_mat4()).inverse().transpose(),
        }
    }

    /// Vertex `i`'s matrix.
    fn matrix(&self, i: usize) -> DMat4 {
        match self {
            Self::Node { world, .. } => *world,
            Self::Skinned(m) => m.get(i).copied().unwrap_or(DMat4::IDENTITY),
        }
    }

    /// Vertex `i`'s linear part (tangents move by it).
    fn linear(&self, i: usize) -> Mat3 {
        Mat3::from_mat4(self.matrix(i).as_mat4())
    }

    /// Vertex `i`'s normal matrix: the inverse transpose of its linear part.
    fn normal_matrix(&self, i: usize) -> Mat3 {
        match self {
            Self::Node { normal_matrix, .. } => *normal_matrix,
            Self::Skinned(_) => self.linear(i).inverse().transpose(),
        }
    }
}

/// A node's local matrix (its `matrix` or TRS), in f64.
fn local_matrix(node: &gltf::Node) -> DMat4 {
    DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)))
}

/// Every node's world matrix, through its parents (glTF 2.0 §3.5.3): what a skin's joints need,
/// wherever they sit in the hierarchy; empty for a file without skins. A node in a cycle gets its
/// local matrix only.
fn node_world_matrices(document: &gltf::Document) -> Vec<DMat4> {
    if document.skins().len() == 0 {
        return Vec::new();
    }
    let n = document.nodes().len();
    let mut parent = vec![None; n];
    for node in document.nodes() {
        for child in node.children() {
            parent[child.index()] = Some(node.index());
        }
    }
    let local: Vec<DMat4> = document.nodes().map(|node| local_matrix(&node)).collect();
    (0..n)
        .map(|i| {
            let mut world = local[i];
            let mut at = parent[i];
            let mut steps = 0;
            while let Some(p) = at {
                steps += 1;
                if steps > n {
                    return local[i];
                }
                world = local[p] * world;
                at = parent[p];
            }
            world
        })
        .collect()
}

/// A primitive's morphed displacements per vertex: each list empty (nothing moves) or one per vertex.
#[derive(Default)]
struct MorphDisplacements {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    tangents: Vec<[f32; 3]>,
}

impl MorphDisplacements {
    fn normal(&self, i: usize) -> Vec3 {
        self.normals.get(i).map_or(Vec3::ZERO, |&n| Vec3::from(n))
    }

    fn tangent(&self, i: usize) -> Vec3 {
        self.tangents.get(i).map_or(Vec3::ZERO, |&t| Vec3::from(t))
    }
}

/// The glTF extensions the loader reads whole; the material extensions of
/// [`crate::gltf_pbr::MAPPED_EXTENSIONS`] are read in part (see there).
pub const SUPPORTED_EXTENSIONS: [&str; 2] =
    ["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// Loads a `.gltf` or `.glb` file.
pub fn load_gltf(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    load_gltf_from(&Filesystem, path, options)
}

/// Loads a `.gltf` or `.glb` file, reading it and its external buffers and images from `source`
/// (relative URIs are relative to `path`'s folder).
pub fn load_gltf_from(
    source: &dyn FileSource,
    path: &Path,
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    let bytes = source
        .read(path)
        .map_err(|e| SceneError::from_io(path, e))?;
    let malformed = |message: String| SceneError::Gltf {
        path: path.to_owned(),
        message,
    };
    let gltf =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| malformed(e.to_string()))?;
    let sampler_json = samplers_with_invalid_values(gltf.document.as_json(), &bytes);
    let precision_warnings = core_factors_beyond_f32(&bytes);
    drop(bytes);
    let gltf::Gltf { document, blob } = gltf;
    // gltf 1.4.1 panics on some JSON its validation accepts (or, for POSITION, on a dangling index while
    // validating), so check those first, then validate.
    let mut root = document.into_json();
    let mut early_warnings = check_json(&mut root).map_err(malformed)?;
    early_warnings.extend(replace_invalid_sampler_values(&mut root, &sampler_json));
    early_warnings.extend(precision_warnings);
    // The material extensions fovea maps itself (`crate::gltf_pbr`) are unknown to gltf's validation,
    // which refuses a file that requires one: they are taken off the required list it checks.
    root.extensions_required
        .retain(|e| !crate::gltf_pbr::MAPPED_EXTENSIONS.contains(&e.as_str()));
    let document = gltf::Document::from_json(root).map_err(|e| malformed(e.to_string()))?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let buffers = load_buffers(source, path, &base, &document, blob)?;
    let mut loader = Loader {
        source,
        options,
        path,
        base,
        document: &document,
        buffers: &buffers,
        limits: options.texture_limits(),
        scene: LoadedScene::default(),
        material_slots: HashMap::new(),
        texture_slots: HashMap::new(),
        any_normals: false,
        any_uvs: false,
        world_positions: Vec::new(),
        light_positions: Vec::new(),
        camera_position: DVec3::ZERO,
        unsupported: std::collections::BTreeMap::new(),
        replaced: std::collections::BTreeMap::new(),
    };
    loader.walk()?;
    let animations = document.animations().count();
    if animations > 0 {
        loader.warn(format!(
            "{animations} animation(s) are not played: the scene is drawn as its nodes stand"
        ));
    }
    loader.rebase();
    let mut scene = loader.scene;
    // An optional extension fovea does not read changes how the asset should look: say so, once per
    // extension, naming the materials that use it (a required one is refused by the glTF validation
    // above).
    let named = |materials: &[String]| {
        let names: Vec<String> = materials.iter().take(8).map(|m| format!("{m:?}")).collect();
        let more = materials.len().saturating_sub(names.len());
        let more = if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        };
        format!("{} material(s) {}{more}", materials.len(), names.join(", "))
    };
    for ((extension, what), materials) in &loader.unsupported {
        scene.warnings.push(format!(
            "{}: {extension} is not fully supported: {}: {what}",
            path.display(),
            named(materials),
        ));
    }
    // A value outside its specification's range: the file's value and what fovea used instead.
    for ((extension, what), materials) in &loader.replaced {
        scene.warnings.push(format!(
            "{}: {}: {extension} {what}",
            path.display(),
            named(materials),
        ));
    }
    let unsupported: Vec<&str> = document
        .extensions_used()
        .filter(|e| {
            !SUPPORTED_EXTENSIONS.contains(e)
                && !crate::gltf_pbr::MAPPED_EXTENSIONS.contains(e)
                && !loader.unsupported.keys().any(|(x, _)| x == e)
        })
        .collect();
    if !unsupported.is_empty() {
        scene.warnings.push(format!(
            "{}: glTF extension(s) {} not supported; what they describe is left out",
            path.display(),
            unsupported.join(", ")
        ));
    }
    for w in early_warnings.into_iter().rev() {
        scene.warnings.insert(0, format!("{}: {w}", path.display()));
    }
    if let Some(mtl) = &options.mtl_override {
        scene.warnings.push(format!(
            "{}: the MTL override {} applies to OBJ files only; ignored",
            path.display(),
            mtl.display()
        ));
    }
    if !loader.any_normals {
        scene.normals.clear();
    }
    if !loader.any_uvs {
        scene.uvs.clear();
    }
    scene.validate(path)?;
    Ok(scene)
}

/// What makes two texture records differ: image index, sRGB, sampler bits, coordinate transform (bits).
type TextureKey = (usize, bool, u32, Option<[u32; 6]>);

/// The [`crate::texture::Texture::sampler`] bits of a glTF sampler: its wrap modes per axis, `NEAREST`
/// magnification as nearest-texel lookups, and a minification filter without mip-mapping (`NEAREST`,
/// `LINEAR`) as no mip levels. A texture without a sampler repeats and filters (glTF's default).
fn sampler_bits(sampler: &gltf::texture::Sampler) -> u32 {
    use fovea_core::scene::{
        TEXTURE_CLAMP_S, TEXTURE_CLAMP_T, TEXTURE_MIRROR_S, TEXTURE_MIRROR_T, TEXTURE_NEAREST,
    };
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |mode: WrappingMode, clamp: u32, mirror: u32| match mode {
        WrappingMode::ClampToEdge => clamp,
        WrappingMode::MirroredRepeat => mirror,
        WrappingMode::Repeat => 0,
    };
    let mut bits = wrap(sampler.wrap_s(), TEXTURE_CLAMP_S, TEXTURE_MIRROR_S)
        | wrap(sampler.wrap_t(), TEXTURE_CLAMP_T, TEXTURE_MIRROR_T);
    if sampler.mag_filter() == Some(MagFilter::Nearest) {
        bits |= TEXTURE_NEAREST;
    }
    if matches!(
        sampler.min_filter(),
        Some(MinFilter::Nearest | MinFilter::Linear)
    ) {
        bits |= crate::texture::NO_MIP_LEVELS;
    }
    bits
}

/// Checks (and where harmless repairs) what gltf 1.4.1 would panic on but its validation does not
/// catch: a primitive's `POSITION` naming a missing accessor, an image with neither `uri` nor
/// `bufferView`, a camera without the projection object its `type` names. An image in a buffer view
/// without `mimeType` is accepted (the decoder looks at the bytes) with a warning, returned.
fn check_json(root: &mut gltf::json::Root) -> Result<Vec<String>, String> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let count = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position) {
                if index.value() >= count {
                    return Err(format!(
                        "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not \
                         exist (there are {count})",
                        index.value()
                    ));
                }
            }
        }
    }
    let mut warnings = Vec::new();
    for (i, image) in root.images.iter_mut().enumerate() {
        match (&image.buffer_view, &image.uri, &image.mime_type) {
            (None, None, _) => {
                return Err(format!("images[{i}] has neither a uri nor a bufferView"));
            }
            (Some(_), _, None) => {
                warnings.push(format!(
                    "images[{i}] is in a buffer view but has no mimeType; the format is guessed"
                ));
                image.mime_type = Some(gltf::json::image::MimeType(
                    "application/octet-stream".to_owned(),
                ));
            }
            _ => {}
        }
    }
    for (i, camera) in root.cameras.iter().enumerate() {
        let ok = match camera.type_ {
            Checked::Valid(Type::Perspective) => camera.perspective.is_some(),
            Checked::Valid(Type::Orthographic) => camera.orthographic.is_some(),
            Checked::Invalid => true, // the validation reports it
        };
        if !ok {
            return Err(format!(
                "cameras[{i}] lacks the projection object its type names"
            ));
        }
    }
    Ok(warnings)
}

/// Whether a sampler field holds a number the spec does not allow (gltf's parser keeps only that it is
/// invalid).
fn is_invalid_sampler(sampler: &gltf::json::texture::Sampler) -> bool {
    use gltf::json::validation::Checked::Invalid;
    matches!(sampler.mag_filter, Some(Invalid))
        || matches!(sampler.min_filter, Some(Invalid))
        || matches!(sampler.wrap_s, Invalid)
        || matches!(sampler.wrap_t, Invalid)
}

/// The file's JSON (`bytes`: a `.gltf`, or a `.glb`'s JSON chunk) parsed again as plain values, for
/// the checks that need the file's own numbers; `Null` if it cannot be read (gltf's parse has said why).
fn file_json(bytes: &[u8]) -> serde_json::Value {
    let glb;
    let json: &[u8] = if bytes.starts_with(b"glTF") {
        glb = gltf::Glb::from_slice(bytes).ok();
        match &glb {
            Some(glb) => &glb.json,
            None => return serde_json::Value::Null,
        }
    } else {
        bytes
    };
    serde_json::from_slice(json).unwrap_or_default()
}

/// The file's own `samplers` array when a sampler holds a value the spec does not allow, so that the
/// warning can name the number; `Null` when none does (the usual case: no second parse).
fn samplers_with_invalid_values(root: &gltf::json::Root, bytes: &[u8]) -> serde_json::Value {
    if !root.samplers.iter().any(is_invalid_sampler) {
        return serde_json::Value::Null;
    }
    file_json(bytes)["samplers"].take()
}

/// Whether `text` (JSON) may hold a number that single precision cannot: outside strings, an exponent
/// of two or more digits (f32 ends near 3.4e38 and 1.4e-45) or a run of 38 digits. A cheap scan before
/// the exact check; strings (a data URI's base64 among them) are skipped, since JSON numbers are
/// never inside one.
fn may_exceed_f32(text: &[u8]) -> bool {
    let (mut digits, mut in_string, mut escaped) = (0, false, false);
    for (i, &b) in text.iter().enumerate() {
        if in_string {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => in_string = false,
                _ => {}
            }
            continue;
        }
        if b == b'"' {
            in_string = true;
            digits = 0;
            continue;
        }
        if b.is_ascii_digit() {
            digits += 1;
            if digits >= 38 {
                return true;
            }
            continue;
        }
        digits = 0;
        if b == b'e' || b == b'E' {
            let rest = &text[i + 1..];
            let rest = rest
                .strip_prefix(b"-")
                .or(rest.strip_prefix(b"+"))
                .unwrap_or(rest);
            if rest.len() >= 2 && rest[0].is_ascii_digit() && rest[1].is_ascii_digit() {
                return true;
            }
        }
    }
    false
}

/// `v` with seven significant digits and an exponent, trailing zeros dropped (`1e-50`, `2.5e39`): the
/// file's number as it wrote it, where JSON parsing may have moved it by an ulp.
fn seven_digits(v: f64) -> String {
    let text = format!("{v:.6e}");
    match text.split_once('e') {
        Some((mantissa, exponent)) if mantissa.contains('.') => format!(
            "{}e{exponent}",
            mantissa.trim_end_matches('0').trim_end_matches('.')
        ),
        _ => text,
    }
}

/// Warnings for the core material factors the file gives beyond single precision, which gltf reads
/// as f32 (an overflow as infinity, which the material check then replaces; an underflow silently as
/// 0): `materials[i] ("name"): pbrMetallicRoughness.roughnessFactor 1e-50 is beyond single precision;
/// read as 0`. The extensions' numbers are checked by `crate::gltf_pbr` instead.
fn core_factors_beyond_f32(bytes: &[u8]) -> Vec<String> {
    if !may_exceed_f32(bytes) {
        return Vec::new();
    }
    let json = file_json(bytes);
    let Some(materials) = json["materials"].as_array() else {
        return Vec::new();
    };
    let mut warnings = Vec::new();
    for (i, material) in materials.iter().enumerate() {
        let pbr = &material["pbrMetallicRoughness"];
        let fields = [
            (
                "pbrMetallicRoughness.baseColorFactor",
                &pbr["baseColorFactor"],
            ),
            (
                "pbrMetallicRoughness.metallicFactor",
                &pbr["metallicFactor"],
            ),
            (
                "pbrMetallicRoughness.roughnessFactor",
                &pbr["roughnessFactor"],
            ),
            ("emissiveFactor", &material["emissiveFactor"]),
            ("alphaCutoff", &material["alphaCutoff"]),
            ("normalTexture.scale", &material["normalTexture"]["scale"]),
            (
                "KHR_materials_emissive_strength.emissiveStrength",
                &material["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"],
            ),
        ];
        for (field, value) in fields {
            let numbers: Vec<&serde_json::Value> = match value.as_array() {
                Some(list) => list.iter().collect(),
                None => vec![value],
            };
            let beyond = numbers.iter().find_map(|n| {
                let v = n.as_f64()?;
                let read = v as f32;
                (read.is_infinite() || (read == 0.0 && v != 0.0)).then_some((v, read))
            });
            if let Some((v, read)) = beyond {
                let name = material["name"].as_str().unwrap_or("");
                warnings.push(format!(
                    "materials[{i}] ({name:?}): {field} {} is beyond single precision; read as {read}",
                    seven_digits(v)
                ));
            }
        }
    }
    warnings
}

/// Replaces each sampler value the spec does not allow by glTF's default (linear magnification,
/// mip-mapped minification, `REPEAT`), with a warning naming the sampler, the field, the file's
/// value (from `file_samplers`, [`samplers_with_invalid_values`]) and what is used instead.
fn replace_invalid_sampler_values(
    root: &mut gltf::json::Root,
    file_samplers: &serde_json::Value,
) -> Vec<String> {
    use gltf::json::texture::WrappingMode;
    use gltf::json::validation::Checked::{Invalid, Valid};
    let mut warnings = Vec::new();
    for (i, sampler) in root.samplers.iter_mut().enumerate() {
        let mut replaced = |field: &str, allowed: &str, used: &str| {
            warnings.push(format!(
                "samplers[{i}].{field} {} is not {allowed}; {used} used",
                file_samplers[i][field]
            ));
        };
        if matches!(sampler.mag_filter, Some(Invalid)) {
            replaced(
                "magFilter",
                "9728 (NEAREST) or 9729 (LINEAR)",
                "linear magnification",
            );
            sampler.mag_filter = None;
        }
        if matches!(sampler.min_filter, Some(Invalid)) {
            replaced(
                "minFilter",
                "9728, 9729 or 9984 to 9987",
                "mip-mapped linear minification",
            );
            sampler.min_filter = None;
        }
        let wrap_values = "33071 (CLAMP_TO_EDGE), 33648 (MIRRORED_REPEAT) or 10497 (REPEAT)";
        if matches!(sampler.wrap_s, Invalid) {
            replaced("wrapS", wrap_values, "REPEAT");
            sampler.wrap_s = Valid(WrappingMode::Repeat);
        }
        if matches!(sampler.wrap_t, Invalid) {
            replaced("wrapT", wrap_values, "REPEAT");
            sampler.wrap_t = Valid(WrappingMode::Repeat);
        }
    }
    warnings
}

/// Reads every buffer: the GLB `BIN` chunk, a data URI or an external file (relative to the glTF file).
fn load_buffers(
    source: &dyn FileSource,
    path: &Path,
    base: &Path,
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| SceneError::Gltf {
                path: path.to_owned(),
                message: format!(
                    "buffer {} refers to the GLB BIN chunk, which is missing",
                    buffer.index()
                ),
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(source, path, base, uri)?,
        };
        if data.len() < buffer.length() {
            return Err(SceneError::BufferTooShort {
                path: path.to_owned(),
                what: format!("buffer {} (byteLength)", buffer.index()),
                needed: buffer.length() as u64,
                available: data.len() as u64,
            });
        }
        out.push(data);
    }
    Ok(out)
}

/// Whether `uri` is a `data:` URI.
fn is_data_uri(uri: &str) -> bool {
    uri.starts_with("data:")
}

/// Decodes `%XX` escapes of a relative URI.
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(v) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The file a relative (or `file:`) URI names.
fn uri_path(base: &Path, uri: &str) -> PathBuf {
    let rest = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
        .unwrap_or(uri);
    base.join(percent_decode(rest))
}

/// Reads the bytes a buffer or image URI refers to.
fn read_uri(
    source: &dyn FileSource,
    path: &Path,
    base: &Path,
    uri: &str,
) -> Result<Vec<u8>, SceneError> {
    if is_data_uri(uri) {
        // The gltf crate decodes base64 data URIs for buffer sources; reuse it for images too.
        gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
            .map(|d| d.0)
            .map_err(|e| SceneError::Gltf {
                path: path.to_owned(),
                message: format!("bad data URI: {e}"),
            })
    } else if uri.contains("://") {
        Err(SceneError::Gltf {
            path: path.to_owned(),
            message: format!("unsupported URI scheme in {uri:?}"),
        })
    } else {
        let file = uri_path(base, uri);
        source.read(&file).map_err(|e| SceneError::from_io(file, e))
    }
}

/// Flattening state.
struct Loader<'a> {
    source: &'a dyn FileSource,
    options: &'a LoadOptions,
    path: &'a Path,
    base: PathBuf,
    document: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
    limits: TextureLimits,
    scene: LoadedScene,
    /// glTF material index (`None` = the default material) → index in `scene.materials` and the
    /// texture coordinate set its textures read.
    material_slots: HashMap<Option<usize>, (u32, u32)>,
    /// (image index, sRGB, sampler bits) → index in `scene.textures`, or `INVALID_INDEX` if the image
    /// is missing.
    texture_slots: HashMap<TextureKey, u32>,
    any_normals: bool,
    any_uvs: bool,
    /// World-space positions in f64, until the scene's origin is known ([`crate::rebase`]).
    world_positions: Vec<[f64; 3]>,
    /// The world position of each punctual light (parallel to `scene.punctual_lights`) and of the
    /// camera, in f64 for the same reason.
    light_positions: Vec<DVec3>,
    camera_position: DVec3,
    /// What materials use and fovea leaves out, for one warning per extension: (extension, what is
    /// lost) → the materials.
    unsupported: std::collections::BTreeMap<(String, String), Vec<String>>,
    /// (extension, what was replaced by what) → the materials whose file gave that value
    /// (`gltf_pbr::ExtensionsApplied::replaced`).
    replaced: std::collections::BTreeMap<(String, String), Vec<String>>,
}

impl Loader<'_> {
    /// Moves the scene to the origin [`crate::rebase::scene_origin`] chooses: positions, the camera and
    /// the lights.
    fn rebase(&mut self) {
        let origin = crate::rebase::scene_origin(&self.world_positions, &self.scene.triangles);
        let local = |p: DVec3| crate::rebase::to_local(p.to_array(), origin);
        self.scene.origin = origin;
        self.scene.positions = std::mem::take(&mut self.world_positions)
            .into_iter()
            .map(|p| crate::rebase::to_local(p, origin))
            .collect();
        for (l, &p) in self
            .scene
            .punctual_lights
            .iter_mut()
            .zip(&self.light_positions)
        {
            if l.kind != LIGHT_DIRECTIONAL {
                let [x, y, z] = local(p);
                l.position = [x, y, z, l.position[3]];
            }
        }
        if let Some(c) = &mut self.scene.camera {
            c.position = local(self.camera_position);
        }
    }

    fn warn(&mut self, message: String) {
        self.scene
            .warnings
            .push(format!("{}: {message}", self.path.display()));
    }

    fn malformed(&self, message: String) -> SceneError {
        SceneError::InvalidAccessor {
            path: self.path.to_owned(),
            message,
        }
    }

    /// Walks the scene graph iteratively with world transforms.
    fn walk(&mut self) -> Result<(), SceneError> {
        let document = self.document;
        let roots: Vec<gltf::Node> = match document
            .default_scene()
            .or_else(|| document.scenes().next())
        {
            Some(scene) => scene.nodes().collect(),
            None => {
                let mut is_child = vec![false; document.nodes().len()];
                for node in document.nodes() {
                    for child in node.children() {
                        is_child[child.index()] = true;
                    }
                }
                if document.nodes().len() > 0 {
                    self.warn("no scene defined; rendering every root node".to_owned());
                }
                document.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let node_worlds = node_world_matrices(document);
        // World transforms in f64: a node far from the origin keeps its scene's detail until the rebase.
        let mut stack: Vec<(gltf::Node, DMat4)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, DMat4::IDENTITY))
            .collect();
        let mut visits = 0usize;
        let visit_limit = 16 * document.nodes().len().max(1) + 1024;
        while let Some((node, parent)) = stack.pop() {
            visits += 1;
            if visits > visit_limit {
                return Err(SceneError::Gltf {
                    path: self.path.to_owned(),
                    message: "node hierarchy is cyclic or absurdly instanced".to_owned(),
                });
            }
            let world = parent * local_matrix(&node);
            if let Some(mesh) = node.mesh() {
                // Morph weights: the node's override the mesh's defaults (glTF 2.0 §3.7.2.2).
                let weights = node.weights().or(mesh.weights()).unwrap_or(&[]);
                let joints = match node.skin() {
                    Some(skin) => self.joint_matrices(&skin, &node_worlds),
                    None => None,
                };
                self.add_mesh(&mesh, world, weights, joints.as_deref())?;
            }
            if let Some(camera) = node.camera() {
                self.add_camera(&camera, world);
            }
            if let Some(light) = node.light() {
                self.add_light(&light, world);
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for child in children.into_iter().rev() {
                stack.push((child, world));
            }
        }
        Ok(())
    }

    fn add_camera(&mut self, camera: &gltf::Camera, world_f64: DMat4) {
        let world = world_f64.as_mat4();
        if self.scene.camera.is_some() {
            return;
        }
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
                let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
                self.camera_position = world_f64.transform_point3(DVec3::ZERO);
                self.scene.camera = Some(CameraDesc {
                    // Set by `rebase` from `camera_position`.
                    position: [0.0; 3],
                    forward: forward.to_array(),
                    up: up.to_array(),
                    yfov_radians: p.yfov(),
                    aspect_ratio: p.aspect_ratio(),
                });
            }
            gltf::camera::Projection::Orthographic(_) => {
                self.warn(format!(
                    "camera {} is orthographic; ignored",
                    camera.index()
                ));
            }
        }
    }

    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world_f64: DMat4) {
        use gltf::khr_lights_punctual::Kind;
        let world = world_f64.as_mat4();
        let c = Vec3::from(light.color()) * light.intensity();
        // The position is set by `rebase` from the f64 one.
        let world_position = world_f64.transform_point3(DVec3::ZERO);
        let position = Vec3::ZERO;
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let mut l = Light {
            index: INVALID_INDEX,
            intensity: [c.x, c.y, c.z, 0.0],
            ..Light::default()
        };
        match light.kind() {
            Kind::Point => {
                l.kind = LIGHT_POINT;
                l.position = [position.x, position.y, position.z, 0.0];
            }
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                l.kind = LIGHT_SPOT;
                l.position = [position.x, position.y, position.z, inner_cone_angle.cos()];
                l.direction = [direction.x, direction.y, direction.z, 0.0];
                l.intensity[3] = outer_cone_angle.cos();
            }
            Kind::Directional => {
                l.kind = LIGHT_DIRECTIONAL;
                l.direction = [direction.x, direction.y, direction.z, 0.0];
            }
        }
        if direction == Vec3::ZERO && l.kind != LIGHT_POINT {
            self.warn(format!(
                "light {} has a degenerate node transform; skipped",
                light.index()
            ));
            return;
        }
        self.scene.punctual_lights.push(l);
        self.light_positions.push(world_position);
    }

    /// Checks that `accessor` has one of the accepted (dimensions, component type) pairs and that its
    /// bytes lie inside the buffer.
    fn check_accessor(
        &self,
        accessor: &gltf::Accessor,
        what: &str,
        dims: Dimensions,
        types: &[DataType],
    ) -> Result<(), SceneError> {
        if accessor.dimensions() != dims || !types.contains(&accessor.data_type()) {
            return Err(self.malformed(format!(
                "{what} (accessor {}) is {:?} {:?}; expected {dims:?} of {types:?}",
                accessor.index(),
                accessor.dimensions(),
                accessor.data_type()
            )));
        }
        if accessor.count() == 0 {
            return Err(self.malformed(format!(
                "{what} (accessor {}) has count 0",
                accessor.index()
            )));
        }
        let check_view =
            |view: gltf::buffer::View, offset: usize, count: usize, size: usize, label: &str| {
                let stride = view.stride().unwrap_or(size);
                if stride < size {
                    return Err(self.malformed(format!(
                        "{label}: byteStride {stride} is smaller than an element ({size} bytes)"
                    )));
                }
                let needed_in_view =
                    offset as u64 + stride as u64 * (count as u64 - 1) + size as u64;
                if needed_in_view > view.length() as u64 {
                    return Err(SceneError::BufferTooShort {
                        path: self.path.to_owned(),
                        what: format!("{label} (in buffer view {})", view.index()),
                        needed: needed_in_view,
                        available: view.length() as u64,
                    });
                }
                let available = self.buffers[view.buffer().index()].len() as u64;
                let needed = view.offset() as u64 + view.length() as u64;
                if needed > available {
                    return Err(SceneError::BufferTooShort {
                        path: self.path.to_owned(),
                        what: format!("buffer view {} of {label}", view.index()),
                        needed,
                        available,
                    });
                }
                Ok(())
            };
        let label = format!("{what} (accessor {})", accessor.index());
        if let Some(view) = accessor.view() {
            check_view(
                view,
                accessor.offset(),
                accessor.count(),
                accessor.size(),
                &label,
            )?;
        } else if accessor.sparse().is_none() {
            return Err(
                self.malformed(format!("{label} has neither a buffer view nor sparse data"))
            );
        }
        if let Some(sparse) = accessor.sparse() {
            let n = sparse.count();
            if n > 0 {
                let idx = sparse.indices();
                check_view(
                    idx.view(),
                    idx.offset(),
                    n,
                    idx.index_type().size(),
                    &format!("{label} sparse indices"),
                )?;
                let val = sparse.values();
                check_view(
                    val.view(),
                    val.offset(),
                    n,
                    accessor.size(),
                    &format!("{label} sparse values"),
                )?;
            }
        }
        Ok(())
    }

    /// A skin's joint matrices, `world(joint) · inverse bind matrix` (glTF 2.0 §3.7.3), in the skin's
    /// joint order; `None`, with a warning, where its inverse bind matrices cannot be read.
    fn joint_matrices(&mut self, skin: &gltf::Skin, node_worlds: &[DMat4]) -> Option<Vec<DMat4>> {
        let label = format!("skin {}", skin.index());
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind: Vec<DMat4> = match skin.inverse_bind_matrices() {
            None => vec![DMat4::IDENTITY; joints.len()],
            Some(accessor) => {
                let checked = self.check_accessor(
                    &accessor,
                    &format!("{label} inverseBindMatrices"),
                    Dimensions::Mat4,
                    &[DataType::F32],
                );
                let buffers = self.buffers;
                let read: Option<Vec<DMat4>> = checked.ok().and_then(|_| {
                    skin.reader(|b| buffers.get(b.index()).map(Vec::as_slice))
                        .read_inverse_bind_matrices()
                        .map(|m| {
                            m.map(|c| DMat4::from_cols_array_2d(&c.map(|c| c.map(f64::from))))
                                .collect()
                        })
                });
                match read.filter(|m| m.len() == joints.len()) {
                    Some(m) => m,
                    None => {
                        self.warn(format!(
                            "{label}: its inverse bind matrices cannot be read as {} matrices; its meshes are drawn unposed",
                            joints.len()
                        ));
                        return None;
                    }
                }
            }
        };
        Some(
            joints
                .iter()
                .zip(inverse_bind)
                .map(|(&j, ibm)| node_worlds[j] * ibm)
                .collect(),
        )
    }

    /// Where `primitive`'s vertices go: its node's `world` matrix, or, for a skinned mesh (`joints`
    /// given), each vertex's blend of joint matrices by `JOINTS_0` and `WEIGHTS_0` (the node's own
    /// transform is then ignored, as glTF 2.0 §3.7.3 says). A skin whose attributes are missing or
    /// malformed falls back to the node, with a warning.
    fn placement(
        &mut self,
        primitive: &gltf::Primitive,
        label: &str,
        world: DMat4,
        joints: Option<&[DMat4]>,
        vertex_count: usize,
    ) -> VertexPlacement {
        let Some(joints) = joints else {
            return VertexPlacement::node(world);
        };
        let buffers = self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let indices: Option<Vec<[u16; 4]>> = reader.read_joints(0).map(|j| j.into_u16().collect());
        let weights: Option<Vec<[f32; 4]>> = reader.read_weights(0).map(|w| w.into_f32().collect());
        let (Some(indices), Some(weights)) = (indices, weights) else {
            self.warn(format!(
                "{label}: skinned but without JOINTS_0 and WEIGHTS_0; drawn by its node's transform"
            ));
            return VertexPlacement::node(world);
        };
        if indices.len() != vertex_count || weights.len() != vertex_count {
            self.warn(format!(
                "{label}: JOINTS_0 or WEIGHTS_0 is not one per vertex; drawn by its node's transform"
            ));
            return VertexPlacement::node(world);
        }
        let mut out_of_range = false;
        let matrices = indices
            .iter()
            .zip(&weights)
            .map(|(j, w)| {
                let mut m = DMat4::ZERO;
                let mut total = 0.0f64;
                for (&joint, &weight) in j.iter().zip(w) {
                    let weight = f64::from(weight);
                    if !(weight > 0.0) {
                        continue;
                    }
                    match joints.get(usize::from(joint)) {
                        Some(jm) => {
                            m += *jm * weight;
                            total += weight;
                        }
                        None => out_of_range = true,
                    }
                }
                // Weights should sum to 1; normalised here, and a vertex with none stays put.
                if total > 0.0 {
                    m * (1.0 / total)
                } else {
                    world
                }
            })
            .collect();
        if out_of_range {
            self.warn(format!(
                "{label}: JOINTS_0 names joints its skin does not have; those weights are ignored"
            ));
        }
        VertexPlacement::Skinned(matrices)
    }

    /// The summed displacements of `primitive`'s morph targets under `weights`, per vertex (empty
    /// where nothing moves). A target whose accessor is malformed or of another length, and weights
    /// that do not match the targets in number, are warned about; a missing weight is 0.
    fn morph_displacements(
        &mut self,
        primitive: &gltf::Primitive,
        label: &str,
        weights: &[f32],
        vertex_count: usize,
    ) -> MorphDisplacements {
        let mut out = MorphDisplacements::default();
        let targets: Vec<gltf::mesh::MorphTarget> = primitive.morph_targets().collect();
        if targets.is_empty() {
            return out;
        }
        if weights.len() != targets.len() {
            self.warn(format!(
                "{label}: {} morph targets but {} weights; missing weights are 0, extra ones ignored",
                targets.len(),
                weights.len()
            ));
        }
        let buffers = self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        for (t, ((positions, normals, tangents), target)) in
            reader.read_morph_targets().zip(&targets).enumerate()
        {
            let w = weights.get(t).copied().unwrap_or(0.0);
            if !w.is_finite() {
                self.warn(format!("{label}: morph weight {t} is {w}; read as 0"));
                continue;
            }
            if w == 0.0 {
                continue;
            }
            let fields = [
                ("POSITION", target.positions(), &mut out.positions),
                ("NORMAL", target.normals(), &mut out.normals),
                ("TANGENT", target.tangents(), &mut out.tangents),
            ];
            let mut values = [
                positions.map(|i| i.collect::<Vec<[f32; 3]>>()),
                normals.map(|i| i.collect::<Vec<[f32; 3]>>()),
                tangents.map(|i| i.collect::<Vec<[f32; 3]>>()),
            ];
            for ((name, accessor, sum), read) in fields.into_iter().zip(values.iter_mut()) {
                let Some(accessor) = accessor else { continue };
                let what = format!("{label} morph target {t} {name}");
                let usable = self
                    .check_accessor(&accessor, &what, Dimensions::Vec3, &[DataType::F32])
                    .is_ok()
                    && accessor.count() == vertex_count;
                match read.take().filter(|v| usable && v.len() == vertex_count) {
                    Some(displacements) => {
                        sum.resize(vertex_count, [0.0; 3]);
                        for (s, d) in sum.iter_mut().zip(displacements) {
                            *s = (Vec3::from(*s) + w * Vec3::from(d)).to_array();
                        }
                    }
                    None => self.warn(format!(
                        "{what} is not {vertex_count} float vectors in its buffer; ignored"
                    )),
                }
            }
        }
        out
    }

    /// Adds `mesh`'s primitives in world space, each morphed by `weights` (its morph targets'
    /// displacements of positions, normals and tangents, weighted and summed).
    ///
    /// Long because it reads a primitive's attributes one after another (positions, normals, texture
    /// coordinates, tangents, colours, indices), each checked against its accessor where it is read;
    /// apart, the pieces would pass the same dozen locals to each other.
    fn add_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world_f64: DMat4,
        weights: &[f32],
        joints: Option<&[DMat4]>,
    ) -> Result<(), SceneError> {
        for primitive in mesh.primitives() {
            let label = format!("mesh {} primitive {}", mesh.index(), primitive.index());
            let mode = primitive.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.warn(format!(
                    "{label} has mode {mode:?}; only triangles are rendered, skipped"
                ));
                continue;
            }
            let Some(pos_acc) = primitive.get(&gltf::Semantic::Positions) else {
                self.warn(format!("{label} has no POSITION attribute; skipped"));
                continue;
            };
            self.check_accessor(
                &pos_acc,
                &format!("{label} POSITION"),
                Dimensions::Vec3,
                &[DataType::F32],
            )?;
            let normal_acc = primitive.get(&gltf::Semantic::Normals);
            if let Some(a) = &normal_acc {
                self.check_accessor(
                    a,
                    &format!("{label} NORMAL"),
                    Dimensions::Vec3,
                    &[DataType::F32],
                )?;
            }
            // Tangents are optional (MikkTSpace's replace them): a malformed accessor is a warning.
            let mut tangent_acc = primitive.get(&gltf::Semantic::Tangents);
            if let Some(a) = tangent_acc.clone() {
                let checked = self.check_accessor(
                    &a,
                    &format!("{label} TANGENT"),
                    Dimensions::Vec4,
                    &[DataType::F32],
                );
                if let Err(e) = checked {
                    self.warn(format!("{e}; its tangents are ignored"));
                    tangent_acc = None;
                }
            }
            // The texture coordinate set the material's textures name (one per material).
            let (material, mut uv_set) = self.material_slot(&primitive.material())?;
            if uv_set != 0 && primitive.get(&gltf::Semantic::TexCoords(uv_set)).is_none() {
                self.warn(format!(
                    "{label}: its material's textures read TEXCOORD_{uv_set}, which it lacks; TEXCOORD_0 is used"
                ));
                uv_set = 0;
            }
            // Vertex colours are optional: a malformed accessor is a warning.
            let mut color_acc = primitive.get(&gltf::Semantic::Colors(0));
            if let Some(a) = color_acc.clone() {
                let dims = if a.dimensions() == Dimensions::Vec3 {
                    Dimensions::Vec3
                } else {
                    Dimensions::Vec4
                };
                let checked = self.check_accessor(
                    &a,
                    &format!("{label} COLOR_0"),
                    dims,
                    &[DataType::F32, DataType::U8, DataType::U16],
                );
                if let Err(e) = checked {
                    self.warn(format!("{e}; its vertex colours are ignored"));
                    color_acc = None;
                }
            }
            let uv_acc = primitive.get(&gltf::Semantic::TexCoords(uv_set));
            if let Some(a) = &uv_acc {
                self.check_accessor(
                    a,
                    &format!("{label} TEXCOORD_{uv_set}"),
                    Dimensions::Vec2,
                    &[DataType::F32, DataType::U8, DataType::U16],
                )?;
            }
            if let Some(a) = primitive.indices() {
                self.check_accessor(
                    &a,
                    &format!("{label} indices"),
                    Dimensions::Scalar,
                    &[DataType::U8, DataType::U16, DataType::U32],
                )?;
            }

            // Bound the allocations below by the options before making them (a sparse accessor without a
            // buffer view can declare any count).
            let index_count = primitive.indices().map_or(pos_acc.count(), |a| a.count());
            let new_triangles = if mode == Mode::Triangles {
                index_count / 3
            } else {
                index_count.saturating_sub(2)
            };
            self.options.check_size(
                self.path,
                (self.world_positions.len() + pos_acc.count()) as u64,
                (self.scene.triangles.len() + new_triangles) as u64,
            )?;

            let buffers = self.buffers;
            let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let short = |what: &str| SceneError::InvalidAccessor {
                path: self.path.to_owned(),
                message: format!("{label} {what} cannot be read from its buffer"),
            };
            let mut positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| short("POSITION"))?
                .collect();
            let vertex_count = positions.len();
            let morph = self.morph_displacements(&primitive, &label, weights, vertex_count);
            for (p, d) in positions.iter_mut().zip(&morph.positions) {
                *p = (Vec3::from(*p) + Vec3::from(*d)).to_array();
            }
            let placement = self.placement(&primitive, &label, world_f64, joints, vertex_count);
            // A mirroring transform flips the winding (a skin: judged by its first vertex).
            let flip = placement.linear(0).determinant() < 0.0;
            let base = self.world_positions.len();
            if base + vertex_count > u32::MAX as usize {
                return Err(self.malformed("more than 2^32 vertices".to_owned()));
            }
            self.world_positions
                .extend(positions.iter().enumerate().map(|(i, &p)| {
                    placement
                        .matrix(i)
                        .transform_point3(Vec3::from(p).as_dvec3())
                        .to_array()
                }));

            let mut normals_added = false;
            if let Some(acc) = &normal_acc {
                if acc.count() == vertex_count {
                    let normals = reader.read_normals().ok_or_else(|| short("NORMAL"))?;
                    self.scene.normals.extend(normals.enumerate().map(|(i, n)| {
                        let n = Vec3::from(n) + morph.normal(i);
                        // A non-finite normal stays non-finite, so that validation skips its triangles.
                        if n.is_finite() {
                            (placement.normal_matrix(i) * n)
                                .normalize_or_zero()
                                .to_array()
                        } else {
                            n.to_array()
                        }
                    }));
                    if self.scene.normals.len() != base + vertex_count {
                        return Err(short("NORMAL"));
                    }
                    normals_added = true;
                    self.any_normals = true;
                } else {
                    self.warn(format!(
                        "{label}: {} normals for {vertex_count} positions; normals ignored",
                        acc.count()
                    ));
                }
            }
            if !normals_added {
                self.scene.normals.resize(base + vertex_count, [0.0; 3]);
            }
            // Tangents move with the mesh (the linear part of its transform); a mirroring transform
            // flips their handedness. Without normals glTF ignores them.
            let mut tangents_added = false;
            if let Some(acc) = tangent_acc.as_ref().filter(|_| normals_added) {
                if acc.count() == vertex_count {
                    let mirror = if flip { -1.0 } else { 1.0 };
                    let tangents: Vec<[f32; 4]> = reader
                        .read_tangents()
                        .ok_or_else(|| short("TANGENT"))?
                        .collect();
                    self.warn_about_tangents(&label, &tangents);
                    self.scene.tangents.resize(base, [0.0; 4]);
                    self.scene.tangents.extend(tangents.iter().enumerate().map(
                        |(i, &[x, y, z, w])| {
                            let t = (placement.linear(i) * (Vec3::new(x, y, z) + morph.tangent(i)))
                                .normalize_or_zero();
                            [t.x, t.y, t.z, w * mirror]
                        },
                    ));
                    if self.scene.tangents.len() != base + vertex_count {
                        return Err(short("TANGENT"));
                    }
                    tangents_added = true;
                } else {
                    self.warn(format!(
                        "{label}: {} tangents for {vertex_count} positions; ignored",
                        acc.count()
                    ));
                }
            }
            if !tangents_added && !self.scene.tangents.is_empty() {
                self.scene.tangents.resize(base + vertex_count, [0.0; 4]);
            }
            let mut uvs_added = false;
            if let Some(acc) = &uv_acc {
                if acc.count() == vertex_count {
                    let uvs = reader
                        .read_tex_coords(uv_set)
                        .ok_or_else(|| short(&format!("TEXCOORD_{uv_set}")))?
                        .into_f32();
                    self.scene.uvs.extend(uvs);
                    if self.scene.uvs.len() != base + vertex_count {
                        return Err(short(&format!("TEXCOORD_{uv_set}")));
                    }
                    uvs_added = true;
                    self.any_uvs = true;
                } else {
                    self.warn(format!(
                        "{label}: {} texture coordinates for {vertex_count} positions; ignored",
                        acc.count()
                    ));
                }
            }
            if !uvs_added {
                self.scene.uvs.resize(base + vertex_count, [0.0; 2]);
            }
            // Vertex colours multiply the base colour and its alpha (glTF 2.0 §3.7.2.1); the vertices
            // of primitives without them are white.
            let mut colors_added = false;
            if let Some(acc) = &color_acc {
                if acc.count() == vertex_count {
                    let colors = reader
                        .read_colors(0)
                        .ok_or_else(|| short("COLOR_0"))?
                        .into_rgba_f32();
                    self.scene.colors.resize(base, [1.0; 4]);
                    self.scene.colors.extend(colors);
                    if self.scene.colors.len() != base + vertex_count {
                        return Err(short("COLOR_0"));
                    }
                    let added = &mut self.scene.colors[base..];
                    let first_outside = added
                        .iter()
                        .find(|c| !c.iter().all(|x| (0.0..=1.0).contains(x)))
                        .copied();
                    let outside = crate::mesh::clamp_colors(added);
                    if let Some(first) = first_outside {
                        self.warn(format!(
                            "{label}: {outside} COLOR_0 values outside 0..1 (the first {first:?}); \
                             clamped to 0..1, NaN read as 1"
                        ));
                    }
                    colors_added = true;
                } else {
                    self.warn(format!(
                        "{label}: {} vertex colours for {vertex_count} positions; ignored",
                        acc.count()
                    ));
                }
            }
            if !colors_added && !self.scene.colors.is_empty() {
                self.scene.colors.resize(base + vertex_count, [1.0; 4]);
            }

            let indices: Vec<u32> = match reader.read_indices() {
                Some(r) => r.into_u32().collect(),
                None if primitive.indices().is_some() => return Err(short("indices")),
                None => (0..vertex_count as u32).collect(),
            };
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(SceneError::FaceIndexOutOfRange {
                    path: self.path.to_owned(),
                    message: format!(
                        "{label} uses vertex {bad} but has only {vertex_count} vertices"
                    ),
                });
            }
            let before = self.scene.triangles.len();
            let b = base as u32;
            let mut push = |t: [u32; 3]| {
                let t = if flip { [t[0], t[2], t[1]] } else { t };
                self.scene.triangles.push([t[0] + b, t[1] + b, t[2] + b]);
            };
            match mode {
                Mode::Triangles => {
                    if !indices.chunks_exact(3).remainder().is_empty() {
                        self.scene.warnings.push(format!(
                            "{}: {label} has {} indices, not a multiple of 3; the rest is ignored",
                            self.path.display(),
                            indices.len()
                        ));
                    }
                    for t in indices.chunks_exact(3) {
                        push([t[0], t[1], t[2]]);
                    }
                }
                Mode::TriangleStrip => {
                    for i in 0..indices.len().saturating_sub(2) {
                        if i % 2 == 0 {
                            push([indices[i], indices[i + 1], indices[i + 2]]);
                        } else {
                            push([indices[i + 1], indices[i], indices[i + 2]]);
                        }
                    }
                }
                _ => {
                    for i in 1..indices.len().saturating_sub(1) {
                        push([indices[0], indices[i], indices[i + 1]]);
                    }
                }
            }
            let added = self.scene.triangles.len() - before;
            self.scene
                .triangle_materials
                .resize(before + added, material);
        }
        Ok(())
    }

    /// Warns about the file's `TANGENT` values of primitive `label` that break the spec (glTF 2.0
    /// §3.7.2.1: a unit `xyz` and a `w` of ±1), naming what fovea uses instead: a zero or non-finite
    /// `xyz` is no tangent (MikkTSpace makes one where a material needs it), and a `w` other than ±1 is
    /// read by its sign (-1 below 0, +1 otherwise, NaN and 0 included).
    fn warn_about_tangents(&mut self, label: &str, tangents: &[[f32; 4]]) {
        let unusable = |t: &&[f32; 4]| {
            let xyz = Vec3::new(t[0], t[1], t[2]);
            !xyz.is_finite() || xyz == Vec3::ZERO
        };
        let bad_w = |t: &&[f32; 4]| t[3] != 1.0 && t[3] != -1.0;
        if let Some(first) = tangents.iter().find(unusable) {
            let n = tangents.iter().filter(unusable).count();
            self.warn(format!(
                "{label}: {n} TANGENT values have a zero or non-finite xyz (the first {first:?}); \
                 MikkTSpace's tangents are used where a material needs one"
            ));
        }
        if let Some(first) = tangents.iter().find(bad_w) {
            let n = tangents.iter().filter(bad_w).count();
            self.warn(format!(
                "{label}: {n} TANGENT w values are not 1 or -1 (the first {}); read as -1 below 0 \
                 and as 1 otherwise",
                first[3]
            ));
        }
    }

    /// The `scene.materials` index of a glTF material, converting it on first use, and the texture
    /// coordinate set its textures read.
    ///
    /// Long because it converts a glTF material field by field (core PBR, textures with their
    /// transforms, extensions, emission), each naming what it could not use.
    fn material_slot(&mut self, m: &gltf::Material) -> Result<(u32, u32), SceneError> {
        if let Some(&slot) = self.material_slots.get(&m.index()) {
            return Ok(slot);
        }
        let label = match (m.index(), m.name()) {
            (Some(i), Some(n)) => format!("material {i} ({n})"),
            (Some(i), None) => format!("material {i}"),
            (None, _) => "the default material".to_owned(),
        };
        let pbr = m.pbr_metallic_roughness();
        let mut out = Material {
            base_color: pbr.base_color_factor(),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            specular: 0.5,
            ..Material::default()
        };
        let mut strength = m.emissive_strength().unwrap_or(1.0);
        if strength < 0.0 {
            // The extension's range is [0, ∞); clamped as the material check clamps (`mesh`).
            self.warn(format!(
                "{label}: KHR_materials_emissive_strength.emissiveStrength {strength} is negative (used 0)"
            ));
            strength = 0.0;
        }
        let e = Vec3::from(m.emissive_factor()) * strength;
        out.emission = [e.x, e.y, e.z, 0.0];
        match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => {}
            gltf::material::AlphaMode::Mask => {
                out.flags |= MATERIAL_ALPHA_CUTOUT;
                out.alpha_cutoff = m.alpha_cutoff().unwrap_or(0.5);
            }
            gltf::material::AlphaMode::Blend => {
                out.flags |= MATERIAL_ALPHA_CUTOUT;
                out.alpha_cutoff = 0.5;
                self.warn(format!(
                    "{label} uses alpha BLEND; approximated by a cut-out at 0.5"
                ));
            }
        }
        if m.double_sided() {
            out.flags |= MATERIAL_DOUBLE_SIDED_EMISSION;
        }
        // The texture coordinate set of each texture read, (role, set), to choose the material's one.
        let mut sets: Vec<(&'static str, u32)> = Vec::new();
        let mut read = |this: &mut Self,
                        role: &'static str,
                        texture: &gltf::Texture,
                        tex_coord: u32,
                        extensions: Option<&serde_json::Map<String, gltf::json::Value>>,
                        srgb: bool|
         -> Result<u32, SceneError> {
            let mut replaced = Vec::new();
            let transform = crate::gltf_pbr::texture_transform(extensions, &mut replaced);
            for what in replaced {
                this.warn(format!("{label} {role}: KHR_texture_transform {what}"));
            }
            sets.push((
                role,
                crate::gltf_pbr::coordinate_set(tex_coord, transform.as_ref()),
            ));
            this.texture_slot(&label, role, texture, transform, srgb)
        };
        if let Some(info) = pbr.base_color_texture() {
            out.base_color_texture = read(
                self,
                "baseColorTexture",
                &info.texture(),
                info.tex_coord(),
                info.extensions(),
                true,
            )?;
        }
        if let Some(info) = pbr.metallic_roughness_texture() {
            out.metallic_roughness_texture = read(
                self,
                "metallicRoughnessTexture",
                &info.texture(),
                info.tex_coord(),
                info.extensions(),
                false,
            )?;
        }
        if let Some(info) = m.normal_texture() {
            out.normal_texture = read(
                self,
                "normalTexture",
                &info.texture(),
                info.tex_coord(),
                info.extensions(),
                false,
            )?;
            out.normal_scale = info.scale();
        }
        if let Some(info) = m.emissive_texture() {
            out.emission_texture = read(
                self,
                "emissiveTexture",
                &info.texture(),
                info.tex_coord(),
                info.extensions(),
                true,
            )?;
        }
        // The PBR extensions, after the textures (unlit emits the base colour texture).
        let name = m.name().map_or_else(|| label.clone(), str::to_owned);
        let applied = m
            .extensions()
            .map(|e| crate::gltf_pbr::apply_material_extensions(e, &mut out))
            .unwrap_or_default();
        let mut notes = applied.unsupported;
        for note in applied.replaced {
            self.replaced
                .entry((note.extension, note.what))
                .or_default()
                .push(name.clone());
        }
        for t in &applied.textures {
            let Some(texture) = self.document.textures().nth(t.index) else {
                return Err(self.malformed(format!(
                    "{label} {} names texture {}, but the file has {}",
                    t.role,
                    t.index,
                    self.document.textures().len()
                )));
            };
            sets.push((
                t.role,
                crate::gltf_pbr::coordinate_set(t.tex_coord, t.transform.as_ref()),
            ));
            *t.slot.field(&mut out) =
                self.texture_slot(&label, t.role, &texture, t.transform, t.slot.srgb())?;
        }
        // One texture coordinate set per material: the one its textures name, or (if they disagree)
        // the base colour's, with a warning.
        let uv_set = sets.first().map_or(0, |&(_, set)| set);
        if let Some(&(role, other)) = sets.iter().find(|&&(_, set)| set != uv_set) {
            notes.push(crate::gltf_pbr::Unsupported {
                extension: "glTF texCoord".to_owned(),
                what: format!(
                    "textures name different coordinate sets ({} TEXCOORD_{uv_set}, {role} TEXCOORD_{other}); \
                     fovea reads one set per material and uses TEXCOORD_{uv_set}",
                    sets[0].0
                ),
            });
        }
        for note in notes {
            self.unsupported
                .entry((note.extension, note.what))
                .or_default()
                .push(name.clone());
        }
        let slot = self.scene.materials.len() as u32;
        self.scene.materials.push(out);
        self.scene.material_names.push(match (m.index(), m.name()) {
            (_, Some(n)) => n.to_owned(),
            (Some(i), None) => format!("material {i}"),
            (None, None) => "default".to_owned(),
        });
        self.material_slots.insert(m.index(), (slot, uv_set));
        Ok((slot, uv_set))
    }

    /// The `scene.textures` index of a texture's image decoded with `srgb`, or `INVALID_INDEX` if its
    /// file is missing (with a warning).
    fn texture_slot(
        &mut self,
        material: &str,
        role: &str,
        texture: &gltf::Texture,
        transform: Option<crate::gltf_pbr::TextureTransform>,
        srgb: bool,
    ) -> Result<u32, SceneError> {
        let image = texture.source();
        let sampler = sampler_bits(&texture.sampler());
        let transform = transform.map(|t| t.matrix);
        let key = (
            image.index(),
            srgb,
            sampler,
            transform.map(|m| m.map(f32::to_bits)),
        );
        if let Some(&slot) = self.texture_slots.get(&key) {
            return Ok(slot);
        }
        let embedded_name = match image.name() {
            Some(n) => format!("{}#image{} ({n})", self.path.display(), image.index()),
            None => format!("{}#image{}", self.path.display(), image.index()),
        };
        let decoded = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let data = &self.buffers[view.buffer().index()];
                let end = view.offset() as u64 + view.length() as u64;
                if end > data.len() as u64 {
                    return Err(SceneError::BufferTooShort {
                        path: self.path.to_owned(),
                        what: format!("image {} (buffer view {})", image.index(), view.index()),
                        needed: end,
                        available: data.len() as u64,
                    });
                }
                Some(decode_texture_bytes(
                    &data[view.offset()..end as usize],
                    &embedded_name,
                    srgb,
                    &self.limits,
                )?)
            }
            gltf::image::Source::Uri { uri, .. } if is_data_uri(uri) => {
                let bytes = read_uri(self.source, self.path, &self.base, uri)?;
                Some(decode_texture_bytes(
                    &bytes,
                    &embedded_name,
                    srgb,
                    &self.limits,
                )?)
            }
            gltf::image::Source::Uri { uri, .. } => {
                let file = uri_path(&self.base, uri);
                match load_texture_from(
                    self.source,
                    &file,
                    TextureRole::Color { srgb },
                    &self.limits,
                ) {
                    Ok(t) => Some(t),
                    Err(SceneError::MissingFile { path }) => {
                        self.warn(format!(
                            "{material} {role}: image file {} not found; using the factor only",
                            path.display()
                        ));
                        None
                    }
                    Err(e) => return Err(e),
                }
            }
        };
        let slot = match decoded {
            Some(mut t) => {
                t.sampler = sampler;
                t.transform = transform;
                self.scene.textures.push(t);
                (self.scene.textures.len() - 1) as u32
            }
            None => INVALID_INDEX,
        };
        self.texture_slots.insert(key, slot);
        Ok(slot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_scene;

    /// The scenes the repository bundles.
    fn scenes() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets")
    }

    fn load(rel: &str) -> LoadedScene {
        load_scene(&scenes().join(rel), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fovea_gltf_test_{}_{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn cornell_box_gltf() {
        let s = load("cornell_box_gltf/cornell_box.gltf");
        assert_eq!(s.triangle_count(), 36);
        assert_eq!(s.normals.len(), s.positions.len());
        let emissive: Vec<&Material> = s.materials.iter().filter(|m| m.is_emissive()).collect();
        assert_eq!(emissive.len(), 1);
        let e = emissive[0].emission;
        assert!(
            (e[0] - 17.0).abs() < 0.05 && (e[1] - 12.0).abs() < 0.05 && (e[2] - 4.0).abs() < 0.05,
            "{e:?}"
        );
        assert_eq!(s.emissive_triangle_count(), 2);
        // The file has no camera node.
        let json =
            std::fs::read_to_string(scenes().join("cornell_box_gltf/cornell_box.gltf")).unwrap();
        assert_eq!(s.camera.is_some(), json.contains("\"cameras\""));
        // The light quad faces down (-Y) with counter-clockwise winding.
        let light_tri = s
            .triangles
            .iter()
            .zip(&s.triangle_materials)
            .find(|(_, &m)| s.materials[m as usize].is_emissive())
            .unwrap()
            .0;
        let p = light_tri.map(|v| Vec3::from(s.positions[v as usize]));
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        assert!(n.y < 0.0, "{n}");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!(s.punctual_lights.is_empty());
    }

    #[test]
    fn cornell_stiff_gltf_materials() {
        let s = load("cornell_stiff/cornell_stiff.gltf");
        assert_eq!(s.triangle_count(), 36);
        let light = s.materials.iter().find(|m| m.is_emissive()).unwrap();
        assert!(
            (light.emission[0] - 1700.0).abs() < 1.0,
            "{:?}",
            light.emission
        );
        let metals: Vec<&Material> = s.materials.iter().filter(|m| m.metallic == 1.0).collect();
        assert_eq!(metals.len(), 2);
        assert!(metals
            .iter()
            .all(|m| m.roughness < 0.05 && m.specular == 0.5));
    }

    #[test]
    fn glb_files() {
        let s = load("dark_cornell_pema99/DarkCornell.glb");
        assert_eq!(s.triangle_count(), 184);
        assert_eq!(s.emissive_triangle_count(), 2);
        let s = load("emissive_triangle_kajiya/triangle.glb");
        assert_eq!(s.triangle_count(), 1);
        assert_eq!(s.emissive_triangle_count(), 1);
    }

    #[test]
    fn veach_mis_applies_node_scale() {
        let s = load("veach_mis_pema99/VeachMIS.glb");
        assert_eq!(s.triangle_count(), 2932);
        assert!(s.camera.is_none() && s.punctual_lights.is_empty());
        // The three emissive spheres share one material and are 960 consecutive triangles each; measure
        // each sphere's radius from its vertices.
        let emissive: Vec<[u32; 3]> = s
            .triangles
            .iter()
            .zip(&s.triangle_materials)
            .filter(|(_, &m)| s.materials[m as usize].is_emissive())
            .map(|(t, _)| *t)
            .collect();
        assert_eq!(emissive.len(), 3 * 960);
        let groups: Vec<Vec<u32>> = emissive
            .chunks(960)
            .map(|c| c.iter().flatten().copied().collect())
            .collect();
        let mut radii: Vec<f32> = groups
            .iter()
            .map(|g| {
                let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
                for &v in g {
                    let p = Vec3::from(s.positions[v as usize]);
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                (hi - lo).max_element() * 0.5
            })
            .collect();
        radii.sort_by(f32::total_cmp);
        assert!((radii[0] - 0.05).abs() < 0.01, "{radii:?}");
        assert!((radii[1] - 0.5).abs() < 0.05, "{radii:?}");
        assert!((radii[2] - 1.0).abs() < 0.1, "{radii:?}");
        // Normals were transformed and are unit length.
        let n = Vec3::from(s.normals[s.triangles[0][0] as usize]);
        assert!((n.length() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn roughness_scale_textures() {
        let s = load("roughness_scale_kajiya/scene.gltf");
        assert_eq!(s.triangle_count(), 51_200);
        assert_eq!(s.textures.len(), 5);
        assert!(s
            .textures
            .iter()
            .all(|t| t.width == 1 && t.height == 1 && t.texels.len() == 1));
        assert!(!s.uvs.is_empty());
        let textured = s
            .materials
            .iter()
            .filter(|m| {
                m.metallic_roughness_texture != INVALID_INDEX
                    || m.base_color_texture != INVALID_INDEX
            })
            .count();
        assert!(textured >= 5);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// Every numeric field of the mapped material extensions, at values inside its specification
    /// (extremes included), reaches the material of a whole load as the extension layer made it: no
    /// later layer (the material sanitiser, packing's preparation) changes it, and nothing is warned
    /// about. `ior: 0` and diamond's 2.4 used to leave the loader clamped to a specular of 1.
    #[test]
    fn extension_values_inside_the_spec_reach_the_material_unchanged() {
        use crate::load::load_scene_from;
        use crate::source::MemoryFiles;
        let cases = [
            r#"{"KHR_materials_ior":{"ior":0}}"#,
            r#"{"KHR_materials_ior":{"ior":1}}"#,
            r#"{"KHR_materials_ior":{"ior":2.4}}"#,
            r#"{"KHR_materials_ior":{"ior":10}}"#,
            r#"{"KHR_materials_specular":{"specularFactor":0.3,"specularColorFactor":[1,0.5,0.2]}}"#,
            r#"{"KHR_materials_specular":{"specularFactor":1},"KHR_materials_ior":{"ior":3}}"#,
            // The spec bounds specularColorFactor below only.
            r#"{"KHR_materials_specular":{"specularColorFactor":[2,1.5,1]}}"#,
            r#"{"KHR_materials_transmission":{"transmissionFactor":1},"KHR_materials_ior":{"ior":1.33}}"#,
            r#"{"KHR_materials_transmission":{"transmissionFactor":0.4},"KHR_materials_volume":{"thicknessFactor":2,"attenuationDistance":0.5,"attenuationColor":[1,0.2,0.1]}}"#,
            r#"{"KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatRoughnessFactor":0}}"#,
            r#"{"KHR_materials_clearcoat":{"clearcoatFactor":0.3,"clearcoatRoughnessFactor":1}}"#,
            r#"{"KHR_materials_sheen":{"sheenColorFactor":[1,1,1]}}"#,
            r#"{"KHR_materials_sheen":{"sheenColorFactor":[0.2,0.4,0.6],"sheenRoughnessFactor":0}}"#,
            r#"{"KHR_materials_anisotropy":{"anisotropyStrength":1}}"#,
            r#"{"KHR_materials_anisotropy":{"anisotropyStrength":0.25,"anisotropyRotation":0}}"#,
            r#"{"KHR_materials_unlit":{}}"#,
        ];
        let load = |extensions: Option<&str>| {
            let base = triangle_gltf(TRI, None, "");
            let json = match extensions {
                None => base,
                Some(ext) => {
                    let map: serde_json::Map<String, serde_json::Value> =
                        serde_json::from_str(ext).unwrap();
                    let used: Vec<&String> = map.keys().collect();
                    base.replacen(
                        r#""emissiveFactor":[1,1,1]}"#,
                        &format!(r#""emissiveFactor":[1,1,1],"extensions":{ext}}}"#),
                        1,
                    )
                    .replacen(
                        r#"{"asset""#,
                        &format!(
                            r#"{{"extensionsUsed":{},"asset""#,
                            serde_json::to_string(&used).unwrap()
                        ),
                        1,
                    )
                }
            };
            let files = MemoryFiles::new().with("d/e.gltf", json);
            load_scene_from(&files, Path::new("d/e.gltf"), &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{extensions:?}: {e}"))
        };
        let base = load(None).materials[0];
        for ext in cases {
            let s = load(Some(ext));
            assert!(s.warnings.is_empty(), "{ext}: {:?}", s.warnings);
            let map: serde_json::Map<String, serde_json::Value> =
                serde_json::from_str(ext).unwrap();
            let mut expected = base;
            let applied = crate::gltf_pbr::apply_material_extensions(&map, &mut expected);
            assert!(applied.unsupported.is_empty(), "{ext}");
            assert_eq!(s.materials[0], expected, "{ext}");
        }
        // emissiveStrength (the loader's, not the extension layer's) multiplies the emission.
        for strength in [0.0f32, 5.0, 1000.0] {
            let ext = format!(
                r#"{{"KHR_materials_emissive_strength":{{"emissiveStrength":{strength}}}}}"#
            );
            let s = load(Some(&ext));
            assert!(s.warnings.is_empty(), "{ext}: {:?}", s.warnings);
            let mut expected = base;
            for c in &mut expected.emission[..3] {
                *c *= strength;
            }
            assert_eq!(s.materials[0], expected, "{ext}");
        }
        // A value fovea does not read is named, with what it does instead.
        for (ext, field) in [
            (
                r#"{"KHR_materials_sheen":{"sheenColorFactor":[1,1,1],"sheenRoughnessFactor":0.5}}"#,
                "sheenRoughnessFactor",
            ),
            (
                r#"{"KHR_materials_anisotropy":{"anisotropyStrength":1,"anisotropyRotation":6.0}}"#,
                "anisotropyRotation",
            ),
        ] {
            let s = load(Some(ext));
            assert!(
                s.warnings.len() == 1 && s.warnings[0].contains(field),
                "{:?}",
                s.warnings
            );
        }
        // What the renderer gets: diamond's F0 of 0.17 (specular 2.1) and the infinite index's 1.
        let specular = |ext| load(Some(ext)).materials[0].specular;
        assert!((specular(cases[2]) - (1.4f32 / 3.4).powi(2) / 0.08).abs() < 1e-5);
        assert_eq!(specular(cases[0]), fovea_core::bsdf::disney::SPECULAR_MAX);
    }

    /// A minimal glTF with one triangle in a base64 buffer, optionally with a texture at `image_uri`.
    fn triangle_gltf(
        positions: [[f32; 3]; 3],
        image_uri: Option<&str>,
        node_extra: &str,
    ) -> String {
        let mut bytes = Vec::new();
        for p in positions {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        let b64 = base64_encode(&bytes);
        let (images, textures, mat_tex) = match image_uri {
            Some(uri) => (
                format!(r#","images":[{{"uri":"{uri}"}}]"#),
                r#","textures":[{"source":0}]"#.to_owned(),
                r#","baseColorTexture":{"index":0}"#.to_owned(),
            ),
            None => (String::new(), String::new(), String::new()),
        };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{{"mesh":0{node_extra}}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],
            "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.25,1]{mat_tex}}},"emissiveFactor":[1,1,1]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]{images}{textures}}}"#
        )
    }

    fn base64_encode(data: &[u8]) -> String {
        const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for c in data.chunks(3) {
            let n = (u32::from(c[0]) << 16)
                | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
                | u32::from(*c.get(2).unwrap_or(&0));
            out.push(T[(n >> 18) as usize & 63] as char);
            out.push(T[(n >> 12) as usize & 63] as char);
            out.push(if c.len() > 1 {
                T[(n >> 6) as usize & 63] as char
            } else {
                '='
            });
            out.push(if c.len() > 2 {
                T[n as usize & 63] as char
            } else {
                '='
            });
        }
        out
    }

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    /// The first triangle's vertices, sorted by x, then y, then z (loading may reorder them).
    fn first_triangle_sorted(s: &LoadedScene) -> Vec<Vec3> {
        let mut v: Vec<Vec3> = s.triangles[0]
            .iter()
            .map(|&i| Vec3::from(s.positions[i as usize]))
            .collect();
        v.sort_by(|a, b| {
            a.x.total_cmp(&b.x)
                .then(a.y.total_cmp(&b.y))
                .then(a.z.total_cmp(&b.z))
        });
        v
    }

    /// A skinned triangle is posed by its joints' world transforms, its own node's transform ignored
    /// (glTF 2.0 §3.7.3): vertex 0 follows joint 0 (5 up), vertex 1 half of it, vertex 2 joint 1
    /// (which stays put).
    #[test]
    fn skins_are_posed_by_their_joints() {
        let mut bytes = Vec::new();
        for p in TRI {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for j in [[0u16, 0, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0]] {
            for c in j {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for w in [
            [1.0f32, 0.0, 0.0, 0.0],
            [0.5, 0.5, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
        ] {
            for c in w {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        let b64 = base64_encode(&bytes);
        let gltf = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1,2]}}],
            "nodes":[{{"mesh":0,"skin":0,"translation":[100,0,0]}},{{"translation":[0,5,0]}},{{}}],
            "skins":[{{"joints":[1,2]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"JOINTS_0":1,"WEIGHTS_0":2}}}}]}}],
            "accessors":[
                {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                {{"bufferView":0,"byteOffset":36,"componentType":5123,"count":3,"type":"VEC4"}},
                {{"bufferView":0,"byteOffset":60,"componentType":5126,"count":3,"type":"VEC4"}}],
            "bufferViews":[{{"buffer":0,"byteLength":108}}],
            "buffers":[{{"byteLength":108,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
        );
        let dir = temp_dir("skin");
        let file = dir.join("s.gltf");
        std::fs::write(&file, gltf).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert_eq!(
            first_triangle_sorted(&s),
            [
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 5.0, 0.0),
                Vec3::new(1.0, 2.5, 0.0)
            ],
            "{:?}",
            s.warnings
        );
        std::fs::remove_dir_all(dir).ok();
    }

    /// A triangle with two morph targets (target 0 lifts vertex 2 by 2 in z, target 1 moves vertex 1
    /// by 4 in y), the mesh's default weights 0.5 and 0.25, `node_extra` added to the node, and
    /// `extra` (more top-level members) added to the file.
    fn morphed_triangle_gltf(node_extra: &str, extra: &str) -> String {
        let mut bytes = Vec::new();
        let mut push = |v: [[f32; 3]; 3]| {
            for p in v {
                for c in p {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
        };
        push(TRI);
        push([[0.0; 3], [0.0; 3], [0.0, 0.0, 2.0]]);
        push([[0.0; 3], [0.0, 4.0, 0.0], [0.0; 3]]);
        let b64 = base64_encode(&bytes);
        let accessor = |offset: u32, max: &str| {
            format!(
                r#"{{"bufferView":0,"byteOffset":{offset},"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":{max}}}"#
            )
        };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{{"mesh":0{node_extra}}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},
                "targets":[{{"POSITION":1}},{{"POSITION":2}}]}}],"weights":[0.5,0.25]}}],
            "accessors":[{a0},{a1},{a2},{{"bufferView":0,"componentType":5126,"count":3,"type":"SCALAR","min":[0],"max":[1]}}],
            "bufferViews":[{{"buffer":0,"byteLength":108}}],
            "buffers":[{{"byteLength":108,"uri":"data:application/octet-stream;base64,{b64}"}}]{extra}}}"#,
            a0 = accessor(0, "[1,1,0]"),
            a1 = accessor(36, "[0,0,2]"),
            a2 = accessor(72, "[0,4,0]"),
        )
    }

    /// `COLOR_0` as the spec allows it (normalised unsigned bytes RGBA, normalised unsigned shorts RGB
    /// with a byte stride, floats RGB), each vertex's colour read in order; float values outside 0..1
    /// clamped with a warning naming the primitive (NaN read as 1); a primitive without colours white.
    /// A scene whose colours are all white packs none.
    #[test]
    fn vertex_colours_are_read_in_every_format_the_spec_allows() {
        use fovea_core::scene::Features as _;
        let mut bytes = Vec::new();
        for p in TRI {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        // 36..48: RGBA8.
        bytes.extend_from_slice(&[255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0]);
        // 48..72: RGB16, each element padded to 8 bytes (byteStride 8).
        for rgb in [[65535u16, 32768, 0], [0, 65535, 1], [0, 0, 65535]] {
            for c in rgb {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
            bytes.extend_from_slice(&[0, 0]);
        }
        // 72..108: float RGB, out of range in two vertices.
        for rgb in [[2.0f32, 0.5, -1.0], [f32::NAN, 0.25, 1.0], [0.5, 0.5, 0.5]] {
            for c in rgb {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        let b64 = base64_encode(&bytes);
        let gltf = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[
                {{"attributes":{{"POSITION":0,"COLOR_0":1}}}},
                {{"attributes":{{"POSITION":0,"COLOR_0":2}}}},
                {{"attributes":{{"POSITION":0,"COLOR_0":3}}}},
                {{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[
                {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                {{"bufferView":0,"byteOffset":36,"componentType":5121,"normalized":true,"count":3,"type":"VEC4"}},
                {{"bufferView":1,"componentType":5123,"normalized":true,"count":3,"type":"VEC3"}},
                {{"bufferView":0,"byteOffset":72,"componentType":5126,"count":3,"type":"VEC3"}}],
            "bufferViews":[{{"buffer":0,"byteLength":108}},{{"buffer":0,"byteOffset":48,"byteLength":24,"byteStride":8}}],
            "buffers":[{{"byteLength":108,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
        );
        let dir = temp_dir("vertex-colours");
        let file = dir.join("c.gltf");
        std::fs::write(&file, gltf).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert_eq!(s.colors.len(), s.positions.len());
        // Triangle k is primitive k; its colours by vertex (TRI order).
        let colours_of = |k: usize| -> Vec<[f32; 4]> {
            let mut by_vertex: Vec<([f32; 3], [f32; 4])> = s.triangles[k]
                .iter()
                .map(|&v| (s.positions[v as usize], s.colors[v as usize]))
                .collect();
            by_vertex.sort_by_key(|(p, _)| TRI.iter().position(|t| t == p));
            by_vertex.into_iter().map(|(_, c)| c).collect()
        };
        let b = |n: u32| n as f32 / 255.0;
        let h = |n: u32| n as f32 / 65535.0;
        assert_eq!(
            colours_of(0),
            [
                [1.0, 0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0, b(128)],
                [0.0, 0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(
            colours_of(1),
            [
                [1.0, h(32768), 0.0, 1.0],
                [0.0, 1.0, h(1), 1.0],
                [0.0, 0.0, 1.0, 1.0]
            ]
        );
        assert_eq!(
            colours_of(2),
            [
                [1.0, 0.5, 0.0, 1.0],
                [1.0, 0.25, 1.0, 1.0],
                [0.5, 0.5, 0.5, 1.0]
            ]
        );
        assert_eq!(colours_of(3), [[1.0; 4]; 3]);
        let clamped: Vec<&String> = s
            .warnings
            .iter()
            .filter(|w| w.contains("COLOR_0 values outside 0..1"))
            .collect();
        assert!(
            clamped.len() == 1 && clamped[0].contains("mesh 0 primitive 2: 2 COLOR_0"),
            "{:?}",
            s.warnings
        );

        let packed = crate::pack::pack_scene(
            s,
            &crate::environment::Environment::None,
            &crate::bvh::BvhBuildOptions::default(),
        );
        assert!(packed
            .features()
            .has(fovea_core::scene::features::FEATURE_VERTEX_COLORS));
        let mut white = load_scene(&file, &LoadOptions::default()).unwrap();
        white.colors.iter_mut().for_each(|c| *c = [1.0; 4]);
        let packed = crate::pack::pack_scene(
            white,
            &crate::environment::Environment::None,
            &crate::bvh::BvhBuildOptions::default(),
        );
        assert!(packed.geometry.vertex_colors.is_empty());
        assert!(!packed
            .features()
            .has(fovea_core::scene::features::FEATURE_VERTEX_COLORS));
        std::fs::remove_dir_all(dir).ok();
    }

    /// Morph targets move the vertices by their default weights (the mesh's, or the node's, which
    /// override them), as glTF 2.0 §3.7.2.2 says; animations, not read, are warned about.
    #[test]
    fn morph_targets_apply_their_default_weights_and_what_is_not_read_is_named() {
        let dir = temp_dir("morph");
        let file = dir.join("m.gltf");
        let load = |node_extra: &str, extra: &str| {
            std::fs::write(&file, morphed_triangle_gltf(node_extra, extra)).unwrap();
            load_scene(&file, &LoadOptions::default()).unwrap()
        };
        let s = load("", "");
        // The mesh's weights: vertex 1 up by 0.25 · 4, vertex 2 up by 0.5 · 2 (z).
        assert_eq!(
            first_triangle_sorted(&s),
            [
                Vec3::ZERO,
                Vec3::new(0.0, 1.0, 1.0),
                Vec3::new(1.0, 1.0, 0.0)
            ],
            "{:?}",
            s.positions
        );
        // The node's weights override them.
        let s = load(r#","weights":[1,0]"#, "");
        assert_eq!(
            first_triangle_sorted(&s),
            [
                Vec3::ZERO,
                Vec3::new(0.0, 1.0, 2.0),
                Vec3::new(1.0, 0.0, 0.0)
            ]
        );
        // Too few weights: the missing one is 0, with a warning.
        let s = load(r#","weights":[1]"#, "");
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("2 morph targets but 1 weights")),
            "{:?}",
            s.warnings
        );
        // An animation is named, not dropped in silence.
        let animated = load(
            "",
            r#","animations":[{"channels":[{"sampler":0,"target":{"node":0,"path":"translation"}}],
                "samplers":[{"input":3,"output":0}]}]"#,
        );
        assert!(
            animated
                .warnings
                .iter()
                .any(|w| w.contains("1 animation(s) are not played")),
            "{:?}",
            animated.warnings
        );
        // A skin without JOINTS_0 and WEIGHTS_0 is named: its mesh stays where its node puts it.
        let skinned = load(r#","skin":0"#, r#","skins":[{"joints":[0]}]"#);
        assert!(
            skinned.warnings.iter().any(|w| w.contains("skinned")),
            "{:?}",
            skinned.warnings
        );
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn minimal_gltf_with_mirror_transform_flips_winding() {
        let dir = temp_dir("mirror");
        let file = dir.join("t.gltf");
        std::fs::write(&file, triangle_gltf(TRI, None, r#","scale":[-1,1,1]"#)).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert_eq!(s.triangle_count(), 1);
        let p = s.triangles[0].map(|v| Vec3::from(s.positions[v as usize]));
        // Mirrored in x: the original normal +Z must be kept by flipping the winding.
        assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0);
        assert!(s.positions.iter().any(|p| p[0] == -1.0));
        assert_eq!(s.materials[0].base_color, [1.0, 0.5, 0.25, 1.0]);
        assert!(s.normals.is_empty() && s.uvs.is_empty());
        std::fs::remove_dir_all(dir).ok();
    }

    /// `TANGENT` moves with the node's transform, and a mirroring one flips its handedness (the
    /// bitangent `w (n × t)` must follow the mirrored surface); a malformed accessor is a warning.
    #[test]
    fn tangents_follow_the_node_transform_and_mirrors_flip_their_handedness() {
        let dir = temp_dir("tangents");
        let file = dir.join("t.gltf");
        let mut bytes = Vec::new();
        let floats: Vec<f32> = [
            TRI.concat(),
            [0.0, 0.0, 1.0].repeat(3),
            [0.0, 1.0, 0.0, 1.0].repeat(3),
        ]
        .concat();
        for f in floats {
            bytes.extend_from_slice(&f.to_le_bytes());
        }
        let gltf = |node: &str, tangent_type: &str| {
            format!(
                r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
                "nodes":[{{"mesh":0{node}}}],
                "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TANGENT":2}}}}]}}],
                "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                    {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},
                    {{"bufferView":2,"componentType":5126,"count":3,"type":"{tangent_type}"}}],
                "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},
                    {{"buffer":0,"byteOffset":72,"byteLength":48}}],
                "buffers":[{{"byteLength":120,"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
                base64_encode(&bytes)
            )
        };
        for (node, want) in [
            ("", [0.0, 1.0, 0.0, 1.0]),
            // A quarter turn about z: the tangent turns with it.
            (
                r#","rotation":[0,0,0.70710678,0.70710678]"#,
                [-1.0, 0.0, 0.0, 1.0],
            ),
            // Mirrored in y: the tangent follows and the handedness flips.
            (r#","scale":[1,-1,1]"#, [0.0, -1.0, 0.0, -1.0]),
        ] {
            std::fs::write(&file, gltf(node, "VEC4")).unwrap();
            let s = load_scene(&file, &LoadOptions::default()).unwrap();
            for t in &s.tangents {
                for c in 0..4 {
                    assert!((t[c] - want[c]).abs() < 1e-6, "{node}: {t:?}");
                }
            }
            assert_eq!(s.tangents.len(), 3, "{node}");
        }
        // VEC3 tangents (a common exporter mistake): ignored with a warning, not an error.
        std::fs::write(&file, gltf("", "VEC3")).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert!(s.tangents.is_empty());
        assert!(
            s.warnings.iter().any(|w| w.contains("TANGENT")),
            "{:?}",
            s.warnings
        );
        // The spec's unit xyz and w of ±1 broken: each class named once, with what is used instead.
        std::fs::write(&file, gltf("", "VEC4")).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert!(
            s.warnings.iter().all(|w| !w.contains("TANGENT")),
            "{:?}",
            s.warnings
        );
        let mut broken = bytes.clone();
        let mut put = |float: usize, value: f32| {
            broken[4 * float..4 * float + 4].copy_from_slice(&value.to_le_bytes());
        };
        put(18 + 3, 0.0); // vertex 0: w = 0
        put(18 + 4, f32::NAN); // vertex 1: x = NaN
        put(18 + 11, 0.5); // vertex 2: w = 0.5
        let text = gltf("", "VEC4").replace(&base64_encode(&bytes), &base64_encode(&broken));
        std::fs::write(&file, text).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        let named = |what: &str| s.warnings.iter().filter(|w| w.contains(what)).count();
        assert_eq!(
            named(
                "1 TANGENT values have a zero or non-finite xyz (the first [NaN, 1.0, 0.0, 1.0])"
            ),
            1,
            "{:?}",
            s.warnings
        );
        assert_eq!(named("2 TANGENT w values are not 1 or -1 (the first 0)"), 1);
        assert_eq!(s.tangents[0], [0.0, 1.0, 0.0, 1.0]);
        assert_eq!(s.tangents[1], [0.0; 4]);
        std::fs::remove_dir_all(dir).ok();
    }

    /// Core material factors beyond single precision, which gltf reads as f32 (an overflow as
    /// infinity, an underflow as 0), are named with the file's number and what was read.
    #[test]
    fn core_factors_beyond_single_precision_are_named() {
        let dir = temp_dir("precision");
        let file = dir.join("p.gltf");
        let text = triangle_gltf(TRI, None, "")
            .replace(
                r#""baseColorFactor":[1,0.5,0.25,1]"#,
                r#""baseColorFactor":[1e39,0.5,0.25,1],"roughnessFactor":1e-50"#,
            )
            .replace(
                r#""emissiveFactor":[1,1,1]"#,
                r#""emissiveFactor":[2e-46,1,1]"#,
            );
        std::fs::write(&file, text).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        for want in [
            r#"materials[0] (""): pbrMetallicRoughness.baseColorFactor 1e39 is beyond single precision; read as inf"#,
            r#"materials[0] (""): pbrMetallicRoughness.roughnessFactor 1e-50 is beyond single precision; read as 0"#,
            r#"materials[0] (""): emissiveFactor 2e-46 is beyond single precision; read as 0"#,
        ] {
            assert_eq!(
                s.warnings.iter().filter(|w| w.ends_with(want)).count(),
                1,
                "{want}: {:?}",
                s.warnings
            );
        }
        // The infinite base colour is then replaced, with the material check's own warning.
        assert_eq!(s.materials[0].base_color[0], 0.8);
        assert!(s
            .warnings
            .iter()
            .any(|w| w.contains("base colour inf (used 0.8)")));
        // Numbers within single precision get no such warning.
        std::fs::write(&file, triangle_gltf(TRI, None, "")).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert!(
            s.warnings.iter().all(|w| !w.contains("single precision")),
            "{:?}",
            s.warnings
        );
        assert!(!may_exceed_f32(br#"{"a":[1.5e3,-2.25,100000]}"#));
        assert!(may_exceed_f32(br#"{"a":1e-50}"#) && may_exceed_f32(br#"{"a":3.5E+38}"#));
        assert!(!may_exceed_f32(br#"{"uri":"data:;base64,AAe45x\"e99"}"#));
        std::fs::remove_dir_all(dir).ok();
    }

    /// A negative `emissiveStrength` is named and clamped to 0, not multiplied into a negative emission.
    #[test]
    fn a_negative_emissive_strength_is_named_and_clamped() {
        let dir = temp_dir("strength");
        let file = dir.join("s.gltf");
        let text = triangle_gltf(TRI, None, "").replace(
            r#""emissiveFactor":[1,1,1]"#,
            r#""emissiveFactor":[1,1,1],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":-2.5}}"#,
        );
        std::fs::write(&file, text).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        let named: Vec<&String> = s
            .warnings
            .iter()
            .filter(|w| w.contains("emissiveStrength -2.5 is negative (used 0)"))
            .collect();
        assert_eq!(named.len(), 1, "{:?}", s.warnings);
        assert_eq!(s.materials[0].emission[..3], [0.0; 3]);
        // No second warning from the material check for the product.
        assert!(
            s.warnings.iter().all(|w| !w.contains("emission -")),
            "{:?}",
            s.warnings
        );
        std::fs::remove_dir_all(dir).ok();
    }

    /// Sampler values outside the spec's enums (which gltf's validation would refuse) are replaced by
    /// glTF's defaults, each named with the file's number and what is used.
    #[test]
    fn sampler_values_outside_the_spec_are_named_and_replaced() {
        let dir = temp_dir("samplers");
        let file = dir.join("s.gltf");
        let base = triangle_gltf(TRI, None, "");
        let with_samplers = format!(
            r#"{},"samplers":[{{"magFilter":1234,"minFilter":7,"wrapS":5,"wrapT":33648}}]}}"#,
            &base[..base.len() - 1]
        );
        std::fs::write(&file, with_samplers).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        for want in [
            "samplers[0].magFilter 1234 is not 9728 (NEAREST) or 9729 (LINEAR); linear magnification used",
            "samplers[0].minFilter 7 is not 9728, 9729 or 9984 to 9987; mip-mapped linear minification used",
            "samplers[0].wrapS 5 is not 33071 (CLAMP_TO_EDGE), 33648 (MIRRORED_REPEAT) or 10497 (REPEAT); REPEAT used",
        ] {
            assert_eq!(
                s.warnings.iter().filter(|w| w.ends_with(want)).count(),
                1,
                "{want}: {:?}",
                s.warnings
            );
        }
        assert!(
            s.warnings.iter().all(|w| !w.contains("wrapT")),
            "{:?}",
            s.warnings
        );
        std::fs::remove_dir_all(dir).ok();
    }

    /// One texture coordinate set per material: a primitive without the set its material's textures
    /// name falls back to TEXCOORD_0, and textures that name different sets are one warning.
    #[test]
    fn texture_coordinate_sets_are_chosen_per_material_with_warnings() {
        let dir = temp_dir("texcoord");
        let file = dir.join("t.gltf");
        let base = triangle_gltf(TRI, Some("missing.png"), "");
        let set1 = base.replace(
            r#""baseColorTexture":{"index":0}"#,
            r#""baseColorTexture":{"index":0,"texCoord":1}"#,
        );
        std::fs::write(&file, &set1).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        let all = s.warnings.join("\n");
        assert!(
            all.contains("read TEXCOORD_1, which it lacks; TEXCOORD_0 is used"),
            "{all}"
        );
        assert!(!all.contains("different coordinate sets"), "{all}");
        let mixed = set1.replace(
            r#""emissiveFactor":[1,1,1]"#,
            r#""emissiveFactor":[1,1,1],"emissiveTexture":{"index":0}"#,
        );
        std::fs::write(&file, mixed).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        let all = s.warnings.join("\n");
        assert!(
            all.contains("baseColorTexture TEXCOORD_1, emissiveTexture TEXCOORD_0")
                && all.contains("uses TEXCOORD_1"),
            "{all}"
        );
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn an_unsupported_optional_extension_is_warned_about_and_a_required_one_refused() {
        let dir = temp_dir("extensions");
        let file = dir.join("t.gltf");
        let base = triangle_gltf(TRI, None, "");
        let used = base.replace(
            r#""nodes":[{"mesh":0}]"#,
            r#""nodes":[{"mesh":0}],"extensionsUsed":["KHR_materials_iridescence"]"#,
        );
        std::fs::write(&file, used).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("KHR_materials_iridescence") && w.contains("not supported")),
            "{:?}",
            s.warnings
        );
        let required = base.replace(
            r#""nodes":[{"mesh":0}]"#,
            r#""nodes":[{"mesh":0}],"extensionsUsed":["KHR_materials_iridescence"],"extensionsRequired":["KHR_materials_iridescence"]"#,
        );
        std::fs::write(&file, required).unwrap();
        assert!(load_scene(&file, &LoadOptions::default()).is_err());
        // A required extension fovea maps loads.
        let mapped = base.replace(
            r#""nodes":[{"mesh":0}]"#,
            r#""nodes":[{"mesh":0}],"extensionsUsed":["KHR_materials_transmission"],"extensionsRequired":["KHR_materials_transmission"]"#,
        );
        std::fs::write(&file, mapped).unwrap();
        assert!(load_scene(&file, &LoadOptions::default()).is_ok());
        std::fs::remove_dir_all(dir).ok();
    }

    /// A scene whose root node sits 1e5 from the world origin loads with the coordinates, camera and
    /// lights it has at the origin, and `origin` says where it is (the f64 rebase, [`crate::rebase`]).
    #[test]
    fn a_scene_far_from_the_origin_is_rebased_with_its_camera_and_lights() {
        let dir = temp_dir("far");
        let file = dir.join("t.gltf");
        let json = |root: &str| {
            triangle_gltf(TRI, None, "").replace(
                r#""nodes":[{"mesh":0}]"#,
                &format!(
                    r#""nodes":[{{"mesh":0,"children":[1,2]{root}}},
                    {{"camera":0,"translation":[0.3,0.2,3]}},
                    {{"translation":[0.1,0.9,0.5],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
                    "cameras":[{{"type":"perspective","perspective":{{"yfov":0.7,"znear":0.1}}}}],
                    "extensionsUsed":["KHR_lights_punctual"],
                    "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":3}}]}}}}"#
                ),
            )
        };
        std::fs::write(&file, json("")).unwrap();
        let near = load_scene(&file, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&file, json(r#","translation":[100000,200000,-100000]"#)).unwrap();
        let far = load_scene(&file, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(near.origin, [0.0; 3]);
        assert_eq!(far.origin, [100000.0, 200000.0, -100000.0]);
        assert_eq!(far.positions, near.positions);
        assert_eq!(
            far.camera.expect("camera").position,
            near.camera.expect("camera").position
        );
        assert_eq!(
            far.punctual_lights[0].position,
            near.punctual_lights[0].position
        );
        // In f32 world coordinates the light's 0.1 would have been rounded to a multiple of 2^-7.
        assert_eq!(far.punctual_lights[0].position[0], 0.1);
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn camera_and_punctual_lights_follow_node_transforms() {
        let dir = temp_dir("camlight");
        let file = dir.join("t.gltf");
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let json = triangle_gltf(TRI, None, "")
            .replace(
                r#""nodes":[{"mesh":0}]"#,
                &format!(
                    r#""nodes":[{{"mesh":0,"children":[1,2,3]}},
                    {{"camera":0,"translation":[1,2,3],"rotation":[0,{h},0,{h}]}},
                    {{"translation":[0,5,0],"rotation":[-{h},0,0,{h}],
                      "extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},
                    {{"translation":[7,0,0],"scale":[2,2,2],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}}],
                    "cameras":[{{"type":"perspective","perspective":{{"yfov":0.7,"aspectRatio":1.5,"znear":0.1}}}}],
                    "extensionsUsed":["KHR_lights_punctual"],
                    "extensions":{{"KHR_lights_punctual":{{"lights":[
                      {{"type":"spot","color":[1,0.5,0.25],"intensity":10,"spot":{{"innerConeAngle":0.1,"outerConeAngle":0.5}}}},
                      {{"type":"point","intensity":3}}]}}}}"#
                ),
            );
        std::fs::write(&file, json).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let cam = s.camera.expect("camera");
        let close = |a: [f32; 3], b: [f32; 3]| (Vec3::from(a) - Vec3::from(b)).length() < 1e-5;
        assert!(close(cam.position, [1.0, 2.0, 3.0]), "{cam:?}");
        assert!(close(cam.forward, [-1.0, 0.0, 0.0]), "{cam:?}");
        assert!(close(cam.up, [0.0, 1.0, 0.0]), "{cam:?}");
        assert_eq!((cam.yfov_radians, cam.aspect_ratio), (0.7, Some(1.5)));
        assert_eq!(s.punctual_lights.len(), 2);
        let spot = &s.punctual_lights[0];
        assert_eq!(spot.kind, LIGHT_SPOT);
        assert!(close(
            [spot.position[0], spot.position[1], spot.position[2]],
            [0.0, 5.0, 0.0]
        ));
        assert!(close(
            [spot.direction[0], spot.direction[1], spot.direction[2]],
            [0.0, -1.0, 0.0]
        ));
        assert_eq!(&spot.intensity[..3], &[10.0, 5.0, 2.5]);
        assert!((spot.position[3] - 0.1f32.cos()).abs() < 1e-6);
        assert!((spot.intensity[3] - 0.5f32.cos()).abs() < 1e-6);
        assert_eq!(spot.pmf, 0.0);
        let point = &s.punctual_lights[1];
        assert_eq!(point.kind, LIGHT_POINT);
        assert!(close(
            [point.position[0], point.position[1], point.position[2]],
            [7.0, 0.0, 0.0]
        ));
        assert_eq!(&point.intensity[..3], &[3.0, 3.0, 3.0]);
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn missing_texture_is_a_warning() {
        let dir = temp_dir("missingtex");
        let file = dir.join("t.gltf");
        std::fs::write(&file, triangle_gltf(TRI, Some("no%20such.png"), "")).unwrap();
        let s = load_scene(&file, &LoadOptions::default()).unwrap();
        assert_eq!(s.triangle_count(), 1);
        assert!(s.textures.is_empty());
        assert_eq!(s.materials[0].base_color_texture, INVALID_INDEX);
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        assert!(s.warnings[0].contains("no such.png") && s.warnings[0].contains("t.gltf"));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn nan_vertex_is_skipped_and_counted() {
        let dir = temp_dir("nan");
        let file = dir.join("t.gltf");
        // Two triangles: the second primitive has a NaN vertex. Use one file with the NaN triangle only
        // and expect Empty; the OBJ test covers the mixed case.
        std::fs::write(
            &file,
            triangle_gltf(
                [[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                None,
                "",
            ),
        )
        .unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::Empty { .. }), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn malformed_gltf_errors() {
        let dir = temp_dir("malformed");
        let file = dir.join("bad.gltf");
        std::fs::write(
            &file,
            r#"{"asset":{"version":"2.0"}, "nodes": [ {"mesh": 0 "#,
        )
        .unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
        assert!(e.to_string().contains("bad.gltf"), "{e}");

        // The buffer's data is shorter than its byteLength.
        let full: Vec<u8> = TRI.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        let good = triangle_gltf(TRI, None, "");
        assert!(good.contains(&base64_encode(&full)));
        std::fs::write(
            &file,
            good.replace(&base64_encode(&full), &base64_encode(&full[..24])),
        )
        .unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::BufferTooShort { .. }), "{e}");
        assert!(e.to_string().contains("bad.gltf"), "{e}");
        // A consistent but too short buffer: the accessor reaches past the end of buffer and view.
        let short = good
            .replace(&base64_encode(&full), &base64_encode(&full[..24]))
            .replace(r#""byteLength":36"#, r#""byteLength":24"#);
        std::fs::write(&file, short).unwrap();
        let e = load_scene(&file, &LoadOptions::default()).unwrap_err();
        assert!(
            matches!(
                e,
                SceneError::BufferTooShort { .. } | SceneError::Gltf { .. }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("bad.gltf"), "{e}");

        let e = load_scene(&dir.join("absent.glb"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }

    /// Fuzz regression (gltf crash-0043fc3a): a POSITION attribute naming a missing accessor panicked
    /// inside gltf-json's validation.
    #[test]
    fn json_the_gltf_crate_panics_on_is_an_error_or_repaired() {
        use crate::load::load_scene_from;
        use crate::source::MemoryFiles;
        let json = r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":5}}]}]}"#;
        let files = MemoryFiles::new().with("d/p.gltf", json);
        let e =
            load_scene_from(&files, Path::new("d/p.gltf"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            "d/p.gltf: malformed glTF: meshes[0].primitives[0].attributes.POSITION: accessor 5 does \
             not exist (there are 0)"
        );
        // Fuzz regression (gltf crash-f2e47ac7): an image in a buffer view without a mimeType panicked
        // in gltf's Image::source; it is now decoded by content, with a warning. Neither uri nor view,
        // or a camera without its projection object, are errors.
        let png = {
            let mut out = std::io::Cursor::new(Vec::new());
            image::DynamicImage::ImageRgb8(image::RgbImage::new(1, 1))
                .write_to(&mut out, image::ImageFormat::Png)
                .unwrap();
            out.into_inner()
        };
        let full: Vec<u8> = TRI.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        let mut bytes = full.clone();
        bytes.extend_from_slice(&png);
        let json = triangle_gltf(TRI, None, "")
            .replace(&base64_encode(&full), &base64_encode(&bytes))
            .replace(
                r#""buffers":[{"byteLength":36"#,
                &format!(r#""buffers":[{{"byteLength":{}"#, bytes.len()),
            )
            .replace(
                r#""bufferViews":[{"buffer":0,"byteLength":36}]"#,
                &format!(
                    r#""bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":{}}}],
                    "images":[{{"bufferView":1}}],"textures":[{{"source":0}}]"#,
                    png.len()
                ),
            )
            .replace(
                r#""baseColorFactor":[1,0.5,0.25,1]"#,
                r#""baseColorFactor":[1,0.5,0.25,1],"baseColorTexture":{"index":0}"#,
            );
        let files = MemoryFiles::new().with("d/i.gltf", json.clone());
        let s = load_scene_from(&files, Path::new("d/i.gltf"), &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.textures.len(), 1);
        assert!(
            s.warnings[0]
                .starts_with("d/i.gltf: images[0] is in a buffer view but has no mimeType"),
            "{:?}",
            s.warnings
        );
        let files = MemoryFiles::new().with("d/i.gltf", json.replace(r#"{"bufferView":1}"#, "{}"));
        let e =
            load_scene_from(&files, Path::new("d/i.gltf"), &LoadOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .contains("images[0] has neither a uri nor a bufferView"),
            "{e}"
        );
        let json = r#"{"asset":{"version":"2.0"},"cameras":[{"type":"perspective","orthographic":{"xmag":1,"ymag":1,"zfar":10,"znear":1}}]}"#;
        let files = MemoryFiles::new().with("d/c.gltf", json);
        let e =
            load_scene_from(&files, Path::new("d/c.gltf"), &LoadOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .contains("cameras[0] lacks the projection object"),
            "{e}"
        );
        // Other dangling indices are caught by the validation itself.
        let json = r#"{"asset":{"version":"2.0"},"nodes":[{"mesh":3}]}"#;
        let files = MemoryFiles::new().with("d/n.gltf", json);
        let e =
            load_scene_from(&files, Path::new("d/n.gltf"), &LoadOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("d/n.gltf: malformed glTF: invalid glTF"),
            "{e}"
        );
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.png"), "a b.png");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("x%4"), "x%4");
    }
}
