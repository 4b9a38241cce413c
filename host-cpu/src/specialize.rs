//! The CPU's specialised render paths: the per-sample integrator monomorphised over a handful of
//! compile-time feature masks ([`StaticFeatures`]), one chosen per scene at render time.
//!
//! A path exists for every combination of three feature groups that scenes tend to have or lack together:
//! textures and cut-outs; glossy reflection (the GGX specular lobe, metals); and the rarer features
//! (environment maps, punctual lights, sheen, clearcoat, anisotropy, transmission, the glTF
//! extensions' textures, volume absorption, vertex colours). Every path keeps the features
//! nearly every scene has (emissive triangles, a constant sky, shading normals). A scene runs the
//! smallest path that covers its features, so only the groups it lacks are compiled out; eight copies of
//! the integrator keep the build time and binary size in check. `FeatureFlags::ALL` (the
//! `--no-specialize` view) selects the path with every group.
use fovea_core::scene::features::*;
use fovea_core::scene::{Features, SceneView, StaticFeatures};

/// Features every path keeps.
pub const GROUP_BASE: u32 =
    FEATURE_EMISSIVE_TRIANGLES | FEATURE_ENVIRONMENT_CONSTANT | FEATURE_SHADING_NORMALS;
/// Textures, alpha cut-outs and the texture coordinates they read.
pub const GROUP_TEXTURES: u32 = FEATURE_BASE_COLOR_TEXTURE
    | FEATURE_METALLIC_ROUGHNESS_TEXTURE
    | FEATURE_NORMAL_TEXTURE
    | FEATURE_EMISSION_TEXTURE
    | FEATURE_ALPHA_CUTOUT
    | FEATURE_UVS;
/// Glossy reflection: the GGX specular lobe and metals.
pub const GROUP_GLOSSY: u32 = FEATURE_LOBE_SPECULAR | FEATURE_LOBE_METALLIC;
/// The rarer features: environment maps, punctual lights, the sheen, clearcoat, anisotropy and
/// transmission lobes, the glTF extensions' textures, volume absorption and vertex colours.
pub const GROUP_RARE: u32 = FEATURE_ENVIRONMENT_MAP
    | FEATURE_PUNCTUAL_LIGHTS
    | FEATURE_LOBE_SHEEN
    | FEATURE_LOBE_CLEARCOAT
    | FEATURE_LOBE_ANISOTROPY
    | FEATURE_LOBE_TRANSMISSION
    | FEATURE_EXTENSION_TEXTURES
    | FEATURE_VOLUME_ABSORPTION
    | FEATURE_VERTEX_COLORS;

const V0: u32 = GROUP_BASE;
const V1: u32 = GROUP_BASE | GROUP_TEXTURES;
const V2: u32 = GROUP_BASE | GROUP_GLOSSY;
const V3: u32 = GROUP_BASE | GROUP_TEXTURES | GROUP_GLOSSY;
const V4: u32 = GROUP_BASE | GROUP_RARE;
const V5: u32 = GROUP_BASE | GROUP_TEXTURES | GROUP_RARE;
const V6: u32 = GROUP_BASE | GROUP_GLOSSY | GROUP_RARE;
const V7: u32 = GROUP_BASE | GROUP_TEXTURES | GROUP_GLOSSY | GROUP_RARE;

/// The feature mask of the path that renders a scene with features `mask`: the smallest compiled one
/// that contains it.
#[must_use]
pub fn path_mask(mask: u32) -> u32 {
    let mut path = GROUP_BASE;
    if mask & GROUP_TEXTURES != 0 {
        path |= GROUP_TEXTURES;
    }
    if mask & GROUP_GLOSSY != 0 {
        path |= GROUP_GLOSSY;
    }
    if mask & GROUP_RARE != 0 {
        path |= GROUP_RARE;
    }
    path
}

/// Something to run with a scene view of some static feature set (a generic closure, which Rust lacks).
pub trait WithScene {
    type Output;
    fn run<F: Features + Sync>(self, scene: &SceneView<'_, F>) -> Self::Output;
}

/// Runs `job` on `scene` viewed through the compiled path for the scene view's feature mask.
pub fn dispatch<J: WithScene>(scene: &SceneView<'_>, job: J) -> J::Output {
    match path_mask(scene.features.bits()) {
        V0 => job.run(&scene.with_features(StaticFeatures::<V0>)),
        V1 => job.run(&scene.with_features(StaticFeatures::<V1>)),
        V2 => job.run(&scene.with_features(StaticFeatures::<V2>)),
        V3 => job.run(&scene.with_features(StaticFeatures::<V3>)),
        V4 => job.run(&scene.with_features(StaticFeatures::<V4>)),
        V5 => job.run(&scene.with_features(StaticFeatures::<V5>)),
        V6 => job.run(&scene.with_features(StaticFeatures::<V6>)),
        _ => job.run(&scene.with_features(StaticFeatures::<V7>)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_feature_belongs_to_a_group_and_paths_cover_their_scenes() {
        assert_eq!(
            GROUP_BASE | GROUP_TEXTURES | GROUP_GLOSSY | GROUP_RARE,
            FEATURES_ALL
        );
        for mask in 0..=FEATURES_ALL {
            let path = path_mask(mask);
            assert_eq!(
                path & mask,
                mask,
                "path {path:#x} misses features of {mask:#x}"
            );
        }
        assert_eq!(path_mask(FEATURES_ALL), FEATURES_ALL);
        assert_eq!(path_mask(FEATURE_EMISSIVE_TRIANGLES), GROUP_BASE);
    }
}
