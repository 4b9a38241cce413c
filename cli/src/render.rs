//! `fovea render`: parse and check every option, load the scene, render one frame (or one per gaze-trace
//! line), write images and statistics.
use std::path::{Path, PathBuf};
use std::time::Instant;

use fovea_core::foveation::blocks::count_samples;
use fovea_core::foveation::regions::{FoveationParams, FOVEATION_OK};
use fovea_core::integrator::FrameParams;
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::RenderArgs;
use crate::backend::{FrameOutput, Renderer};
use crate::error::{FoveaError, Result};
use crate::output::{
    check_json_path, check_output_path, regions_overlay, tonemapped_rgb8, write_image, write_png,
    ImageFormat, WrittenFiles,
};
use crate::partial::{
    identity_lines, largest_spp, samples_in_part, write_part, PartSpec, RenderIdentity,
};
use crate::scene_setup::{choose_camera, prepare_scene, Lighting, PreparedScene};
use crate::stats::FrameStats;

use crate::schedule::{
    FoveationRule, FrameSchedule, FrameSettings, FrameView, LonePath, ScheduledFrame,
};
use crate::stereo::{eye_path, StereoSource, EYES};
use crate::values::{self, SampleSelection};

/// How the foveation options make each view's foveation from `template` ([`foveation_of`]'s):
/// fixated on the view's gaze unless uniform, and, where `--radii` does not fix them, with radii
/// from each eye's own frustum (a views file's or a headset's eyes).
pub(crate) fn foveation_rule(
    options: &crate::args::FoveationArgs,
    template: FoveationParams,
) -> FoveationRule {
    FoveationRule {
        template,
        uniform: options.uniform,
        eye_eccentricity: options
            .radii
            .is_none()
            .then_some(options.display.eccentricity.0),
    }
}

/// Everything `render` needs, parsed and checked before any work starts.
struct Plan {
    resolution: [u32; 2],
    /// The run's foveation, and how each view's gaze and eye set it.
    foveation_rule: FoveationRule,
    radii_px: [f32; 2],
    /// The frames, each with its gaze and camera.
    schedule: FrameSchedule,
    output: PathBuf,
    output_format: ImageFormat,
    /// `--samples`: this run renders one part of a split render, written to `output` (a .fvpart file):
    /// its sample range, and its index and count for `--samples I/N`.
    samples: Option<PartSpec>,
    /// `--keep-raw`: where the image before the denoiser goes.
    keep_raw: Option<(PathBuf, ImageFormat)>,
    per_frame_outputs: bool,
    /// `--stereo`, `--stereo-views`: each frame's two eyes.
    stereo: Option<StereoSource>,
    settings: FrameSettings,
    lighting: Lighting,
    /// Every file the run writes (each frame's and eye's), resolved once.
    written: WrittenFiles,
    /// Options that are accepted but do not do what a user may expect (printed unless `--quiet`).
    warnings: Vec<String>,
}

/// The foveation the options give an image of `resolution` (the gaze at its centre), its region radii
/// in pixels, and the warnings about options it does not use.
pub(crate) fn foveation_of(
    options: &crate::args::FoveationArgs,
    resolution: [u32; 2],
) -> Result<(FoveationParams, [f32; 2], Vec<String>)> {
    let [w, h] = resolution;
    let (spp, blocks) = (options.spp.0, options.blocks.0);
    let mut warnings = Vec::new();
    // The image fills the display, so pixels per centimetre come from the rendered width.
    let (display, aspect_warning) = values::display_geometry(
        options.display.display_cm,
        options.display.distance_cm,
        resolution,
    )?;
    let radii_px = match options.radii {
        Some(r) => r.0,
        None => {
            warnings.extend(aspect_warning);
            values::eccentricity_radii(options.display.eccentricity, &display)
        }
    };
    let foveation = if options.uniform {
        if spp[1..] != [16, 8] || blocks != [1, 2, 4] || options.radii.is_some() {
            warnings.push(format!(
                "--uniform renders every pixel at --spp's first value ({}); the other --spp values, \
                 --blocks and --radii are not used",
                spp[0]
            ));
        }
        FoveationParams::uniform(spp[0])
    } else {
        FoveationParams::new([0.5 * w as f32, 0.5 * h as f32], radii_px, spp, blocks)
    };
    if foveation.validate() != FOVEATION_OK {
        return Err(FoveaError::option(
            "--spp/--blocks/--radii",
            "the foveation settings are inconsistent",
        ));
    }
    Ok((foveation, radii_px, warnings))
}

