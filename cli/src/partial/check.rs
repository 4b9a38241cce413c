//! Whether part files belong together, and their sum: [`check_parts`] refuses parts of different renders,
//! overlapping samples and gaps (naming what to render again), and [`CheckedParts::merged`] adds the
//! parts' data in sample order and fills the image.
use std::path::PathBuf;

use fovea_core::integrator::FrameParams;
use fovea_cpu::FrameImage;

use super::{largest_spp, PartHeader};
use crate::error::{FoveaError, Result};
use crate::values::SampleSelection;

/// The parts of one render, checked to belong together and to tile its samples, in sample order.
pub struct CheckedParts {
    /// Each part's file and header, sorted by their samples.
    pub parts: Vec<(PathBuf, PartHeader)>,
}

/// The key of the first line where two headers' identity lines differ (`header` where one has more).
fn first_difference<'a>(a: &'a [(String, String)], b: &[(String, String)]) -> Option<&'a str> {
    a.iter()
        .zip(b)
        .find(|(x, y)| x != y)
        .map(|(x, _)| x.0.as_str())
        .or((a.len() != b.len()).then_some("header"))
}

/// Checks that `parts` come from one render (the same identity lines) and that their sample ranges
/// tile `0..largest-spp` with no gap and no overlap. A gap names the missing samples, the `--samples`
/// options that render them and, for `I/N` parts, the job-array tasks to resubmit.
pub fn check_parts(mut parts: Vec<(PathBuf, PartHeader)>) -> Result<CheckedParts> {
    if parts.is_empty() {
        return Err(FoveaError::option("PARTS", "no part files given"));
    }
    // The render is the one most parts agree on (the first listed of a tie), so that a stray part
    // listed first is the one named, not the good parts after it.
    let agreeing = |i: usize| {
        parts
            .iter()
            .filter(|(_, p)| p.identity == parts[i].1.identity)
            .count()
    };
    let majority = (0..parts.len())
        .max_by_key(|&i| (agreeing(i), std::cmp::Reverse(i)))
        .unwrap_or(0);
    let (first_path, first) = parts[majority].clone();
    for (path, part) in &parts {
        if let Some(key) = first_difference(&first.identity, &part.identity) {
            // An edited or damaged header reads as another render's; its checksum tells.
            part.verify(path)?;
            return Err(FoveaError::file(
                path,
                format!(
                    "belongs to another render than '{}': their '{key}' lines differ",
                    first_path.display()
                ),
            ));
        }
    }
    parts.sort_by_key(|(_, p)| p.spec.samples);
    let total = largest_spp(&first.frame.foveation);
    let mut gaps = Vec::new();
    let mut covered = 0u32;
    for (i, (path, part)) in parts.iter().enumerate() {
        let [a, b] = part.spec.samples;
        if a < covered {
            let (other, _) = &parts[i - 1];
            return Err(FoveaError::file(
                path,
                format!(
                    "its samples {a}..{b} overlap those of '{}'; merge each sample once (is one of \
                     them left from an earlier split?)",
                    other.display()
                ),
            ));
        }
        if a > covered {
            gaps.push([covered, a]);
        }
        covered = b;
    }
    if covered < total {
        gaps.push([covered, total]);
    }
    if !gaps.is_empty() {
        let ranges: Vec<String> = gaps.iter().map(|[a, b]| format!("{a}..{b}")).collect();
        let options: Vec<String> = ranges.iter().map(|r| format!("--samples {r}")).collect();
        let mut message = format!(
            "samples {} of 0..{total} are missing; render them ({}) and merge again",
            ranges.join(", "),
            options.join(", ")
        );
        if let Some(tasks) = missing_tasks(&parts, &gaps, total) {
            message +=
                &format!(" (parts {tasks} of the --samples I/N split: resubmit those array tasks)");
        }
        return Err(FoveaError::option("PARTS", message));
    }
    Ok(CheckedParts { parts })
}

/// Where every part was rendered as `--samples I/N` with one `N`: the indices `I` whose ranges fall in
/// `gaps`, as `1, 3 of 4` (the job-array tasks to resubmit).
fn missing_tasks(parts: &[(PathBuf, PartHeader)], gaps: &[[u32; 2]], total: u32) -> Option<String> {
    let counts: Vec<u32> = parts
        .iter()
        .map(|(_, p)| p.spec.split.map(|[_, n]| n))
        .collect::<Option<_>>()?;
    let count = counts[0];
    if counts.iter().any(|&c| c != count) {
        return None;
    }
    let missing: Vec<String> = (0..count)
        .filter(|&index| {
            let [a, b] = SampleSelection::Part { index, count }.range(total);
            a < b && gaps.iter().any(|g| a < g[1] && g[0] < b)
        })
        .map(|i| i.to_string())
        .collect();
    Some(format!("{} of {count}", missing.join(", ")))
}

impl CheckedParts {
    /// Checks that these are parts of the render whose identity lines are `expected`
    /// ([`super::identity_lines`]), naming the first line that differs.
    pub fn expect_identity(&self, expected: &[(String, String)], what: &str) -> Result<()> {
        let (path, part) = &self.parts[0];
        match first_difference(expected, &part.identity) {
            None => Ok(()),
            Some(key) => Err(FoveaError::file(
                path,
                format!("is not a part of {what}: its '{key}' line differs"),
            )),
        }
    }

    /// The frame every part renders.
    #[must_use]
    pub fn frame(&self) -> &FrameParams {
        &self.parts[0].1.frame
    }

    /// The merged image: every pixel's sums and counts added over the parts in sample order (one part
    /// in memory at a time, each checked against its checksum as it is read), then the frame's block
    /// fill.
    pub fn merged(&self) -> Result<(FrameImage, Vec<(PathBuf, usize)>)> {
        let frame = *self.frame();
        let mut sums = vec![[0.0f32; 4]; frame.width as usize * frame.height as usize];
        let mut non_finite = Vec::new();
        for (path, part) in &self.parts {
            let bad = part.add_data_to(path, &mut sums)?;
            if bad > 0 {
                non_finite.push((path.clone(), bad));
            }
        }
        let image = fovea_cpu::fill_from_sample_sums(&frame, &sums, self.parts[0].1.fill_mode);
        Ok((image, non_finite))
    }
}
