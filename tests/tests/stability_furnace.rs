//! Furnace scene: a closed convex sphere (a level-4 icosphere, 5120 flat facets) under a constant
//! environment of radiance 1, rendered on the CPU and on the Vulkan device.
//!
//! For a convex object every path from the camera hits it at most once and then escapes (no facet sees
//! another), so a pixel's radiance is exactly the directional albedo `a(wo) = ∫ f(wo, wi) cos θi dωi`
//! of its material towards the camera (times the environment's 1), and the background is 1.
//!
//! **Which material.** Disney's diffuse lobe is not Lambertian: its retro-reflective Fresnel factors
//! (`F_D90 = 0.5 + 2 r cos² θd`) make the albedo of a white diffuse material depend on the angle (the
//! test prints it), and even `specular = 0` keeps the Schlick grazing term of the specular lobe. So two
//! materials:
//! - **white conductor, roughness 0** (`metallic = 1`, `base_color = 1`): `F ≡ 1` and GGX at the minimum
//!   alpha (1e-4) is a mirror whose masking is 1 except within 1e-4 of grazing, so `a(wo) = 1` and the
//!   whole image must be uniformly 1 within 1 %. This exercises next-event estimation of the environment,
//!   BSDF sampling of a near-delta lobe and their MIS weights (the delta-like lobe must take all the
//!   weight).
//! - **white Disney diffuse** (`metallic = 0`, `roughness = 1`, `specular = 0`): the expected value of a
//!   pixel is `a(cos θo)` of its facet, computed here by quadrature of `eval` (f64 sum over a 512 × 512
//!   cosine-weighted grid); the mean over the sphere's interior pixels must match within 1 %.
//! - **white Lambertian diffuse** (the same with `MATERIAL_LAMBERTIAN`): the quadrature albedo is 1 at
//!   every angle, and so must the image's mean be, within 1 %.
//! - **clear glass** (`transmission = 1`, `ior = 1.5`, roughness 0: the rough dielectric of
//!   `fovea_core::bsdf::dielectric` at alpha 1e-4): light is split, refracted and reflected inside the
//!   sphere (here paths do meet the object twice) but never absorbed, so the image must again be
//!   uniformly 1 within 1 %, like the conductor's.
//!
//! And one absorbing glass cube (Beer–Lambert, `absorbing_cube`), against its closed-form radiance.
use std::time::Instant;

use fovea_core::bsdf::DisneyParams;
use fovea_core::bvh::closest_hit;
use fovea_core::camera::Camera;
use fovea_core::foveation::fill::FILL_BILINEAR;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::glam::{Vec2, Vec3};
use fovea_core::integrator::FrameParams;
use fovea_core::scene::Material;
use fovea_scene::environment::Environment;
use fovea_scene::pack::PackedScene;
use fovea_tests::stability::{icosphere, loaded_scene, pack, pick};
use rayon::prelude::*;

const W: u32 = 64;
const H: u32 = 64;

struct Furnace {
    name: &'static str,
    material: Material,
    /// `None`: the expected radiance is 1 everywhere.
    albedo_table: Option<Vec<f64>>,
    /// Largest error allowed of a background or silhouette pixel.
    edge_tolerance: f64,
}

fn conductor() -> Material {
    Material {
        base_color: [1.0, 1.0, 1.0, 1.0],
        metallic: 1.0,
        roughness: 0.0,
        ..Default::default()
    }
}

fn diffuse() -> Material {
    Material {
        base_color: [1.0, 1.0, 1.0, 1.0],
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        ..Default::default()
    }
}

/// [`diffuse`] with a Lambertian diffuse lobe (`MATERIAL_LAMBERTIAN`, as `--mtl-diffuse lambert` gives
/// purely diffuse OBJ materials): albedo exactly 1 from every direction.
fn lambertian() -> Material {
    Material {
        flags: fovea_core::scene::MATERIAL_LAMBERTIAN,
        ..diffuse()
    }
}

/// Clear glass: a smooth dielectric of index 1.5 with a white tint, nothing else. A path that enters
/// the sphere leaves it again, every interface splits it by Fresnel and refracts or reflects it without
/// loss (the 1/η² of radiance entering is undone leaving), so every pixel is 1.
fn glass() -> Material {
    Material {
        base_color: [1.0, 1.0, 1.0, 1.0],
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        ..Default::default()
    }
}

fn params(m: &Material) -> DisneyParams {
    fovea_core::material::material_params(m)
}

