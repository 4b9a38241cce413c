//! 4-wide BVH traversal over the flat node array of [`crate::scene::SceneView`].
pub mod traverse;

pub use traverse::{any_hit, closest_hit, Hit, MAX_NODE_COUNT, TRAVERSAL_STACK_SIZE};
