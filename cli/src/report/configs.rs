//! The configurations a report measures (the paper's Tables 1 and 2 and more): uniform 32 spp, foveated
//! 32/16/8, 32/8/4, 32/2/1, 32/16/8 with both radii halved, 32/16/8 with the other texture rule (the
//! block-footprint mip levels if the report reads level 0, level 0 if it reads the block's levels), the
//! user's own (`--spp/--blocks/--radii/--eccentricity`), 32/16/8 denoised, 4/2/1 raw and denoised,
//! uniform at equal time, and a uniform sweep.
use fovea_core::foveation::regions::FoveationParams;
use fovea_core::integrator::path::{TEXTURE_LOD_BLOCK, TEXTURE_LOD_OFF};

/// What a configuration is, for the tables and the plot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigKind {
    /// The paper's baseline, uniform 32 spp.
    Uniform,
    /// A foveated configuration.
    Foveated,
    /// Uniform at the spp whose render time matches foveated 32/16/8.
    EqualTime,
    /// A point of the uniform spp sweep.
    Sweep,
}

impl ConfigKind {
    /// Its name in JSON and CSV.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Uniform => "uniform",
            Self::Foveated => "foveated",
            Self::EqualTime => "equal_time",
            Self::Sweep => "sweep",
        }
    }
}

/// One configuration to render.
#[derive(Clone, Debug)]
pub struct ConfigSpec {
    /// Its name in the tables ("uniform", "32/16/8", "uniform 4", ...).
    pub name: String,
    /// Its file name stem ("uniform", "32-16-8", "uniform-4", ...).
    pub slug: String,
    pub kind: ConfigKind,
    pub foveation: FoveationParams,
    /// The `TEXTURE_LOD_*` rule this configuration renders with; `None`: the report's (`--texture-lod`).
    pub texture_lod: Option<u32>,
    /// Denoised (`fovea_core::denoise`) after the fill.
    pub denoise: bool,
}

/// The uniform baseline's samples per pixel (the paper's 32).
pub const UNIFORM_SPP: u32 = 32;

/// Uniform rendering at `spp`, named for its `kind`.
#[must_use]
pub fn uniform(spp: u32, kind: ConfigKind) -> ConfigSpec {
    let (name, slug) = match kind {
        ConfigKind::Uniform => ("uniform".to_string(), "uniform".to_string()),
        ConfigKind::EqualTime => (
            format!("equal time ({spp} spp)"),
            format!("equal-time-{spp}"),
        ),
        _ => (format!("uniform {spp}"), format!("uniform-{spp}")),
    };
    ConfigSpec {
        name,
        slug,
        kind,
        foveation: FoveationParams::uniform(spp),
        texture_lod: None,
        denoise: false,
    }
}

/// The user's own configuration (`--spp`, `--blocks`, `--radii` or `--eccentricity` given), measured
/// after the paper's.
#[must_use]
pub fn user_config(foveation: FoveationParams) -> ConfigSpec {
    let [f, i, p, _] = foveation.spp;
    let [bf, bi, bp, _] = foveation.block_size;
    ConfigSpec {
        name: format!(
            "yours {f}/{i}/{p} blocks {bf}/{bi}/{bp} radii {:.1}/{:.1}",
            foveation.radius_fovea, foveation.radius_intermediate
        ),
        slug: "yours".into(),
        kind: ConfigKind::Foveated,
        foveation,
        texture_lod: None,
        denoise: false,
    }
}

/// The fixed configurations: uniform 32, then the foveated ones derived from `paper` (the paper's
/// 32/16/8 foveation with radii for this display and resolution), 32/16/8 with the texture rule that
/// `texture_lod` (the report's `TEXTURE_LOD_*`) is not, then the user's own if any.
#[must_use]
pub fn table_configs(
    paper: &FoveationParams,
    user: Option<&FoveationParams>,
    texture_lod: u32,
) -> Vec<ConfigSpec> {
    let foveated = |spp: [u32; 3], radius_scale: f32, suffix: &str| {
        let mut f = *paper;
        f.spp = [spp[0], spp[1], spp[2], 0];
        f.radius_fovea *= radius_scale;
        f.radius_intermediate *= radius_scale;
        let base = format!("{}/{}/{}", spp[0], spp[1], spp[2]);
        ConfigSpec {
            name: if suffix.is_empty() {
                base.clone()
            } else {
                format!("{base} {suffix}")
            },
            slug: format!(
                "{}{}",
                base.replace('/', "-"),
                if suffix.is_empty() {
                    String::new()
                } else {
                    format!("-{}", suffix.replace(' ', "-"))
                }
            ),
            kind: ConfigKind::Foveated,
            foveation: f,
            texture_lod: None,
            denoise: false,
        }
    };
    let mut configs = vec![
        uniform(UNIFORM_SPP, ConfigKind::Uniform),
        foveated([32, 16, 8], 1.0, ""),
        foveated([32, 8, 4], 1.0, ""),
        foveated([32, 2, 1], 1.0, ""),
        foveated([32, 16, 8], 0.5, "half radii"),
        if texture_lod == TEXTURE_LOD_OFF {
            ConfigSpec {
                texture_lod: Some(TEXTURE_LOD_BLOCK),
                ..foveated([32, 16, 8], 1.0, "block texture LOD")
            }
        } else {
            ConfigSpec {
                texture_lod: Some(TEXTURE_LOD_OFF),
                ..foveated([32, 16, 8], 1.0, "texture level 0")
            }
        },
    ];
    configs.extend(user.map(|f| user_config(*f)));
    // The denoiser: on the paper's budget, and on an eighth of it raw and denoised.
    configs.extend([
        ConfigSpec {
            denoise: true,
            ..foveated([32, 16, 8], 1.0, "denoised")
        },
        foveated([4, 2, 1], 1.0, ""),
        ConfigSpec {
            denoise: true,
            ..foveated([4, 2, 1], 1.0, "denoised")
        },
    ]);
    configs
}