fn plan(args: &RenderArgs) -> Result<Plan> {
    let resolution = args.resolution.0;
    let [w, h] = resolution;
    let (mut foveation_template, radii_px, mut warnings) =
        foveation_of(&args.foveation, resolution)?;
    let sequence = &args.sequence;
    if sequence.gaze_trace.is_some() && args.gaze.is_some() {
        return Err(FoveaError::option(
            "--gaze-trace",
            "give either --gaze or --gaze-trace, not both",
        ));
    }
    if args.frame != 0 {
        if sequence.gaze_trace.is_some() {
            return Err(FoveaError::option(
                "--frame",
                "numbers a single frame; a --gaze-trace numbers its own frames (its first column)",
            ));
        }
        if sequence.camera_path.is_some() {
            return Err(FoveaError::option(
                "--frame",
                "numbers a single frame; a --camera-path numbers its own frames (its first column)",
            ));
        }
    }
    let still = ScheduledFrame {
        number: args.frame,
        gaze: args.gaze.map_or([0.5 * w as f32, 0.5 * h as f32], |g| g.0),
        eyes: None,
        camera: None,
    };
    let mut schedule =
        FrameSchedule::read(sequence, still, resolution, LonePath::NumbersFrames, None)?;
    warnings.extend(schedule.notes.iter().cloned());
    let stereo = stereo_of(args, &mut schedule)?;
    if stereo.is_none() && schedule.frames.iter().any(|f| f.eyes.is_some()) {
        warnings.push(
            "the --gaze-trace gives both eyes' gaze; one view is rendered, fixated between them \
             (--stereo IPD renders each eye with its own)"
                .to_string(),
        );
    }
    if args.history && schedule.frames.len() < 2 {
        warnings.push(
            "--history accumulates over the frames of a --gaze-trace or --camera-path; a single \
             frame is rendered as it is"
                .to_string(),
        );
    }
    foveation_template.gaze = schedule.frames[0].gaze;
    if foveation_template.validate() != FOVEATION_OK {
        return Err(FoveaError::option(
            "--spp/--blocks/--radii",
            "the foveation settings are inconsistent",
        ));
    }

    let samples = args
        .samples
        .map(|s| check_part_options(args, s, &foveation_template))
        .transpose()?;
    // A part is neither image format; EXR stands in (linear, no tone map) and is never written.
    let output_format = match samples {
        Some(_) => ImageFormat::Exr,
        None => check_output_path(&args.output, "--output", true)?,
    };
    if let Some(p) = &args.regions_overlay {
        check_output_path(p, "--regions-overlay", false)?;
    }
    let keep_raw = match &args.keep_raw {
        None => None,
        Some(_) if !args.denoise => {
            return Err(FoveaError::option(
                "--keep-raw",
                "keeps the image the denoiser starts from; add --denoise",
            ))
        }
        Some(p) => Some((p.clone(), check_output_path(p, "--keep-raw", true)?)),
    };
    if let Some(p) = &args.stats {
        check_json_path(p, "--stats")?;
    }

    if samples.is_some() && args.image.exposure != 0.0 {
        warnings.push(
            "--exposure does not apply to a part (linear sums); give it to `fovea merge` for a PNG"
                .into(),
        );
    }
    let only_exr = output_format == ImageFormat::Exr
        && args.regions_overlay.is_none()
        && args.samples.is_none();
    if args.image.exposure != 0.0 && only_exr {
        warnings.push(
            "--exposure applies to tone-mapped images (PNG, --regions-overlay); the --output EXR is linear"
                .into(),
        );
    }

    let mut plan = Plan {
        resolution,
        foveation_rule: foveation_rule(&args.foveation, foveation_template),
        radii_px,
        per_frame_outputs: schedule.from_files,
        schedule,
        stereo,
        output: args.output.clone(),
        output_format,
        samples,
        keep_raw,
        settings: FrameSettings::new(resolution, &args.path, &args.image),
        lighting: Lighting::default(),
        written: WrittenFiles::resolve::<PathBuf>(&[])?,
        warnings,
    };
    // Every file the run writes, checked against each other and the command line's inputs before
    // the environment map is read (an output over it must be refused, not a missing map); the
    // scene's own files are checked against the same set once the scene is read.
    plan.written = WrittenFiles::resolve(&written_files(args, &plan))?;
    plan.written.refuse_inputs(&command_line_inputs(args))?;
    plan.lighting = Lighting::from_args(&args.lighting)?;
    Ok(plan)
}

