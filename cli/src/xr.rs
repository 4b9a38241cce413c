//! `fovea xr`: a headset through OpenXR. Each frame the runtime locates both eyes; each eye is
//! rendered as a view of the frame ([`fovea_core::passes::FrameRequest::view`]) at its pose and
//! field of view, foveated around its own gaze and with its own history (which head motion
//! reprojects, as a moving camera's), and copied into its layer of the runtime's swapchain on the
//! runtime's own Vulkan device (`fovea_vulkan::xr`). `--record` writes what `render --stereo-views`
//! needs to render the session again, frame for frame.
//!
//! The headset's tracking space (metres, looking along -z, y up) is placed at the scene's camera: its
//! origin at the camera's position, its -z along the camera's view, scaled by `--world-scale`.
use crate::args::XrArgs;
use crate::error::Result;

/// Runs `fovea xr` (this build cannot: the headset's swapchain is Vulkan's).
#[cfg(not(feature = "vulkan"))]
pub fn run(_args: &XrArgs) -> Result<()> {
    Err(crate::error::FoveaError::Backend(
        "this build of fovea has no Vulkan backend (built without the `vulkan` feature), which \
         `fovea xr` hands its images to the headset through"
            .into(),
    ))
}

#[cfg(feature = "vulkan")]
pub use session::run;

#[cfg(feature = "vulkan")]
mod session {
    use std::fmt::Write as _;
    use std::path::Path;
    use std::time::Instant;

    use fovea_core::camera::Camera;
    use fovea_vulkan::xr::{SessionStatus, XrEyeView, XrSession, XrSystem, READY_TIMEOUT, XR_EYES};
    use fovea_vulkan::{PresentSource, VulkanContext};
    use glam::{DMat3, DQuat, DVec3, Vec3};
    use serde_json::json;

    use super::*;
    use crate::args::XrGazeSource;
    use crate::backend::{FrameOutput, Renderer};
    use crate::error::FoveaError;
    use crate::output::{write_atomically, write_image, ImageFormat};
    use crate::scene_setup::{choose_camera, prepare_scene, Lighting};
    use crate::schedule::{EyeCamera, FrameSettings, FrameView, ScheduledFrame};
    use crate::stereo::{eye_path, EyeView};

    /// One eye of one frame, for `--stats`.
    struct EyeStats {
        frame: u32,
        eye: usize,
        gaze: [f32; 2],
        radii: [f32; 2],
        render_ms: f64,
        samples: u64,
        history_restarted: bool,
        /// The backend's own figures (the Vulkan host's chunks, warm-up, validation messages).
        extra: Option<serde_json::Value>,
    }

    /// Where the headset's tracking space lies in the scene: the scene camera's position and the
    /// rotation taking the tracking space's axes (x right, y up, -z ahead) to the camera's.
    struct TrackingOrigin {
        position: DVec3,
        rotation: DQuat,
        scale: f64,
    }

    impl TrackingOrigin {
        fn of(camera: &Camera, scale: f64) -> Self {
            let axis = |v: [f32; 4]| Vec3::from_slice(&v[..3]).normalize().as_dvec3();
            let right = axis(camera.right);
            let up = axis(camera.up);
            let back = right.cross(up);
            Self {
                position: Vec3::from_slice(&camera.position[..3]).as_dvec3(),
                rotation: DQuat::from_mat3(&DMat3::from_cols(right, up, back)).normalize(),
                scale,
            }
        }

        /// A direction of the tracking space (the gaze ray's) in world coordinates.
        fn direction(&self, d: [f32; 3]) -> Vec3 {
            (self.rotation * DVec3::from_array(d.map(f64::from))).as_vec3()
        }

        /// An eye the runtime located, in world coordinates (`origin`: the scene's, see
        /// `fovea_scene::rebase`), as a `--stereo-views` line gives it.
        fn eye(&self, view: &XrEyeView, origin: [f64; 3]) -> EyeView {
            let p = DVec3::from_array(view.position.map(f64::from));
            let local = self.position + self.rotation * (p * self.scale);
            let [x, y, z, w] = view.orientation.map(f64::from);
            let q = (self.rotation * DQuat::from_xyzw(x, y, z, w)).normalize();
            EyeView {
                position: (local + DVec3::from_array(origin)).to_array(),
                orientation: q.to_array(),
                angles: view.angles,
            }
        }
    }

