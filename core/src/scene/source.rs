//! Where core reads the scene's large arrays: the BVH nodes and triangle blocks traversal tests, and
//! what shading reads at a hit (triangle positions, from the blocks, and info, materials, vertex normals,
//! texture coordinates and colours, texture infos and texels).
//!
//! On the CPU from the [`SceneView`]'s slices ([`SceneSlices`]). On the GPU from one storage texel
//! buffer that holds all of them (`SceneTexels`, `R32G32B32A32_UINT`): each array starts at the texel
//! named in [`SceneGlobals::texel_offsets`](crate::scene::SceneGlobals::texel_offsets) (nodes at 0) and
//! holds the same bytes as the slice, so a 16-byte element is one texel, a [`Bvh4Node`] seven, and two
//! texture coordinates or four texture words share one.
//!
//! Why a texel buffer: lavapipe (Mesa 25) compiles a storage-buffer load whose offset differs between
//! invocations into a loop over the 8 lanes with a bounds check per component, but a texel-buffer read
//! into a branch-free gather; traversal is mostly such loads, and reading nodes and triangles through a
//! texel buffer made frames 31-36 % faster there (docs/performance.md, "lavapipe against the CPU host"). rust-gpu
//! cannot keep an image inside a struct, so the source is an argument of its own next to the
//! [`SceneView`] rather than one of its fields.
use crate::scene::features::Features;
use crate::scene::layout::{
    positions_at, Bvh4Node, Material, TextureInfo, TriangleBlock, TriangleInfo, TrianglePositions,
};
use crate::scene::view::SceneView;

/// Texels (16 bytes each) per [`Bvh4Node`].
pub const NODE_TEXELS: u32 = 7;
/// Texels per [`Material`].
pub const MATERIAL_TEXELS: u32 = 10;
/// Texels per [`TriangleBlock`].
pub const BLOCK_TEXELS: u32 = 10;
/// Texels per [`TextureInfo`].
pub const TEXTURE_INFO_TEXELS: u32 = 3;

const _: () = {
    assert!(core::mem::size_of::<Bvh4Node>() == NODE_TEXELS as usize * 16);
    assert!(core::mem::size_of::<Material>() == MATERIAL_TEXELS as usize * 16);
    assert!(core::mem::size_of::<TriangleBlock>() == BLOCK_TEXELS as usize * 16);
    assert!(core::mem::size_of::<TriangleInfo>() == 16);
    assert!(core::mem::size_of::<TextureInfo>() == TEXTURE_INFO_TEXELS as usize * 16);
};

/// Reads the scene's large arrays (see the module documentation). Indices are those of the
/// [`SceneView`]'s slices.
pub trait SceneSource {
    /// Node `index` of the BVH (root 0).
    fn node<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Bvh4Node;
    /// The positions of triangle `index` (BVH leaf order), from its block lane
    /// ([`GeometryArrays::triangle_lanes`](crate::scene::GeometryArrays::triangle_lanes)).
    fn triangle<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TrianglePositions;
    /// The positions of triangle block `index`, which leaves name (its `index` field is not read: see
    /// [`Self::block_lanes`]).
    fn block<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TriangleBlock;
    /// The [`TriangleBlock::index`] words of triangle block `index`, read apart because a ray usually
    /// hits none of a block's triangles.
    fn block_lanes<F: Features>(&self, scene: &SceneView<F>, index: u32) -> glam::UVec4;
    /// Vertex indices and material of triangle `index`.
    fn triangle_info<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TriangleInfo;
    /// Material `index`.
    fn material<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Material;
    /// Shading normal of vertex `index` (the scene must have normals).
    fn normal<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [f32; 4];
    /// Texture coordinates of vertex `index` (the scene must have them).
    fn uv<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [f32; 2];
    /// The encoded colour of vertex `index` (the scene must have vertex colours;
    /// [`crate::material::vertex_color`]).
    fn vertex_color<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [u32; 2];
    /// Texture `index`'s record.
    fn texture<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TextureInfo;
    /// Word `index` of the packed texture texels.
    fn texel<F: Features>(&self, scene: &SceneView<F>, index: u32) -> u32;
    /// Words `index` and `index + 1` of the packed texture texels, for an even `index` (an RGBA16
    /// texel; the packer starts RGBA16 textures at even words).
    fn texel_pair<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [u32; 2];
}

/// Reads the [`SceneView`]'s slices: the CPU's source.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneSlices;

impl SceneSource for SceneSlices {
    #[inline(always)]
    fn node<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Bvh4Node {
        scene.geometry.nodes[index as usize]
    }

    #[inline(always)]
    fn triangle<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TrianglePositions {
        positions_at(
            scene.geometry.blocks,
            scene.geometry.triangle_lanes[index as usize],
        )
    }

    #[inline(always)]
    fn block<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TriangleBlock {
        scene.geometry.blocks[index as usize]
    }

    #[inline(always)]
    fn block_lanes<F: Features>(&self, scene: &SceneView<F>, index: u32) -> glam::UVec4 {
        scene.geometry.blocks[index as usize].index
    }

    #[inline(always)]
    fn triangle_info<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TriangleInfo {
        scene.geometry.triangle_info[index as usize]
    }

    #[inline(always)]
    fn material<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Material {
        scene.materials.list[index as usize]
    }

    #[inline(always)]
    fn normal<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [f32; 4] {
        scene.geometry.normals[index as usize]
    }

