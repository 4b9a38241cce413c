//! Display geometry: from eccentricity angles to radii in pixels (Mohanto et al. 2023, section 3.1).
//!
//! The paper converts an eccentricity `e` into a length on the screen with the tangent formula
//! `a = 2 d tan(e / 2)` (the extent of what a visual angle `e` subtends at distance `d`) and that length into
//! pixels with the display's pixel density `R / A` (pixels per cm). The eccentricities of the paper (5.2° for
//! the fovea, 17° for the intermediate region) are the full angular extent of each region around the gaze,
//! so a region's *radius* is half of that extent: `r = d tan(e / 2) · res_x / width_cm`. This is the reading
//! that reproduces the paper's 4K radii (5.2° gives 147.67 px, the paper's "~147"; 17° gives 486.02 px, the
//! paper's "~482" being a rounding of its own); `2 d tan(e/2) · res_x / width_cm` would give twice that.
use super::regions::FoveationParams;
use crate::math::float::{atan2, tan, PI};

/// Eccentricity bound of the fovea in degrees (the paper's `e_f`).
pub const FOVEA_ECCENTRICITY_DEG: f32 = 5.2;
/// Eccentricity bound of the intermediate region in degrees (the paper's `e_i`).
pub const INTERMEDIATE_ECCENTRICITY_DEG: f32 = 17.0;

/// A physical display and the viewer's distance to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayGeometry {
    /// Visible width of the screen in cm.
    pub width_cm: f32,
    /// Visible height of the screen in cm.
    pub height_cm: f32,
    /// Distance from the eye to the screen in cm.
    pub distance_cm: f32,
    /// Native resolution in pixels (width, height).
    pub resolution: [u32; 2],
}

impl Default for DisplayGeometry {
    /// The paper's setup: a 70.848 × 39.852 cm 4K (3840 × 2160) display seen from 60 cm.
    fn default() -> Self {
        Self {
            width_cm: 70.848,
            height_cm: 39.852,
            distance_cm: 60.0,
            resolution: [3840, 2160],
        }
    }
}

/// Horizontal pixel density of `display` in pixels per cm (the paper's `R / A`).
#[inline]
#[must_use]
pub fn pixels_per_cm(display: &DisplayGeometry) -> f32 {
    display.resolution[0] as f32 / display.width_cm
}

/// Radius in display pixels of the region within eccentricity `e_deg` of the gaze (section 3.1):
/// `d tan(e / 2) · res_x / width_cm`, half of the on-screen extent `a = 2 d tan(e / 2)` (see the module
/// documentation for why half).
#[inline]
#[must_use]
pub fn eccentricity_to_radius_px(e_deg: f32, display: &DisplayGeometry) -> f32 {
    let extent_cm = 2.0 * display.distance_cm * tan(0.5 * e_deg * (PI / 180.0));
    0.5 * extent_cm * pixels_per_cm(display)
}

/// Eccentricity in degrees (the visual angle between the gaze and a point) of a point `distance_px`
/// display pixels from the gaze on the screen: `atan(distance_cm / d)`, the screen taken as flat and
/// the eye in front of the gaze. The inverse of [`eccentricity_to_radius_px`] up to that function's
/// convention: a region bounded by the paper's extent `e` has its edge at eccentricity `e / 2`.
#[inline]
#[must_use]
pub fn radius_px_to_eccentricity_deg(distance_px: f32, display: &DisplayGeometry) -> f32 {
    let distance_cm = distance_px / pixels_per_cm(display);
    atan2(distance_cm, display.distance_cm) * (180.0 / PI)
}

/// Pixels per degree of visual angle near the gaze: `d · res_x / width_cm · π / 180` (56.76 for the paper's
/// display). This is the `pixels_per_degree` FLIP needs (its default, 67.02, is a different display).
#[inline]
#[must_use]
pub fn pixels_per_degree(display: &DisplayGeometry) -> f32 {
    display.distance_cm * pixels_per_cm(display) * (PI / 180.0)
}

/// Scales a radius measured in display pixels to an image rendered `render_width` pixels wide and shown
/// full-screen on `display`: `r · render_width / res_x`.
#[inline]
#[must_use]
pub fn radius_for_resolution(
    radius_display_px: f32,
    display: &DisplayGeometry,
    render_width: u32,
) -> f32 {
    radius_display_px * (render_width as f32 / display.resolution[0] as f32)
}

/// The paper's foveation (32/16/8 spp, blocks 1/2/4, radii from 5.2° and 17°) for an image `render_width`
/// pixels wide shown full-screen on `display`, with `gaze` in the image's pixel coordinates.
#[must_use]
pub fn paper_params_for_display(
    gaze: [f32; 2],
    display: &DisplayGeometry,
    render_width: u32,
) -> FoveationParams {
    let r_f = radius_for_resolution(
        eccentricity_to_radius_px(FOVEA_ECCENTRICITY_DEG, display),
        display,
        render_width,
    );
    let r_i = radius_for_resolution(
        eccentricity_to_radius_px(INTERMEDIATE_ECCENTRICITY_DEG, display),
        display,
        render_width,
    );
    FoveationParams::paper(gaze, r_f, r_i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_radii_at_4k() {
        let d = DisplayGeometry::default();
        let r_f = eccentricity_to_radius_px(FOVEA_ECCENTRICITY_DEG, &d);
        let r_i = eccentricity_to_radius_px(INTERMEDIATE_ECCENTRICITY_DEG, &d);
        assert!((r_f - 147.67).abs() < 0.01, "r_f = {r_f}");
        assert!((r_i - 486.02).abs() < 0.01, "r_i = {r_i}");
        assert_eq!(eccentricity_to_radius_px(0.0, &d), 0.0);
    }

    #[test]
    fn pixels_per_degree_of_paper_display() {
        let ppd = pixels_per_degree(&DisplayGeometry::default());
        assert!((ppd - 56.76).abs() < 0.005, "ppd = {ppd}");
        // For small angles the radius per degree approaches the pixels per degree.
        let d = DisplayGeometry::default();
        let r = eccentricity_to_radius_px(0.2, &d) / 0.1;
        assert!((r - ppd).abs() < 1e-2, "{r} vs {ppd}");
    }

    #[test]
    fn radii_scale_with_render_width() {
        let d = DisplayGeometry::default();
        assert!((radius_for_resolution(147.67, &d, 960) - 36.9175).abs() < 1e-4);
        assert_eq!(radius_for_resolution(100.0, &d, 3840), 100.0);
        let p = paper_params_for_display([480.0, 270.0], &d, 960);
        assert!((p.radius_fovea - 147.67 / 4.0).abs() < 0.01);
        assert!((p.radius_intermediate - 486.02 / 4.0).abs() < 0.01);
        assert_eq!(p.spp, [32, 16, 8, 0]);
    }

    #[test]
    fn eccentricity_of_a_region_edge_is_half_its_extent() {
        let d = DisplayGeometry::default();
        for e in [1.0f32, 5.2, 17.0, 60.0] {
            let r = eccentricity_to_radius_px(e, &d);
            let back = radius_px_to_eccentricity_deg(r, &d);
            assert!((back - 0.5 * e).abs() < 1e-3 * e, "{e}: {back}");
        }
        assert_eq!(radius_px_to_eccentricity_deg(0.0, &d), 0.0);
    }
}