    /// Where a gaze `direction` (world coordinates; the eyes' combined gaze ray, whose point at
    /// infinity both eyes see) falls on each eye's `size` image, in pixels; an eye that the direction
    /// points away from keeps its `ahead` fixation.
    fn gaze_in_eyes(
        direction: Vec3,
        eyes: &[EyeCamera; XR_EYES],
        [w, h]: [u32; 2],
        ahead: [[f32; 2]; XR_EYES],
    ) -> [[f32; 2]; XR_EYES] {
        [0, 1].map(|eye| {
            let film = eyes[eye].camera.film_position(direction, w, h);
            if film.z > 0.0 && film.x.is_finite() && film.y.is_finite() {
                [film.x, film.y]
            } else {
                ahead[eye]
            }
        })
    }

    /// An OpenXR failure as fovea's error.
    fn xr_failure(e: String) -> FoveaError {
        FoveaError::Backend(format!("OpenXR: {e}"))
    }

    /// Checks the options that need no runtime, before one is started.
    fn check_options(args: &XrArgs) -> Result<()> {
        if !(args.world_scale.is_finite() && args.world_scale > 0.0) {
            return Err(FoveaError::option(
                "--world-scale",
                "must be a positive number of scene units per metre",
            ));
        }
        if let Some(p) = &args.stats {
            crate::output::check_json_path(p, "--stats")?;
        }
        if let Some(dir) = &args.record {
            if dir.is_file() {
                return Err(FoveaError::option(
                    "--record",
                    format!("'{}' is a file, not a folder", dir.display()),
                ));
            }
            std::fs::create_dir_all(dir).map_err(|e| FoveaError::file(dir, e))?;
            crate::output::check_folder_takes_files(dir)
                .map_err(|why| FoveaError::option("--record", why))?;
        }
        Ok(())
    }

    /// Runs `fovea xr`.
    pub fn run(args: &XrArgs) -> Result<()> {
        check_options(args)?;
        let lighting = Lighting::from_args(&args.lighting)?;
        let system = XrSystem::new().map_err(xr_failure)?;
        let size = args.size.map_or(system.recommended_size, |s| s.0);
        let (mut renderer, mut copier) =
            Renderer::for_headset(system.device_factory(), &args.target)?;
        let device = match (renderer.vulkan_context(), copier.as_ref()) {
            (Some(ctx), _) => ctx.device_description(),
            (None, Some(ctx)) => ctx.device_description(),
            (None, None) => unreachable!("a headset renderer always has a context"),
        };
        let mut notes = vec![format!(
            "OpenXR runtime {} on '{}', Vulkan device {device}, {}x{} per eye",
            system.runtime, system.system_name, size[0], size[1]
        )];
        if args.gaze_source == XrGazeSource::Ahead {
            notes.push(if system.eye_gaze_available {
                "gaze from XR_EXT_eye_gaze_interaction: each eye fixates the runtime's gaze ray, \
                 projected into its view (straight ahead while the ray is not tracked)"
                    .into()
            } else {
                "no eye-gaze extension (XR_EXT_eye_gaze_interaction): each eye fixates straight \
                 ahead (or give --gaze-source udp:PORT)"
                    .into()
            });
        }
        if !args.quiet {
            for n in &notes {
                eprintln!("note: {n}");
            }
        }
        // The session lives on the context, and goes before it (the end of this scope).
        let session = match (&copier, renderer.vulkan_context()) {
            (Some(ctx), _) => XrSession::new(&system, ctx),
            (None, Some(ctx)) => XrSession::new(&system, ctx),
            (None, None) => unreachable!("a headset renderer always has a context"),
        };
        let mut session = session.map_err(xr_failure)?;
        if let (Some(note), false) = (&session.eye_gaze_note, args.quiet) {
            eprintln!("note: {note}; each eye fixates straight ahead");
        }
        session
            .create_swapchain(&system, size)
            .map_err(xr_failure)?;
        let outcome = run_session(
            args,
            &lighting,
            size,
            &mut renderer,
            &mut copier,
            &mut session,
        );
        drop(session);
        let mut outcome = outcome?;
        outcome.notes.splice(0..0, notes);
        finish(args, &renderer, copier.as_ref(), size, &outcome)
    }

