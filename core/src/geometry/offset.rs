//! Scale-aware ray origin offsets (Wächter and Binder, Ray Tracing Gems ch. 6).
