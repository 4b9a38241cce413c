//! The geometry group: the BVH over the triangles, their positions in four-wide blocks, and the
//! per-vertex normals, texture coordinates and colours shading reads
//! ([`fovea_core::scene::GeometryArrays`]).
use fovea_core::bvh::wide::Bvh8Node;
use fovea_core::kernel_abi::{
    BINDING_NODES, BINDING_NORMALS, BINDING_TRIANGLE_BLOCKS, BINDING_TRIANGLE_INFO,
    BINDING_TRIANGLE_LANES, BINDING_UVS, BINDING_VERTEX_COLORS,
};
use fovea_core::material::tangent::{encode_tangent, NO_TANGENT};
use fovea_core::material::vertex_color::encode_vertex_color;
use fovea_core::scene::{
    Bvh4Node, GeometryArrays, Material, TriangleBlock, TriangleInfo, TrianglePositions,
    MATERIAL_ALPHA_CUTOUT,
};
use glam::{Vec3, Vec4};

use super::array::{ArrayRead, PackedArray};
use crate::bvh::blocks::{name_wide_leaf_blocks, pack_leaf_blocks, LeafBlocks};
use crate::bvh::{build_bvh_indexed, BvhBuildOptions, BvhStats};

/// The geometry arrays, owned.
#[derive(Clone, Debug, Default)]
pub struct PackedGeometry {
    pub nodes: Vec<Bvh4Node>,
    /// The CPU's 8-wide tree over the same leaves (`fovea_core::bvh::wide`); the GPU traverses `nodes`.
    pub wide_nodes: Vec<Bvh8Node>,
    /// For each triangle, its block lane (`GeometryArrays::triangle_lanes`).
    pub triangle_lanes: Vec<u32>,
    pub blocks: Vec<TriangleBlock>,
    pub triangle_info: Vec<TriangleInfo>,
    pub normals: Vec<[f32; 4]>,
    pub uvs: Vec<[f32; 2]>,
    /// Encoded vertex colours ([`GeometryArrays::vertex_colors`]).
    pub vertex_colors: Vec<[u32; 2]>,
}

impl PackedGeometry {
    /// The borrowed view core reads.
    #[must_use]
    pub fn view(&self) -> GeometryArrays<'_> {
        GeometryArrays {
            nodes: &self.nodes,
            wide_nodes: &self.wide_nodes,
            triangle_lanes: &self.triangle_lanes,
            blocks: &self.blocks,
            triangle_info: &self.triangle_info,
            normals: &self.normals,
            uvs: &self.uvs,
            vertex_colors: &self.vertex_colors,
        }
    }

    /// The arrays the GPU receives, each with its binding (all read through the scene texel buffer).
    #[must_use]
    pub fn gpu_arrays(&self) -> [PackedArray<'_>; 7] {
        use ArrayRead::Texels;
        [
            PackedArray::new(BINDING_NODES, "BVH nodes", Texels, &self.nodes),
            PackedArray::new(
                BINDING_TRIANGLE_BLOCKS,
                "triangle blocks",
                Texels,
                &self.blocks,
            ),
            PackedArray::new(
                BINDING_TRIANGLE_LANES,
                "triangle lanes",
                Texels,
                &self.triangle_lanes,
            ),
            PackedArray::new(
                BINDING_TRIANGLE_INFO,
                "triangle info",
                Texels,
                &self.triangle_info,
            ),
            PackedArray::new(BINDING_NORMALS, "normals", Texels, &self.normals),
            PackedArray::new(BINDING_UVS, "texture coordinates", Texels, &self.uvs),
            PackedArray::new(
                BINDING_VERTEX_COLORS,
                "vertex colours",
                Texels,
                &self.vertex_colors,
            ),
        ]
    }

    /// Bytes held, the CPU-only 8-wide tree included.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.wide_nodes.as_slice())
            + self
                .gpu_arrays()
                .iter()
                .map(|a| a.bytes.len())
                .sum::<usize>()
    }
}

/// What the geometry packer takes from the loaded scene (moved in, so that each array is dropped as
/// soon as its packed form exists: packing's peak memory is the BVH build beside the loaded scene).
pub(super) struct GeometryInput {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub tangents: Vec<[f32; 4]>,
    pub colors: Vec<[f32; 4]>,
    pub triangles: Vec<[u32; 3]>,
    pub triangle_materials: Vec<u32>,
}

