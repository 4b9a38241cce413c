//! Finding, loading and packing the scene, and choosing its camera and sky.
use std::path::{Path, PathBuf};
use std::time::Instant;

use fovea_core::camera::Camera;
use fovea_scene::bvh::BvhBuildOptions;
use fovea_scene::environment::Environment;
use fovea_scene::mesh::{LoadOptions, LoadedScene, MtlDiffuse};
use fovea_scene::pack::{pack_scene, PackedScene};
use glam::Vec3;

use crate::args::LightingArgs;
use crate::error::{FoveaError, Result};
use crate::values::WorldPointLight;
use fovea_scene::rebase::to_local;

/// The bundled default scene: the paper's Lost Empire (CC BY 3.0, see assets/lost_empire/SOURCE.md).
pub fn default_scene_path() -> PathBuf {
    if let Some(dir) = std::env::var_os("FOVEA_ASSETS") {
        return PathBuf::from(dir).join("lost_empire/lost_empire.obj");
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/lost_empire/lost_empire.obj")
}

/// The view of the bundled Lost Empire: down the hillside towards the waterfall.
pub const LOST_EMPIRE_EYE: [f32; 3] = [-20.0, 30.0, 60.0];
pub const LOST_EMPIRE_TARGET: [f32; 3] = [5.0, 15.0, 20.0];
pub const LOST_EMPIRE_FOV_DEG: f32 = 60.0;
/// The sky that lights the bundled scene (the paper's code used a constant probe).
pub const DEFAULT_SKY: [f32; 3] = [1.0, 1.0, 1.0];

/// A loaded and packed scene with its timings.
pub struct PreparedScene {
    pub packed: PackedScene,
    /// The world position of the scene's origin (`LoadedScene::origin`): the packed scene and its
    /// camera are relative to it.
    pub origin: [f64; 3],
    pub camera_desc: Option<fovea_scene::mesh::CameraDesc>,
    pub warnings: Vec<String>,
    pub load_ms: f64,
    pub bvh_ms: f64,
    pub pack_ms: f64,
    pub triangle_count: usize,
    pub is_default: bool,
    /// Every file the load read (the scene file, its MTL libraries, buffers and textures): the
    /// inputs no output may replace.
    pub files: Vec<std::path::PathBuf>,
    /// What the scene's files give that fovea's mapping does not use (`LoadedScene::unused`).
    pub unused: Vec<String>,
}

/// The warning for a scene with no light and no sky (`render` and `view` print it and list it in
/// `--stats`).
pub const NO_LIGHT_WARNING: &str =
    "the scene has no light and no sky: the image will be black (add \
                                    --sky R,G,B or --point-light X,Y,Z,R,G,B)";

/// Given when a rendered image is black although the scene has lights: none of their light reached the
/// camera (e.g. the bundled Lost Empire named by its path: the camera then frames the whole map from
/// outside, without the bundled sky, and the lava is inside).
pub const BLACK_IMAGE_WARNING: &str = "the image is black: no light reached the camera (a scene \
     named by its file gets no bundled sky, and its own lights may be hidden from this view): add \
     --sky R,G,B, --env-map FILE or --point-light X,Y,Z,R,G,B, or raise --exposure";

/// Loads `path` (or the default scene; OBJ materials from `mtl_override` if given, purely diffuse ones
/// as `mtl_diffuse` says), adds `environment` and the `extra_lights` (point lights from the command line)
/// and packs it, with the CPU's 8-wide tree if `wide_bvh` (see
/// [`crate::backend::Renderer::wants_wide_bvh`]).
pub fn prepare_scene(
    path: Option<&Path>,
    mtl_override: Option<&Path>,
    mtl_diffuse: MtlDiffuse,
    environment: &Environment,
    extra_lights: &[WorldPointLight],
    wide_bvh: bool,
) -> Result<PreparedScene> {
    let is_default = path.is_none();
    let path = path
        .map(Path::to_path_buf)
        .unwrap_or_else(default_scene_path);
    let options = LoadOptions {
        mtl_override: mtl_override.map(Path::to_path_buf),
        mtl_diffuse,
        ..Default::default()
    };
    let start = Instant::now();
    let source = fovea_scene::source::RecordingFilesystem::default();
    let mut loaded: LoadedScene = fovea_scene::load_scene_from(&source, &path, &options)?;
    let origin = loaded.origin;
    loaded
        .punctual_lights
        .extend(extra_lights.iter().map(|l| l.in_scene(origin)));
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let camera_desc = loaded.camera;
    let warnings = loaded.warnings.clone();
    let unused = loaded.unused.clone();
    let triangle_count = loaded.triangles.len();
    let options = BvhBuildOptions {
        wide: wide_bvh,
        ..BvhBuildOptions::default()
    };
    let packed = pack_scene(loaded, environment, &options);
    Ok(PreparedScene {
        bvh_ms: packed.stats.bvh.build_ms,
        pack_ms: packed.stats.pack_ms,
        packed,
        origin,
        camera_desc,
        warnings,
        load_ms,
        triangle_count,
        is_default,
        files: source.files(),
        unused,
    })
}

/// The camera, in the scene's coordinates: explicit `--eye/--target` (world space) first, then the
/// scene's own camera, then the bundled view of the default scene, then a view that frames the scene's
/// bounds.
pub fn choose_camera(
    scene: &PreparedScene,
    eye: Option<[f64; 3]>,
    target: Option<[f64; 3]>,
    up: [f32; 3],
    fov_deg: Option<f32>,
    aspect: f32,
) -> Result<Camera> {
    let up = Vec3::from(up);
    if up.length_squared() == 0.0 {
        return Err(FoveaError::option("--up", "the up vector must not be zero"));
    }
    let fov = |default_deg: f32| fov_deg.unwrap_or(default_deg).to_radians();
    if let Some(f) = fov_deg {
        if !(f > 0.0 && f < 180.0) {
            return Err(FoveaError::option(
                "--fov",
                format!("{f} is not in (0, 180) degrees"),
            ));
        }
    }
    match (eye, target) {
        (Some(e), Some(t)) => {
            if e == t {
                return Err(FoveaError::option(
                    "--eye/--target",
                    "eye and target are the same point",
                ));
            }
            let local = |p: [f64; 3]| Vec3::from(to_local(p, scene.origin));
            return Ok(Camera::look_at(local(e), local(t), up, fov(45.0), aspect));
        }
        (Some(_), None) | (None, Some(_)) => {
            return Err(FoveaError::option(
                "--eye/--target",
                "give both --eye and --target",
            ));
        }
        (None, None) => {}
    }
    if let Some(c) = &scene.camera_desc {
        let yfov = fov_deg.map(f32::to_radians).unwrap_or(c.yfov_radians);
        return Ok(Camera::from_forward(
            Vec3::from(c.position),
            Vec3::from(c.forward),
            Vec3::from(c.up),
            yfov,
            aspect,
        ));
    }
    if scene.is_default {
        let local = |p: [f32; 3]| Vec3::from(to_local(p.map(f64::from), scene.origin));
        return Ok(Camera::look_at(
            local(LOST_EMPIRE_EYE),
            local(LOST_EMPIRE_TARGET),
            up,
            fov(LOST_EMPIRE_FOV_DEG),
            aspect,
        ));
    }
    // Frame the bounding sphere from the +z side, slightly above.
    let (lo, hi) = (scene.packed.bounds_min, scene.packed.bounds_max);
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let fov_rad = fov(45.0);
    let distance = radius / (0.5 * fov_rad).tan().max(1e-3) * 1.05;
    let dir = Vec3::new(0.0, 0.15, 1.0).normalize();
    Ok(Camera::look_at(
        centre + dir * distance,
        centre,
        up,
        fov_rad,
        aspect,
    ))
}

/// The light options of `render` and `report`, checked: a constant sky or an environment map (not both;
/// neither: the bundled scene's own sky, or none) and point lights.
#[derive(Default)]
pub struct Lighting {
    sky: Option<[f32; 3]>,
    /// The loaded map with its path and scale (for the reference cache key).
    map: Option<(Environment, PathBuf, f32)>,
    pub point_lights: Vec<WorldPointLight>,
}

impl Lighting {
    /// Parses and checks the options and loads `--env-map`.
    pub fn from_args(args: &LightingArgs) -> Result<Self> {
        if args.sky.is_some() && args.env_map.is_some() {
            return Err(FoveaError::option(
                "--sky",
                "give either --sky or --env-map",
            ));
        }
        let sky = args.sky.map(|c| c.0);
        if !(args.env_scale.is_finite() && args.env_scale >= 0.0) {
            return Err(FoveaError::option(
                "--env-scale",
                "must be a finite, non-negative number",
            ));
        }
        if args.env_scale != 1.0 && args.env_map.is_none() {
            return Err(FoveaError::option(
                "--env-scale",
                "scales --env-map, and none is given (for a constant sky, scale --sky R,G,B)",
            ));
        }
        let point_lights = args.point_lights.iter().map(|l| l.0).collect();
        let map = match &args.env_map {
            Some(path) => Some((
                Environment::load_map(path, [args.env_scale; 3])?,
                path.clone(),
                args.env_scale,
            )),
            None => None,
        };
        Ok(Self {
            sky,
            map,
            point_lights,
        })
    }

    /// The environment of a scene; `is_default`: the bundled scene, lit by [`DEFAULT_SKY`] unless the
    /// options say otherwise.
    #[must_use]
    pub fn environment(&self, is_default: bool) -> Environment {
        match (&self.sky, &self.map) {
            (Some(c), _) => Environment::Constant(*c),
            (None, Some((map, ..))) => map.clone(),
            (None, None) if is_default => Environment::Constant(DEFAULT_SKY),
            (None, None) => Environment::None,
        }
    }

    /// A canonical description of [`Self::environment`] (part of the report's reference cache key).
    #[must_use]
    pub fn environment_key(&self, is_default: bool) -> String {
        match (&self.sky, &self.map) {
            (Some(c), _) => format!("constant {c:?}"),
            (None, Some((_, path, scale))) => {
                format!("map {} scale {}", path.display(), scale.to_bits())
            }
            (None, None) if is_default => format!("constant {DEFAULT_SKY:?}"),
            (None, None) => "none".into(),
        }
    }
}
