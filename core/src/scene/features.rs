//! The optional features a scene uses, so that shading code can leave out what a scene does not need.
//!
//! [`FeatureFlags::of_scene`] derives the set from the packed scene at load (materials, textures, lights,
//! environment, vertex attributes). Core functions take a [`Features`] value and test it before each
//! optional step (a texture fetch, an alpha test, a Disney lobe, a light kind). Two implementations:
//! - [`StaticFeatures<BITS>`]: the mask is a constant, so after inlining the tests fold away and absent
//!   features cost nothing: the CPU host's monomorphised render paths.
//! - [`FeatureFlags`]: the mask is a value: the general path, and on the GPU the kernel's specialization
//!   constant, which the driver folds when it compiles the pipeline.
//!
//! A feature's test may only skip work whose result is provably zero or a no-op for scenes without the
//! feature, and must not change which random numbers are drawn: a specialised render is bit-identical to
//! the general one.
use super::layout::{
    Light, Material, SceneGlobals, ENVIRONMENT_CONSTANT, ENVIRONMENT_MAP, INVALID_INDEX,
    LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, LIGHT_TRIANGLE, MATERIAL_ALPHA_CUTOUT,
};

/// A base-colour texture on some material.
pub const FEATURE_BASE_COLOR_TEXTURE: u32 = 1 << 0;
/// A metallic-roughness texture on some material.
pub const FEATURE_METALLIC_ROUGHNESS_TEXTURE: u32 = 1 << 1;
/// A normal map on some material.
pub const FEATURE_NORMAL_TEXTURE: u32 = 1 << 2;
/// An emission texture on some material.
pub const FEATURE_EMISSION_TEXTURE: u32 = 1 << 3;
/// Alpha cut-outs (glTF `MASK`, OBJ `map_d`/`d`): traversal must test opacity.
pub const FEATURE_ALPHA_CUTOUT: u32 = 1 << 4;
/// Emissive triangles.
pub const FEATURE_EMISSIVE_TRIANGLES: u32 = 1 << 5;
/// A constant environment.
pub const FEATURE_ENVIRONMENT_CONSTANT: u32 = 1 << 6;
/// An HDR environment map.
pub const FEATURE_ENVIRONMENT_MAP: u32 = 1 << 7;
/// KHR_lights_punctual point, spot or directional lights.
pub const FEATURE_PUNCTUAL_LIGHTS: u32 = 1 << 8;
/// Some material has `sheen > 0`.
pub const FEATURE_LOBE_SHEEN: u32 = 1 << 9;
/// Some material has `clearcoat > 0`.
pub const FEATURE_LOBE_CLEARCOAT: u32 = 1 << 10;
/// Some material has `anisotropic != 0`.
pub const FEATURE_LOBE_ANISOTROPY: u32 = 1 << 11;
/// Some material has a specular (GGX) reflection: `specular > 0` or `metallic > 0`. With both zero the
/// Disney specular lobe vanishes (F0 = 0 and, with the F90 fade of `bsdf::disney`, no grazing Fresnel).
pub const FEATURE_LOBE_SPECULAR: u32 = 1 << 12;
/// Some material has `metallic > 0` (or a metallic-roughness texture).
pub const FEATURE_LOBE_METALLIC: u32 = 1 << 13;
/// Per-vertex shading normals.
pub const FEATURE_SHADING_NORMALS: u32 = 1 << 14;
/// Per-vertex texture coordinates (needed by textures and by the tangent of anisotropy).
pub const FEATURE_UVS: u32 = 1 << 15;
/// The rough dielectric interface of transmissive materials ([`crate::bsdf::dielectric`]).
pub const FEATURE_LOBE_TRANSMISSION: u32 = 1 << 16;

/// A glTF extension's texture (transmission, clear coat, sheen, specular, anisotropy) on some material.
pub const FEATURE_EXTENSION_TEXTURES: u32 = 1 << 17;
/// Some transmissive material's inside absorbs (`Material::absorption`, glTF `KHR_materials_volume`).
pub const FEATURE_VOLUME_ABSORPTION: u32 = 1 << 18;
/// Per-vertex colours (glTF `COLOR_0`), which multiply the base colour and opacity
/// ([`crate::material::vertex_color`]).
pub const FEATURE_VERTEX_COLORS: u32 = 1 << 19;