/// The packed geometry, its BVH's figures and the bounds of the vertices the triangles use.
pub(super) struct GeometryOutput {
    pub geometry: PackedGeometry,
    pub bvh: BvhStats,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// Builds the BVH over `input`'s triangles and packs them in its leaf order; texture coordinates are
/// kept only when a material reads a texture, normals only when one is not zero, tangents (in the
/// normals' `w`) only when a material reads them, colours only when one is not white.
pub(super) fn pack_geometry(
    input: GeometryInput,
    materials: &[Material],
    bvh_options: &BvhBuildOptions,
) -> GeometryOutput {
    let GeometryInput {
        positions,
        normals,
        uvs,
        tangents,
        colors,
        triangles,
        triangle_materials,
    } = input;
    let (bounds_min, bounds_max) = used_bounds(&positions, &triangles);

    let mut bvh = build_bvh_indexed(&positions, &triangles, bvh_options);
    let triangle_info: Vec<TriangleInfo> = bvh
        .triangle_order
        .iter()
        .map(|&i| TriangleInfo {
            vertices: triangles[i as usize],
            material: triangle_materials[i as usize],
        })
        .collect();
    drop(triangles);
    drop(triangle_materials);
    // The leaves' triangles four at a time, marked where their material has an alpha cut-out: the
    // only copy of the positions.
    let LeafBlocks {
        blocks,
        triangle_lanes,
    } = pack_leaf_blocks(
        &mut bvh.nodes,
        triangle_info.len(),
        |i| triangle_at(&positions, triangle_info[i].vertices),
        |i| materials[triangle_info[i].material as usize].flags & MATERIAL_ALPHA_CUTOUT != 0,
    );
    drop(positions);
    let mut wide_nodes = std::mem::take(&mut bvh.wide_nodes);
    name_wide_leaf_blocks(&mut wide_nodes, &triangle_lanes);

    let uvs = if materials.iter().any(Material::has_texture) && !uvs.is_empty() {
        uvs
    } else {
        Vec::new()
    };
    // Each vertex's tangent rides in its normal's `w` (`fovea_core::material::tangent`), where a
    // material reads tangents.
    let tangents = if materials.iter().any(Material::reads_tangent) {
        tangents
    } else {
        Vec::new()
    };
    let tangent_word = |i: usize| match tangents.get(i) {
        Some(&[x, y, z, w]) => encode_tangent(Vec3::new(x, y, z), w),
        None => NO_TANGENT,
    };
    let normals: Vec<[f32; 4]> = if normals.iter().any(|n| *n != [0.0; 3]) {
        normals
            .iter()
            .enumerate()
            .map(|(i, n)| [n[0], n[1], n[2], tangent_word(i)])
            .collect()
    } else {
        Vec::new()
    };

    // White multiplies nothing.
    let vertex_colors = if colors.iter().any(|c| *c != [1.0; 4]) {
        colors.iter().map(|&c| encode_vertex_color(c)).collect()
    } else {
        Vec::new()
    };

    GeometryOutput {
        geometry: PackedGeometry {
            nodes: bvh.nodes,
            wide_nodes,
            triangle_lanes,
            blocks,
            triangle_info,
            normals,
            uvs,
            vertex_colors,
        },
        bvh: bvh.stats,
        bounds_min,
        bounds_max,
    }
}

/// Bounds of the vertices the triangles use (an unused far-away vertex must not move the camera); zero
/// for no triangles.
fn used_bounds(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> (Vec3, Vec3) {
    if triangles.is_empty() {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let mut bounds_min = Vec3::splat(f32::MAX);
    let mut bounds_max = Vec3::splat(f32::MIN);
    for t in triangles {
        for &v in t {
            bounds_min = bounds_min.min(Vec3::from(positions[v as usize]));
            bounds_max = bounds_max.max(Vec3::from(positions[v as usize]));
        }
    }
    (bounds_min, bounds_max)
}

/// The vertex positions of the triangle with vertex indices `t`, in the layout the kernels read.
#[inline]
fn triangle_at(positions: &[[f32; 3]], t: [u32; 3]) -> TrianglePositions {
    let [v0, v1, v2] = t.map(|i| {
        let p = positions[i as usize];
        Vec4::new(p[0], p[1], p[2], 0.0)
    });
    TrianglePositions { v0, v1, v2 }
}
