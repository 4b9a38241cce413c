//! The three foveation regions and their sampling parameters (Mohanto et al. 2023, section 3.2, eq. 1).
//!
//! The fovea (eccentricity up to `e_f`) gets `τ1` samples per pixel, the intermediate ring (up to `e_i`)
//! `τ2` samples per `n × n` block and the periphery `τ3` samples per `m × m` block. Pixel (x, y) covers
//! `[x, x + 1) × [y, y + 1)` with its centre at (x + 0.5, y + 0.5); the gaze is given in the same continuous
//! pixel coordinates and may lie outside the image.
use bytemuck::{Pod, Zeroable};
use glam::Vec2;

use crate::math::float::is_finite;

/// Region index of the fovea (full resolution, most samples).
pub const REGION_FOVEA: u32 = 0;
/// Region index of the intermediate ring.
pub const REGION_INTERMEDIATE: u32 = 1;
/// Region index of the periphery (coarsest blocks, fewest samples).
pub const REGION_PERIPHERY: u32 = 2;
/// Number of regions.
pub const REGION_COUNT: u32 = 3;

/// [`FoveationParams::validate`]: the parameters are usable.
pub const FOVEATION_OK: u32 = 0;
/// [`FoveationParams::validate`] bit: a region's block size is 0.
pub const FOVEATION_ERROR_ZERO_BLOCK: u32 = 1;
/// [`FoveationParams::validate`] bit: block sizes are not nested (`b_f | b_i | b_p` fails).
pub const FOVEATION_ERROR_NOT_NESTED: u32 = 2;
/// [`FoveationParams::validate`] bit: a region has 0 samples per block.
pub const FOVEATION_ERROR_ZERO_SPP: u32 = 4;
/// [`FoveationParams::validate`] bit: a radius is NaN or negative.
pub const FOVEATION_ERROR_BAD_RADIUS: u32 = 8;
/// [`FoveationParams::validate`] bit: the gaze is not finite.
pub const FOVEATION_ERROR_BAD_GAZE: u32 = 16;

/// Foveation parameters of one frame (48 bytes, GPU layout). Arrays are indexed by region
/// ([`REGION_FOVEA`], [`REGION_INTERMEDIATE`], [`REGION_PERIPHERY`]); element 3 is padding.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FoveationParams {
    /// Gaze point in continuous pixel coordinates of the rendered image.
    pub gaze: [f32; 2],
    /// Fovea radius in rendered pixels: points at distance `<= radius_fovea` from the gaze are foveal.
    pub radius_fovea: f32,
    /// Intermediate radius in rendered pixels: points farther than `radius_fovea` and at most this far
    /// are intermediate; everything farther is periphery.
    pub radius_intermediate: f32,
    /// Primary samples per block of each region (the paper's `τ1, τ2, τ3`).
    pub spp: [u32; 4],
    /// Block edge length in pixels of each region (the paper's 1, `n`, `m`); must be nested, see
    /// [`FoveationParams::validate`].
    pub block_size: [u32; 4],
}

impl FoveationParams {
    /// The paper's configuration: 32 / 16 / 8 samples per block on 1×1 / 2×2 / 4×4 blocks.
    #[inline]
    #[must_use]
    pub fn paper(gaze: [f32; 2], radius_fovea: f32, radius_intermediate: f32) -> Self {
        Self::new(
            gaze,
            [radius_fovea, radius_intermediate],
            [32, 16, 8],
            [1, 2, 4],
        )
    }

    /// Foveation around `gaze` with region radii `radii` (fovea, intermediate) in pixels, `spp` samples
    /// per fovea pixel, intermediate block and periphery block, and `blocks` block edges.
    #[inline]
    #[must_use]
    pub fn new(gaze: [f32; 2], radii: [f32; 2], spp: [u32; 3], blocks: [u32; 3]) -> Self {
        Self {
            gaze,
            radius_fovea: radii[0],
            radius_intermediate: radii[1],
            spp: [spp[0], spp[1], spp[2], 0],
            block_size: [blocks[0], blocks[1], blocks[2], 0],
        }
    }

    /// Uniform (non-foveated) rendering: every pixel is foveal with `spp` samples.
    #[inline]
    #[must_use]
    pub fn uniform(spp: u32) -> Self {
        Self {
            gaze: [0.0, 0.0],
            radius_fovea: f32::MAX,
            radius_intermediate: f32::MAX,
            spp: [spp, spp, spp, 0],
            block_size: [1, 1, 1, 0],
        }
    }

    /// Checks the parameters; returns [`FOVEATION_OK`] or an OR of `FOVEATION_ERROR_*` bits.
    ///
    /// Block sizes must be non-zero and nested: each region's block size divides the next coarser one
    /// (`b_f | b_i | b_p`), which makes the aligned block grids nest so that ownership by block centre
    /// ([`super::blocks::owning_block`]) covers every pixel exactly once. Radii must be non-negative (not
    /// NaN); `radius_intermediate < radius_fovea` is allowed and simply leaves the intermediate ring empty.
    #[must_use]
    pub fn validate(&self) -> u32 {
        let mut error = FOVEATION_OK;
        let b = self.block_size;
        if b[0] == 0 || b[1] == 0 || b[2] == 0 {
            error |= FOVEATION_ERROR_ZERO_BLOCK;
        } else if !divides(b[0], b[1]) || !divides(b[1], b[2]) {
            error |= FOVEATION_ERROR_NOT_NESTED;
        }
        if self.spp[0] == 0 || self.spp[1] == 0 || self.spp[2] == 0 {
            error |= FOVEATION_ERROR_ZERO_SPP;
        }
        if !radius_is_valid(self.radius_fovea) || !radius_is_valid(self.radius_intermediate) {
            error |= FOVEATION_ERROR_BAD_RADIUS;
        }
        if !is_finite(self.gaze[0]) || !is_finite(self.gaze[1]) {
            error |= FOVEATION_ERROR_BAD_GAZE;
        }
        error
    }

