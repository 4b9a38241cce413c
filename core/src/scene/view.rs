//! [`SceneView`]: borrowed slices of the packed scene, the one argument every traversal and shading
//! function takes. The CPU host builds it from `Vec`s, the GPU kernel from storage buffers.
//!
//! The arrays come in four groups, one per concept: [`GeometryArrays`] (what traversal and hit
//! reconstruction read), [`MaterialArrays`] (materials and their textures), [`LightArrays`] (what
//! next-event estimation picks from) and [`EnvironmentArrays`] (the environment map and its sampling
//! tables). A new array joins one group: its field here, its packer in `fovea_scene::pack`, its binding in
//! [`crate::kernel_abi`] and the kernel's parameter list; the views, uploads and sizes follow from
//! the group.
use super::features::{FeatureFlags, Features};
#[cfg(not(target_arch = "spirv"))]
use super::layout::Bvh8Node;
use super::layout::{
    Bvh4Node, Light, Material, SceneGlobals, TextureInfo, TriangleBlock, TriangleInfo,
};

/// The geometry: the BVH, the triangles' positions and per-vertex attributes.
#[derive(Clone, Copy, Default)]
pub struct GeometryArrays<'a> {
    /// 4-wide BVH nodes, root first (see [`Bvh4Node`]); empty for an empty scene.
    pub nodes: &'a [Bvh4Node],
    /// The CPU's 8-wide tree over the same leaves as `nodes` ([`crate::bvh::wide`]);
    /// when it is not empty, traversal uses it instead of `nodes`. The GPU has only `nodes`.
    #[cfg(not(target_arch = "spirv"))]
    pub wide_nodes: &'a [Bvh8Node],
    /// The ray-query kernel module's hardware traversal: the top-level acceleration structure's address
    /// and the map from its triangles to the scene's (`crate::bvh::hardware`). Only in that module.
    #[cfg(all(target_arch = "spirv", feature = "ray-query"))]
    pub hardware: &'a [u32],
    /// Where each triangle's positions are (BVH leaf order): `4 * block + lane` of the [`TriangleBlock`]
    /// lane that holds them ([`super::triangle_lane`]). The blocks are the only copy of the positions.
    pub triangle_lanes: &'a [u32],
    /// The leaves' triangles four at a time, which traversal tests ([`TriangleBlock`]); leaf slot words
    /// of `nodes` index it.
    pub blocks: &'a [TriangleBlock],
    /// Per-triangle vertex indices and material, parallel to `triangle_lanes`.
    pub triangle_info: &'a [TriangleInfo],
    /// Per-vertex shading normals (`xyz`) and tangents (`w`, encoded: `crate::material::tangent`;
    /// [`crate::material::tangent::NO_TANGENT`] where the vertex has none). Empty when the scene has no
    /// shading normals; a zero normal means "use the geometric normal".
    pub normals: &'a [[f32; 4]],
    /// Per-vertex texture coordinates. Empty when no material has a texture.
    pub uvs: &'a [[f32; 2]],
    /// Per-vertex colours (glTF `COLOR_0`), RGBA as four 16-bit unsigned normalised numbers
    /// ([`crate::material::vertex_color`]). Empty when no vertex has a colour other than white.
    pub vertex_colors: &'a [[u32; 2]],
}

/// The materials and the textures they read.
#[derive(Clone, Copy, Default)]
pub struct MaterialArrays<'a> {
    /// The materials, indexed by [`TriangleInfo::material`].
    pub list: &'a [Material],
    /// One record per texture: where its texels are and how they are stored.
    pub textures: &'a [TextureInfo],
    /// Texels of all textures: one `u32` per RGBA8 texel, two per RGBA16 one.
    pub texels: &'a [u32],
}

/// The lights next-event estimation picks from.
#[derive(Clone, Copy, Default)]
pub struct LightArrays<'a> {
    /// The light list.
    pub list: &'a [Light],
    /// Cumulative light-selection table: `light_count + 1` entries from 0 to 1.
    pub cdf: &'a [f32],
    /// For each triangle, its index in `list`, or `INVALID_INDEX`. Empty without emissive triangles.
    pub triangle_light: &'a [u32],
}

/// The environment map and its importance-sampling tables (empty unless the scene has a map).
#[derive(Clone, Copy, Default)]
pub struct EnvironmentArrays<'a> {
    /// Equirectangular environment map texels (linear RGB, `w` unused), row-major, top row first.
    pub texels: &'a [[f32; 4]],
    /// Marginal CDF over rows (`height + 1` entries).
    pub marginal_cdf: &'a [f32],
    /// One CDF per row (`height * (width + 1)` entries).
    pub conditional_cdf: &'a [f32],
}

/// The packed scene as borrowed slices. Arrays a scene does not need are empty.
///
/// `F` is the set of optional features the shading code may meet (see [`super::features`]): the
/// default [`FeatureFlags`] is a run-time mask, [`super::StaticFeatures`] a compile-time one for the
/// CPU's specialised paths.
#[derive(Clone, Copy)]
pub struct SceneView<'a, F: Features = FeatureFlags> {
    /// Which optional features may occur; a superset of the scene's own (tested, never required).
    pub features: F,
    pub globals: SceneGlobals,
    pub geometry: GeometryArrays<'a>,
    pub materials: MaterialArrays<'a>,
    pub lights: LightArrays<'a>,
    pub environment: EnvironmentArrays<'a>,
}

impl SceneView<'_> {
    /// A scene without geometry, materials, lights or environment, with every feature on: the base that
    /// tests fill in with struct update syntax (`SceneView { geometry, ..SceneView::empty() }`).
    #[must_use]
    pub fn empty() -> Self {
        SceneView {
            features: FeatureFlags::ALL,
            globals: SceneGlobals::default(),
            geometry: GeometryArrays::default(),
            materials: MaterialArrays::default(),
            lights: LightArrays::default(),
            environment: EnvironmentArrays::default(),
        }
    }
}

impl<'a, F: Features> SceneView<'a, F> {
    /// The same arrays with another feature set, which must include every feature the scene uses.
    #[inline]
    #[must_use]
    pub fn with_features<G: Features>(&self, features: G) -> SceneView<'a, G> {
        SceneView {
            features,
            globals: self.globals,
            geometry: self.geometry,
            materials: self.materials,
            lights: self.lights,
            environment: self.environment,
        }
    }
}
