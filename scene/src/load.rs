//! Loading a scene file: the loader is chosen by extension, and what every loader's scene must satisfy
//! is checked after it ([`load_scene`]), where the triangles that need tangents and lack them get
//! MikkTSpace's ([`crate::tangents`]) and textures no material reads are dropped. Above the loaders
//! ([`crate::gltf_loader`], [`crate::obj_loader`]) and the scene types they fill ([`crate::mesh`]), so
//! that imports run one way.
use std::path::Path;

use crate::error::SceneError;
use crate::mesh::{LoadOptions, LoadedScene};
use crate::source::{FileSource, Filesystem};

/// Loads a scene file, choosing the loader by extension (case-insensitive): `.gltf` / `.glb` →
/// [`crate::gltf_loader::load_gltf`], `.obj` → [`crate::obj_loader::load_obj`].
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    load_scene_from(&Filesystem, path, options)
}

/// [`load_scene`] reading the scene file and every file it refers to from `source`.
pub fn load_scene_from(
    source: &dyn FileSource,
    path: &Path,
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let scene = match extension.as_str() {
        "gltf" | "glb" => crate::gltf_loader::load_gltf_from(source, path, options),
        "obj" => crate::obj_loader::load_obj_from(source, path, options),
        _ => Err(SceneError::UnknownExtension {
            path: path.to_owned(),
            extension,
        }),
    }?;
    let mut scene = scene;
    crate::tangents::generate_missing_tangents(&mut scene);
    scene.drop_unused_textures();
    let words = crate::pack::packed_texel_words(&scene.textures);
    if words > u64::from(u32::MAX) {
        return Err(SceneError::TooLarge {
            path: path.to_owned(),
            message: format!(
                "its textures need {words} 32-bit texel words once packed (sRGB colour takes two per \
                 texel); at most {} fit",
                u32::MAX
            ),
        });
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_extension_is_an_error() {
        let e = load_scene(Path::new("/tmp/scene.PLY"), &LoadOptions::default()).unwrap_err();
        match e {
            SceneError::UnknownExtension { extension, .. } => assert_eq!(extension, "ply"),
            other => panic!("{other}"),
        }
    }
}
