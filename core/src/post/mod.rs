//! Post-processing of the filled HDR image (Mohanto et al. 2023, section 3.4): exposure compensation and
//! Reinhard tone mapping to 8-bit sRGB ([`tonemap`]). What frames accumulate over time is
//! [`crate::temporal`].
pub mod tonemap;

pub use tonemap::{
    exposure_scale, pack_rgba8, reinhard, sanitize_hdr, tonemap_linear, tonemap_to_rgba8,
    tonemap_to_srgb8, unorm8, HDR_MAX,
};
