//! Progressive accumulation while the eye and the camera rest (the live view): frame `n` (0-based since
//! the last reset) renders new sample indices, and each pixel keeps the running mean of the `n + 1`
//! filled frames, `m_n = m_{n-1} + (x_n - m_{n-1}) / (n + 1)` (Welford's update, which stays accurate
//! over many frames where a running sum divided at the end would lose low bits). The frames being
//! independent estimates of the same pixel, the mean's variance falls as `1 / (n + 1)`. The paper's code
//! has this step commented out; fovea's live view turns it on.
use glam::Vec4;

/// The running mean after adding `frame` to `mean`, the mean of the `frames_before` earlier frames
/// (`frames_before == 0` starts afresh: the result is `frame`, whatever `mean` holds).
#[inline]
#[must_use]
pub fn accumulate_mean(mean: Vec4, frame: Vec4, frames_before: u32) -> Vec4 {
    if frames_before == 0 {
        frame
    } else {
        mean + (frame - mean) / (frames_before as f32 + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_mean_equals_the_mean() {
        let frames = [1.0f32, 5.0, 2.0, 8.0, 4.0];
        let mut m = Vec4::splat(f32::NAN); // ignored on the first frame
        for (n, &x) in frames.iter().enumerate() {
            m = accumulate_mean(m, Vec4::splat(x), n as u32);
        }
        assert!((m.x - 4.0).abs() < 1e-6);
    }
}
