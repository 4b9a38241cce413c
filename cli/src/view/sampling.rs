//! What the live view samples: the configurations the `C` key cycles through, the foveated/uniform
//! toggle, and the frame-time budget that renders a fraction of a configuration's samples per frame.
//!
//! **Budget.** A configuration asks for `spp = [F, I, P]` samples per fovea pixel, intermediate block and
//! periphery block. When a frame at full `spp` takes longer than the budget (default 33 ms), frames render
//! `spp >> k` (at least 1 each), so the regions keep their ratios until the periphery is down to one
//! sample, after which the fovea keeps the most ("fovea first"). Accumulation while the eye and the camera
//! rest completes the configuration: after `2^k` frames each region has at least its configured samples.
//! `k` follows the measured frame time on every frame: up by `log2` of the overshoot at once (a 1.3 s
//! frame against 33 ms jumps five steps, not one per frame), down one step when twice the work would
//! still fit. A change of `k` does not restart the running mean: each frame is an unbiased estimate of
//! the pixel, so their plain mean stays unbiased, and the effective samples are counted frame by frame.
use fovea_core::foveation::regions::FoveationParams;

/// One sampling configuration of the live view.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplingConfig {
    /// Shown on screen, e.g. "32/16/8".
    pub name: String,
    /// Samples per fovea pixel, intermediate block, periphery block.
    pub spp: [u32; 3],
    /// Block edges per region.
    pub blocks: [u32; 3],
    /// Factor on the region radii (0.5 for the "half radii" configuration).
    pub radius_scale: f32,
}

impl SamplingConfig {
    /// The samples per pixel / block the configuration asks for: its own, or with `uniform` the
    /// fovea's everywhere.
    #[must_use]
    pub fn spp_for(&self, uniform: bool) -> [u32; 3] {
        if uniform {
            [self.spp[0]; 3]
        } else {
            self.spp
        }
    }

    fn new(spp: [u32; 3], blocks: [u32; 3], radius_scale: f32) -> Self {
        let mut name = format!("{}/{}/{}", spp[0], spp[1], spp[2]);
        if blocks != [1, 2, 4] {
            name.push_str(&format!(
                " blocks {}/{}/{}",
                blocks[0], blocks[1], blocks[2]
            ));
        }
        if radius_scale != 1.0 {
            name.push_str(&format!(" radii x{radius_scale}"));
        }
        Self {
            name,
            spp,
            blocks,
            radius_scale,
        }
    }
}

/// The configurations `C` cycles through: the paper's 32/16/8, two cheaper peripheries (32/8/4,
/// 32/2/1), 32/16/8 with half radii, and the user's `--spp/--blocks` when it is none of these. The first
/// is the user's (so the view starts with what the command line asked for).
#[must_use]
pub fn configurations(user_spp: [u32; 3], user_blocks: [u32; 3]) -> Vec<SamplingConfig> {
    let paper = [1, 2, 4];
    let mut list = vec![SamplingConfig::new(user_spp, user_blocks, 1.0)];
    for c in [
        SamplingConfig::new([32, 16, 8], paper, 1.0),
        SamplingConfig::new([32, 8, 4], paper, 1.0),
        SamplingConfig::new([32, 2, 1], paper, 1.0),
        SamplingConfig::new([32, 16, 8], paper, 0.5),
    ] {
        if !list.contains(&c) {
            list.push(c);
        }
    }
    list
}

/// The largest budget shift: beyond it every region is at one sample per frame anyway.
pub const MAX_SHIFT: u32 = 20;

/// Samples per frame for `spp` at budget shift `k`: `spp >> k`, at least 1.
#[must_use]
pub fn frame_spp(spp: [u32; 3], shift: u32) -> [u32; 3] {
    spp.map(|s| (s >> shift.min(31)).max(1))
}

/// The foveation parameters of one frame: `config` at `shift` around `gaze` with `radii` (before the
/// configuration's radius scale), or uniform at the fovea's samples per pixel.
#[must_use]
pub fn frame_foveation(
    config: &SamplingConfig,
    uniform: bool,
    shift: u32,
    gaze: [f32; 2],
    radii: [f32; 2],
) -> FoveationParams {
    let spp = frame_spp(config.spp, shift);
    if uniform {
        let mut f = FoveationParams::uniform(spp[0]);
        f.gaze = gaze;
        return f;
    }
    FoveationParams::new(
        gaze,
        radii.map(|r| r * config.radius_scale),
        spp,
        config.blocks,
    )
}

