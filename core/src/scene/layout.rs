//! GPU-layout scene types: exactly the bytes both backends receive.
//!
//! Every type here is `#[repr(C)]`, [`Pod`], built from 4-byte scalars, 4-byte-element arrays and the
//! 16-byte `Vec4`/`UVec4`, and a multiple of 16 bytes where it is an array element, so that its Rust
//! layout equals its std430 layout in SPIR-V. `glam::Vec3` is never used (12 bytes on the CPU, 16 in
//! rust-gpu). Absent references are [`INVALID_INDEX`]; booleans are bits in a `u32` flags word.
//!
//! The two types traversal reads, [`Bvh4Node`] and [`TriangleBlock`], hold `Vec4`/`UVec4` rather
//! than `[f32; 4]`. Every type the GPU reads from its scene texel buffer ([`super::source`]) is a whole
//! number of 16-byte texels.
use crate::math::lane_mask::lane_u32;
use bytemuck::{Pod, Zeroable};
use glam::{UVec4, Vec4};

/// Marks an absent index (no texture, no light, no triangle hit).
pub const INVALID_INDEX: u32 = u32::MAX;

/// The four words of a 16-byte texel as the floats they hold (the GPU reads the scene's arrays as `u32`
/// texels: see [`super::source`]).
#[inline(always)]
#[must_use]
pub(crate) fn texel_floats(u: UVec4) -> Vec4 {
    Vec4::new(
        f32::from_bits(u.x),
        f32::from_bits(u.y),
        f32::from_bits(u.z),
        f32::from_bits(u.w),
    )
}

/// A node of a binary bounding-volume hierarchy (32 bytes): the builder's intermediate form, which
/// `fovea_scene::bvh` collapses into [`Bvh4Node`]s. Traversal never sees it.
///
/// An interior node (`triangle_count == 0`) at arena slot `s` has its left child at `s + 1` and its right
/// child at `s + left_or_first`. Leaves hold triangles `left_or_first .. left_or_first + triangle_count`
/// of the (BVH-ordered) triangle arrays.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub bounds_min: [f32; 3],
    pub left_or_first: u32,
    pub bounds_max: [f32; 3],
    pub triangle_count: u32,
}

impl BvhNode {
    /// Whether this node is a leaf.
    #[inline]
    #[must_use]
    pub fn is_leaf(&self) -> bool {
        self.triangle_count != 0
    }
}

/// [`Bvh4Node::slots`]: marks a leaf slot word (see [`Bvh4Node`]).
pub const SLOT_LEAF: u32 = 1 << 31;
/// [`Bvh4Node::slots`]: an empty slot.
pub const SLOT_EMPTY: u32 = INVALID_INDEX;
/// A leaf's triangle count minus one sits in the 4 bits from here.
const LEAF_COUNT_SHIFT: u32 = 27;
/// A leaf's first triangle or block sits in the low 27 bits.
const LEAF_FIRST_MASK: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// Most triangles one leaf may hold: what its 4-bit count can say. The builder keeps leaves at this many
/// triangles or fewer.
pub const MAX_LEAF_TRIANGLES: u32 = 16;
/// Leaf triangle and block indices stay below this (27 bits); `first + count` at most this.
pub const MAX_LEAF_TRIANGLE_INDEX: u32 = 1 << LEAF_COUNT_SHIFT;

/// The slot word of a leaf of `count` triangles (`1 <= count <= MAX_LEAF_TRIANGLES`) from `first` (`first
/// + count <= MAX_LEAF_TRIANGLE_INDEX`): in a built BVH (`fovea_scene::bvh::Bvh`) `first` is the first of
/// the triangles in the leaf-ordered arrays; once packed, the first of the `ceil(count / 4)`
/// [`TriangleBlock`]s that hold them (the packer rewrites each leaf's word).
#[inline]
#[must_use]
pub const fn leaf_slot(first: u32, count: u32) -> u32 {
    SLOT_LEAF | ((count - 1) << LEAF_COUNT_SHIFT) | first
}

/// The first triangle of a leaf slot word.
#[inline(always)]
#[must_use]
pub const fn leaf_first(slot: u32) -> u32 {
    slot & LEAF_FIRST_MASK
}

/// Whether the slot word `word` names a leaf (not an interior node, not an empty slot); for either tree.
#[inline(always)]
#[must_use]
pub const fn is_leaf_word(word: u32) -> bool {
    word & SLOT_LEAF != 0 && word != SLOT_EMPTY
}

/// The triangle count of a leaf slot word.
#[inline(always)]
#[must_use]
pub const fn leaf_count(slot: u32) -> u32 {
    ((slot >> LEAF_COUNT_SHIFT) & (MAX_LEAF_TRIANGLES - 1)) + 1
}

