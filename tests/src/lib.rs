//! Shared helpers for the end-to-end tests in `tests/tests/`.
use std::path::{Path, PathBuf};

use fovea_core::camera::Camera;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::integrator::{FrameParams, IntegratorSettings};
use fovea_cpu::{FrameImage, RenderStats};
use fovea_scene::bvh::BvhBuildOptions;
use fovea_scene::environment::Environment;
use fovea_scene::mesh::{load_scene, LoadOptions};
use fovea_scene::pack::{pack_scene, PackedScene};
use glam::Vec3;

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The shared scene folder next to the repository (`../shared/scenes`).
pub fn shared_scenes() -> PathBuf {
    repo_root().join("../shared/scenes")
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
    let loaded = load_scene(path, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("loading {}: {e}", path.display()));
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

/// The 8-bit sRGB RGB bytes of packed RGBA8 pixels (core's `tonemap_to_rgba8` layout).
pub fn rgba8_to_rgb8(pixels: &[u32]) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| [*p as u8, (*p >> 8) as u8, (*p >> 16) as u8])
        .collect()
}

/// A validating Vulkan context on the default device, or `None` (the caller skips its test with a message)
/// where there is no Vulkan loader or device and `CI` is not `true`; under `CI=true` a missing device fails.
pub fn vulkan_context_or_skip(what: &str) -> Option<fovea_vulkan::VulkanContext> {
    use fovea_vulkan::{ContextOptions, VulkanContext, VulkanError};
    std::env::set_var("FOVEA_VULKAN_VALIDATION", "1");
    let options = ContextOptions {
        device_index: None,
        validation: fovea_vulkan::validation_requested(),
    };
    match VulkanContext::new(&options) {
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
