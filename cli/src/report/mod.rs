//! `fovea report`: error against run time. For each scene it renders (or takes from the cache) a converged
//! uniform reference, then the paper's configurations (uniform 32 spp, foveated 32/16/8, 32/8/4, 32/2/1,
//! 32/16/8 with halved radii), uniform at equal time and a uniform spp sweep, and reports per configuration
//! the median render time, the primary samples, the speed-up over uniform and the error against the
//! reference (mean FLIP and relMSE over the whole image and each foveation region).
mod configs;
mod fvvdp;
pub(crate) mod metrics;
mod plot;
mod reference_cache;
mod saccades;
mod sequence;
mod tasks;
mod write;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use fovea_core::camera::Camera;
use fovea_core::foveation::blocks::count_samples;
use fovea_core::foveation::display::{pixels_per_degree, DisplayGeometry};
use fovea_core::foveation::regions::{FoveationParams, FOVEATION_OK};
use fovea_core::integrator::FrameParams;
use fovea_cpu::FrameImage;
use fovea_scene::environment::Environment;
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::ReportArgs;
use crate::backend::{FrameOutput, Renderer};
use crate::error::{FoveaError, Result};
use crate::output::{regions_overlay, tonemapped_rgb8, write_png};
use crate::partial::{
    check_parts, identity_lines, samples_in_part, write_part, PartHeader, PartSpec, RenderIdentity,
};
use crate::scene_setup::{choose_camera, default_scene_path, prepare_scene, Lighting};
use crate::schedule::{FrameSchedule, FrameSettings, LonePath, ScheduledFrame};
use crate::values::{self, SampleSelection, MAX_SPP};

use configs::{ConfigKind, ConfigSpec, UNIFORM_SPP};
use metrics::{RegionMap, RegionMeans};
use reference_cache::CacheEntry;

/// The reference's seed is the test seed XOR this, so its noise is independent of the test renders'
/// (the random numbers are keyed by block, frame, sample and seed: with the same seed, uniform 32 spp would
/// be the reference's first 32 samples and its error would be underestimated).
const REFERENCE_SEED_XOR: u32 = 0x5eed_cafe;

/// One measured configuration.
#[derive(Clone, Debug)]
pub struct ConfigResult {
    pub spec: ConfigSpec,
    /// Median render time over the runs, in ms, as the backend reports it.
    pub render_ms: f64,
    pub runs_ms: Vec<f64>,
    pub primary_samples: u64,
    pub samples_per_region: [u64; 3],
    /// Uniform 32 spp render time / this one.
    pub speedup: f64,
    /// Uniform 32 spp primary samples / this configuration's.
    pub sample_ratio: f64,
    pub flip: RegionMeans,
    pub rel_mse: RegionMeans,
    /// Tone-mapped PNG and FLIP map, relative to the scene's output folder.
    pub image: String,
    pub flip_map: String,
}

/// Everything the outputs of one scene are written from.
pub struct SceneReport {
    pub scene: String,
    pub scene_name: String,
    pub backend: &'static str,
    pub device: String,
    pub resolution: [u32; 2],
    pub gaze: [f32; 2],
    pub radii_px: [f32; 2],
    pub display_cm: [f32; 2],
    pub distance_cm: f32,
    pub ppd: f32,
    pub reference: String,
    pub reference_spp: u32,
    pub reference_cache: PathBuf,
    pub reference_cached: bool,
    pub reference_render_ms: Option<f64>,
    pub regions: String,
    pub region_pixels: [u64; 3],
    pub runs: u32,
    pub seed: u32,
    pub equal_time_spp: Option<u32>,
    /// The sweep line's unrounded spp at the 32/16/8 time (NaN when too few sweep points).
    pub equal_time_fit: f64,
    pub wall_ms: f64,
    pub configs: Vec<ConfigResult>,
    /// The gaze-trace sequence (`--gaze-trace`), judged by eccentricity and over time.
    pub sequence: Option<sequence::SequenceReport>,
}

/// The options, checked, with `--quick` applied.
/// The paper's region bounds in degrees (5.2° and 17°).
const PAPER_ECCENTRICITY: values::Eccentricity = values::Eccentricity([
    fovea_core::foveation::FOVEA_ECCENTRICITY_DEG,
    fovea_core::foveation::INTERMEDIATE_ECCENTRICITY_DEG,
]);

/// The user's own foveation settings (an extra configuration).
#[derive(Clone, Copy, Debug)]
struct UserFoveation {
    spp: [u32; 3],
    blocks: [u32; 3],
    radii_px: [f32; 2],
}

impl UserFoveation {
    fn around(&self, gaze: [f32; 2]) -> FoveationParams {
        FoveationParams::new(gaze, self.radii_px, self.spp, self.blocks)
    }
}

struct Plan {
    resolution: [u32; 2],
    /// The user's own configuration, if they gave one.
    user: Option<UserFoveation>,
    gaze: [f32; 2],
    runs: u32,
    reference_spp: u32,
    sweep_max: u32,
    display: DisplayGeometry,
    radii_px: [f32; 2],
    ppd: f32,
    /// What every frame shares (size, integrator, seed, fill, exposure).
    settings: FrameSettings,
    eye: Option<[f64; 3]>,
    target: Option<[f64; 3]>,
    up: [f32; 3],
    cache_dir: PathBuf,
    sequence: Option<sequence::SequencePlan>,
    /// `--reference-parts`: where references are merged from, or (with `reference_part`) where this
    /// run writes its part of each.
    reference_parts: Option<PathBuf>,
    /// `--reference-part I/N`: render only this part of each reference, and no report.
    reference_part: Option<SampleSelection>,
    /// `--task I/N`: measure only this task's scenes, and write no combined report.
    task: Option<values::ArrayTask>,
}

