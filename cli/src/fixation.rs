//! A fixation filter for eye-tracker gaze: I-DT, dispersion-threshold identification (Salvucci and
//! Goldberg 2000; the radius form of Blignaut 2009). While the samples stay within `radius` of their
//! centroid they are one fixation, and the regions sit on its centroid instead of on every noisy
//! sample; a sample farther away is a saccade, and the gaze jumps to it at once (no lag). A fixation
//! needs [`MIN_FIXATION_SAMPLES`] samples before the centroid is used; the centroid is over the last
//! [`MAX_WINDOW_SAMPLES`], so slow drift is followed.
//!
//! Gaze processing, not rendering math: it runs on the host before the frame's foveation is built.

/// Samples before a run of close samples counts as a fixation (about 100 ms at 30 Hz).
pub const MIN_FIXATION_SAMPLES: usize = 3;
/// Samples the centroid is taken over (about 2 s at 60 Hz).
pub const MAX_WINDOW_SAMPLES: usize = 120;

/// The filter's state: the samples of the current fixation.
#[derive(Clone, Debug)]
pub struct FixationFilter {
    radius: f32,
    window: Vec<[f32; 2]>,
}

impl FixationFilter {
    /// A filter with a dispersion radius of `radius` (in the samples' units, e.g. pixels).
    #[must_use]
    pub fn new(radius: f32) -> Self {
        Self {
            radius,
            window: Vec::new(),
        }
    }

    /// The dispersion radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Adds a raw sample and returns where the regions go: the fixation's centroid, or the sample
    /// itself at a saccade or before a fixation has [`MIN_FIXATION_SAMPLES`] samples.
    pub fn push(&mut self, sample: [f32; 2]) -> [f32; 2] {
        if self.window.len() == MAX_WINDOW_SAMPLES {
            self.window.remove(0);
        }
        self.window.push(sample);
        let centroid = centroid(&self.window);
        let within = |p: &[f32; 2]| {
            let (dx, dy) = (p[0] - centroid[0], p[1] - centroid[1]);
            dx * dx + dy * dy <= self.radius * self.radius
        };
        if !self.window.iter().all(within) {
            // A saccade: a new fixation starts at this sample.
            self.window.clear();
            self.window.push(sample);
            return sample;
        }
        if self.window.len() < MIN_FIXATION_SAMPLES {
            sample
        } else {
            centroid
        }
    }
}

fn centroid(points: &[[f32; 2]]) -> [f32; 2] {
    let n = points.len().max(1) as f32;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(x, y), p| (x + p[0], y + p[1]));
    [sx / n, sy / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_within_the_radius_becomes_one_steady_fixation() {
        let mut f = FixationFilter::new(10.0);
        let noisy = [
            [100.0, 50.0],
            [103.0, 48.0],
            [98.0, 53.0],
            [101.0, 49.0],
            [97.0, 50.0],
        ];
        let out: Vec<[f32; 2]> = noisy.iter().map(|&s| f.push(s)).collect();
        // The first two are raw, then the centroid.
        assert_eq!(out[0], noisy[0]);
        assert_eq!(out[1], noisy[1]);
        assert_eq!(out[2], [301.0 / 3.0, 151.0 / 3.0]);
        let spread = |a: &[[f32; 2]]| {
            let xs = a.iter().map(|p| p[0]);
            xs.clone().fold(f32::MIN, f32::max) - xs.fold(f32::MAX, f32::min)
        };
        assert!(spread(&out[2..]) < spread(&noisy[2..]) / 2.0, "{out:?}");
    }

    #[test]
    fn a_saccade_moves_the_gaze_at_once() {
        let mut f = FixationFilter::new(10.0);
        for _ in 0..10 {
            f.push([100.0, 100.0]);
        }
        assert_eq!(f.push([300.0, 120.0]), [300.0, 120.0]);
        assert_eq!(f.push([302.0, 121.0]), [302.0, 121.0]);
        assert_eq!(f.push([301.0, 119.0]), [301.0, 120.0]);
    }
}
