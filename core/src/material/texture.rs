//! Texture fetches from the packed texel array (RGBA8 or linear RGBA16; bilinear or nearest filtering;
//! repeated, clamped or mirrored addressing per axis, as the glTF sampler says), and trilinear
//! filtering between mip levels ([`sample_texture_lod`]).
//!
//! **Which level.** A first hit's level follows the footprint of the camera ray's cone (Akenine-Möller
//! et al. 2019, "Texture Level of Detail Strategies for Real-Time Ray Tracing", Ray Tracing Gems ch. 20,
//! the ray cone at the primary hit): the cone of spread angle γ has width `γ t` at distance `t`, which
//! covers `γ t / |n·d|` of the surface and, through the triangle's texture-to-surface scale
//! `sqrt(A_uv / A_world)`, that many units of texture space; the level is log2 of it in texels. fovea's
//! rule is the *block's* footprint: a sample of an `s × s` block stands for `s` pixels' width, so its cone
//! is `s` times a pixel's (`crate::integrator::TEXTURE_LOD_BLOCK`): periphery samples (4 × 4 blocks)
//! read two levels coarser than fovea samples, which removes the texture aliasing and noise the block
//! would otherwise average from too few samples, at no cost. Paths' later hits read level 0.
use glam::{Vec2, Vec4};

use crate::math::float::{floor, ln};
use crate::scene::{
    SceneSource, SceneView, TextureInfo, TEXTURE_ADDRESSING, TEXTURE_CLAMP_S, TEXTURE_CLAMP_T,
    TEXTURE_MIPMAPPED, TEXTURE_MIRROR_S, TEXTURE_MIRROR_T, TEXTURE_NEAREST, TEXTURE_RGBA16,
    TEXTURE_TRANSFORMED,
};

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

/// Integer coordinate `i` of an axis of `size` texels under the addressing of the axis: `clamp` to the
/// edge texels, `mirror`ed repeat, else repeat.
#[inline]
fn address(i: i32, size: u32, clamp: bool, mirror: bool) -> u32 {
    let s = size as i32;
    if clamp {
        i.clamp(0, s - 1) as u32
    } else if mirror {
        let m = wrap(i, 2 * size) as i32;
        (if m < s { m } else { 2 * s - 1 - m }) as u32
    } else {
        wrap(i, size)
    }
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
    bilinear(scene, source, &info, transformed(&info, uv))
}

/// `uv` mapped by the texture's coordinate transform (glTF `KHR_texture_transform`), if it has one.
#[inline]
#[must_use]
pub fn transformed(info: &TextureInfo, uv: Vec2) -> Vec2 {
    if info.flags & TEXTURE_TRANSFORMED == 0 {
        return uv;
    }
    let m = info.matrix;
    Vec2::new(
        m[0] * uv.x + m[1] * uv.y + info.translation[0],
        m[2] * uv.x + m[3] * uv.y + info.translation[1],
    )
}

/// Number of mip levels of a `width × height` texture with a full chain: `1 + floor(log2(max))`.
#[inline]
#[must_use]
pub fn mip_level_count(width: u32, height: u32) -> u32 {
    // A loop rather than `leading_zeros`, which the SPIR-V build did not compile to the same count
    // (the CPU/lavapipe frame test caught it: far surfaces read past their texture's levels).
    let mut size = width.max(height).max(1);
    let mut levels = 1;
    while size > 1 {
        size /= 2;
        levels += 1;
    }
    levels
}

/// The record of mip level `level` of `info` (which must be mipmapped): levels follow level 0 in the
/// texel array, each `max(1, size >> 1)` of the one before, in the same texel format.
#[inline]
#[must_use]
pub fn mip_level(info: &TextureInfo, level: u32) -> TextureInfo {
    let words = if info.flags & TEXTURE_RGBA16 != 0 {
        2
    } else {
        1
    };
    let (mut offset, mut width, mut height) = (info.offset, info.width, info.height);
    let mut k = 0;
    while k < level {
        offset += words * width * height;
        width = (width / 2).max(1);
        height = (height / 2).max(1);
        k += 1;
    }
    TextureInfo {
        offset,
        width,
        height,
        ..*info
    }
}

