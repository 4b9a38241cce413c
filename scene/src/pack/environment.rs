//! The environment group: an equirectangular map and its importance-sampling tables
//! ([`fovea_core::scene::EnvironmentArrays`]); a constant environment or none needs only the globals.
use fovea_core::kernel_abi::{
    BINDING_ENVIRONMENT_CONDITIONAL, BINDING_ENVIRONMENT_MARGINAL, BINDING_ENVIRONMENT_TEXELS,
};
use fovea_core::scene::{
    EnvironmentArrays, SceneGlobals, ENVIRONMENT_CONSTANT, ENVIRONMENT_MAP, ENVIRONMENT_NONE,
};

use super::array::{ArrayRead, PackedArray};
use crate::environment::{Environment, EnvironmentTables};

/// The environment arrays, owned (empty unless the environment is a map).
#[derive(Clone, Debug, Default)]
pub struct PackedEnvironment {
    pub texels: Vec<[f32; 4]>,
    pub marginal_cdf: Vec<f32>,
    pub conditional_cdf: Vec<f32>,
}

impl PackedEnvironment {
    /// The borrowed view core reads.
    #[must_use]
    pub fn view(&self) -> EnvironmentArrays<'_> {
        EnvironmentArrays {
            texels: &self.texels,
            marginal_cdf: &self.marginal_cdf,
            conditional_cdf: &self.conditional_cdf,
        }
    }

    /// The arrays the GPU receives, each with its binding (storage buffers of their own).
    #[must_use]
    pub fn gpu_arrays(&self) -> [PackedArray<'_>; 3] {
        use ArrayRead::Storage;
        [
            PackedArray::new(
                BINDING_ENVIRONMENT_TEXELS,
                "environment texels",
                Storage,
                &self.texels,
            ),
            PackedArray::new(
                BINDING_ENVIRONMENT_MARGINAL,
                "environment marginal CDF",
                Storage,
                &self.marginal_cdf,
            ),
            PackedArray::new(
                BINDING_ENVIRONMENT_CONDITIONAL,
                "environment conditional CDF",
                Storage,
                &self.conditional_cdf,
            ),
        ]
    }
}

/// Packs `environment`, setting its kind, radiance, size and integral in `globals` (its light, if any,
/// is added with the other lights: `super::lights`).
pub(super) fn pack_environment(
    environment: &Environment,
    globals: &mut SceneGlobals,
) -> PackedEnvironment {
    match environment {
        Environment::None => {
            globals.environment_kind = ENVIRONMENT_NONE;
            PackedEnvironment::default()
        }
        Environment::Constant(c) => {
            globals.environment_kind = ENVIRONMENT_CONSTANT;
            globals.environment_radiance = [c[0], c[1], c[2], 0.0];
            PackedEnvironment::default()
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
            PackedEnvironment {
                texels: texels.clone(),
                marginal_cdf: tables.marginal_cdf,
                conditional_cdf: tables.conditional_cdf,
            }
        }
    }
}
