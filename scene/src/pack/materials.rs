//! The materials group: the materials, one record per texture and all texels in one array
//! ([`fovea_core::scene::MaterialArrays`]). sRGB colour textures become linear RGBA16 here, once.
use fovea_core::kernel_abi::{BINDING_MATERIALS, BINDING_TEXELS, BINDING_TEXTURES};
use fovea_core::scene::{Material, MaterialArrays, TextureInfo, TEXTURE_RGBA16};
use glam::Vec3;

use super::{ArrayRead, PackedArray};
use crate::texture::Texture;

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
        infos.push(TextureInfo {
            offset: texels.len() as u32,
            width: t.width,
            height: t.height,
            flags: if t.srgb { TEXTURE_RGBA16 } else { 0 },
        });
        if t.srgb {
            for &texel in &t.texels {
                let [r, g, b, a] = srgb_texel_to_linear16(texel, &linear16).map(u32::from);
                texels.push(r | g << 16);
                texels.push(b | a << 16);
            }
        } else {
            texels.extend_from_slice(&t.texels);
        }
    }
    PackedMaterials {
        list: materials,
        textures: infos,
        texels,
    }
}

/// At most the `u32` words the packed texel array of `textures` needs: one per RGBA8 texel, two per
/// sRGB texel (stored as linear RGBA16, see `fovea_core::scene::TEXTURE_RGBA16`), and one of padding per
/// texture (RGBA16 textures start at an even word). The loaders refuse scenes whose textures need more
/// than `u32::MAX`.
#[must_use]
pub fn packed_texel_words(textures: &[Texture]) -> u64 {
    textures
        .iter()
        .map(|t| t.texels.len() as u64 * if t.srgb { 2 } else { 1 } + 1)
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