/// `slot_bounds` and `set_slot_bounds` for a node type whose bounds are the per-lane indexable fields
/// `min_x` ... `max_z` ([`Bvh4Node`]'s `Vec4`s, the CPU's `Bvh8Node`'s `[f32; 8]`s).
macro_rules! slot_box_methods {
    () => {
        /// The box of slot `i` as `(min, max)`.
        #[inline]
        #[must_use]
        pub fn slot_bounds(&self, i: usize) -> ([f32; 3], [f32; 3]) {
            (
                [self.min_x[i], self.min_y[i], self.min_z[i]],
                [self.max_x[i], self.max_y[i], self.max_z[i]],
            )
        }

        /// Sets slot `i`'s box.
        #[inline]
        pub fn set_slot_bounds(&mut self, i: usize, min: [f32; 3], max: [f32; 3]) {
            self.min_x[i] = min[0];
            self.min_y[i] = min[1];
            self.min_z[i] = min[2];
            self.max_x[i] = max[0];
            self.max_y[i] = max[1];
            self.max_z[i] = max[2];
        }
    };
}

/// A node of the 4-wide BVH that both backends traverse (112 bytes), node 0 the root.
///
/// The boxes of the four children are stored structure-of-arrays, so one `Vec4` holds one bound of all
/// four and a single SIMD slab test checks the four boxes at once (Wald, Benthin, Boulos 2008,
/// "Getting rid of packets"; Dammertz et al. 2008, "Shallow bounding volume hierarchies"). Slot `i` is
/// described by one word, `slots[i]`:
/// - an interior node: its index, below [`SLOT_LEAF`];
/// - a leaf of `count` triangles: [`leaf_slot`]`(first, count)`, the triangles in the blocks `first ..`
///   of [`super::GeometryArrays::blocks`] (in a built, not yet packed, BVH, the triangles `first .. first +
///   count` of the leaf-ordered arrays), read back with [`leaf_first`] and [`leaf_count`];
/// - empty: [`SLOT_EMPTY`]. An empty slot's box is inverted (`min = f32::MAX`, `max = -f32::MAX`),
///   which the slab test (with near and far planes chosen by the ray's direction signs) always misses,
///   so it is never entered. (Read as a leaf, the word would end past [`MAX_LEAF_TRIANGLE_INDEX`].)
///
/// A slot word is also what traversal keeps on its stack, so a leaf is tested without reading its
/// parent again. Boxes strictly contain their triangles (the builder widens them by a few ulps).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Bvh4Node {
    pub min_x: Vec4,
    pub max_x: Vec4,
    pub min_y: Vec4,
    pub max_y: Vec4,
    pub min_z: Vec4,
    pub max_z: Vec4,
    pub slots: UVec4,
}

impl Bvh4Node {
    /// The node whose bytes are the texels `t` (the GPU's scene texel buffer holds nodes as seven
    /// texels: the six bound vectors, then the slot words).
    #[inline(always)]
    #[must_use]
    pub fn from_texels(t: [UVec4; 7]) -> Self {
        Self {
            min_x: texel_floats(t[0]),
            max_x: texel_floats(t[1]),
            min_y: texel_floats(t[2]),
            max_y: texel_floats(t[3]),
            min_z: texel_floats(t[4]),
            max_z: texel_floats(t[5]),
            slots: t[6],
        }
    }

    /// A node with four empty slots.
    pub const EMPTY: Self = Self {
        min_x: Vec4::splat(f32::MAX),
        max_x: Vec4::splat(-f32::MAX),
        min_y: Vec4::splat(f32::MAX),
        max_y: Vec4::splat(-f32::MAX),
        min_z: Vec4::splat(f32::MAX),
        max_z: Vec4::splat(-f32::MAX),
        slots: UVec4::splat(SLOT_EMPTY),
    };

    /// The word of slot `i` (see the type's docs).
    ///
    /// Read by value rather than by indexing `slots` in place: on the GPU, indexing a vector in place
    /// makes rust-gpu select between pointers, which SPIR-V's logical addressing does not allow.
    #[inline(always)]
    #[must_use]
    pub fn slot(&self, i: usize) -> u32 {
        lane_u32(self.slots, i)
    }

    /// Whether slot `i` is empty.
    #[inline]
    #[must_use]
    pub fn is_empty_slot(&self, i: usize) -> bool {
        self.slot(i) == SLOT_EMPTY
    }

    /// Whether slot `i` is a leaf.
    #[inline]
    #[must_use]
    pub fn is_leaf_slot(&self, i: usize) -> bool {
        is_leaf_word(self.slot(i))
    }

