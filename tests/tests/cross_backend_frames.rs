//! Cross-backend frame diffs: every small scene the repository bundles (`assets/`) rendered with the same camera,
//! seed, gaze and settings on the CPU host and on the Vulkan device (lavapipe in CI), compared in linear
//! HDR (fraction of pixels within 1e-3 relative, max abs diff) and with FLIP (nv-flip, 67.02 ppd) on the
//! tone-mapped images. Prints a per-scene table (`-- --nocapture`).
//!
//! Each scene is also rendered with the scene's specialised path (only the features it uses: the CPU's
//! monomorphised integrator, the GPU's specialization constant) and with the general one (every
//! feature, `--no-specialize`); on each backend the two must be bit-identical.
//!
//! Without a Vulkan device the test prints a note and passes, except with `CI=true`. The validation
//! layer is on and must stay silent.
use std::path::PathBuf;

use fovea_core::camera::Camera;
use fovea_core::foveation::fill::FILL_BILINEAR;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::post::tonemap::tonemap_to_rgba8;
use fovea_scene::environment::Environment;
use fovea_scene::mesh::{LoadOptions, MtlDiffuse};
use fovea_tests::*;
use glam::Vec3;

const W: u32 = 96;
const H: u32 = 72;
/// Hardware traversal against the CPU: fraction of pixels within 1e-3 and mean FLIP (see the assertions).
/// Measured: 100 % on every scene but the Lost Empire crop: 99.32 % (mean FLIP 3.7e-4) when a block's
/// samples spread over the whole block; since they land on pixels (issue 50), 98.52 % with seed 7
/// (FLIP 5.8e-4), and 99.06 % and 99.97 % with seeds 8 and 9. Which rare grazing path flips is luck of
/// where the samples land, and one flipped sample of a 4 × 4 periphery block (1 sample here) spreads
/// over the block's fill.
const HARDWARE_MIN_WITHIN: f64 = 0.98;
const HARDWARE_MAX_FLIP: f64 = 1e-3;

/// The paper's three regions around the image centre, with few samples (4 / 2 / 1 on 1×1 / 2×2 / 4×4
/// blocks) to keep lavapipe fast.
fn foveation() -> FoveationParams {
    let mut f = FoveationParams::paper([W as f32 * 0.5, H as f32 * 0.5], 14.0, 30.0);
    f.spp = [4, 2, 1, 0];
    f
}

/// How a scene's camera is chosen.
enum View {
    /// The file's camera, else framing the bounds from +z.
    FileOrFrame,
    /// McGuire's Cornell box front view.
    Cornell,
    /// From the `+z` side of the bounds, looking along `-z` at their centre. (SOURCE.md says the
    /// original view looks along +Z; from the -z side this scene renders exactly black here, so the
    /// file's axes evidently differ from that note.)
    AlongMinusZ,
    /// From inside the bounds (a closed box), at 80 % of the way to the `+z` wall, looking along `-z`.
    Inside,
    /// The bundled Lost Empire view, narrowed to its central 320 × 180 window of 1920 × 1080.
    LostEmpireCrop,
}

struct SceneCase {
    name: &'static str,
    path: PathBuf,
    environment: Environment,
    view: View,
    /// How purely diffuse MTL materials reflect (Lambertian for one Cornell box, so that both backends
    /// run that lobe too).
    mtl_diffuse: MtlDiffuse,
    /// `TEXTURE_LOD_*` of the frame (the block-footprint mip levels for the textured generated scenes,
    /// so that both backends run the trilinear lookups too).
    texture_lod: u32,
}

