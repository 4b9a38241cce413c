//! Packing a [`LoadedScene`] into the flat arrays of `fovea_core::scene::layout`, in the four groups of
//! [`fovea_core::scene::SceneView`]: [`geometry`] (the BVH and triangles), [`materials`] (with their
//! textures), [`lights`] (the list and its selection table) and [`environment`]. A [`PackedScene`] is
//! exactly what the GPU receives ([`PackedScene::gpu_arrays`]); the CPU host reads it through
//! [`PackedScene::view`].
pub mod array;
pub mod environment;
pub mod geometry;
pub mod lights;
pub mod materials;

use std::time::Instant;

use fovea_core::scene::{
    positions_at, FeatureFlags, SceneGlobals, SceneView, TrianglePositions, VertexAttributes,
};
use glam::Vec3;

pub use self::array::{ArrayRead, PackedArray};
pub use self::environment::PackedEnvironment;
pub use self::geometry::PackedGeometry;
pub use self::lights::PackedLights;
pub use self::materials::{packed_texel_words, PackedMaterials};
use crate::bvh::{BvhBuildOptions, BvhStats};
use crate::environment::Environment;
use crate::mesh::LoadedScene;

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

/// The packed scene: owned arrays in the GPU layout, grouped as [`SceneView`] groups them.
#[derive(Clone, Debug, Default)]
pub struct PackedScene {
    pub globals: SceneGlobals,
    pub geometry: PackedGeometry,
    pub materials: PackedMaterials,
    pub lights: PackedLights,
    pub environment: PackedEnvironment,
    /// Bounds of all triangles, in the scene's coordinates (relative to `LoadedScene::origin`).
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    pub stats: PackStats,
}

impl PackedScene {
    /// The optional features the scene uses (derived from its materials, lights, environment and
    /// vertex arrays; see `fovea_core::scene::features`).
    pub fn features(&self) -> FeatureFlags {
        FeatureFlags::of_scene(
            &self.globals,
            &self.materials.list,
            &self.lights.list,
            VertexAttributes {
                normals: !self.geometry.normals.is_empty(),
                uvs: !self.geometry.uvs.is_empty(),
                colors: !self.geometry.vertex_colors.is_empty(),
            },
        )
    }

    /// The borrowed view every core function takes, with every feature on (the general path; see
    /// [`SceneView::with_features`] for a specialised one).
    pub fn view(&self) -> SceneView<'_> {
        SceneView {
            features: FeatureFlags::ALL,
            globals: self.globals,
            geometry: self.geometry.view(),
            materials: self.materials.view(),
            lights: self.lights.view(),
            environment: self.environment.view(),
        }
    }

    /// Every array the GPU receives with its binding, group by group (the globals apart: the host
    /// completes them with where it put each array).
    #[must_use]
    pub fn gpu_arrays(&self) -> Vec<PackedArray<'_>> {
        let mut arrays = Vec::with_capacity(15);
        arrays.extend(self.geometry.gpu_arrays());
        arrays.extend(self.materials.gpu_arrays());
        arrays.extend(self.lights.gpu_arrays());
        arrays.extend(self.environment.gpu_arrays());
        arrays
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.geometry.triangle_info.len()
    }

    /// The positions of triangle `i` (BVH leaf order), read from its block.
    ///
    /// # Panics
    /// If `i` is not below [`Self::triangle_count`].
    #[must_use]
    pub fn triangle(&self, i: usize) -> TrianglePositions {
        positions_at(&self.geometry.blocks, self.geometry.triangle_lanes[i])
    }

    /// Bytes held by the packed arrays (the CPU's 8-wide tree included).
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.geometry.wide_nodes.as_slice())
            + self
                .gpu_arrays()
                .iter()
                .map(|a| a.bytes.len())
                .sum::<usize>()
    }

    /// Radius of the bounding sphere of the geometry.
    pub fn bounding_radius(&self) -> f32 {
        0.5 * (self.bounds_max - self.bounds_min).length()
    }
}