/// Entries of the albedo table: `cos θo = i / (TABLE - 1)`.
const TABLE: usize = 65;

/// Directional albedo (luminance) of `m` at `TABLE` values of cos θo, by a cosine-weighted 512 × 512
/// midpoint grid: `a = π · mean f(wo, wi)` with `wi` uniform in the projected disk.
fn albedo_table(m: &Material) -> Vec<f64> {
    let p = params(m);
    let n = 512usize;
    (0..TABLE)
        .into_par_iter()
        .map(|i| {
            let c = (i as f64 / (TABLE - 1) as f64).max(1e-4);
            let wo = Vec3::new((1.0 - c * c).sqrt() as f32, 0.0, c as f32);
            let mut sum = 0.0f64;
            for a in 0..n {
                let r2 = (a as f64 + 0.5) / n as f64;
                let cos_i = (1.0 - r2).sqrt();
                let sin_i = r2.sqrt();
                for b in 0..n {
                    let phi = (b as f64 + 0.5) / n as f64 * std::f64::consts::TAU;
                    let wi = Vec3::new(
                        (sin_i * phi.cos()) as f32,
                        (sin_i * phi.sin()) as f32,
                        cos_i as f32,
                    );
                    let f = p.eval(wo, wi);
                    sum +=
                        0.2126 * f64::from(f.x) + 0.7152 * f64::from(f.y) + 0.0722 * f64::from(f.z);
                }
            }
            std::f64::consts::PI * sum / (n * n) as f64
        })
        .collect()
}

fn lookup(table: &[f64], cos_o: f32) -> f64 {
    let x = f64::from(cos_o.clamp(0.0, 1.0)) * (TABLE - 1) as f64;
    let i = (x.floor() as usize).min(TABLE - 2);
    let t = x - i as f64;
    table[i] * (1.0 - t) + table[i + 1] * t
}

fn furnace_scene(material: Material) -> PackedScene {
    let (p, t) = icosphere(Vec3::ZERO, 1.0, 4);
    let n = t.len();
    pack(
        loaded_scene(p, t, vec![0; n], vec![material]),
        &Environment::Constant([1.0, 1.0, 1.0]),
    )
}

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 0.3, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        45f32.to_radians(),
        W as f32 / H as f32,
    )
}

/// Paths of up to 1000 bounces, so that the light the glass sphere keeps inside still finds its way out:
/// light entering near the rim meets the inside close to the critical angle, and the flat facets turn
/// some of it past it, where total internal reflection traps it for many bounces. Measured on the CPU
/// at 64 spp: with 16 bounces 10 % of the sphere's pixels lost at least one sample's light (mean
/// -0.4 %), with 64 bounces 7 % (-0.2 %), with 1000 fewer than 1 %. The opaque spheres' paths end after
/// one bounce either way.
fn frame(spp: u32) -> FrameParams {
    let mut frame = fovea_tests::frame_params(camera(), FoveationParams::uniform(spp), W, H, 11);
    frame.integrator.max_bounces = 1000;
    frame
}

/// Per pixel: `Some(expected luminance)` for pixels whose centre and four corners all see the sphere
/// (interior pixels), `None` otherwise.
fn expected(scene: &PackedScene, albedo: Option<&[f64]>) -> Vec<Option<f64>> {
    let view = scene.view();
    let cam = camera();
    let mut out = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let mut inside = true;
            let mut centre_cos = 1.0;
            for (k, (dx, dy)) in [
                (0.5f32, 0.5f32),
                (0.0, 0.0),
                (1.0, 0.0),
                (0.0, 1.0),
                (1.0, 1.0),
            ]
            .into_iter()
            .enumerate()
            {
                let ray = cam.generate_ray(Vec2::new(x as f32 + dx, y as f32 + dy), W, H);
                let hit = closest_hit(&view, &ray, f32::INFINITY);
                if !hit.is_hit() {
                    inside = false;
                    break;
                }
                if k == 0 {
                    let t = scene.triangle(hit.triangle as usize);
                    let v = |a: glam::Vec4| a.truncate();
                    let n = (v(t.v1) - v(t.v0)).cross(v(t.v2) - v(t.v0)).normalize();
                    centre_cos = n.dot(-ray.direction.normalize()).abs();
                }
            }
            out.push(if inside {
                Some(albedo.map_or(1.0, |a| lookup(a, centre_cos)))
            } else {
                None
            });
        }
    }
    out
}