    /// What a session did, for `--stats`, `--record` and the summary line.
    struct Outcome {
        frames: u32,
        skipped: u32,
        ending: String,
        frame_ms: Vec<f64>,
        wait_ms: Vec<f64>,
        eyes: Vec<EyeStats>,
        views_csv: String,
        gaze_csv: String,
        warnings: Vec<String>,
        notes: Vec<String>,
        wall_ms: f64,
    }

    /// The frame loop: poll, wait, locate, render each eye and copy it in, end the frame.
    fn run_session(
        args: &XrArgs,
        lighting: &Lighting,
        size: [u32; 2],
        renderer: &mut Renderer,
        copier: &mut Option<VulkanContext>,
        session: &mut XrSession,
    ) -> Result<Outcome> {
        let (eye, look_at, up) = args.camera.points();
        let scene = prepare_scene(
            args.scene.as_deref(),
            args.materials.mtl.as_deref(),
            args.materials.mtl_diffuse.into(),
            &lighting.environment(args.scene.is_none()),
            &lighting.point_lights,
            renderer.wants_wide_bvh(),
        )?;
        let settings = FrameSettings::new(size, &args.path, &args.image);
        let camera = choose_camera(&scene, eye, look_at, up, args.camera.fov, settings.aspect())?;
        let tracking = TrackingOrigin::of(&camera, args.world_scale);
        renderer.set_scene(&scene.packed, !args.no_specialize)?;
        let (template, _, warnings) = crate::render::foveation_of(&args.foveation, size)?;
        let rule = crate::render::foveation_rule(&args.foveation, template);
        let mut gaze_udp = match args.gaze_source {
            XrGazeSource::Ahead => None,
            XrGazeSource::Udp(port) => Some(
                crate::gaze::UdpGazeSource::bind(
                    std::net::SocketAddr::from(([127, 0, 0, 1], port)),
                    crate::gaze::GazeConvention::Normalized,
                )
                .map_err(|e| FoveaError::option("--gaze-source", e))?,
            ),
        };
        let history = !args.no_history;
        // The Vulkan backend keeps each eye's image on the device for the copy (a read-back only to
        // record it); the CPU backend hands over its pixels.
        let on_device = copier.is_none();
        let output = if on_device && args.record.is_none() {
            FrameOutput::Present { overlay: false }
        } else {
            FrameOutput::ReadBack {
                want_hdr: args.record.is_some(),
                want_raw: false,
            }
        };
        let request = settings.request(history, args.denoise, output);
        let mut out = Outcome {
            frames: 0,
            skipped: 0,
            ending: String::new(),
            frame_ms: Vec::new(),
            wait_ms: Vec::new(),
            eyes: Vec::new(),
            views_csv: String::from(
                "frame,eye,x,y,z,qx,qy,qz,qw,angle_left,angle_right,angle_up,angle_down\n",
            ),
            gaze_csv: String::from("frame,lx,ly,rx,ry\n"),
            warnings,
            notes: Vec::new(),
            wall_ms: 0.0,
        };
        let mut untracked = 0u32;
        let mut last_gaze: Option<[[f32; 2]; XR_EYES]> = None;
        let start = Instant::now();
        let mut waiting_since = Instant::now();
        out.ending = loop {
            match session.poll().map_err(xr_failure)? {
                SessionStatus::Over(why) => break why,
                SessionStatus::Waiting => {
                    if waiting_since.elapsed() > READY_TIMEOUT {
                        return Err(xr_failure(format!(
                            "the session did not become ready within {} s",
                            READY_TIMEOUT.as_secs()
                        )));
                    }
                    std::thread::sleep(std::time::Duration::from_millis(5));
                    continue;
                }
                SessionStatus::Running => waiting_since = Instant::now(),
            }
            if args.frames.is_some_and(|n| out.frames >= n) {
                session.request_exit().map_err(xr_failure)?;
                // The runtime stops the session; keep polling until it has.
                std::thread::sleep(std::time::Duration::from_millis(5));
                continue;
            }
            let waited = Instant::now();
            let frame = session.begin_frame().map_err(xr_failure)?;
            out.wait_ms.push(waited.elapsed().as_secs_f64() * 1e3);
            if !frame.should_render {
                out.skipped += 1;
                session.end_frame(&frame, false).map_err(xr_failure)?;
                continue;
            }
            untracked += u32::from(!frame.orientation_tracked);
            if let Some(source) = gaze_udp.as_mut() {
                if let Some((sample, _)) = source.poll(size).newest {
                    last_gaze = Some(sample.eyes.unwrap_or([[sample.x, sample.y]; XR_EYES]));
                }
            }
            let began = Instant::now();
            let number = out.frames;
            let eye_views = frame.views.map(|v| tracking.eye(&v, scene.origin));
            let eyes = eye_views.map(|v| EyeCamera {
                camera: v.camera(scene.origin),
                focal_px: Some(v.focal_px(size[0])),
            });
            let ahead = eye_views.map(|v| v.ahead_px(size));
            let gazes = match (last_gaze, frame.gaze_ray, args.gaze_source) {
                (Some(udp), ..) => udp,
                (None, Some((_, direction)), XrGazeSource::Ahead) => {
                    gaze_in_eyes(tracking.direction(direction), &eyes, size, ahead)
                }
                _ => ahead,
            };
            let scheduled = ScheduledFrame {
                number,
                gaze: gazes[0],
                eyes: Some(gazes),
                camera: None,
            };
            for FrameView {
                view,
                frame: params,
            } in settings.views(&scheduled, camera, Some(eyes), &rule)
            {
                let eye = view.expect("a headset frame has two eyes");
                let rendered = renderer.render(
                    &scene.packed,
                    &params,
                    &request.for_view(eye as u32),
                    &|_| {},
                )?;
                match (copier.as_mut(), &rendered.image.rgba8) {
                    (Some(ctx), Some(pixels)) => session.copy_eye(
                        ctx,
                        eye,
                        PresentSource::Host {
                            pixels,
                            width: size[0],
                            height: size[1],
                        },
                    ),
                    (None, _) => {
                        let ctx = renderer
                            .vulkan_context()
                            .expect("the Vulkan backend has its context");
                        session.copy_eye(ctx, eye, PresentSource::LastFrame)
                    }
                    (Some(_), None) => Err("the CPU backend returned no 8-bit image".into()),
                }
                .map_err(xr_failure)?;
                if let Some(dir) = &args.record {
                    let hdr = rendered.image.hdr.as_ref().ok_or_else(|| {
                        FoveaError::Backend("the backend returned no HDR image to record".into())
                    })?;
                    let path =
                        crate::render::frame_path(&eye_path(&dir.join("f.exr"), eye), number);
                    write_image(&path, ImageFormat::Exr, hdr, settings.exposure_ev)?;
                }
                let v = &eye_views[eye];
                let [x, y, z] = v.position;
                let [qx, qy, qz, qw] = v.orientation;
                let [l, r, u, d] = v.angles;
                let name = fovea_core::passes::STEREO_VIEW_NAMES[eye];
                let _ = writeln!(
                    out.views_csv,
                    "{number},{name},{x},{y},{z},{qx},{qy},{qz},{qw},{l},{r},{u},{d}"
                );
                out.eyes.push(EyeStats {
                    frame: number,
                    eye,
                    gaze: params.foveation.gaze,
                    radii: [
                        params.foveation.radius_fovea,
                        params.foveation.radius_intermediate,
                    ],
                    render_ms: rendered.stats.render_ms,
                    samples: rendered.stats.primary_samples,
                    history_restarted: history && rendered.history_restarted,
                    extra: rendered.extra.clone(),
                });
            }
            let [[lx, ly], [rx, ry]] = gazes;
            let _ = writeln!(out.gaze_csv, "{number},{lx},{ly},{rx},{ry}");
            session.end_frame(&frame, true).map_err(xr_failure)?;
            out.frame_ms.push(began.elapsed().as_secs_f64() * 1e3);
            out.frames += 1;
        };
        if untracked > 0 {
            out.notes.push(format!(
                "the runtime did not track the head's orientation in {untracked} of {} frames (a \
                 simulated headset holds still)",
                out.frames
            ));
        }
        out.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(out)
    }

