//! Texture decoding into RGBA8 texels.
