//! BVH traversal over the flat node arrays of [`crate::scene::SceneView`]: the queries ([`query`]:
//! closest hit, any hit) and who answers them: the 4-wide tree both backends share ([`traverse`]) and,
//! on the CPU, an 8-wide tree over the same leaves ([`wide`]), which a block's coherent camera rays also
//! traverse as one packet ([`packet`]); in the kernel module built for ray queries, the driver's
//! acceleration structures (`hardware`). Imports run one way: `query` uses the traversals, which share
//! `traverse`'s hit record and leaf test.
/// Hardware traversal (`VK_KHR_ray_query`), in the kernel module built with the `RayQueryKHR`
/// capability.
#[cfg(all(target_arch = "spirv", feature = "ray-query"))]
#[allow(unsafe_code)] // spirv-std's ray queries are `unsafe`; each block says why it is sound.
pub mod hardware;
#[cfg(not(target_arch = "spirv"))]
pub mod packet;
pub mod query;
pub mod traverse;
#[cfg(not(target_arch = "spirv"))]
pub mod wide;

pub use query::{any_hit, any_hit_with, closest_hit, closest_hit_with};
pub use traverse::{Hit, MAX_NODE_COUNT, TRAVERSAL_STACK_SIZE};