fn positive(option: &'static str, value: u32, max: u32) -> Result<u32> {
    if value == 0 || value > max {
        return Err(FoveaError::option(
            option,
            format!("must be 1 to {max}, got {value}"),
        ));
    }
    Ok(value)
}

fn plan(args: &ReportArgs) -> Result<Plan> {
    let resolution = args
        .resolution
        .map_or(if args.quick { [320, 180] } else { [3840, 2160] }, |r| r.0);
    let [w, h] = resolution;
    let gaze = args.gaze.map_or([0.5 * w as f32, 0.5 * h as f32], |g| g.0);
    let runs = positive(
        "--runs",
        args.runs.unwrap_or(if args.quick { 1 } else { 3 }),
        1000,
    )?;
    let reference_spp = positive(
        "--reference-spp",
        args.reference_spp
            .unwrap_or(if args.quick { 256 } else { 1024 }),
        MAX_SPP,
    )?;
    let sweep_max = positive(
        "--sweep-max",
        args.sweep_max.unwrap_or(if args.quick { 8 } else { 64 }),
        MAX_SPP,
    )?;
    // The image fills the display whatever its resolution, as in `fovea render`: pixels per centimetre,
    // radii and pixels per degree all scale with the rendered width.
    let (display, aspect_warning) = values::display_geometry(
        args.display.display_cm,
        args.display.distance_cm,
        resolution,
    )?;
    if let (Some(w), false) = (aspect_warning, args.quiet) {
        eprintln!("warning: {w}");
    }
    // The paper's configurations keep the paper's angles; the user's own foveation, when any of its
    // options is given, is measured as one more configuration.
    let radii_px = values::eccentricity_radii(PAPER_ECCENTRICITY, &display);
    let own = args.spp.is_some()
        || args.blocks.is_some()
        || args.radii.is_some()
        || args.display.eccentricity != PAPER_ECCENTRICITY;
    let user = own.then(|| UserFoveation {
        spp: args.spp.map_or([32, 16, 8], |s| s.0),
        blocks: args.blocks.map_or([1, 2, 4], |b| b.0),
        radii_px: args.radii.map_or_else(
            || values::eccentricity_radii(args.display.eccentricity, &display),
            |r| r.0,
        ),
    });
    let (eye, target, up) = args.camera.points();
    let mut names = std::collections::HashSet::new();
    for s in &args.scenes {
        if !s.is_file() {
            return Err(FoveaError::file(s, "no such scene file"));
        }
        if !names.insert(s.clone()) {
            return Err(FoveaError::option(
                "SCENE",
                format!("'{}' is given twice", s.display()),
            ));
        }
    }
    // The trace's frames (with --camera-path, their cameras); a path without a trace is refused.
    let still = ScheduledFrame {
        number: 0,
        gaze,
        eyes: None,
        camera: None,
    };
    let schedule = FrameSchedule::read(
        &args.sequence,
        still,
        resolution,
        LonePath::NeedsTrace,
        args.sequence_frames,
    )?;
    if !args.quiet {
        for n in &schedule.notes {
            eprintln!("warning: {n}");
        }
    }
    Ok(Plan {
        resolution,
        gaze,
        runs,
        reference_spp,
        sweep_max,
        ppd: pixels_per_degree(&display),
        display,
        radii_px,
        user,
        settings: FrameSettings::new(resolution, &args.path, &args.image),
        eye,
        target,
        up,
        cache_dir: reference_cache::cache_dir(args.cache_dir.as_deref())?,
        reference_parts: match &args.reference_parts {
            Some(dir) if !dir.is_dir() => {
                return Err(FoveaError::option(
                    "--reference-parts",
                    crate::output::missing_folder(dir),
                ))
            }
            dir => dir.clone(),
        },
        reference_part: match (args.reference_part, &args.reference_parts) {
            (Some(_), None) => {
                return Err(FoveaError::option(
                    "--reference-part",
                    "writes its part into a folder: add --reference-parts DIR",
                ))
            }
            (part, _) => part,
        },
        task: match (args.task, args.reference_part.is_some(), args.combine) {
            (Some(_), true, _) => return Err(FoveaError::option(
                "--task",
                "splits the scenes and --reference-part their references: use one of them per run",
            )),
            (Some(_), _, true) => {
                return Err(FoveaError::option(
                    "--combine",
                    "writes the combined report after every --task run: run it without --task",
                ))
            }
            (None, true, true) => {
                return Err(FoveaError::option(
                    "--combine",
                    "renders nothing, and --reference-part renders only a part: use one of them",
                ))
            }
            (task, ..) => task,
        },
        sequence: match &args.sequence.gaze_trace {
            Some(trace) => Some(sequence::SequencePlan::read(
                &args.sequence,
                trace,
                schedule,
                args.band_deg,
            )?),
            None => None,
        },
    })
}

/// The files `report` writes into each scene's folder, besides those in its `images/` and `flip/`.
const REPORT_FILES: [&str; 7] = [
    "report.md",
    "report.json",
    "report.csv",
    "plot.svg",
    "sequence.svg",
    "reference.png",
    "regions.png",
];

