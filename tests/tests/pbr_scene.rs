//! The bundled glTF PBR-extension scene (`assets/pbr_extensions`, made by `scripts/make-pbr-scene.py`):
//! one test per extension of the loader's mapping (`fovea_scene::gltf_pbr`), the warnings for what fovea
//! does not render, and the unlit material's look. Its CPU/lavapipe agreement is a case of
//! `cross_backend_frames`.
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::scene::{Material, MATERIAL_LAMBERTIAN, MATERIAL_UNLIT};
use fovea_scene::environment::Environment;
use fovea_scene::gltf_pbr::specular_from_ior;
use fovea_scene::load_scene;
use fovea_scene::mesh::{LoadOptions, LoadedScene};
use glam::Vec3;

fn scene_path() -> std::path::PathBuf {
    fovea_tests::repo_root().join("assets/pbr_extensions/pbr_extensions.gltf")
}

fn load() -> LoadedScene {
    load_scene(&scene_path(), &LoadOptions::default()).expect("the bundled PBR scene loads")
}

fn material<'a>(scene: &'a LoadedScene, name: &str) -> &'a Material {
    let i = scene
        .material_names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no material {name:?}"));
    &scene.materials[i]
}

#[test]
fn khr_materials_transmission_makes_a_dielectric() {
    let m = *material(&load(), "glass");
    assert_eq!((m.transmission, m.ior), (1.0, 1.5));
    assert_eq!(m.roughness, 0.0);
}

#[test]
fn khr_materials_ior_sets_the_dielectric_reflectance() {
    let s = load();
    let f0 = (0.33f32 / 2.33).powi(2);
    assert!((material(&s, "ior").specular - f0 / 0.08).abs() < 1e-6);
    // ior 1.5 is Burley's default specular 0.5.
    assert!((material(&s, "glass").specular - 0.5).abs() < 1e-6);
}

#[test]
fn khr_materials_specular_scales_the_reflectance() {
    let s = load();
    let want = specular_from_ior(1.5, 0.6 * 1.0);
    assert!((material(&s, "specular").specular - want).abs() < 1e-6);
}

#[test]
fn khr_materials_clearcoat_sets_the_coat() {
    let m = *material(&load(), "clearcoat");
    assert_eq!(m.clearcoat, 1.0);
    assert!((m.clearcoat_gloss - 0.9).abs() < 1e-6);
}

#[test]
fn khr_materials_sheen_sets_the_sheen() {
    let m = *material(&load(), "sheen");
    assert!((m.sheen - 0.9).abs() < 1e-6);
    assert_eq!(m.sheen_tint, 0.0);
}

#[test]
fn khr_materials_anisotropy_sets_the_anisotropy() {
    let m = *material(&load(), "anisotropy");
    assert!((m.anisotropic - 0.8).abs() < 1e-6);
    assert_eq!(m.metallic, 1.0);
}

#[test]
fn khr_materials_emissive_strength_scales_the_emission() {
    let m = *material(&load(), "emissive_strength");
    assert_eq!(m.emission, [5.0, 3.0, 1.0, 0.0]);
}

/// KHR_texture_transform: the base colour texture's record carries T R S (scale 4, rotation 0.3); the
/// floor, which reads the same image untransformed, keeps its own record.
#[test]
fn khr_texture_transform_sets_the_coordinate_transform() {
    let s = load();
    let m = *material(&s, "texture_transform");
    let t = &s.textures[m.base_color_texture as usize];
    let (sin, cos) = 0.3f32.sin_cos();
    let want = [cos * 4.0, sin * 4.0, -sin * 4.0, cos * 4.0, 0.0, 0.0];
    let got = t.transform.expect("a transform");
    assert!(
        got.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6),
        "{got:?}"
    );
    let floor = *material(&s, "floor");
    assert_ne!(floor.base_color_texture, m.base_color_texture);
    assert_eq!(
        s.textures[floor.base_color_texture as usize].transform,
        None
    );
}

/// The materials that use no extension keep Burley's defaults (what they had before the mapping).
#[test]
fn materials_without_extensions_keep_the_defaults() {
    let m = *material(&load(), "texture_transform");
    let d = Material::default();
    assert_eq!(
        (m.specular, m.clearcoat, m.sheen, m.anisotropic),
        (d.specular, d.clearcoat, d.sheen, d.anisotropic)
    );
}

/// An extension fovea does not render is one warning naming it and its materials; the mapped ones
/// give none.
#[test]
fn unsupported_extensions_are_one_warning_each_naming_the_materials() {
    let s = load();
    let find =
        |ext: &str| -> Vec<&String> { s.warnings.iter().filter(|w| w.contains(ext)).collect() };
    let volume = find("KHR_materials_volume");
    assert_eq!(volume.len(), 1, "{:?}", s.warnings);
    assert!(volume[0].contains("\"glass\""), "{}", volume[0]);
    for ext in [
        "KHR_texture_transform",
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_specular",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
        "KHR_materials_anisotropy",
        "KHR_materials_unlit",
        "KHR_materials_emissive_strength",
    ] {
        assert!(find(ext).is_empty(), "{ext}: {:?}", s.warnings);
    }
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
}

/// KHR_materials_unlit: the sphere shows its base colour exactly (on camera rays: emission, black
/// BRDF) and is not a light, so the light list holds the emissive sphere's triangles and the point
/// light only.
#[test]
fn khr_materials_unlit_shows_its_base_colour_and_lights_nothing() {
    let s = load();
    let m = *material(&s, "unlit");
    assert_ne!(m.flags & MATERIAL_UNLIT, 0);
    assert_ne!(m.flags & MATERIAL_LAMBERTIAN, 0);
    let emissive_strength_triangles = s
        .triangle_materials
        .iter()
        .filter(|&&t| s.material_names[t as usize] == "emissive_strength")
        .count();
    let unlit_index = s.material_names.iter().position(|n| n == "unlit").unwrap();
    let unlit_centre = {
        // The unlit sphere's centre, in the scene's coordinates (its vertices' mean).
        let mut sum = Vec3::ZERO;
        let mut n = 0.0;
        for (t, &mat) in s.triangles.iter().zip(&s.triangle_materials) {
            if mat as usize == unlit_index {
                for &v in t {
                    sum += Vec3::from(s.positions[v as usize]);
                    n += 1.0;
                }
            }
        }
        sum / n
    };
    let camera_desc = s.camera.expect("the scene has a camera");
    let packed = fovea_tests::stability::pack(s, &Environment::None);
    assert_eq!(packed.lights.list.len(), emissive_strength_triangles + 1);

    // Look straight at the unlit sphere: every sample of the centre pixels hits it.
    let (w, h) = (16u32, 16u32);
    let eye = Vec3::from(camera_desc.position);
    let camera = fovea_core::camera::Camera::look_at(eye, unlit_centre, Vec3::Y, 0.02, 1.0);
    let frame = fovea_tests::frame_params(camera, FoveationParams::uniform(4), w, h, 3);
    let (image, _) = fovea_tests::render(&packed, &frame);
    let p = image.pixels[(h / 2 * w + w / 2) as usize];
    for (c, want) in p.iter().zip([0.9f32, 0.5, 0.1]) {
        assert!((c - want).abs() < 1e-5, "{p:?}");
    }
}
