//! The on-disk cache of converged references: a linear HDR EXR per key, so a reference is rendered once.
//!
//! The key is the FNV-1a-64 hash of a canonical text ([`reference_key_text`]) that names everything the
//! reference image depends on: the scene's content (the scene file's bytes, and the packed materials,
//! textures, texels, lights and environment, so an edited `.mtl` or texture also changes the key), the
//! camera, the resolution, the integrator settings, the samples per pixel, the seed, fovea's version and a
//! hash of the running `fovea` executable (any rebuild can change the renderer: a reference from an older
//! build would bias every error, so a rebuilt binary renders its own).
//! The text is stored next to the image (`<hash>.key`) and compared on load, so a hash collision is a miss,
//! never a wrong reference.
use std::path::{Path, PathBuf};

use fovea_core::integrator::FrameParams;
use fovea_cpu::FrameImage;
use fovea_scene::pack::PackedScene;

use crate::content_hash::{executable_hash, fnv1a64, packed_scene_hash};
use crate::error::{FoveaError, Result};
use crate::output::{read_exr, write_atomically, write_image, ImageFormat};

/// The canonical text that keys a reference. `scene_file_hash` is the FNV-1a-64 of the scene file's bytes;
/// `environment` describes the sky or environment map as given on the command line.
#[must_use]
pub fn reference_key_text(
    scene_file_hash: u64,
    packed: &PackedScene,
    environment: &str,
    frame: &FrameParams,
    fill_mode: u32,
) -> String {
    let bits = |v: &[f32]| {
        v.iter()
            .map(|x| format!("{:08x}", x.to_bits()))
            .collect::<Vec<_>>()
            .join(",")
    };
    let c = &frame.camera;
    let i = &frame.integrator;
    let f = &frame.foveation;
    format!(
        "fovea-report-reference 1\n\
         fovea {} executable {}\n\
         scene-file fnv1a64 {scene_file_hash:016x}\n\
         scene-content fnv1a64 {:016x}\n\
         environment {environment}\n\
         camera {};{};{};{}\n\
         resolution {}x{}\n\
         integrator max_bounces {} russian_roulette_start {} strategy {}\n\
         spp {:?} blocks {:?} radii {} fill {fill_mode}\n\
         seed {} frame {}\n",
        env!("CARGO_PKG_VERSION"),
        executable_hash().map_or_else(|| "unknown".to_string(), |h| format!("{h:016x}")),
        packed_scene_hash(packed),
        bits(&c.position[..3]),
        bits(&c.forward[..3]),
        bits(&c.right[..3]),
        bits(&c.up[..3]),
        frame.width,
        frame.height,
        i.max_bounces,
        i.russian_roulette_start,
        i.strategy,
        &f.spp[..3],
        &f.block_size[..3],
        bits(&[f.radius_fovea, f.radius_intermediate]),
        frame.seed,
        frame.frame_index,
    )
}

/// The cache folder: `--cache-dir`, else `$FOVEA_CACHE_DIR`, else `$XDG_CACHE_HOME/fovea`, else
/// `$HOME/.cache/fovea`.
pub fn cache_dir(option: Option<&Path>) -> Result<PathBuf> {
    if let Some(p) = option {
        return Ok(p.to_path_buf());
    }
    let non_empty = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(p) = non_empty("FOVEA_CACHE_DIR") {
        return Ok(PathBuf::from(p));
    }
    if let Some(p) = non_empty("XDG_CACHE_HOME") {
        return Ok(PathBuf::from(p).join("fovea"));
    }
    if let Some(p) = non_empty("HOME") {
        return Ok(PathBuf::from(p).join(".cache/fovea"));
    }
    Err(FoveaError::option(
        "--cache-dir",
        "no cache folder: set --cache-dir, FOVEA_CACHE_DIR, XDG_CACHE_HOME or HOME",
    ))
}

/// A reference's place in the cache.
pub struct CacheEntry {
    pub key_text: String,
    pub image: PathBuf,
    pub key_file: PathBuf,
}

impl CacheEntry {
    /// The entry for `key_text` in `dir`.
    #[must_use]
    pub fn new(dir: &Path, key_text: String) -> Self {
        let name = format!("reference-{:016x}", fnv1a64(key_text.as_bytes()));
        Self {
            image: dir.join(format!("{name}.exr")),
            key_file: dir.join(format!("{name}.key")),
            key_text,
        }
    }

    /// The entry's file name without extension (`reference-<hash of the key text>`), which also names
    /// the reference's parts in a `--reference-parts` folder.
    #[must_use]
    pub fn name(&self) -> String {
        self.image
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }

    /// The cached image, if there is one with the same key text and the expected size. A cache file that
    /// cannot be read is a miss (it is rendered again and replaced).
    #[must_use]
    pub fn load(&self, width: u32, height: u32) -> Option<FrameImage> {
        let stored = std::fs::read_to_string(&self.key_file).ok()?;
        if stored != self.key_text {
            return None;
        }
        let image = read_exr(&self.image).ok()?;
        (image.width == width && image.height == height).then_some(image)
    }

    /// Stores `image` (the image first, then the key, each atomically).
    pub fn store(&self, image: &FrameImage) -> Result<()> {
        let dir = self.image.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir)
            .map_err(|e| FoveaError::file(dir, format!("cannot create the cache folder: {e}")))?;
        write_image(&self.image, ImageFormat::Exr, image, 0.0)?;
        write_atomically(&self.key_file, |tmp| {
            std::fs::write(tmp, self.key_text.as_bytes()).map_err(|e| e.to_string())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_round_trip_and_key_mismatch() {
        let dir = std::env::temp_dir().join(format!("fovea-refcache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let image = FrameImage {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| [i as f32 * 0.5, 1.0 / (i as f32 + 1.0), 7.25, 1.0])
                .collect(),
        };
        let entry = CacheEntry::new(&dir, "key one".into());
        assert!(entry.load(3, 2).is_none());
        entry.store(&image).unwrap();
        let back = entry.load(3, 2).expect("cached");
        assert_eq!(back.pixels, image.pixels);
        assert!(entry.load(4, 2).is_none(), "wrong size is a miss");
        // A different key text is a different file; a tampered key file is a miss.
        let other = CacheEntry::new(&dir, "key two".into());
        assert_ne!(other.image, entry.image);
        std::fs::write(&entry.key_file, "something else").unwrap();
        assert!(entry.load(3, 2).is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