/// Packs `scene` lit additionally by `environment`, building the BVH with `bvh_options`: the geometry
/// first (it drops the loaded positions as soon as the blocks hold them), then the materials, the
/// environment and the lights, which need all three.
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
        tangents,
        colors,
        triangles,
        triangle_materials,
        materials,
        textures,
        punctual_lights,
        ..
    } = scene;

    let geometry::GeometryOutput {
        geometry,
        bvh,
        bounds_min,
        bounds_max,
    } = geometry::pack_geometry(
        geometry::GeometryInput {
            positions,
            normals,
            uvs,
            tangents,
            colors,
            triangles,
            triangle_materials,
        },
        &materials,
        bvh_options,
    );
    let materials = materials::pack_materials(materials, &textures);
    let mut globals = SceneGlobals::default();
    let packed_environment = environment::pack_environment(environment, &mut globals);
    let radius = {
        let r = 0.5 * (bounds_max - bounds_min).length();
        if r > 0.0 && r.is_finite() {
            r
        } else {
            1.0
        }
    };
    let (lights, emissive_triangle_count) = lights::pack_lights(
        &lights::LightSources {
            geometry: &geometry,
            materials: &materials,
            textures: &textures,
            punctual: &punctual_lights,
            environment,
            radius,
        },
        &mut globals,
    );

    let mut packed = PackedScene {
        globals,
        geometry,
        materials,
        lights,
        environment: packed_environment,
        bounds_min,
        bounds_max,
        stats: PackStats::default(),
    };
    packed.stats = PackStats {
        triangle_count: packed.triangle_count(),
        emissive_triangle_count,
        light_count: packed.lights.list.len(),
        texture_count: packed.materials.textures.len(),
        pack_ms: (start.elapsed().as_secs_f64() * 1e3 - bvh.build_ms).max(0.0),
        bvh,
        memory_bytes: packed.memory_bytes(),
    };
    packed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhBuildOptions;
    use fovea_core::scene::{Material, TEXTURE_RGBA16};

    /// One triangle with the default material, and `textures` to pack.
    fn textured_triangle(textures: Vec<crate::texture::Texture>) -> LoadedScene {
        LoadedScene {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            triangle_materials: vec![0],
            materials: vec![Material::default()],
            material_names: vec!["m".into()],
            textures,
            ..LoadedScene::default()
        }
    }

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
        assert_eq!(packed.lights.list.len(), 2);
        let sum: f32 = packed.lights.list.iter().map(|l| l.pmf).sum();
        assert!((sum - 1.0).abs() < 1e-6, "{sum}");
        assert_eq!(packed.lights.cdf.len(), 3);
        assert_eq!(packed.lights.cdf[2], 1.0);
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
        let scene = textured_triangle(vec![colour, data]);
        let words = packed_texel_words(&scene.textures);
        let packed = pack_scene(scene, &Environment::None, &BvhBuildOptions::default());
        assert!(packed.materials.texels.len() as u64 <= words);
        // The 2 × 1 colour texture and its 1 × 1 level (two words each), then the 1 × 1 data texture.
        assert_eq!(packed.materials.texels.len(), 2 * (2 + 1) + 1);
        assert_eq!(packed.materials.textures[0].offset % 2, 0);
        assert_eq!(
            packed.materials.textures[0].flags,
            TEXTURE_RGBA16 | fovea_core::scene::TEXTURE_MIPMAPPED
        );
        assert_eq!(packed.materials.textures[1].flags, 0);
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

    /// Mip levels are built in linear space (the mean of the decoded values, not of the sRGB codes),
    /// halving down to 1 × 1 with odd edges repeated; `sample_texture_lod` picks level 0 for a footprint of
    /// at most one texel, the last level for one as large as the texture, and blends in between.
    #[test]
    fn mip_levels_are_linear_means_and_the_footprint_picks_them() {
        use crate::texture::{pack_rgba8, Texture};
        use fovea_core::material::texture::{mip_level, sample_texture_lod};
        use fovea_core::scene::{SceneSlices, TEXTURE_MIPMAPPED};
        use glam::Vec2;
        let mut t = Texture::single_color("c", [0, 0, 0, 255], true);
        // 4 × 2: left half black, right half white (sRGB 255 = linear 1).
        t.width = 4;
        t.height = 2;
        let (black, white) = (pack_rgba8([0, 0, 0, 255]), pack_rgba8([255, 255, 255, 255]));
        t.texels = vec![black, black, white, white, black, black, white, white];
        let scene = textured_triangle(vec![t]);
        let words = packed_texel_words(&scene.textures);
        let packed = pack_scene(scene, &Environment::None, &BvhBuildOptions::default());
        let info = packed.materials.textures[0];
        assert_ne!(info.flags & TEXTURE_MIPMAPPED, 0);
        // Levels 4 × 2, 2 × 1, 1 × 1: 11 texels of two words.
        assert_eq!(packed.materials.texels.len(), 22);
        assert!(packed.materials.texels.len() as u64 <= words);
        let l2 = mip_level(&info, 2);
        assert_eq!((l2.width, l2.height, l2.offset), (1, 1, 20));
        let view = packed.view();
        let at =
            |uv: Vec2, footprint: f32| sample_texture_lod(&view, &SceneSlices, 0, uv, footprint);
        // Level 0: the texel's own value; a footprint of one texel or less changes nothing.
        assert_eq!(at(Vec2::new(0.125, 0.25), 0.0).x, 0.0);
        assert_eq!(at(Vec2::new(0.125, 0.25), 0.3).x, 0.0);
        // The last level: the linear mean, 0.5 (an sRGB-code mean would be 128 -> 0.216).
        let coarse = at(Vec2::new(0.125, 0.25), 1.0e3);
        assert!((coarse.x - 0.5).abs() < 1e-4, "{coarse}");
        // Between levels 0 and 1 (sqrt(8) texels per unit footprint): a blend.
        let mid = at(Vec2::new(0.125, 0.25), 1.5 / 8f32.sqrt()).x;
        assert!(mid > 0.0 && mid < 0.5, "{mid}");
    }

    /// The glTF sampler's addressing and filter reach the lookups: repeat (the default) wraps, clamp
    /// holds the edge texel, mirror reflects, nearest reads one texel; a sampler without mip-mapping
    /// gets no levels.
    #[test]
    fn sampler_addressing_and_filters() {
        use crate::texture::{pack_rgba8, Texture, NO_MIP_LEVELS};
        use fovea_core::material::texture::sample_texture;
        use fovea_core::scene::{
            SceneSlices, TEXTURE_CLAMP_S, TEXTURE_MIPMAPPED, TEXTURE_MIRROR_S, TEXTURE_NEAREST,
        };
        use glam::Vec2;
        // Data textures (stored as they are): 4 × 1 texels of red 0, 85, 170, 255.
        let texture = |sampler: u32| {
            let mut t = Texture::single_color("t", [0, 0, 0, 255], false);
            t.width = 4;
            t.texels = [0u8, 85, 170, 255]
                .iter()
                .map(|&r| pack_rgba8([r, 0, 0, 255]))
                .collect();
            t.sampler = sampler;
            t
        };
        let scene = textured_triangle(vec![
            texture(0),
            texture(TEXTURE_CLAMP_S),
            texture(TEXTURE_MIRROR_S),
            texture(TEXTURE_NEAREST | NO_MIP_LEVELS),
        ]);
        let packed = pack_scene(scene, &Environment::None, &BvhBuildOptions::default());
        let view = packed.view();
        let red =
            |k: u32, u: f32| sample_texture(&view, &SceneSlices, k, Vec2::new(u, 0.5)).x * 255.0;
        let close = |a: f32, b: f32| (a - b).abs() < 1e-3;
        // u = 1.125 is texel 0's centre one period on: repeat reads texel 0, clamp the last texel, mirror
        // texel 3 (the reflected copy starts with the last texel).
        assert!(close(red(0, 1.125), 0.0), "{}", red(0, 1.125));
        assert!(close(red(1, 1.125), 255.0), "{}", red(1, 1.125));
        assert!(close(red(2, 1.125), 255.0), "{}", red(2, 1.125));
        // Between texels 0 and 1: bilinear blends, nearest takes the texel the point is in.
        assert!(close(red(0, 0.25), 42.5), "{}", red(0, 0.25));
        assert!(close(red(3, 0.24), 0.0) && close(red(3, 0.26), 85.0));
        // Repeat at the left edge blends with the last texel; clamp does not.
        assert!(close(red(0, 0.0), 127.5) && close(red(1, 0.0), 0.0));
        let flags: Vec<u32> = packed.materials.textures.iter().map(|t| t.flags).collect();
        assert!(flags[..3].iter().all(|f| f & TEXTURE_MIPMAPPED != 0));
        assert_eq!(flags[3] & TEXTURE_MIPMAPPED, 0);
    }

    /// A texture's coordinate transform (`KHR_texture_transform`) maps the lookup's coordinates first:
    /// scale 2 reads at twice the coordinate, an offset shifts it.
    #[test]
    fn texture_transform_maps_coordinates() {
        use crate::texture::{pack_rgba8, Texture};
        use fovea_core::material::texture::sample_texture;
        use fovea_core::scene::{SceneSlices, TEXTURE_TRANSFORMED};
        use glam::Vec2;
        let texture = |transform: Option<[f32; 6]>| {
            let mut t = Texture::single_color("t", [0, 0, 0, 255], false);
            t.width = 4;
            t.texels = [0u8, 85, 170, 255]
                .iter()
                .map(|&r| pack_rgba8([r, 0, 0, 255]))
                .collect();
            t.transform = transform;
            t
        };
        let scene = textured_triangle(vec![
            texture(None),
            texture(Some([2.0, 0.0, 0.0, 1.0, 0.0, 0.0])),
            texture(Some([1.0, 0.0, 0.0, 1.0, 0.25, 0.0])),
        ]);
        let packed = pack_scene(scene, &Environment::None, &BvhBuildOptions::default());
        assert_eq!(packed.materials.textures[0].flags & TEXTURE_TRANSFORMED, 0);
        assert_ne!(packed.materials.textures[1].flags & TEXTURE_TRANSFORMED, 0);
        let view = packed.view();
        let red =
            |k: u32, u: f32| sample_texture(&view, &SceneSlices, k, Vec2::new(u, 0.5)).x * 255.0;
        // Texel 1's centre is u = 0.375: reached at 0.1875 with scale 2, at 0.125 with offset 0.25.
        assert!((red(0, 0.375) - 85.0).abs() < 1e-3);
        assert!((red(1, 0.1875) - 85.0).abs() < 1e-3, "{}", red(1, 0.1875));
        assert!((red(2, 0.125) - 85.0).abs() < 1e-3, "{}", red(2, 0.125));
    }
}
