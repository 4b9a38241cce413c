//! End-to-end renders of the Cornell box on the CPU host: finite and lit, foveated agrees with uniform in
//! the fovea, per-region sample counts, thread-count independence.
use fovea_core::foveation::blocks::{count_samples, owning_block};
use fovea_core::foveation::regions::{FoveationParams, REGION_FOVEA};
use fovea_scene::environment::Environment;
use fovea_tests::*;

const W: u32 = 96;
const H: u32 = 72;

#[test]
fn cornell_box_renders_finite_and_lit() {
    let scene = load_packed(&cornell_box_path(), &Environment::None);
    assert_eq!(scene.triangle_count(), 36);
    assert!(
        scene.stats.emissive_triangle_count >= 2,
        "the ceiling light is an emitter"
    );
    let frame = frame_params(cornell_camera(W, H), FoveationParams::uniform(16), W, H, 1);
    let (image, stats) = render(&scene, &frame);
    assert_eq!(stats.primary_samples, (W * H * 16) as u64);
    assert!(image
        .pixels
        .iter()
        .all(|p| p.iter().all(|v| v.is_finite() && *v >= 0.0)));
    let mean = mean_rgb(&image, (0..H).flat_map(|y| (0..W).map(move |x| (x, y))));
    // The light is warm (Ke 17, 12, 4), so blue is the dimmest channel.
    assert!(
        mean.x > 0.08 && mean.y > 0.05 && mean.z > 0.01,
        "the box is lit: mean {mean}"
    );
    // The left wall (about 12-28 % of the width here) is red and the right wall green.
    let left = mean_rgb(
        &image,
        (H / 3..2 * H / 3).flat_map(|y| (W * 16 / 100..W * 24 / 100).map(move |x| (x, y))),
    );
    let right = mean_rgb(
        &image,
        (H / 3..2 * H / 3).flat_map(|y| (W * 76 / 100..W * 84 / 100).map(move |x| (x, y))),
    );
    assert!(left.x > 1.5 * left.y, "left wall red: {left}");
    assert!(right.y > 1.5 * right.x, "right wall green: {right}");
}

#[test]
fn foveated_matches_uniform_in_the_fovea_and_on_average_elsewhere() {
    let scene = load_packed(&cornell_box_path(), &Environment::None);
    let foveated = FoveationParams::paper([W as f32 * 0.5, H as f32 * 0.5], 12.0, 28.0);
    let (fov, fov_stats) = render(
        &scene,
        &frame_params(cornell_camera(W, H), foveated, W, H, 7),
    );
    let (uni, _) = render(
        &scene,
        &frame_params(cornell_camera(W, H), FoveationParams::uniform(32), W, H, 7),
    );
    // Same random numbers in the fovea: fovea pixels are bit-identical.
    let mut fovea_pixels = 0;
    for y in 0..H {
        for x in 0..W {
            if owning_block(x, y, &foveated).region == REGION_FOVEA {
                let i = (y * W + x) as usize;
                assert_eq!(fov.pixels[i], uni.pixels[i], "fovea pixel ({x}, {y})");
                fovea_pixels += 1;
            }
        }
    }
    assert!(fovea_pixels > 300, "the fovea covers {fovea_pixels} pixels");
    // The sample counts the host reports equal the closed count.
    assert_eq!(fov_stats.samples_per_region, count_samples(W, H, &foveated));
    assert!(fov_stats.primary_samples < (W * H * 32) as u64 / 3);
    // Elsewhere the images agree on average (same estimator, fewer samples).
    let all = |img| mean_rgb(img, (0..H).flat_map(|y| (0..W).map(move |x| (x, y))));
    let (a, b) = (all(&fov), all(&uni));
    assert!(
        (a - b).abs().max_element() < 0.05 * b.max_element(),
        "foveated mean {a} vs uniform {b}"
    );
}

#[test]
fn image_does_not_depend_on_the_thread_count() {
    let scene = load_packed(&cornell_box_path(), &Environment::None);
    let frame = frame_params(
        cornell_camera(W, H),
        FoveationParams::paper([30.0, 40.0], 10.0, 25.0),
        W,
        H,
        3,
    );
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| render(&scene, &frame).0);
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| render(&scene, &frame).0);
    assert_eq!(one.pixels, two.pixels);
}

#[test]
fn gltf_and_obj_cornell_boxes_agree() {
    let gltf = bundled_scenes().join("cornell_box_gltf/cornell_box.gltf");
    let a = load_packed(&gltf, &Environment::None);
    let b = load_packed(&cornell_box_path(), &Environment::None);
    let frame = frame_params(cornell_camera(W, H), FoveationParams::uniform(16), W, H, 5);
    let all = |img: &fovea_cpu::FrameImage| {
        mean_rgb(img, (0..H).flat_map(|y| (0..W).map(move |x| (x, y))))
    };
    let (ma, mb) = (all(&render(&a, &frame).0), all(&render(&b, &frame).0));
    // Same geometry and emission (glTF: factor x KHR_materials_emissive_strength 17); the OBJ's Phong
    // exponent maps to a slightly different roughness, so allow 10 %.
    let rel = (ma - mb).abs() / mb.max(glam::Vec3::splat(1e-3));
    assert!(rel.max_element() < 0.10, "glTF {ma} vs OBJ {mb}");
}