    /// Whether slot `i` is an interior node.
    #[inline]
    #[must_use]
    pub fn is_interior_slot(&self, i: usize) -> bool {
        self.slot(i) & SLOT_LEAF == 0
    }

    slot_box_methods!();
}

impl Default for Bvh4Node {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// World-space vertex positions of one triangle (48 bytes; `w` is unused and zero): what shading and
/// light sampling get from [`super::SceneSource::triangle`], and the builder's input. Packed scenes store
/// positions only in [`TriangleBlock`]s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TrianglePositions {
    pub v0: Vec4,
    pub v1: Vec4,
    pub v2: Vec4,
}

/// Up to four triangles of one BVH leaf, structure of arrays (160 bytes), which traversal tests with one
/// SIMD watertight test: lane `k` of each vector is triangle `index[k]`'s. A leaf's triangles fill
/// `ceil(count / 4)` consecutive blocks, and a packed BVH's leaf slot words name blocks
/// ([`leaf_slot`]). Unused lanes of a leaf's last block have degenerate positions (all zero: never hit)
/// and `index` [`INVALID_INDEX`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TriangleBlock {
    pub v0x: Vec4,
    pub v0y: Vec4,
    pub v0z: Vec4,
    pub v1x: Vec4,
    pub v1y: Vec4,
    pub v1z: Vec4,
    pub v2x: Vec4,
    pub v2y: Vec4,
    pub v2z: Vec4,
    /// Each lane's triangle (BVH leaf order, the index of [`super::GeometryArrays::triangle_info`]), with
    /// [`BLOCK_LANE_CUTOUT`] set
    /// when its material has an alpha cut-out (so traversal runs the cut-out test only for such
    /// triangles, without reading their material first).
    pub index: UVec4,
}

/// [`TriangleBlock::index`]: the lane's triangle has an alpha cut-out material.
pub const BLOCK_LANE_CUTOUT: u32 = 1 << 31;

impl TriangleBlock {
    /// A block of four unused lanes.
    pub const EMPTY: Self = Self {
        v0x: Vec4::ZERO,
        v0y: Vec4::ZERO,
        v0z: Vec4::ZERO,
        v1x: Vec4::ZERO,
        v1y: Vec4::ZERO,
        v1z: Vec4::ZERO,
        v2x: Vec4::ZERO,
        v2y: Vec4::ZERO,
        v2z: Vec4::ZERO,
        index: UVec4::splat(INVALID_INDEX),
    };

    /// The block whose position bytes are the texels `t` (the first nine of its ten), with `index`
    /// zero: traversal reads the index words apart, as the tenth texel (`SceneSource::block_lanes`).
    #[inline(always)]
    #[must_use]
    pub fn from_position_texels(t: [UVec4; 9]) -> Self {
        Self {
            v0x: texel_floats(t[0]),
            v0y: texel_floats(t[1]),
            v0z: texel_floats(t[2]),
            v1x: texel_floats(t[3]),
            v1y: texel_floats(t[4]),
            v1z: texel_floats(t[5]),
            v2x: texel_floats(t[6]),
            v2y: texel_floats(t[7]),
            v2z: texel_floats(t[8]),
            index: UVec4::ZERO,
        }
    }

    /// Puts triangle `index` (positions `t`, cut-out flag included in `index`) in lane `lane`.
    #[inline]
    pub fn set_lane(&mut self, lane: usize, t: &TrianglePositions, index: u32) {
        self.v0x[lane] = t.v0.x;
        self.v0y[lane] = t.v0.y;
        self.v0z[lane] = t.v0.z;
        self.v1x[lane] = t.v1.x;
        self.v1y[lane] = t.v1.y;
        self.v1z[lane] = t.v1.z;
        self.v2x[lane] = t.v2.x;
        self.v2y[lane] = t.v2.y;
        self.v2z[lane] = t.v2.z;
        self.index[lane] = index;
    }

    /// The positions in lane `lane` (0 to 3).
    #[inline(always)]
    #[must_use]
    pub fn lane_positions(&self, lane: usize) -> TrianglePositions {
        let at = |v: Vec4| -> f32 {
            // A lane read by value on the GPU (see `lane_mask::lane`); an indexed load on the CPU.
            #[cfg(target_arch = "spirv")]
            {
                crate::math::lane_mask::lane(v, lane)
            }
            #[cfg(not(target_arch = "spirv"))]
            {
                v[lane]
            }
        };
        TrianglePositions {
            v0: Vec4::new(at(self.v0x), at(self.v0y), at(self.v0z), 0.0),
            v1: Vec4::new(at(self.v1x), at(self.v1y), at(self.v1z), 0.0),
            v2: Vec4::new(at(self.v2x), at(self.v2y), at(self.v2z), 0.0),
        }
    }
}

