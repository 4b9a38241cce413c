//! Texture decoding into RGBA8 texels.
//!
//! Every image format the `image` crate is built with here (PNG, JPEG, HDR, TGA, BMP) is decoded with
//! [`image::Limits`] (maximum width/height and a maximum allocation) and converted to 8-bit RGBA, the one
//! texel format of `fovea_core::scene::layout` (R in the low byte of a `u32`, row-major, top row first).
use std::io::Cursor;
use std::path::Path;

use image::{DynamicImage, ImageError, ImageReader};

use crate::error::SceneError;
use crate::source::{FileSource, Filesystem};

/// A decoded texture, ready to be packed.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The file (or `scene.glb#image3` for embedded images); used in messages only.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Whether the colour channels are sRGB-encoded (base colour, emission) rather than linear data
    /// (metallic-roughness, normals, opacity). The packer turns this into `TEXTURE_SRGB`.
    pub srgb: bool,
    /// `width * height` RGBA8 texels, R in the low byte, row-major, top row first.
    pub texels: Vec<u32>,
    /// How it is sampled: `fovea_core::scene::TEXTURE_CLAMP_S` ... `TEXTURE_NEAREST` bits (0: repeat,
    /// bilinear), and [`NO_MIP_LEVELS`] when the sampler asks for no mip-mapping.
    pub sampler: u32,
    /// Texture-coordinate transform `[m0, m1, m2, m3, tx, ty]` (`uv' = [m0 m1; m2 m3] uv + t`, glTF
    /// `KHR_texture_transform`), if any.
    pub transform: Option<[f32; 6]>,
}

/// [`Texture::sampler`]: the packer builds no mip levels (glTF `minFilter` `NEAREST` or `LINEAR`).
pub const NO_MIP_LEVELS: u32 = 1 << 31;

/// Packs one RGBA8 texel with R in the low byte (the layout `fovea_core::material::texture` reads).
#[inline]
#[must_use]
pub fn pack_rgba8(rgba: [u8; 4]) -> u32 {
    u32::from_le_bytes(rgba)
}

impl Texture {
    /// A texture of `texels` (RGBA8, `width × height`), repeated and filtered by default, untransformed.
    #[must_use]
    pub fn new(
        name: impl Into<String>,
        width: u32,
        height: u32,
        srgb: bool,
        texels: Vec<u32>,
    ) -> Self {
        Self {
            name: name.into(),
            width,
            height,
            srgb,
            texels,
            sampler: 0,
            transform: None,
        }
    }

    /// A 1×1 texture of one colour (fallbacks and tests).
    #[must_use]
    pub fn single_color(name: impl Into<String>, rgba: [u8; 4], srgb: bool) -> Self {
        Self::new(name, 1, 1, srgb, vec![pack_rgba8(rgba)])
    }

    /// The texel at column `x`, row `y` (row 0 is the top) as `[r, g, b, a]`.
    #[must_use]
    pub fn texel(&self, x: u32, y: u32) -> [u8; 4] {
        self.texels[(y * self.width + x) as usize].to_le_bytes()
    }
}

/// Limits applied while decoding images (from [`crate::mesh::LoadOptions`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureLimits {
    /// Largest accepted width and height in texels.
    pub max_dimension: u32,
    /// Largest allocation the decoder may make, and the largest accepted RGBA8 result, in bytes.
    pub max_bytes: u64,
}

impl Default for TextureLimits {
    fn default() -> Self {
        Self {
            max_dimension: 16384,
            max_bytes: 1 << 30,
        }
    }
}

/// What a decoded image is used for, which decides how it becomes RGBA8.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureRole {
    /// Colour or data as stored (any format converted to RGBA8); `srgb` is recorded in the texture.
    Color { srgb: bool },
    /// An opacity mask (OBJ `map_d`): the image's alpha channel if it has one that is not uniformly
    /// opaque, else its luminance (Rec. 709 weights on the stored values), written to A; RGB are set to
    /// 255. Always linear. (Lost Empire's `lost_empire-Alpha.png` is RGBA with alpha 255 everywhere and
    /// the mask in RGB, hence the "not uniformly opaque" test.)
    Opacity,
}

/// The size an encoded image's header claims, for messages (`None` if it cannot be read).
#[must_use]
pub fn claimed_dimensions(bytes: &[u8]) -> Option<(u32, u32)> {
    ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .ok()?
        .into_dimensions()
        .ok()
}

/// The message of a limits error: what the header claims and what the limits are.
#[must_use]
pub fn limits_message(bytes: &[u8], limits: &TextureLimits, detail: &str) -> String {
    let claimed = match claimed_dimensions(bytes) {
        Some((w, h)) => format!("the header claims {w}x{h} texels; "),
        None => String::new(),
    };
    format!(
        "{claimed}limits are {} texels per side and {} bytes ({detail})",
        limits.max_dimension, limits.max_bytes
    )
}