fn cases() -> Vec<SceneCase> {
    let s = bundled_scenes();
    let case = |name, rel: &str, environment, view| SceneCase {
        name,
        path: s.join(rel),
        environment,
        view,
        mtl_diffuse: MtlDiffuse::Disney,
        texture_lod: fovea_core::integrator::path::TEXTURE_LOD_OFF,
    };
    vec![
        case(
            "cornell_box_gltf",
            "cornell_box_gltf/cornell_box.gltf",
            Environment::None,
            View::FileOrFrame,
        ),
        case(
            "mcguire Original",
            "cornell_box/CornellBox-Original.obj",
            Environment::None,
            View::Cornell,
        ),
        SceneCase {
            mtl_diffuse: MtlDiffuse::Lambert,
            ..case(
                "mcguire Original, Lambertian",
                "cornell_box/CornellBox-Original.obj",
                Environment::None,
                View::Cornell,
            )
        },
        case(
            "mcguire Mirror",
            "cornell_box/CornellBox-Mirror.obj",
            Environment::None,
            View::Cornell,
        ),
        case(
            "mcguire Sphere",
            "cornell_box/CornellBox-Sphere.obj",
            Environment::None,
            View::Cornell,
        ),
        case(
            "cornell_stiff",
            "cornell_stiff/cornell_stiff.gltf",
            Environment::None,
            View::FileOrFrame,
        ),
        case(
            "dark_cornell_pema99",
            "dark_cornell_pema99/DarkCornell.glb",
            Environment::None,
            View::Inside,
        ),
        case(
            "emissive_triangle_kajiya",
            "emissive_triangle_kajiya/triangle.glb",
            Environment::None,
            View::FileOrFrame,
        ),
        case(
            "veach_mis_pema99",
            "veach_mis_pema99/VeachMIS.glb",
            Environment::None,
            View::AlongMinusZ,
        ),
        SceneCase {
            path: fovea_tests::repo_root().join("assets/pbr_extensions/pbr_extensions.gltf"),
            texture_lod: fovea_core::integrator::path::TEXTURE_LOD_BLOCK,
            ..case(
                "pbr_extensions, block LOD",
                "",
                Environment::None,
                View::FileOrFrame,
            )
        },
        SceneCase {
            path: fovea_tests::repo_root().join("assets/pbr_extensions/checker_floor.gltf"),
            texture_lod: fovea_core::integrator::path::TEXTURE_LOD_BLOCK,
            ..case(
                "checker_floor, block LOD",
                "",
                Environment::Constant([0.3, 0.4, 0.6]),
                View::FileOrFrame,
            )
        },
        case(
            "roughness_scale_kajiya",
            "roughness_scale_kajiya/scene.gltf",
            Environment::Constant([1.0, 1.0, 1.0]),
            View::FileOrFrame,
        ),
        case(
            "lost_empire crop",
            "lost_empire/lost_empire.obj",
            Environment::Constant([1.0, 1.0, 1.0]),
            View::LostEmpireCrop,
        ),
    ]
}

fn camera(
    view: &View,
    packed: &fovea_scene::pack::PackedScene,
    desc: Option<&fovea_scene::mesh::CameraDesc>,
) -> Camera {
    let aspect = W as f32 / H as f32;
    match view {
        View::FileOrFrame => scene_camera(packed, desc, aspect),
        View::Cornell => cornell_camera(W, H),
        View::AlongMinusZ => {
            let (lo, hi) = (packed.bounds_min, packed.bounds_max);
            let centre = 0.5 * (lo + hi);
            let radius = 0.5 * (hi - lo).length();
            let fov = 45f32.to_radians();
            let distance = radius / (0.5 * fov).tan();
            Camera::look_at(centre + Vec3::Z * distance, centre, Vec3::Y, fov, aspect)
        }
        View::Inside => {
            let (lo, hi) = (packed.bounds_min, packed.bounds_max);
            let centre = 0.5 * (lo + hi);
            let eye = Vec3::new(centre.x, centre.y, centre.z + 0.8 * 0.5 * (hi.z - lo.z));
            Camera::look_at(eye, centre, Vec3::Y, 60f32.to_radians(), aspect)
        }
        View::LostEmpireCrop => {
            // The bundled view (60° vertical over 1080 rows); its central 180 rows span this angle.
            // 180 rows of the 1080p frame of `lost_empire_full_frame_renders_alike`.
            let fov = 2.0 * ((30f32.to_radians()).tan() * 180.0 / 1080.0).atan();
            lost_empire_camera(fov, aspect)
        }
    }
}

/// Per-scene figures.
struct Figures {
    within: f64,
    max_abs: f32,
    mean_flip: f64,
    cpu_mean: f32,
}

/// Per-pixel agreement (within 1e-3 relative or 1e-4 absolute on every channel) and mean FLIP of the
/// tone-mapped images, for a `width`×`height` frame.
fn compare(
    cpu: &[[f32; 4]],
    gpu: &[[f32; 4]],
    gpu_ldr: &[u32],
    width: u32,
    height: u32,
) -> Figures {
    let mut within = 0usize;
    let mut max_abs = 0f32;
    let mut sum = 0f64;
    for (a, b) in cpu.iter().zip(gpu) {
        let (ok, d) = fovea_tests::pixels_agree(a, b);
        max_abs = max_abs.max(d);
        sum += f64::from(a[0]) + f64::from(a[1]) + f64::from(a[2]);
        within += usize::from(ok);
    }
    let cpu_ldr: Vec<u32> = cpu
        .iter()
        .map(|p| tonemap_to_rgba8(Vec3::new(p[0], p[1], p[2]), 0.0))
        .collect();
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, &rgba8_to_rgb8(&cpu_ldr));
    let test = nv_flip::FlipImageRgb8::with_data(width, height, &rgba8_to_rgb8(gpu_ldr));
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec();
    let mean_flip = error.iter().map(|&e| f64::from(e)).sum::<f64>() / error.len() as f64;
    Figures {
        within: within as f64 / cpu.len() as f64,
        max_abs,
        mean_flip,
        cpu_mean: (sum / (3.0 * cpu.len() as f64)) as f32,
    }
}

