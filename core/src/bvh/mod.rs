//! BVH traversal over the flat node array of [`crate::scene::SceneView`].
pub mod traverse;

pub use traverse::{any_hit, closest_hit, Hit, TRAVERSAL_STACK_SIZE};
