//! `fovea`: the command line of the fovea foveated path tracer.
mod args;
mod backend;
mod error;
mod output;
mod parse;
mod render;
mod scene_setup;
mod stats;
mod trace;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = args::Cli::parse();
    let result = match &cli.command {
        args::Command::Render(r) => render::run(r),
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
