//! Writing images: PNG (tone-mapped sRGB) and EXR (linear HDR), always through a temporary file in the
//! destination folder that is renamed into place, so a failed or interrupted run leaves nothing behind.
use std::path::{Path, PathBuf};

use fovea_core::foveation::overlay::overlay_rgba8;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::post::tonemap::{pack_rgba8, tonemap_to_srgb8};
use fovea_cpu::FrameImage;
use glam::Vec3;

use crate::error::{FoveaError, Result};

/// Output formats, chosen by the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

/// Checks an output path before any rendering: a known extension and an existing folder.
pub fn check_output_path(path: &Path, what: &'static str, allow_exr: bool) -> Result<ImageFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("png") => ImageFormat::Png,
        Some("exr") if allow_exr => ImageFormat::Exr,
        Some(other) => {
            let known = if allow_exr { ".png or .exr" } else { ".png" };
            return Err(FoveaError::option(
                what,
                format!(
                    "'{}': unknown image extension '.{other}' (use {known})",
                    path.display()
                ),
            ));
        }
        None => {
            return Err(FoveaError::option(
                what,
                format!(
                    "'{}' has no extension (use .png{})",
                    path.display(),
                    if allow_exr { " or .exr" } else { "" }
                ),
            ))
        }
    };
    check_writable_file(path, what)?;
    Ok(format)
}

/// Checks before any work that `path` can be written: its folder exists and takes new files, and the
/// path is not a folder itself. The write later is atomic (a temporary sibling, then a rename), so the
/// folder must take a new file even where `path` exists.
pub fn check_writable_file(path: &Path, what: &'static str) -> Result<()> {
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(FoveaError::option(what, missing_folder(&dir)));
    }
    if path.is_dir() {
        return Err(FoveaError::option(
            what,
            format!("'{}' is a folder, not a file", path.display()),
        ));
    }
    check_folder_takes_files(&dir).map_err(|why| FoveaError::option(what, why))
}

/// Whether new files can be created in the folder `dir` (a probe file, created and removed): the
/// permission bits do not tell for root, read-only mounts or `/proc`.
pub fn check_folder_takes_files(dir: &Path) -> std::result::Result<(), String> {
    let probe = dir.join(format!(".fovea-write-check-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!(
            "cannot write into the folder '{}': {e}",
            dir.display()
        )),
    }
}

/// The file `p` names, symbolic links and `..` resolved: itself if it exists, else its folder's
/// resolved path with its name (a file still to be written).
#[must_use]
pub fn resolved_path(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let name = p.file_name().map(PathBuf::from).unwrap_or_default();
    match parent_dir(p).canonicalize() {
        Ok(dir) => dir.join(name),
        Err(_) => p.to_path_buf(),
    }
}

