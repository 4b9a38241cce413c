//! `fovea merge`: the parts of a render split by samples (`fovea render --samples A..B`) into the
//! image the whole render gives. The parts are checked first ([`crate::partial::check_parts`]): one
//! render, samples tiled without gap or overlap, each file whole. Nothing is written on refusal.
use crate::args::MergeArgs;
use crate::error::Result;
use std::path::PathBuf;

use crate::output::{check_output_path, refuse_overwriting_inputs, write_image};
use crate::partial::{check_parts, largest_spp, PartHeader};

/// Runs `fovea merge`.
pub fn run(args: &MergeArgs) -> Result<()> {
    let format = check_output_path(&args.output, "--output", true)?;
    let parts: Vec<&std::path::Path> = args.parts.iter().map(PathBuf::as_path).collect();
    refuse_overwriting_inputs(&[("--output", &args.output)], &parts)?;
    let parts = args
        .parts
        .iter()
        .map(|p| PartHeader::read(p).map(|part| (p.clone(), part)))
        .collect::<Result<Vec<_>>>()?;
    let checked = check_parts(parts)?;
    let frame = *checked.frame();
    let (image, non_finite) = checked.merged()?;
    if format == crate::output::ImageFormat::Exr && args.exposure != 0.0 {
        eprintln!(
            "warning: --exposure applies to a tone-mapped PNG; the --output EXR is linear and is \
             written without it"
        );
    }
    for (part, count) in &non_finite {
        eprintln!(
            "warning: {count} pixel(s) of '{}' hold NaN or infinite sums, which the merged image \
             shows as they are",
            part.display()
        );
    }
    write_image(&args.output, format, &image, args.exposure)?;
    if !args.quiet {
        println!(
            "fovea: merged {} part(s), samples 0..{} of a {}x{} frame -> {}",
            checked.parts.len(),
            largest_spp(&frame.foveation),
            frame.width,
            frame.height,
            args.output.display()
        );
    }
    Ok(())
}
