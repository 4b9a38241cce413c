//! Shared helpers for the end-to-end tests in `tests/tests/`.
use std::path::{Path, PathBuf};

use fovea_core::camera::Camera;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::integrator::{FrameParams, IntegratorSettings};
use fovea_cpu::{FrameImage, RenderStats};
use fovea_scene::bvh::BvhBuildOptions;
use fovea_scene::environment::Environment;
use fovea_scene::load_scene;
use fovea_scene::mesh::LoadOptions;
use fovea_scene::pack::{pack_scene, PackedScene};
use glam::Vec3;

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The scenes that ship with the repository (`assets/`): the Cornell boxes, their glTF and stiff
/// variants, the Veach MIS scene, the roughness sweep, the emissive triangle, the dark Cornell box and
/// Lost Empire, each with its `SOURCE.md` and licence.
pub fn bundled_scenes() -> PathBuf {
    repo_root().join("assets")
}

/// The bundled Cornell box (CornellBox-Original, 36 triangles, ceiling light).
pub fn cornell_box_path() -> PathBuf {
    repo_root().join("assets/cornell_box/CornellBox-Original.obj")
}

/// Loads and packs a scene file.
pub fn load_packed(path: &Path, environment: &Environment) -> PackedScene {
    let loaded = load_scene(path, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("loading {}: {e}", path.display()));
    pack_scene(loaded, environment, &BvhBuildOptions::default())
}

/// The indices of a packed scene's emissive triangles.
pub fn emissive_triangles(packed: &PackedScene) -> Vec<u32> {
    (0..packed.triangle_count() as u32)
        .filter(|&t| {
            let m = packed.geometry.triangle_info[t as usize].material as usize;
            packed.materials.list[m].is_emissive()
        })
        .collect()
}

/// The Lost Empire view of the Vulkan tests (over the village towards the lava) with vertical field of
/// view `fov_y` (radians).
pub fn lost_empire_camera(fov_y: f32, aspect: f32) -> Camera {
    Camera::look_at(
        Vec3::new(-20.0, 30.0, 60.0),
        Vec3::new(5.0, 15.0, 20.0),
        Vec3::Y,
        fov_y,
        aspect,
    )
}

/// The paper's foveation (32/16/8 spp on 1/2/4 blocks, 5.2° and 17°) for a `width`×`height` image on the
/// default display (70.848 × 39.852 cm at 60 cm), gaze at the centre.
pub fn paper_foveation(width: u32, height: u32) -> FoveationParams {
    use fovea_core::foveation::display::{eccentricity_to_radius_px, DisplayGeometry};
    let display = DisplayGeometry {
        width_cm: 70.848,
        height_cm: 39.852,
        distance_cm: 60.0,
        resolution: [width, height],
    };
    FoveationParams::paper(
        [width as f32 * 0.5, height as f32 * 0.5],
        eccentricity_to_radius_px(5.2, &display),
        eccentricity_to_radius_px(17.0, &display),
    )
}

/// The camera that views McGuire's Cornell box from the front.
pub fn cornell_camera(width: u32, height: u32) -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 1.0, 3.9),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::Y,
        38f32.to_radians(),
        width as f32 / height as f32,
    )
}

/// Frame parameters with default integrator settings.
pub fn frame_params(
    camera: Camera,
    foveation: FoveationParams,
    width: u32,
    height: u32,
    seed: u32,
) -> FrameParams {
    FrameParams {
        camera,
        foveation,
        integrator: IntegratorSettings::default(),
        width,
        height,
        frame_index: 0,
        seed,
    }
}

/// Renders on the CPU host with bilinear fill.
pub fn render(scene: &PackedScene, frame: &FrameParams) -> (FrameImage, RenderStats) {
    fovea_cpu::render_frame(
        &scene.view(),
        frame,
        fovea_core::foveation::fill::FILL_BILINEAR,
        &|_| {},
    )
}

/// Mean of the RGB channels over a set of pixels.
pub fn mean_rgb(image: &FrameImage, pixels: impl Iterator<Item = (u32, u32)>) -> Vec3 {
    let mut sum = glam::DVec3::ZERO;
    let mut n = 0u64;
    for (x, y) in pixels {
        let p = image.pixels[(y * image.width + x) as usize];
        sum += glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        n += 1;
    }
    (sum / n.max(1) as f64).as_vec3()
}

