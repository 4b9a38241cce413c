//! The lights group: the list next-event estimation picks from (emissive triangles, punctual lights, the
//! environment), its selection table by power, and each triangle's entry
//! ([`fovea_core::scene::LightArrays`]).
use fovea_core::kernel_abi::{BINDING_LIGHTS, BINDING_LIGHT_CDF, BINDING_TRIANGLE_LIGHT};
use fovea_core::lights::power;
use fovea_core::scene::{
    positions_at, Light, LightArrays, SceneGlobals, ENVIRONMENT_NONE, INVALID_INDEX,
    LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_SPOT, LIGHT_TRIANGLE,
    MATERIAL_DOUBLE_SIDED_EMISSION, MATERIAL_UNLIT,
};
use glam::Vec3;

use super::array::{ArrayRead, PackedArray};
use super::geometry::PackedGeometry;
use super::materials::{mean_texture_color, PackedMaterials};
use crate::environment::{build_cdf, Environment};
use crate::texture::Texture;

/// The light arrays, owned.
#[derive(Clone, Debug, Default)]
pub struct PackedLights {
    pub list: Vec<Light>,
    pub cdf: Vec<f32>,
    pub triangle_light: Vec<u32>,
}

impl PackedLights {
    /// The borrowed view core reads.
    #[must_use]
    pub fn view(&self) -> LightArrays<'_> {
        LightArrays {
            list: &self.list,
            cdf: &self.cdf,
            triangle_light: &self.triangle_light,
        }
    }

    /// The arrays the GPU receives, each with its binding (storage buffers of their own).
    #[must_use]
    pub fn gpu_arrays(&self) -> [PackedArray<'_>; 3] {
        use ArrayRead::Storage;
        [
            PackedArray::new(BINDING_LIGHTS, "lights", Storage, &self.list),
            PackedArray::new(BINDING_LIGHT_CDF, "light CDF", Storage, &self.cdf),
            PackedArray::new(
                BINDING_TRIANGLE_LIGHT,
                "triangle lights",
                Storage,
                &self.triangle_light,
            ),
        ]
    }
}

/// What the lights are packed from.
pub(super) struct LightSources<'a> {
    pub geometry: &'a PackedGeometry,
    pub materials: &'a PackedMaterials,
    /// The loaded textures (an emissive texture's mean colour scales its triangles' power).
    pub textures: &'a [Texture],
    pub punctual: &'a [Light],
    pub environment: &'a Environment,
    /// Radius of the scene's bounding sphere (a directional or environment light's power is over it).
    pub radius: f32,
}

/// The light list in the order emissive triangles, punctual lights, environment, each with a
/// selection probability proportional to its power (`fovea_core::lights::power`); lights of no power are
/// left out. Sets `globals.light_count` and `globals.environment_light`.
pub(super) fn pack_lights(
    sources: &LightSources,
    globals: &mut SceneGlobals,
) -> (PackedLights, usize) {
    let mut lights: Vec<Light> = Vec::new();
    let mut light_power: Vec<f64> = Vec::new();
    let (triangle_light, emissive_triangle_count) =
        emissive_triangles(sources, &mut lights, &mut light_power);

    for l in sources.punctual {
        let intensity = Vec3::from_slice(&l.intensity);
        let p = match l.kind {
            LIGHT_POINT => power::point_power(intensity),
            LIGHT_SPOT => power::spot_power(intensity, l.position[3], l.intensity[3]),
            LIGHT_DIRECTIONAL => power::directional_power(intensity, sources.radius),
            _ => 0.0,
        };
        if p > 0.0 && p.is_finite() {
            lights.push(Light { pmf: 0.0, ..*l });
            light_power.push(p as f64);
        }
    }

    globals.environment_light = INVALID_INDEX;
    if globals.environment_kind != ENVIRONMENT_NONE {
        let p = power::environment_power(sources.environment.mean_radiance(), sources.radius);
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

    let cdf = if lights.is_empty() {
        Vec::new()
    } else {
        build_cdf(&light_power).0
    };
    for (i, l) in lights.iter_mut().enumerate() {
        l.pmf = cdf[i + 1] - cdf[i];
    }
    globals.light_count = lights.len() as u32;
    let packed = PackedLights {
        list: lights,
        cdf,
        triangle_light,
    };
    (packed, emissive_triangle_count)
}

/// Appends one light per emissive triangle of non-zero power to `lights` (and its power to
/// `light_power`); returns each triangle's light index (empty when no triangle is a light) and the
/// count.
fn emissive_triangles(
    sources: &LightSources,
    lights: &mut Vec<Light>,
    light_power: &mut Vec<f64>,
) -> (Vec<u32>, usize) {
    let materials = &sources.materials.list;
    let is_light =
        |m: &fovea_core::scene::Material| m.is_emissive() && m.flags & MATERIAL_UNLIT == 0;
    if !materials.iter().any(is_light) {
        return (Vec::new(), 0);
    }
    let geometry = sources.geometry;
    let mut triangle_light = vec![INVALID_INDEX; geometry.triangle_info.len()];
    let mut count = 0;
    // Each emission texture's mean colour, averaged once however many triangles use it.
    let mut texture_means: Vec<Option<Vec3>> = vec![None; sources.textures.len()];
    for (i, (&at, info)) in geometry
        .triangle_lanes
        .iter()
        .zip(&geometry.triangle_info)
        .enumerate()
    {
        let m = &materials[info.material as usize];
        if !is_light(m) {
            continue;
        }
        let t = positions_at(&geometry.blocks, at);
        let (v0, v1, v2) = (t.v0.truncate(), t.v1.truncate(), t.v2.truncate());
        let area = 0.5 * (v1 - v0).cross(v2 - v0).length();
        if !(area > 0.0) || !area.is_finite() {
            continue;
        }
        let mut radiance = Vec3::from_slice(&m.emission);
        if m.emission_texture != INVALID_INDEX {
            let k = m.emission_texture as usize;
            radiance *=
                *texture_means[k].get_or_insert_with(|| mean_texture_color(&sources.textures[k]));
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
        count += 1;
    }
    if count == 0 {
        triangle_light.clear();
    }
    (triangle_light, count)
}
