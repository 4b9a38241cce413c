//! The bundled glTF PBR-extension scene (`assets/pbr_extensions`, made by `scripts/make-pbr-scene.py`):
//! one test per extension of the loader's mapping (`fovea_scene::gltf_pbr`), the warnings for what fovea
//! does not render, and the unlit material's look. Its CPU/lavapipe agreement is a case of
//! `cross_backend_frames`.
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::scene::{Material, MATERIAL_LAMBERTIAN, MATERIAL_THIN_WALLED, MATERIAL_UNLIT};
use fovea_scene::environment::Environment;
use fovea_scene::gltf_pbr::{absorption_coefficient, specular_from_ior};
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
    assert_eq!(m.flags & MATERIAL_THIN_WALLED, 0);
    // Without KHR_materials_volume: a thin wall.
    let thin = *material(&load(), "textured_glass");
    assert_ne!(thin.flags & MATERIAL_THIN_WALLED, 0);
    assert_eq!(thin.absorption, [0.0; 3]);
}

/// KHR_materials_volume: attenuationColor (0.9, 0.95, 1) over attenuationDistance 2 is the absorption
/// σ = −ln(c) / 2 (its rendering is `stability_furnace`'s Beer–Lambert test).
#[test]
fn khr_materials_volume_sets_the_absorption() {
    let m = *material(&load(), "glass");
    let want = absorption_coefficient([0.9, 0.95, 1.0], 2.0);
    assert_eq!(m.absorption, want);
    assert!((want[0] - 0.9f32.ln().abs() / 2.0).abs() < 1e-6 && want[2] == 0.0);
}

