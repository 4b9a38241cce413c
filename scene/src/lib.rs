//! fovea-scene: loading, BVH build and packing.
