//! GGX distribution of visible normals: evaluation and sampling.