/// The files a run will write, each resolved once to the file it names ([`resolved_path`]; numbered
/// outputs share a folder, which is resolved once), with the option that names it.
pub struct WrittenFiles {
    resolved: std::collections::HashMap<PathBuf, (&'static str, PathBuf)>,
}

impl WrittenFiles {
    /// Resolves `outputs` (option, path), refusing one that another output writes too: fovea never
    /// overwrites one output with another.
    pub fn resolve<P: AsRef<Path>>(outputs: &[(&'static str, P)]) -> Result<Self> {
        let mut resolved = std::collections::HashMap::new();
        let mut folders: std::collections::HashMap<PathBuf, PathBuf> =
            std::collections::HashMap::new();
        for (option, output) in outputs {
            let output = output.as_ref();
            let out = match (output.canonicalize(), output.file_name()) {
                (Ok(c), _) => c,
                (Err(_), Some(name)) => folders
                    .entry(parent_dir(output))
                    .or_insert_with_key(|dir| dir.canonicalize().unwrap_or_else(|_| dir.clone()))
                    .join(name),
                (Err(_), None) => output.to_path_buf(),
            };
            if let Some((other, first)) = resolved.insert(out, (*option, output.to_path_buf())) {
                return Err(FoveaError::option(
                    option,
                    format!(
                        "'{}' is also written as '{}' ({other}); give each output its own file",
                        output.display(),
                        first.display()
                    ),
                ));
            }
        }
        Ok(Self { resolved })
    }

    /// Refuses, before any work, an output that is one of `inputs`, by the files they resolve to:
    /// fovea never overwrites its input.
    pub fn refuse_inputs(&self, inputs: &[&Path]) -> Result<()> {
        for input in inputs {
            if let Some((option, output)) = self.resolved.get(&resolved_path(input)) {
                return Err(FoveaError::option(
                    option,
                    format!(
                        "'{}' is an input of this run ('{}'); fovea never overwrites its input",
                        output.display(),
                        input.display()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Refuses, before any work, an output (`option`, path) that is one of the run's `inputs`, or that
/// another output writes too ([`WrittenFiles`]).
pub fn refuse_overwriting_inputs<P: AsRef<Path>>(
    outputs: &[(&'static str, P)],
    inputs: &[&Path],
) -> Result<()> {
    WrittenFiles::resolve(outputs)?.refuse_inputs(inputs)
}

/// Why the folder `dir` cannot take an output file: a path through a file names that file, else the
/// folder does not exist.
#[must_use]
pub fn missing_folder(dir: &Path) -> String {
    match dir.ancestors().find(|a| a.is_file()) {
        Some(file) => format!(
            "'{}' is a file, so '{}' cannot be a folder",
            file.display(),
            dir.display()
        ),
        None => format!("the folder '{}' does not exist", dir.display()),
    }
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Checks an output JSON path before any work: a `.json` name in an existing folder.
pub fn check_json_path(p: &Path, option: &'static str) -> Result<()> {
    let ext = p
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() != Some("json") {
        return Err(FoveaError::option(
            option,
            format!("'{}' must end in .json", p.display()),
        ));
    }
    check_writable_file(p, option)
}

/// Writes `bytes_writer`'s output to `path` atomically: a temporary sibling file, then a rename.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> Result<()> {
    let dir = parent_dir(path);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}.{ext}", std::process::id()));
    if let Err(message) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(FoveaError::file(path, message));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        FoveaError::file(path, e)
    })
}

/// Tone-maps a frame to 8-bit sRGB RGB bytes.
pub fn tonemapped_rgb8(image: &FrameImage, exposure_ev: f32) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(image.pixels.len() * 3);
    for p in &image.pixels {
        bytes.extend_from_slice(&tonemap_to_srgb8(Vec3::new(p[0], p[1], p[2]), exposure_ev));
    }
    bytes
}

/// Writes a frame as PNG (tone-mapped) or EXR (linear HDR).
pub fn write_image(
    path: &Path,
    format: ImageFormat,
    image: &FrameImage,
    exposure_ev: f32,
) -> Result<()> {
    match format {
        ImageFormat::Png => {
            let rgb = tonemapped_rgb8(image, exposure_ev);
            write_png(path, image.width, image.height, &rgb)
        }
        ImageFormat::Exr => write_atomically(path, |tmp| {
            use exr::prelude::*;
            let (w, h) = (image.width as usize, image.height as usize);
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = image.pixels[y * w + x];
                (p[0], p[1], p[2])
            });
            // Compressed serially: the parallel writer stores blocks in the order they finish, so two
            // writes of the same image could differ byte for byte (a render is deterministic; its file
            // should be too, so that `cmp` or a hash can check it).
            Image::from_channels((w, h), channels)
                .write()
                .non_parallel()
                .to_file(tmp)
                .map_err(|e| e.to_string())
        }),
    }
}

/// Writes 8-bit RGB bytes as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgb,
            width,
            height,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

/// The render (tone-mapped 8-bit RGB bytes `base`) with each pixel tinted by the region of its owning
/// block and block edges darkened (core's [`overlay_rgba8`], which the live view draws on the GPU too).
pub fn regions_overlay(
    base: &[u8],
    width: u32,
    height: u32,
    foveation: &FoveationParams,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(base.len());
    for y in 0..height {
        for x in 0..width {
            let i = ((y * width + x) * 3) as usize;
            let rgba = pack_rgba8(
                u32::from(base[i]),
                u32::from(base[i + 1]),
                u32::from(base[i + 2]),
            );
            let o = overlay_rgba8(rgba, x, y, foveation);
            out.extend_from_slice(&[o as u8, (o >> 8) as u8, (o >> 16) as u8]);
        }
    }
    out
}
/// Reads the RGB channels of an EXR file as a linear HDR frame.
pub fn read_exr(path: &Path) -> Result<FrameImage> {
    struct Pixels {
        width: usize,
        data: Vec<[f32; 4]>,
    }
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| Pixels {
            width: resolution.width(),
            data: vec![[0.0, 0.0, 0.0, 1.0]; resolution.width() * resolution.height()],
        },
        |pixels: &mut Pixels, position, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = position.y() * pixels.width + position.x();
            pixels.data[i] = [r, g, b, 1.0];
        },
    )
    .map_err(|e| FoveaError::file(path, e))?;
    let size = image.layer_data.size;
    Ok(FrameImage {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels: image.layer_data.channel_data.pixels.data,
    })
}
