//! Procedurally generated scenes of any size, for scale tests and benchmarks (San Miguel's 10 M triangles
//! are not available here; a generated scene of the same size stands in for it).
//!
//! [`city_scene`] builds a rolling heightfield (half the triangles) covered with a scattered "forest" of
//! small, randomly sized and placed icosahedron-based blobs (the other half), lit by a few emissive
//! panels floating above it. The heightfield gives large coherent surfaces, the blobs many small,
//! overlapping objects of very different size, so the BVH builder and traversal see both regimes.
//! Everything is deterministic in `seed`.
use fovea_core::scene::Material;

use crate::mesh::LoadedScene;

/// Side length of the generated scene in world units (the heightfield spans `[-S/2, S/2]` in x and z).
pub const CITY_SIZE: f32 = 100.0;

/// A deterministic 64-bit mix (SplitMix64 finaliser) for placements.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A uniform number in `[0, 1)` from `mix64(seed, i, k)`.
fn unit(seed: u64, i: u64, k: u64) -> f32 {
    let bits = mix64(seed ^ mix64(i.wrapping_mul(8).wrapping_add(k)));
    (bits >> 40) as f32 / (1u64 << 24) as f32
}

/// Height of the terrain at `(x, z)`.
fn height(x: f32, z: f32) -> f32 {
    2.0 * (0.11 * x).sin() * (0.07 * z).cos() + 0.6 * (0.37 * x + 0.23 * z).sin()
}

/// The 20 faces of the icosahedron of [`icosahedron`] (vertex indices, counter-clockwise seen from
/// outside); also the base of the tests' subdivided icospheres.
pub const ICOSAHEDRON_FACES: [[u32; 3]; 20] = [
    [0, 11, 5],
    [0, 5, 1],
    [0, 1, 7],
    [0, 7, 10],
    [0, 10, 11],
    [1, 5, 9],
    [5, 11, 4],
    [11, 10, 2],
    [10, 7, 6],
    [7, 1, 8],
    [3, 9, 4],
    [3, 4, 2],
    [3, 2, 6],
    [3, 6, 8],
    [3, 8, 9],
    [4, 9, 5],
    [2, 4, 11],
    [6, 2, 10],
    [8, 6, 7],
    [9, 8, 1],
];

/// The 20 faces of an icosahedron and its 12 vertices (unit circumradius).
fn icosahedron() -> ([[f32; 3]; 12], [[u32; 3]; 20]) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let n = (1.0 + t * t).sqrt();
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p: [f32; 3]| [p[0] / n, p[1] / n, p[2] / n]);
    (v, ICOSAHEDRON_FACES)
}

/// Builds a scene of about `triangles` triangles (at least a few hundred); see the module documentation.
#[must_use]
pub fn city_scene(triangles: u64, seed: u64) -> LoadedScene {
    let triangles = triangles.max(400);
    // Heightfield: n × n quads, two triangles each, for half the budget.
    let n = (((triangles / 2) as f64 / 2.0).sqrt().floor() as u32).max(2);
    // Blobs: the rest, 20 triangles each (an icosahedron with jittered vertices).
    let blob_count = (triangles.saturating_sub(2 * u64::from(n) * u64::from(n)) / 20) as u32;
    let light_panels = 4u32;

    let vertex_count =
        (n as usize + 1).pow(2) + blob_count as usize * 12 + light_panels as usize * 4;
    let triangle_count =
        2 * (n as usize).pow(2) + blob_count as usize * 20 + light_panels as usize * 2;
    let mut scene = LoadedScene {
        positions: Vec::with_capacity(vertex_count),
        triangles: Vec::with_capacity(triangle_count),
        triangle_materials: Vec::with_capacity(triangle_count),
        ..LoadedScene::default()
    };
    scene.materials = vec![
        Material {
            base_color: [0.35, 0.45, 0.25, 1.0],
            roughness: 0.9,
            ..Material::default()
        },
        Material {
            base_color: [0.6, 0.5, 0.4, 1.0],
            roughness: 0.4,
            metallic: 0.3,
            ..Material::default()
        },
        Material {
            base_color: [0.0, 0.0, 0.0, 1.0],
            emission: [40.0, 36.0, 30.0, 0.0],
            ..Material::default()
        },
    ];
    scene.material_names = vec!["terrain".into(), "blob".into(), "panel".into()];

    let step = CITY_SIZE / n as f32;
    let half = CITY_SIZE / 2.0;
    for j in 0..=n {
        for i in 0..=n {
            let x = -half + i as f32 * step;
            let z = -half + j as f32 * step;
            scene.positions.push([x, height(x, z), z]);
        }
    }
    let row = n + 1;
    for j in 0..n {
        for i in 0..n {
            let a = j * row + i;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            // Counter-clockwise seen from above (+y).
            scene.triangles.push([a, c, b]);
            scene.triangles.push([b, c, d]);
            scene.triangle_materials.extend_from_slice(&[0, 0]);
        }
    }

    let (ico_v, ico_f) = icosahedron();
    for b in 0..u64::from(blob_count) {
        let x = -half + CITY_SIZE * unit(seed, b, 0);
        let z = -half + CITY_SIZE * unit(seed, b, 1);
        // Mostly small blobs, a few large ones (radius 0.05 to ~1.5).
        let r = 0.05 + 1.45 * unit(seed, b, 2).powi(4);
        let y = height(x, z) + r * 0.7;
        let base = scene.positions.len() as u32;
        for (k, v) in ico_v.iter().enumerate() {
            let jitter = 0.8 + 0.4 * unit(seed, b * 16 + k as u64, 3);
            scene.positions.push([
                x + r * jitter * v[0],
                y + r * jitter * v[1],
                z + r * jitter * v[2],
            ]);
        }
        for f in &ico_f {
            scene
                .triangles
                .push([base + f[0], base + f[1], base + f[2]]);
            scene.triangle_materials.push(1);
        }
    }

    // Emissive panels facing down, 8 units above the terrain's centre region.
    for p in 0..light_panels {
        let cx = -20.0 + 40.0 * (p % 2) as f32;
        let cz = -20.0 + 40.0 * (p / 2) as f32;
        let y = 10.0;
        let s = 2.0;
        let base = scene.positions.len() as u32;
        scene.positions.extend_from_slice(&[
            [cx - s, y, cz - s],
            [cx + s, y, cz - s],
            [cx + s, y, cz + s],
            [cx - s, y, cz + s],
        ]);
        // Counter-clockwise seen from below (-y): the emitting side faces the terrain.
        scene.triangles.push([base, base + 1, base + 2]);
        scene.triangles.push([base, base + 2, base + 3]);
        scene.triangle_materials.extend_from_slice(&[2, 2]);
    }
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn city_scene_has_about_the_requested_size_and_is_valid() {
        let mut scene = city_scene(20_000, 1);
        let count = scene.triangle_count();
        assert!((19_000..=20_100).contains(&count), "{count} triangles");
        assert_eq!(scene.triangle_materials.len(), count);
        assert!(scene.emissive_triangle_count() == 8);
        scene
            .validate(std::path::Path::new("city"))
            .expect("generated scene is valid");
        // Deterministic in the seed.
        let again = city_scene(20_000, 1);
        assert_eq!(again.positions, city_scene(20_000, 1).positions);
        assert_ne!(city_scene(20_000, 2).positions, again.positions);
    }
}
