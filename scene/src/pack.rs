//! Packing a [`LoadedScene`] into the flat arrays of `fovea_core::scene::layout`: BVH-ordered triangles,
//! materials, textures, the light list with its selection table and the environment tables. A
//! [`PackedScene`] is exactly what the GPU receives; the CPU host reads it through [`PackedScene::view`].
use std::time::Instant;

use fovea_core::lights::power;
use fovea_core::scene::{
    positions_at, Bvh4Node, Light, Material, SceneGlobals, SceneView, TextureInfo, TriangleBlock,
    TriangleInfo, TrianglePositions, ENVIRONMENT_CONSTANT, ENVIRONMENT_MAP, ENVIRONMENT_NONE,
    INVALID_INDEX, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_SPOT, LIGHT_TRIANGLE,
    MATERIAL_ALPHA_CUTOUT, MATERIAL_DOUBLE_SIDED_EMISSION, TEXTURE_RGBA16,
};
use glam::{Vec3, Vec4};

use crate::bvh::blocks::{name_wide_leaf_blocks, pack_leaf_blocks, LeafBlocks};
use crate::bvh::{build_bvh_indexed, BvhBuildOptions, BvhStats};
use crate::environment::{build_cdf, Environment, EnvironmentTables};
use crate::mesh::LoadedScene;
use fovea_core::bvh::wide::Bvh8Node;

/// Figures about a packed scene, for `--stats` and `--verbose`.
#[derive(Clone, Debug, Default)]
pub struct PackStats {
    pub triangle_count: usize,
    pub emissive_triangle_count: usize,
    pub light_count: usize,
    pub texture_count: usize,
    pub bvh: BvhStats,
    /// Time to pack everything except the BVH build.
    pub pack_ms: f64,
    /// Bytes of all packed arrays (what the GPU would hold).
    pub memory_bytes: usize,
}

/// The packed scene: owned arrays in the GPU layout.
#[derive(Clone, Debug, Default)]
pub struct PackedScene {
    pub globals: SceneGlobals,
    pub nodes: Vec<Bvh4Node>,
    /// The CPU's 8-wide tree over the same leaves (`fovea_core::bvh::wide`); the GPU traverses `nodes`.
    pub wide_nodes: Vec<Bvh8Node>,
    /// For each triangle, its block lane (`SceneView::triangle_lanes`).
    pub triangle_lanes: Vec<u32>,
    pub blocks: Vec<TriangleBlock>,
    pub triangle_info: Vec<TriangleInfo>,
    pub normals: Vec<[f32; 4]>,
    pub uvs: Vec<[f32; 2]>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureInfo>,
    pub texels: Vec<u32>,
    pub lights: Vec<Light>,
    pub light_cdf: Vec<f32>,
    pub triangle_light: Vec<u32>,
    pub environment_texels: Vec<[f32; 4]>,
    pub environment_marginal_cdf: Vec<f32>,
    pub environment_conditional_cdf: Vec<f32>,
    /// World-space bounds of all triangles.
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    pub stats: PackStats,
}

impl PackedScene {
    /// The optional features the scene uses (derived from its materials, lights, environment and
    /// vertex arrays; see `fovea_core::scene::features`).
    pub fn features(&self) -> fovea_core::scene::FeatureFlags {
        fovea_core::scene::FeatureFlags::of_scene(
            &self.globals,
            &self.materials,
            &self.lights,
            !self.normals.is_empty(),
            !self.uvs.is_empty(),
        )
    }