/// Checks before any work that every folder the run writes into takes files (`--out` and each
/// scene's folder in it, the reference cache, `--reference-parts` for a part) and that no file it
/// writes is one of its inputs (the scenes, `--env-map`, the trace, the camera path), by the files
/// they resolve to: one line naming the path, and nothing rendered.
fn check_outputs(
    args: &ReportArgs,
    plan: &Plan,
    scenes: &[tasks::SceneEntry],
    writes_report: bool,
) -> Result<()> {
    let takes_files = |dir: &Path, option: &'static str| -> Result<()> {
        create_dir(dir)?;
        crate::output::check_folder_takes_files(dir).map_err(|why| FoveaError::option(option, why))
    };
    let inputs: Vec<&Path> = args
        .scenes
        .iter()
        .map(PathBuf::as_path)
        .chain(args.lighting.env_map.as_deref())
        .chain(args.sequence.gaze_trace.as_deref())
        .chain(args.sequence.camera_path.as_deref())
        .collect();
    if writes_report {
        takes_files(&args.out, "--out")?;
        for (_, dir) in scenes {
            takes_files(dir, "--out")?;
            let files: Vec<(&'static str, PathBuf)> = REPORT_FILES
                .iter()
                .map(|n| ("--out", dir.join(n)))
                .collect();
            crate::output::refuse_overwriting_inputs(&files, &inputs)?;
            for sub in ["images", "flip"] {
                let folder = crate::output::resolved_path(&dir.join(sub));
                if let Some(input) = inputs
                    .iter()
                    .find(|i| crate::output::resolved_path(i).starts_with(&folder))
                {
                    return Err(FoveaError::option(
                        "--out",
                        format!(
                            "'{}' is an input of this run inside '{}', which the report writes \
                             into; fovea never overwrites its input",
                            input.display(),
                            dir.join(sub).display()
                        ),
                    ));
                }
            }
        }
    }
    if !args.no_cache {
        takes_files(&plan.cache_dir, "--cache-dir")?;
    }
    if let (Some(_), Some(dir)) = (plan.reference_part, &plan.reference_parts) {
        crate::output::check_folder_takes_files(dir)
            .map_err(|why| FoveaError::option("--reference-parts", why))?;
    }
    Ok(())
}

/// Creates `dir` (and its parents).
fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| FoveaError::file(dir, format!("cannot create the folder: {e}")))
}

