//! The interface between the Vulkan host and the rust-gpu kernel: descriptor bindings and the push
//! constants of every entry point ([`crate::integrator::FrameParams`] travels in a buffer). Both sides import these definitions, so they cannot drift apart.
//!
//! All bindings are storage buffers in descriptor set 0 (std430 layout, so the `#[repr(C)]` types of
//! [`crate::scene::layout`] map one to one). Buffers a scene does not need are bound as small dummies.
use bytemuck::{Pod, Zeroable};

/// `SceneGlobals` (one element).
pub const BINDING_GLOBALS: u32 = 0;
/// `Bvh4Node` array.
pub const BINDING_NODES: u32 = 1;
/// Triangle to block lane (`GeometryArrays::triangle_lanes`), `u32`.
pub const BINDING_TRIANGLE_LANES: u32 = 2;
/// `TriangleInfo` array.
pub const BINDING_TRIANGLE_INFO: u32 = 3;
/// Per-vertex normals `[f32; 4]`.
pub const BINDING_NORMALS: u32 = 4;
/// Per-vertex texture coordinates `[f32; 2]`.
pub const BINDING_UVS: u32 = 5;
/// Per-vertex colours `[u32; 2]` (four unorm16, `crate::material::vertex_color`). Numbered after the
/// frame's bindings because it came later; it belongs to the scene's geometry group.
pub const BINDING_VERTEX_COLORS: u32 = 31;
/// `Material` array.
pub const BINDING_MATERIALS: u32 = 6;
/// `TextureInfo` array.
pub const BINDING_TEXTURES: u32 = 7;
/// RGBA8 texels, `u32` each.
pub const BINDING_TEXELS: u32 = 8;
/// `Light` array.
pub const BINDING_LIGHTS: u32 = 9;
/// Light-selection CDF, `f32`.
pub const BINDING_LIGHT_CDF: u32 = 10;
/// Triangle to light index, `u32`.
pub const BINDING_TRIANGLE_LIGHT: u32 = 11;
/// Environment texels `[f32; 4]`.
pub const BINDING_ENVIRONMENT_TEXELS: u32 = 12;
/// Environment marginal CDF, `f32`.
pub const BINDING_ENVIRONMENT_MARGINAL: u32 = 13;
/// Environment conditional CDFs, `f32`.
pub const BINDING_ENVIRONMENT_CONDITIONAL: u32 = 14;
/// The blocks of one dispatch chunk: `[origin_x, origin_y, size, region]` each ([`crate::foveation::OwnedBlock`]).
pub const BINDING_BLOCKS: u32 = 15;
/// One radiance estimate per sample of the chunk (`[f32; 4]`, rgb + unused).
pub const BINDING_SAMPLES: u32 = 16;
/// The replicated image: every pixel holds its block's mean (`[f32; 4]`, width × height). The fill kernel
/// overwrites it with the filled image in place ([`crate::foveation::fill_value`]).
pub const BINDING_REPLICATED: u32 = 17;
/// Cell means of every block size above one (see `foveation::fill`).
pub const BINDING_CELL_MEANS: u32 = 18;
/// The filled linear HDR image (`[f32; 4]`, width × height) that tone mapping reads: the buffer of
/// [`BINDING_REPLICATED`], after the fill. No kernel binds both.
pub const BINDING_HDR: u32 = 19;
/// The tone-mapped image (RGBA8 packed in `u32`, width × height).
pub const BINDING_LDR: u32 = 20;
/// The frame's [`FrameParams`](crate::integrator::FrameParams) (one element; a buffer rather than push
/// constants because it is larger than the 128 bytes of push constants Vulkan guarantees).
pub const BINDING_FRAME: u32 = 21;
/// The scene's large arrays (nodes, triangle blocks and positions, triangle info, materials, normals,
/// texture coordinates, texture infos and texels) again, as one storage texel buffer (`R32G32B32A32_UINT`)
/// that core reads them from on the GPU ([`crate::scene::source`]).
pub const BINDING_SCENE_TEXELS: u32 = 22;
/// `TriangleBlock` array (the leaves' triangles four at a time).
pub const BINDING_TRIANGLE_BLOCKS: u32 = 23;
/// This frame's history ([`crate::temporal::HistoryTexel`] per pixel), written by `temporal`.
pub const BINDING_HISTORY: u32 = 24;
/// Hardware traversal (the ray-query kernel module only): the top-level acceleration structure's
/// device address and the map from its triangles to the scene's (`u32` words;
/// `crate::bvh::hardware`). The host binds a placeholder for the software module.
pub const BINDING_HARDWARE_TRAVERSAL: u32 = 25;
/// The previous frame's history ([`crate::temporal::HistoryTexel`] per pixel of the previous size),
/// read by `temporal`; the host swaps it with [`BINDING_HISTORY`] every frame.
pub const BINDING_PREVIOUS_HISTORY: u32 = 26;
/// This frame's G-buffer ([`crate::temporal::GBufferTexel`] per pixel), written by `gbuffer`.
pub const BINDING_GBUFFER: u32 = 27;
/// The previous frame's G-buffer, read by `temporal`; swapped with [`BINDING_GBUFFER`] every frame.
pub const BINDING_PREVIOUS_GBUFFER: u32 = 28;
/// The temporal pass's [`crate::temporal::TemporalParams`] (one element).
pub const BINDING_TEMPORAL: u32 = 29;
/// The denoiser's texels ([`crate::denoise::DenoiseTexel`]): two halves of one per pixel each, used in
/// turn by its passes (step `k` reads half `k % 2` and writes the other; `denoise_input` writes half 0).
pub const BINDING_DENOISE: u32 = 30;
/// Each pixel's sum of the samples that landed in it this frame (`[r, g, b, count]`, width × height;
/// [`crate::integrator::add_to_pixel_sum`]), written by `reduce_blocks` and read by `temporal`.
pub const BINDING_PIXEL_SAMPLES: u32 = 32;
/// Number of bindings.
pub const BINDING_COUNT: u32 = 33;