/// Figures of one render.
struct Figures {
    sphere_pixels: usize,
    /// Mean over sphere pixels of rendered / expected, minus 1.
    mean_error: f64,
    /// Largest |rendered / expected - 1| of a pixel (sphere) and of the background (`1` expected).
    max_pixel_error: f64,
    max_background_error: f64,
    /// Largest |rendered / expected - 1| of a 4×4-pixel tile of interior sphere pixels.
    max_tile_error: f64,
    /// Fraction of sphere pixels within 1 % of their expected value.
    within_1_percent: f64,
    non_finite: usize,
}

fn measure(pixels: &[[f32; 4]], expected: &[Option<f64>]) -> Figures {
    let lum = |p: &[f32; 4]| {
        0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
    };
    let mut f = Figures {
        sphere_pixels: 0,
        mean_error: 0.0,
        max_pixel_error: 0.0,
        max_background_error: 0.0,
        max_tile_error: 0.0,
        within_1_percent: 0.0,
        non_finite: 0,
    };
    let mut within = 0usize;
    let (mut sum, mut sum_expected) = (0.0, 0.0);
    for (p, e) in pixels.iter().zip(expected) {
        if !p.iter().all(|c| c.is_finite()) {
            f.non_finite += 1;
            continue;
        }
        let l = lum(p);
        if let Some(e) = e {
            f.sphere_pixels += 1;
            sum += l;
            sum_expected += e;
            let err = (l / e - 1.0).abs();
            f.max_pixel_error = f.max_pixel_error.max(err);
            if err <= 0.01 {
                within += 1;
            }
        }
        // Every pixel that is not interior mixes sphere and background; for the conductor both are 1.
    }
    for (p, e) in pixels.iter().zip(expected) {
        if e.is_none() {
            f.max_background_error = f.max_background_error.max((lum(p) - 1.0).abs());
        }
    }
    f.mean_error = sum / sum_expected - 1.0;
    f.within_1_percent = within as f64 / f.sphere_pixels.max(1) as f64;
    for ty in 0..H / 4 {
        for tx in 0..W / 4 {
            let (mut l, mut e, mut interior) = (0.0, 0.0, true);
            for y in ty * 4..ty * 4 + 4 {
                for x in tx * 4..tx * 4 + 4 {
                    let i = (y * W + x) as usize;
                    match expected[i] {
                        Some(v) => {
                            l += lum(&pixels[i]);
                            e += v;
                        }
                        None => interior = false,
                    }
                }
            }
            if interior {
                f.max_tile_error = f.max_tile_error.max((l / e - 1.0).abs());
            }
        }
    }
    f
}

fn furnaces() -> Vec<Furnace> {
    vec![
        Furnace {
            name: "white conductor, roughness 0",
            material: conductor(),
            albedo_table: None,
            edge_tolerance: 0.01,
        },
        Furnace {
            name: "white Disney diffuse, roughness 1",
            material: diffuse(),
            albedo_table: Some(albedo_table(&diffuse())),
            edge_tolerance: 0.01,
        },
        Furnace {
            name: "white Lambertian diffuse",
            material: lambertian(),
            albedo_table: Some(lambertian_albedo()),
            edge_tolerance: 0.01,
        },
        Furnace {
            name: "clear glass sphere, ior 1.5",
            material: glass(),
            albedo_table: None,
            // Silhouette pixels see the rim at grazing incidence, where light is trapped longest (see
            // `frame`): two of their 64 samples may still be inside after 1000 bounces (measured 0.031).
            edge_tolerance: 0.05,
        },
    ]
}

/// The quadrature albedo table of [`lambertian`], checked to be 1 at every angle (Lambert's BRDF is
/// `1 / π` exactly, and the quadrature's error is far below 1e-4).
fn lambertian_albedo() -> Vec<f64> {
    let table = albedo_table(&lambertian());
    for (i, a) in table.iter().enumerate() {
        assert!(
            (a - 1.0).abs() < 1e-4,
            "cos θo {}: albedo {a}",
            i as f64 / (TABLE - 1) as f64
        );
    }
    table
}

