//! Vertex tangents (glTF `TANGENT`, or MikkTSpace's at load), stored in the unused `w` of each vertex's
//! normal ([`crate::scene::GeometryArrays::normals`]) so that they cost no array, binding or fetch of
//! their own.
//!
//! **Encoding.** The unit tangent is mapped to the octahedron (Meyer et al. 2010, "On floating-point
//! normal vectors"; Cigolle et al. 2014), each of the two coordinates quantised to 12 bits, and the pair
//! stored as the integer `4096 qx + qy + 1` in an `f32` (at most 2²⁴, so exactly representable: no NaN,
//! denormal or rounding for a GPU to disturb). Its sign is the bitangent's handedness (glTF's `w`: the
//! bitangent is `w · (n × t)`). 0 means "no tangent", the packer's default. The quantisation error is
//! below 0.07°.
use glam::{Vec2, Vec3};

/// The `w` of a vertex without a tangent.
pub const NO_TANGENT: f32 = 0.0;

/// Largest quantised octahedral coordinate (12 bits; even, so that 0 is a step: axis-aligned tangents
/// come back exact).
const STEPS: f32 = 4094.0;

/// `w` for the unit tangent `tangent` with handedness `sign` (±1; negative means mirrored texture
/// coordinates); [`NO_TANGENT`] for a zero or non-finite tangent.
#[must_use]
pub fn encode_tangent(tangent: Vec3, sign: f32) -> f32 {
    let l1 = tangent.x.abs() + tangent.y.abs() + tangent.z.abs();
    if !(l1 > 0.0) || !l1.is_finite() {
        return NO_TANGENT;
    }
    let mut p = Vec2::new(tangent.x, tangent.y) / l1;
    if tangent.z < 0.0 {
        p = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign_not_zero(p);
    }
    let q = ((p * 0.5 + 0.5) * STEPS)
        .round()
        .clamp(Vec2::ZERO, Vec2::splat(STEPS));
    let value = q.x * 4096.0 + q.y + 1.0;
    if sign < 0.0 {
        -value
    } else {
        value
    }
}

/// The unit tangent and handedness (±1) that [`encode_tangent`] stored in `w` (meaningless for
/// [`NO_TANGENT`]: test [`has_tangent`] first).
#[must_use]
pub fn decode_tangent(w: f32) -> (Vec3, f32) {
    let a = (crate::math::float::abs(w) as u32).max(1) - 1;
    let q = Vec2::new((a >> 12) as f32, (a & 4095) as f32);
    let p = q / STEPS * 2.0 - 1.0;
    let mut v = Vec3::new(p.x, p.y, 1.0 - p.x.abs() - p.y.abs());
    if v.z < 0.0 {
        let folded =
            (Vec2::ONE - Vec2::new(v.y.abs(), v.x.abs())) * sign_not_zero(Vec2::new(v.x, v.y));
        v = Vec3::new(folded.x, folded.y, v.z);
    }
    (v.normalize_or(Vec3::X), if w < 0.0 { -1.0 } else { 1.0 })
}

/// Whether `w` holds a tangent.
#[inline]
#[must_use]
pub fn has_tangent(w: f32) -> bool {
    w != NO_TANGENT
}

/// ±1 per component, +1 for zero (the octahedral fold's sign).
#[inline]
fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(
        if v.x < 0.0 { -1.0 } else { 1.0 },
        if v.y < 0.0 { -1.0 } else { 1.0 },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every direction survives the round trip within 0.07°, with its handedness; the value is an
    /// exactly representable integer; zero and non-finite tangents encode as "none".
    #[test]
    fn tangents_round_trip_within_the_quantisation() {
        let mut worst = 0.0f32;
        let mut rng = crate::test_support::SplitMix64(7);
        for i in 0..20_000 {
            let t = match i {
                0 => Vec3::X,
                1 => -Vec3::Z,
                2 => Vec3::new(0.0, -1.0, 0.0),
                3 => Vec3::new(1.0, 1.0, -1.0).normalize(),
                _ => rng.unit_vector(),
            };
            let sign = if i % 3 == 0 { -1.0 } else { 1.0 };
            let w = encode_tangent(t, sign);
            assert!(
                has_tangent(w) && w.abs() >= 1.0 && w.abs() <= 16_777_216.0 && w.fract() == 0.0
            );
            let (d, s) = decode_tangent(w);
            assert_eq!(s, sign);
            worst = worst.max(d.dot(t).clamp(-1.0, 1.0).acos().to_degrees());
        }
        assert!(worst < 0.07, "worst {worst}°");
        for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            assert_eq!(decode_tangent(encode_tangent(axis, 1.0)).0, axis);
        }
        assert_eq!(encode_tangent(Vec3::ZERO, 1.0), NO_TANGENT);
        assert_eq!(
            encode_tangent(Vec3::new(f32::NAN, 0.0, 1.0), 1.0),
            NO_TANGENT
        );
        assert!(!has_tangent(NO_TANGENT));
    }
}
