//! BVH traversal over the flat node array of [`crate::scene::SceneView`].
pub mod traverse;