fn check(backend: &str, furnace: &Furnace, f: &Figures, spp: u32, seconds: f64) {
    eprintln!(
        "{backend}: {:<34} {W}x{H} x {spp} spp: {} sphere pixels, mean error {:+.5}, max 4x4 tile \
         error {:.4}, {:.2} % of pixels within 1 % (max {:.4}), max background/edge error {:.4}, {} \
         non-finite, {seconds:.2} s",
        furnace.name,
        f.sphere_pixels,
        f.mean_error,
        f.max_tile_error,
        100.0 * f.within_1_percent,
        f.max_pixel_error,
        f.max_background_error,
        f.non_finite
    );
    assert_eq!(f.non_finite, 0);
    assert!(f.sphere_pixels > (W * H / 3) as usize);
    assert!(
        f.mean_error.abs() < 0.01,
        "{backend} {}: mean error {}",
        furnace.name,
        f.mean_error
    );
    if furnace.albedo_table.is_none() {
        // Uniform within 1 %: every 4×4 tile of the sphere, 99 % of its pixels, and the background and
        // silhouette pixels (which mix sphere and sky, both 1). Single pixels may lose one sample's worth
        // (1/spp): a VNDF sample from the far tail of the GGX lobe (u → 1) gets an MIS weight of about 0
        // against the environment's uniform density, and its share is carried, unbiased, by the rare
        // light samples that land in that tail; that is variance, not bias (the mean is within 1e-4).
        assert!(f.max_tile_error < 0.01, "{}", f.max_tile_error);
        assert!(f.within_1_percent > 0.99, "{}", f.within_1_percent);
        assert!(
            f.max_background_error < furnace.edge_tolerance,
            "{}",
            f.max_background_error
        );
    }
}

#[test]
fn furnace_sphere_is_uniform_on_cpu() {
    let spp = pick(64u32, 1024);
    for furnace in furnaces() {
        let start = Instant::now();
        let scene = furnace_scene(furnace.material);
        let exp = expected(&scene, furnace.albedo_table.as_deref());
        if let Some(t) = &furnace.albedo_table {
            eprintln!(
                "{}: albedo {:.4} head-on, {:.4} at cos 0.5, {:.4} at cos 0.1",
                furnace.name,
                lookup(t, 1.0),
                lookup(t, 0.5),
                lookup(t, 0.1)
            );
        }
        let (image, _) = fovea_tests::render(&scene, &frame(spp));
        let f = measure(&image.pixels, &exp);
        check("CPU", &furnace, &f, spp, start.elapsed().as_secs_f64());
    }
}

#[test]
fn furnace_sphere_is_uniform_on_vulkan() {
    let Some(mut ctx) = fovea_tests::vulkan_context_or_skip("the Vulkan furnace test") else {
        return;
    };
    let log = ctx.validation_log();
    let device = ctx.device_name().to_string();
    let spp = pick(64u32, 1024);
    for furnace in furnaces() {
        let start = Instant::now();
        let scene = furnace_scene(furnace.material);
        let exp = expected(&scene, furnace.albedo_table.as_deref());
        let gpu_scene = ctx.upload_scene(&scene).expect("upload");
        let (gpu, _) = ctx
            .render_frame(&gpu_scene, &frame(spp), FILL_BILINEAR, 0.0, true)
            .unwrap_or_else(|e| panic!("{}: {e}", furnace.name));
        let hdr = gpu.hdr.expect("HDR requested");
        let f = measure(&hdr.pixels, &exp);
        check(&device, &furnace, &f, spp, start.elapsed().as_secs_f64());
    }
    drop(ctx);
    let messages = log.lock().unwrap().clone();
    assert!(messages.is_empty(), "validation messages: {messages:#?}");
}

/// Beer–Lambert absorption (`Material::absorption`, glTF `KHR_materials_volume`): a smooth glass cube
/// of side `L = 1` and index 1.5 whose inside absorbs `σ = (0, 0.5, 2)` per unit, seen head-on under
/// the constant environment 1 through a narrow field of view. Between its two parallel faces light
/// bounces at normal incidence with reflectance `R = 0.04`; the radiance `X` leaving a face from the
/// inside solves `X = e^{−σL} ((1 − R) + R X)`, and the pixel sees `R + (1 − R) X`:
/// `R + (1 − R)² e^{−σL} / (1 − R e^{−σL})`. Red does not absorb and must stay 1 (energy is kept);
/// green and blue must match within 1 %.
fn absorbing_cube() -> (PackedScene, Camera, [f64; 3]) {
    let sigma = [0.0f32, 0.5, 2.0];
    let material = Material {
        base_color: [1.0, 1.0, 1.0, 1.0],
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        absorption: sigma,
        ..Default::default()
    };
    // The unit cube around the origin, faces counter-clockwise seen from outside.
    let p: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 != 0 { 0.5 } else { -0.5 },
                if i & 2 != 0 { 0.5 } else { -0.5 },
                if i & 4 != 0 { 0.5 } else { -0.5 },
            ]
        })
        .collect();
    let quads = [
        [0, 4, 6, 2], // −x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // −y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // −z
        [4, 5, 7, 6], // +z
    ];
    let t: Vec<[u32; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let n = t.len();
    let scene = pack(
        loaded_scene(p, t, vec![0; n], vec![material]),
        &Environment::Constant([1.0, 1.0, 1.0]),
    );
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.0, 10.0),
        Vec3::ZERO,
        Vec3::Y,
        2f32.to_radians(),
        1.0,
    );
    let r = 0.04f64;
    let expected = sigma.map(|s| {
        let e = (-f64::from(s)).exp();
        r + (1.0 - r) * (1.0 - r) * e / (1.0 - r * e)
    });
    (scene, camera, expected)
}