/// `--stereo IPD` or `--stereo-views FILE`, read and checked against the frames `schedule` holds; a
/// views file without a gaze trace or camera path gives the frames (each at the still gaze).
fn stereo_of(args: &RenderArgs, schedule: &mut FrameSchedule) -> Result<Option<StereoSource>> {
    let source = match (&args.stereo.stereo, &args.stereo.stereo_views) {
        (Some(ipd), _) => StereoSource::Separation(ipd.0),
        (None, Some(path)) => {
            if args.sequence.camera_path.is_some() {
                return Err(FoveaError::option(
                    "--stereo-views",
                    "gives every frame's eye poses; leave out --camera-path (or use --stereo IPD \
                     with it)",
                ));
            }
            StereoSource::Views(crate::stereo::read_eye_views(path)?)
        }
        (None, None) => return Ok(None),
    };
    if let (Some(numbers), false) = (source.frame_numbers(), schedule.from_files) {
        let still = schedule.frames[0];
        schedule.frames = numbers
            .into_iter()
            .map(|number| ScheduledFrame { number, ..still })
            .collect();
        schedule.from_files = true;
    }
    if let StereoSource::Views(views) = &source {
        if let Some(f) = schedule
            .frames
            .iter()
            .find(|f| !views.contains_key(&f.number))
        {
            return Err(FoveaError::option(
                "--stereo-views",
                format!(
                    "has no lines for frame {}, which the --gaze-trace renders",
                    f.number
                ),
            ));
        }
    }
    Ok(Some(source))
}

/// `--samples`: one still frame on the CPU, written as a part (.fvpart) whose range lies within the
/// frame's samples.
fn check_part_options(
    args: &RenderArgs,
    selection: SampleSelection,
    foveation: &FoveationParams,
) -> Result<PartSpec> {
    let refuse = |option: &'static str, why: &str| {
        Err(FoveaError::option(
            option,
            format!("{why}; --samples renders one part of a single still frame"),
        ))
    };
    if args.sequence.gaze_trace.is_some() {
        return refuse("--gaze-trace", "renders a sequence");
    }
    if args.sequence.camera_path.is_some() {
        return refuse("--camera-path", "renders a sequence");
    }
    if args.history {
        return refuse("--history", "accumulates over a sequence");
    }
    if args.stereo.stereo.is_some() || args.stereo.stereo_views.is_some() {
        return refuse("--stereo", "renders two views");
    }
    if args.denoise {
        return refuse(
            "--denoise",
            "filters a whole image (denoise the merged one)",
        );
    }
    if args.regions_overlay.is_some() {
        return refuse("--regions-overlay", "draws over a whole image");
    }
    crate::backend::cpu_target_for_parts(&args.target, "--samples")?;
    let spec = PartSpec::new(selection, largest_spp(foveation))
        .map_err(|why| FoveaError::option("--samples", why))?;
    let is_part = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("fvpart"));
    if !is_part {
        return Err(FoveaError::option(
            "--output",
            format!(
                "'{}': with --samples the output is a part file (.fvpart), which `fovea merge` joins into the image",
                args.output.display()
            ),
        ));
    }
    crate::output::check_writable_file(&args.output, "--output")?;
    Ok(spec)
}

