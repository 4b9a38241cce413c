//! rust-gpu compute entry points of fovea.
//!
//! Each entry point only maps an invocation id and the storage buffers of [`fovea_core::kernel_abi`] to
//! one call into `fovea-core`; no rendering math lives here. One frame runs, per dispatch chunk of blocks
//! of one region, `render_samples` then `reduce_blocks`, and then, once per frame, `cell_means`, `fill`
//! and `tonemap` (the CPU host's passes 1-3 and its tone mapping, in the same order and with the same
//! sums). Temporal reuse (the live view, `fovea render --history`) adds `gbuffer` and `temporal`
//! between `fill` and `tonemap`, and the live view `overlay_regions` after `tonemap`. `probe` evaluates single core functions for the cross-backend tests.
//!
//! Built twice: the plain module traverses the software BVH; the module built with the `RayQueryKHR`
//! capability and the crate feature `ray-query` (`--traversal hardware`) also binds [`kernel_abi::BINDING_HARDWARE_TRAVERSAL`] in the
//! entry points that trace rays, and core's traversal asks the driver's acceleration structures instead
//! (`fovea_core::bvh::hardware`).
//!
//! All entry points run [`WORKGROUP_SIZE`] = 64 invocations per workgroup. The invocation index is
//! `id.x + id.y · (num_workgroups.x · 64)`, so a host may dispatch up to 65535 workgroups in x and more
//! rows in y; invocations past the item count return at once.
//!
//! Built to SPIR-V by `gpu-kernel/builder/` (run from `host-vulkan/build.rs`); on the host it compiles as a plain
//! library (the attributes are then inert).
#![cfg_attr(target_arch = "spirv", no_std)]
// Entry points take one argument per binding.
#![allow(clippy::too_many_arguments)]

use fovea_core::denoise::{self as denoiser, DenoiseTexel};
use fovea_core::foveation::overlay::overlay_rgba8;
use fovea_core::foveation::OwnedBlock;
use fovea_core::foveation::{block_extent, block_mean, cell_mean_at, fill_value};
use fovea_core::glam::{Vec3, Vec4};
use fovea_core::integrator::{
    add_to_pixel_sum, clear_block_pixel_sums, render_sample_stream, FrameParams,
};
use fovea_core::kernel_abi::{self, KernelPushConstants, WORKGROUP_SIZE};
use fovea_core::post::tonemap::tonemap_to_rgba8;
use fovea_core::scene::features::FEATURES_ALL;
use fovea_core::temporal::albedo::cell_albedo_at;
// Built for the host (a plain library), the scene texel binding is the scene's own slices.
#[cfg(not(target_arch = "spirv"))]
use fovea_core::scene::SceneSlices as SceneTexels;
#[cfg(target_arch = "spirv")]
use fovea_core::scene::SceneTexels;
use fovea_core::scene::{
    Bvh4Node, EnvironmentArrays, FeatureFlags, GeometryArrays, Light, LightArrays, Material,
    MaterialArrays, SceneGlobals, SceneView, TextureInfo, TriangleBlock, TriangleInfo,
};
use fovea_core::temporal::{
    first_hit_gbuffer, resolve_pixel, temporal_accumulate, GBufferTexel, HistoryTexel,
    TemporalParams,
};
use spirv_std::glam::UVec3;
use spirv_std::spirv;

