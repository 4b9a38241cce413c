//! Where the loaders read a scene's files from.
//!
//! A scene is often several files: an OBJ and its MTL libraries and textures, or a `.gltf` with external
//! buffers and images. The loaders read every one of them through a [`FileSource`]: [`Filesystem`] for
//! real scenes, [`MemoryFiles`] for scenes held in memory (tests, fuzzing, embedding).
use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};

/// Reads whole files by path. `Sync` because the OBJ loader decodes textures in parallel.
pub trait FileSource: Sync {
    /// The bytes of `path`; a file that does not exist is [`io::ErrorKind::NotFound`].
    fn read(&self, path: &Path) -> io::Result<Vec<u8>>;
}

/// The real file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct Filesystem;

impl FileSource for Filesystem {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        std::fs::read(path)
    }
}

/// Files held in memory, looked up by exact path; every other path is not found.
#[derive(Clone, Debug, Default)]
pub struct MemoryFiles {
    files: HashMap<PathBuf, Vec<u8>>,
}

impl MemoryFiles {
    /// No files.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds (or replaces) the file `path`.
    pub fn insert(&mut self, path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) -> &mut Self {
        self.files.insert(path.into(), bytes.into());
        self
    }

    /// Builder form of [`Self::insert`].
    #[must_use]
    pub fn with(mut self, path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) -> Self {
        self.insert(path, bytes);
        self
    }
}

impl FileSource for MemoryFiles {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        self.files.get(path).cloned().ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::NotFound,
                format!("{} is not among the in-memory files", path.display()),
            )
        })
    }
}

/// The real file system, remembering every file a load read (the scene file, its MTL libraries,
/// buffers and textures): the files a command must not write over.
#[derive(Debug, Default)]
pub struct RecordingFilesystem {
    read: std::sync::Mutex<Vec<PathBuf>>,
}

impl RecordingFilesystem {
    /// Every path read so far (also those that failed to read), in the order first read.
    #[must_use]
    pub fn files(&self) -> Vec<PathBuf> {
        self.read.lock().map(|r| r.clone()).unwrap_or_default()
    }
}

impl FileSource for RecordingFilesystem {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        if let Ok(mut read) = self.read.lock() {
            if !read.iter().any(|p| p == path) {
                read.push(path.to_path_buf());
            }
        }
        std::fs::read(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_filesystem_lists_what_a_load_read() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell_box");
        let source = RecordingFilesystem::default();
        crate::load_scene_from(
            &source,
            &root.join("CornellBox-Original.obj"),
            &crate::mesh::LoadOptions::default(),
        )
        .unwrap();
        let names: Vec<String> = source
            .files()
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            names,
            ["CornellBox-Original.obj", "CornellBox-Original.mtl"]
        );
    }

    #[test]
    fn memory_files_find_exact_paths_only() {
        let files = MemoryFiles::new().with("d/a.obj", b"v 0 0 0\n".to_vec());
        assert_eq!(files.read(Path::new("d/a.obj")).unwrap(), b"v 0 0 0\n");
        let e = files.read(Path::new("a.obj")).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        assert_eq!(
            Filesystem
                .read(Path::new("/nonexistent/fovea/x"))
                .unwrap_err()
                .kind(),
            io::ErrorKind::NotFound
        );
    }
}