/// Loads and packs a scene file and returns its camera description, if the file has one.
pub fn load_packed_with_camera(
    path: &Path,
    environment: &Environment,
) -> (PackedScene, Option<fovea_scene::mesh::CameraDesc>) {
    load_packed_with_camera_and(path, environment, &LoadOptions::default())
}

/// [`load_packed_with_camera`] with other load options.
pub fn load_packed_with_camera_and(
    path: &Path,
    environment: &Environment,
    options: &LoadOptions,
) -> (PackedScene, Option<fovea_scene::mesh::CameraDesc>) {
    let loaded =
        load_scene(path, options).unwrap_or_else(|e| panic!("loading {}: {e}", path.display()));
    let camera = loaded.camera;
    (
        pack_scene(loaded, environment, &BvhBuildOptions::default()),
        camera,
    )
}

/// The file's camera if it has one, else a view from `+z` (slightly above) that frames the scene's
/// bounding sphere, as `fovea render` chooses.
pub fn scene_camera(
    packed: &PackedScene,
    desc: Option<&fovea_scene::mesh::CameraDesc>,
    aspect: f32,
) -> Camera {
    if let Some(c) = desc {
        return Camera::from_forward(
            Vec3::from(c.position),
            Vec3::from(c.forward),
            Vec3::from(c.up),
            c.yfov_radians,
            aspect,
        );
    }
    let (lo, hi) = (packed.bounds_min, packed.bounds_max);
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let fov = 45f32.to_radians();
    let distance = radius / (0.5 * fov).tan() * 1.05;
    let dir = Vec3::new(0.0, 0.15, 1.0).normalize();
    Camera::look_at(centre + dir * distance, centre, Vec3::Y, fov, aspect)
}

pub use fovea_frame::rgba8_to_rgb8;

pub use fovea_frame::{agreement, pixels_agree};

