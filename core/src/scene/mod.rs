//! The packed scene: the flat arrays both backends receive ([`layout`]), the borrowed view of them that
//! every core function reads ([`view`]), and the optional features a scene uses ([`features`]).
pub mod features;
pub mod layout;
pub mod view;

pub use features::{FeatureFlags, Features, StaticFeatures};
pub use layout::*;
pub use view::SceneView;