    /// The borrowed view every core function takes, with every feature on (the general path; see
    /// [`SceneView::with_features`] for a specialised one).
    pub fn view(&self) -> SceneView<'_> {
        SceneView {
            features: fovea_core::scene::FeatureFlags::ALL,
            globals: self.globals,
            nodes: &self.nodes,
            wide_nodes: &self.wide_nodes,
            triangle_lanes: &self.triangle_lanes,
            blocks: &self.blocks,
            triangle_info: &self.triangle_info,
            normals: &self.normals,
            uvs: &self.uvs,
            materials: &self.materials,
            textures: &self.textures,
            texels: &self.texels,
            lights: &self.lights,
            light_cdf: &self.light_cdf,
            triangle_light: &self.triangle_light,
            environment_texels: &self.environment_texels,
            environment_marginal_cdf: &self.environment_marginal_cdf,
            environment_conditional_cdf: &self.environment_conditional_cdf,
        }
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangle_info.len()
    }

    /// The positions of triangle `i` (BVH leaf order), read from its block.
    ///
    /// # Panics
    /// If `i` is not below [`Self::triangle_count`].
    #[must_use]
    pub fn triangle(&self, i: usize) -> TrianglePositions {
        positions_at(&self.blocks, self.triangle_lanes[i])
    }

    /// Bytes held by the packed arrays.
    pub fn memory_bytes(&self) -> usize {
        fn bytes<T>(v: &[T]) -> usize {
            std::mem::size_of_val(v)
        }
        bytes(&self.nodes)
            + bytes(&self.wide_nodes)
            + bytes(&self.triangle_lanes)
            + bytes(&self.blocks)
            + bytes(&self.triangle_info)
            + bytes(&self.normals)
            + bytes(&self.uvs)
            + bytes(&self.materials)
            + bytes(&self.textures)
            + bytes(&self.texels)
            + bytes(&self.lights)
            + bytes(&self.light_cdf)
            + bytes(&self.triangle_light)
            + bytes(&self.environment_texels)
            + bytes(&self.environment_marginal_cdf)
            + bytes(&self.environment_conditional_cdf)
    }

    /// Radius of the bounding sphere of the geometry.
    pub fn bounding_radius(&self) -> f32 {
        0.5 * (self.bounds_max - self.bounds_min).length()
    }
}

/// The vertex positions of the triangle with vertex indices `t`, in the layout the kernels read.
#[inline]
fn triangle_at(positions: &[[f32; 3]], t: [u32; 3]) -> TrianglePositions {
    let [v0, v1, v2] = t.map(|i| {
        let p = positions[i as usize];
        Vec4::new(p[0], p[1], p[2], 0.0)
    });
    TrianglePositions { v0, v1, v2 }
}

