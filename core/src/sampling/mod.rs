//! Sample warping: turning uniform random numbers into directions and points with known densities.
pub mod distribution;
pub mod ggx_vndf;
pub mod warp;
