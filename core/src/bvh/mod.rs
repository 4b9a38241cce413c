//! 4-wide BVH traversal over the flat node array of [`crate::scene::SceneView`].
pub mod traverse;

pub use traverse::{
    any_hit, any_hit_with, closest_hit, closest_hit_with, Hit, MAX_NODE_COUNT, TRAVERSAL_STACK_SIZE,
};