/// The [`super::GeometryArrays::triangle_lanes`] word of lane `lane` (0 to 3) of block `block`.
#[inline]
#[must_use]
pub const fn triangle_lane(block: u32, lane: u32) -> u32 {
    4 * block + lane
}

/// The block and the lane a [`super::GeometryArrays::triangle_lanes`] word names (undoes [`triangle_lane`]).
#[inline]
#[must_use]
pub const fn block_and_lane(word: u32) -> (u32, usize) {
    (word / 4, (word % 4) as usize)
}

/// The positions in the lane of `blocks` that the [`super::GeometryArrays::triangle_lanes`] word `word`
/// names (the CPU's read; the GPU reads the block from its texel buffer).
#[inline(always)]
#[must_use]
pub fn positions_at(blocks: &[TriangleBlock], word: u32) -> TrianglePositions {
    let (block, lane) = block_and_lane(word);
    blocks[block as usize].lane_positions(lane)
}

/// What shading needs to know about one triangle besides its positions (16 bytes), in BVH leaf order.
///
/// `vertices` index the per-vertex arrays [`super::GeometryArrays::normals`] and [`super::GeometryArrays::uvs`];
/// those arrays are empty when the scene needs no shading normals or no texture coordinates.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriangleInfo {
    pub vertices: [u32; 3],
    pub material: u32,
}

impl TriangleInfo {
    /// The record whose bytes are the texel `t`.
    #[inline(always)]
    #[must_use]
    pub fn from_texel(t: UVec4) -> Self {
        Self {
            vertices: [t.x, t.y, t.z],
            material: t.w,
        }
    }
}

/// [`Material::flags`]: the material has an alpha cut-out (glTF MASK or BLEND, OBJ `map_d` / `d < 1`).
pub const MATERIAL_ALPHA_CUTOUT: u32 = 1;
/// [`Material::flags`]: the material emits from both faces (otherwise only from the front face, the side
/// the counter-clockwise winding faces).
pub const MATERIAL_DOUBLE_SIDED_EMISSION: u32 = 2;
/// [`Material::flags`]: the diffuse lobe is Lambertian instead of Burley's retro-reflective diffuse (see
/// [`crate::bsdf::DisneyParams::lambertian`]); set for purely diffuse OBJ materials on request.
pub const MATERIAL_LAMBERTIAN: u32 = 4;
/// [`Material::flags`]: the material's emission is its look, not a light (glTF `KHR_materials_unlit`):
/// the packer leaves its triangles out of the light list, so next-event estimation never picks them,
/// and the integrator adds their emission on camera rays only (it neither lights the scene nor shows
/// in reflections).
pub const MATERIAL_UNLIT: u32 = 8;
/// [`Material::flags`]: a transmissive material is a thin wall (glTF `KHR_materials_transmission` without
/// `KHR_materials_volume`): light passes straight through instead of refracting into a volume
/// (`crate::bsdf::dielectric::RoughDielectric::thin`).
pub const MATERIAL_THIN_WALLED: u32 = 16;

/// The number of glTF extension textures a [`Material`] holds ([`Material::extension_texture`]).
pub const EXTENSION_TEXTURES: u32 = 7;

