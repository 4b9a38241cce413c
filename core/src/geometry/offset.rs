//! Scale-aware ray origin offsets (Wächter and Binder 2019, "A Fast and Robust Method for Avoiding
//! Self-Intersection", Ray Tracing Gems ch. 6), extended to geometry smaller than unit scale.
//!
//! A hit point computed in floating point lies near, not on, its triangle; a ray leaving it may re-hit the
//! same surface. Instead of a world-space epsilon, each coordinate is moved along the geometric normal by a
//! fixed number of ulps (so the offset scales with the coordinate's magnitude), and by a small fixed
//! distance for coordinates near zero, where ulps become arbitrarily small.
//!
//! Wächter and Binder's near-zero constants assume unit-scale geometry: a triangle of size 1e-5 near the
//! origin would be pushed 1.5e-5 off its plane, through anything facing it. The error of an interpolated
//! hit point is relative to the triangle's vertex coordinates, so both near-zero constants are scaled
//! here by the triangle's magnitude (its largest absolute vertex coordinate, [`triangle_magnitude`])
//! when that is below 1. Triangles of magnitude 1 or more get exactly the published offsets.
use glam::Vec3;

/// Coordinates with magnitude below this (times the triangle's magnitude, if below 1) are offset by
/// [`FLOAT_SCALE`] (times the same) world units rather than in ulps.
pub const ORIGIN: f32 = 1.0 / 32.0;
/// The offset (times the normal) of coordinates near zero, for triangles of magnitude 1 or more.
pub const FLOAT_SCALE: f32 = 1.0 / 65536.0;
/// The offset in ulps (times the normal) of the other coordinates.
pub const INT_SCALE: f32 = 256.0;

/// Where a shadow ray `origin + t (target - origin)` towards an offset target stops: 2^-16 short of the
/// target (pbrt-v4 uses `1 - 1e-4`, its `ShadowEpsilon`).
///
/// The target is offset from its surface by up to 256 ulps of *its own* coordinates, but the hit
/// distance `t` of a segment is only known to a few ulps of 1, i.e. a few times 6e-8 of the segment's
/// length: when the segment is much longer than the target's coordinates are large (an origin far from
/// a light near the world origin), the target's own surface can be found at `t = 1 - 1 ulp` and block
/// the ray. Stopping at `1 - 2^-16` leaves 512 ulps of `t` to that error; it ignores occluders within
/// 1.5e-5 of the segment's length of the target.
pub const SHADOW_RAY_T_MAX: f32 = 1.0 - 1.0 / 65536.0;

/// The smallest magnitude the near-zero offsets scale down to (2^-32 ≈ 2.3e-10). Below it the watertight
/// test's scaled distance, a product of three coordinates, comes within reach of f32's subnormals
/// (about 1e-38), so its sign is no longer reliable and a smaller offset would re-hit the triangle.
pub const MIN_MAGNITUDE: f32 = 1.0 / 4_294_967_296.0;

/// The magnitude that scales a triangle's near-zero offsets: its largest absolute vertex coordinate.
#[inline]
#[must_use]
pub fn triangle_magnitude(v: &[Vec3; 3]) -> f32 {
    v[0].abs().max(v[1].abs()).max(v[2].abs()).max_element()
}

/// One coordinate of [`offset_ray_origin`]; `scale` is the triangle magnitude clamped to
/// [`MIN_MAGNITUDE`, 1].
#[inline]
#[must_use]
fn offset_component(p: f32, n: f32, scale: f32) -> f32 {
    // A unit normal's components lie in [-1, 1]; clamping keeps the float-to-int cast below in range for
    // any input (an out-of-range `OpConvertFToS` is undefined on the GPU).
    let n = n.clamp(-1.0, 1.0);
    if p.abs() < ORIGIN * scale {
        p + FLOAT_SCALE * scale * n
    } else {
        // |INT_SCALE * n| <= 256; the cast truncates towards zero.
        let ulps = (INT_SCALE * n) as i32;
        // Integer steps on the bit pattern move away from zero for positive steps, so flip the sign of
        // the step for negative coordinates.
        let ulps = if p < 0.0 { -ulps } else { ulps };
        f32::from_bits((p.to_bits() as i32).wrapping_add(ulps) as u32)
    }
}

