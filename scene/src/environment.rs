//! Environment lighting: constant radiance or an equirectangular HDR map with its sampling tables.
