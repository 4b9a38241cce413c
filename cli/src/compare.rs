//! `fovea compare`: how far one linear HDR image is from another. It gives the figures the
//! cross-backend tests use, for any two images of one size. For example, the CPU's frame against a
//! GPU's, or fovea against Mitsuba on the same view:
//! - the share of pixels whose three channels all agree within 1e-3 relative or 1e-4 absolute;
//! - the largest absolute difference of a channel;
//! - the mean relMSE (`report`'s, [`crate::report::metrics::rel_mse_map`]);
//! - the mean FLIP of the two images tone-mapped as `render` writes PNGs.
//!
//! With `--gaze`, also relMSE and FLIP pooled by the paper's foveation regions around that fixation,
//! FLIP at the display's pixels per degree: `report`'s per-region figures for any two images.
use crate::args::CompareArgs;
use crate::error::{FoveaError, Result};
use crate::output::{read_exr, tonemapped_rgb8};
use crate::report::metrics::{flip_map, rel_mse_map, RegionMap, RegionMeans};
use crate::values;
use fovea_core::foveation::display::pixels_per_degree;
use fovea_core::foveation::regions::FoveationParams;
use fovea_cpu::FrameImage;

/// What `fovea compare` reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// Share of pixels whose every channel agrees ([`fovea_frame::pixels_agree`]).
    pub within: f64,
    /// The largest absolute difference of one channel, over the pixels finite in both images;
    /// `None` where no pixel is (an image all NaN), never a 0 that would read as "identical".
    pub max_abs: Option<f32>,
    /// Mean relMSE of the test against the reference.
    pub rel_mse: f64,
    /// Mean FLIP of the tone-mapped images (FLIP's default 67 pixels per degree).
    pub mean_flip: f64,
    /// Pixels with a NaN or infinite channel, in the test image and in the reference (they agree
    /// with nothing, and `max_abs` is over the pixels finite in both).
    pub non_finite: [usize; 2],
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
    let finite = |p: &[f32; 4]| p[..3].iter().all(|c| c.is_finite());
    let any_finite_pair = test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .any(|(a, b)| finite(a) && finite(b));
    let max_abs = any_finite_pair.then_some(max_abs);
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
    let bad = |image: &FrameImage| image.pixels.iter().filter(|p| !finite(p)).count();
    Agreement {
        within,
        max_abs,
        rel_mse,
        mean_flip,
        non_finite: [bad(test), bad(reference)],
    }
}

/// The error pooled by foveation region (`report`'s measure).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionErrors {
    /// The pixels per degree FLIP was computed at.
    pub pixels_per_degree: f32,
    /// Mean relMSE over the image and each region.
    pub rel_mse: RegionMeans,
    /// Mean FLIP over the image and each region.
    pub flip: RegionMeans,
}

/// relMSE and FLIP (at `pixels_per_degree`) of `test` against `reference`, pooled by the regions of
/// `foveation`.
#[must_use]
pub fn region_errors(
    test: &FrameImage,
    reference: &FrameImage,
    exposure_ev: f32,
    foveation: &FoveationParams,
    pixels_per_degree: f32,
) -> RegionErrors {
    let map = RegionMap::new(test.width, test.height, foveation);
    let flip = flip_map(
        &tonemapped_rgb8(reference, exposure_ev),
        &tonemapped_rgb8(test, exposure_ev),
        test.width,
        test.height,
        pixels_per_degree,
    );
    RegionErrors {
        pixels_per_degree,
        rel_mse: RegionMeans::of(&rel_mse_map(test, reference), &map),
        flip: RegionMeans::of(&flip, &map),
    }
}

/// The four means as JSON (`null` for a region without pixels).
fn means_json(m: RegionMeans) -> serde_json::Value {
    serde_json::json!({
        "all": m.all,
        "fovea": m.fovea,
        "intermediate": m.intermediate,
        "periphery": m.periphery,
    })
}