fn check_absorption(backend: &str, pixels: &[[f32; 4]], size: u32, expected: [f64; 3]) {
    let mut sum = [0.0f64; 3];
    for p in pixels {
        for c in 0..3 {
            sum[c] += f64::from(p[c]);
        }
    }
    let mean = sum.map(|s| s / pixels.len() as f64);
    eprintln!(
        "{backend}: absorbing glass cube {size}x{size}: mean RGB {mean:.4?}, Beer-Lambert {expected:.4?}"
    );
    for c in 0..3 {
        assert!(
            (mean[c] / expected[c] - 1.0).abs() < 0.01,
            "{backend} channel {c}: {} against {}",
            mean[c],
            expected[c]
        );
    }
    // The absorption is visible: blue keeps less than half of what red keeps.
    assert!(mean[2] < 0.5 * mean[0]);
}

fn absorption_frame(camera: Camera, spp: u32) -> FrameParams {
    let mut frame = fovea_tests::frame_params(camera, FoveationParams::uniform(spp), 16, 16, 5);
    frame.integrator.max_bounces = 64;
    frame
}

#[test]
fn absorbing_glass_matches_beer_lambert_on_cpu() {
    let (scene, camera, expected) = absorbing_cube();
    let (image, _) = fovea_tests::render(&scene, &absorption_frame(camera, pick(4096, 16384)));
    check_absorption("CPU", &image.pixels, 16, expected);
}

#[test]
fn absorbing_glass_matches_beer_lambert_on_vulkan() {
    let Some(mut ctx) = fovea_tests::vulkan_context_or_skip("the Vulkan absorption test") else {
        return;
    };
    let (scene, camera, expected) = absorbing_cube();
    let gpu_scene = ctx.upload_scene(&scene).expect("upload");
    let (gpu, _) = ctx
        .render_frame(
            &gpu_scene,
            &absorption_frame(camera, pick(4096, 16384)),
            FILL_BILINEAR,
            0.0,
            true,
        )
        .expect("render");
    let device = ctx.device_name().to_string();
    check_absorption(
        &device,
        &gpu.hdr.expect("HDR requested").pixels,
        16,
        expected,
    );
}

/// Absorption needs a volume entered through its front: an open, absorbing glass pane seen from behind
/// (its back face towards the camera) is crossed leaving "inside" for outside, so nothing is absorbed,
/// and the image is bit for bit the clear pane's. (A rule that absorbed on every back-face hit darkened
/// it by `exp(−σ d)` over the camera's distance.)
#[test]
fn an_open_pane_seen_from_behind_absorbs_nothing() {
    let render_pane = |sigma: f32| {
        let material = Material {
            base_color: [1.0, 1.0, 1.0, 1.0],
            roughness: 0.2,
            transmission: 1.0,
            ior: 1.5,
            absorption: [sigma; 3],
            ..Default::default()
        };
        // A unit square at z = 0 facing +z; the camera looks at it from −z.
        let p = vec![
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ];
        let t = vec![[0, 1, 2], [0, 2, 3]];
        let scene = pack(
            loaded_scene(p, t, vec![0; 2], vec![material]),
            &Environment::Constant([1.0, 1.0, 1.0]),
        );
        let camera = Camera::look_at(Vec3::new(0.0, 0.0, -4.0), Vec3::ZERO, Vec3::Y, 0.4, 1.0);
        let frame = fovea_tests::frame_params(camera, FoveationParams::uniform(16), 16, 16, 3);
        let (image, _) = fovea_tests::render(&scene, &frame);
        image.pixels
    };
    let clear = render_pane(0.0);
    let absorbing = render_pane(2.0);
    assert!(clear.iter().any(|p| p[0] > 0.1));
    assert_eq!(clear, absorbing);
}