#[test]
fn small_scenes_render_alike_on_cpu_and_vulkan() {
    small_scenes_render_alike(fovea_vulkan::Traversal::Software);
}

/// The same frames with the driver's acceleration structures (`--traversal hardware`) on the device.
#[test]
fn small_scenes_render_alike_with_hardware_traversal() {
    small_scenes_render_alike(fovea_vulkan::Traversal::Hardware);
}

/// Renders every small scene on the CPU and on the device with `traversal` and compares them.
fn small_scenes_render_alike(traversal: fovea_vulkan::Traversal) {
    let Some(mut ctx) = vulkan_context_with_or_skip("the Vulkan frame test", traversal) else {
        return;
    };
    let hardware = ctx.hardware_traversal();
    let log = ctx.validation_log();
    let device = ctx.device_description();
    let mut rows = Vec::new();
    for case in cases() {
        let start = std::time::Instant::now();
        let options = LoadOptions {
            mtl_diffuse: case.mtl_diffuse,
            ..LoadOptions::default()
        };
        let (packed, desc) = load_packed_with_camera_and(&case.path, &case.environment, &options);
        if case.mtl_diffuse == MtlDiffuse::Lambert {
            assert!(
                packed
                    .materials
                    .list
                    .iter()
                    .any(|m| m.flags & fovea_core::scene::MATERIAL_LAMBERTIAN != 0),
                "{}: no Lambertian material",
                case.name
            );
        }
        let cam = camera(&case.view, &packed, desc.as_ref());
        let mut frame = frame_params(cam, foveation(), W, H, 7);
        frame.integrator.texture_lod = case.texture_lod;
        let (cpu, _) = render(&packed, &frame);
        let features = packed.features();
        let specialised_view = packed.view().with_features(features);
        let (cpu_specialised, _) =
            fovea_cpu::render_frame(&specialised_view, &frame, FILL_BILINEAR, &|_| {});
        let mut scene = ctx.upload_scene(&packed).expect("upload");
        assert_eq!(
            scene.features, features,
            "{}: upload specialises",
            case.name
        );
        let (gpu, _) = ctx
            .render_frame(&scene, &frame, FILL_BILINEAR, 0.0, true)
            .unwrap_or_else(|e| panic!("{}: {e}", case.name));
        scene.features = fovea_core::scene::FeatureFlags::ALL;
        let (gpu_general, _) = ctx
            .render_frame(&scene, &frame, FILL_BILINEAR, 0.0, true)
            .unwrap_or_else(|e| panic!("{}: {e}", case.name));
        drop(scene);
        let hdr = gpu.hdr.as_ref().expect("HDR requested");
        let f = compare(&cpu.pixels, &hdr.pixels, gpu.rgba8.as_ref().unwrap(), W, H);
        let cpu_identical = cpu.pixels == cpu_specialised.pixels;
        let gpu_identical = gpu.hdr.as_ref().map(|i| &i.pixels)
            == gpu_general.hdr.as_ref().map(|i| &i.pixels)
            && gpu.rgba8 == gpu_general.rgba8;
        rows.push((
            case.name,
            f,
            start.elapsed().as_secs_f64(),
            features.0,
            cpu_identical && gpu_identical,
        ));
    }

    eprintln!(
        "\nCPU vs {device} ({} traversal), {W}x{H} foveated (4/2/1 spp), seed 7",
        if hardware { "hardware" } else { "software" }
    );
    eprintln!(
        "| {:<24} | {:>12} | {:>10} | {:>10} | {:>9} | {:>6} | {:>8} | {:>12} |",
        "scene", "within 1e-3", "max abs", "mean FLIP", "CPU mean", "s", "features", "spec==gen"
    );
    eprintln!(
        "|{:-<26}|{:-<14}|{:-<12}|{:-<12}|{:-<11}|{:-<8}|{:-<10}|{:-<14}|",
        "", "", "", "", "", "", "", ""
    );
    for (name, f, s, features, identical) in &rows {
        eprintln!(
            "| {:<24} | {:>11.4}% | {:>10.3e} | {:>10.3e} | {:>9.3e} | {:>6.2} | {:>#8x} | {:>12} |",
            name,
            100.0 * f.within,
            f.max_abs,
            f.mean_flip,
            f.cpu_mean,
            s,
            features,
            identical
        );
    }
    drop(ctx);
    let messages = log.lock().unwrap().clone();
    assert!(messages.is_empty(), "validation messages: {messages:#?}");
    for (name, f, _, _, identical) in &rows {
        assert!(f.cpu_mean > 0.0, "{name}: black image");
        assert!(
            *identical,
            "{name}: specialised and general renders differ (CPU or Vulkan)"
        );
        // Every scene, the Lost Empire crop included, measured 100 % within 1e-3 since core computes
        // sin, cos, atan2, exp and ln with its own polynomials (`math::transcendental`) instead of
        // `libm` on the CPU and GLSL.std.450 on the GPU (one ulp apart, which flipped a few paths:
        // the crop was 99.09-99.41 % before). The task's 99.9 % is asserted. Hardware traversal
        // finds the same triangles but computes hit distances and barycentrics its own way, so a path
        // that grazes an edge may go elsewhere: its bound is looser (measured figures in docs/architecture.md, "Hardware traversal").
        let (min_within, max_flip) = if hardware {
            (HARDWARE_MIN_WITHIN, HARDWARE_MAX_FLIP)
        } else {
            (0.999, 1e-3)
        };
        assert!(
            f.within >= min_within,
            "{name}: {:.4} % within",
            100.0 * f.within
        );
        assert!(f.mean_flip <= max_flip, "{name}: mean FLIP {}", f.mean_flip);
    }
}

