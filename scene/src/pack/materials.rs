//! The materials group: the materials, one record per texture and all texels in one array
//! ([`fovea_core::scene::MaterialArrays`]). sRGB colour textures become linear RGBA16 here, once, and
//! every texture larger than one texel gets its mip levels (box-filtered 2 × 2 in the stored, linear,
//! values, colour weighted by alpha; an odd edge's last texel joins its neighbours) unless its sampler asks
//! for none;
//! `fovea_core::material::texture::sample_texture_lod` reads them.
use fovea_core::kernel_abi::{BINDING_MATERIALS, BINDING_TEXELS, BINDING_TEXTURES};
use fovea_core::scene::{
    Material, MaterialArrays, TextureInfo, TEXTURE_ADDRESSING, TEXTURE_MIPMAPPED, TEXTURE_NEAREST,
    TEXTURE_RGBA16, TEXTURE_TRANSFORMED,
};
use glam::Vec3;

use super::array::{ArrayRead, PackedArray};
use crate::texture::{Texture, NO_MIP_LEVELS};

/// The material arrays, owned.
#[derive(Clone, Debug, Default)]
pub struct PackedMaterials {
    pub list: Vec<Material>,
    pub textures: Vec<TextureInfo>,
    pub texels: Vec<u32>,
}

impl PackedMaterials {
    /// The borrowed view core reads.
    #[must_use]
    pub fn view(&self) -> MaterialArrays<'_> {
        MaterialArrays {
            list: &self.list,
            textures: &self.textures,
            texels: &self.texels,
        }
    }

    /// The arrays the GPU receives, each with its binding (all read through the scene texel buffer).
    #[must_use]
    pub fn gpu_arrays(&self) -> [PackedArray<'_>; 3] {
        use ArrayRead::Texels;
        [
            PackedArray::new(BINDING_MATERIALS, "materials", Texels, &self.list),
            PackedArray::new(BINDING_TEXTURES, "texture infos", Texels, &self.textures),
            PackedArray::new(BINDING_TEXELS, "texels", Texels, &self.texels),
        ]
    }
}

/// Packs `materials` and their `textures`: one texel array, one info record each.
pub(super) fn pack_materials(materials: Vec<Material>, textures: &[Texture]) -> PackedMaterials {
    let mut infos = Vec::with_capacity(textures.len());
    let mut texels = Vec::with_capacity(packed_texel_words(textures) as usize);
    let linear16 = srgb8_to_linear16();
    for t in textures {
        if t.srgb && texels.len() % 2 == 1 {
            // RGBA16 textures start at an even word, so a texel's two words share one GPU texel.
            texels.push(0);
        }
        let mipmapped = t.width.max(t.height) > 1 && t.sampler & NO_MIP_LEVELS == 0;
        let mut flags = if t.srgb { TEXTURE_RGBA16 } else { 0 };
        flags |= t.sampler & (TEXTURE_ADDRESSING | TEXTURE_NEAREST);
        if mipmapped {
            flags |= TEXTURE_MIPMAPPED;
        }
        let (matrix, translation) = match t.transform {
            Some([m0, m1, m2, m3, tx, ty]) => {
                flags |= TEXTURE_TRANSFORMED;
                ([m0, m1, m2, m3], [tx, ty])
            }
            None => ([1.0, 0.0, 0.0, 1.0], [0.0, 0.0]),
        };
        infos.push(TextureInfo {
            offset: texels.len() as u32,
            width: t.width,
            height: t.height,
            flags,
            matrix,
            translation,
            _pad: [0; 2],
        });
        // Level 0 as 16-bit linear channels (sRGB) or bytes (data), then each level from the one before.
        let mut level: Vec<[u16; 4]> = if t.srgb {
            t.texels
                .iter()
                .map(|&texel| srgb_texel_to_linear16(texel, &linear16))
                .collect()
        } else {
            t.texels
                .iter()
                .map(|&texel| texel.to_le_bytes().map(u16::from))
                .collect()
        };
        let (mut w, mut h) = (t.width as usize, t.height as usize);
        loop {
            for c in &level {
                if t.srgb {
                    texels.push(u32::from(c[0]) | u32::from(c[1]) << 16);
                    texels.push(u32::from(c[2]) | u32::from(c[3]) << 16);
                } else {
                    texels.push(u32::from_le_bytes(c.map(|v| v as u8)));
                }
            }
            if !mipmapped || (w == 1 && h == 1) {
                break;
            }
            (level, w, h) = downsample(&level, w, h, t.srgb);
        }
    }
    PackedMaterials {
        list: materials,
        textures: infos,
        texels,
    }
}