/// Runs `fovea report`.
///
/// Long because it is the report's run in order: the scenes and their folders, the checks before work,
/// each scene, the combined files and the summary.
pub fn run(args: &ReportArgs) -> Result<()> {
    let wall = Instant::now();
    let plan = plan(args)?;

    // One entry per scene: its path (None: the bundled default) and its output folder.
    let all_scenes: Vec<tasks::SceneEntry> = if args.scenes.len() <= 1 {
        vec![(args.scenes.first().cloned(), args.out.clone())]
    } else {
        let mut used = std::collections::HashSet::new();
        args.scenes
            .iter()
            .map(|s| {
                let stem = s
                    .file_stem()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "scene".into());
                let mut name = stem.clone();
                let mut i = 2;
                while !used.insert(name.clone()) {
                    name = format!("{stem}-{i}");
                    i += 1;
                }
                (Some(s.clone()), args.out.join(name))
            })
            .collect()
    };
    if args.combine {
        return combine_tasks(args, &all_scenes);
    }
    let scenes = match plan.task {
        Some(task) => tasks::scenes_of_task(&all_scenes, task)?,
        None => all_scenes.clone(),
    };

    // A part of the references renders on the CPU, the one host that renders a range of samples.
    let target = match plan.reference_part {
        Some(_) => crate::backend::cpu_target_for_parts(&args.target, "--reference-part")?,
        None => args.target,
    };
    // A part of the references is all a `--reference-part` run writes.
    let writes_report = plan.reference_part.is_none();
    check_outputs(args, &plan, &scenes, writes_report)?;
    let mut renderer = Renderer::new(&target, args.quiet)?;
    let lighting = Lighting::from_args(&args.lighting)?;

    let [w, h] = plan.resolution;
    let paper = FoveationParams::paper(plan.gaze, plan.radii_px[0], plan.radii_px[1]);
    if paper.validate() != FOVEATION_OK {
        return Err(FoveaError::option(
            "--gaze/--eccentricity",
            "the foveation settings are inconsistent",
        ));
    }
    let user = plan.user.map(|u| u.around(plan.gaze));
    if user.is_some_and(|u| u.validate() != FOVEATION_OK) {
        return Err(FoveaError::option(
            "--spp/--blocks/--radii",
            "the foveation settings are inconsistent",
        ));
    }
    // Samples of every render known now (the reference and equal time are added when known).
    let per_scene: u64 =
        configs::table_configs(&paper, user.as_ref(), plan.settings.integrator.texture_lod)
            .iter()
            .map(|c| c.foveation)
            .chain(
                configs::sweep_spps(plan.sweep_max)
                    .into_iter()
                    .filter(|&s| s != UNIFORM_SPP)
                    .map(FoveationParams::uniform),
            )
            .map(|f| count_samples(w, h, &f).iter().sum::<u64>())
            .sum::<u64>()
            * u64::from(plan.runs);
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        // A part of the references adds its own samples as it starts.
        let per_scene = if writes_report { per_scene } else { 0 };
        let bar = ProgressBar::new(per_scene * scenes.len() as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% {msg} ({eta} left)",
            )
            .expect("static progress template is valid"),
        );
        bar
    };

    // Several scenes: each is loaded and checked before hours of measurement start.
    if scenes.len() > 1 {
        for (scene_path, _) in &scenes {
            prepare_scene(
                scene_path.as_deref(),
                None,
                args.mtl_diffuse.into(),
                &lighting.environment(scene_path.is_none()),
                &lighting.point_lights,
                renderer.wants_wide_bvh(),
            )?;
        }
    }
    let mut markdown = Vec::new();
    // A scene that fails later is named in the report; the others' results are still written.
    let mut failures: Vec<(String, FoveaError)> = Vec::new();
    for (scene_path, out_dir) in &scenes {
        if writes_report {
            create_dir(out_dir)?;
        }
        let environment = lighting.environment(scene_path.is_none());
        let env_text = lighting.environment_key(scene_path.is_none());
        let scene_start = Instant::now();
        let result = run_scene(
            args,
            &plan,
            &mut renderer,
            &bar,
            scene_path.as_deref(),
            &environment,
            &env_text,
            &lighting.point_lights,
            out_dir,
        );
        let mut report = match result {
            Ok(Some(report)) => report,
            Ok(None) => continue,
            Err(e) if scenes.len() > 1 => {
                let name = scene_path
                    .as_deref()
                    .map_or_else(|| "the default scene".into(), |p| p.display().to_string());
                note(
                    &bar,
                    false,
                    &format!("error: {name}: {e}; going on with the others"),
                );
                failures.push((name, e));
                continue;
            }
            Err(e) => return Err(e),
        };
        report.wall_ms = scene_start.elapsed().as_secs_f64() * 1e3;
        let md = write::report_md(&report);
        write::write_text(
            &out_dir.join("report.md"),
            &format!("{}{md}", tasks::HEADING),
        )?;
        let json = write::report_json(&report);
        crate::stats::write_json(&out_dir.join("report.json"), &json)?;
        write::write_text(&out_dir.join("report.csv"), &write::report_csv(&report))?;
        let svg =
            plot::plot_svg(&report).map_err(|e| FoveaError::file(out_dir.join("plot.svg"), e))?;
        write::write_text(&out_dir.join("plot.svg"), &svg)?;
        if let Some(seq) = &report.sequence {
            let path = out_dir.join("sequence.svg");
            let svg = plot::sequence_svg(&report.scene_name, seq)
                .map_err(|e| FoveaError::file(&path, e))?;
            write::write_text(&path, &svg)?;
        }
        markdown.push((out_dir.clone(), md));
    }
    bar.finish_and_clear();
    if !writes_report {
        return Ok(());
    }
    // A task's scenes are combined with the other tasks' by `--combine`.
    if all_scenes.len() > 1 && plan.task.is_none() {
        let failed: Vec<(String, String)> = failures
            .iter()
            .map(|(name, e)| (name.clone(), e.to_string()))
            .collect();
        let text = tasks::combined_markdown(&args.out, &markdown, &failed);
        write::write_text(&args.out.join("report.md"), &text)?;
    }
    // Where the results are: the combined report, or a task's scene folders.
    let results = match plan.task {
        Some(_) => {
            let dirs: Vec<String> = markdown
                .iter()
                .map(|(dir, _)| dir.display().to_string())
                .collect();
            format!("{} (combine the tasks with --combine)", dirs.join(", "))
        }
        None => args.out.join("report.md").display().to_string(),
    };
    if !failures.is_empty() {
        let names: Vec<&str> = failures.iter().map(|(n, _)| n.as_str()).collect();
        return Err(FoveaError::Backend(format!(
            "{} of {} scenes failed ({}); the others' results are in {results}",
            failures.len(),
            scenes.len(),
            names.join(", "),
        )));
    }
    if let (Some(task), false) = (plan.task, args.quiet) {
        eprintln!(
            "fovea: report task {}/{}: {} scene(s) in {:.1} s -> {results}",
            task.0[0],
            task.0[1],
            scenes.len(),
            wall.elapsed().as_secs_f64(),
        );
    } else if !args.quiet {
        eprintln!(
            "fovea: report of {} scene{} in {:.1} s -> {}",
            scenes.len(),
            if scenes.len() == 1 { "" } else { "s" },
            wall.elapsed().as_secs_f64(),
            args.out.join("report.md").display()
        );
    }
    Ok(())
}

/// `--combine`: the combined report.md of several scenes from their folders, which `--task` runs
/// wrote; nothing is rendered.
fn combine_tasks(args: &ReportArgs, scenes: &[tasks::SceneEntry]) -> Result<()> {
    if scenes.len() < 2 {
        return Err(FoveaError::option(
            "--combine",
            "joins the reports of several scenes: give the SCENE list the --task runs were given",
        ));
    }
    let sections = tasks::read_sections(scenes)?;
    let path = args.out.join("report.md");
    write::write_text(&path, &tasks::combined_markdown(&args.out, &sections, &[]))?;
    if !args.quiet {
        eprintln!(
            "fovea: combined the reports of {} scenes -> {}",
            scenes.len(),
            path.display()
        );
    }
    Ok(())
}