/// Specialization constant id of `render_samples`' feature mask (`FEATURE_*` bits; default every
/// feature). The host sets it per scene when it creates the pipeline.
pub const SPEC_CONSTANT_FEATURES: u32 = 0;

/// Push constants of every entry point: what this dispatch covers (32 bytes). The frame itself is in
/// [`BINDING_FRAME`].
///
/// `render_samples` renders the chunk's `block_count · spp` samples, sample `i` being sample `i % spp` of
/// block `i / spp` (all blocks of a chunk belong to one region, so they share `spp`), about
/// [`SAMPLES_PER_INVOCATION`] per invocation. `reduce_blocks` runs one invocation per block of the
/// chunk. `cell_means`, `fill`, `gbuffer`, `temporal`, `tonemap` and `overlay_regions` run one
/// invocation per cell or pixel, `item_count` in all.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct KernelPushConstants {
    /// Blocks in this chunk (`render_samples`, `reduce_blocks`).
    pub block_count: u32,
    /// Samples per block in this chunk.
    pub spp: u32,
    /// Items for the per-cell and per-pixel kernels.
    pub item_count: u32,
    /// `FILL_BILINEAR` or `FILL_REPLICATE`.
    pub fill_mode: u32,
    /// Exposure compensation in EV for `tonemap`.
    pub exposure_ev: f32,
    /// The denoiser's à-trous step (`denoise_atrous`; `denoise_output` reads the half the last step
    /// wrote, `pass % 2` after [`crate::denoise::DENOISE_MAX_PASSES`] steps).
    pub pass: u32,
    /// `denoise_input`'s flags ([`crate::denoise::DENOISE_WITH_HISTORY`]).
    pub flags: u32,
    pub _pad: u32,
}

/// Workgroup size of every entry point.
pub const WORKGROUP_SIZE: u32 = 64;

/// About how many samples one `render_samples` invocation renders, one after the other: the host
/// dispatches `ceil(samples / SAMPLES_PER_INVOCATION)` invocations
/// ([`crate::integrator::render_sample_stream`]).
pub const SAMPLES_PER_INVOCATION: u32 = 4;

// ---------------------------------------------------------------------------------------------------------
// The `probe` entry point: evaluates one core function per invocation, for the cross-backend tests.
// ---------------------------------------------------------------------------------------------------------

/// `probe` input records (`[f32; 4]` each; [`PROBE_INPUT_RECORDS`] per item). Shares the binding of
/// [`BINDING_BLOCKS`] (the probe never runs with blocks).
pub const BINDING_PROBE_INPUT: u32 = 15;
/// `probe` output records (`[f32; 4]` each; [`PROBE_OUTPUT_RECORDS`] per item). Shares the binding of
/// [`BINDING_SAMPLES`].
pub const BINDING_PROBE_OUTPUT: u32 = 16;
/// Input records per probe item, whatever the selector: item `i` reads `inputs[i · 8 .. i · 8 + 8]`
/// (unused records are ignored).
pub const PROBE_INPUT_RECORDS: u32 = 8;
/// Output records per probe item, whatever the selector: item `i` writes `outputs[i · 2 .. i · 2 + 2]`
/// (unused records are written as zero).
pub const PROBE_OUTPUT_RECORDS: u32 = 2;

