//! Shared driver of the fuzz targets: split the input into a scene file and the files it refers to, load
//! it from memory, then build the BVH, pack it and check the packed arrays' invariants and a few rays.
//!
//! Input layout: the scene file's bytes, optionally followed by [`SIDE_FILE_SEPARATOR`] and the bytes
//! every other file the scene asks for (an MTL library, a glTF buffer or image, a texture) reads as.
//! For OBJ, a second separator splits that tail into the MTL library (first) and every other file.
use std::io;
use std::path::{Path, PathBuf};

use fovea_core::bvh::closest_hit;
use fovea_core::geometry::Ray;
use fovea_core::scene::{
    is_leaf_word, triangle_lane, GeometryArrays, SceneView, BLOCK_LANE_CUTOUT, INVALID_INDEX,
    TEXTURE_RGBA16,
};
use fovea_scene::bvh::blocks::leaf_slots;
use fovea_scene::bvh::{BvhBuildOptions, MAX_NODE_DEPTH};
use fovea_scene::environment::Environment;
use fovea_scene::load_scene_from;
use fovea_scene::mesh::{LoadOptions, MtlDiffuse};
use fovea_scene::pack::{pack_scene, PackedScene};
use fovea_scene::source::FileSource;
use glam::Vec3;

/// Separates the scene file from the files it refers to.
pub const SIDE_FILE_SEPARATOR: &[u8] = b"\n#%FOVEA-FILE%#\n";

/// Limits small enough that no input can make the pipeline allocate more than a few hundred MiB; purely
/// diffuse MTL materials Lambertian, the loader's non-default branch.
pub fn fuzz_options() -> LoadOptions {
    LoadOptions {
        mtl_override: None,
        max_texture_dimension: 2048,
        max_texture_bytes: 32 << 20,
        max_vertices: 1 << 20,
        max_triangles: 1 << 20,
        mtl_diffuse: MtlDiffuse::Lambert,
    }
}

/// Splits `data` at the first `separator`.
pub fn split<'a>(data: &'a [u8], separator: &[u8]) -> (&'a [u8], Option<&'a [u8]>) {
    match data.windows(separator.len()).position(|w| w == separator) {
        Some(i) => (&data[..i], Some(&data[i + separator.len()..])),
        None => (data, None),
    }
}

/// The scene file at a fixed path, MTL libraries (`*.mtl`) and every other file from the input.
pub struct FuzzFiles<'a> {
    pub scene_path: PathBuf,
    pub scene: &'a [u8],
    pub mtl: Option<&'a [u8]>,
    pub other: Option<&'a [u8]>,
}

impl FileSource for FuzzFiles<'_> {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        let not_found = || io::Error::from(io::ErrorKind::NotFound);
        if path == self.scene_path {
            return Ok(self.scene.to_vec());
        }
        let is_mtl = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mtl"));
        let bytes = if is_mtl { self.mtl } else { self.other };
        bytes.map(<[u8]>::to_vec).ok_or_else(not_found)
    }
}

/// Loads `files.scene_path` from `files`, then packs and checks it. Errors are fine; panics and broken
/// invariants are what the fuzzer looks for.
pub fn run(files: &FuzzFiles) {
    let options = fuzz_options();
    let loaded = match load_scene_from(files, &files.scene_path, &options) {
        Ok(s) => s,
        Err(e) => {
            // Every error names the scene or one of its files (MTL and texture paths may be absolute).
            let text = e.to_string();
            assert!(names_a_file(&text), "error without a file name: {text}");
            return;
        }
    };
    let triangles = loaded.triangles.len();
    assert!(triangles > 0);
    for w in &loaded.warnings {
        assert!(names_a_file(w), "warning without a file name: {w}");
    }
    let packed = pack_scene(loaded, &Environment::None, &BvhBuildOptions::default());
    check_packed(&packed, triangles);
    cast_rays(&packed);
}