/// A converged reference of `reference_frame`, rendered and stored in the cache as `entry`; its
/// render time.
#[allow(clippy::too_many_arguments)]
fn render_reference(
    args: &ReportArgs,
    plan: &Plan,
    renderer: &mut Renderer,
    bar: &ProgressBar,
    packed: &fovea_scene::pack::PackedScene,
    entry: &CacheEntry,
    reference_frame: &FrameParams,
    what: &str,
) -> Result<(FrameImage, Option<f64>)> {
    let (w, h) = (reference_frame.width, reference_frame.height);
    bar.inc_length(u64::from(w) * u64::from(h) * u64::from(plan.reference_spp));
    bar.set_message(format!("{what}: reference ({} spp)", plan.reference_spp));
    let request = plan.settings.request(
        false,
        false,
        FrameOutput::ReadBack {
            want_hdr: true,
            want_raw: false,
        },
    );
    let rendered = renderer.render(packed, reference_frame, &request, &|n| bar.inc(n))?;
    let image = rendered
        .image
        .hdr
        .ok_or_else(|| FoveaError::Backend("the backend returned no HDR image".into()))?;
    match entry.store(&image) {
        Ok(()) => note(
            bar,
            args.quiet,
            &format!("reference: rendered and cached {}", entry.image.display()),
        ),
        Err(e) => note(
            bar,
            false,
            &format!("warning: the reference could not be cached: {e}"),
        ),
    }
    Ok((image, Some(rendered.stats.render_ms)))
}

/// What a scene's references are keyed and identified by.
struct ReferenceScene<'a> {
    /// The scene file, named in parts.
    file: &'a Path,
    /// The scene file's, packed scene's and executable's hashes.
    identity: &'a RenderIdentity,
    packed: &'a fovea_scene::pack::PackedScene,
    /// The lighting's part of the cache key.
    env_text: &'a str,
}

/// A reference as [`obtain_reference`] got it.
struct Obtained {
    image: FrameImage,
    /// The render's time, when this run rendered it.
    render_ms: Option<f64>,
    /// Whether it came from the cache.
    cached: bool,
    /// Where it is cached.
    cache_path: PathBuf,
}

/// The converged reference of `frame` (`what` names it in messages). With `--reference-part`: renders
/// that part of it into `--reference-parts` on the CPU and returns `None`. Otherwise: the cached image,
/// else one merged from all of its parts in `--reference-parts`, else rendered; a merged or rendered
/// one is cached.
#[allow(clippy::too_many_arguments)]
fn obtain_reference(
    args: &ReportArgs,
    plan: &Plan,
    renderer: &mut Renderer,
    bar: &ProgressBar,
    scene: &ReferenceScene,
    frame: &FrameParams,
    what: &str,
) -> Result<Option<Obtained>> {
    let (w, h) = (frame.width, frame.height);
    let entry = CacheEntry::new(
        &plan.cache_dir,
        reference_cache::reference_key_text(
            scene.identity.scene_file_hash,
            scene.packed,
            scene.env_text,
            frame,
            plan.settings.fill_mode,
        ),
    );
    let identity = identity_lines(scene.identity, frame, plan.settings.fill_mode);
    if let (Some(selection), Some(dir)) = (plan.reference_part, &plan.reference_parts) {
        let spec = PartSpec::new(selection, plan.reference_spp)
            .map_err(|why| FoveaError::option("--reference-part", why))?;
        let [first, end] = spec.samples;
        bar.inc_length(samples_in_part(w, h, &frame.foveation, spec.samples));
        bar.set_message(format!("{what}: reference samples {first}..{end}"));
        let (sums, _) =
            renderer.render_sample_range(scene.packed, frame, spec.samples, &|n| bar.inc(n))?;
        let path = dir.join(format!("{}.part-{first:08}-{end:08}.fvpart", entry.name()));
        write_part(&path, &identity, scene.file, spec, &sums.pixels)?;
        note(
            bar,
            args.quiet,
            &format!(
                "{what}: reference samples {first}..{end} -> {}",
                path.display()
            ),
        );
        return Ok(None);
    }
    if let Some(image) = (!args.no_cache).then(|| entry.load(w, h)).flatten() {
        note(
            bar,
            args.quiet,
            &format!("reference: cached {} ({what})", entry.image.display()),
        );
        return Ok(Some(Obtained {
            image,
            render_ms: None,
            cached: true,
            cache_path: entry.image,
        }));
    }
    if let Some(dir) = &plan.reference_parts {
        let image = merge_reference_parts(dir, &entry.name(), what, &identity)?;
        match entry.store(&image) {
            Ok(()) => note(
                bar,
                args.quiet,
                &format!(
                    "reference: merged from the parts in {} and cached {} ({what})",
                    dir.display(),
                    entry.image.display()
                ),
            ),
            Err(e) => note(
                bar,
                false,
                &format!("warning: the reference could not be cached: {e}"),
            ),
        }
        return Ok(Some(Obtained {
            image,
            render_ms: None,
            cached: false,
            cache_path: entry.image,
        }));
    }
    let (image, render_ms) =
        render_reference(args, plan, renderer, bar, scene.packed, &entry, frame, what)?;
    Ok(Some(Obtained {
        image,
        render_ms,
        cached: false,
        cache_path: entry.image,
    }))
}

/// A reference merged from its parts in `dir` (`<name>.part-*.fvpart`, written by `--reference-part`),
/// checked to be parts of exactly this reference (`expected`, its identity lines).
fn merge_reference_parts(
    dir: &Path,
    name: &str,
    scene_name: &str,
    expected: &[(String, String)],
) -> Result<FrameImage> {
    let prefix = format!("{name}.part-");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| FoveaError::file(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".fvpart"))
        })
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(FoveaError::option(
            "--reference-parts",
            format!(
                "'{}' holds no part of {scene_name}'s reference ({prefix}*.fvpart): render them with \
                 the same options plus --reference-part I/N --reference-parts {}, by the same fovea \
                 binary",
                dir.display(),
                dir.display()
            ),
        ));
    }
    let parts = paths
        .into_iter()
        .map(|p| PartHeader::read(&p).map(|part| (p, part)))
        .collect::<Result<Vec<_>>>()?;
    let checked = check_parts(parts)?;
    checked.expect_identity(expected, &format!("{scene_name}'s reference"))?;
    let (image, non_finite) = checked.merged()?;
    match non_finite.first() {
        // A reference with NaN pixels would make every figure against it NaN.
        Some((path, count)) => Err(FoveaError::file(
            path,
            format!("{count} pixel(s) of this part of {scene_name}'s reference hold NaN or infinite sums; render it again"),
        )),
        None => Ok(image),
    }
}