// `#[spirv(binding = N)]` needs literals: these checks keep the literals below equal to the ABI.
const _: () = {
    assert!(WORKGROUP_SIZE == 64);
    assert!(kernel_abi::BINDING_GLOBALS == 0);
    assert!(kernel_abi::BINDING_NODES == 1);
    assert!(kernel_abi::BINDING_TRIANGLE_LANES == 2);
    assert!(kernel_abi::BINDING_TRIANGLE_INFO == 3);
    assert!(kernel_abi::BINDING_NORMALS == 4);
    assert!(kernel_abi::BINDING_UVS == 5);
    assert!(kernel_abi::BINDING_MATERIALS == 6);
    assert!(kernel_abi::BINDING_TEXTURES == 7);
    assert!(kernel_abi::BINDING_TEXELS == 8);
    assert!(kernel_abi::BINDING_LIGHTS == 9);
    assert!(kernel_abi::BINDING_LIGHT_CDF == 10);
    assert!(kernel_abi::BINDING_TRIANGLE_LIGHT == 11);
    assert!(kernel_abi::BINDING_ENVIRONMENT_TEXELS == 12);
    assert!(kernel_abi::BINDING_ENVIRONMENT_MARGINAL == 13);
    assert!(kernel_abi::BINDING_ENVIRONMENT_CONDITIONAL == 14);
    assert!(kernel_abi::BINDING_BLOCKS == 15);
    assert!(kernel_abi::BINDING_SAMPLES == 16);
    assert!(kernel_abi::BINDING_REPLICATED == 17);
    assert!(kernel_abi::BINDING_CELL_MEANS == 18);
    assert!(kernel_abi::BINDING_HDR == 19);
    assert!(kernel_abi::BINDING_LDR == 20);
    assert!(kernel_abi::BINDING_FRAME == 21);
    assert!(kernel_abi::BINDING_SCENE_TEXELS == 22);
    assert!(kernel_abi::BINDING_TRIANGLE_BLOCKS == 23);
    assert!(kernel_abi::BINDING_VERTEX_COLORS == 31);
    assert!(kernel_abi::BINDING_HISTORY == 24);
    assert!(kernel_abi::BINDING_HARDWARE_TRAVERSAL == 25);
    assert!(kernel_abi::BINDING_PREVIOUS_HISTORY == 26);
    assert!(kernel_abi::BINDING_GBUFFER == 27);
    assert!(kernel_abi::BINDING_PREVIOUS_GBUFFER == 28);
    assert!(kernel_abi::BINDING_TEMPORAL == 29);
    assert!(kernel_abi::BINDING_DENOISE == 30);
    assert!(kernel_abi::BINDING_PIXEL_SAMPLES == 32);
    assert!(kernel_abi::BINDING_PROBE_INPUT == 15);
    assert!(kernel_abi::BINDING_PROBE_OUTPUT == 16);
    assert!(kernel_abi::PROBE_OUTPUT_RECORDS == 2);
    // `render_samples`' specialization constant: id and default (every feature).
    assert!(kernel_abi::SPEC_CONSTANT_FEATURES == 0);
    assert!(FEATURES_ALL == 0xFFFFF);
};

/// Declares a compute entry point that binds the whole scene, group by group as
/// [`SceneView`] holds it, and runs `$body` with it as `$scene`: the one list of scene bindings
/// (`BINDING_GLOBALS ..= BINDING_ENVIRONMENT_CONDITIONAL`, `BINDING_TRIANGLE_BLOCKS`,
/// `BINDING_VERTEX_COLORS` and, in the ray-query module, `BINDING_HARDWARE_TRAVERSAL`) for every entry point that reads the scene. A new
/// scene array is one parameter and one field here. `$features` is the [`FeatureFlags`] the view
/// carries.
macro_rules! scene_entry_point {
    (
        $(#[$meta:meta])*
        pub fn $name:ident($($param:tt)*) with_scene($scene:ident, $features:expr) $body:block
    ) => {
        $(#[$meta])*
        pub fn $name(
            $($param)*
            #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] globals: &SceneGlobals,
            #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] nodes: &[Bvh4Node],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] triangle_lanes: &[u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] triangle_info: &[TriangleInfo],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] normals: &[[f32; 4]],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] uvs: &[[f32; 2]],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] materials: &[Material],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] textures: &[TextureInfo],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] texels: &[u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] lights: &[Light],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] light_cdf: &[f32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] triangle_light: &[u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 12)]
            environment_texels: &[[f32; 4]],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 13)]
            environment_marginal_cdf: &[f32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 14)]
            environment_conditional_cdf: &[f32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 23)]
            triangle_blocks: &[TriangleBlock],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 31)]
            vertex_colors: &[[u32; 2]],
            #[cfg(feature = "ray-query")]
            #[spirv(storage_buffer, descriptor_set = 0, binding = 25)]
            hardware: &[u32],
        ) {
            let $scene = SceneView {
                features: $features,
                globals: *globals,
                geometry: GeometryArrays {
                    nodes,
                    #[cfg(not(target_arch = "spirv"))]
                    wide_nodes: &[],
                    #[cfg(feature = "ray-query")]
                    hardware,
                    triangle_lanes,
                    blocks: triangle_blocks,
                    triangle_info,
                    normals,
                    uvs,
                    vertex_colors,
                },
                materials: MaterialArrays {
                    list: materials,
                    textures,
                    texels,
                },
                lights: LightArrays {
                    list: lights,
                    cdf: light_cdf,
                    triangle_light,
                },
                environment: EnvironmentArrays {
                    texels: environment_texels,
                    marginal_cdf: environment_marginal_cdf,
                    conditional_cdf: environment_conditional_cdf,
                },
            };
            $body
        }
    };
}

/// The linear invocation index of a (possibly 2D) dispatch of 64-wide workgroups.
#[inline]
#[must_use]
pub fn invocation_index(id: UVec3, num_workgroups: UVec3) -> u32 {
    id.x + id.y * (num_workgroups.x * WORKGROUP_SIZE)
}