/// `out.png` → `out_00012.png` for frame 12 of a gaze trace.
pub(crate) fn frame_path(path: &Path, frame: u32) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}_{frame:05}.{ext}"))
}

/// Runs `fovea render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    let wall = Instant::now();
    let plan = plan(args)?;
    // The command line's warnings (the scene's are in `scene.warnings`), for `--stats` too.
    let mut run_warnings = plan.warnings.clone();
    if !args.quiet {
        for w in &plan.warnings {
            eprintln!("warning: {w}");
        }
    }
    // The backend first: a bad `--device` fails before the scene loads. A part renders on the CPU.
    let target = match plan.samples {
        Some(_) => crate::backend::cpu_target_for_parts(&args.target, "--samples")?,
        None => args.target,
    };
    if args.dry_run {
        let scene = args
            .scene
            .clone()
            .unwrap_or_else(crate::scene_setup::default_scene_path);
        std::fs::File::open(&scene).map_err(|e| FoveaError::file(&scene, e))?;
        if !args.quiet {
            println!("fovea: the command line is valid (--dry-run: nothing rendered)");
        }
        return Ok(());
    }
    let mut renderer = Renderer::new(&target, args.quiet)?;
    let (eye, target, up) = args.camera.points();
    let scene = prepare_scene(
        args.scene.as_deref(),
        args.materials.mtl.as_deref(),
        args.materials.mtl_diffuse.into(),
        &plan.lighting.environment(args.scene.is_none()),
        &plan.lighting.point_lights,
        renderer.wants_wide_bvh(),
    )?;
    // The scene's own files (its MTL libraries, buffers, textures) are known once it is read.
    let scene_files: Vec<&Path> = scene.files.iter().map(PathBuf::as_path).collect();
    plan.written.refuse_inputs(&scene_files)?;
    run_warnings.extend(describe_scene(args, &scene));

    let settings = plan.settings;
    let camera = choose_camera(&scene, eye, target, up, args.camera.fov, settings.aspect())?;
    let cameras = plan.schedule.cameras(camera, |key| {
        choose_camera(
            &scene,
            Some(key.eye),
            Some(key.target),
            up,
            args.camera.fov,
            settings.aspect(),
        )
    })?;
    renderer.set_scene(&scene.packed, !args.no_specialize)?;

    let mut frames = Vec::new();
    // Frames whose tone-mapped image is all black (see `BLACK_IMAGE_WARNING`).
    let mut black_frames = 0usize;
    for (g, &camera) in plan.schedule.frames.iter().zip(&cameras) {
        if let Some(spec) = plan.samples {
            let frame = settings.frame(g.number, camera, plan.foveation_rule.at(g.gaze, None));
            let bar = progress_bar(args.quiet, &plan, &frame.foveation);
            let part = render_part(args, &plan, spec, &mut renderer, &scene, &frame, &bar)?;
            // The eye's gaze, which a uniform frame's foveation does not follow.
            frames.push(FrameStats {
                gaze: g.gaze,
                ..part
            });
            continue;
        }
        // The HDR image is needed for EXR output; PNG and the overlay use the backend's tone map.
        let want_hdr = plan.output_format == ImageFormat::Exr;
        let request = settings.request(
            args.history,
            args.denoise,
            FrameOutput::ReadBack {
                want_hdr,
                want_raw: plan.keep_raw.is_some(),
            },
        );
        // One view, or each eye in turn as a view of the frame, with its own history.
        let eyes = match &plan.stereo {
            None => None,
            Some(stereo) => {
                Some(stereo.eye_cameras(g.number, camera, scene.origin, plan.resolution[0])?)
            }
        };
        for FrameView { view, frame } in settings.views(g, camera, eyes, &plan.foveation_rule) {
            let bar = progress_bar(args.quiet, &plan, &frame.foveation);
            let request = request.for_view(view.unwrap_or(0) as u32);
            let rendered = renderer.render(&scene.packed, &frame, &request, &|n| bar.inc(n))?;
            bar.finish_and_clear();
            let (stats, black) = write_frame_outputs(args, &plan, &frame, g, view, rendered)?;
            black_frames += usize::from(black);
            frames.push(stats);
        }
    }

    // A black image from a scene with lights (one without has had its warning): say why, not only
    // write it. Like the no-light warning, also under --quiet: the output is of no use as it is.
    if black_frames > 0 && !scene.packed.lights.list.is_empty() {
        let warning = if frames.len() == 1 {
            crate::scene_setup::BLACK_IMAGE_WARNING.to_string()
        } else {
            format!(
                "{black_frames} of {} frames: {}",
                frames.len(),
                crate::scene_setup::BLACK_IMAGE_WARNING
            )
        };
        eprintln!("warning: {warning}");
        run_warnings.push(warning);
    }
    let wall_ms = wall.elapsed().as_secs_f64() * 1e3;
    let report = crate::stats::build_report(
        renderer.name(),
        &renderer.device_name(),
        &plan.foveation_rule.template,
        args.foveation.uniform,
        plan.radii_px,
        plan.resolution,
        &scene,
        &run_warnings,
        &frames,
        wall_ms,
    );
    if let Some(p) = &args.stats {
        crate::stats::write_json(p, &report)?;
    }
    if !args.quiet {
        print_summary(args, plan.resolution, renderer.name(), &frames);
    }
    Ok(())
}

