//! `fovea compare`: how far one linear HDR image is from another. It gives the figures the
//! cross-backend tests use, for any two images of one size. For example, the CPU's frame against a
//! GPU's, or fovea against Mitsuba on the same view:
//! - the share of pixels whose three channels all agree within 1e-3 relative or 1e-4 absolute;
//! - the largest absolute difference of a channel;
//! - the mean relMSE (`report`'s, [`crate::report::metrics::rel_mse_map`]);
//! - the mean FLIP of the two images tone-mapped as `render` writes PNGs.
use crate::args::CompareArgs;
use crate::error::{FoveaError, Result};
use crate::output::{read_exr, tonemapped_rgb8};
use crate::report::metrics::{flip_map, rel_mse_map};
use fovea_cpu::FrameImage;

/// What `fovea compare` reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// Share of pixels whose every channel agrees ([`fovea_frame::pixels_agree`]).
    pub within: f64,
    /// The largest absolute difference of one channel.
    pub max_abs: f32,
    /// Mean relMSE of the test against the reference.
    pub rel_mse: f64,
    /// Mean FLIP of the tone-mapped images (FLIP's default 67 pixels per degree).
    pub mean_flip: f64,
}

/// The figures of `test` against `reference`, which must be of one size.
#[must_use]
pub fn agreement(test: &FrameImage, reference: &FrameImage, exposure_ev: f32) -> Agreement {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height),
        "same size"
    );
    let (within, max_abs) = fovea_frame::agreement(test, reference);
    let n = test.pixels.len().max(1) as f64;
    let rel_mse = rel_mse_map(test, reference)
        .iter()
        .map(|&e| f64::from(e))
        .sum::<f64>()
        / n;
    let flip = flip_map(
        &tonemapped_rgb8(reference, exposure_ev),
        &tonemapped_rgb8(test, exposure_ev),
        test.width,
        test.height,
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let mean_flip = flip.iter().map(|&e| f64::from(e)).sum::<f64>() / n;
    Agreement {
        within,
        max_abs,
        rel_mse,
        mean_flip,
    }
}

/// Runs `fovea compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    for path in [&args.test, &args.reference] {
        let exr = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if !exr {
            return Err(FoveaError::file(
                path,
                "compare reads linear HDR .exr images (render with -o NAME.exr); a PNG is tone-mapped \
                 and 8-bit",
            ));
        }
    }
    let test = read_exr(&args.test)?;
    let reference = read_exr(&args.reference)?;
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(FoveaError::option(
            "TEST",
            format!(
                "'{}' is {}x{} and '{}' is {}x{}: compare needs images of one size",
                args.test.display(),
                test.width,
                test.height,
                args.reference.display(),
                reference.width,
                reference.height
            ),
        ));
    }
    let a = agreement(&test, &reference, args.exposure);
    println!(
        "fovea: {} against {} ({}x{}): {:.4} % of pixels within 1e-3, max abs {:.3e}, relMSE {:.3e}, \
         mean FLIP {:.3e}",
        args.test.display(),
        args.reference.display(),
        test.width,
        test.height,
        100.0 * a.within,
        a.max_abs,
        a.rel_mse,
        a.mean_flip
    );
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "test": args.test.display().to_string(),
            "reference": args.reference.display().to_string(),
            "width": test.width,
            "height": test.height,
            "within_1e-3": a.within,
            "max_abs": a.max_abs,
            "rel_mse": a.rel_mse,
            "mean_flip": a.mean_flip,
        });
        crate::stats::write_json(path, &json)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: Vec<[f32; 4]>) -> FrameImage {
        FrameImage {
            width: pixels.len() as u32,
            height: 1,
            pixels,
        }
    }

    #[test]
    fn agreement_counts_pixels_within_the_tolerances() {
        let reference = image(vec![[1.0, 0.5, 0.0, 0.0]; 4]);
        assert_eq!(agreement(&reference, &reference, 0.0).within, 1.0);
        assert_eq!(agreement(&reference, &reference, 0.0).max_abs, 0.0);
        let test = image(vec![
            [1.0005, 0.5, 0.0, 0.0],  // 5e-4 relative: agrees
            [1.0, 0.5, 0.00005, 0.0], // 5e-5 absolute near zero: agrees
            [1.01, 0.5, 0.0, 0.0],    // 1e-2 relative: does not
            [f32::NAN, 0.5, 0.0, 0.0],
        ]);
        let a = agreement(&test, &reference, 0.0);
        assert_eq!(a.within, 0.5);
        assert!((a.max_abs - 0.01).abs() < 1e-6, "{}", a.max_abs);
        // A NaN pixel shows in the mean error rather than being skipped.
        assert!(a.rel_mse.is_nan());
        let one = |r: f32| image(vec![[r, 0.5, 0.0, 0.0]]);
        assert!(agreement(&one(1.01), &one(1.0), 0.0).rel_mse > 0.0);
    }
}