fn decode_error(name: &str, e: ImageError, bytes: &[u8], limits: &TextureLimits) -> SceneError {
    match e {
        ImageError::Limits(l) => SceneError::TextureTooLarge {
            path: name.into(),
            message: limits_message(bytes, limits, &l.to_string()),
        },
        other => SceneError::Texture {
            path: name.into(),
            message: other.to_string(),
        },
    }
}

/// Decodes `bytes` (format guessed from the content) with `limits`.
fn decode_dynamic(
    bytes: &[u8],
    name: &str,
    limits: &TextureLimits,
) -> Result<DynamicImage, SceneError> {
    let mut reader = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| SceneError::Texture {
            path: name.into(),
            message: e.to_string(),
        })?;
    if reader.format().is_none() {
        return Err(SceneError::Texture {
            path: name.into(),
            message: "unknown or unsupported image format".to_owned(),
        });
    }
    let mut l = image::Limits::default();
    l.max_image_width = Some(limits.max_dimension);
    l.max_image_height = Some(limits.max_dimension);
    l.max_alloc = Some(limits.max_bytes);
    reader.limits(l);
    let image = reader
        .decode()
        .map_err(|e| decode_error(name, e, bytes, limits))?;
    let (w, h) = (image.width(), image.height());
    if w == 0 || h == 0 {
        return Err(SceneError::Texture {
            path: name.into(),
            message: format!("image is {w}x{h}"),
        });
    }
    let rgba_bytes = u64::from(w) * u64::from(h) * 4;
    if w > limits.max_dimension || h > limits.max_dimension || rgba_bytes > limits.max_bytes {
        return Err(SceneError::TextureTooLarge {
            path: name.into(),
            message: format!(
                "{w}x{h} ({rgba_bytes} bytes as RGBA8); limits are {} texels per side and {} bytes",
                limits.max_dimension, limits.max_bytes
            ),
        });
    }
    Ok(image)
}

/// Converts a decoded image to a [`Texture`] for `role`.
fn to_texture(image: DynamicImage, name: &str, role: TextureRole) -> Texture {
    let (width, height) = (image.width(), image.height());
    match role {
        TextureRole::Color { srgb } => {
            let rgba = image.into_rgba8();
            let texels = rgba
                .as_raw()
                .chunks_exact(4)
                .map(|c| pack_rgba8([c[0], c[1], c[2], c[3]]))
                .collect();
            Texture::new(name.to_owned(), width, height, srgb, texels)
        }
        TextureRole::Opacity => {
            let has_alpha = image.color().has_alpha();
            let rgba = image.into_rgba8();
            let use_alpha = has_alpha && rgba.as_raw().chunks_exact(4).any(|c| c[3] != 255);
            let texels = rgba
                .as_raw()
                .chunks_exact(4)
                .map(|c| {
                    let opacity = if use_alpha {
                        c[3]
                    } else {
                        let l = 0.2126 * f32::from(c[0])
                            + 0.7152 * f32::from(c[1])
                            + 0.0722 * f32::from(c[2]);
                        l.round().clamp(0.0, 255.0) as u8
                    };
                    pack_rgba8([255, 255, 255, opacity])
                })
                .collect();
            Texture::new(name.to_owned(), width, height, false, texels)
        }
    }
}

/// Decodes an encoded image (`bytes`, format guessed from the content) for `role`; `name` is used in
/// error messages and stored in the texture.
pub fn decode_texture_bytes_as(
    bytes: &[u8],
    name: &str,
    role: TextureRole,
    limits: &TextureLimits,
) -> Result<Texture, SceneError> {
    decode_dynamic(bytes, name, limits).map(|image| to_texture(image, name, role))
}

/// Decodes an encoded image into an RGBA8 colour/data texture.
pub fn decode_texture_bytes(
    bytes: &[u8],
    name: &str,
    srgb: bool,
    limits: &TextureLimits,
) -> Result<Texture, SceneError> {
    decode_texture_bytes_as(bytes, name, TextureRole::Color { srgb }, limits)
}

/// Reads an image file from `source` and decodes it for `role`. A missing file is
/// [`SceneError::MissingFile`].
pub fn load_texture_from(
    source: &dyn FileSource,
    path: &Path,
    role: TextureRole,
    limits: &TextureLimits,
) -> Result<Texture, SceneError> {
    let bytes = source
        .read(path)
        .map_err(|e| SceneError::from_io(path, e))?;
    decode_texture_bytes_as(&bytes, &path.display().to_string(), role, limits)
}

/// Reads and decodes an image file for `role`. A missing file is [`SceneError::MissingFile`].
pub fn load_texture_file_as(
    path: &Path,
    role: TextureRole,
    limits: &TextureLimits,
) -> Result<Texture, SceneError> {
    load_texture_from(&Filesystem, path, role, limits)
}