/// Prints a status line above the progress bar (nothing with `--quiet`).
fn note(bar: &ProgressBar, quiet: bool, message: &str) {
    if !quiet {
        bar.suspend(|| eprintln!("{message}"));
    }
}

/// Renders and measures one scene; writes its images. With `--reference-part`, renders only that part of
/// its reference into `--reference-parts` and returns `None`.
///
/// Long because it is one scene's report in order (load, reference from the cache, parts or a render,
/// the configurations, the sequence, the files), each step using the ones before.
#[allow(clippy::too_many_arguments)]
fn run_scene(
    args: &ReportArgs,
    plan: &Plan,
    renderer: &mut Renderer,
    bar: &ProgressBar,
    scene_path: Option<&Path>,
    environment: &Environment,
    env_text: &str,
    point_lights: &[crate::values::WorldPointLight],
    out_dir: &Path,
) -> Result<Option<SceneReport>> {
    let [w, h] = plan.resolution;
    let file = scene_path
        .map(Path::to_path_buf)
        .unwrap_or_else(default_scene_path);
    let scene_name = file
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    bar.set_message(format!("{scene_name}: loading"));
    let scene = prepare_scene(
        scene_path,
        None,
        args.mtl_diffuse.into(),
        environment,
        point_lights,
        renderer.wants_wide_bvh(),
    )?;
    if plan.settings.integrator.texture_lod != fovea_core::integrator::path::TEXTURE_LOD_OFF
        && scene.packed.stats.texture_count == 0
    {
        note(
            bar,
            false,
            &format!("note: {scene_name} has no textures, so --texture-lod changes nothing"),
        );
    }
    if scene.packed.lights.list.is_empty() {
        note(
            bar,
            false,
            &format!(
                "warning: {scene_name} has no light and no sky: every image will be black \
                 (add --sky R,G,B or --point-light X,Y,Z,R,G,B)"
            ),
        );
    }
    let camera: Camera = choose_camera(
        &scene,
        plan.eye,
        plan.target,
        plan.up,
        args.camera.fov,
        w as f32 / h as f32,
    )?;
    renderer.set_scene(&scene.packed, true)?;
    let paper = FoveationParams::paper(plan.gaze, plan.radii_px[0], plan.radii_px[1]);
    let regions = RegionMap::new(w, h, &paper);

    // The reference: from the cache, or rendered and stored.
    let scene_bytes = std::fs::read(&file).map_err(|e| FoveaError::file(&file, e))?;
    // The reference reads every texture at level 0: many samples per pixel integrate the pixel's
    // footprint themselves (the ground truth the texture level of detail approximates).
    // Its seed differs from the test renders', so that its noise is independent of theirs.
    let reference_settings = FrameSettings {
        seed: plan.settings.seed ^ REFERENCE_SEED_XOR,
        ..plan
            .settings
            .with_texture_lod(fovea_core::integrator::path::TEXTURE_LOD_OFF)
    };
    let reference_foveation = FoveationParams::uniform(plan.reference_spp);
    let reference_frame = reference_settings.frame(0, camera, reference_foveation);
    let identity = RenderIdentity::of(&scene_bytes, &scene.packed);
    let references = ReferenceScene {
        file: &file,
        identity: &identity,
        packed: &scene.packed,
        env_text,
    };
    let reference = obtain_reference(
        args,
        plan,
        renderer,
        bar,
        &references,
        &reference_frame,
        &scene_name,
    )?;
    // A --camera-path sequence: each frame's camera, chosen once, and each moving camera's
    // reference (a still one shares the scene's), or with --reference-part a part of it.
    let moving_sequence = plan
        .sequence
        .as_ref()
        .filter(|seq| seq.camera_path.is_some());
    let frame_cameras: Option<Vec<Camera>> = match moving_sequence {
        Some(seq) => Some(seq.schedule.cameras(camera, |key| {
            choose_camera(
                &scene,
                Some(key.eye),
                Some(key.target),
                plan.up,
                args.camera.fov,
                plan.settings.aspect(),
            )
        })?),
        None => None,
    };
    let mut moving: Vec<(Camera, FrameImage, Vec<u8>)> = Vec::new();
    if let (Some(seq), Some(cameras)) = (moving_sequence, &frame_cameras) {
        // The scene's own camera has its reference above (it joins `moving` below).
        let mut done: Vec<Camera> = vec![camera];
        for (f, &camera) in seq.schedule.frames.iter().zip(cameras) {
            if done.contains(&camera) {
                continue;
            }
            done.push(camera);
            let frame_reference = reference_settings.frame(0, camera, reference_foveation);
            let what = format!("{scene_name} frame {}", f.number);
            if let Some(obtained) = obtain_reference(
                args,
                plan,
                renderer,
                bar,
                &references,
                &frame_reference,
                &what,
            )? {
                let rgb8 = tonemapped_rgb8(&obtained.image, plan.settings.exposure_ev);
                moving.push((camera, obtained.image, rgb8));
            }
        }
    }
    // With --reference-part, the parts are all this run makes.
    let Some(Obtained {
        image: reference,
        render_ms: reference_render_ms,
        cached: reference_cached,
        cache_path: reference_cache_path,
    }) = reference
    else {
        return Ok(None);
    };
    let reference_rgb8 = tonemapped_rgb8(&reference, plan.settings.exposure_ev);
    if frame_cameras.as_ref().is_some_and(|c| c.contains(&camera)) {
        moving.push((camera, reference.clone(), reference_rgb8.clone()));
    }
    write_png(&out_dir.join("reference.png"), w, h, &reference_rgb8)?;
    write_png(
        &out_dir.join("regions.png"),
        w,
        h,
        &regions_overlay(&reference_rgb8, w, h, &paper),
    )?;
    create_dir(&out_dir.join("images"))?;
    create_dir(&out_dir.join("flip"))?;

    let measurer = Measurer {
        plan,
        packed: &scene.packed,
        bar,
        scene_name: &scene_name,
        reference: &reference,
        reference_rgb8: &reference_rgb8,
        regions: &regions,
        out_dir,
        camera,
    };
    let (mut results, equal_spp, equal_fit) =
        measure_configs(&measurer, renderer, plan, &paper, bar)?;
    let sequence = match &plan.sequence {
        Some(seq) => {
            let views: Vec<sequence::FrameView> = match &frame_cameras {
                Some(cameras) => cameras
                    .iter()
                    .map(|camera| {
                        let (camera, image, rgb8) = moving
                            .iter()
                            .find(|(c, _, _)| c == camera)
                            .expect("every camera has its reference");
                        sequence::FrameView {
                            camera: *camera,
                            reference: image,
                            reference_rgb8: rgb8,
                        }
                    })
                    .collect(),
                None => vec![
                    sequence::FrameView {
                        camera,
                        reference: &reference,
                        reference_rgb8: &reference_rgb8,
                    };
                    seq.schedule.frames.len()
                ],
            };
            Some(measure_sequence(
                args,
                plan,
                renderer,
                bar,
                seq,
                &scene.packed,
                &paper,
                views,
                &scene_name,
                out_dir,
            )?)
        }
        None => None,
    };

    let (base_ms, base_samples) = (results[0].render_ms, results[0].primary_samples);
    for r in &mut results {
        r.speedup = base_ms / r.render_ms;
        r.sample_ratio = base_samples as f64 / r.primary_samples.max(1) as f64;
    }

    Ok(Some(SceneReport {
        scene: file.display().to_string(),
        scene_name,
        backend: renderer.name(),
        device: renderer.device_name(),
        resolution: plan.resolution,
        gaze: plan.gaze,
        radii_px: plan.radii_px,
        display_cm: [plan.display.width_cm, plan.display.height_cm],
        distance_cm: plan.display.distance_cm,
        ppd: plan.ppd,
        reference: "reference.png".into(),
        reference_spp: plan.reference_spp,
        reference_cache: reference_cache_path,
        reference_cached,
        reference_render_ms,
        regions: "regions.png".into(),
        region_pixels: regions.pixels,
        runs: plan.runs,
        seed: plan.settings.seed,
        equal_time_spp: Some(equal_spp),
        equal_time_fit: equal_fit,
        wall_ms: 0.0,
        configs: results,
        sequence,
    }))
}

