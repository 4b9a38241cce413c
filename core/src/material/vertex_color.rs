//! Per-vertex colours (glTF 2.0 `COLOR_0`, §3.7.2.1): a linear RGBA multiplier of the base colour and
//! its opacity, interpolated over the triangle like any vertex attribute.
//!
//! Each colour is stored as four 16-bit unsigned normalised numbers in two words (`r | g << 16`,
//! `b | a << 16`): eight bytes per vertex instead of sixteen, exact for the 8- and 16-bit colours files
//! carry, and within 1/131070 of a float one. Values are clamped to `[0, 1]` when encoded: the loader
//! warns about a file's values outside it before they get here.
use glam::Vec4;

use crate::scene::features::FEATURE_VERTEX_COLORS;
use crate::scene::{Features, SceneSource, SceneView};

/// The largest 16-bit unsigned normalised number, which stands for 1.
const UNORM16_MAX: f32 = 65535.0;

/// One channel in `[0, 1]` as a 16-bit unsigned normalised number (NaN as 0).
#[inline]
fn encode_channel(c: f32) -> u32 {
    // A NaN stays NaN through the clamp, and Rust's `as` turns it into 0.
    (c.clamp(0.0, 1.0) * UNORM16_MAX + 0.5) as u32
}

/// Encodes a linear RGBA colour (see the module documentation).
#[inline]
#[must_use]
pub fn encode_vertex_color(rgba: [f32; 4]) -> [u32; 2] {
    let [r, g, b, a] = rgba.map(encode_channel);
    [r | g << 16, b | a << 16]
}

/// Decodes what [`encode_vertex_color`] wrote.
#[inline]
#[must_use]
pub fn decode_vertex_color(words: [u32; 2]) -> Vec4 {
    Vec4::new(
        decode_channel(words[0] & 0xFFFF),
        decode_channel(words[0] >> 16),
        decode_channel(words[1] & 0xFFFF),
        decode_channel(words[1] >> 16),
    )
}

/// One 16-bit unsigned normalised number as a float in `[0, 1]`.
#[inline]
fn decode_channel(n: u32) -> f32 {
    n as f32 / UNORM16_MAX
}