scene_entry_point! {
    /// Pass 1a: the chunk's `block_count · spp` samples into `samples` (rgb, w = 0; sample `i` is sample
    /// `i % spp` of block `i / spp`), invocation `i` rendering samples `i`, `i + n`, `i + 2n`, ... for `n`
    /// invocations in the dispatch, one sample after another (core's `render_sample_stream`). `features`
    /// is a specialization constant: the host sets the scene's feature mask when it creates the pipeline, so
    /// the driver drops the code of absent features.
    #[spirv(compute(threads(64)))]
    pub fn render_samples(
        #[spirv(spec_constant(id = 0, default = 1048575))] features: u32,
        #[spirv(global_invocation_id)] id: UVec3,
        #[spirv(num_workgroups)] num_workgroups: UVec3,
        #[spirv(push_constant)] pc: &KernelPushConstants,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 15)] blocks: &[OwnedBlock],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 16)] samples: &mut [[f32; 4]],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
        #[spirv(descriptor_set = 0, binding = 22)] scene_texels: &SceneTexels,
    ) with_scene(scene, FeatureFlags(features)) {
        let i = invocation_index(id, num_workgroups);
        if pc.spp == 0 {
            return;
        }
        let invocations = num_workgroups.x * num_workgroups.y * WORKGROUP_SIZE;
        render_sample_stream(
            &scene,
            scene_texels,
            frame,
            blocks,
            pc.block_count,
            pc.spp,
            i,
            invocations,
            samples,
        );
    }
}

/// Pass 1b: invocation `j < block_count` averages the `spp` samples of block `j` (summed in order from
/// zero, like the CPU host) and writes `[mean, 1]` to every pixel of the block's clipped footprint;
/// and adds each sample to the sum of the pixel it landed in (core's [`add_to_pixel_sum`], the block's
/// pixels zeroed first), which each pixel's history takes.
#[spirv(compute(threads(64)))]
pub fn reduce_blocks(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 15)] blocks: &[OwnedBlock],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 16)] samples: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 17)] replicated: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 32)] pixel_samples: &mut [[f32; 4]],
) {
    let j = invocation_index(id, num_workgroups);
    if j >= pc.block_count {
        return;
    }
    let spp = pc.spp;
    let first = j * spp;
    let block = blocks[j as usize];
    clear_block_pixel_sums(pixel_samples, 0, frame, &block);
    let mut sum = Vec3::ZERO;
    for s in 0..spp {
        let v = samples[(first + s) as usize];
        let v = Vec3::new(v[0], v[1], v[2]);
        sum += v;
        add_to_pixel_sum(pixel_samples, 0, frame, &block, s, v);
    }
    let value = block_mean(sum, spp);
    let extent = block_extent(&block, frame.width, frame.height);
    for dy in 0..extent[1] {
        let row = (block.origin[1] + dy) * frame.width + block.origin[0];
        for dx in 0..extent[0] {
            replicated[(row + dx) as usize] = value;
        }
    }
}

/// Pass 2: invocation `i < item_count` writes element `i` of the cell-mean buffer.
#[spirv(compute(threads(64)))]
pub fn cell_means(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 17)] replicated: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cell_means: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
) {
    let i = invocation_index(id, num_workgroups);
    if i >= pc.item_count {
        return;
    }
    let m = cell_mean_at(replicated, frame.width, frame.height, &frame.foveation, i);
    cell_means[i as usize] = m.to_array();
}

/// Pass 3: invocation `p < item_count` (= width · height) fills pixel `p` (row-major) of the HDR image,
/// alpha 1 like the CPU host. In place: a pixel's fill reads only its own replicated value (and the cell
/// means), so the replicated image becomes the HDR image ([`fovea_core::kernel_abi::BINDING_HDR`] is
/// bound to the same buffer).
#[spirv(compute(threads(64)))]
pub fn fill(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 17)] replicated: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cell_means: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
) {
    let p = invocation_index(id, num_workgroups);
    if p >= pc.item_count || frame.width == 0 {
        return;
    }
    let (x, y) = (p % frame.width, p / frame.width);
    let own = Vec4::from(replicated[p as usize]);
    let v = fill_value(
        own,
        cell_means,
        frame.width,
        frame.height,
        &frame.foveation,
        x,
        y,
        pc.fill_mode,
    );
    replicated[p as usize] = [v.x, v.y, v.z, 1.0];
}