// Probe selectors. The `probe` entry point takes [`KernelPushConstants`]: `spp` is the selector and
// `item_count` the number of items. Integers travel as `f32` bit patterns (`f32::from_bits` /
// `to_bits`), so they come back bit-exact. `in[k]` is the item's k-th input record, `out[k]` its k-th
// output record; components not named are ignored (input) or zero (output).

/// [`crate::rng::pcg4d`]: `in[0]` = four words (bits) → `out[0]` = four hashed words (bits).
pub const PROBE_PCG4D: u32 = 0;
/// [`crate::rng::SampleRng`]: `in[0]` = (pixel x, pixel y, frame, sample) bits, `in[1]` = (region, seed,
/// draws) bits → `out[0]` = `next_u32x4` after skipping `draws` draws (bits), `out[1].xy` = the
/// following `next_2d`.
pub const PROBE_SAMPLE_RNG: u32 = 1;
/// [`crate::geometry::offset::offset_ray_origin`]: `in[0]` = (p xyz, triangle magnitude), `in[1].xyz` =
/// n → `out[0].xyz`.
pub const PROBE_OFFSET_RAY_ORIGIN: u32 = 2;
/// The watertight ray-triangle test ([`crate::geometry::triangle::WatertightRay`]): `in[0]` = (origin
/// xyz, t_max), `in[1].xyz` = direction, `in[2]`, `in[3]`, `in[4]` = v0, v1, v2 (as packed in
/// [`crate::scene::TrianglePositions`]) → `out[0]` = (t, b1, b2, hit ? 1 : 0).
pub const PROBE_TRIANGLE: u32 = 3;
/// [`crate::bsdf::disney::DisneyParams::eval_and_pdf`]: `in[0]` = (base colour rgb, metallic), `in[1]` =
/// (roughness, anisotropic, specular, specular_tint), `in[2]` = (sheen, sheen_tint, clearcoat,
/// clearcoat_gloss), `in[3].xyz` = wo, `in[4].xyz` = wi, `in[5]` = (transmission, ior, front ? 1 : 0,
/// thin wall ? 1 : 0)
/// → `out[0]` = (f rgb, pdf), evaluated through [`crate::bsdf::disney::DisneyParams::at_wo_facing`]
/// (so transmissive materials also refract).
pub const PROBE_DISNEY_EVAL: u32 = 4;
/// [`crate::bsdf::disney::DisneyParams::sample`]: `in[0..3]` and `in[5]` as for [`PROBE_DISNEY_EVAL`],
/// `in[3].xyz` = wo, `in[4].xyz` = u → `out[0]` = (wi xyz, pdf), `out[1].xyz` = f.
pub const PROBE_DISNEY_SAMPLE: u32 = 5;
/// [`crate::post::tonemap::tonemap_to_rgba8`]: `in[0]` = (hdr rgb, exposure EV) → `out[0].x` = packed
/// RGBA8 (bits).
pub const PROBE_TONEMAP: u32 = 6;
/// [`crate::foveation::owning_block`] with the frame's foveation ([`BINDING_FRAME`]): `in[0].xy` = pixel
/// (bits) → `out[0]` = (region, size, origin x, origin y) (bits).
pub const PROBE_OWNING_BLOCK: u32 = 7;
/// [`crate::foveation::cell_mean_at`] over the image in [`BINDING_REPLICATED`] (frame width, height and
/// foveation): `in[0].x` = cell index (bits) → `out[0]` = the cell mean.
pub const PROBE_CELL_MEAN: u32 = 8;
/// [`crate::foveation::fill_pixel`] (the bilinear cell weights) over [`BINDING_REPLICATED`] and
/// [`BINDING_CELL_MEANS`]: `in[0]` = (x, y, fill mode) (bits) → `out[0]` = the filled value.
pub const PROBE_FILL_PIXEL: u32 = 9;
/// [`crate::lights::power_heuristic`]: `in[0].xy` = (pdf_a, pdf_b) → `out[0].x` = the weight.
pub const PROBE_POWER_HEURISTIC: u32 = 10;
/// The portable transcendental functions ([`crate::math::transcendental`]): `in[0]` = (x, y, z, w),
/// `in[1].xy` = (a, b) → `out[0]` = (sin x, cos x, tan x, atan2(a, b)), `out[1]` = (e^z, ln y, y^w, 2^z).
pub const PROBE_TRANSCENDENTAL: u32 = 11;
/// Number of probe selectors; any other selector writes zeros.
pub const PROBE_SELECTOR_COUNT: u32 = 12;