/// Every feature: the general render path (`--no-specialize`).
pub const FEATURES_ALL: u32 = (1 << 20) - 1;

/// Names of the feature bits, bit `i` at index `i` (for `--verbose` and `--stats`).
pub const FEATURE_NAMES: [&str; 20] = [
    "base_color_texture",
    "metallic_roughness_texture",
    "normal_texture",
    "emission_texture",
    "alpha_cutout",
    "emissive_triangles",
    "environment_constant",
    "environment_map",
    "punctual_lights",
    "lobe_sheen",
    "lobe_clearcoat",
    "lobe_anisotropy",
    "lobe_specular",
    "lobe_metallic",
    "shading_normals",
    "uvs",
    "lobe_transmission",
    "extension_textures",
    "volume_absorption",
    "vertex_colors",
];

/// Which per-vertex arrays a scene has (each empty or one entry per vertex).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VertexAttributes {
    /// Shading normals ([`FEATURE_SHADING_NORMALS`]).
    pub normals: bool,
    /// Texture coordinates ([`FEATURE_UVS`]).
    pub uvs: bool,
    /// Colours ([`FEATURE_VERTEX_COLORS`]).
    pub colors: bool,
}

/// A set of features to test against; see the module documentation.
pub trait Features: Copy {
    /// The `FEATURE_*` mask.
    #[must_use]
    fn bits(self) -> u32;

    /// Whether any of the features in `mask` may occur.
    #[inline]
    #[must_use]
    fn has(self, mask: u32) -> bool {
        self.bits() & mask != 0
    }
}

/// A feature mask known at compile time: tests of absent features fold to `false`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StaticFeatures<const BITS: u32>;

impl<const BITS: u32> Features for StaticFeatures<BITS> {
    #[inline(always)]
    fn bits(self) -> u32 {
        BITS
    }
}

/// A feature mask held as a value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FeatureFlags(pub u32);

impl Features for FeatureFlags {
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0
    }
}

impl Default for FeatureFlags {
    /// Every feature on.
    fn default() -> Self {
        Self(FEATURES_ALL)
    }
}

impl FeatureFlags {
    /// Every feature on: the general path.
    pub const ALL: Self = Self(FEATURES_ALL);

    /// The features of the scene described by its materials, lights, globals and vertex-attribute arrays.
    // Index loops: the rust-gpu subset of this crate has no slice iterators.
    #[allow(clippy::needless_range_loop)]
    #[must_use]
    pub fn of_scene(
        globals: &SceneGlobals,
        materials: &[Material],
        lights: &[Light],
        vertices: VertexAttributes,
    ) -> Self {
        let mut bits = 0u32;
        for i in 0..materials.len() {
            bits |= Self::of_material(&materials[i]);
        }
        for i in 0..lights.len() {
            let kind = lights[i].kind;
            if kind == LIGHT_TRIANGLE {
                bits |= FEATURE_EMISSIVE_TRIANGLES;
            } else if kind == LIGHT_POINT || kind == LIGHT_SPOT || kind == LIGHT_DIRECTIONAL {
                bits |= FEATURE_PUNCTUAL_LIGHTS;
            }
        }
        if globals.environment_kind == ENVIRONMENT_CONSTANT {
            bits |= FEATURE_ENVIRONMENT_CONSTANT;
        } else if globals.environment_kind == ENVIRONMENT_MAP {
            bits |= FEATURE_ENVIRONMENT_MAP;
        }
        if vertices.normals {
            bits |= FEATURE_SHADING_NORMALS;
        }
        if vertices.uvs {
            bits |= FEATURE_UVS;
        }
        if vertices.colors {
            bits |= FEATURE_VERTEX_COLORS;
        }
        Self(bits)
    }

