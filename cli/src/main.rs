//! `fovea`: the command line of the fovea foveated path tracer.
mod args;
mod backend;
mod bench;
mod camera_path;
mod compare;
mod content_hash;
mod csv_lines;
mod error;
// Without the Vulkan backend (`--no-default-features`: the CPU-only build of scripts/render-default.sh
// and the cluster's portable binary) the live view cannot run, but its modules (fly camera, HUD, gaze
// sources, fixation filter, budget) are still built and unit-tested: unused there, not dead.
#[cfg_attr(not(feature = "vulkan"), allow(dead_code))]
mod fixation;
#[cfg_attr(not(feature = "vulkan"), allow(dead_code))]
mod gaze;
mod merge;
mod output;
mod partial;
mod render;
mod report;
mod scene_setup;
mod schedule;
mod stats;
mod stereo;
mod values;
#[cfg_attr(not(feature = "vulkan"), allow(dead_code))]
mod view;
mod xr;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = args::Cli::parse();
    let result = match &cli.command {
        args::Command::Render(r) => render::run(r),
        args::Command::Merge(m) => merge::run(m),
        args::Command::Compare(c) => compare::run(c),
        args::Command::Report(r) => report::run(r),
        args::Command::Bench(b) => bench::run(b),
        args::Command::View(v) => view::run(v),
        args::Command::Xr(x) => xr::run(x),
        args::Command::Devices => {
            backend::print_devices();
            Ok(())
        }
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fovea: error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
