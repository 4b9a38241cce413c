//! The fovea after a saccade: how long the new point of gaze takes to get back the quality the old
//! one had.
//!
//! Offline, every frame's fovea lies exactly on that frame's gaze, so the lag of the regions behind the
//! eye is zero by construction. What does lag is *quality*: with temporal reuse, the pixels the eye
//! left had converged, and the pixels it lands on carry coarse periphery history, which the fovea's
//! first frame replaces. A saccade here is a gaze step larger than the fovea's radius in degrees (the
//! eye lands outside the old fovea); its lag is the number of frames until the fovea's mean FLIP is
//! back within [`RECOVERY_TOLERANCE`] of its mean over the frames before the saccade.
use fovea_core::foveation::display::{radius_px_to_eccentricity_deg, DisplayGeometry};

/// How close to the pre-saccade error counts as recovered (10 % above it).
pub const RECOVERY_TOLERANCE: f64 = 1.1;
/// Frames before a saccade whose mean is its baseline (fewer where the fixation was shorter).
pub const BASELINE_FRAMES: usize = 3;

/// Indices of the frames whose gaze lies more than `min_deg` of visual angle from the previous frame's.
#[must_use]
pub fn saccade_frames(gaze: &[[f32; 2]], display: &DisplayGeometry, min_deg: f32) -> Vec<usize> {
    (1..gaze.len())
        .filter(|&i| {
            let [a, b] = [gaze[i - 1], gaze[i]];
            radius_px_to_eccentricity_deg((a[0] - b[0]).hypot(a[1] - b[1]), display) > min_deg
        })
        .collect()
}

/// The fovea's recovery after the saccades of one sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct FoveaLag {
    /// Saccades with at least one frame before them.
    pub saccades: u32,
    /// Of those, the ones whose fovea was back within the tolerance before the next saccade (or the
    /// end of the sequence).
    pub recovered: u32,
    /// The median of the recovered ones' frames until recovery (0: the saccade's own frame was
    /// already as good); NaN when none recovered.
    pub median_frames: f64,
    /// The median over saccades of the fovea's error on the saccade's frame against its baseline.
    pub median_jump: f64,
}

/// The fovea's recovery: `fovea_error[i]` is frame `i`'s mean error in the fovea at its gaze,
/// `saccades` the frames where the gaze jumped ([`saccade_frames`]). `None` without a saccade that
/// has frames before it.
#[must_use]
pub fn fovea_lag(fovea_error: &[f64], saccades: &[usize]) -> Option<FoveaLag> {
    let mut frames_to_recover = Vec::new();
    let mut jumps = Vec::new();
    let mut counted = 0u32;
    for (k, &s) in saccades.iter().enumerate() {
        if s == 0 || s >= fovea_error.len() {
            continue;
        }
        let since_previous = if k > 0 { s - saccades[k - 1] } else { s };
        let n = since_previous.clamp(1, BASELINE_FRAMES);
        let baseline = fovea_error[s - n..s].iter().sum::<f64>() / n as f64;
        if baseline.is_nan() || baseline <= 0.0 {
            continue;
        }
        counted += 1;
        jumps.push(fovea_error[s] / baseline);
        let end = saccades
            .get(k + 1)
            .copied()
            .unwrap_or(fovea_error.len())
            .min(fovea_error.len());
        if let Some(lag) = (s..end).find(|&i| fovea_error[i] <= baseline * RECOVERY_TOLERANCE) {
            frames_to_recover.push((lag - s) as f64);
        }
    }
    if counted == 0 {
        return None;
    }
    Some(FoveaLag {
        saccades: counted,
        recovered: frames_to_recover.len() as u32,
        median_frames: if frames_to_recover.is_empty() {
            f64::NAN
        } else {
            super::median(&frames_to_recover)
        },
        median_jump: super::median(&jumps),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gaze_step_beyond_the_threshold_is_a_saccade_and_jitter_is_not() {
        let d = DisplayGeometry {
            resolution: [640, 360],
            ..DisplayGeometry::default()
        };
        // About 9.5 px per degree here: 2 px of jitter, then a 60 px (about 6 degree) jump.
        let gaze = [
            [320.0, 180.0],
            [322.0, 181.0],
            [321.0, 179.0],
            [381.0, 179.0],
            [382.0, 180.0],
        ];
        assert_eq!(saccade_frames(&gaze, &d, 2.6), vec![3]);
    }

    #[test]
    fn the_lag_counts_frames_until_the_error_is_back_near_its_baseline() {
        // Converged to 1.0 before each saccade; the first saccade's error decays over 3 frames, the
        // second never recovers before the sequence ends.
        let error = [1.0, 1.0, 1.0, 4.0, 2.0, 1.5, 1.05, 1.0, 1.0, 3.0, 2.5];
        let lag = fovea_lag(&error, &[3, 9]).unwrap();
        assert_eq!(lag.saccades, 2);
        assert_eq!(lag.recovered, 1);
        assert_eq!(lag.median_frames, 3.0);
        // Jumps: 4 against 1, and 3 against the 3 frames before the second saccade.
        let second = 3.0 / ((1.05 + 1.0 + 1.0) / 3.0);
        assert!(
            (lag.median_jump - (4.0 + second) / 2.0).abs() < 1e-12,
            "{lag:?}"
        );
        // Without history the error does not move: no lag.
        let flat = [1.0; 8];
        let lag = fovea_lag(&flat, &[4]).unwrap();
        assert_eq!(
            (lag.recovered, lag.median_frames, lag.median_jump),
            (1, 0.0, 1.0)
        );
        // No saccade with a frame before it: nothing to say.
        assert!(fovea_lag(&flat, &[0]).is_none());
        assert!(fovea_lag(&flat, &[]).is_none());
    }
}