/// The uniform sweep: 1, 2, 4, ... up to `max`, and `max` itself when it is not a power of two.
#[must_use]
pub fn sweep_spps(max: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let mut s = 1u32;
    while s <= max {
        out.push(s);
        match s.checked_mul(2) {
            Some(n) => s = n,
            None => break,
        }
    }
    if out.last() != Some(&max) && max > 0 {
        out.push(max);
    }
    out
}

/// The uniform spp whose time matches `target_ms` on the least-squares line `t = a + b · spp` through
/// the sweep's `(spp, ms)` points, rounded to the nearest integer and at least 1 (at most `max_spp`).
/// With fewer than two distinct spp or a non-increasing line, the sweep point closest in time is taken
/// instead. Returns the spp and the line's unrounded, unclamped spp (NaN when the fallback was used).
#[must_use]
pub fn equal_time_fit(points: &[(u32, f64)], target_ms: f64, max_spp: u32) -> (u32, f64) {
    let n = points.len() as f64;
    let mean_s = points.iter().map(|p| f64::from(p.0)).sum::<f64>() / n;
    let mean_t = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points
        .iter()
        .map(|p| (f64::from(p.0) - mean_s).powi(2))
        .sum();
    let sxt: f64 = points
        .iter()
        .map(|p| (f64::from(p.0) - mean_s) * (p.1 - mean_t))
        .sum();
    let slope = sxt / sxx;
    if points.len() >= 2 && sxx > 0.0 && slope.is_finite() && slope > 0.0 && target_ms.is_finite() {
        let spp = (target_ms - (mean_t - slope * mean_s)) / slope;
        return (
            spp.round().clamp(1.0, f64::from(max_spp.max(1))) as u32,
            spp,
        );
    }
    let nearest = points
        .iter()
        .min_by(|a, b| (a.1 - target_ms).abs().total_cmp(&(b.1 - target_ms).abs()))
        .map_or(1, |p| p.0.max(1));
    (nearest, f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_is_powers_of_two_up_to_max() {
        assert_eq!(sweep_spps(64), vec![1, 2, 4, 8, 16, 32, 64]);
        assert_eq!(sweep_spps(8), vec![1, 2, 4, 8]);
        assert_eq!(sweep_spps(1), vec![1]);
        assert_eq!(sweep_spps(48), vec![1, 2, 4, 8, 16, 32, 48]);
        assert!(sweep_spps(0).is_empty());
    }

    #[test]
    fn table_has_the_papers_configurations() {
        let paper = FoveationParams::paper([960.0, 540.0], 73.8, 243.0);
        let c = table_configs(&paper, None, TEXTURE_LOD_OFF);
        let names: Vec<_> = c.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "uniform",
                "32/16/8",
                "32/8/4",
                "32/2/1",
                "32/16/8 half radii",
                "32/16/8 block texture LOD",
                "32/16/8 denoised",
                "4/2/1",
                "4/2/1 denoised"
            ]
        );
        assert_eq!(c[5].texture_lod, Some(TEXTURE_LOD_BLOCK));
        assert!(c[6].denoise && !c[7].denoise && c[8].denoise);
        assert!(c[..5].iter().all(|c| c.texture_lod.is_none()));
        // A report that reads the block's levels compares with level 0.
        let c = table_configs(&paper, None, TEXTURE_LOD_BLOCK);
        assert_eq!(c[5].name, "32/16/8 texture level 0");
        assert_eq!(c[5].texture_lod, Some(TEXTURE_LOD_OFF));
        assert_eq!(c[0].foveation, FoveationParams::uniform(32));
        assert_eq!(c[1].foveation, paper);
        assert_eq!(c[3].foveation.spp, [32, 2, 1, 0]);
        assert_eq!(c[4].slug, "32-16-8-half-radii");
        assert_eq!(c[4].foveation.radius_fovea, 36.9);
        assert_eq!(c[4].foveation.radius_intermediate, 121.5);
        assert!(c[1..].iter().all(|c| c.kind == ConfigKind::Foveated));
    }

    #[test]
    fn equal_time_from_a_linear_fit() {
        // t = 10 + 2 spp exactly: 30 ms is 10 spp, 31 ms rounds 10.5 to 11 (round half away from zero).
        let pts = [(1, 12.0), (2, 14.0), (4, 18.0), (8, 26.0)];
        assert_eq!(equal_time_fit(&pts, 30.0, 1 << 20).0, 10);
        assert_eq!(equal_time_fit(&pts, 31.0, 1 << 20).0, 11);
        assert_eq!(equal_time_fit(&pts, 1.0, 1 << 20).0, 1, "at least 1");
        assert_eq!(equal_time_fit(&pts, 1.0, 1 << 20), (1, -4.5));
        assert_eq!(equal_time_fit(&pts, 1.0e9, 64).0, 64, "at most max");
        // Degenerate sweeps fall back to the closest point in time.
        assert_eq!(equal_time_fit(&[(4, 10.0)], 30.0, 64).0, 4);
        assert!(equal_time_fit(&[(4, 10.0)], 30.0, 64).1.is_nan());
        assert_eq!(equal_time_fit(&[(1, 10.0), (2, 5.0)], 6.0, 64).0, 2);
    }
}