/// A Disney "principled" material (Burley 2012) with optional textures (160 bytes).
///
/// Texture values multiply the factors as in glTF: base colour (RGB, alpha in A), metallic in B and
/// roughness in G of `metallic_roughness_texture`, tangent-space normal map, emissive colour. The glTF
/// extensions' textures (`transmission_texture` to `anisotropy_texture`) multiply their factor by the
/// channel their extension names (`crate::material::shading`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Linear RGB base colour and, in `w`, the opacity used by the alpha cut-out.
    pub base_color: [f32; 4],
    /// Linear RGB emitted radiance (factor × strength); `w` unused.
    pub emission: [f32; 4],
    pub metallic: f32,
    /// Perceptual roughness; the GGX alpha is its square.
    pub roughness: f32,
    pub anisotropic: f32,
    pub specular: f32,
    pub specular_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    /// Opacity below which a point is cut out (when [`MATERIAL_ALPHA_CUTOUT`] is set).
    pub alpha_cutoff: f32,
    /// glTF `normalTexture.scale`.
    pub normal_scale: f32,
    /// `MATERIAL_*` bits.
    pub flags: u32,
    pub base_color_texture: u32,
    pub metallic_roughness_texture: u32,
    pub normal_texture: u32,
    pub emission_texture: u32,
    /// A separate opacity texture (OBJ `map_d`), read from its alpha channel; [`INVALID_INDEX`] if none.
    pub alpha_texture: u32,
    /// Weight of the rough dielectric interface (`crate::bsdf::dielectric`, glTF
    /// `KHR_materials_transmission`): the non-metallic part of the material refracts this fraction of
    /// the light it does not reflect, tinted by the base colour. 0: opaque.
    pub transmission: f32,
    /// Index of refraction of the material's inside (relative to the outside, the side the
    /// counter-clockwise front face points to); read only where `transmission` is above 0.
    pub ior: f32,
    /// `transmission` × this texture's R (glTF `transmissionTexture`).
    pub transmission_texture: u32,
    /// Absorption coefficient σₐ of the inside, per unit of distance (glTF `KHR_materials_volume`:
    /// `−ln(attenuationColor) / attenuationDistance`); a path that travels `d` inside is attenuated by
    /// `exp(−σₐ d)` (Beer–Lambert). 0: clear.
    pub absorption: [f32; 3],
    /// `clearcoat` × this texture's R (glTF `clearcoatTexture`).
    pub clearcoat_texture: u32,
    /// The clear coat's roughness (`1 − clearcoat_gloss`) × this texture's G (glTF
    /// `clearcoatRoughnessTexture`).
    pub clearcoat_roughness_texture: u32,
    /// `sheen` × the largest of this texture's RGB (glTF `sheenColorTexture`).
    pub sheen_texture: u32,
    /// `specular` × this texture's A (glTF `specularTexture`).
    pub specular_texture: u32,
    /// `specular` × the largest of this texture's RGB (glTF `specularColorTexture`).
    pub specular_color_texture: u32,
    /// `anisotropic` × this texture's B (glTF `anisotropyTexture`; its RG direction is not read).
    pub anisotropy_texture: u32,
    pub _pad: [u32; 3],
}

impl Default for Material {
    fn default() -> Self {
        Self {
            base_color: [0.8, 0.8, 0.8, 1.0],
            emission: [0.0; 4],
            metallic: 0.0,
            roughness: 0.5,
            anisotropic: 0.0,
            specular: 0.5,
            specular_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 1.0,
            alpha_cutoff: 0.5,
            normal_scale: 1.0,
            flags: 0,
            base_color_texture: INVALID_INDEX,
            metallic_roughness_texture: INVALID_INDEX,
            normal_texture: INVALID_INDEX,
            emission_texture: INVALID_INDEX,
            alpha_texture: INVALID_INDEX,
            transmission: 0.0,
            ior: 1.5,
            transmission_texture: INVALID_INDEX,
            absorption: [0.0; 3],
            clearcoat_texture: INVALID_INDEX,
            clearcoat_roughness_texture: INVALID_INDEX,
            sheen_texture: INVALID_INDEX,
            specular_texture: INVALID_INDEX,
            specular_color_texture: INVALID_INDEX,
            anisotropy_texture: INVALID_INDEX,
            _pad: [0; 3],
        }
    }
}

impl Material {
    /// The material whose bytes are the texels `t`.
    #[inline(always)]
    #[must_use]
    pub fn from_texels(t: [UVec4; 10]) -> Self {
        let (factors, more, last, textures, alpha) = (t[2], t[3], t[4], t[5], t[6]);
        let (volume, extension, anisotropy) = (t[7], t[8], t[9]);
        Self {
            base_color: texel_floats(t[0]).to_array(),
            emission: texel_floats(t[1]).to_array(),
            metallic: f32::from_bits(factors.x),
            roughness: f32::from_bits(factors.y),
            anisotropic: f32::from_bits(factors.z),
            specular: f32::from_bits(factors.w),
            specular_tint: f32::from_bits(more.x),
            sheen: f32::from_bits(more.y),
            sheen_tint: f32::from_bits(more.z),
            clearcoat: f32::from_bits(more.w),
            clearcoat_gloss: f32::from_bits(last.x),
            alpha_cutoff: f32::from_bits(last.y),
            normal_scale: f32::from_bits(last.z),
            flags: last.w,
            base_color_texture: textures.x,
            metallic_roughness_texture: textures.y,
            normal_texture: textures.z,
            emission_texture: textures.w,
            alpha_texture: alpha.x,
            transmission: f32::from_bits(alpha.y),
            ior: f32::from_bits(alpha.z),
            transmission_texture: alpha.w,
            absorption: [
                f32::from_bits(volume.x),
                f32::from_bits(volume.y),
                f32::from_bits(volume.z),
            ],
            clearcoat_texture: volume.w,
            clearcoat_roughness_texture: extension.x,
            sheen_texture: extension.y,
            specular_texture: extension.z,
            specular_color_texture: extension.w,
            anisotropy_texture: anisotropy.x,
            _pad: [0; 3],
        }
    }