/// The colour of `triangle` at barycentrics (`b1`, `b2`); white (1, 1, 1, 1), which changes nothing,
/// when the scene has no vertex colours.
#[inline]
#[must_use]
pub fn interpolate_vertex_color<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    b1: f32,
    b2: f32,
) -> Vec4 {
    if !scene.features.has(FEATURE_VERTEX_COLORS) || scene.geometry.vertex_colors.is_empty() {
        return Vec4::ONE;
    }
    let v = source.triangle_info(scene, triangle).vertices;
    let c0 = decode_vertex_color(source.vertex_color(scene, v[0]));
    let c1 = decode_vertex_color(source.vertex_color(scene, v[1]));
    let c2 = decode_vertex_color(source.vertex_color(scene, v[2]));
    c0 * (1.0 - b1 - b2) + c1 * b1 + c2 * b2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_and_sixteen_bit_colours_round_trip_exactly() {
        for n in [0u32, 1, 127, 128, 255] {
            let c = n as f32 / 255.0;
            let complement = (255 - n) as f32 / 255.0;
            let back = decode_vertex_color(encode_vertex_color([c, complement, c, 1.0]));
            // 65535 = 255 · 257: every 8-bit value is a 16-bit one.
            assert_eq!(back.x, c, "{n}/255");
            assert_eq!(back.y, complement, "{n}/255");
            assert_eq!(back.w, 1.0);
        }
        for n in [0u32, 1, 32768, 65534, 65535] {
            let c = n as f32 / 65535.0;
            assert_eq!(
                decode_vertex_color(encode_vertex_color([c; 4])),
                Vec4::splat(c)
            );
        }
    }

    #[test]
    fn float_colours_round_to_the_nearest_step_and_out_of_range_values_clamp() {
        let c = 0.123_456_7;
        let back = decode_vertex_color(encode_vertex_color([c; 4]));
        assert!((back.x - c).abs() <= 0.5 / 65535.0 + 1e-7, "{back}");
        let clamped =
            decode_vertex_color(encode_vertex_color([-1.0, 2.0, f32::NAN, f32::INFINITY]));
        assert_eq!(clamped, Vec4::new(0.0, 1.0, 0.0, 1.0));
    }

    /// glTF 2.0 §3.7.2.1: `COLOR_0` multiplies the base colour and its alpha, interpolated over the
    /// triangle; without the feature (a specialised path of a scene without colours) nothing changes.
    #[test]
    fn vertex_colours_multiply_the_base_colour_and_the_cut_out_alpha() {
        use crate::geometry::Hit;
        use crate::material::alpha::is_cut_out;
        use crate::material::surface_point;
        use crate::scene::features::FEATURES_ALL;
        use crate::scene::{
            FeatureFlags, GeometryArrays, Material, MaterialArrays, SceneSlices, TriangleInfo,
            TrianglePositions, MATERIAL_ALPHA_CUTOUT,
        };
        use glam::Vec3;

        let tri = TrianglePositions {
            v0: Vec4::new(0.0, 0.0, 0.0, 0.0),
            v1: Vec4::new(1.0, 0.0, 0.0, 0.0),
            v2: Vec4::new(0.0, 1.0, 0.0, 0.0),
        };
        let (blocks, lanes) = crate::test_support::one_triangle_per_block(&[tri], &[]);
        let info = TriangleInfo {
            vertices: [0, 1, 2],
            material: 0,
        };
        let materials = [Material {
            base_color: [0.5, 0.5, 0.5, 1.0],
            flags: MATERIAL_ALPHA_CUTOUT,
            alpha_cutoff: 0.5,
            ..Material::default()
        }];
        // Red and opaque, green and opaque, blue and clear.
        let colors = [
            encode_vertex_color([1.0, 0.0, 0.0, 1.0]),
            encode_vertex_color([0.0, 1.0, 0.0, 1.0]),
            encode_vertex_color([0.0, 0.0, 1.0, 0.0]),
        ];
        let view = SceneView {
            geometry: GeometryArrays {
                blocks: &blocks,
                triangle_lanes: &lanes,
                triangle_info: core::slice::from_ref(&info),
                vertex_colors: &colors,
                ..GeometryArrays::default()
            },
            materials: MaterialArrays {
                list: &materials,
                ..MaterialArrays::default()
            },
            ..SceneView::empty()
        };
        let hit = |b1: f32, b2: f32| Hit {
            t: 1.0,
            triangle: 0,
            b1,
            b2,
        };
        let base = |view: &SceneView<FeatureFlags>, b1, b2| {
            surface_point(view, &SceneSlices, &hit(b1, b2))
                .params
                .base_color
        };
        // At the vertices: 0.5 times each vertex's colour; at (0.25, 0.25) the blend (0.5, 0.25, 0.25).
        assert_eq!(base(&view, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(base(&view, 1.0, 0.0), Vec3::new(0.0, 0.5, 0.0));
        assert_eq!(base(&view, 0.0, 1.0), Vec3::new(0.0, 0.0, 0.5));
        let mid = base(&view, 0.25, 0.25);
        assert!(
            (mid - Vec3::new(0.25, 0.125, 0.125)).abs().max_element() < 1e-6,
            "{mid}"
        );
        // Alpha 1 - b2: cut out where it falls below the 0.5 cutoff.
        assert!(!is_cut_out(&view, &SceneSlices, 0, 0.2, 0.4));
        assert!(is_cut_out(&view, &SceneSlices, 0, 0.2, 0.6));

        let no_colors = view.with_features(FeatureFlags(FEATURES_ALL & !FEATURE_VERTEX_COLORS));
        assert_eq!(base(&no_colors, 0.0, 1.0), Vec3::splat(0.5));
        assert!(!is_cut_out(&no_colors, &SceneSlices, 0, 0.2, 0.6));
    }
}