/// The next mip level of a `w × h` level: each texel the mean of its 2 × 2 square (rounded), and on an odd
/// edge of the last one, 3 texels wide (so that no texel is left out of the coarser levels). Colour
/// textures (`weight_by_alpha`) weight colour by alpha, so that the colour of transparent texels (cut-out
/// leaves' surroundings, whatever the painter left there) does not bleed into coarser levels; alpha, and
/// colour where all are transparent, is the plain mean.
fn downsample(
    level: &[[u16; 4]],
    w: usize,
    h: usize,
    weight_by_alpha: bool,
) -> (Vec<[u16; 4]>, usize, usize) {
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    // The source span of output coordinate `i` of `n` over `size`: [2i, 2i + 1], the last one reaching
    // the edge.
    let span = |i: usize, n: usize, size: usize| {
        let start = (2 * i).min(size - 1);
        let end = if i + 1 == n {
            size - 1
        } else {
            (2 * i + 1).min(size - 1)
        };
        start..=end
    };
    let mut out = Vec::with_capacity(nw * nh);
    for y in 0..nh {
        for x in 0..nw {
            let (mut sum, mut weighted, mut count) = ([0u64; 4], [0u64; 3], 0u64);
            for sy in span(y, nh, h) {
                for sx in span(x, nw, w) {
                    let t = level[sy * w + sx];
                    for k in 0..4 {
                        sum[k] += u64::from(t[k]);
                    }
                    for k in 0..3 {
                        weighted[k] += u64::from(t[k]) * u64::from(t[3]);
                    }
                    count += 1;
                }
            }
            let alpha = sum[3];
            out.push(std::array::from_fn(|k| {
                let v = if k < 3 && weight_by_alpha && alpha > 0 {
                    (weighted[k] + alpha / 2) / alpha
                } else {
                    (sum[k] + count / 2) / count
                };
                v as u16
            }));
        }
    }
    (out, nw, nh)
}

/// The texels of a `width × height` texture and all its mip levels down to 1 × 1.
#[must_use]
pub fn mip_chain_texels(width: u32, height: u32) -> u64 {
    let (mut w, mut h) = (u64::from(width.max(1)), u64::from(height.max(1)));
    let mut total = w * h;
    while w > 1 || h > 1 {
        w = (w / 2).max(1);
        h = (h / 2).max(1);
        total += w * h;
    }
    total
}

/// At most the `u32` words the packed texel array of `textures` needs: one per RGBA8 texel, two per
/// sRGB texel (stored as linear RGBA16, see `fovea_core::scene::TEXTURE_RGBA16`), over every mip level,
/// and one of padding per texture (RGBA16 textures start at an even word). The loaders refuse scenes
/// whose textures need more than `u32::MAX`.
#[must_use]
pub fn packed_texel_words(textures: &[Texture]) -> u64 {
    textures
        .iter()
        .map(|t| {
            let texels = if t.sampler & NO_MIP_LEVELS != 0 {
                u64::from(t.width) * u64::from(t.height)
            } else {
                mip_chain_texels(t.width, t.height)
            };
            texels * if t.srgb { 2 } else { 1 } + 1
        })
        .sum()
}

/// The 16-bit unorm linear value of each 8-bit sRGB level (IEC 61966-2-1, evaluated in f64).
fn srgb8_to_linear16() -> [u16; 256] {
    std::array::from_fn(|i| {
        let v = i as f64 / 255.0;
        let linear = if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        };
        (linear * 65535.0).round() as u16
    })
}

/// An RGBA8 sRGB texel as 16-bit unorm linear RGBA (`linear16` from [`srgb8_to_linear16`]; alpha is
/// linear already and only widened).
fn srgb_texel_to_linear16(texel: u32, linear16: &[u16; 256]) -> [u16; 4] {
    let [r, g, b, a] = texel.to_le_bytes();
    [
        linear16[usize::from(r)],
        linear16[usize::from(g)],
        linear16[usize::from(b)],
        u16::from(a) * 257,
    ]
}

/// Mean linear colour of a texture, as its lookups see it (sRGB texels decoded as the packer stores
/// them).
pub(super) fn mean_texture_color(t: &Texture) -> Vec3 {
    if t.texels.is_empty() {
        return Vec3::ONE;
    }
    let linear16 = srgb8_to_linear16();
    let mut sum = glam::DVec3::ZERO;
    for &texel in &t.texels {
        sum += if t.srgb {
            let [r, g, b, _] = srgb_texel_to_linear16(texel, &linear16).map(f64::from);
            glam::DVec3::new(r, g, b) / 65535.0
        } else {
            let [r, g, b, _] = texel.to_le_bytes().map(f64::from);
            glam::DVec3::new(r, g, b) / 255.0
        };
    }
    (sum / t.texels.len() as f64).as_vec3()
}