/// Tone mapping: invocation `p < item_count` writes pixel `p` of the RGBA8 image (exposure
/// `exposure_ev`, Reinhard, sRGB; core's [`tonemap_to_rgba8`]).
#[spirv(compute(threads(64)))]
pub fn tonemap(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 19)] hdr: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 20)] ldr: &mut [u32],
) {
    let p = invocation_index(id, num_workgroups);
    if p >= pc.item_count {
        return;
    }
    let c = hdr[p as usize];
    ldr[p as usize] = tonemap_to_rgba8(Vec3::new(c[0], c[1], c[2]), pc.exposure_ev);
}

scene_entry_point! {
    /// Temporal reuse, after `fill`: invocation `p < item_count` writes pixel `p`'s G-buffer texel, the
    /// first hit through its centre (core's [`first_hit_gbuffer`]), with every feature on.
    #[spirv(compute(threads(64)))]
    pub fn gbuffer(
        #[spirv(global_invocation_id)] id: UVec3,
        #[spirv(num_workgroups)] num_workgroups: UVec3,
        #[spirv(push_constant)] pc: &KernelPushConstants,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &mut [GBufferTexel],
        #[spirv(descriptor_set = 0, binding = 22)] scene_texels: &SceneTexels,
    ) with_scene(scene, FeatureFlags(FEATURES_ALL)) {
        let p = invocation_index(id, num_workgroups);
        if p >= pc.item_count || frame.width == 0 {
            return;
        }
        gbuffer[p as usize] =
            first_hit_gbuffer(&scene, scene_texels, frame, p % frame.width, p / frame.width);
    }
}

/// After `gbuffer`: invocation `i < item_count` writes element `i` of the cell buffer, its cell's mean
/// albedo (core's [`cell_albedo_at`]), over the cell means the fill has used.
#[spirv(compute(threads(64)))]
pub fn cell_albedo(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cells: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &[GBufferTexel],
) {
    let i = invocation_index(id, num_workgroups);
    if i >= pc.item_count {
        return;
    }
    cells[i as usize] = cell_albedo_at(frame, gbuffer, i).extend(0.0).to_array();
}

/// Temporal reuse, after `cell_albedo`: invocation `p < item_count` reprojects the previous history to pixel
/// `p`, merges the filled HDR pixel into it (core's [`temporal_accumulate`]) and writes the new history.
/// The HDR image is only read here (the clamp reads the neighbours): `resolve_history` writes it.
#[spirv(compute(threads(64)))]
pub fn temporal(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cell_albedo: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 19)] hdr: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 24)] history: &mut [HistoryTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 26)] previous_history: &[HistoryTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &[GBufferTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 28)] previous_gbuffer: &[GBufferTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 29)] temporal: &TemporalParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 32)] pixel_samples: &[[f32; 4]],
) {
    let p = invocation_index(id, num_workgroups);
    if p >= pc.item_count || frame.width == 0 {
        return;
    }
    let texel = temporal_accumulate(
        frame,
        temporal,
        pixel_samples,
        hdr,
        gbuffer,
        cell_albedo,
        previous_gbuffer,
        previous_history,
        p % frame.width,
        p / frame.width,
    );
    history[p as usize] = texel;
}

/// Temporal reuse, after `temporal`: invocation `p < item_count` writes what is shown of pixel `p`
/// over its HDR pixel (core's [`resolve_pixel`]: its history where confident, else the fill, under its
/// own albedo), so that `tonemap` and a read-back see it. In place: a pixel reads only its own filled
/// value.
#[spirv(compute(threads(64)))]
pub fn resolve_history(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cell_albedo: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 19)] hdr: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 24)] history: &[HistoryTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &[GBufferTexel],
) {
    let p = invocation_index(id, num_workgroups);
    if p >= pc.item_count || frame.width == 0 {
        return;
    }
    let shown = resolve_pixel(
        frame,
        history,
        hdr,
        gbuffer,
        cell_albedo,
        pc.fill_mode,
        p % frame.width,
        p / frame.width,
    );
    hdr[p as usize] = shown;
}

/// Denoiser, after the fill or `resolve_history`: invocation `p < item_count` writes pixel `p`'s
/// demodulated value, variance and strength (core's [`denoiser::denoise_input`], with `pc.flags`) to half 0 of
/// the denoiser's texels.
#[spirv(compute(threads(64)))]
pub fn denoise_input(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cell_albedo: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 19)] hdr: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 24)] history: &[HistoryTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &[GBufferTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 30)] denoise: &mut [DenoiseTexel],
) {
    let p = invocation_index(id, num_workgroups);
    if p >= pc.item_count || frame.width == 0 {
        return;
    }
    denoise[p as usize] = denoiser::denoise_input(
        frame,
        hdr,
        gbuffer,
        cell_albedo,
        history,
        pc.flags,
        p % frame.width,
        p / frame.width,
    );
}