/// The extensions' textures (clearcoatTexture R, clearcoatRoughnessTexture G, sheenColorTexture RGB
/// in sRGB, specularTexture A, transmissionTexture R) are decoded and multiply their factors where a
/// ray hits: for points of the textured spheres, the shading parameters equal the factors times the
/// texture channels read at the point's coordinates, and the checker makes them vary.
#[test]
fn extension_textures_multiply_their_factors() {
    use fovea_core::material::surface_point;
    use fovea_core::material::texture::sample_texture;
    use fovea_core::scene::{SceneSlices, SceneSource, INVALID_INDEX};

    let s = load();
    let m = *material(&s, "extension_textures");
    for t in [
        m.clearcoat_texture,
        m.clearcoat_roughness_texture,
        m.sheen_texture,
        m.specular_texture,
    ] {
        assert_ne!(t, INVALID_INDEX, "{m:?}");
    }
    // The colour texture is decoded from sRGB, the others are linear: two records of one image.
    assert_eq!(m.clearcoat_texture, m.clearcoat_roughness_texture);
    assert_ne!(m.clearcoat_texture, m.sheen_texture);
    let glass = *material(&s, "textured_glass");
    assert_ne!(glass.transmission_texture, INVALID_INDEX);

    let names = s.material_names.clone();
    let centre = |name: &str| sphere_centre(&s, name);
    let (textured, glass_centre) = (centre("extension_textures"), centre("textured_glass"));
    let eye = Vec3::from(s.camera.expect("camera").position);
    let packed = fovea_tests::stability::pack(s, &Environment::None);
    let view = packed.view();
    let mut clearcoats = Vec::new();
    let mut transmissions = Vec::new();
    for (target, name) in [
        (textured, "extension_textures"),
        (glass_centre, "textured_glass"),
    ] {
        for hit in hits_on_sphere(&view, &names, eye, target, name) {
            let info = SceneSlices.triangle_info(&view, hit.triangle);
            let mat = view.materials.list[info.material as usize];
            let p = surface_point(&view, &SceneSlices, &hit);
            let tex = |t: u32| sample_texture(&view, &SceneSlices, t, p.uv);
            if name == "textured_glass" {
                let want = tex(mat.transmission_texture).x;
                assert!((p.params.transmission - want).abs() < 1e-6);
                transmissions.push(p.params.transmission);
                continue;
            }
            let coat = tex(mat.clearcoat_texture);
            assert!((p.params.clearcoat - coat.x).abs() < 1e-6, "{p:?}");
            assert!((p.params.clearcoat_gloss - (1.0 - 0.5 * coat.y)).abs() < 1e-6);
            let sheen = tex(mat.sheen_texture);
            assert!((p.params.sheen - sheen.x.max(sheen.y).max(sheen.z)).abs() < 1e-6);
            // specularTexture's alpha is 1: Burley's default specular is kept.
            assert!((p.params.specular - mat.specular).abs() < 1e-6);
            clearcoats.push(p.params.clearcoat);
        }
    }
    for (what, values) in [
        ("clear coat", &clearcoats),
        ("transmission", &transmissions),
    ] {
        assert!(values.len() > 100, "{what}: {} hits", values.len());
        let (lo, hi) = values
            .iter()
            .fold((1f32, 0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        // The checker's two texels: 40 / 255 and 230 / 255, linear.
        assert!(
            (lo - 40.0 / 255.0).abs() < 1e-3 && (hi - 230.0 / 255.0).abs() < 1e-3,
            "{what}: {lo}..{hi}"
        );
    }
}

/// glTF `COLOR_0` (normalised bytes, RGBA, 0.5 + 0.5 · the sphere's unit position) multiplies the base
/// colour (0.9) where a ray hits, and its alpha (0 below a local y of -0.6) cuts the sphere's bottom
/// cap out under `MASK`: a ray from just above the floor passes it and hits the top from inside.
#[test]
fn vertex_colours_multiply_the_base_colour_and_cut_out_by_their_alpha() {
    use fovea_core::bvh::closest_hit;
    use fovea_core::geometry::Ray;
    use fovea_core::material::surface_point;
    use fovea_core::scene::features::FEATURE_VERTEX_COLORS;
    use fovea_core::scene::{Features, SceneSlices};

    let s = load();
    assert!(
        s.warnings.iter().all(|w| !w.contains("COLOR_0")),
        "{:?}",
        s.warnings
    );
    let names = s.material_names.clone();
    let centre = sphere_centre(&s, "vertex_colors");
    let eye = Vec3::from(s.camera.expect("camera").position);
    let packed = fovea_tests::stability::pack(s, &Environment::None);
    assert!(packed.features().has(FEATURE_VERTEX_COLORS));
    let view = packed.view();
    let mut hits = 0;
    for hit in hits_on_sphere(&view, &names, eye, centre, "vertex_colors") {
        let p = surface_point(&view, &SceneSlices, &hit);
        // The colour is linear in the position, so interpolating it over a flat triangle gives the
        // same function of the hit point (up to the bytes' rounding); the node scales the sphere by 0.9.
        let want = 0.9 * (Vec3::splat(0.5) + 0.5 * (p.position - centre) / 0.9);
        assert!(
            (p.params.base_color - want).abs().max_element() < 0.01,
            "{} at {}: want {want}",
            p.params.base_color,
            p.position
        );
        hits += 1;
    }
    assert!(hits > 100, "{hits} hits");
    let below = centre - Vec3::Y * 0.85;
    let hit = closest_hit(&view, &Ray::new(below, Vec3::Y), f32::INFINITY);
    assert!(hit.is_hit());
    assert!(
        below.y + hit.t > centre.y + 0.8,
        "the ray up stopped at y = {} (centre {})",
        below.y + hit.t,
        centre.y
    );
}

/// A texture that names `TEXCOORD_1` reads that set: the sphere's coordinates are its TEXCOORD_1
/// (twice its TEXCOORD_0, which the other spheres read).
#[test]
fn a_texture_reads_the_coordinate_set_it_names() {
    let s = load();
    let first_vertex = |name: &str| {
        let m = s.material_names.iter().position(|n| n == name).unwrap() as u32;
        s.triangles
            .iter()
            .zip(&s.triangle_materials)
            .filter(|&(_, &t)| t == m)
            .flat_map(|(t, _)| *t)
            .min()
            .unwrap() as usize
    };
    let (set1, set0) = (
        first_vertex("texcoord_1"),
        first_vertex("extension_textures"),
    );
    let n = set0.abs_diff(set1);
    let mut larger = 0;
    for k in 0..n.min(642) {
        let (a, b) = (s.uvs[set1 + k], s.uvs[set0 + k]);
        assert!(
            (a[0] - 2.0 * b[0]).abs() < 1e-5 && (a[1] - 2.0 * b[1]).abs() < 1e-5,
            "{k}: {a:?} {b:?}"
        );
        larger += usize::from(a[0] > 1.0);
    }
    assert!(larger > 100);
    assert!(
        s.warnings.iter().all(|w| !w.contains("TEXCOORD")),
        "{:?}",
        s.warnings
    );
}

/// The hits on material `name` of rays from `eye` through a 20 × 20 grid of points over the visible disc
/// of the sphere at `centre` (radius 0.9).
fn hits_on_sphere(
    view: &fovea_core::scene::SceneView,
    names: &[String],
    eye: Vec3,
    centre: Vec3,
    name: &str,
) -> Vec<fovea_core::bvh::traverse::Hit> {
    use fovea_core::scene::{SceneSlices, SceneSource};
    (0..400)
        .filter_map(|k| {
            let offset = Vec3::new(
                (k % 20) as f32 / 10.0 - 0.95,
                (k / 20) as f32 / 10.0 - 0.95,
                0.0,
            ) * 0.8;
            let ray = fovea_core::geometry::Ray::new(eye, centre + offset - eye);
            let hit = fovea_core::bvh::closest_hit(view, &ray, f32::INFINITY);
            let material = |hit: &fovea_core::bvh::traverse::Hit| {
                SceneSlices.triangle_info(view, hit.triangle).material as usize
            };
            (hit.is_hit() && names[material(&hit)] == name).then_some(hit)
        })
        .collect()
}

/// The mean of a material's vertices (a sphere's centre), in the scene's coordinates.
fn sphere_centre(s: &LoadedScene, name: &str) -> Vec3 {
    let index = s.material_names.iter().position(|n| n == name).unwrap();
    let mut sum = Vec3::ZERO;
    let mut n = 0.0;
    for (t, &mat) in s.triangles.iter().zip(&s.triangle_materials) {
        if mat as usize == index {
            for &v in t {
                sum += Vec3::from(s.positions[v as usize]);
                n += 1.0;
            }
        }
    }
    sum / n
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

/// The mapped extensions give no warning: the bundled scene, which uses only them (and their textures),
/// loads without one. (An extension fovea does not render is one warning naming it and its materials:
/// `fovea_scene::gltf_loader`'s tests.)
#[test]
fn mapped_extensions_give_no_warning() {
    let s = load();
    let find =
        |ext: &str| -> Vec<&String> { s.warnings.iter().filter(|w| w.contains(ext)).collect() };
    for ext in [
        "KHR_materials_volume",
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
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
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
    let unlit_centre = sphere_centre(&s, "unlit");
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

/// The vertices of a material's triangles that come from the file, in its order (the first contiguous
/// run: MikkTSpace's seam copies come after every vertex of the file).
fn material_vertices(s: &LoadedScene, name: &str) -> Vec<usize> {
    let m = s.material_names.iter().position(|n| n == name).unwrap() as u32;
    let mut v: Vec<usize> = s
        .triangles
        .iter()
        .zip(&s.triangle_materials)
        .filter(|&(_, &t)| t == m)
        .flat_map(|(t, _)| t.map(|v| v as usize))
        .collect();
    v.sort_unstable();
    v.dedup();
    let first = v[0];
    v.into_iter()
        .enumerate()
        .take_while(|&(i, v)| v == first + i)
        .map(|(_, v)| v)
        .collect()
}

/// Tangents: the file's own `TANGENT` is read (the analytic ∂p/∂u of the sphere's mapping, handedness
/// −1 as its texture is mirrored), and MikkTSpace's for the same sphere without it agree with them away
/// from the poles and the seam, handedness included.
#[test]
fn tangents_are_read_or_generated_with_mikktspace() {
    let s = load();
    let given = material_vertices(&s, "normal_map_tangents");
    let generated = material_vertices(&s, "normal_map");
    assert_eq!((given.len(), generated.len()), (642, 642));
    // MikkTSpace copied the vertices on the texture's seam.
    assert!(s.positions.len() > generated[0] + 2 * 642 + 10);
    assert!(!s.tangents.is_empty());
    let centre = |vs: &[usize]| {
        vs.iter().map(|&v| Vec3::from(s.positions[v])).sum::<Vec3>() / vs.len() as f32
    };
    let (c_given, c_generated) = (centre(&given), centre(&generated));
    let mut compared = 0;
    for (&a, &b) in given.iter().zip(&generated) {
        let (ta, tb) = (s.tangents[a], s.tangents[b]);
        let p = (Vec3::from(s.positions[a]) - c_given) / 0.9;
        assert!(
            (Vec3::from(s.positions[b]) - c_generated - 0.9 * p).length() < 1e-4,
            "{a} {b} {:?} {:?} {c_given} {c_generated}",
            s.positions[a],
            s.positions[b]
        );
        // The file's: ∂p/∂u = (−z, 0, x) / |(x, z)|, handedness −1.
        if p.y.abs() < 0.95 {
            let want = Vec3::new(-p.z, 0.0, p.x).normalize();
            assert!(
                Vec3::new(ta[0], ta[1], ta[2]).dot(want) > 0.999,
                "{ta:?} {want}"
            );
        }
        assert_eq!(ta[3], -1.0);
        let uv = s.uvs[b];
        if p.y.abs() < 0.8 && uv[0] > 0.05 && uv[0] < 0.95 {
            let d = Vec3::new(ta[0], ta[1], ta[2]).dot(Vec3::new(tb[0], tb[1], tb[2]));
            assert!(
                d > 0.98,
                "vertex {b}: MikkTSpace {tb:?} against the file's {ta:?}"
            );
            assert_eq!(tb[3], ta[3]);
            compared += 1;
        }
    }
    assert!(compared > 200, "{compared}");
}

/// Shading reads the vertex tangents: on the sphere with the file's tangents, the shading frame's
/// tangent at a hit is the interpolated ∂p/∂u, and the normal map tilts the normal. Without vertex
/// tangents (the per-triangle ones shading derives from the texture coordinates, handedness included)
/// the mapped normal is the same within the difference of the two tangent fields.
#[test]
fn shading_uses_the_vertex_tangents() {
    use fovea_core::bvh::closest_hit;
    use fovea_core::material::surface_point;
    use fovea_core::scene::{SceneSlices, SceneSource};

    let s = load();
    let names = s.material_names.clone();
    let centre = sphere_centre(&s, "normal_map_tangents");
    let eye = Vec3::from(s.camera.expect("camera").position);
    let mut without = s.clone();
    without.tangents.clear();
    let packed = fovea_tests::stability::pack(s, &Environment::None);
    let view = packed.view();
    let packed_without = fovea_tests::stability::pack(without, &Environment::None);
    let view_without = packed_without.view();
    let (mut hits, mut tilted) = (0, 0);
    for k in 0..100 {
        let offset = Vec3::new(
            (k % 10) as f32 / 10.0 - 0.45,
            (k / 10) as f32 / 10.0 - 0.45,
            0.0,
        );
        let ray = fovea_core::geometry::Ray::new(eye, centre + offset - eye);
        let hit = closest_hit(&view, &ray, f32::INFINITY);
        if !hit.is_hit() {
            continue;
        }
        let info = SceneSlices.triangle_info(&view, hit.triangle);
        if names[info.material as usize] != "normal_map_tangents" {
            continue;
        }
        let p = surface_point(&view, &SceneSlices, &hit);
        let q = (p.position - centre).normalize();
        let dp_du = Vec3::new(-q.z, 0.0, q.x).normalize();
        // The frame's tangent is ∂p/∂u made orthogonal to the (mapped) normal.
        let expected = (dp_du - p.frame.z * p.frame.z.dot(dp_du)).normalize();
        assert!(
            p.frame.x.dot(expected) > 0.99,
            "{:?} against {expected}",
            p.frame
        );
        tilted += usize::from(p.frame.z.dot(q) < 0.995);
        hits += 1;
        let derived = surface_point(
            &view_without,
            &SceneSlices,
            &closest_hit(&view_without, &ray, f32::INFINITY),
        );
        assert!(
            derived.frame.z.dot(p.frame.z) > 0.995,
            "{:?} against {:?}",
            derived.frame.z,
            p.frame.z
        );
    }
    assert!(
        hits > 30 && tilted > hits / 2,
        "{hits} hits, {tilted} tilted"
    );
}

/// A normal map that turns the shading normal away from a grazing viewer (here: every point of a quad
/// tilted 64° towards +x by its one-texel map, seen from far along −x) is shaded with the interpolated
/// normal instead of ending the path black: the white Lambertian quad under a uniform sky of 1 shows
/// its albedo 0.8.
#[test]
fn a_normal_map_turned_from_the_viewer_falls_back_to_the_interpolated_normal() {
    use fovea_core::scene::{INVALID_INDEX, MATERIAL_LAMBERTIAN};
    use fovea_scene::texture::{pack_rgba8, Texture};

    let material = Material {
        base_color: [0.8, 0.8, 0.8, 1.0],
        specular: 0.0,
        flags: MATERIAL_LAMBERTIAN,
        normal_texture: 0,
        ..Material::default()
    };
    let mut s = fovea_tests::stability::textured_quad(material);
    // The tangent-space normal (0.9, 0, 0.44): towards +u, which runs along +x.
    s.textures = vec![Texture::new(
        "n",
        1,
        1,
        false,
        vec![pack_rgba8([242, 128, 183, 255])],
    )];
    let packed = fovea_tests::stability::pack(s, &Environment::Constant([1.0, 1.0, 1.0]));
    assert_ne!(
        packed.view().materials.list[0].normal_texture,
        INVALID_INDEX
    );
    let camera = fovea_core::camera::Camera::look_at(
        Vec3::new(-6.0, 0.0, 0.6),
        Vec3::ZERO,
        Vec3::Y,
        0.05,
        1.0,
    );
    let frame = fovea_tests::frame_params(camera, FoveationParams::uniform(256), 8, 8, 5);
    let (image, _) = fovea_tests::render(&packed, &frame);
    // The middle pixels (the outer rows see past the quad).
    let mean = fovea_tests::mean_rgb(&image, (3..5).flat_map(|y| (3..5).map(move |x| (x, y))));
    assert!(
        (mean - Vec3::splat(0.8)).abs().max_element() < 0.02,
        "{mean}"
    );
}