/// Samples texture `texture` at `uv` filtered for a footprint `footprint_uv` wide in texture
/// coordinates (see the module documentation): trilinearly between the two mip levels around
/// `log2(footprint_uv · sqrt(width · height))`. A footprint of at most one texel, or a texture without
/// mip levels, is exactly [`sample_texture`].
#[must_use]
pub fn sample_texture_lod<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    texture: u32,
    uv: Vec2,
    footprint_uv: f32,
) -> Vec4 {
    let info = source.texture(scene, texture);
    let uv = transformed(&info, uv);
    // A transform scales the footprint by sqrt(|det|) (its area ratio).
    let scale = if info.flags & TEXTURE_TRANSFORMED != 0 {
        let m = info.matrix;
        crate::math::float::sqrt((m[0] * m[3] - m[1] * m[2]).abs())
    } else {
        1.0
    };
    let texels =
        footprint_uv * scale * crate::math::float::sqrt(info.width as f32 * info.height as f32);
    // `!(x > 1)` also takes NaN to level 0.
    if info.flags & TEXTURE_MIPMAPPED == 0 || !(texels > 1.0) {
        return bilinear(scene, source, &info, uv);
    }
    let top = mip_level_count(info.width, info.height) - 1;
    let lod = ln(texels) * core::f32::consts::LOG2_E;
    // Written so that any lod at or past the last level (or NaN) reads the last level alone.
    if !(lod < top as f32) {
        return bilinear(scene, source, &mip_level(&info, top), uv);
    }
    let l0 = floor(lod);
    let t = lod - l0;
    let level = (l0 as u32).min(top);
    let fine = bilinear(scene, source, &mip_level(&info, level), uv);
    if t > 0.0 && level < top {
        let coarse = bilinear(scene, source, &mip_level(&info, level + 1), uv);
        fine + (coarse - fine) * t
    } else {
        fine
    }
}

/// Bilinear lookup of the image `info` describes (one mip level) at `uv`, REPEAT addressing.
#[inline]
#[must_use]
fn bilinear<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    info: &TextureInfo,
    uv: Vec2,
) -> Vec4 {
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
    let flags = info.flags;
    if flags & (TEXTURE_ADDRESSING | TEXTURE_NEAREST) != 0 {
        return filtered_with_sampler(scene, source, info, fx, fy);
    }
    let x0 = floor(fx);
    let y0 = floor(fy);
    let tx = fx - x0;
    let ty = fy - y0;
    // Two integer remainders per lookup rather than one per texel coordinate (they are slow on both
    // targets, a scalar division per lane on lavapipe).
    let (x0, y0) = (wrap(x0 as i32, info.width), wrap(y0 as i32, info.height));
    let (x1, y1) = (next_wrapped(x0, info.width), next_wrapped(y0, info.height));
    blend(scene, source, info, [x0, x1], [y0, y1], [tx, ty])
}

/// [`bilinear`] for a texture whose sampler clamps, mirrors or reads the nearest texel (`fx`, `fy`: the
/// lookup in texel units, half a texel shifted, already bounded).
#[must_use]
fn filtered_with_sampler<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    info: &TextureInfo,
    fx: f32,
    fy: f32,
) -> Vec4 {
    let flags = info.flags;
    let (clamp_s, mirror_s) = (flags & TEXTURE_CLAMP_S != 0, flags & TEXTURE_MIRROR_S != 0);
    let (clamp_t, mirror_t) = (flags & TEXTURE_CLAMP_T != 0, flags & TEXTURE_MIRROR_T != 0);
    if flags & TEXTURE_NEAREST != 0 {
        // The texel the (unshifted) coordinate falls in.
        let x = address(floor(fx + 0.5) as i32, info.width, clamp_s, mirror_s);
        let y = address(floor(fy + 0.5) as i32, info.height, clamp_t, mirror_t);
        return fetch(scene, source, info, x, y);
    }
    let x0 = floor(fx);
    let y0 = floor(fy);
    let tx = fx - x0;
    let ty = fy - y0;
    let (xi, yi) = (x0 as i32, y0 as i32);
    let x0 = address(xi, info.width, clamp_s, mirror_s);
    let x1 = address(xi + 1, info.width, clamp_s, mirror_s);
    let y0 = address(yi, info.height, clamp_t, mirror_t);
    let y1 = address(yi + 1, info.height, clamp_t, mirror_t);
    blend(scene, source, info, [x0, x1], [y0, y1], [tx, ty])
}

/// The bilinear blend of texels (`xs[0..2]`, `ys[0..2]`), already addressed, with weights `t` of the second
/// column and row.
#[inline]
#[must_use]
fn blend<F: crate::scene::Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    info: &TextureInfo,
    xs: [u32; 2],
    ys: [u32; 2],
    t: [f32; 2],
) -> Vec4 {
    let c00 = fetch(scene, source, info, xs[0], ys[0]);
    let c10 = fetch(scene, source, info, xs[1], ys[0]);
    let c01 = fetch(scene, source, info, xs[0], ys[1]);
    let c11 = fetch(scene, source, info, xs[1], ys[1]);
    let top = c00 + (c10 - c00) * t[0];
    let bottom = c01 + (c11 - c01) * t[0];
    top + (bottom - top) * t[1]
}
