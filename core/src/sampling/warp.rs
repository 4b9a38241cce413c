//! Cosine-weighted hemisphere, uniform sphere, disk and triangle warps.
