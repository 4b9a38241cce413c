//! Rays, the watertight ray-triangle test and scale-aware ray-origin offsets.
pub mod offset;
pub mod ray;
pub mod triangle;

pub use ray::Ray;