// Scene probe selectors: the `probe_scene` entry point evaluates them over the scene bound at
// `BINDING_GLOBALS ..= BINDING_ENVIRONMENT_CONDITIONAL` and `BINDING_VERTEX_COLORS` (with every
// feature on), reading
// [`BINDING_PROBE_INPUT`] and writing [`BINDING_PROBE_OUTPUT`] with the same strides as `probe`
// ([`probe_scene_eval`]).

/// [`crate::bvh::closest_hit`]: `in[0]` = (origin xyz, t_max), `in[1].xyz` = direction →
/// `out[0]` = (t, b1, b2, triangle (bits)); a miss gives t = +inf and triangle `INVALID_INDEX`.
pub const PROBE_SCENE_CLOSEST_HIT: u32 = 16;
/// [`crate::bvh::any_hit`]: inputs as for [`PROBE_SCENE_CLOSEST_HIT`] → `out[0].x` = 1 if
/// blocked, else 0.
pub const PROBE_SCENE_ANY_HIT: u32 = 17;
/// [`crate::lights::sample_light`]: `in[0].xyz` = shading point, `in[1].xyz` = (u_select, u.x, u.y) →
/// `out[0]` = (direction xyz, pdf), `out[1]` = (radiance rgb, flags (bits): 1 infinite | 2 delta).
pub const PROBE_SCENE_SAMPLE_LIGHT: u32 = 18;
/// Emissive triangles: `in[0]` = (shading point xyz, triangle (bits)), `in[1].xy` = u, `in[2].xyz` =
/// a point q → `out[0]` = [`crate::lights::triangle::sample`]'s (direction xyz, pdf), `out[1]` = (its
/// radiance rgb, [`crate::lights::triangle::solid_angle_pdf`] of q).
pub const PROBE_SCENE_TRIANGLE_LIGHT: u32 = 19;
/// The environment: `in[0].xyz` = a direction d, `in[1].xy` = u → `out[0]` =
/// ([`crate::lights::environment::radiance`] rgb of d, [`crate::lights::environment::pdf`] of d),
/// `out[1]` = [`crate::lights::environment::sample`]'s (direction xyz, pdf).
pub const PROBE_SCENE_ENVIRONMENT: u32 = 20;
/// One past the last scene selector; scene selectors are `PROBE_SCENE_CLOSEST_HIT ..
/// PROBE_SCENE_SELECTOR_END`, any other writes zeros.
pub const PROBE_SCENE_SELECTOR_END: u32 = 21;

/// The Disney parameters of probe input records `in[base .. base + 3]`.
#[inline]
#[must_use]
fn probe_disney_params(inputs: &[[f32; 4]], base: usize) -> crate::bsdf::disney::DisneyParams {
    let a = inputs[base];
    let b = inputs[base + 1];
    let c = inputs[base + 2];
    let t = inputs[base + 5];
    crate::bsdf::disney::DisneyParams {
        base_color: glam::Vec3::new(a[0], a[1], a[2]),
        metallic: a[3],
        roughness: b[0],
        anisotropic: b[1],
        specular: b[2],
        specular_tint: b[3],
        sheen: c[0],
        sheen_tint: c[1],
        clearcoat: c[2],
        clearcoat_gloss: c[3],
        lambertian: false,
        transmission: t[0],
        ior: t[1],
        thin_walled: t[3] != 0.0,
    }
}

/// `xyz` of a record.
#[inline]
#[must_use]
fn probe_vec3(r: [f32; 4]) -> glam::Vec3 {
    glam::Vec3::new(r[0], r[1], r[2])
}