/// Reads and decodes an image file into an RGBA8 colour/data texture.
pub fn load_texture_file(
    path: &Path,
    srgb: bool,
    limits: &TextureLimits,
) -> Result<Texture, SceneError> {
    load_texture_file_as(path, TextureRole::Color { srgb }, limits)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{ImageFormat, Rgb, RgbImage, Rgba, RgbaImage};

    fn encode(image: DynamicImage) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        image.write_to(&mut out, ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn rgb_png_becomes_rgba8_top_row_first() {
        let mut img = RgbImage::new(2, 3);
        img.put_pixel(0, 0, Rgb([10, 20, 30]));
        img.put_pixel(1, 2, Rgb([200, 100, 50]));
        let bytes = encode(DynamicImage::ImageRgb8(img));
        let t = decode_texture_bytes(&bytes, "mem.png", true, &TextureLimits::default()).unwrap();
        assert_eq!((t.width, t.height, t.srgb), (2, 3, true));
        assert_eq!(t.texels.len(), 6);
        assert_eq!(t.texel(0, 0), [10, 20, 30, 255]);
        assert_eq!(t.texel(1, 2), [200, 100, 50, 255]);
        assert_eq!(t.texels[0], 10 | (20 << 8) | (30 << 16) | (255 << 24));
    }

    #[test]
    fn opacity_uses_alpha_or_luminance() {
        let mut img = RgbaImage::new(1, 1);
        img.put_pixel(0, 0, Rgba([0, 0, 0, 77]));
        let bytes = encode(DynamicImage::ImageRgba8(img));
        let t = decode_texture_bytes_as(
            &bytes,
            "a.png",
            TextureRole::Opacity,
            &TextureLimits::default(),
        )
        .unwrap();
        assert_eq!(t.texel(0, 0), [255, 255, 255, 77]);
        assert!(!t.srgb);
        let mut img = RgbImage::new(1, 1);
        img.put_pixel(0, 0, Rgb([100, 100, 100]));
        let bytes = encode(DynamicImage::ImageRgb8(img));
        let t = decode_texture_bytes_as(
            &bytes,
            "l.png",
            TextureRole::Opacity,
            &TextureLimits::default(),
        )
        .unwrap();
        assert_eq!(t.texel(0, 0), [255, 255, 255, 100]);
        // RGBA with a uniformly opaque alpha channel: the mask is in RGB.
        let mut img = RgbaImage::new(2, 1);
        img.put_pixel(0, 0, Rgba([0, 0, 0, 255]));
        img.put_pixel(1, 0, Rgba([255, 255, 255, 255]));
        let bytes = encode(DynamicImage::ImageRgba8(img));
        let t = decode_texture_bytes_as(
            &bytes,
            "m.png",
            TextureRole::Opacity,
            &TextureLimits::default(),
        )
        .unwrap();
        assert_eq!((t.texel(0, 0)[3], t.texel(1, 0)[3]), (0, 255));
    }

    #[test]
    fn limits_and_garbage_are_errors_naming_the_texture() {
        let bytes = encode(DynamicImage::ImageRgb8(RgbImage::new(64, 8)));
        let limits = TextureLimits {
            max_dimension: 32,
            max_bytes: 1 << 30,
        };
        let e = decode_texture_bytes(&bytes, "big.png", false, &limits).unwrap_err();
        assert!(matches!(e, SceneError::TextureTooLarge { .. }), "{e}");
        assert!(e.to_string().contains("big.png"));
        let limits = TextureLimits {
            max_dimension: 1024,
            max_bytes: 1000,
        };
        let e = decode_texture_bytes(&bytes, "big.png", false, &limits).unwrap_err();
        assert!(matches!(e, SceneError::TextureTooLarge { .. }), "{e}");
        let e = decode_texture_bytes(
            b"definitely not an image",
            "junk.png",
            false,
            &TextureLimits::default(),
        )
        .unwrap_err();
        assert!(matches!(e, SceneError::Texture { .. }), "{e}");
        assert!(e.to_string().contains("junk.png"));
        let mut truncated = encode(DynamicImage::ImageRgb8(RgbImage::new(16, 16)));
        truncated.truncate(truncated.len() / 2);
        let e = decode_texture_bytes(&truncated, "cut.png", false, &TextureLimits::default())
            .unwrap_err();
        assert!(matches!(e, SceneError::Texture { .. }), "{e}");
    }

    #[test]
    fn missing_file_and_single_color() {
        let e = load_texture_file(
            Path::new("/nonexistent/fovea/tex.png"),
            true,
            &TextureLimits::default(),
        )
        .unwrap_err();
        assert!(matches!(e, SceneError::MissingFile { .. }));
        let t = Texture::single_color("white", [255, 128, 0, 255], true);
        assert_eq!((t.width, t.height), (1, 1));
        assert_eq!(t.texel(0, 0), [255, 128, 0, 255]);
    }

    #[test]
    fn real_png_files_decode() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/roughness_scale_kajiya");
        let t = load_texture_file(&dir.join("127.png"), false, &TextureLimits::default()).unwrap();
        assert_eq!((t.width, t.height), (1, 1));
        assert_eq!(t.texel(0, 0)[3], 255);
    }
}