    /// Whether the material emits light.
    #[inline]
    #[must_use]
    pub fn is_emissive(&self) -> bool {
        self.emission[0] > 0.0 || self.emission[1] > 0.0 || self.emission[2] > 0.0
    }

    /// Whether the material reads any texture (and so needs the vertices' texture coordinates).
    #[inline]
    #[must_use]
    pub fn has_texture(&self) -> bool {
        self.base_color_texture != INVALID_INDEX
            || self.metallic_roughness_texture != INVALID_INDEX
            || self.normal_texture != INVALID_INDEX
            || self.emission_texture != INVALID_INDEX
            || self.alpha_texture != INVALID_INDEX
            || self.has_extension_texture()
    }

    /// Every texture index the material holds ([`INVALID_INDEX`] where it has none), for passes that
    /// renumber textures (the CPU's loaders; not for the kernel).
    #[must_use]
    pub fn texture_indices_mut(&mut self) -> [&mut u32; 12] {
        [
            &mut self.base_color_texture,
            &mut self.metallic_roughness_texture,
            &mut self.normal_texture,
            &mut self.emission_texture,
            &mut self.alpha_texture,
            &mut self.transmission_texture,
            &mut self.clearcoat_texture,
            &mut self.clearcoat_roughness_texture,
            &mut self.sheen_texture,
            &mut self.specular_texture,
            &mut self.specular_color_texture,
            &mut self.anisotropy_texture,
        ]
    }

    /// The `slot`-th (0 to [`EXTENSION_TEXTURES`] − 1) of the glTF extensions' textures: transmission,
    /// clear coat, clear-coat roughness, sheen colour, specular, specular colour, anisotropy.
    #[inline(always)]
    #[must_use]
    pub fn extension_texture(&self, slot: u32) -> u32 {
        match slot {
            0 => self.transmission_texture,
            1 => self.clearcoat_texture,
            2 => self.clearcoat_roughness_texture,
            3 => self.sheen_texture,
            4 => self.specular_texture,
            5 => self.specular_color_texture,
            _ => self.anisotropy_texture,
        }
    }

    /// Whether the material reads one of the glTF extensions' textures ([`Self::extension_texture`]).
    #[inline]
    #[must_use]
    pub fn has_extension_texture(&self) -> bool {
        let mut slot = 0;
        while slot < EXTENSION_TEXTURES {
            if self.extension_texture(slot) != INVALID_INDEX {
                return true;
            }
            slot += 1;
        }
        false
    }

    /// Whether shading reads a tangent at the material's points: for its normal map or its anisotropy.
    #[inline]
    #[must_use]
    pub fn reads_tangent(&self) -> bool {
        self.normal_texture != INVALID_INDEX || !(self.anisotropic == 0.0)
    }

    /// Whether the material's inside absorbs (`absorption` above 0 in some channel).
    #[inline]
    #[must_use]
    pub fn absorbs(&self) -> bool {
        self.absorption[0] > 0.0 || self.absorption[1] > 0.0 || self.absorption[2] > 0.0
    }
}

/// [`TextureInfo::flags`]: the texels are RGBA16, two `u32` each (`R | G << 16`, `B | A << 16`, 16-bit
/// unorm): the loader's sRGB colour textures, decoded to linear once when the scene is packed, so that a
/// lookup needs no transfer function (three `powf` per lookup were a sixth of Lost Empire's CPU time) and
/// filters linear values, as pbrt and GPUs' sRGB formats do. Without the flag, texels are RGBA8, one `u32`
/// each (R in the low byte), used as stored.
pub const TEXTURE_RGBA16: u32 = 1;
/// [`TextureInfo::flags`]: mip levels follow level 0 in the texel array, halving down to 1 × 1 (box
/// filtered at load, in linear space; see `crate::material::texture::mip_level`).
pub const TEXTURE_MIPMAPPED: u32 = 2;
/// [`TextureInfo::flags`]: the `s` (u) coordinate clamps to the edge texels (glTF `CLAMP_TO_EDGE`).
pub const TEXTURE_CLAMP_S: u32 = 1 << 4;
/// [`TextureInfo::flags`]: the `s` coordinate repeats mirrored (glTF `MIRRORED_REPEAT`).
pub const TEXTURE_MIRROR_S: u32 = 1 << 5;
/// [`TextureInfo::flags`]: the `t` (v) coordinate clamps to the edge texels.
pub const TEXTURE_CLAMP_T: u32 = 1 << 6;
/// [`TextureInfo::flags`]: the `t` coordinate repeats mirrored.
pub const TEXTURE_MIRROR_T: u32 = 1 << 7;
/// [`TextureInfo::flags`]: lookups read the nearest texel instead of interpolating (glTF `NEAREST`).
pub const TEXTURE_NEAREST: u32 = 1 << 8;
/// [`TextureInfo::flags`]: texture coordinates are transformed by [`TextureInfo::matrix`] and
/// [`TextureInfo::translation`] before the lookup.
pub const TEXTURE_TRANSFORMED: u32 = 1 << 9;
/// Every addressing bit: without any, coordinates repeat (glTF `REPEAT`, the default).
pub const TEXTURE_ADDRESSING: u32 =
    TEXTURE_CLAMP_S | TEXTURE_MIRROR_S | TEXTURE_CLAMP_T | TEXTURE_MIRROR_T;