/// Evaluates probe item `item` with `selector` (one of the `PROBE_*` selectors; see each for the record
/// layout): reads `inputs[item · PROBE_INPUT_RECORDS ..]` and returns the item's
/// [`PROBE_OUTPUT_RECORDS`] output records. Both the GPU `probe` entry point and the CPU side of the
/// cross-backend tests call this, so they differ only in how the core functions were compiled.
/// `replicated` and `cell_means` are only read by [`PROBE_CELL_MEAN`] and [`PROBE_FILL_PIXEL`].
#[must_use]
pub fn probe_eval(
    selector: u32,
    inputs: &[[f32; 4]],
    item: u32,
    frame: &crate::integrator::FrameParams,
    replicated: &[[f32; 4]],
    cell_means: &[[f32; 4]],
) -> [[f32; 4]; 2] {
    let base = (item * PROBE_INPUT_RECORDS) as usize;
    let r0 = inputs[base];
    let mut out = [[0.0f32; 4]; 2];
    if selector == PROBE_PCG4D {
        let h = crate::rng::pcg4d([
            r0[0].to_bits(),
            r0[1].to_bits(),
            r0[2].to_bits(),
            r0[3].to_bits(),
        ]);
        out[0] = [
            f32::from_bits(h[0]),
            f32::from_bits(h[1]),
            f32::from_bits(h[2]),
            f32::from_bits(h[3]),
        ];
    } else if selector == PROBE_SAMPLE_RNG {
        let r1 = inputs[base + 1];
        let mut rng = crate::rng::SampleRng::new(
            [r0[0].to_bits(), r0[1].to_bits()],
            r0[2].to_bits(),
            r0[3].to_bits(),
            r1[0].to_bits(),
            r1[1].to_bits(),
        );
        for _ in 0..r1[2].to_bits() {
            let _ = rng.next_u32x4();
        }
        let h = rng.next_u32x4();
        out[0] = [
            f32::from_bits(h[0]),
            f32::from_bits(h[1]),
            f32::from_bits(h[2]),
            f32::from_bits(h[3]),
        ];
        let u = rng.next_2d();
        out[1] = [u.x, u.y, 0.0, 0.0];
    } else if selector == PROBE_OFFSET_RAY_ORIGIN {
        let p = crate::geometry::offset::offset_ray_origin(
            probe_vec3(r0),
            probe_vec3(inputs[base + 1]),
            r0[3],
        );
        out[0] = [p.x, p.y, p.z, 0.0];
    } else if selector == PROBE_TRIANGLE {
        let ray = crate::geometry::Ray::new(probe_vec3(r0), probe_vec3(inputs[base + 1]));
        let tri = crate::scene::TrianglePositions {
            v0: glam::Vec4::from_array(inputs[base + 2]),
            v1: glam::Vec4::from_array(inputs[base + 3]),
            v2: glam::Vec4::from_array(inputs[base + 4]),
        };
        let hit = crate::geometry::triangle::WatertightRay::new(&ray).intersect(&tri, r0[3]);
        out[0] = [hit.t, hit.b1, hit.b2, if hit.hit { 1.0 } else { 0.0 }];
    } else if selector == PROBE_DISNEY_EVAL {
        let params = probe_disney_params(inputs, base);
        let front = inputs[base + 5][2] != 0.0;
        let at_wo = params.at_wo_facing(
            crate::scene::FeatureFlags::ALL,
            probe_vec3(inputs[base + 3]),
            front,
        );
        let (f, pdf) = at_wo.eval_and_pdf(probe_vec3(inputs[base + 4]));
        out[0] = [f.x, f.y, f.z, pdf];
    } else if selector == PROBE_DISNEY_SAMPLE {
        let params = probe_disney_params(inputs, base);
        let front = inputs[base + 5][2] != 0.0;
        let s = params
            .at_wo_facing(
                crate::scene::FeatureFlags::ALL,
                probe_vec3(inputs[base + 3]),
                front,
            )
            .sample(probe_vec3(inputs[base + 4]));
        out[0] = [s.wi.x, s.wi.y, s.wi.z, s.pdf];
        out[1] = [s.f.x, s.f.y, s.f.z, 0.0];
    } else if selector == PROBE_TONEMAP {
        let packed = crate::post::tonemap::tonemap_to_rgba8(probe_vec3(r0), r0[3]);
        out[0] = [f32::from_bits(packed), 0.0, 0.0, 0.0];
    } else if selector == PROBE_OWNING_BLOCK {
        let b = crate::foveation::owning_block(r0[0].to_bits(), r0[1].to_bits(), &frame.foveation);
        out[0] = [
            f32::from_bits(b.region),
            f32::from_bits(b.size),
            f32::from_bits(b.origin[0]),
            f32::from_bits(b.origin[1]),
        ];
    } else if selector == PROBE_CELL_MEAN {
        let m = crate::foveation::cell_mean_at(
            replicated,
            frame.width,
            frame.height,
            &frame.foveation,
            r0[0].to_bits(),
        );
        out[0] = m.to_array();
    } else if selector == PROBE_FILL_PIXEL {
        let v = crate::foveation::fill_pixel(
            replicated,
            cell_means,
            frame.width,
            frame.height,
            &frame.foveation,
            r0[0].to_bits(),
            r0[1].to_bits(),
            r0[2].to_bits(),
        );
        out[0] = v.to_array();
    } else if selector == PROBE_POWER_HEURISTIC {
        out[0][0] = crate::lights::power_heuristic(r0[0], r0[1]);
    } else if selector == PROBE_TRANSCENDENTAL {
        use crate::math::transcendental as t;
        let r1 = inputs[base + 1];
        let (s, c) = t::sin_cos(r0[0]);
        out[0] = [s, c, t::tan(r0[0]), t::atan2(r1[0], r1[1])];
        out[1] = [
            t::exp(r0[2]),
            t::ln(r0[1]),
            t::powf(r0[1], r0[3]),
            t::exp2(r0[2]),
        ];
    }
    out
}