/// Prints what loading the scene found (all of it with `--verbose`, else how many warnings), and
/// returns the warnings that `--stats` lists: a scene without lights, `--texture-lod` without textures.
fn describe_scene(args: &RenderArgs, scene: &PreparedScene) -> Vec<String> {
    if args.verbose {
        for w in &scene.warnings {
            eprintln!("warning: {w}");
        }
        for u in &scene.unused {
            eprintln!("note: {u}");
        }
        let s = &scene.packed.stats;
        eprintln!(
            "scene: {} triangles, {} materials, {} textures, {} lights ({} emissive triangles); BVH {} 4-wide nodes (depth {}), {} 8-wide nodes; {:.1} MiB packed",
            s.triangle_count,
            scene.packed.materials.list.len(),
            s.texture_count,
            s.light_count,
            s.emissive_triangle_count,
            s.bvh.node_count,
            s.bvh.max_depth,
            s.bvh.wide_node_count,
            s.memory_bytes as f64 / (1024.0 * 1024.0)
        );
        eprintln!(
            "features: {}{}",
            crate::stats::feature_names(scene.packed.features().0).join(", "),
            if args.no_specialize {
                " (--no-specialize: rendering with every feature)"
            } else {
                ""
            }
        );
    } else if !scene.warnings.is_empty() && !args.quiet {
        eprintln!(
            "{} warning(s) while loading the scene (--verbose lists them)",
            scene.warnings.len()
        );
    }
    let mut warnings = Vec::new();
    if scene.packed.lights.list.is_empty() {
        eprintln!("warning: {}", crate::scene_setup::NO_LIGHT_WARNING);
        warnings.push(crate::scene_setup::NO_LIGHT_WARNING.to_string());
    }
    if args.path.integrator().texture_lod != fovea_core::integrator::path::TEXTURE_LOD_OFF
        && scene.packed.stats.texture_count == 0
    {
        let warning = "the scene has no textures, so --texture-lod changes nothing";
        if !args.quiet {
            eprintln!("warning: {warning}");
        }
        warnings.push(warning.to_string());
    }
    warnings
}

