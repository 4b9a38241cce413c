//! The loaded, not yet packed scene.
