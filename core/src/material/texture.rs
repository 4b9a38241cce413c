//! Texture fetches from the packed RGBA8 texel array (bilinear filtering, REPEAT addressing).
use glam::{Vec2, Vec4};

use crate::math::color::srgb_to_linear;
use crate::math::float::floor;
use crate::scene::{SceneView, TextureInfo, TEXTURE_SRGB};

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

/// Wraps an integer coordinate into `[0, size)`.
#[inline]
fn wrap(i: i32, size: u32) -> u32 {
    let s = size as i32;
    let m = i % s;
    (if m < 0 { m + s } else { m }) as u32
}

#[inline]
fn fetch<F: crate::scene::Features>(
    scene: &SceneView<F>,
    info: &TextureInfo,
    x: i32,
    y: i32,
) -> Vec4 {
    let xi = wrap(x, info.width);
    let yi = wrap(y, info.height);
    let index = info.offset + yi * info.width + xi;
    unpack_rgba8(scene.texels[index as usize])
}

/// Samples texture `texture` at `uv` with bilinear filtering; sRGB textures come back linear (alpha stays
/// linear). `uv` (0, 0) is the top-left corner of the image, as in glTF.
#[must_use]
pub fn sample_texture<F: crate::scene::Features>(
    scene: &SceneView<F>,
    texture: u32,
    uv: Vec2,
) -> Vec4 {
    let info = scene.textures[texture as usize];
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
    let (xi, yi) = (x0 as i32, y0 as i32);
    let c00 = fetch(scene, &info, xi, yi);
    let c10 = fetch(scene, &info, xi + 1, yi);
    let c01 = fetch(scene, &info, xi, yi + 1);
    let c11 = fetch(scene, &info, xi + 1, yi + 1);
    let top = c00 + (c10 - c00) * tx;
    let bottom = c01 + (c11 - c01) * tx;
    let c = top + (bottom - top) * ty;
    if info.flags & TEXTURE_SRGB != 0 {
        Vec4::new(
            srgb_to_linear(c.x),
            srgb_to_linear(c.y),
            srgb_to_linear(c.z),
            c.w,
        )
    } else {
        c
    }
}
