//! Scene coordinates relative to an origin near the scene, chosen in f64 at load.
//!
//! A position far from the world origin has few bits left for the scene's detail in f32: at 1e4 units
//! a coordinate's ulp is 2^-10 (1e-3) and at 1e5 2^-7, and the ray offsets that keep a bounce from
//! re-hitting its surface (`fovea_core::geometry::offset`, 256 ulps) grow with it, to 0.25 and 2 units:
//! a Cornell box two units wide, moved 1e5 away, loses its contact shadows and then its light. The
//! loaders therefore read positions in f64, subtract [`scene_origin`] in f64 and only then round to
//! f32 ([`to_local`]); the camera and the lights move with the scene, and `LoadedScene::origin` keeps
//! the world position of the new origin. The scene's coordinates are then small whatever its
//! distance from the world origin, so it renders as it would at the origin, and the offsets, which
//! follow the coordinates' magnitude, stay tied to the scene's size.
//!
//! The origin is the centre of the bounds rounded to a multiple of the *grid*, the smallest power of two
//! at least twice the bounds' diagonal. Scenes whose centre lies within one diagonal of the world origin
//! (most scenes) keep origin zero and exactly the coordinates they had; every other scene's coordinates
//! stay within about two diagonals of zero, and a scene moved by a multiple of its grid (1e4 is one
//! for a box below 8 units: 2^4 · 625) gets exactly the coordinates of the unmoved one.
use glam::DVec3;

/// The origin of a scene whose world-space vertices are `world` and whose triangles index them (see
/// the module documentation). Zero for no triangles; non-finite vertices are left out of the bounds.
#[must_use]
pub fn scene_origin(world: &[[f64; 3]], triangles: &[[u32; 3]]) -> [f64; 3] {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &v in triangles.iter().flatten() {
        if let Some(p) = world.get(v as usize).map(|p| DVec3::from(*p)) {
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    if !(lo.cmple(hi).all()) {
        return [0.0; 3];
    }
    let centre = 0.5 * (lo + hi);
    let diagonal = (hi - lo).length();
    if !(diagonal > 0.0 && diagonal.is_finite()) {
        return if centre.is_finite() {
            centre.to_array()
        } else {
            [0.0; 3]
        };
    }
    let grid = (2.0 * diagonal).log2().ceil().exp2();
    ((centre / grid).round() * grid).to_array()
}

/// The world point `p` in the coordinates of a scene whose origin is `origin` (subtracted in f64,
/// then rounded to f32).
#[inline]
#[must_use]
pub fn to_local(p: [f64; 3], origin: [f64; 3]) -> [f32; 3] {
    (DVec3::from(p) - DVec3::from(origin)).as_vec3().to_array()
}

/// The scene point `p` in world coordinates (the inverse of [`to_local`], exact in f64).
#[inline]
#[must_use]
pub fn to_world(p: [f32; 3], origin: [f64; 3]) -> [f64; 3] {
    (glam::Vec3::from(p).as_dvec3() + DVec3::from(origin)).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOX: [[f64; 3]; 4] = [
        [-1.0, 0.0, -1.0],
        [1.0, 0.0, -1.0],
        [1.0, 2.0, 1.0],
        [0.03, 1.99, -0.04],
    ];
    const TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [1, 2, 3]];

    fn moved(by: f64) -> Vec<[f64; 3]> {
        BOX.iter().map(|p| p.map(|c| c + by)).collect()
    }

    #[test]
    fn a_scene_near_the_world_origin_keeps_its_coordinates() {
        assert_eq!(scene_origin(&BOX, &TRIANGLES), [0.0; 3]);
        for p in BOX {
            assert_eq!(to_local(p, [0.0; 3]), p.map(|c| c as f32));
        }
    }

    /// Moved by 1e3, 1e4 or 1e5 (multiples of the box's 8-unit grid), the box gets back the coordinates
    /// it has at the origin, which f32 world coordinates could not hold (1e5 + 0.03 has ulps of 2^-7).
    #[test]
    fn a_moved_scene_gets_the_coordinates_of_the_unmoved_one() {
        for by in [1e3, 1e4, 1e5, -1e5, 1e7] {
            let world = moved(by);
            let origin = scene_origin(&world, &TRIANGLES);
            assert_eq!(origin, [by; 3], "{by}");
            for (p, q) in world.iter().zip(BOX) {
                let local = to_local(*p, origin);
                let exact = q.map(|c| c as f32);
                for k in 0..3 {
                    assert!(
                        (local[k] - exact[k]).abs() <= 1e-6,
                        "{by}: {local:?} {exact:?}"
                    );
                }
                let back = to_world(local, origin);
                assert!((0..3).all(|k| (back[k] - p[k]).abs() < 1e-6));
            }
            // Without the rebase the same point in f32 is off by up to half an ulp of the distance.
            if by >= 1e5 {
                let f32_world = (world[3][0] as f32) as f64;
                assert!((f32_world - world[3][0]).abs() > 1e-3);
            }
        }
    }

    /// Off a grid multiple, the coordinates stay within two diagonals of zero.
    #[test]
    fn coordinates_stay_near_zero() {
        for by in [3.3e4, -7.77e5, 12345.678] {
            let world = moved(by);
            let origin = scene_origin(&world, &TRIANGLES);
            let diagonal = 12f64.sqrt();
            for p in &world {
                let local = to_local(*p, origin);
                assert!(
                    local.iter().all(|c| f64::from(c.abs()) <= 2.5 * diagonal),
                    "{local:?}"
                );
            }
        }
    }

    #[test]
    fn empty_degenerate_and_non_finite_scenes() {
        assert_eq!(scene_origin(&[], &[]), [0.0; 3]);
        let nan = [[f64::NAN, 0.0, 0.0], [1e6, 1e6, 1e6]];
        assert_eq!(scene_origin(&nan, &[[0, 1, 1]]), [1e6; 3]);
        assert_eq!(scene_origin(&[[f64::NAN; 3]], &[[0, 0, 0]]), [0.0; 3]);
        // An index past the vertices is the validation's to report, not a panic here.
        assert_eq!(scene_origin(&BOX, &[[0, 1, 99]]), [0.0; 3]);
    }
}