    #[inline(always)]
    fn uv<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [f32; 2] {
        scene.geometry.uvs[index as usize]
    }

    #[inline(always)]
    fn vertex_color<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [u32; 2] {
        scene.geometry.vertex_colors[index as usize]
    }

    #[inline(always)]
    fn texture<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TextureInfo {
        scene.materials.textures[index as usize]
    }

    #[inline(always)]
    fn texel<F: Features>(&self, scene: &SceneView<F>, index: u32) -> u32 {
        scene.materials.texels[index as usize]
    }

    #[inline(always)]
    fn texel_pair<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [u32; 2] {
        [
            scene.materials.texels[index as usize],
            scene.materials.texels[index as usize + 1],
        ]
    }
}

/// The GPU's scene texel buffer (see the module documentation).
#[cfg(target_arch = "spirv")]
pub type SceneTexels = spirv_std::Image!(buffer, format = rgba32ui, sampled = false);

#[cfg(target_arch = "spirv")]
mod texels {
    use super::*;
    use crate::math::lane_mask::lane_u32;
    use crate::scene::layout::{block_and_lane, texel_floats};
    use glam::UVec4;

    /// The seven texels from `first` on (a node: [`NODE_TEXELS`]). Written out rather than a loop
    /// filling a local array, which lavapipe would index dynamically.
    #[inline(always)]
    fn seven_texels(texels: &SceneTexels, first: u32) -> [UVec4; 7] {
        [
            texels.read(first),
            texels.read(first + 1),
            texels.read(first + 2),
            texels.read(first + 3),
            texels.read(first + 4),
            texels.read(first + 5),
            texels.read(first + 6),
        ]
    }

    /// The ten texels of the material at `first` ([`MATERIAL_TEXELS`]), written out as
    /// [`seven_texels`].
    #[inline(always)]
    fn material_texels(texels: &SceneTexels, first: u32) -> [UVec4; 10] {
        let s = seven_texels(texels, first);
        [
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5],
            s[6],
            texels.read(first + 7),
            texels.read(first + 8),
            texels.read(first + 9),
        ]
    }

    impl SceneSource for SceneTexels {
        #[inline(always)]
        fn node<F: Features>(&self, _scene: &SceneView<F>, index: u32) -> Bvh4Node {
            Bvh4Node::from_texels(seven_texels(self, index * NODE_TEXELS))
        }

        #[inline(always)]
        fn triangle<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TrianglePositions {
            let w: UVec4 = self.read(scene.globals.texel_offsets.triangle_lanes + index / 4);
            let (block, lane) = block_and_lane(lane_u32(w, (index % 4) as usize));
            self.block(scene, block).lane_positions(lane)
        }

        #[inline(always)]
        fn block<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TriangleBlock {
            let t = scene.globals.texel_offsets.blocks + index * BLOCK_TEXELS;
            TriangleBlock::from_position_texels([
                self.read(t),
                self.read(t + 1),
                self.read(t + 2),
                self.read(t + 3),
                self.read(t + 4),
                self.read(t + 5),
                self.read(t + 6),
                self.read(t + 7),
                self.read(t + 8),
            ])
        }

        #[inline(always)]
        fn block_lanes<F: Features>(&self, scene: &SceneView<F>, index: u32) -> UVec4 {
            self.read(scene.globals.texel_offsets.blocks + index * BLOCK_TEXELS + 9)
        }

        #[inline(always)]
        fn triangle_info<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TriangleInfo {
            TriangleInfo::from_texel(self.read(scene.globals.texel_offsets.triangle_info + index))
        }

        #[inline(always)]
        fn material<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Material {
            let first = scene.globals.texel_offsets.materials + index * MATERIAL_TEXELS;
            Material::from_texels(material_texels(self, first))
        }

        #[inline(always)]
        fn normal<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [f32; 4] {
            texel_floats(self.read(scene.globals.texel_offsets.normals + index)).to_array()
        }

        #[inline(always)]
        fn uv<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [f32; 2] {
            let w: UVec4 = self.read(scene.globals.texel_offsets.uvs + index / 2);
            let (u, v) = if index & 1 == 0 {
                (w.x, w.y)
            } else {
                (w.z, w.w)
            };
            [f32::from_bits(u), f32::from_bits(v)]
        }

        #[inline(always)]
        fn vertex_color<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [u32; 2] {
            let w: UVec4 = self.read(scene.globals.texel_offsets.vertex_colors + index / 2);
            if index & 1 == 0 {
                [w.x, w.y]
            } else {
                [w.z, w.w]
            }
        }

        #[inline(always)]
        fn texture<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TextureInfo {
            let first = scene.globals.texel_offsets.textures + index * TEXTURE_INFO_TEXELS;
            TextureInfo::from_texels([self.read(first), self.read(first + 1), self.read(first + 2)])
        }

        #[inline(always)]
        fn texel<F: Features>(&self, scene: &SceneView<F>, index: u32) -> u32 {
            let w: UVec4 = self.read(scene.globals.texel_offsets.texels + index / 4);
            lane_u32(w, (index & 3) as usize)
        }

        #[inline(always)]
        fn texel_pair<F: Features>(&self, scene: &SceneView<F>, index: u32) -> [u32; 2] {
            let w: UVec4 = self.read(scene.globals.texel_offsets.texels + index / 4);
            if index & 2 == 0 {
                [w.x, w.y]
            } else {
                [w.z, w.w]
            }
        }
    }
}
