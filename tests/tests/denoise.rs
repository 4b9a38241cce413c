//! The foveated denoiser end to end (`fovea_core::denoise`, the CPU's denoiser passes, the kernel's
//! `denoise_input`/`denoise_atrous`/`denoise_output`): closer to converged than the raw frame, the
//! fovea's detail kept, and the same on the CPU and lavapipe.
//!
//! The Cornell box at 96 × 72; errors are relMSE against a uniform 1024-spp render of the same camera
//! (`-- --nocapture` prints them).
use fovea_core::camera::Camera;
use fovea_core::foveation::fill::FILL_BILINEAR;
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::integrator::FrameParams;
use fovea_core::passes::{FrameOutput, FrameRequest};
use fovea_cpu::{render_frame_passes, FrameImage, TemporalHistory};
use fovea_scene::environment::Environment;
use fovea_scene::pack::PackedScene;
use fovea_tests::*;
use glam::Vec3;

const W: u32 = 96;
const H: u32 = 72;
const RADII: [f32; 2] = [16.0, 30.0];
const CENTRE: [f32; 2] = [48.0, 36.0];

fn scene() -> PackedScene {
    load_packed(&cornell_box_path(), &Environment::None)
}

fn frame(camera: Camera, gaze: [f32; 2], spp: [u32; 3], index: u32) -> FrameParams {
    let mut foveation = FoveationParams::paper(gaze, RADII[0], RADII[1]);
    foveation.spp = [spp[0], spp[1], spp[2], 0];
    let mut f = frame_params(camera, foveation, W, H, 7);
    f.frame_index = index;
    f
}

/// One frame's HDR image on the CPU with `request` (and `history` kept across calls).
fn cpu_frame(
    scene: &PackedScene,
    f: &FrameParams,
    history: &mut TemporalHistory,
    request: FrameRequest,
) -> FrameImage {
    render_frame_passes(&scene.view(), f, &request, history, &|_| {})
        .0
        .hdr
        .expect("the CPU host returns the HDR image")
}

fn distance_to_centre(x: u32, y: u32) -> f32 {
    ((x as f32 + 0.5 - CENTRE[0]).powi(2) + (y as f32 + 0.5 - CENTRE[1]).powi(2)).sqrt()
}

/// The HDR image alone, raw.
const RAW: FrameRequest = FrameRequest {
    fill_mode: FILL_BILINEAR,
    exposure_ev: 0.0,
    history: false,
    denoise: false,
    output: FrameOutput::Hdr,
    view: 0,
};
/// The HDR image alone, denoised.
const DENOISE: FrameRequest = FrameRequest {
    denoise: true,
    ..RAW
};

#[test]
fn denoising_a_low_budget_frame_brings_it_closer_to_converged_and_keeps_the_fovea() {
    let scene = scene();
    let camera = cornell_camera(W, H);
    let mut reference_frame = frame_params(camera, FoveationParams::uniform(1024), W, H, 99);
    reference_frame.frame_index = 1 << 20;
    let reference = render(&scene, &reference_frame).0;
    let fovea = |x: u32, y: u32| distance_to_centre(x, y) < RADII[0] - 4.0;
    let all = |_: u32, _: u32| true;
    let run = |spp: [u32; 3], request: FrameRequest| {
        cpu_frame(
            &scene,
            &frame(camera, CENTRE, spp, 1),
            &mut TemporalHistory::new(),
            request,
        )
    };
    let raw_low = run([4, 2, 1], RAW);
    let denoised_low = run([4, 2, 1], DENOISE);
    let raw_full = run([32, 16, 8], RAW);
    let denoised_full = run([32, 16, 8], DENOISE);
    let e =
        |img: &FrameImage, keep: &dyn Fn(u32, u32) -> bool| rel_mse_where(img, &reference, keep);
    eprintln!(
        "relMSE whole / fovea: raw 4/2/1 {:.4} / {:.4}, denoised 4/2/1 {:.4} / {:.4}, raw 32/16/8 {:.4} / {:.4}, denoised 32/16/8 {:.4} / {:.4}",
        e(&raw_low, &all),
        e(&raw_low, &fovea),
        e(&denoised_low, &all),
        e(&denoised_low, &fovea),
        e(&raw_full, &all),
        e(&raw_full, &fovea),
        e(&denoised_full, &all),
        e(&denoised_full, &fovea),
    );
    assert!(e(&denoised_low, &all) < 0.7 * e(&raw_low, &all));
    assert!(e(&denoised_low, &fovea) < 0.7 * e(&raw_low, &fovea));
    // At the full 32 samples per pixel the fovea is left alone: it keeps every detail it paid for.
    assert!(e(&denoised_full, &fovea) <= 1.001 * e(&raw_full, &fovea));
}