    /// Writes `--record`'s files and `--stats`, and prints the summary line.
    fn finish(
        args: &XrArgs,
        renderer: &Renderer,
        copier: Option<&VulkanContext>,
        size: [u32; 2],
        out: &Outcome,
    ) -> Result<()> {
        if let Some(dir) = &args.record {
            write_text(&dir.join("views.csv"), &out.views_csv)?;
            write_text(&dir.join("gaze.csv"), &out.gaze_csv)?;
        }
        let median = |v: &[f64]| {
            let mut v = v.to_vec();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(0.0)
        };
        let validation: Vec<String> = renderer
            .validation_messages()
            .into_iter()
            .chain(
                copier
                    .map(VulkanContext::validation_messages)
                    .unwrap_or_default(),
            )
            .collect();
        if let Some(p) = &args.stats {
            let report = json!({
                "command": "xr",
                "backend": renderer.name(),
                "device": renderer.device_name(),
                "size_per_eye": size,
                "frames_submitted": out.frames,
                "frames_skipped": out.skipped,
                "ending": out.ending,
                "history": !args.no_history,
                "median_frame_ms": median(&out.frame_ms),
                "median_wait_ms": median(&out.wait_ms),
                "wall_ms": out.wall_ms,
                "notes": out.notes,
                "warnings": out.warnings,
                "validation_messages": validation,
                "eyes": out.eyes.iter().map(|e| json!({
                    "frame": e.frame,
                    "view": fovea_core::passes::STEREO_VIEW_NAMES[e.eye],
                    "gaze": e.gaze,
                    "radii_px": e.radii,
                    "render_ms": e.render_ms,
                    "primary_samples": e.samples,
                    "history_restarted": e.history_restarted,
                    "backend_details": e.extra,
                })).collect::<Vec<_>>(),
            });
            crate::stats::write_json(p, &report)?;
        }
        if !args.quiet {
            println!(
                "fovea xr: {} frames of {}x{} per eye on {} in {:.0} ms a frame (median); {}",
                out.frames,
                size[0],
                size[1],
                renderer.name(),
                median(&out.frame_ms),
                out.ending
            );
        }
        Ok(())
    }