/// Packs `scene` lit additionally by `environment`, building the BVH with `bvh_options`.
pub fn pack_scene(
    scene: LoadedScene,
    environment: &Environment,
    bvh_options: &BvhBuildOptions,
) -> PackedScene {
    let start = Instant::now();
    let LoadedScene {
        positions,
        normals,
        uvs,
        triangles,
        triangle_materials,
        materials,
        textures,
        punctual_lights,
        ..
    } = scene;

    // Bounds of the vertices the triangles use (an unused far-away vertex must not move the camera).
    let mut bounds_min = Vec3::splat(f32::MAX);
    let mut bounds_max = Vec3::splat(f32::MIN);
    for t in &triangles {
        for &v in t {
            bounds_min = bounds_min.min(Vec3::from(positions[v as usize]));
            bounds_max = bounds_max.max(Vec3::from(positions[v as usize]));
        }
    }
    if triangles.is_empty() {
        bounds_min = Vec3::ZERO;
        bounds_max = Vec3::ZERO;
    }

    // Packing's peak memory is here: the build's temporaries next to the loaded scene. The loaded arrays
    // are dropped as soon as their leaf-ordered forms exist.
    let mut bvh = build_bvh_indexed(&positions, &triangles, bvh_options);
    let triangle_info: Vec<TriangleInfo> = bvh
        .triangle_order
        .iter()
        .map(|&i| TriangleInfo {
            vertices: triangles[i as usize],
            material: triangle_materials[i as usize],
        })
        .collect();
    drop(triangles);
    drop(triangle_materials);
    // The leaves' triangles four at a time, marked where their material has an alpha cut-out: the
    // only copy of the positions.
    let LeafBlocks {
        blocks,
        triangle_lanes,
    } = pack_leaf_blocks(
        &mut bvh.nodes,
        triangle_info.len(),
        |i| triangle_at(&positions, triangle_info[i].vertices),
        |i| materials[triangle_info[i].material as usize].flags & MATERIAL_ALPHA_CUTOUT != 0,
    );
    drop(positions);
    let mut wide_nodes = std::mem::take(&mut bvh.wide_nodes);
    name_wide_leaf_blocks(&mut wide_nodes, &triangle_lanes);

    // Per-vertex arrays only when something reads them.
    let any_texture = materials.iter().any(|m| {
        m.base_color_texture != INVALID_INDEX
            || m.metallic_roughness_texture != INVALID_INDEX
            || m.normal_texture != INVALID_INDEX
            || m.emission_texture != INVALID_INDEX
            || m.alpha_texture != INVALID_INDEX
    });
    let packed_uvs = if any_texture && !uvs.is_empty() {
        uvs
    } else {
        Vec::new()
    };
    let any_normal = normals.iter().any(|n| *n != [0.0; 3]);
    let packed_normals: Vec<[f32; 4]> = if any_normal {
        normals.iter().map(|n| [n[0], n[1], n[2], 0.0]).collect()
    } else {
        Vec::new()
    };
    drop(normals);

    // Textures: one texel array, one info record each; sRGB colour becomes linear RGBA16.
    let mut texture_infos = Vec::with_capacity(textures.len());
    let mut texels = Vec::with_capacity(packed_texel_words(&textures) as usize);
    let linear16 = srgb8_to_linear16();
    for t in &textures {
        if t.srgb && texels.len() % 2 == 1 {
            // RGBA16 textures start at an even word, so a texel's two words share one GPU texel.
            texels.push(0);
        }
        texture_infos.push(TextureInfo {
            offset: texels.len() as u32,
            width: t.width,
            height: t.height,
            flags: if t.srgb { TEXTURE_RGBA16 } else { 0 },
        });
        if t.srgb {
            for &texel in &t.texels {
                let [r, g, b, a] = srgb_texel_to_linear16(texel, &linear16).map(u32::from);
                texels.push(r | g << 16);
                texels.push(b | a << 16);
            }
        } else {
            texels.extend_from_slice(&t.texels);
        }
    }

    let radius = {
        let r = 0.5 * (bounds_max - bounds_min).length();
        if r > 0.0 && r.is_finite() {
            r
        } else {
            1.0
        }
    };

    // The light list and the power of each entry.
    let mut lights: Vec<Light> = Vec::new();
    let mut light_power: Vec<f64> = Vec::new();
    let mut triangle_light = Vec::new();
    let mut emissive_triangle_count = 0;
    if materials.iter().any(|m| m.is_emissive()) {
        triangle_light = vec![INVALID_INDEX; triangle_info.len()];
        // Each emission texture's mean colour, averaged once however many triangles use it.
        let mut texture_means: Vec<Option<Vec3>> = vec![None; textures.len()];
        for (i, (&at, info)) in triangle_lanes.iter().zip(&triangle_info).enumerate() {
            let m = &materials[info.material as usize];
            if !m.is_emissive() {
                continue;
            }
            let t = positions_at(&blocks, at);
            let (v0, v1, v2) = (t.v0.truncate(), t.v1.truncate(), t.v2.truncate());
            let area = 0.5 * (v1 - v0).cross(v2 - v0).length();
            if !(area > 0.0) || !area.is_finite() {
                continue;
            }
            let mut radiance = Vec3::from_slice(&m.emission);
            if m.emission_texture != INVALID_INDEX {
                let k = m.emission_texture as usize;
                radiance *= *texture_means[k]
                    .get_or_insert_with(|| mean_texture_color(&textures[k], &linear16));
            }
            let p = power::triangle_power(
                radiance,
                area,
                m.flags & MATERIAL_DOUBLE_SIDED_EMISSION != 0,
            );
            if !(p > 0.0) {
                continue;
            }
            triangle_light[i] = lights.len() as u32;
            lights.push(Light {
                kind: LIGHT_TRIANGLE,
                index: i as u32,
                ..Default::default()
            });
            light_power.push(p as f64);
            emissive_triangle_count += 1;
        }
        if emissive_triangle_count == 0 {
            triangle_light.clear();
        }
    }
    for l in &punctual_lights {
        let intensity = Vec3::from_slice(&l.intensity);
        let p = match l.kind {
            LIGHT_POINT => power::point_power(intensity),
            LIGHT_SPOT => power::spot_power(intensity, l.position[3], l.intensity[3]),
            LIGHT_DIRECTIONAL => power::directional_power(intensity, radius),
            _ => 0.0,
        };
        if p > 0.0 && p.is_finite() {
            lights.push(Light { pmf: 0.0, ..*l });
            light_power.push(p as f64);
        }
    }

    let mut globals = SceneGlobals {
        environment_light: INVALID_INDEX,
        ..Default::default()
    };
    let mut environment_texels = Vec::new();
    let mut environment_marginal_cdf = Vec::new();
    let mut environment_conditional_cdf = Vec::new();
    let mean_env = environment.mean_radiance();
    match environment {
        Environment::None => globals.environment_kind = ENVIRONMENT_NONE,
        Environment::Constant(c) => {
            globals.environment_kind = ENVIRONMENT_CONSTANT;
            globals.environment_radiance = [c[0], c[1], c[2], 0.0];
        }
        Environment::Map {
            width,
            height,
            texels,
            scale,
        } => {
            globals.environment_kind = ENVIRONMENT_MAP;
            globals.environment_radiance = [scale[0], scale[1], scale[2], 0.0];
            globals.environment_width = *width;
            globals.environment_height = *height;
            let tables = EnvironmentTables::build(*width, *height, texels);
            globals.environment_integral = tables.integral;
            environment_texels = texels.clone();
            environment_marginal_cdf = tables.marginal_cdf;
            environment_conditional_cdf = tables.conditional_cdf;
        }
    }
    if globals.environment_kind != ENVIRONMENT_NONE {
        let p = power::environment_power(mean_env, radius);
        if p > 0.0 && p.is_finite() {
            globals.environment_light = lights.len() as u32;
            lights.push(Light {
                kind: LIGHT_ENVIRONMENT,
                index: 0,
                ..Default::default()
            });
            light_power.push(p as f64);
        }
    }

    let (light_cdf, _) = if lights.is_empty() {
        (Vec::new(), 0.0)
    } else {
        build_cdf(&light_power)
    };
    for (i, l) in lights.iter_mut().enumerate() {
        l.pmf = light_cdf[i + 1] - light_cdf[i];
    }
    globals.light_count = lights.len() as u32;

    let mut packed = PackedScene {
        globals,
        nodes: bvh.nodes,
        wide_nodes,
        triangle_lanes,
        blocks,
        triangle_info,
        normals: packed_normals,
        uvs: packed_uvs,
        materials,
        textures: texture_infos,
        texels,
        lights,
        light_cdf,
        triangle_light,
        environment_texels,
        environment_marginal_cdf,
        environment_conditional_cdf,
        bounds_min,
        bounds_max,
        stats: PackStats::default(),
    };
    packed.stats = PackStats {
        triangle_count: packed.triangle_count(),
        emissive_triangle_count,
        light_count: packed.lights.len(),
        texture_count: packed.textures.len(),
        pack_ms: (start.elapsed().as_secs_f64() * 1e3 - bvh.stats.build_ms).max(0.0),
        bvh: bvh.stats,
        memory_bytes: packed.memory_bytes(),
    };
    packed
}