/// Where one texture's texels lie in [`super::MaterialArrays::texels`] and how they are looked up (48
/// bytes, three texels): `offset` is the index of its first `u32`; texels are row-major, top row first,
/// RGBA8 or, with [`TEXTURE_RGBA16`] in `flags`, RGBA16; `flags` also holds the sampler's addressing and
/// filter and whether mip levels follow. With [`TEXTURE_TRANSFORMED`], texture coordinates are mapped by
/// `uv' = [m0 m1; m2 m3] uv + translation` first (glTF `KHR_texture_transform`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TextureInfo {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub flags: u32,
    /// The 2 × 2 part of the coordinate transform, row-major.
    pub matrix: [f32; 4],
    pub translation: [f32; 2],
    pub _pad: [u32; 2],
}

impl TextureInfo {
    /// The record whose bytes are the texels `t`.
    #[inline(always)]
    #[must_use]
    pub fn from_texels(t: [UVec4; 3]) -> Self {
        Self {
            offset: t[0].x,
            width: t[0].y,
            height: t[0].z,
            flags: t[0].w,
            matrix: texel_floats(t[1]).to_array(),
            translation: [f32::from_bits(t[2].x), f32::from_bits(t[2].y)],
            _pad: [0; 2],
        }
    }
}

/// [`Light::kind`]: an emissive triangle ([`Light::index`] is the triangle).
pub const LIGHT_TRIANGLE: u32 = 0;
/// [`Light::kind`]: the environment (constant or map, see [`SceneGlobals`]).
pub const LIGHT_ENVIRONMENT: u32 = 1;
/// [`Light::kind`]: a KHR_lights_punctual point light.
pub const LIGHT_POINT: u32 = 2;
/// [`Light::kind`]: a KHR_lights_punctual spot light.
pub const LIGHT_SPOT: u32 = 3;
/// [`Light::kind`]: a KHR_lights_punctual directional light.
pub const LIGHT_DIRECTIONAL: u32 = 4;

/// One entry of the light list that next-event estimation picks from (64 bytes).
///
/// Lights are chosen with probability `pmf`, proportional to an estimate of their power; the matching
/// cumulative table is [`super::LightArrays::cdf`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    /// `LIGHT_*`.
    pub kind: u32,
    /// The emissive triangle for [`LIGHT_TRIANGLE`].
    pub index: u32,
    /// Probability of picking this light.
    pub pmf: f32,
    pub _pad: u32,
    /// Point and spot: world position; `w`: spot `cos(inner cone angle)`.
    pub position: [f32; 4],
    /// Spot and directional: the direction light travels (unit); `w` unused.
    pub direction: [f32; 4],
    /// Point and spot: intensity in W/sr per channel; directional: irradiance. `w`: spot
    /// `cos(outer cone angle)`.
    pub intensity: [f32; 4],
}

/// [`SceneGlobals::environment_kind`]: no environment; escaping rays see black.
pub const ENVIRONMENT_NONE: u32 = 0;
/// [`SceneGlobals::environment_kind`]: constant radiance `environment_radiance` in every direction.
pub const ENVIRONMENT_CONSTANT: u32 = 1;
/// [`SceneGlobals::environment_kind`]: an equirectangular HDR map scaled by `environment_radiance`.
pub const ENVIRONMENT_MAP: u32 = 2;

/// Scene-wide constants (96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SceneGlobals {
    /// Constant environment radiance, or the scale of the environment map; `w` unused.
    pub environment_radiance: [f32; 4],
    /// `ENVIRONMENT_*`.
    pub environment_kind: u32,
    pub environment_width: u32,
    pub environment_height: u32,
    /// Number of entries in the light list.
    pub light_count: u32,
    /// Integral of the environment map's sampling function over the unit square (normalises its pdf).
    pub environment_integral: f32,
    /// Index of the environment in the light list, or [`INVALID_INDEX`] when there is none.
    pub environment_light: u32,
    pub _pad: [u32; 2],
    /// Where the arrays start in the GPU's scene texel buffer; set by the Vulkan host when it uploads the
    /// scene, unused on the CPU.
    pub texel_offsets: TexelOffsets,
}

