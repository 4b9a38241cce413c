//! `fovea merge`: the parts of a render split by samples (`fovea render --samples A..B`) into the
//! image the whole render gives. The parts are checked first ([`crate::partial::check_parts`]): one
//! render, samples tiled without gap or overlap, each file whole. Nothing is written on refusal.
use crate::args::MergeArgs;
use crate::error::{FoveaError, Result};
use crate::output::{check_output_path, write_image};
use crate::partial::{check_parts, largest_spp, PartHeader};

/// Runs `fovea merge`.
pub fn run(args: &MergeArgs) -> Result<()> {
    let format = check_output_path(&args.output, "--output", true)?;
    if let Some(p) = args.parts.iter().find(|p| **p == args.output) {
        return Err(FoveaError::option(
            "--output",
            format!(
                "'{}' is one of the parts; fovea never overwrites its input",
                p.display()
            ),
        ));
    }
    let parts = args
        .parts
        .iter()
        .map(|p| PartHeader::read(p).map(|part| (p.clone(), part)))
        .collect::<Result<Vec<_>>>()?;
    let checked = check_parts(parts)?;
    let frame = *checked.frame();
    let image = checked.merged()?;
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