/// relMSE (per channel: squared error over the reference squared plus 0.01) over the pixels `keep`
/// selects.
pub fn rel_mse_where(
    image: &FrameImage,
    reference: &FrameImage,
    keep: impl Fn(u32, u32) -> bool,
) -> f64 {
    let mut sum = 0.0f64;
    let mut n = 0u64;
    for y in 0..image.height {
        for x in 0..image.width {
            if !keep(x, y) {
                continue;
            }
            let i = (y * image.width + x) as usize;
            for c in 0..3 {
                let (a, r) = (
                    f64::from(image.pixels[i][c]),
                    f64::from(reference.pixels[i][c]),
                );
                sum += (a - r) * (a - r) / (r * r + 0.01);
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

/// A validating Vulkan context on the default device, or `None` (the caller skips its test with a message)
/// where there is no Vulkan loader or device and `CI` is not `true`; under `CI=true` a missing device fails.
pub fn vulkan_context_or_skip(what: &str) -> Option<fovea_vulkan::VulkanContext> {
    vulkan_context_with_or_skip(what, fovea_vulkan::Traversal::Software)
}

/// [`vulkan_context_or_skip`] with the given traversal (`Hardware` fails the test where the device has
/// no ray queries: lavapipe has them).
pub fn vulkan_context_with_or_skip(
    what: &str,
    traversal: fovea_vulkan::Traversal,
) -> Option<fovea_vulkan::VulkanContext> {
    std::env::set_var("FOVEA_VULKAN_VALIDATION", "1");
    let options = fovea_vulkan::ContextOptions {
        device_index: None,
        validation: fovea_vulkan::validation_requested(),
        window: None,
        traversal,
        present_only: false,
        factory: None,
    };
    vulkan_context_from_or_skip(what, &options)
}

/// A Vulkan context made with `options`, or `None` (a note printed) where there is no Vulkan device;
/// under `CI=true` a missing device fails the test.
pub fn vulkan_context_from_or_skip(
    what: &str,
    options: &fovea_vulkan::ContextOptions,
) -> Option<fovea_vulkan::VulkanContext> {
    use fovea_vulkan::{VulkanContext, VulkanError};
    match VulkanContext::new(options) {
        Ok(ctx) => Some(ctx),
        Err(e @ (VulkanError::NoLoader(_) | VulkanError::NoDevice(_))) => {
            if std::env::var("CI").as_deref() == Ok("true") {
                panic!("CI=true but no Vulkan device: {e}");
            }
            eprintln!("skipping {what}: {e}");
            None
        }
        Err(e) => panic!("cannot create a Vulkan context: {e}"),
    }
}

/// Helpers of the numerical-stability suite (`tests/tests/stability_*.rs`).
pub mod stability {
    use fovea_core::scene::Material;
    use fovea_scene::bvh::BvhBuildOptions;
    use fovea_scene::environment::Environment;
    use fovea_scene::mesh::LoadedScene;
    use fovea_scene::pack::{pack_scene, PackedScene};
    use glam::Vec3;

    /// Whether the heavy (nightly / manual) variant runs: `FOVEA_HEAVY=1`.
    pub fn heavy() -> bool {
        std::env::var("FOVEA_HEAVY").as_deref() == Ok("1")
    }

    /// `ci` normally, `heavy` with `FOVEA_HEAVY=1`.
    pub fn pick<T>(ci: T, heavy_value: T) -> T {
        if heavy() {
            heavy_value
        } else {
            ci
        }
    }

    /// A float's position on the number line in ULPs (±0 both map to 0), for ULP distances.
    pub fn ordered(x: f32) -> i64 {
        let b = x.to_bits() as i32;
        if b < 0 {
            -i64::from(b & 0x7fff_ffff)
        } else {
            i64::from(b)
        }
    }

    /// Appends one probe item: `records` padded with zeros to `kernel_abi::PROBE_INPUT_RECORDS`.
    pub fn push_probe_item(inputs: &mut Vec<[f32; 4]>, records: &[[f32; 4]]) {
        let stride = fovea_core::kernel_abi::PROBE_INPUT_RECORDS as usize;
        assert!(
            records.len() <= stride,
            "a probe item has at most {stride} records"
        );
        let start = inputs.len();
        inputs.extend_from_slice(records);
        inputs.resize(start + stride, [0.0; 4]);
    }

    /// SplitMix64 (Steele, Lea, Flood 2014): a small deterministic generator of test inputs.
    #[derive(Clone, Debug)]
    pub struct Rng(pub u64);

    impl Rng {
        pub fn u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        pub fn u32(&mut self) -> u32 {
            (self.u64() >> 32) as u32
        }
        /// Uniform in [0, 1).
        pub fn f(&mut self) -> f32 {
            (self.u32() >> 8) as f32 * (1.0 / 16_777_216.0)
        }
        /// Uniform in [0, 1) in double precision.
        pub fn f64(&mut self) -> f64 {
            (self.u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
        }
        pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.f()
        }
        /// Uniform integer in `0..n`.
        pub fn below(&mut self, n: u32) -> u32 {
            ((u64::from(self.u32()) * u64::from(n)) >> 32) as u32
        }
        /// Log-uniform in `[lo, hi]` (both positive).
        pub fn log_uniform(&mut self, lo: f32, hi: f32) -> f32 {
            let (a, b) = (f64::from(lo).ln(), f64::from(hi).ln());
            (a + (b - a) * self.f64()).exp() as f32
        }
        /// Random sign.
        pub fn sign(&mut self) -> f32 {
            if self.u32() & 1 == 0 {
                1.0
            } else {
                -1.0
            }
        }
        /// A uniform unit vector.
        pub fn dir(&mut self) -> Vec3 {
            let z = self.range(-1.0, 1.0);
            let phi = self.range(0.0, std::f32::consts::TAU);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        }
        /// A local-frame direction whose cosine is adversarial: exactly 0 or 1, log-uniform down to
        /// 1e-7 (either sign: below the horizon too), or uniform; sometimes scaled to a non-unit length
        /// (1e-6 .. 1e6) or exactly zero.
        pub fn adversarial_dir(&mut self) -> Vec3 {
            let z = match self.below(10) {
                0 => 0.0,
                1 => 1.0,
                2 => self.log_uniform(1e-7, 1e-2),
                3 => -self.log_uniform(1e-7, 1e-2),
                4 => -self.f(),
                5 => 1.0 - self.log_uniform(1e-7, 1e-3),
                _ => self.f(),
            };
            let phi = match self.below(8) {
                0 => 0.0,
                1 => std::f32::consts::FRAC_PI_2,
                _ => self.range(0.0, std::f32::consts::TAU),
            };
            let r = (1.0 - z * z).max(0.0).sqrt();
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            match self.below(12) {
                0 => d * self.log_uniform(1e-6, 1e6),
                1 if self.below(8) == 0 => Vec3::ZERO,
                _ => d,
            }
        }
        /// A parameter in [0, 1]: exactly 0 or 1, within 1e-7 of them, or uniform.
        pub fn unit_param(&mut self) -> f32 {
            match self.below(8) {
                0 | 1 => 0.0,
                2 | 3 => 1.0,
                4 => self.log_uniform(1e-7, 1e-3),
                5 => 1.0 - self.log_uniform(1e-7, 1e-3),
                _ => self.f(),
            }
        }
        /// A magnitude of random decade in `[10^lo, 10^hi]` with random sign, sometimes exactly 0.
        pub fn wide(&mut self, lo: f32, hi: f32) -> f32 {
            if self.below(32) == 0 {
                return 0.0;
            }
            self.sign() * self.log_uniform(10f32.powf(lo), 10f32.powf(hi))
        }
    }

    /// A scene of the given vertices, triangles and per-triangle materials, without normals or
    /// texture coordinates.
    pub fn loaded_scene(
        positions: Vec<[f32; 3]>,
        triangles: Vec<[u32; 3]>,
        triangle_materials: Vec<u32>,
        materials: Vec<Material>,
    ) -> LoadedScene {
        let names = vec![String::new(); materials.len()];
        LoadedScene {
            positions,
            triangles,
            triangle_materials,
            materials,
            material_names: names,
            ..Default::default()
        }
    }

    /// The square `[-1, 1]²` at z = 0, facing +z, of one `material`, with texture coordinates over it
    /// (u along +x, v along −y: down the image, as glTF's) and no texture yet: set `textures` to what the material names.
    pub fn textured_quad(material: Material) -> LoadedScene {
        let mut s = loaded_scene(
            vec![
                [-1.0, -1.0, 0.0],
                [1.0, -1.0, 0.0],
                [1.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            vec![0, 0],
            vec![material],
        );
        s.uvs = vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
        s
    }

    /// Packs a loaded scene with the default BVH options.
    pub fn pack(scene: LoadedScene, environment: &Environment) -> PackedScene {
        pack_scene(scene, environment, &BvhBuildOptions::default())
    }

    /// An icosphere of radius `r` around `centre`: the icosahedron subdivided `levels` times, vertices
    /// shared between triangles (so edges are exactly shared), counter-clockwise seen from outside.
    pub fn icosphere(centre: Vec3, r: f32, levels: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v: Vec<[f64; 3]> = vec![
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
        ];
        let norm = |p: [f64; 3]| {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            [p[0] / l, p[1] / l, p[2] / l]
        };
        for p in &mut v {
            *p = norm(*p);
        }
        let mut f: Vec<[u32; 3]> = fovea_scene::procedural::ICOSAHEDRON_FACES.to_vec();
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut next = Vec::with_capacity(f.len() * 4);
            let mut midpoint = |a: u32, b: u32, v: &mut Vec<[f64; 3]>| -> u32 {
                let key = (a.min(b), a.max(b));
                *mid.entry(key).or_insert_with(|| {
                    let (p, q) = (v[a as usize], v[b as usize]);
                    v.push(norm([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                    (v.len() - 1) as u32
                })
            };
            for t in &f {
                let ab = midpoint(t[0], t[1], &mut v);
                let bc = midpoint(t[1], t[2], &mut v);
                let ca = midpoint(t[2], t[0], &mut v);
                next.push([t[0], ab, ca]);
                next.push([t[1], bc, ab]);
                next.push([t[2], ca, bc]);
                next.push([ab, bc, ca]);
            }
            f = next;
        }
        let c = centre.as_dvec3();
        let positions = v
            .iter()
            .map(|p| {
                [
                    (c.x + f64::from(r) * p[0]) as f32,
                    (c.y + f64::from(r) * p[1]) as f32,
                    (c.z + f64::from(r) * p[2]) as f32,
                ]
            })
            .collect();
        (positions, f)
    }

    /// Relative mean squared error `mean((x - ref)² / (ref² + eps))` over the luminance of two images.
    pub fn rel_mse(image: &[[f32; 4]], reference: &[[f32; 4]], eps: f64) -> f64 {
        assert_eq!(image.len(), reference.len());
        let lum = |p: &[f32; 4]| {
            0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
        };
        let mut sum = 0.0;
        for (a, b) in image.iter().zip(reference) {
            let (x, r) = (lum(a), lum(b));
            sum += (x - r) * (x - r) / (r * r + eps);
        }
        sum / image.len() as f64
    }

    /// The `q`-quantile (0..1) of `values` (sorted in place; nearest rank).
    pub fn quantile(values: &mut [f32], q: f64) -> f32 {
        if values.is_empty() {
            return 0.0;
        }
        values.sort_unstable_by(|a, b| a.total_cmp(b));
        let i = ((values.len() as f64 - 1.0) * q).round() as usize;
        values[i.min(values.len() - 1)]
    }
}
