//! BVH construction: binned SAH, built in parallel, flattened for traversal.
