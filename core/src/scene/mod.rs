//! The packed scene: the flat arrays both backends receive ([`layout`]), the borrowed view of them that
//! every core function reads ([`view`]), where its large arrays are read from ([`source`]), and the
//! optional features a scene uses ([`features`]).
pub mod features;
pub mod layout;
pub mod source;
pub mod view;

pub use features::{FeatureFlags, Features, StaticFeatures, VertexAttributes};
pub use layout::*;
#[cfg(target_arch = "spirv")]
pub use source::SceneTexels;
pub use source::{SceneSlices, SceneSource};
pub use view::{EnvironmentArrays, GeometryArrays, LightArrays, MaterialArrays, SceneView};
