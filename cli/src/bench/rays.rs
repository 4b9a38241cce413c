//! `fovea bench rays`: ray-traversal throughput alone, without shading, so that the traversal can be
//! compared with another renderer's on the very same rays (`scripts/bench-rays.py` writes a ray file and
//! times Mitsuba 3's Embree traversal on it).
//!
//! Rays come from a ray file or are generated inside the scene's bounds. A ray file is a flat array of
//! little-endian `f32` records of eight values: origin x y z, direction x y z, `t_max` (`inf` for no
//! limit) and the kind, 0 for a closest-hit query ([`closest_hit`]) or 1 for an occlusion query
//! ([`any_hit`]). Generated rays are half of each kind: closest-hit rays from uniform points in the
//! bounds in uniform directions, occlusion rays between two uniform points in the bounds.
use std::path::Path;
use std::time::Instant;

use fovea_core::bvh::{any_hit, closest_hit};
use fovea_core::geometry::Ray;
use fovea_core::rng::SampleRng;
use fovea_core::sampling::warp::square_to_uniform_sphere;
use fovea_core::scene::{Features, SceneView};
use fovea_cpu::specialize::{dispatch, WithScene};
use glam::Vec3;
use rayon::prelude::*;

use crate::error::{FoveaError, Result};

/// Bytes of one ray record in a ray file.
const RECORD_BYTES: usize = 32;
/// Most rays a file may hold or `--count` may ask for.
pub const MAX_RAYS: usize = 1 << 27;
/// Rays per parallel task.
const CHUNK: usize = 4096;

/// One query to time.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    pub ray: Ray,
    pub t_max: f32,
}

/// The two kinds of query, each in file order.
#[derive(Debug, Default)]
pub struct RaySet {
    pub closest: Vec<RayQuery>,
    pub occlusion: Vec<RayQuery>,
}

impl RaySet {
    /// The queries of a ray file (world space) in the coordinates of a scene whose origin is `origin`
    /// (`LoadedScene::origin`; zero leaves them as they are).
    #[must_use]
    pub fn in_scene(mut self, origin: [f64; 3]) -> Self {
        if origin != [0.0; 3] {
            for q in self.closest.iter_mut().chain(&mut self.occlusion) {
                let o = fovea_scene::rebase::to_local(q.ray.origin.as_dvec3().to_array(), origin);
                q.ray = Ray::new(glam::Vec3::from(o), q.ray.direction);
            }
        }
        self
    }
}

/// Reads a ray file (see the module documentation), naming the file and the record in any error.
pub fn read_ray_file(path: &Path) -> Result<RaySet> {
    let bytes = std::fs::read(path).map_err(|e| FoveaError::file(path, e))?;
    parse_ray_records(&bytes).map_err(|message| FoveaError::file(path, message))
}

/// Parses ray records (see the module documentation).
pub fn parse_ray_records(bytes: &[u8]) -> std::result::Result<RaySet, String> {
    if bytes.is_empty() || !bytes.len().is_multiple_of(RECORD_BYTES) {
        return Err(format!(
            "a ray file holds records of {RECORD_BYTES} bytes; {} bytes is not a positive multiple",
            bytes.len()
        ));
    }
    if bytes.len() / RECORD_BYTES > MAX_RAYS {
        return Err(format!("more than {MAX_RAYS} rays"));
    }
    let mut set = RaySet::default();
    for (i, record) in bytes.chunks_exact(RECORD_BYTES).enumerate() {
        let v: [f32; 8] = core::array::from_fn(|k| {
            f32::from_le_bytes([
                record[4 * k],
                record[4 * k + 1],
                record[4 * k + 2],
                record[4 * k + 3],
            ])
        });
        let origin = Vec3::new(v[0], v[1], v[2]);
        let direction = Vec3::new(v[3], v[4], v[5]);
        if !origin.is_finite() || !direction.is_finite() || direction == Vec3::ZERO {
            return Err(format!(
                "ray {i}: origin and direction must be finite, the direction non-zero"
            ));
        }
        if v[6].is_nan() || v[6] <= 0.0 {
            return Err(format!(
                "ray {i}: t_max must be positive (or inf), not {}",
                v[6]
            ));
        }
        let query = RayQuery {
            ray: Ray::new(origin, direction),
            t_max: v[6],
        };
        if v[7] == 0.0 {
            set.closest.push(query);
        } else if v[7] == 1.0 {
            set.occlusion.push(query);
        } else {
            return Err(format!("ray {i}: kind must be 0 or 1, not {}", v[7]));
        }
    }
    Ok(set)
}

