//! BSDFs. fovea shades every surface with the Disney "principled" BRDF ([`disney`]); materials with
//! transmission add a rough dielectric interface ([`dielectric`]) to it.
//!
//! Conventions: directions are in the local shading frame (`z` is the shading normal), both point away from
//! the surface, `wo` towards the viewer, `wi` towards the light. `eval` returns the BRDF value `f` without
//! the cosine factor; `pdf` is a solid-angle density over `wi`.
pub mod dielectric;
pub mod disney;
pub mod sample;

pub use disney::{DisneyParams, ALPHA_MIN};
pub use sample::BsdfSample;