    /// Writes `text` to `path` atomically.
    fn write_text(path: &Path, text: &str) -> Result<()> {
        write_atomically(path, |tmp| {
            std::fs::write(tmp, text.as_bytes()).map_err(|e| e.to_string())
        })
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// An eye of a headset at the tracking origin, turned by `yaw` radians about y, with a
        /// symmetric frustum of ±0.8 rad.
        fn eye(tracking: &TrackingOrigin, yaw: f32, x: f32) -> EyeCamera {
            let (s, c) = (0.5 * yaw).sin_cos();
            let view = tracking.eye(
                &XrEyeView {
                    position: [x, 0.0, 0.0],
                    orientation: [0.0, s, 0.0, c],
                    angles: [-0.8, 0.8, 0.8, -0.8],
                },
                [0.0; 3],
            );
            EyeCamera {
                camera: view.camera([0.0; 3]),
                focal_px: Some(view.focal_px(64)),
            }
        }

        #[test]
        fn the_gaze_ray_falls_where_each_eye_sees_its_direction() {
            let camera = Camera::look_at(
                Vec3::new(0.0, 1.0, 4.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::Y,
                1.0,
                64.0 / 48.0,
            );
            let tracking = TrackingOrigin::of(&camera, 1.0);
            let eyes = [eye(&tracking, 0.0, -0.032), eye(&tracking, 0.0, 0.032)];
            let ahead = [[-1.0, -1.0]; 2];
            // Straight ahead (the tracking space's -z): each eye's centre.
            let centre = gaze_in_eyes(tracking.direction([0.0, 0.0, -1.0]), &eyes, [64, 48], ahead);
            for [x, y] in centre {
                assert!(
                    (x - 32.0).abs() < 1e-3 && (y - 24.0).abs() < 1e-3,
                    "{centre:?}"
                );
            }
            // To the left and up: left of and above the centre, alike in both eyes (a direction
            // has no parallax).
            let d = tracking.direction([-0.3, 0.2, -1.0]);
            let [l, r] = gaze_in_eyes(d, &eyes, [64, 48], ahead);
            assert!(l[0] < 30.0 && l[1] < 22.0, "{l:?}");
            assert!((l[0] - r[0]).abs() < 1e-3 && (l[1] - r[1]).abs() < 1e-3);
            // Behind the eyes: they keep their own fixation.
            let behind = gaze_in_eyes(tracking.direction([0.0, 0.0, 1.0]), &eyes, [64, 48], ahead);
            assert_eq!(behind, ahead);
            // An eye turned 0.5 rad to the left sees the straight-ahead direction right of its centre.
            let turned = [eye(&tracking, 0.5, -0.032), eyes[1]];
            let [t, _] = gaze_in_eyes(
                tracking.direction([0.0, 0.0, -1.0]),
                &turned,
                [64, 48],
                ahead,
            );
            assert!(t[0] > 40.0, "{t:?}");
        }
    }
}