/// Whether a message starts with a file name: the scene's folder (`fuzz/...`), or an absolute path or
/// a path relative to the scene's folder that the scene itself named.
fn names_a_file(message: &str) -> bool {
    message.starts_with("fuzz/")
        || message.starts_with('/')
        || message.contains("fuzz/")
        || message
            .split_once(": ")
            .is_some_and(|(file, _)| !file.trim().is_empty())
}

fn finite(v: &[f32]) -> bool {
    v.iter().all(|c| c.is_finite())
}

/// Invariants every packed scene must satisfy (what the CPU and GPU kernels rely on).
pub fn check_packed(p: &PackedScene, triangles: usize) {
    assert_eq!(p.geometry.triangle_lanes.len(), triangles);
    assert_eq!(p.geometry.triangle_info.len(), triangles);
    assert!(!p.geometry.nodes.is_empty());
    assert!(p.stats.bvh.max_depth <= MAX_NODE_DEPTH, "{:?}", p.stats.bvh);
    assert!(finite(&p.bounds_min.to_array()) && finite(&p.bounds_max.to_array()));
    let vertices = p.geometry.normals.len().max(p.geometry.uvs.len());
    for (i, info) in p.geometry.triangle_info.iter().enumerate() {
        let t = p.triangle(i);
        assert!(
            finite(&t.v0.to_array()) && finite(&t.v1.to_array()) && finite(&t.v2.to_array()),
            "{t:?}"
        );
        assert!((info.material as usize) < p.materials.list.len());
        if vertices > 0 {
            assert!(info.vertices.iter().all(|&v| (v as usize) < vertices));
        }
    }
    for n in &p.geometry.normals {
        assert!(finite(n));
    }
    for uv in &p.geometry.uvs {
        assert!(finite(uv));
    }
    for m in &p.materials.list {
        assert!(finite(&m.base_color) && finite(&m.emission), "{m:?}");
        assert!(m.emission[..3].iter().all(|&e| e >= 0.0), "{m:?}");
        assert!(finite(&[
            m.metallic,
            m.roughness,
            m.alpha_cutoff,
            m.normal_scale,
            m.clearcoat,
            m.sheen,
            m.transmission,
            m.ior
        ]));
        assert!(m.absorption.iter().all(|&a| a.is_finite() && a >= 0.0), "{m:?}");
        for t in [
            m.base_color_texture,
            m.metallic_roughness_texture,
            m.normal_texture,
            m.emission_texture,
            m.alpha_texture,
            m.transmission_texture,
            m.clearcoat_texture,
            m.clearcoat_roughness_texture,
            m.sheen_texture,
            m.specular_texture,
            m.specular_color_texture,
            m.anisotropy_texture,
        ] {
            assert!(t == INVALID_INDEX || (t as usize) < p.materials.textures.len());
        }
    }
    for t in &p.materials.textures {
        let words = if t.flags & TEXTURE_RGBA16 != 0 { 2 } else { 1 };
        let end = t.offset as u64 + words * u64::from(t.width) * u64::from(t.height);
        assert!(t.width > 0 && t.height > 0 && end <= p.materials.texels.len() as u64);
        assert!(
            words == 1 || t.offset % 2 == 0,
            "RGBA16 textures start at an even word"
        );
    }
    // Every leaf names blocks that exist, whose first `count` lanes hold its triangles, each triangle
    // exactly once over all leaves, at the lane `triangle_lanes` names.
    let mut seen = vec![false; triangles];
    for node in &p.geometry.nodes {
        for (_, first, count) in leaf_slots(node) {
            for k in 0..count.div_ceil(4) * 4 {
                let lane = p.geometry.blocks[first + k / 4].index[k % 4];
                if k < count {
                    let t = (lane & !BLOCK_LANE_CUTOUT) as usize;
                    assert!(
                        t < triangles && !seen[t],
                        "leaf lane {k} names triangle {t}"
                    );
                    assert_eq!(
                        p.geometry.triangle_lanes[t],
                        triangle_lane((first + k / 4) as u32, (k % 4) as u32),
                        "triangle {t}'s lane"
                    );
                    seen[t] = true;
                } else {
                    assert_eq!(lane, INVALID_INDEX);
                }
            }
        }
    }
    assert!(seen.iter().all(|&s| s), "every triangle is in a leaf");
    // The CPU's 8-wide tree has the very same leaves.
    let leaf_words = |words: Vec<u32>| {
        let mut w: Vec<u32> = words.into_iter().filter(|&w| is_leaf_word(w)).collect();
        w.sort_unstable();
        w
    };
    let four = leaf_words(
        p.geometry
            .nodes
            .iter()
            .flat_map(|n| n.slots.to_array())
            .collect(),
    );
    let eight = leaf_words(p.geometry.wide_nodes.iter().flat_map(|n| n.slots).collect());
    assert_eq!(four, eight, "8-wide leaves");
    assert!(!p.geometry.wide_nodes.is_empty());
    if !p.lights.list.is_empty() {
        assert_eq!(p.lights.cdf.len(), p.lights.list.len() + 1);
        assert!(p.lights.cdf.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(*p.lights.cdf.last().unwrap(), 1.0);
        let sum: f32 = p.lights.list.iter().map(|l| l.pmf).sum();
        assert!(p
            .lights
            .list
            .iter()
            .all(|l| l.pmf.is_finite() && l.pmf >= 0.0));
        assert!((sum - 1.0).abs() < 1e-3, "pmf sum {sum}");
        for l in &p.lights.list {
            assert!(finite(&l.position) && finite(&l.direction) && finite(&l.intensity));
        }
    }
    if !p.lights.triangle_light.is_empty() {
        assert_eq!(p.lights.triangle_light.len(), triangles);
    }
}

/// Rays through the scene from outside its bounds and from its centre: traversal must not panic and hits
/// must be valid.
pub fn cast_rays(p: &PackedScene) {
    let view = p.view();
    let centre = 0.5 * (p.bounds_min + p.bounds_max);
    let extent = (p.bounds_max - p.bounds_min).max_element().max(1.0);
    let dirs = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::new(1.0, 2.0, 3.0).normalize(),
        Vec3::new(-3.0, 0.5, -1.0).normalize(),
    ];
    let mut rays: Vec<Ray> = Vec::new();
    for d in dirs {
        rays.push(Ray::new(centre, d));
        let outside = centre - d * extent * 2.0;
        if outside.is_finite() {
            rays.push(Ray::new(outside, d));
        }
    }
    // A ray at the centroid of a few triangles.
    let step = (p.triangle_count() / 8).max(1);
    for t in (0..p.triangle_count())
        .step_by(step)
        .take(8)
        .map(|i| p.triangle(i))
    {
        let c = (t.v0.truncate() + t.v1.truncate() + t.v2.truncate()) / 3.0;
        let origin = c + Vec3::new(0.3, 1.0, 0.7) * extent;
        let d = (c - origin).normalize_or_zero();
        if d != Vec3::ZERO && c.is_finite() && origin.is_finite() {
            rays.push(Ray::new(origin, d));
        }
    }
    // The same rays through the 4-wide tree alone (what the GPU traverses) find the same distances.
    let four_wide = SceneView {
        geometry: GeometryArrays {
            wide_nodes: &[],
            ..view.geometry
        },
        ..view
    };
    for ray in &rays {
        let hit = closest_hit(&view, ray, f32::INFINITY);
        if hit.is_hit() {
            assert!((hit.triangle as usize) < p.triangle_count());
            assert!(hit.t >= 0.0 && hit.t.is_finite(), "{hit:?}");
        }
        let four = closest_hit(&four_wide, ray, f32::INFINITY);
        assert_eq!(hit.is_hit(), four.is_hit(), "{ray:?}");
        assert_eq!(hit.t.to_bits(), four.t.to_bits(), "{ray:?}");
    }
}