#[test]
fn mis_light_only_and_bsdf_only_agree_on_average() {
    use fovea_core::integrator::path::{STRATEGY_BSDF_ONLY, STRATEGY_LIGHT_ONLY, STRATEGY_MIS};
    let scene = load_packed(&cornell_box_path(), &Environment::None);
    let (w, h) = (48, 36);
    let mean_of = |strategy: u32| {
        let mut frame = frame_params(
            cornell_camera(w, h),
            FoveationParams::uniform(256),
            w,
            h,
            11,
        );
        frame.integrator.strategy = strategy;
        let (image, _) = render(&scene, &frame);
        mean_rgb(&image, (0..h).flat_map(|y| (0..w).map(move |x| (x, y))))
    };
    let mis = mean_of(STRATEGY_MIS);
    let light = mean_of(STRATEGY_LIGHT_ONLY);
    let bsdf = mean_of(STRATEGY_BSDF_ONLY);
    // All three are unbiased estimators of the same image: their means agree to within noise (BSDF-only
    // is the noisiest with a small light), so an emitter hit that MIS dropped or double counted shows.
    for (name, m) in [("light-only", light), ("bsdf-only", bsdf)] {
        let rel = (m - mis).abs() / mis;
        assert!(rel.max_element() < 0.03, "{name} mean {m} vs MIS {mis}");
    }
}

/// The GPU kernel's schedule (`render_sample_stream`: every invocation renders every `stride`-th sample
/// of a chunk) gives every sample the value the CPU host computes for it, whatever the stride.
#[test]
fn sample_stream_matches_per_sample_rendering() {
    use fovea_core::foveation::OwnedBlock;
    use fovea_core::integrator::{render_block_sample, render_sample_stream};
    let scene = load_packed(&cornell_box_path(), &Environment::None);
    let frame = frame_params(cornell_camera(W, H), FoveationParams::uniform(3), W, H, 5);
    let blocks: Vec<OwnedBlock> = (0..37)
        .map(|i| OwnedBlock {
            origin: [i * 2 % W, i * 5 % H],
            size: 1,
            region: REGION_FOVEA,
        })
        .collect();
    let spp = 3;
    let total = blocks.len() as u32 * spp;
    let expected: Vec<[f32; 4]> = (0..total)
        .map(|i| {
            let c =
                render_block_sample(&scene.view(), &frame, &blocks[(i / spp) as usize], i % spp);
            [c.x, c.y, c.z, 0.0]
        })
        .collect();
    for stride in [1, 4, 7, total - 1, total, total + 5] {
        let mut out = vec![[f32::NAN; 4]; total as usize];
        for first in 0..stride.min(total) {
            render_sample_stream(
                &scene.view(),
                &fovea_core::scene::SceneSlices,
                &frame,
                &blocks,
                blocks.len() as u32,
                spp,
                first,
                stride,
                &mut out,
            );
        }
        assert_eq!(out, expected, "stride {stride}");
    }
}

/// A frame split by samples (`fovea render --samples`) and merged (`fovea merge`): the parts' sums
/// added and filled give the single render's image, bit for bit from one part holding every sample and
/// within float rounding of the sums' order from several.
#[test]
fn a_frame_split_by_samples_merges_to_the_single_render() {
    let scene = load_packed(&cornell_box_path(), &Environment::None);
    let view = scene.view();
    let foveated = FoveationParams::paper([W as f32 * 0.3, H as f32 * 0.6], 12.0, 28.0);
    let frame = frame_params(cornell_camera(W, H), foveated, W, H, 5);
    let (single, single_stats) = render(&scene, &frame);
    let fill = fovea_core::foveation::fill::FILL_BILINEAR;
    let merge = |ranges: &[[u32; 2]]| {
        let mut sums = vec![[0.0f32; 4]; (W * H) as usize];
        let mut samples = 0;
        for &range in ranges {
            let (part, stats) = fovea_cpu::render_sample_range(&view, &frame, range, &|_| {});
            samples += stats.primary_samples;
            for (s, p) in sums.iter_mut().zip(&part.pixels) {
                for c in 0..4 {
                    s[c] += p[c];
                }
            }
        }
        assert_eq!(
            samples, single_stats.primary_samples,
            "{ranges:?}: every sample once"
        );
        fovea_cpu::fill_from_sample_sums(&frame, &sums, fill)
    };
    assert_eq!(
        merge(&[[0, 32]]).pixels,
        single.pixels,
        "one part is the render"
    );
    // Uneven parts, one inside the periphery's 8 samples, one past the intermediate ring's 16.
    let merged = merge(&[[0, 3], [3, 8], [8, 20], [20, 32]]);
    let mut worst = 0.0f32;
    for (m, s) in merged.pixels.iter().zip(&single.pixels) {
        for c in 0..3 {
            worst = worst.max((m[c] - s[c]).abs() / s[c].abs().max(1e-3));
        }
    }
    // Float addition in another order: a few ulps of the sum (measured: below 1e-6).
    assert!(
        worst < 1e-5,
        "merged differs from the single render by {worst:e} (relative)"
    );
    eprintln!("four parts against the single render: worst relative difference {worst:e}");
}