/// The whole 1920×1080 Lost Empire frame as `fovea render` makes it by default (32/16/8 spp on 1/2/4
/// blocks, radii of the default display), the frame the crop above is cut from. Measured 99.98 % of
/// pixels within 1e-3 and mean FLIP 8.6e-6 (about 25 s on lavapipe, 2 s on the CPU with 2 threads).
/// Also prints the GPU's dispatch figures (chunks, idle invocations).
#[test]
fn lost_empire_full_frame_renders_alike() {
    let Some(mut ctx) = vulkan_context_or_skip("the full-frame Vulkan test") else {
        return;
    };
    let log = ctx.validation_log();
    let (w, h) = (1920u32, 1080u32);
    let path = bundled_scenes().join("lost_empire/lost_empire.obj");
    let packed = load_packed(&path, &Environment::Constant([1.0, 1.0, 1.0]));
    let cam = lost_empire_camera(60f32.to_radians(), w as f32 / h as f32);
    let frame = frame_params(cam, paper_foveation(w, h), w, h, 7);
    let (cpu, cpu_stats) = render(&packed, &frame);
    let upload = std::time::Instant::now();
    let scene = ctx.upload_scene(&packed).expect("upload");
    let upload_ms = upload.elapsed().as_secs_f64() * 1e3;
    let (gpu, gpu_stats) = ctx
        .render_frame(&scene, &frame, FILL_BILINEAR, 0.0, true)
        .expect("Vulkan render");
    drop(scene);
    let hdr = gpu.hdr.as_ref().expect("HDR requested");
    let f = compare(&cpu.pixels, &hdr.pixels, gpu.rgba8.as_ref().unwrap(), w, h);
    eprintln!(
        "Lost Empire {w}x{h} 32/16/8 ({} samples), CPU vs {}: {:.4} % within 1e-3, max abs {:.3e}, mean \
         FLIP {:.3e}; CPU {:.0} ms, GPU {:.0} ms ({} chunks, {} idle invocations, plan {:.1} ms, upload \
         {upload_ms:.0} ms)",
        gpu_stats.render.primary_samples,
        ctx.device_description(),
        100.0 * f.within,
        f.max_abs,
        f.mean_flip,
        cpu_stats.render_ms,
        gpu_stats.render.render_ms,
        gpu_stats.chunks,
        gpu_stats.idle_invocations,
        gpu_stats.plan_ms,
    );
    assert_eq!(
        gpu_stats.render.samples_per_region,
        cpu_stats.samples_per_region
    );
    drop(ctx);
    assert!(log.lock().unwrap().is_empty(), "validation messages");
    assert!(f.cpu_mean > 0.0, "black image");
    assert!(f.within >= 0.999, "{:.4} % within", 100.0 * f.within);
    assert!(f.mean_flip <= 1e-3, "mean FLIP {}", f.mean_flip);
}