/// A progress bar over a frame's samples (a part's with `--samples`), hidden under `--quiet` and for
/// frames of fewer than 2 M samples.
fn progress_bar(quiet: bool, plan: &Plan, foveation: &FoveationParams) -> ProgressBar {
    let [w, h] = plan.resolution;
    let total: u64 = match plan.samples {
        Some(spec) => samples_in_part(w, h, foveation, spec.samples),
        None => count_samples(w, h, foveation).iter().sum(),
    };
    if quiet || total < 2_000_000 {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {percent}% samples ({eta} left)",
        )
        .expect("static progress template is valid"),
    );
    bar
}

/// `--samples`: renders the part `spec` of `frame` and writes it (with the identity of the scene
/// file and the executable as they are when the work starts).
fn render_part(
    args: &RenderArgs,
    plan: &Plan,
    spec: PartSpec,
    renderer: &mut Renderer,
    scene: &PreparedScene,
    frame: &FrameParams,
    bar: &ProgressBar,
) -> Result<FrameStats> {
    let scene_path = args
        .scene
        .clone()
        .unwrap_or_else(crate::scene_setup::default_scene_path);
    let scene_bytes = std::fs::read(&scene_path).map_err(|e| FoveaError::file(&scene_path, e))?;
    let identity = identity_lines(
        &RenderIdentity::of(&scene_bytes, &scene.packed),
        frame,
        plan.settings.fill_mode,
    );
    let (sums, stats) =
        renderer.render_sample_range(&scene.packed, frame, spec.samples, &|n| bar.inc(n))?;
    bar.finish_and_clear();
    write_part(&plan.output, &identity, &scene_path, spec, &sums.pixels)?;
    Ok(FrameStats {
        frame: frame.frame_index,
        gaze: frame.foveation.gaze,
        output: plan.output.clone(),
        render: stats,
        extra: None,
        history_restarted: None,
        view: None,
    })
}

/// The file an output option's `path` names for frame `number` and `view`: `out.png` →
/// `out_left.png` for an eye, then `out_left_00012.png` for a frame of a sequence.
fn numbered_output(plan: &Plan, path: &Path, number: u32, view: Option<usize>) -> PathBuf {
    let path = match view {
        Some(view) => eye_path(path, view),
        None => path.to_path_buf(),
    };
    if plan.per_frame_outputs {
        frame_path(&path, number)
    } else {
        path
    }
}

/// Every file the run will write, with the option that names it: each frame's and each eye's
/// image, `--keep-raw` and `--regions-overlay`, and `--stats`.
fn written_files(args: &RenderArgs, plan: &Plan) -> Vec<(&'static str, PathBuf)> {
    let views: Vec<Option<usize>> = match plan.stereo {
        Some(_) => (0..EYES).map(Some).collect(),
        None => vec![None],
    };
    let images = [
        ("--output", Some(&plan.output)),
        ("--keep-raw", plan.keep_raw.as_ref().map(|(p, _)| p)),
        ("--regions-overlay", args.regions_overlay.as_ref()),
    ];
    let mut files = Vec::new();
    for (option, base) in images {
        let Some(base) = base else { continue };
        for frame in &plan.schedule.frames {
            for &view in &views {
                files.push((option, numbered_output(plan, base, frame.number, view)));
            }
        }
    }
    files.extend(args.stats.iter().map(|p| ("--stats", p.clone())));
    files
}

