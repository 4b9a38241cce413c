//! The CPU's packet traversal of a block's camera rays (`fovea_core::bvh::packet`) against the
//! single-ray 8-wide traversal it replaces for them: the same hits, bit for bit, on coherent packets
//! (jittered camera rays of 1x1, 2x2 and 4x4 blocks) and on incoherent ones (random rays from inside
//! the scene, some with a finite `t_max`), with 1 to 8 rays; and the same sample values from
//! `render_block_samples_packet` as from `render_block_sample`. Every input is from a fixed seed, so a
//! pass is not luck.
use fovea_core::bvh::packet::{closest_hits_packet, PACKET_SIZE};
use fovea_core::bvh::wide::closest_hit_wide;
use fovea_core::bvh::Hit;
use fovea_core::foveation::blocks::OwnedBlock;
use fovea_core::foveation::regions::{
    FoveationParams, REGION_FOVEA, REGION_INTERMEDIATE, REGION_PERIPHERY,
};
use fovea_core::geometry::Ray;
use fovea_core::integrator::{render_block_sample, render_block_samples_packet};
use fovea_core::lights::INFINITE_DISTANCE;
use fovea_core::scene::SceneSlices;
use fovea_scene::environment::Environment;
use fovea_scene::pack::PackedScene;
use fovea_tests::*;
use glam::Vec3;

const W: u32 = 160;
const H: u32 = 120;

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Scenes with their cameras: McGuire's Cornell boxes (large flat walls, a sphere) and Lost Empire
/// (225k triangles, alpha cut-outs).
fn scenes() -> Vec<(&'static str, PackedScene, fovea_core::camera::Camera)> {
    let s = bundled_scenes();
    let mut out = Vec::new();
    for (name, rel) in [
        ("cornell original", "cornell_box/CornellBox-Original.obj"),
        ("cornell sphere", "cornell_box/CornellBox-Sphere.obj"),
    ] {
        out.push((
            name,
            load_packed(&s.join(rel), &Environment::None),
            cornell_camera(W, H),
        ));
    }
    let le = repo_root().join("assets/lost_empire/lost_empire.obj");
    out.push((
        "lost empire",
        load_packed(&le, &Environment::Constant([1.0; 3])),
        lost_empire_camera(60f32.to_radians(), W as f32 / H as f32),
    ));
    out
}

fn assert_same_hits(name: &str, scene: &PackedScene, rays: &[Ray], t_max: f32) -> usize {
    let view = scene.view();
    assert!(
        !view.geometry.wide_nodes.is_empty(),
        "{name}: no 8-wide tree"
    );
    let mut hits = [Hit::miss(); PACKET_SIZE];
    closest_hits_packet(&view, &SceneSlices, rays, t_max, &mut hits);
    let mut found = 0;
    for (ray, packet) in rays.iter().zip(hits) {
        let single = closest_hit_wide(&view, &SceneSlices, ray, t_max);
        assert_eq!(
            (
                packet.t.to_bits(),
                packet.triangle,
                packet.b1.to_bits(),
                packet.b2.to_bits()
            ),
            (
                single.t.to_bits(),
                single.triangle,
                single.b1.to_bits(),
                single.b2.to_bits()
            ),
            "{name}: {ray:?} t_max {t_max}: packet {packet:?}, single ray {single:?}"
        );
        found += usize::from(single.is_hit());
    }
    found
}

#[test]
fn packet_hits_match_single_ray_hits() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for (name, scene, camera) in scenes() {
        let (mut rays_tested, mut hits) = (0, 0);
        // Coherent: the jittered camera rays of blocks of every size, 1 to 8 at a time.
        for k in 0..600u32 {
            let size = [1, 2, 4][(k % 3) as usize];
            let origin = [
                (rng.next() * (W / size) as f32) as u32 * size,
                (rng.next() * (H / size) as f32) as u32 * size,
            ];
            let count = 1 + (k as usize % PACKET_SIZE);
            let rays: Vec<Ray> = (0..count)
                .map(|_| {
                    let film = glam::Vec2::new(
                        origin[0] as f32 + rng.next() * size as f32,
                        origin[1] as f32 + rng.next() * size as f32,
                    );
                    camera.generate_ray(film, W, H)
                })
                .collect();
            hits += assert_same_hits(name, &scene, &rays, INFINITE_DISTANCE);
            rays_tested += count;
        }
        // Incoherent: random rays from inside the bounds, some ending early.
        let (lo, hi) = (scene.bounds_min, scene.bounds_max);
        for k in 0..600u32 {
            let count = 1 + (k as usize % PACKET_SIZE);
            let rays: Vec<Ray> = (0..count)
                .map(|_| {
                    let o = lo + (hi - lo) * Vec3::new(rng.next(), rng.next(), rng.next());
                    let d = Vec3::new(rng.next(), rng.next(), rng.next()) * 2.0 - Vec3::ONE;
                    Ray::new(o, d.try_normalize().unwrap_or(Vec3::Z))
                })
                .collect();
            let t_max = if k % 2 == 0 {
                INFINITE_DISTANCE
            } else {
                rng.next() * (hi - lo).length()
            };
            hits += assert_same_hits(name, &scene, &rays, t_max);
            rays_tested += count;
        }
        eprintln!("{name}: {rays_tested} rays in packets, {hits} hits, all as one by one");
        assert!(hits > rays_tested / 4, "{name}: too few hits to test");
    }
}

#[test]
fn packet_samples_match_single_samples() {
    let mut rng = Rng(42);
    for (name, scene, camera) in scenes() {
        let foveation = FoveationParams::paper([W as f32 * 0.5, H as f32 * 0.5], 20.0, 45.0);
        let frame = frame_params(camera, foveation, W, H, 3);
        let view = scene.view();
        for k in 0..60u32 {
            let (region, size) = [
                (REGION_FOVEA, 1),
                (REGION_INTERMEDIATE, 2),
                (REGION_PERIPHERY, 4),
            ][(k % 3) as usize];
            let block = OwnedBlock {
                region,
                size,
                origin: [
                    (rng.next() * (W / size) as f32) as u32 * size,
                    (rng.next() * (H / size) as f32) as u32 * size,
                ],
            };
            let first = k % 5;
            let count = 1 + (k as usize % PACKET_SIZE);
            let mut packet = vec![Vec3::NAN; count];
            render_block_samples_packet(&view, &frame, &block, first, &mut packet);
            for (i, value) in packet.iter().enumerate() {
                let single = render_block_sample(&view, &frame, &block, first + i as u32);
                assert_eq!(
                    value.to_array().map(f32::to_bits),
                    single.to_array().map(f32::to_bits),
                    "{name}: block {block:?} sample {}",
                    first + i as u32
                );
            }
        }
    }
}