/// Denoiser: invocation `p < item_count` runs à-trous step `pc.pass` at pixel `p` (core's
/// [`denoiser::denoise_atrous`]), reading half `pass % 2` of the denoiser's texels and writing the other.
#[spirv(compute(threads(64)))]
pub fn denoise_atrous(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &[GBufferTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 30)] denoise: &mut [DenoiseTexel],
) {
    let p = invocation_index(id, num_workgroups);
    let n = pc.item_count;
    if p >= n || frame.width == 0 {
        return;
    }
    let (read, write) = if pc.pass % 2 == 0 { (0, n) } else { (n, 0) };
    let texel = denoiser::denoise_atrous(
        frame,
        denoise,
        read as usize,
        gbuffer,
        pc.pass,
        p % frame.width,
        p / frame.width,
    );
    denoise[(write + p) as usize] = texel;
}

/// Denoiser, last: invocation `p < item_count` writes pixel `p` of the HDR image from the half the
/// last step wrote (`pc.pass % 2`), remodulated (core's [`denoiser::denoise_output`]).
#[spirv(compute(threads(64)))]
pub fn denoise_output(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 19)] hdr: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 27)] gbuffer: &[GBufferTexel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 30)] denoise: &[DenoiseTexel],
) {
    let p = invocation_index(id, num_workgroups);
    let n = pc.item_count;
    if p >= n || frame.width == 0 {
        return;
    }
    let base = if pc.pass % 2 == 0 { 0 } else { n };
    hdr[p as usize] = denoiser::denoise_output(
        frame,
        denoise,
        base as usize,
        gbuffer,
        p % frame.width,
        p / frame.width,
    );
}

/// Live view, after `tonemap`: invocation `p < item_count` draws the region overlay over pixel `p` of
/// the RGBA8 image (core's [`overlay_rgba8`], the picture of `fovea render --regions-overlay`).
#[spirv(compute(threads(64)))]
pub fn overlay_regions(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 20)] ldr: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
) {
    let p = invocation_index(id, num_workgroups);
    if p >= pc.item_count || frame.width == 0 {
        return;
    }
    let (x, y) = (p % frame.width, p / frame.width);
    ldr[p as usize] = overlay_rgba8(ldr[p as usize], x, y, &frame.foveation);
}

/// Cross-backend probe: item `i < item_count` evaluates core function `spp` (a `PROBE_*` selector of
/// [`kernel_abi`]) on its input records and writes its two output records
/// ([`kernel_abi::probe_eval`]).
#[spirv(compute(threads(64)))]
pub fn probe(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(num_workgroups)] num_workgroups: UVec3,
    #[spirv(push_constant)] pc: &KernelPushConstants,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 15)] inputs: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 16)] outputs: &mut [[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 17)] replicated: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 18)] cell_means: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 21)] frame: &FrameParams,
) {
    let i = invocation_index(id, num_workgroups);
    if i >= pc.item_count {
        return;
    }
    let out = kernel_abi::probe_eval(pc.spp, inputs, i, frame, replicated, cell_means);
    let base = (i * kernel_abi::PROBE_OUTPUT_RECORDS) as usize;
    outputs[base] = out[0];
    outputs[base + 1] = out[1];
}

scene_entry_point! {
    /// Cross-backend scene probe: item `i < item_count` evaluates scene function `spp` (a `PROBE_SCENE_*`
    /// selector of [`kernel_abi`]: BVH traversal, light and environment sampling and densities) over the
    /// bound scene, with every feature on, and writes its two output records
    /// ([`kernel_abi::probe_scene_eval`]).
    #[spirv(compute(threads(64)))]
    pub fn probe_scene(
        #[spirv(global_invocation_id)] id: UVec3,
        #[spirv(num_workgroups)] num_workgroups: UVec3,
        #[spirv(push_constant)] pc: &KernelPushConstants,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 15)] inputs: &[[f32; 4]],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 16)] outputs: &mut [[f32; 4]],
        #[spirv(descriptor_set = 0, binding = 22)] scene_texels: &SceneTexels,
    ) with_scene(scene, FeatureFlags(FEATURES_ALL)) {
        let i = invocation_index(id, num_workgroups);
        if i >= pc.item_count {
            return;
        }
        let out = kernel_abi::probe_scene_eval(pc.spp, &scene, scene_texels, inputs, i);
        let base = (i * kernel_abi::PROBE_OUTPUT_RECORDS) as usize;
        outputs[base] = out[0];
        outputs[base + 1] = out[1];
    }
}
