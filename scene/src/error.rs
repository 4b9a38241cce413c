//! Errors of the scene pipeline, each naming the file and what is wrong with it.
use std::path::PathBuf;

/// Everything that can go wrong while loading a scene or a texture.
///
/// Every variant names the offending file (or, for textures embedded in a glTF file, the glTF file and the
/// image index) so that a user can tell which of a scene's many files is broken. Problems that allow a
/// sensible fallback (a missing MTL or texture file, an unsupported primitive mode, ...) are not errors but
/// entries of [`crate::mesh::LoadedScene::warnings`].
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file does not exist.
    #[error("{}: file not found", .path.display())]
    MissingFile { path: PathBuf },

    /// The file exists but could not be read (the I/O error's message).
    #[error("{}: cannot read: {message}", .path.display())]
    Io { path: PathBuf, message: String },

    /// The scene file's extension is none of `.gltf`, `.glb`, `.obj`.
    #[error("{}: unsupported scene file extension {extension:?} (expected .gltf, .glb or .obj)", .path.display())]
    UnknownExtension { path: PathBuf, extension: String },

    /// The glTF JSON or GLB container is malformed or invalid (the gltf crate's message).
    #[error("{}: malformed glTF: {message}", .path.display())]
    Gltf { path: PathBuf, message: String },

    /// A glTF buffer (or the bytes an accessor / buffer view needs) is shorter than declared.
    #[error("{}: {what} needs {needed} bytes but its buffer has only {available}", .path.display())]
    BufferTooShort {
        path: PathBuf,
        what: String,
        needed: u64,
        available: u64,
    },

    /// A glTF accessor has a type or layout the loader cannot read for its purpose.
    #[error("{}: {message}", .path.display())]
    InvalidAccessor { path: PathBuf, message: String },

    /// The OBJ file is malformed (tobj's message).
    #[error("{}: malformed OBJ: {message}", .path.display())]
    Obj { path: PathBuf, message: String },

    /// An MTL file exists but is malformed (tobj's message).
    #[error("{}: malformed MTL: {message}", .path.display())]
    Mtl { path: PathBuf, message: String },

    /// A face (OBJ) or index (glTF) refers to a vertex that does not exist.
    #[error("{}: face index out of range: {message}", .path.display())]
    FaceIndexOutOfRange { path: PathBuf, message: String },

    /// The scene has more vertices or triangles than [`crate::mesh::LoadOptions`] allow, or more texels
    /// than the packed texel array can index.
    #[error("{}: scene too large: {message}", .path.display())]
    TooLarge { path: PathBuf, message: String },

    /// After validation the scene has no triangle left to render.
    #[error("{}: the scene has no valid triangles{detail}", .path.display())]
    Empty { path: PathBuf, detail: String },

    /// An image could not be decoded (the image crate's message). `path` is the image file or, for an
    /// image embedded in a glTF file, `scene.glb#image3`.
    #[error("{}: cannot decode texture: {message}", .path.display())]
    Texture { path: PathBuf, message: String },

    /// An image is larger than [`crate::texture::TextureLimits`] allow (`path` as for [`Self::Texture`]).
    #[error("{}: texture over the size limit: {message}", .path.display())]
    TextureTooLarge { path: PathBuf, message: String },
}

impl SceneError {
    /// Maps an I/O error on `path` to [`SceneError::MissingFile`] or [`SceneError::Io`].
    #[must_use]
    pub fn from_io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        let path = path.into();
        if source.kind() == std::io::ErrorKind::NotFound {
            Self::MissingFile { path }
        } else {
            Self::Io {
                path,
                message: source.to_string(),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_file() {
        let e = SceneError::from_io(
            "/tmp/x/scene.obj",
            std::io::Error::from(std::io::ErrorKind::NotFound),
        );
        assert!(matches!(e, SceneError::MissingFile { .. }));
        assert_eq!(e.to_string(), "/tmp/x/scene.obj: file not found");
        let e = SceneError::from_io(
            "a.gltf",
            std::io::Error::from(std::io::ErrorKind::PermissionDenied),
        );
        assert!(matches!(e, SceneError::Io { .. }));
        assert!(e.to_string().starts_with("a.gltf: cannot read"));
        let e = SceneError::UnknownExtension {
            path: "a.ply".into(),
            extension: "ply".into(),
        };
        assert!(e.to_string().contains("a.ply") && e.to_string().contains("\"ply\""));
    }
}