#[test]
fn cpu_and_lavapipe_denoise_alike() {
    let Some(mut ctx) = vulkan_context_or_skip("the denoiser's cross-backend test") else {
        return;
    };
    let scene = scene();
    let gpu_scene = ctx.upload_scene(&scene).expect("upload");
    let camera_at = |i: u32| {
        let eye = Vec3::new(0.02 * i as f32, 1.0, 3.9);
        Camera::look_at(
            eye,
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::Y,
            38f32.to_radians(),
            W as f32 / H as f32,
        )
    };
    // The frame alone, then six frames of history with a jittered gaze and a moving camera. Both
    // backends also hand back the image as the denoiser found it (`render --keep-raw`).
    for history_frames in [0u32, 6] {
        let history = history_frames > 0;
        let request = FrameRequest {
            history,
            output: FrameOutput::ReadBack {
                want_hdr: true,
                want_raw: true,
            },
            ..DENOISE
        };
        let mut cpu_history = TemporalHistory::new();
        ctx.reset_history();
        let (mut cpu, mut gpu) = (None, None);
        for i in 0..history_frames.max(1) {
            let gaze = [CENTRE[0] + (i % 3) as f32 * 1.7, CENTRE[1] - (i % 2) as f32];
            let f = frame(camera_at(i.min(4)), gaze, [4, 2, 1], i);
            let image =
                render_frame_passes(&scene.view(), &f, &request, &mut cpu_history, &|_| {}).0;
            if !history {
                // Without history the raw image is exactly the frame rendered without the denoiser.
                let plain = cpu_frame(&scene, &f, &mut TemporalHistory::new(), RAW);
                assert_eq!(
                    image.raw_hdr.as_ref().expect("raw kept").pixels,
                    plain.pixels
                );
            }
            cpu = Some((
                image.hdr.expect("the CPU host returns the HDR image"),
                image.raw_hdr.expect("raw kept"),
            ));
            let (image, _) = ctx
                .render(&gpu_scene, &f, &request, &|_| {})
                .expect("the device renders");
            gpu = Some((
                image.hdr.expect("HDR was asked for"),
                image.raw_hdr.expect("raw kept"),
            ));
        }
        let ((cpu, cpu_raw), (gpu, gpu_raw)) = (cpu.unwrap(), gpu.unwrap());
        let (fraction, max_abs) = agreement(&cpu, &gpu);
        let (raw_fraction, _) = agreement(&cpu_raw, &gpu_raw);
        let (denoised_is_raw, _) = agreement(&gpu, &gpu_raw);
        let messages = ctx.validation_messages();
        eprintln!(
            "denoised, {history_frames} frames of history: CPU against lavapipe {:.3} % of pixels within 1e-3, max abs {max_abs:.2e} (raw: {:.3} %); {} validation messages",
            fraction * 100.0,
            raw_fraction * 100.0,
            messages.len()
        );
        assert!(messages.is_empty(), "{messages:?}");
        assert!(fraction >= 0.995, "{fraction}");
        assert!(raw_fraction >= 0.995, "{raw_fraction}");
        assert!(
            denoised_is_raw < 0.9,
            "the denoiser changed {denoised_is_raw} of the pixels"
        );
    }
}