/// The table's configurations (uniform, the paper's, the user's), the uniform sweep and the uniform
/// spp that takes 32/16/8's time (fitted to the sweep), measured: the results in the report's order,
/// and the equal-time spp with its fit.
fn measure_configs(
    measurer: &Measurer,
    renderer: &mut Renderer,
    plan: &Plan,
    paper: &FoveationParams,
    bar: &ProgressBar,
) -> Result<(Vec<ConfigResult>, u32, f64)> {
    let [w, h] = plan.resolution;
    // Uniform results by spp: the sweep's 32 spp and an equal-time spp already measured are reused.
    let mut uniform_by_spp: HashMap<u32, ConfigResult> = HashMap::new();
    let mut results = Vec::new();
    let user = plan.user.map(|u| u.around(plan.gaze));
    for spec in configs::table_configs(paper, user.as_ref(), plan.settings.integrator.texture_lod) {
        let r = measurer.measure(renderer, &spec)?;
        if spec.kind == ConfigKind::Uniform {
            uniform_by_spp.insert(spec.foveation.spp[0], r.clone());
        }
        results.push(r);
    }
    let mut sweep = Vec::new();
    for spp in configs::sweep_spps(plan.sweep_max) {
        let spec = configs::uniform(spp, ConfigKind::Sweep);
        let r = match uniform_by_spp.get(&spp) {
            Some(done) => ConfigResult {
                spec,
                ..done.clone()
            },
            None => measurer.measure(renderer, &spec)?,
        };
        uniform_by_spp.insert(spp, r.clone());
        sweep.push(r);
    }
    let target_ms = results[1].render_ms;
    let points: Vec<(u32, f64)> = sweep
        .iter()
        .map(|r| (r.spec.foveation.spp[0], r.render_ms))
        .collect();
    let (equal_spp, equal_fit) = configs::equal_time_fit(&points, target_ms, MAX_SPP);
    let spec = configs::uniform(equal_spp, ConfigKind::EqualTime);
    let equal = match uniform_by_spp.get(&equal_spp) {
        Some(done) => ConfigResult {
            spec,
            ..done.clone()
        },
        None => {
            bar.inc_length(
                u64::from(w) * u64::from(h) * u64::from(equal_spp) * u64::from(plan.runs),
            );
            measurer.measure(renderer, &spec)?
        }
    };
    results.push(equal);
    results.extend(sweep);

    Ok((results, equal_spp, equal_fit))
}