/// Moves the hit point `p` off its surface along the unit geometric normal `n` (Wächter and Binder 2019,
/// Listing 6-1, with the near-zero constants scaled by `magnitude` when it is below 1, down to
/// [`MIN_MAGNITUDE`]; see the module documentation). Pass `-n` to leave on the back side (transmission, or a back-face hit).
///
/// `p` should be interpolated from the triangle's vertices with the barycentrics of the hit (more accurate
/// than `origin + t * direction`); `n` must be unit length (it is not normalised here); `magnitude` is the
/// triangle's [`triangle_magnitude`] (1 gives the published method).
#[inline]
#[must_use]
pub fn offset_ray_origin(p: Vec3, n: Vec3, magnitude: f32) -> Vec3 {
    // Written so that NaN takes the smallest scale.
    let scale = if magnitude >= 1.0 {
        1.0
    } else if magnitude > MIN_MAGNITUDE {
        magnitude
    } else {
        MIN_MAGNITUDE
    };
    Vec3::new(
        offset_component(p.x, n.x, scale),
        offset_component(p.y, n.y, scale),
        offset_component(p.z, n.z, scale),
    )
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::geometry::triangle::WatertightRay;
    use crate::geometry::Ray;
    use crate::scene::TrianglePositions;

    use crate::test_support::SplitMix64 as TestRng;

    #[test]
    fn offset_moves_along_normal() {
        // Near the origin: a fixed float step.
        let q = offset_ray_origin(Vec3::ZERO, Vec3::Z, 1.0);
        assert_eq!(q, Vec3::new(0.0, 0.0, FLOAT_SCALE));
        // Far away: 256 ulps along the normal, in the normal's direction for either sign of p.
        let q = offset_ray_origin(
            Vec3::new(1000.0, -1000.0, 5.0),
            Vec3::new(1.0, 1.0, -1.0) * 0.57735,
            1000.0,
        );
        assert!(q.x > 1000.0 && q.y > -1000.0 && q.z < 5.0);
        assert_eq!(q.x.to_bits() - 1000.0f32.to_bits(), 147);
        assert_eq!((-1000.0f32).to_bits() - q.y.to_bits(), 147);
    }

    #[test]
    fn near_zero_offsets_scale_with_small_triangles() {
        let tiny = [
            Vec3::new(1e-5, 0.0, 0.0),
            Vec3::new(0.0, 2e-5, 0.0),
            Vec3::ZERO,
        ];
        let m = triangle_magnitude(&tiny);
        assert_eq!(m, 2e-5);
        let q = offset_ray_origin(Vec3::ZERO, Vec3::Z, m);
        assert_eq!(q, Vec3::new(0.0, 0.0, FLOAT_SCALE * 2e-5));
        let q = offset_ray_origin(Vec3::ZERO, Vec3::Z, 1e-20);
        assert_eq!(q, Vec3::new(0.0, 0.0, FLOAT_SCALE * MIN_MAGNITUDE));
        // Magnitude 1 and above: the published constants; degenerate or NaN magnitudes stay finite.
        assert_eq!(
            offset_ray_origin(Vec3::ZERO, Vec3::Z, 7.0),
            offset_ray_origin(Vec3::ZERO, Vec3::Z, 1.0)
        );
        for m in [0.0, -1.0, f32::NAN] {
            let q = offset_ray_origin(Vec3::ZERO, Vec3::Z, m);
            assert!(q.z > 0.0 && q.is_finite(), "{m}: {q:?}");
        }
    }

    /// Random points on random triangles at scales from 1e-8 to 1e6 and far from the origin: rays leaving
    /// the offset point into the hemisphere of the offset never re-hit their own triangle.
    #[test]
    fn offset_points_do_not_self_intersect() {
        let mut rng = TestRng(11);
        let scales = [1e-8f32, 1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6];
        let centres = [0.0f32, 1.0, 1e3, 1e5, 1e6];
        let mut tested = 0;
        for &scale in &scales {
            for &distance in &centres {
                // Keep at least ~13 bits of relative precision in the vertices, otherwise the triangle
                // is a quantised sliver whose stored plane differs from its computed normal.
                if scale < distance * 1e-4 {
                    continue;
                }
                let mut done = 0;
                while done < 400 {
                    let centre = rng.unit_vector() * distance;
                    let v0 = centre + rng.unit_vector() * scale;
                    let v1 = centre + rng.unit_vector() * scale;
                    let v2 = centre + rng.unit_vector() * scale;
                    let cross = (v1 - v0).cross(v2 - v0);
                    let longest = (v1 - v0)
                        .length()
                        .max((v2 - v1).length())
                        .max((v0 - v2).length());
                    let proper = cross.length() > 0.1 * longest * longest;
                    if !proper {
                        continue; // slivers
                    }
                    let n = cross.normalize();
                    let tri = TrianglePositions {
                        v0: v0.extend(0.0),
                        v1: v1.extend(0.0),
                        v2: v2.extend(0.0),
                    };
                    let (mut b1, mut b2) = (rng.uniform(), rng.uniform());
                    if b1 + b2 > 1.0 {
                        b1 = 1.0 - b1;
                        b2 = 1.0 - b2;
                    }
                    let (t0, t1, t2) = (tri.v0.truncate(), tri.v1.truncate(), tri.v2.truncate());
                    let p = t0 * (1.0 - b1 - b2) + t1 * b1 + t2 * b2;
                    for side in [1.0f32, -1.0] {
                        let ns = n * side;
                        let origin = offset_ray_origin(p, ns, triangle_magnitude(&[t0, t1, t2]));
                        for _ in 0..16 {
                            let mut d = rng.unit_vector();
                            if d.dot(ns) < 0.0 {
                                d = -d;
                            }
                            let hit = WatertightRay::new(&Ray::new(origin, d))
                                .intersect(&tri, f32::INFINITY);
                            assert!(
                                !hit.hit,
                                "self-hit: scale {scale} distance {distance} p {p:?} n {ns:?} d {d:?} t {}",
                                hit.t
                            );
                            tested += 1;
                        }
                        // The offset is small next to the triangle: the ray straight back hits it.
                        if scale >= 0.01 * distance.max(1.0) && b1.min(b2).min(1.0 - b1 - b2) > 0.05
                        {
                            let back = WatertightRay::new(&Ray::new(origin, -ns))
                                .intersect(&tri, f32::INFINITY);
                            assert!(back.hit, "{scale} {distance} {p:?} {origin:?}");
                            let m = triangle_magnitude(&[t0, t1, t2]).min(1.0);
                            assert!(back.t < 1e-4 * p.abs().max_element() + 2.0 * FLOAT_SCALE * m);
                        }
                    }
                    done += 1;
                }
            }
        }
        assert!(tested > 100_000);
    }
}
