//! Rays, the watertight ray-triangle test and scale-aware ray-origin offsets.
pub mod hit;
pub mod offset;
pub mod ray;
pub mod triangle;

pub use hit::Hit;
pub use ray::Ray;