    /// The gaze as a [`Vec2`].
    #[inline]
    #[must_use]
    pub fn gaze(&self) -> Vec2 {
        Vec2::new(self.gaze[0], self.gaze[1])
    }
}

/// Whether `a` divides `b` (`a > 0`). Written without `u32::is_multiple_of`, which is newer than the
/// toolchains rust-gpu pins.
#[inline]
#[must_use]
fn divides(a: u32, b: u32) -> bool {
    b / a * a == b
}

/// Whether `r` is usable as a radius: non-negative and not NaN (`+inf` is fine).
#[inline]
#[must_use]
fn radius_is_valid(r: f32) -> bool {
    // False for NaN, whose comparisons are all false.
    r >= 0.0
}

/// The region of the point `p` (continuous pixel coordinates): fovea if `|p - gaze| <= r_f`, intermediate
/// if `<= r_i`, otherwise periphery (eq. 1 with eccentricity measured as screen distance from the gaze).
#[inline]
#[must_use]
pub fn region_of_point(p: Vec2, params: &FoveationParams) -> u32 {
    let d2 = (p - params.gaze()).length_squared();
    // Squared radii: `f32::MAX²` overflows to +inf, which still compares as intended.
    if d2 <= params.radius_fovea * params.radius_fovea {
        REGION_FOVEA
    } else if d2 <= params.radius_intermediate * params.radius_intermediate {
        REGION_INTERMEDIATE
    } else {
        REGION_PERIPHERY
    }
}

/// The region of the centre of pixel (`x`, `y`).
#[inline]
#[must_use]
pub fn region_of_pixel(x: u32, y: u32, params: &FoveationParams) -> u32 {
    region_of_point(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), params)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_by_distance() {
        let p = FoveationParams::paper([100.0, 50.0], 10.0, 30.0);
        assert_eq!(region_of_point(Vec2::new(100.0, 50.0), &p), REGION_FOVEA);
        assert_eq!(region_of_point(Vec2::new(110.0, 50.0), &p), REGION_FOVEA); // on the circle
        assert_eq!(
            region_of_point(Vec2::new(110.01, 50.0), &p),
            REGION_INTERMEDIATE
        );
        assert_eq!(
            region_of_point(Vec2::new(100.0, 80.0), &p),
            REGION_INTERMEDIATE
        );
        assert_eq!(
            region_of_point(Vec2::new(100.0, 80.01), &p),
            REGION_PERIPHERY
        );
        assert_eq!(region_of_pixel(99, 49, &p), REGION_FOVEA);
        assert_eq!(region_of_pixel(0, 0, &p), REGION_PERIPHERY);
    }

    #[test]
    fn uniform_is_all_fovea() {
        let p = FoveationParams::uniform(4);
        assert_eq!(p.validate(), FOVEATION_OK);
        assert_eq!(region_of_point(Vec2::new(1.0e6, -1.0e6), &p), REGION_FOVEA);
        assert_eq!(region_of_pixel(3839, 2159, &p), REGION_FOVEA);
        assert_eq!(p.spp[0], 4);
    }

    #[test]
    fn zero_radii_leave_only_the_gaze_point_foveal() {
        let p = FoveationParams::paper([4.5, 4.5], 0.0, 0.0);
        assert_eq!(region_of_point(Vec2::new(4.5, 4.5), &p), REGION_FOVEA);
        assert_eq!(region_of_point(Vec2::new(4.5, 4.6), &p), REGION_PERIPHERY);
    }

    #[test]
    fn validation() {
        let ok = FoveationParams::paper([0.0, 0.0], 10.0, 20.0);
        assert_eq!(ok.validate(), FOVEATION_OK);
        let mut p = ok;
        p.block_size = [1, 2, 6, 0];
        assert_eq!(p.validate(), FOVEATION_OK);
        p.block_size = [2, 4, 8, 0];
        assert_eq!(p.validate(), FOVEATION_OK);
        p.block_size = [1, 3, 4, 0];
        assert_eq!(p.validate(), FOVEATION_ERROR_NOT_NESTED);
        p.block_size = [2, 3, 6, 0];
        assert_eq!(p.validate(), FOVEATION_ERROR_NOT_NESTED);
        p.block_size = [1, 4, 2, 0];
        assert_eq!(p.validate(), FOVEATION_ERROR_NOT_NESTED);
        p.block_size = [1, 0, 4, 0];
        assert_eq!(p.validate(), FOVEATION_ERROR_ZERO_BLOCK);
        let mut p = ok;
        p.spp[2] = 0;
        assert_eq!(p.validate(), FOVEATION_ERROR_ZERO_SPP);
        let mut p = ok;
        p.radius_fovea = f32::NAN;
        p.gaze[1] = f32::INFINITY;
        assert_eq!(
            p.validate(),
            FOVEATION_ERROR_BAD_RADIUS | FOVEATION_ERROR_BAD_GAZE
        );
        let mut p = ok;
        p.radius_intermediate = -1.0;
        assert_eq!(p.validate(), FOVEATION_ERROR_BAD_RADIUS);
    }

    #[test]
    fn layout_is_48_bytes() {
        assert_eq!(core::mem::size_of::<FoveationParams>(), 48);
    }
}
