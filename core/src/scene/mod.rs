//! The packed scene: the flat arrays both backends receive ([`layout`]) and the borrowed view of them that
//! every core function reads ([`view`]).
pub mod layout;
pub mod view;

pub use layout::*;
pub use view::SceneView;
