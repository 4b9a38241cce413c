//! From a hit to shading inputs: texture fetches, vertex colours, alpha cut-outs and the Disney
//! parameters at a point.
pub mod alpha;
pub mod shading;
pub mod tangent;
pub mod texture;
pub mod vertex_color;

pub use shading::{material_params, surface_point, SurfacePoint};
