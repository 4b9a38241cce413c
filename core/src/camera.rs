//! Pinhole camera.