/// The sequence of `--gaze-trace`, each configuration rendered frame by frame and scored against
/// `views`' references.
#[allow(clippy::too_many_arguments)]
fn measure_sequence(
    args: &ReportArgs,
    plan: &Plan,
    renderer: &mut Renderer,
    bar: &ProgressBar,
    seq: &sequence::SequencePlan,
    packed: &fovea_scene::pack::PackedScene,
    paper: &FoveationParams,
    views: Vec<sequence::FrameView>,
    scene_name: &str,
    out_dir: &Path,
) -> Result<sequence::SequenceReport> {
    let [w, h] = plan.resolution;
    let metric = if args.no_fovvideovdp {
        Err("off (--no-fovvideovdp)".to_string())
    } else {
        fvvdp::FovVideoVdp::find()
    };
    let specs = sequence::sequence_specs(&configs::sweep_spps(plan.sweep_max));
    let samples: u64 = specs
        .iter()
        .map(|s| {
            let mut f = if s.foveated {
                *paper
            } else {
                FoveationParams::uniform(s.spp[0])
            };
            f.spp = [s.spp[0], s.spp[1], s.spp[2], 0];
            count_samples(w, h, &f).iter().sum::<u64>()
        })
        .sum::<u64>()
        * seq.schedule.frames.len() as u64;
    bar.inc_length(samples);
    let inputs = sequence::SequenceInputs {
        packed,
        settings: plan.settings,
        paper: *paper,
        display: plan.display,
        ppd: plan.ppd,
        views,
        scene_name,
        bar,
        fovvideovdp: metric.as_ref().map_err(Clone::clone),
        scratch_dir: out_dir,
    };
    sequence::run_sequence(renderer, seq, &specs, &inputs)
}

/// What measuring a configuration needs.
struct Measurer<'a> {
    plan: &'a Plan,
    packed: &'a fovea_scene::pack::PackedScene,
    bar: &'a ProgressBar,
    scene_name: &'a str,
    reference: &'a FrameImage,
    reference_rgb8: &'a [u8],
    regions: &'a RegionMap,
    out_dir: &'a Path,
    /// The scene's camera.
    camera: Camera,
}

/// The median of `v` (the mean of the middle two for an even count).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

impl Measurer<'_> {
    /// Renders `spec` `runs` times, measures the first image against the reference and writes its PNG
    /// and FLIP map.
    fn measure(&self, renderer: &mut Renderer, spec: &ConfigSpec) -> Result<ConfigResult> {
        let [w, h] = self.plan.resolution;
        let settings = spec.texture_lod.map_or(self.plan.settings, |lod| {
            self.plan.settings.with_texture_lod(lod)
        });
        let mut frame = settings.frame(0, self.camera, spec.foveation);
        // Each configuration draws its own random numbers: with one key, 32/16/8's fovea would be
        // uniform's image there, and their comparison would hold by construction.
        frame.seed = sequence::spec_seed(frame.seed, &spec.slug);
        let mut runs_ms = Vec::new();
        let mut first: Option<(FrameImage, fovea_cpu::RenderStats)> = None;
        for run in 0..self.plan.runs {
            self.bar.set_message(format!(
                "{}: {} (run {}/{})",
                self.scene_name,
                spec.name,
                run + 1,
                self.plan.runs
            ));
            let request = settings.request(
                false,
                spec.denoise,
                FrameOutput::ReadBack {
                    want_hdr: first.is_none(),
                    want_raw: false,
                },
            );
            let rendered = renderer.render(self.packed, &frame, &request, &|n| self.bar.inc(n))?;
            runs_ms.push(rendered.stats.render_ms);
            match &first {
                None => {
                    let hdr = rendered.image.hdr.ok_or_else(|| {
                        FoveaError::Backend("the backend returned no HDR image".into())
                    })?;
                    first = Some((hdr, rendered.stats));
                }
                Some((_, stats)) if stats.primary_samples != rendered.stats.primary_samples => {
                    return Err(FoveaError::Backend(format!(
                        "{}: primary samples differ between runs ({} vs {})",
                        spec.name, stats.primary_samples, rendered.stats.primary_samples
                    )));
                }
                Some(_) => {}
            }
        }
        let (image, stats) = first.expect("at least one run");
        self.bar
            .set_message(format!("{}: {} (error)", self.scene_name, spec.name));
        let rgb8 = tonemapped_rgb8(&image, settings.exposure_ev);
        let flip = metrics::flip_map(self.reference_rgb8, &rgb8, w, h, self.plan.ppd);
        let rel_mse = metrics::rel_mse_map(&image, self.reference);
        let image_rel = format!("images/{}.png", spec.slug);
        let flip_rel = format!("flip/{}.png", spec.slug);
        write_png(&self.out_dir.join(&image_rel), w, h, &rgb8)?;
        write_png(
            &self.out_dir.join(&flip_rel),
            w,
            h,
            &metrics::flip_map_rgb8(&flip, w, h),
        )?;
        Ok(ConfigResult {
            spec: spec.clone(),
            render_ms: median(&runs_ms),
            runs_ms,
            primary_samples: stats.primary_samples,
            samples_per_region: stats.samples_per_region,
            speedup: f64::NAN,
            sample_ratio: f64::NAN,
            flip: RegionMeans::of(&flip, self.regions),
            rel_mse: RegionMeans::of(&rel_mse, self.regions),
            image: image_rel,
            flip_map: flip_rel,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn medians() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&[7.0]), 7.0);
        assert!(median(&[]).is_nan());
    }
}