/// At most the `u32` words the packed texel array of `textures` needs: one per RGBA8 texel, two per
/// sRGB texel (stored as linear RGBA16, see `fovea_core::scene::TEXTURE_RGBA16`), and one of padding per
/// texture (RGBA16 textures start at an even word). The loaders refuse scenes whose textures need more
/// than `u32::MAX`.
#[must_use]
pub fn packed_texel_words(textures: &[crate::texture::Texture]) -> u64 {
    textures
        .iter()
        .map(|t| t.texels.len() as u64 * if t.srgb { 2 } else { 1 } + 1)
        .sum()
}

/// The 16-bit unorm linear value of each 8-bit sRGB level (IEC 61966-2-1, evaluated in f64).
fn srgb8_to_linear16() -> [u16; 256] {
    std::array::from_fn(|i| {
        let v = i as f64 / 255.0;
        let linear = if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        };
        (linear * 65535.0).round() as u16
    })
}

/// An RGBA8 sRGB texel as 16-bit unorm linear RGBA (`linear16` from [`srgb8_to_linear16`]; alpha is
/// linear already and only widened).
fn srgb_texel_to_linear16(texel: u32, linear16: &[u16; 256]) -> [u16; 4] {
    let [r, g, b, a] = texel.to_le_bytes();
    [
        linear16[usize::from(r)],
        linear16[usize::from(g)],
        linear16[usize::from(b)],
        u16::from(a) * 257,
    ]
}

