//! Texture fetches from the packed texel array (RGBA8 or linear RGBA16; bilinear filtering, REPEAT
//! addressing).
use glam::{Vec2, Vec4};

use crate::math::float::floor;
use crate::scene::{SceneSource, SceneView, TextureInfo, TEXTURE_RGBA16};

/// Decodes one packed RGBA8 texel to [0, 1] floats (no colour-space conversion).
#[inline]
#[must_use]
pub fn unpack_rgba8(texel: u32) -> Vec4 {
    Vec4::new(
        (texel & 0xff) as f32,
        ((texel >> 8) & 0xff) as f32,
        ((texel >> 16) & 0xff) as f32,
        (texel >> 24) as f32,
    ) * (1.0 / 255.0)
}

/// Decodes one RGBA16 texel stored as two words (`R | G << 16`, `B | A << 16`) to [0, 1] floats.
#[inline]
#[must_use]
pub fn unpack_rgba16(rg: u32, ba: u32) -> Vec4 {
    Vec4::new(
        (rg & 0xffff) as f32,
        (rg >> 16) as f32,
        (ba & 0xffff) as f32,
        (ba >> 16) as f32,
    ) * (1.0 / 65535.0)
}

/// Wraps an integer coordinate into `[0, size)`.
#[inline]
fn wrap(i: i32, size: u32) -> u32 {
    let s = size as i32;
    let m = i % s;
    (if m < 0 { m + s } else { m }) as u32
}

/// The wrapped coordinate after `i` (already in `[0, size)`).
#[inline]
fn next_wrapped(i: u32, size: u32) -> u32 {
    if i + 1 == size {
        0
    } else {
        i + 1
    }
}

/// Texel (`x`, `y`) of the texture, both already wrapped.
#[inline]
fn fetch<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    info: &TextureInfo,
    x: u32,
    y: u32,
) -> Vec4 {
    let texel = y * info.width + x;
    if info.flags & TEXTURE_RGBA16 != 0 {
        let [rg, ba] = source.texel_pair(scene, info.offset + 2 * texel);
        unpack_rgba16(rg, ba)
    } else {
        unpack_rgba8(source.texel(scene, info.offset + texel))
    }
}

/// Samples texture `texture` at `uv` with bilinear filtering (colour textures are linear, see
/// [`TEXTURE_RGBA16`]). `uv` (0, 0) is the top-left corner of the image, as in glTF.
#[must_use]
pub fn sample_texture<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    texture: u32,
    uv: Vec2,
) -> Vec4 {
    let info = source.texture(scene, texture);
    let fx = uv.x * info.width as f32 - 0.5;
    let fy = uv.y * info.height as f32 - 0.5;
    // Keep coordinates in a range where f32 -> i32 cannot overflow (absurd or non-finite UVs).
    let fx = if crate::math::float::is_finite(fx) {
        fx.clamp(-1.0e7, 1.0e7)
    } else {
        0.0
    };
    let fy = if crate::math::float::is_finite(fy) {
        fy.clamp(-1.0e7, 1.0e7)
    } else {
        0.0
    };
    let x0 = floor(fx);
    let y0 = floor(fy);
    let tx = fx - x0;
    let ty = fy - y0;
    // Two integer remainders per lookup rather than one per texel coordinate (they are slow on both
    // targets, a scalar division per lane on lavapipe).
    let (x0, y0) = (wrap(x0 as i32, info.width), wrap(y0 as i32, info.height));
    let (x1, y1) = (next_wrapped(x0, info.width), next_wrapped(y0, info.height));
    let c00 = fetch(scene, source, &info, x0, y0);
    let c10 = fetch(scene, source, &info, x1, y0);
    let c01 = fetch(scene, source, &info, x0, y1);
    let c11 = fetch(scene, source, &info, x1, y1);
    let top = c00 + (c10 - c00) * tx;
    let bottom = c01 + (c11 - c01) * tx;
    top + (bottom - top) * ty
}
