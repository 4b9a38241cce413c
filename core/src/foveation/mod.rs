//! Foveation (Mohanto et al. 2023, sections 3.1-3.4): the display geometry that turns eccentricity angles
//! into radii ([`display`]), the three regions and their sampling parameters ([`regions`]), which block of
//! which region renders each pixel ([`blocks`]), which pixel of its block each sample lands in
//! ([`landing`]), how the image is filled from one value per block ([`fill`]), and the overlay that
//! shows the regions ([`overlay`]).
pub mod blocks;
pub mod display;
pub mod fill;
pub mod landing;
pub mod overlay;
pub mod regions;

pub use blocks::{
    block_centre, block_extent, block_sample_position, count_blocks, count_samples, for_each_block,
    for_each_block_in_rows, owning_block, samples_in_block, OwnedBlock,
};
pub use display::{
    eccentricity_to_radius_px, paper_params_for_display, pixels_per_degree, radius_for_resolution,
    radius_px_to_eccentricity_deg, DisplayGeometry, FOVEA_ECCENTRICITY_DEG,
    INTERMEDIATE_ECCENTRICITY_DEG,
};
pub use fill::{
    block_mean, cell_buffer_len, cell_grid_offset, cell_grid_size, cell_mean, cell_mean_at,
    fill_pixel, fill_value, FILL_BILINEAR, FILL_REPLICATE,
};
pub use regions::{
    region_of_pixel, region_of_point, FoveationParams, FOVEATION_ERROR_BAD_GAZE,
    FOVEATION_ERROR_BAD_RADIUS, FOVEATION_ERROR_NOT_NESTED, FOVEATION_ERROR_ZERO_BLOCK,
    FOVEATION_ERROR_ZERO_SPP, FOVEATION_OK, REGION_COUNT, REGION_FOVEA, REGION_INTERMEDIATE,
    REGION_PERIPHERY,
};