/// Evaluates scene probe item `item` with `selector` (one of the `PROBE_SCENE_*` selectors) over
/// `scene`, traversing through `source` (the GPU's texel buffer, or the CPU's slices): reads
/// `inputs[item · PROBE_INPUT_RECORDS ..]` and returns the item's [`PROBE_OUTPUT_RECORDS`] output
/// records. The GPU `probe_scene` entry point and the CPU side of the
/// cross-backend tests both call this.
#[must_use]
pub fn probe_scene_eval<F: crate::scene::Features, S: crate::scene::SceneSource>(
    selector: u32,
    scene: &crate::scene::SceneView<F>,
    source: &S,
    inputs: &[[f32; 4]],
    item: u32,
) -> [[f32; 4]; 2] {
    let base = (item * PROBE_INPUT_RECORDS) as usize;
    let r0 = inputs[base];
    let r1 = inputs[base + 1];
    let mut out = [[0.0f32; 4]; 2];
    if selector == PROBE_SCENE_CLOSEST_HIT || selector == PROBE_SCENE_ANY_HIT {
        let ray = crate::geometry::Ray::new(probe_vec3(r0), probe_vec3(r1));
        if selector == PROBE_SCENE_CLOSEST_HIT {
            let hit = crate::bvh::closest_hit_with(scene, source, &ray, r0[3]);
            out[0] = [hit.t, hit.b1, hit.b2, f32::from_bits(hit.triangle)];
        } else {
            let blocked = crate::bvh::any_hit_with(scene, source, &ray, r0[3]);
            out[0][0] = if blocked { 1.0 } else { 0.0 };
        }
    } else if selector == PROBE_SCENE_SAMPLE_LIGHT {
        let s = crate::lights::sample_light(
            scene,
            source,
            probe_vec3(r0),
            r1[0],
            glam::Vec2::new(r1[1], r1[2]),
        );
        let flags = u32::from(s.is_infinite) | (u32::from(s.is_delta) << 1);
        out[0] = [s.direction.x, s.direction.y, s.direction.z, s.pdf];
        out[1] = [
            s.radiance.x,
            s.radiance.y,
            s.radiance.z,
            f32::from_bits(flags),
        ];
    } else if selector == PROBE_SCENE_TRIANGLE_LIGHT {
        let triangle = r0[3].to_bits();
        if (triangle as usize) < scene.geometry.triangle_lanes.len() {
            let p = probe_vec3(r0);
            let s = crate::lights::triangle::sample(
                scene,
                source,
                triangle,
                p,
                glam::Vec2::new(r1[0], r1[1]),
            );
            let pdf_q = crate::lights::triangle::solid_angle_pdf(
                scene,
                source,
                triangle,
                p,
                probe_vec3(inputs[base + 2]),
            );
            out[0] = [s.direction.x, s.direction.y, s.direction.z, s.pdf];
            out[1] = [s.radiance.x, s.radiance.y, s.radiance.z, pdf_q];
        }
    } else if selector == PROBE_SCENE_ENVIRONMENT {
        let d = probe_vec3(r0);
        let le = crate::lights::environment::radiance(scene, d);
        let pdf = crate::lights::environment::pdf(scene, d);
        let s = crate::lights::environment::sample(scene, glam::Vec2::new(r1[0], r1[1]));
        out[0] = [le.x, le.y, le.z, pdf];
        out[1] = [s.direction.x, s.direction.y, s.direction.z, s.pdf];
    }
    out
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::bsdf::DisneyParams;
    use crate::foveation::{owning_block, FoveationParams};
    use crate::geometry::triangle::WatertightRay;
    use crate::geometry::Ray;
    use crate::integrator::FrameParams;
    use crate::rng::{pcg4d, SampleRng};
    use crate::scene::TrianglePositions;
    use glam::Vec3;

    fn bits(v: [u32; 4]) -> [f32; 4] {
        [
            f32::from_bits(v[0]),
            f32::from_bits(v[1]),
            f32::from_bits(v[2]),
            f32::from_bits(v[3]),
        ]
    }

    fn frame(width: u32, height: u32) -> FrameParams {
        let mut f: FrameParams = bytemuck::Zeroable::zeroed();
        f.width = width;
        f.height = height;
        f.foveation = FoveationParams::paper([9.0, 7.0], 3.0, 6.0);
        f
    }

    /// Runs the probe on one item whose input records are `records` (padded to the stride).
    fn probe_one(selector: u32, records: &[[f32; 4]], frame: &FrameParams) -> [[f32; 4]; 2] {
        probe_one_with(selector, records, frame, &[], &[])
    }

    fn probe_one_with(
        selector: u32,
        records: &[[f32; 4]],
        frame: &FrameParams,
        replicated: &[[f32; 4]],
        cell_means: &[[f32; 4]],
    ) -> [[f32; 4]; 2] {
        // Item 1 of two, so the stride is exercised.
        let mut inputs = vec![[f32::NAN; 4]; 2 * PROBE_INPUT_RECORDS as usize];
        let base = PROBE_INPUT_RECORDS as usize;
        inputs[base..base + records.len()].copy_from_slice(records);
        probe_eval(selector, &inputs, 1, frame, replicated, cell_means)
    }

    #[test]
    fn probe_pcg4d_is_bit_exact() {
        let f = frame(16, 16);
        for v in [
            [0u32, 0, 0, 0],
            [1, 2, 3, 4],
            [0xffff_ffff, 0x7fc0_0001, 0xff80_0000, 12345],
        ] {
            let out = probe_one(PROBE_PCG4D, &[bits(v)], &f);
            let got = [
                out[0][0].to_bits(),
                out[0][1].to_bits(),
                out[0][2].to_bits(),
                out[0][3].to_bits(),
            ];
            assert_eq!(got, pcg4d(v));
            assert_eq!(out[1], [0.0; 4]);
        }
    }

    #[test]
    fn probe_sample_rng_skips_draws() {
        let f = frame(16, 16);
        let out = probe_one(
            PROBE_SAMPLE_RNG,
            &[bits([5, 6, 7, 8]), bits([2, 99, 3, 0])],
            &f,
        );
        let mut rng = SampleRng::new([5, 6], 7, 8, 2, 99);
        for _ in 0..3 {
            let _ = rng.next_u32x4();
        }
        assert_eq!(out[0], bits(rng.next_u32x4()));
        let u = rng.next_2d();
        assert_eq!(out[1], [u.x, u.y, 0.0, 0.0]);
    }

    #[test]
    fn probe_geometry_matches_direct_calls() {
        let f = frame(16, 16);
        let p = Vec3::new(1.5, -200.0, 0.001);
        let n = Vec3::new(0.0, 0.6, -0.8);
        let out = probe_one(
            PROBE_OFFSET_RAY_ORIGIN,
            &[[p.x, p.y, p.z, 0.25], [n.x, n.y, n.z, 0.0]],
            &f,
        );
        let q = crate::geometry::offset::offset_ray_origin(p, n, 0.25);
        assert_eq!(out[0], [q.x, q.y, q.z, 0.0]);

        let tri = TrianglePositions {
            v0: glam::Vec4::new(-1.0, -1.0, 2.0, 0.0),
            v1: glam::Vec4::new(1.0, -1.0, 2.0, 0.0),
            v2: glam::Vec4::new(0.0, 1.0, 2.0, 0.0),
        };
        let ray = Ray::new(Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0));
        let records = [
            [0.1, 0.0, 0.0, 10.0],
            [0.0, 0.0, 1.0, 0.0],
            tri.v0.to_array(),
            tri.v1.to_array(),
            tri.v2.to_array(),
        ];
        let out = probe_one(PROBE_TRIANGLE, &records, &f);
        let hit = WatertightRay::new(&ray).intersect(&tri, 10.0);
        assert!(hit.hit);
        assert_eq!(out[0], [hit.t, hit.b1, hit.b2, 1.0]);
        // Beyond t_max: a miss.
        let mut records = records;
        records[0][3] = 1.0;
        assert_eq!(probe_one(PROBE_TRIANGLE, &records, &f)[0][3], 0.0);
    }

    #[test]
    fn probe_disney_matches_direct_calls() {
        let f = frame(16, 16);
        let mut params = DisneyParams::diffuse(Vec3::new(0.8, 0.5, 0.2));
        params.metallic = 0.3;
        params.roughness = 0.4;
        params.clearcoat = 0.5;
        params.sheen = 0.2;
        let head = [
            [0.8, 0.5, 0.2, 0.3],
            [0.4, 0.0, 0.5, 0.0],
            [0.2, 0.0, 0.5, 0.0],
        ];
        let wo = Vec3::new(0.3, -0.2, 0.9);
        let wi = Vec3::new(-0.4, 0.1, 0.7);
        let mut records: Vec<[f32; 4]> = head.to_vec();
        records.push([wo.x, wo.y, wo.z, 0.0]);
        records.push([wi.x, wi.y, wi.z, 0.0]);
        let out = probe_one(PROBE_DISNEY_EVAL, &records, &f);
        let (fv, pdf) = params.eval_and_pdf(wo, wi);
        assert!(pdf > 0.0);
        assert_eq!(out[0], [fv.x, fv.y, fv.z, pdf]);

        let u = Vec3::new(0.7, 0.25, 0.6);
        records[4] = [u.x, u.y, u.z, 0.0];
        let out = probe_one(PROBE_DISNEY_SAMPLE, &records, &f);
        let s = params.sample(wo, u);
        assert!(s.pdf > 0.0);
        assert_eq!(out[0], [s.wi.x, s.wi.y, s.wi.z, s.pdf]);
        assert_eq!(out[1], [s.f.x, s.f.y, s.f.z, 0.0]);
    }

    #[test]
    fn probe_tonemap_and_foveation_match_direct_calls() {
        let f = frame(16, 12);
        let out = probe_one(PROBE_TONEMAP, &[[0.5, 2.0, 0.01, 1.0]], &f);
        let packed = crate::post::tonemap::tonemap_to_rgba8(Vec3::new(0.5, 2.0, 0.01), 1.0);
        assert_eq!(out[0][0].to_bits(), packed);

        for (x, y) in [(0u32, 0u32), (9, 7), (15, 11), (5, 3)] {
            let out = probe_one(PROBE_OWNING_BLOCK, &[bits([x, y, 0, 0])], &f);
            let b = owning_block(x, y, &f.foveation);
            assert_eq!(out[0], bits([b.region, b.size, b.origin[0], b.origin[1]]));
        }

        let (w, h) = (f.width, f.height);
        let replicated: Vec<[f32; 4]> = (0..w * h)
            .map(|i| [i as f32, (i % 7) as f32, 1.0, 1.0])
            .collect();
        let cells = crate::foveation::cell_buffer_len(w, h, &f.foveation);
        let cell_means: Vec<[f32; 4]> = (0..cells)
            .map(|i| crate::foveation::cell_mean_at(&replicated, w, h, &f.foveation, i).to_array())
            .collect();
        for i in [0, 1, cells / 2, cells - 1] {
            let out = probe_one_with(PROBE_CELL_MEAN, &[bits([i, 0, 0, 0])], &f, &replicated, &[]);
            assert_eq!(out[0], cell_means[i as usize]);
        }
        for (x, y) in [(0u32, 0u32), (1, 2), (15, 11), (6, 9)] {
            let mode = crate::foveation::FILL_BILINEAR;
            let out = probe_one_with(
                PROBE_FILL_PIXEL,
                &[bits([x, y, mode, 0])],
                &f,
                &replicated,
                &cell_means,
            );
            let v = crate::foveation::fill_pixel(
                &replicated,
                &cell_means,
                w,
                h,
                &f.foveation,
                x,
                y,
                mode,
            );
            assert_eq!(out[0], v.to_array());
        }
    }

    #[test]
    fn probe_unknown_selector_writes_zeros() {
        let f = frame(4, 4);
        let out = probe_one(PROBE_SELECTOR_COUNT, &[[1.0; 4]], &f);
        assert_eq!(out, [[0.0; 4]; 2]);
    }
}