/// Writes the outputs of view `view` of frame `scheduled` (the image, `--keep-raw`,
/// `--regions-overlay`; numbered over a sequence); returns its statistics and whether its 8-bit image
/// is all black.
fn write_frame_outputs(
    args: &RenderArgs,
    plan: &Plan,
    frame: &FrameParams,
    scheduled: &ScheduledFrame,
    view: Option<usize>,
    rendered: crate::backend::Rendered,
) -> Result<(FrameStats, bool)> {
    let number = scheduled.number;
    // The eye's gaze, which a uniform frame's foveation does not follow.
    let gaze = view.map_or(scheduled.gaze, |v| scheduled.eye_gaze(v));
    let [w, h] = plan.resolution;
    let exposure = plan.settings.exposure_ev;
    let numbered = |path: &Path| numbered_output(plan, path, number, view);
    let rgb8 = match (rendered.image.rgb8(), &rendered.image.hdr) {
        (Some(bytes), _) => bytes,
        (None, Some(hdr)) => tonemapped_rgb8(hdr, exposure),
        (None, None) => unreachable!("every backend returns HDR or tone-mapped pixels"),
    };
    let output = numbered(&plan.output);
    match (plan.output_format, &rendered.image.hdr) {
        (ImageFormat::Exr, Some(hdr)) => write_image(&output, ImageFormat::Exr, hdr, exposure)?,
        (ImageFormat::Exr, None) => unreachable!("HDR is requested for EXR output"),
        (ImageFormat::Png, _) => write_png(&output, w, h, &rgb8)?,
    }
    if let Some((path, format)) = &plan.keep_raw {
        let raw = rendered.image.raw_hdr.as_ref().ok_or_else(|| {
            FoveaError::Backend("the backend kept no image from before the denoiser".into())
        })?;
        write_image(&numbered(path), *format, raw, exposure)?;
    }
    if let Some(p) = &args.regions_overlay {
        write_png(
            &numbered(p),
            w,
            h,
            &regions_overlay(&rgb8, w, h, &frame.foveation),
        )?;
    }
    let black = rgb8.iter().all(|&byte| byte == 0);
    let stats = FrameStats {
        frame: number,
        gaze,
        output,
        render: rendered.stats,
        extra: rendered.extra,
        history_restarted: args.history.then_some(rendered.history_restarted),
        view: view.map(|v| fovea_core::passes::STEREO_VIEW_NAMES[v]),
    };
    Ok((stats, black))
}

/// The line `render` ends with: what was rendered, on what, how fast, and where it went.
fn print_summary(args: &RenderArgs, [w, h]: [u32; 2], backend: &str, frames: &[FrameStats]) {
    let last = frames.last().expect("at least one frame");
    let render_ms: f64 =
        frames.iter().map(|f| f.render.render_ms).sum::<f64>() / frames.len() as f64;
    let samples: u64 = last.render.primary_samples;
    println!(
        "fovea: {} {}x{} {} on {} in {:.0} ms ({:.2} M samples, {:.2} M paths/s) -> {}",
        if args.foveation.uniform {
            "uniform"
        } else {
            "foveated"
        },
        w,
        h,
        if frames.len() > 1 {
            format!("{} frames", frames.len())
        } else {
            "1 frame".into()
        },
        backend,
        render_ms,
        samples as f64 / 1e6,
        samples as f64 / render_ms / 1e3,
        last.output.display()
    );
}

/// The run's input files named on the command line (the scene, `--mtl`, `--env-map`,
/// `--gaze-trace`, `--camera-path`, `--stereo-views`), which no output may replace.
fn command_line_inputs(args: &RenderArgs) -> Vec<&Path> {
    [
        args.scene.as_deref(),
        args.materials.mtl.as_deref(),
        args.lighting.env_map.as_deref(),
        args.sequence.gaze_trace.as_deref(),
        args.sequence.camera_path.as_deref(),
        args.stereo.stereo_views.as_deref(),
    ]
    .into_iter()
    .flatten()
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_paths_number_the_frames() {
        assert_eq!(
            frame_path(Path::new("out/a.png"), 12),
            PathBuf::from("out/a_00012.png")
        );
    }
}