/// Runs `fovea compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    for path in [&args.test, &args.reference] {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let why = if path.is_dir() {
            "is a folder; compare reads two linear HDR .exr images".to_string()
        } else {
            match ext.as_deref() {
                Some("exr") => continue,
                Some("png") => {
                    "compare reads linear HDR .exr images (render with -o NAME.exr); a PNG \
                                is tone-mapped and 8-bit"
                        .to_string()
                }
                Some(other) => {
                    format!("has the extension '.{other}'; compare reads linear HDR .exr images")
                }
                None => "has no extension; compare reads linear HDR .exr images (NAME.exr)".into(),
            }
        };
        return Err(FoveaError::file(path, why));
    }
    if let Some(json) = &args.json {
        crate::output::check_json_path(json, "--json")?;
        crate::output::refuse_overwriting_inputs(
            &[("--json", json.as_path())],
            &[args.test.as_path(), args.reference.as_path()],
        )?;
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
    let regions = match args.gaze {
        Some(gaze) => {
            let size = [test.width, test.height];
            let (display, warning) =
                values::display_geometry(args.display.display_cm, args.display.distance_cm, size)?;
            if let Some(w) = warning {
                eprintln!("warning: {w}");
            }
            let radii = values::eccentricity_radii(args.display.eccentricity, &display);
            let foveation = FoveationParams::paper(gaze.0, radii[0], radii[1]);
            let ppd = pixels_per_degree(&display);
            Some((
                gaze.0,
                radii,
                region_errors(&test, &reference, args.exposure, &foveation, ppd),
            ))
        }
        None => None,
    };
    println!(
        "fovea: {} against {} ({}x{}): {:.4} % of pixels within 1e-3, max abs {}, relMSE {:.3e}, \
         mean FLIP {:.3e}",
        args.test.display(),
        args.reference.display(),
        test.width,
        test.height,
        100.0 * a.within,
        a.max_abs.map_or_else(
            || "none (no pixel is finite in both)".to_string(),
            |m| format!("{m:.3e}")
        ),
        a.rel_mse,
        a.mean_flip
    );
    for (count, path) in a.non_finite.iter().zip([&args.test, &args.reference]) {
        if *count > 0 {
            println!(
                "fovea: {count} pixel(s) of '{}' are NaN or infinite (they agree with nothing; max \
                 abs is over the pixels finite in both)",
                path.display()
            );
        }
    }
    if let Some((gaze, radii, r)) = &regions {
        let row = |m: RegionMeans| {
            format!(
                "{:.3e} / {:.3e} / {:.3e} / {:.3e}",
                m.all, m.fovea, m.intermediate, m.periphery
            )
        };
        println!(
            "fovea: by region around ({}, {}), radii {:.1} and {:.1} px, all / fovea / intermediate / \
             periphery:\n  relMSE {}\n  FLIP   {} (at {:.2} pixels per degree)",
            gaze[0],
            gaze[1],
            radii[0],
            radii[1],
            row(r.rel_mse),
            row(r.flip),
            r.pixels_per_degree
        );
    }
    if let Some(path) = &args.json {
        let mut json = serde_json::json!({
            "test": args.test.display().to_string(),
            "reference": args.reference.display().to_string(),
            "width": test.width,
            "height": test.height,
            "within_1e-3": a.within,
            "max_abs": a.max_abs,
            "rel_mse": a.rel_mse,
            "mean_flip": a.mean_flip,
            "non_finite_pixels": {"test": a.non_finite[0], "reference": a.non_finite[1]},
        });
        if let Some((gaze, radii, r)) = &regions {
            json["regions"] = serde_json::json!({
                "gaze": gaze,
                "radii_px": radii,
                "pixels_per_degree": r.pixels_per_degree,
                "rel_mse": means_json(r.rel_mse),
                "flip": means_json(r.flip),
            });
        }
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
        assert_eq!(agreement(&reference, &reference, 0.0).max_abs, Some(0.0));
        let test = image(vec![
            [1.0005, 0.5, 0.0, 0.0],  // 5e-4 relative: agrees
            [1.0, 0.5, 0.00005, 0.0], // 5e-5 absolute near zero: agrees
            [1.01, 0.5, 0.0, 0.0],    // 1e-2 relative: does not
            [f32::NAN, 0.5, 0.0, 0.0],
        ]);
        let a = agreement(&test, &reference, 0.0);
        assert_eq!(a.within, 0.5);
        assert!((a.max_abs.unwrap() - 0.01).abs() < 1e-6, "{:?}", a.max_abs);
        assert_eq!(a.non_finite, [1, 0]);
        // An image all NaN has no largest difference, not a 0 that reads as identical.
        let nan = image(vec![[f32::NAN, 0.5, 0.0, 0.0]; 4]);
        let all_nan = agreement(&nan, &reference, 0.0);
        assert_eq!(
            (all_nan.max_abs, all_nan.within, all_nan.non_finite),
            (None, 0.0, [4, 0])
        );
        // A NaN pixel shows in the mean error rather than being skipped.
        assert!(a.rel_mse.is_nan());
        let one = |r: f32| image(vec![[r, 0.5, 0.0, 0.0]]);
        assert!(agreement(&one(1.01), &one(1.0), 0.0).rel_mse > 0.0);
    }
}