    /// The features one material needs. An emissive material counts as emissive triangles even when
    /// the light list has none (a BSDF-sampled ray can still find it).
    #[must_use]
    pub fn of_material(m: &Material) -> u32 {
        let mut bits = 0u32;
        if m.base_color_texture != INVALID_INDEX {
            bits |= FEATURE_BASE_COLOR_TEXTURE;
        }
        if m.metallic_roughness_texture != INVALID_INDEX {
            bits |= FEATURE_METALLIC_ROUGHNESS_TEXTURE;
        }
        if m.normal_texture != INVALID_INDEX {
            bits |= FEATURE_NORMAL_TEXTURE;
        }
        if m.emission_texture != INVALID_INDEX {
            bits |= FEATURE_EMISSION_TEXTURE;
        }
        if m.flags & MATERIAL_ALPHA_CUTOUT != 0 {
            bits |= FEATURE_ALPHA_CUTOUT;
        }
        if m.is_emissive() || m.emission_texture != INVALID_INDEX {
            bits |= FEATURE_EMISSIVE_TRIANGLES;
        }
        // `!(x == 0)` so that a NaN parameter keeps its lobe (the general path's behaviour).
        if !(m.sheen == 0.0) {
            bits |= FEATURE_LOBE_SHEEN;
        }
        if !(m.clearcoat == 0.0) {
            bits |= FEATURE_LOBE_CLEARCOAT;
        }
        if !(m.anisotropic == 0.0) {
            bits |= FEATURE_LOBE_ANISOTROPY;
        }
        let metallic = !(m.metallic == 0.0) || m.metallic_roughness_texture != INVALID_INDEX;
        if metallic {
            bits |= FEATURE_LOBE_METALLIC;
        }
        if metallic || !(m.specular == 0.0) {
            bits |= FEATURE_LOBE_SPECULAR;
        }
        if !(m.transmission == 0.0) {
            bits |= FEATURE_LOBE_TRANSMISSION;
            if m.absorbs() {
                bits |= FEATURE_VOLUME_ABSORPTION;
            }
        }
        if m.has_extension_texture() {
            bits |= FEATURE_EXTENSION_TEXTURES;
        }
        bits
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_cover_every_bit() {
        assert_eq!(FEATURE_NAMES.len() as u32, FEATURES_ALL.count_ones());
    }

    #[test]
    fn a_plain_diffuse_material_needs_nothing_optional() {
        let m = Material {
            specular: 0.0,
            ..Material::default()
        };
        assert_eq!(FeatureFlags::of_material(&m), 0);
        let default_specular = Material::default();
        assert_eq!(
            FeatureFlags::of_material(&default_specular),
            FEATURE_LOBE_SPECULAR
        );
    }

    #[test]
    fn scene_features_collect_lights_environment_and_attributes() {
        let globals = SceneGlobals {
            environment_kind: ENVIRONMENT_MAP,
            ..SceneGlobals::default()
        };
        let lights = [
            Light {
                kind: LIGHT_TRIANGLE,
                ..Light::default()
            },
            Light {
                kind: LIGHT_SPOT,
                ..Light::default()
            },
        ];
        let materials = [Material {
            clearcoat: 1.0,
            flags: MATERIAL_ALPHA_CUTOUT,
            base_color_texture: 0,
            ..Material::default()
        }];
        let vertices = VertexAttributes {
            normals: true,
            uvs: false,
            colors: true,
        };
        let f = FeatureFlags::of_scene(&globals, &materials, &lights, vertices);
        let want = FEATURE_EMISSIVE_TRIANGLES
            | FEATURE_PUNCTUAL_LIGHTS
            | FEATURE_ENVIRONMENT_MAP
            | FEATURE_LOBE_CLEARCOAT
            | FEATURE_LOBE_SPECULAR
            | FEATURE_ALPHA_CUTOUT
            | FEATURE_BASE_COLOR_TEXTURE
            | FEATURE_SHADING_NORMALS
            | FEATURE_VERTEX_COLORS;
        assert_eq!(f.0, want);
        assert!(f.has(FEATURE_ENVIRONMENT_MAP));
        assert!(!StaticFeatures::<0>.has(FEATURE_ENVIRONMENT_MAP));
    }
}