/// Chooses the budget shift from measured frame times.
#[derive(Clone, Debug)]
pub struct BudgetController {
    /// Frame-time budget in milliseconds; 0 turns the budget off (full configuration every frame).
    pub budget_ms: f64,
    shift: u32,
}

impl BudgetController {
    #[must_use]
    pub fn new(budget_ms: f64) -> Self {
        Self {
            budget_ms,
            shift: 0,
        }
    }

    /// The current shift.
    #[must_use]
    pub fn shift(&self) -> u32 {
        self.shift
    }

    /// Learns from a frame that took `frame_ms` at the current shift for `spp`.
    pub fn observe(&mut self, frame_ms: f64, spp: [u32; 3]) {
        if self.budget_ms <= 0.0 || !frame_ms.is_finite() || frame_ms <= 0.0 {
            return;
        }
        // The shift beyond which every region is at one sample.
        let floor = (0..MAX_SHIFT)
            .find(|&k| frame_spp(spp, k) == [1, 1, 1])
            .unwrap_or(MAX_SHIFT);
        if frame_ms > self.budget_ms * 1.2 {
            let steps = (frame_ms / self.budget_ms).log2().ceil().max(1.0) as u32;
            self.shift = (self.shift + steps).min(floor);
        } else if frame_ms * 2.0 < self.budget_ms * 0.8 && self.shift > 0 {
            self.shift -= 1;
        }
    }

    /// Forgets what it learnt (a new configuration or scene size).
    pub fn reset(&mut self) {
        self.shift = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cycle_starts_with_the_users_configuration_and_has_no_duplicates() {
        let list = configurations([32, 16, 8], [1, 2, 4]);
        assert_eq!(list.len(), 4);
        assert_eq!(list[0].name, "32/16/8");
        assert!(list.iter().any(|c| c.name == "32/2/1"));
        assert!(list.iter().any(|c| c.radius_scale == 0.5));
        let list = configurations([64, 8, 2], [1, 4, 8]);
        assert_eq!(list.len(), 5);
        assert_eq!(list[0].name, "64/8/2 blocks 1/4/8");
    }

    #[test]
    fn shifted_spp_keeps_ratios_then_floors_at_one() {
        assert_eq!(frame_spp([32, 16, 8], 0), [32, 16, 8]);
        assert_eq!(frame_spp([32, 16, 8], 3), [4, 2, 1]);
        assert_eq!(frame_spp([32, 16, 8], 4), [2, 1, 1]);
        assert_eq!(frame_spp([32, 16, 8], 40), [1, 1, 1]);
    }

    #[test]
    fn the_controller_jumps_by_the_overshoot_and_creeps_back() {
        let mut b = BudgetController::new(33.0);
        b.observe(100.0, [32, 16, 8]); // 3x over: log2 -> 2 steps
        assert_eq!(b.shift(), 2);
        b.observe(30.0, [32, 16, 8]);
        assert_eq!(b.shift(), 2, "within budget: stays");
        b.observe(5.0, [32, 16, 8]);
        assert_eq!(b.shift(), 1);
        b.observe(1.0e6, [32, 16, 8]);
        assert_eq!(frame_spp([32, 16, 8], b.shift()), [1, 1, 1]);
        assert_eq!(b.shift(), 5, "no further than every region at one sample");
        let mut off = BudgetController::new(0.0);
        off.observe(1000.0, [32, 16, 8]);
        assert_eq!(off.shift(), 0);
    }

    #[test]
    fn uniform_frames_use_the_fovea_spp_everywhere() {
        let c = &configurations([32, 16, 8], [1, 2, 4])[0];
        let f = frame_foveation(c, true, 3, [10.0, 10.0], [50.0, 150.0]);
        assert_eq!(f.spp[0], 4);
        let f = frame_foveation(c, false, 0, [10.0, 10.0], [50.0, 150.0]);
        assert_eq!((f.radius_fovea, f.spp[2]), (50.0, 8));
    }
}