/// The first texel of each array in the GPU's scene texel buffer ([`super::source`]); the BVH nodes
/// start at texel 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct TexelOffsets {
    pub triangle_lanes: u32,
    pub triangle_info: u32,
    pub materials: u32,
    pub normals: u32,
    pub uvs: u32,
    pub textures: u32,
    pub texels: u32,
    pub blocks: u32,
    pub vertex_colors: u32,
    pub _pad: [u32; 3],
}

/// A node of the CPU's 8-wide BVH (224 bytes, 32-byte aligned; traversed by [`crate::bvh::wide`]),
/// node 0 the root. Boxes are stored structure-of-arrays, one 8-lane vector per bound; `slots` are
/// [`Bvh4Node`] slot words (an interior node's index here, a leaf's blocks, or [`SLOT_EMPTY`] with
/// an inverted box).
#[cfg(not(target_arch = "spirv"))]
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Bvh8Node {
    pub min_x: [f32; 8],
    pub max_x: [f32; 8],
    pub min_y: [f32; 8],
    pub max_y: [f32; 8],
    pub min_z: [f32; 8],
    pub max_z: [f32; 8],
    pub slots: [u32; 8],
}

#[cfg(not(target_arch = "spirv"))]
impl Bvh8Node {
    /// A node with eight empty slots.
    pub const EMPTY: Self = Self {
        min_x: [f32::MAX; 8],
        max_x: [-f32::MAX; 8],
        min_y: [f32::MAX; 8],
        max_y: [-f32::MAX; 8],
        min_z: [f32::MAX; 8],
        max_z: [-f32::MAX; 8],
        slots: [SLOT_EMPTY; 8],
    };

    slot_box_methods!();

    /// The six bound arrays as rows `min_x, max_x, min_y, max_y, min_z, max_z` (row 6 is the slot
    /// words), so that traversal can index them by axis and ray direction.
    #[inline(always)]
    #[must_use]
    pub fn bound_rows(&self) -> &[[f32; 8]; 7] {
        bytemuck::cast_ref(self)
    }
}

#[cfg(not(target_arch = "spirv"))]
impl Default for Bvh8Node {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texels the GPU reads for `value`: its bytes, sixteen at a time, as the packer uploads them.
    fn texels<T: Pod, const N: usize>(value: &T) -> [UVec4; N] {
        let words: &[u32] = bytemuck::cast_slice(bytemuck::bytes_of(value));
        assert_eq!(words.len(), 4 * N);
        core::array::from_fn(|i| UVec4::from_slice(&words[4 * i..4 * i + 4]))
    }

    /// A value of `T` whose words are all different finite floats (1.0, 1.0 + ulp, ...), the last
    /// `zeroed` words zero, so that a decoder that swaps or drops any field reads a different value.
    fn distinct<T: Pod>(zeroed: usize) -> T {
        let mut value = T::zeroed();
        let words: &mut [u32] = bytemuck::cast_slice_mut(bytemuck::bytes_of_mut(&mut value));
        let n = words.len();
        for (i, w) in words[..n - zeroed].iter_mut().enumerate() {
            *w = 1.0f32.to_bits() + i as u32;
        }
        value
    }

    /// What the GPU's `SceneTexels` decodes from its texel buffer is what the CPU's slices hold.
    #[test]
    fn texel_decoders_read_every_field_where_the_packer_wrote_it() {
        let node: Bvh4Node = distinct(0);
        assert_eq!(Bvh4Node::from_texels(texels(&node)), node);
        // The index words are read apart (`block_lanes`), so the position decoder leaves them zero.
        let block: TriangleBlock = distinct(4);
        let positions: [UVec4; 10] = texels(&block);
        let first_nine: [UVec4; 9] = core::array::from_fn(|i| positions[i]);
        assert_eq!(TriangleBlock::from_position_texels(first_nine), block);
        let info: TriangleInfo = distinct(0);
        assert_eq!(TriangleInfo::from_texel(texels::<_, 1>(&info)[0]), info);
        // `_pad` (the last two words) decodes as zero.
        let texture: TextureInfo = distinct(2);
        assert_eq!(TextureInfo::from_texels(texels(&texture)), texture);
        // `_pad` (the last three words) decodes as zero.
        let material: Material = distinct(3);
        assert_eq!(Material::from_texels(texels(&material)), material);
    }
}
