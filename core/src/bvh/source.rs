//! Where traversal reads the BVH nodes and the triangle positions it tests.
//!
//! On the CPU from the scene's slices ([`SceneSlices`]); on the GPU from one storage texel buffer that
//! holds both ([`GeometryTexels`]): nodes from texel 0, [`NODE_TEXELS`] each, then triangles from texel
//! [`SceneGlobals::triangle_texels`](crate::scene::SceneGlobals::triangle_texels), [`TRIANGLE_TEXELS`]
//! each, as `R32G32B32A32_UINT` texels holding the same bytes as the slices.
//!
//! Why a texel buffer: lavapipe (Mesa 25) compiles a storage-buffer load whose offset differs between
//! invocations into a loop over the 8 lanes with a bounds check per component, but a texel-buffer read
//! into a branch-free gather; traversal is mostly such loads, and reading it through a texel buffer made
//! frames 31-36 % faster there (README, "lavapipe"). rust-gpu cannot keep an image inside a struct, so the
//! source is an argument of its own next to the [`SceneView`] rather than one of its fields.
use crate::scene::{Bvh4Node, Features, SceneView, TrianglePositions};

/// Texels (16 bytes each) per [`Bvh4Node`].
pub const NODE_TEXELS: u32 = 7;
/// Texels per [`TrianglePositions`].
pub const TRIANGLE_TEXELS: u32 = 3;

const _: () = {
    assert!(core::mem::size_of::<Bvh4Node>() == NODE_TEXELS as usize * 16);
    assert!(core::mem::size_of::<TrianglePositions>() == TRIANGLE_TEXELS as usize * 16);
};

/// Reads BVH nodes and triangle positions for traversal.
pub trait TraversalSource {
    /// Node `index` of the BVH (root 0).
    fn node<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Bvh4Node;
    /// The positions of triangle `index` (BVH leaf order).
    fn triangle<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TrianglePositions;
}

/// Reads [`SceneView::nodes`] and [`SceneView::triangles`]: the CPU's source.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneSlices;

impl TraversalSource for SceneSlices {
    #[inline(always)]
    fn node<F: Features>(&self, scene: &SceneView<F>, index: u32) -> Bvh4Node {
        scene.nodes[index as usize]
    }

    #[inline(always)]
    fn triangle<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TrianglePositions {
        scene.triangles[index as usize]
    }
}

/// The GPU's geometry texel buffer (see the module documentation).
#[cfg(target_arch = "spirv")]
pub type GeometryTexels = spirv_std::Image!(buffer, format = rgba32ui, sampled = false);

/// The four words of a texel as the floats they hold.
#[cfg(target_arch = "spirv")]
#[inline(always)]
fn float_bits(u: glam::UVec4) -> glam::Vec4 {
    glam::Vec4::new(
        f32::from_bits(u.x),
        f32::from_bits(u.y),
        f32::from_bits(u.z),
        f32::from_bits(u.w),
    )
}

#[cfg(target_arch = "spirv")]
impl TraversalSource for GeometryTexels {
    #[inline(always)]
    fn node<F: Features>(&self, _scene: &SceneView<F>, index: u32) -> Bvh4Node {
        let t = index * NODE_TEXELS;
        Bvh4Node {
            min_x: float_bits(self.read(t)),
            max_x: float_bits(self.read(t + 1)),
            min_y: float_bits(self.read(t + 2)),
            max_y: float_bits(self.read(t + 3)),
            min_z: float_bits(self.read(t + 4)),
            max_z: float_bits(self.read(t + 5)),
            slots: self.read(t + 6),
        }
    }

    #[inline(always)]
    fn triangle<F: Features>(&self, scene: &SceneView<F>, index: u32) -> TrianglePositions {
        let t = scene.globals.triangle_texels + index * TRIANGLE_TEXELS;
        TrianglePositions {
            v0: float_bits(self.read(t)),
            v1: float_bits(self.read(t + 1)),
            v2: float_bits(self.read(t + 2)),
        }
    }
}