/// Mean linear colour of a texture, as its lookups see it (sRGB texels decoded as the packer stores
/// them).
fn mean_texture_color(t: &crate::texture::Texture, linear16: &[u16; 256]) -> Vec3 {
    if t.texels.is_empty() {
        return Vec3::ONE;
    }
    let mut sum = glam::DVec3::ZERO;
    for &texel in &t.texels {
        sum += if t.srgb {
            let [r, g, b, _] = srgb_texel_to_linear16(texel, linear16).map(f64::from);
            glam::DVec3::new(r, g, b) / 65535.0
        } else {
            let [r, g, b, _] = texel.to_le_bytes().map(f64::from);
            glam::DVec3::new(r, g, b) / 255.0
        };
    }
    (sum / t.texels.len() as f64).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhBuildOptions;

    #[test]
    fn bounds_ignore_unused_vertices_and_lights_are_normalised() {
        let scene = LoadedScene {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1e30, -1e30, 1e30],
            ],
            triangles: vec![[0, 1, 2]],
            triangle_materials: vec![0],
            materials: vec![Material {
                emission: [2.0, 2.0, 2.0, 0.0],
                ..Material::default()
            }],
            material_names: vec!["light".into()],
            ..LoadedScene::default()
        };
        let packed = pack_scene(
            scene,
            &Environment::Constant([0.5; 3]),
            &BvhBuildOptions::default(),
        );
        assert_eq!(packed.bounds_min, Vec3::ZERO);
        assert_eq!(packed.bounds_max, Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(packed.lights.len(), 2);
        let sum: f32 = packed.lights.iter().map(|l| l.pmf).sum();
        assert!((sum - 1.0).abs() < 1e-6, "{sum}");
        assert_eq!(packed.light_cdf.len(), 3);
        assert_eq!(packed.light_cdf[2], 1.0);
    }

    /// sRGB colour textures are stored as linear RGBA16 and looked up linear (filtered in linear space);
    /// data textures stay RGBA8 as stored; the texel-word count matches the packed array.
    #[test]
    fn srgb_textures_are_packed_linear() {
        use crate::texture::Texture;
        use fovea_core::material::texture::sample_texture;
        use fovea_core::scene::SceneSlices;
        use glam::Vec2;
        let mut colour = Texture::single_color("c", [128, 0, 255, 77], true);
        colour.width = 2;
        colour.texels = vec![
            colour.texels[0],
            crate::texture::pack_rgba8([0, 128, 255, 255]),
        ];
        let data = Texture::single_color("d", [128, 0, 255, 77], false);
        let scene = LoadedScene {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            triangle_materials: vec![0],
            materials: vec![Material::default()],
            material_names: vec!["m".into()],
            textures: vec![colour, data],
            ..LoadedScene::default()
        };
        let words = packed_texel_words(&scene.textures);
        let packed = pack_scene(scene, &Environment::None, &BvhBuildOptions::default());
        assert!(packed.texels.len() as u64 <= words);
        assert_eq!(packed.texels.len(), 2 * 2 + 1);
        assert_eq!(packed.textures[0].offset % 2, 0);
        assert_eq!(packed.textures[0].flags, TEXTURE_RGBA16);
        assert_eq!(packed.textures[1].flags, 0);
        let view = packed.view();
        // Texel centres: sRGB 128 is linear 0.21586 (16-bit 14146), 255 is 1; alpha 77 is 77/255.
        let left = sample_texture(&view, &SceneSlices, 0, Vec2::new(0.25, 0.5));
        assert_eq!(left.x, 14146.0 / 65535.0);
        assert_eq!(left.y, 0.0);
        assert_eq!(left.z, 1.0);
        assert!((left.w - 77.0 / 255.0).abs() < 1e-7);
        // Half way between the two texels: the mean of the linear values, not of the encoded ones.
        let mid = sample_texture(&view, &SceneSlices, 0, Vec2::new(0.5, 0.5));
        assert!((mid.x - 0.5 * 14146.0 / 65535.0).abs() < 1e-6, "{mid}");
        assert!((mid.y - 0.5 * 14146.0 / 65535.0).abs() < 1e-6, "{mid}");
        let d = sample_texture(&view, &SceneSlices, 1, Vec2::new(0.5, 0.5));
        assert!((d.x - 128.0 / 255.0).abs() < 1e-7 && (d.w - 77.0 / 255.0).abs() < 1e-7);
    }
}