/// `count` rays inside the box `lo..hi`, alternately closest-hit and occlusion queries (see the module
/// documentation); the same rays for the same seed. Ray `i` draws from core's sample generator keyed by
/// `i` and the seed, and its direction from core's uniform-sphere warp.
#[must_use]
pub fn generate_rays(lo: Vec3, hi: Vec3, count: usize, seed: u32) -> RaySet {
    let mut set = RaySet::default();
    for i in 0..count {
        let mut rng = SampleRng::new([i as u32, (i as u64 >> 32) as u32], 0, 0, 0, seed);
        let origin = lo + (hi - lo) * rng.next_3d();
        if i % 2 == 0 {
            let direction = square_to_uniform_sphere(rng.next_2d());
            set.closest.push(RayQuery {
                ray: Ray::new(origin, direction),
                t_max: f32::INFINITY,
            });
        } else {
            let d = lo + (hi - lo) * rng.next_3d() - origin;
            let length = d.length();
            if length > 0.0 {
                set.occlusion.push(RayQuery {
                    ray: Ray::new(origin, d / length),
                    t_max: length * (1.0 - 1e-4),
                });
            }
        }
    }
    set
}

/// What one pass over a ray set found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub closest_hits: u64,
    pub occluded: u64,
}

/// One timed pass: the closest-hit queries, then the occlusion queries, each spread over the current
/// rayon pool; the two times in seconds and the counts.
#[must_use]
pub fn trace(scene: &SceneView<'_>, rays: &RaySet) -> (f64, f64, Counts) {
    dispatch(scene, Trace { rays })
}

/// [`trace`] through the scene's specialised feature set (alpha cut-outs are tested only where the
/// scene has them, as in a render).
struct Trace<'a> {
    rays: &'a RaySet,
}

impl WithScene for Trace<'_> {
    type Output = (f64, f64, Counts);

    fn run<F: Features + Sync>(self, scene: &SceneView<'_, F>) -> Self::Output {
        let (closest_s, closest_hits) = count_in_parallel(&self.rays.closest, |q| {
            closest_hit(scene, &q.ray, q.t_max).is_hit()
        });
        let (occlusion_s, occluded) =
            count_in_parallel(&self.rays.occlusion, |q| any_hit(scene, &q.ray, q.t_max));
        let counts = Counts {
            closest_hits,
            occluded,
        };
        (closest_s, occlusion_s, counts)
    }
}

/// How long `test` takes over all `queries` on the current rayon pool, in seconds, and for how many it
/// holds.
fn count_in_parallel(queries: &[RayQuery], test: impl Fn(&RayQuery) -> bool + Sync) -> (f64, u64) {
    let start = Instant::now();
    let count = queries
        .par_chunks(CHUNK)
        .map(|chunk| chunk.iter().filter(|q| test(q)).count() as u64)
        .sum();
    (start.elapsed().as_secs_f64(), count)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(v: [f32; 8]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn parses_records_of_both_kinds() {
        let mut bytes = record([0.0, 0.0, 0.0, 0.0, 0.0, -1.0, f32::INFINITY, 0.0]);
        bytes.extend(record([1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 2.5, 1.0]));
        let set = parse_ray_records(&bytes).unwrap();
        assert_eq!((set.closest.len(), set.occlusion.len()), (1, 1));
        assert_eq!(set.occlusion[0].t_max, 2.5);
        assert_eq!(set.closest[0].t_max, f32::INFINITY);
        assert_eq!(set.closest[0].ray.direction, Vec3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn rejects_bad_records_naming_them() {
        let bad = [
            (vec![0u8; 31], "multiple"),
            (Vec::new(), "multiple"),
            (
                record([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0])
                    .into_iter()
                    .chain(record([f32::NAN, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0]))
                    .collect(),
                "ray 1",
            ),
            (record([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]), "non-zero"),
            (record([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0]), "t_max"),
            (
                record([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, f32::NAN, 0.0]),
                "t_max",
            ),
            (record([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 2.0]), "kind"),
        ];
        for (bytes, needle) in bad {
            let message = parse_ray_records(&bytes).unwrap_err();
            assert!(message.contains(needle), "{message:?} lacks {needle:?}");
        }
    }

    #[test]
    fn generated_rays_are_deterministic_and_inside_the_box() {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 3.0));
        let a = generate_rays(lo, hi, 1000, 5);
        let b = generate_rays(lo, hi, 1000, 5);
        assert_eq!(a.closest.len(), 500);
        assert_eq!(a.occlusion.len(), 500);
        for (x, y) in a.closest.iter().zip(&b.closest) {
            assert_eq!(x.ray.origin, y.ray.origin);
            assert_eq!(x.ray.direction, y.ray.direction);
            assert!(x.ray.origin.cmpge(lo).all() && x.ray.origin.cmple(hi).all());
            assert!((x.ray.direction.length() - 1.0).abs() < 1e-5);
        }
        for q in &a.occlusion {
            let end = q.ray.origin + q.ray.direction * q.t_max;
            assert!(end.cmpge(lo - 1e-4).all() && end.cmple(hi + 1e-4).all());
        }
    }
}
