//! Typed command-line values, parsed once at the edge: clap calls each type's `FromStr` (its value
//! parser), so a malformed or out-of-range value fails in clap's own format and names the option
//! (`error: invalid value '0,1,1' for '--spp <F,I,P>': each value must be 1 to 1048576`), and the code
//! inside takes `[u32; 3]` or `[f32; 2]`, never strings.
use std::str::FromStr;

use fovea_core::foveation::display::{eccentricity_to_radius_px, DisplayGeometry};
use fovea_core::scene::{Light, LIGHT_POINT};

/// The largest image edge fovea accepts.
pub const MAX_IMAGE_EDGE: u32 = 32_768;
/// The most samples per pixel or block fovea accepts.
pub const MAX_SPP: u32 = 1 << 20;
/// The largest block edge.
pub const MAX_BLOCK_EDGE: u32 = 64;
/// How far off the image a gaze may be, in pixels (the regions are then partly or wholly off-screen).
pub const MAX_GAZE_OFFSET: f32 = 1.0e6;

/// Splits `text` at `sep` into exactly `N` values parsed as `T`.
fn split<T: FromStr + Copy + Default, const N: usize>(
    text: &str,
    sep: char,
) -> Result<[T; N], String> {
    let parts: Vec<&str> = text.split(sep).map(str::trim).collect();
    if parts.len() != N {
        return Err(format!("expected {N} values separated by '{sep}'"));
    }
    let mut out = [T::default(); N];
    for (slot, part) in out.iter_mut().zip(&parts) {
        *slot = part.parse().map_err(|_| not_a_number(part))?;
    }
    Ok(out)
}

/// Why `text` did not parse as the number an option wanted: negative, fractional or too large for a
/// whole number, or no number at all.
fn not_a_number(text: &str) -> String {
    match text.parse::<f64>() {
        Ok(v) if v < 0.0 => format!("'{text}' is negative"),
        Ok(v) if v.is_finite() && v.fract() != 0.0 => format!("'{text}' is not a whole number"),
        Ok(v) if !v.is_nan() => format!("'{text}' is too large"),
        _ => format!("'{text}' is not a valid number"),
    }
}

/// A whole number of type `T` (a count or an index: `--threads`, `--device`), with fovea's messages
/// for a negative, fractional or too large one rather than the parser's "invalid digit".
pub fn whole_number<T: FromStr + TryFrom<u64>>(text: &str) -> Result<T, String> {
    let text = text.trim();
    let v: u64 = text.parse().map_err(|_| not_a_number(text))?;
    T::try_from(v).map_err(|_| format!("'{text}' is too large"))
}

/// An exposure compensation in EV (`--exposure`): finite and within ±64 stops (2^64 is beyond what
/// tone mapping can use in f32).
pub fn exposure_ev(text: &str) -> Result<f32, String> {
    let text = text.trim();
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= 64.0 => Ok(v),
        _ => Err(format!("'{text}' is not a finite EV between -64 and 64")),
    }
}

/// `N` finite floats separated by `sep`.
fn finite<const N: usize>(text: &str, sep: char) -> Result<[f32; N], String> {
    let v: [f32; N] = split(text, sep)?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(format!("'{text}' contains a non-finite value"));
    }
    Ok(v)
}

/// `N` f64 values separated by `sep`, each finite and within f32's range (they become f32 once moved
/// into a scene's coordinates).
fn finite_f64<const N: usize>(text: &str, sep: char) -> Result<[f64; N], String> {
    let v: [f64; N] = split(text, sep)?;
    if v.iter()
        .any(|x| !x.is_finite() || x.abs() > f64::from(f32::MAX))
    {
        return Err(format!(
            "'{text}' contains a non-finite value or one beyond single precision's range"
        ));
    }
    Ok(v)
}

/// Declares a newtype over an array parsed by `$parse` (a `fn(&str) -> Result<$inner, String>`).
macro_rules! typed_value {
    ($(#[$doc:meta])* $name:ident($inner:ty) = $parse:expr) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name(pub $inner);

        impl FromStr for $name {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                let parse: fn(&str) -> Result<$inner, String> = $parse;
                parse(s).map(Self)
            }
        }
    };
}

typed_value!(
    /// `WxH`, each edge 1 to [`MAX_IMAGE_EDGE`] pixels.
    Resolution([u32; 2]) = |s| {
        // Parsed wide, so that a negative or huge edge gets the range message too.
        let [w, h]: [i64; 2] = split(&s.to_ascii_lowercase(), 'x')?;
        let edge = 1..=i64::from(MAX_IMAGE_EDGE);
        if !edge.contains(&w) || !edge.contains(&h) {
            return Err(format!("out of range (each edge 1 to {MAX_IMAGE_EDGE} pixels)"));
        }
        Ok([w as u32, h as u32])
    }
);

typed_value!(
    /// `F,I,P`: samples per fovea pixel, intermediate block and periphery block, each 1 to
    /// [`MAX_SPP`].
    SppTriple([u32; 3]) = |s| {
        let v: [i64; 3] = split(s, ',')?;
        if v.iter().any(|&x| !(1..=i64::from(MAX_SPP)).contains(&x)) {
            return Err(format!("each value must be 1 to {MAX_SPP}"));
        }
        Ok(v.map(|x| x as u32))
    }
);

typed_value!(
    /// `F,I,P`: block edges in pixels per region, each 1 to [`MAX_BLOCK_EDGE`] and dividing the next.
    BlockTriple([u32; 3]) = |s| {
        let v: [i64; 3] = split(s, ',')?;
        if v.iter().any(|&x| !(1..=i64::from(MAX_BLOCK_EDGE)).contains(&x)) {
            return Err(format!("each block edge must be 1 to {MAX_BLOCK_EDGE}"));
        }
        let v = v.map(|x| x as u32);
        if !v[1].is_multiple_of(v[0]) || !v[2].is_multiple_of(v[1]) {
            return Err(
                "each block edge must divide the next (fovea | intermediate | periphery)".into(),
            );
        }
        Ok(v)
    }
);

/// `--samples`: which of a frame's samples a part of a split render takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleSelection {
    /// `A..B`: sample indices `A` up to `B` (not included), `0 <= A < B <=` [`MAX_SPP`].
    Range([u32; 2]),
    /// `I/N`: part `I` of `N` equal parts (0-based), as a job array's task `I` of `N` takes it.
    Part { index: u32, count: u32 },
}

impl SampleSelection {
    /// The sample range of a frame whose blocks take at most `largest_spp` samples: part `I` of `N` is
    /// `I·S/N .. (I+1)·S/N`, so the `N` parts tile `0..S`.
    #[must_use]
    pub fn range(self, largest_spp: u32) -> [u32; 2] {
        match self {
            Self::Range(r) => r,
            Self::Part { index, count } => {
                let at = |i: u32| (u64::from(i) * u64::from(largest_spp) / u64::from(count)) as u32;
                [at(index), at(index + 1)]
            }
        }
    }
}

impl FromStr for SampleSelection {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let number = |t: &str| t.trim().parse::<i64>().map_err(|_| not_a_number(t.trim()));
        if let Some((a, b)) = s.split_once("..") {
            let (a, b) = (number(a)?, number(b)?);
            if !(0 <= a && a < b && b <= i64::from(MAX_SPP)) {
                return Err(format!("need 0 <= A < B <= {MAX_SPP}"));
            }
            return Ok(Self::Range([a as u32, b as u32]));
        }
        if s.contains('/') {
            let [index, count] = part_of(s, MAX_SPP)?;
            return Ok(Self::Part { index, count });
        }
        Err("expected A..B (samples A up to B) or I/N (part I of N, from 0)".into())
    }
}

/// `I/N` with `0 <= I < N <= max`: part `I` of `N`, counted from 0 as a job array's task ids are.
fn part_of(s: &str, max: u32) -> Result<[u32; 2], String> {
    let number = |t: &str| t.trim().parse::<i64>().map_err(|_| not_a_number(t.trim()));
    let Some((i, n)) = s.split_once('/') else {
        return Err("expected I/N (part I of N, from 0)".into());
    };
    let (i, n) = (number(i)?, number(n)?);
    if !(0 <= i && i < n && n <= i64::from(max)) {
        return Err(format!("need 0 <= I < N <= {max} (part I of N, from 0)"));
    }
    Ok([i as u32, n as u32])
}

/// The most tasks a report's scenes are split into.
pub const MAX_TASKS: u32 = 10_000;

typed_value!(
    /// `I/N`: task `I` of `N` (from 0, as `SLURM_ARRAY_TASK_ID`), `N` at most [`MAX_TASKS`].
    ArrayTask([u32; 2]) = |s| part_of(s, MAX_TASKS)
);

impl ArrayTask {
    /// Whether item `i` of a list belongs to this task: every `N`-th item from the `I`-th.
    #[must_use]
    pub fn takes(self, i: usize) -> bool {
        i % self.0[1] as usize == self.0[0] as usize
    }
}

typed_value!(
    /// `X,Y` in pixels (a gaze): finite, at most [`MAX_GAZE_OFFSET`] pixels from the origin.
    PixelPoint([f32; 2]) = |s| {
        let v: [f32; 2] = finite(s, ',')?;
        if v.iter().any(|x| x.abs() > MAX_GAZE_OFFSET) {
            return Err(format!("{v:?} is absurdly far off the image (over {MAX_GAZE_OFFSET} px)"));
        }
        Ok(v)
    }
);

typed_value!(
    /// An interpupillary distance in scene units (`render --stereo`): finite, positive, and small
    /// against the f32 range.
    Ipd(f32) = |s| {
        let v: f32 = s.trim().parse().map_err(|_| not_a_number(s.trim()))?;
        if !(v.is_finite() && v > 0.0 && v <= 1e6) {
            return Err(format!(
                "{v} is not a distance between the eyes; give a positive one in scene units (0.064 \
                 for a scene in metres)"
            ));
        }
        Ok(v)
    }
);

typed_value!(
    /// `R1,R2`: region radii in pixels, `0 <= R1 <= R2`.
    RadiiPx([f32; 2]) = |s| {
        let r: [f32; 2] = finite(s, ',')?;
        if !(r[0] >= 0.0 && r[1] >= r[0]) {
            return Err("need 0 <= R1 <= R2".into());
        }
        Ok(r)
    }
);

typed_value!(
    /// `E1,E2`: region bounds in degrees of eccentricity, `0 <= E1 <= E2 < 180`.
    Eccentricity([f32; 2]) = |s| {
        let e: [f32; 2] = finite(s, ',')?;
        if !(e[0] >= 0.0 && e[1] >= e[0] && e[1] < 180.0) {
            return Err("need 0 <= E1 <= E2 < 180 degrees".into());
        }
        Ok(e)
    }
);

typed_value!(
    /// `WxH`: the display's size in centimetres, both positive.
    DisplayCm([f32; 2]) = |s| {
        let v: [f32; 2] = finite(&s.to_ascii_lowercase(), 'x')?;
        if v.iter().any(|&x| x <= 0.0) {
            return Err("both sizes must be positive".into());
        }
        Ok(v)
    }
);

typed_value!(
    /// `X,Y,Z`: a point or vector, finite; kept in f64, so that a world point far from the origin keeps
    /// its precision until it is moved into the scene's coordinates (`fovea_scene::rebase`).
    Point3([f64; 3]) = |s| finite_f64(s, ',')
);

typed_value!(
    /// `R,G,B`: a radiance, finite and not negative.
    Rgb([f32; 3]) = |s| {
        let c: [f32; 3] = finite(s, ',')?;
        if c.iter().any(|&v| v < 0.0) {
            return Err("a radiance must not be negative".into());
        }
        Ok(c)
    }
);

/// A point light given on the command line: its world position (f64) and intensity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldPointLight {
    pub position: [f64; 3],
    pub intensity: [f32; 3],
}

impl WorldPointLight {
    /// The light in the coordinates of a scene whose origin is `origin` (`LoadedScene::origin`).
    #[must_use]
    pub fn in_scene(&self, origin: [f64; 3]) -> Light {
        let [x, y, z] = fovea_scene::rebase::to_local(self.position, origin);
        let [r, g, b] = self.intensity;
        Light {
            kind: LIGHT_POINT,
            position: [x, y, z, 0.0],
            intensity: [r, g, b, 0.0],
            ..Default::default()
        }
    }
}

typed_value!(
    /// `X,Y,Z,R,G,B`: a point light at X,Y,Z (world space) with intensity R,G,B in W/sr (radiant
    /// intensity per channel, as KHR_lights_punctual's candela without the photometric factor).
    PointLight(WorldPointLight) = |s| {
        let [x, y, z, r, g, b]: [f64; 6] = finite_f64(s, ',')?;
        if [r, g, b].iter().any(|&v| v < 0.0) {
            return Err("intensity must not be negative".into());
        }
        Ok(WorldPointLight {
            position: [x, y, z],
            intensity: [r as f32, g as f32, b as f32],
        })
    }
);

/// The display model for an image of `resolution` that fills the display's width (radii scale with the
/// rendered width), and a warning when the display's aspect ratio is not the image's (the height is then
/// not what the image covers, and the radii follow the width alone).
pub fn display_geometry(
    display_cm: DisplayCm,
    distance_cm: f32,
    resolution: [u32; 2],
) -> Result<(DisplayGeometry, Option<String>), crate::error::FoveaError> {
    if !(distance_cm.is_finite() && distance_cm > 0.0) {
        return Err(crate::error::FoveaError::option(
            "--distance-cm",
            "the viewing distance must be positive",
        ));
    }
    let display = display_at(display_cm, distance_cm, resolution);
    let [w, h] = display_cm.0;
    let display_aspect = w / h;
    let image_aspect = resolution[0] as f32 / resolution[1] as f32;
    let warning = ((display_aspect / image_aspect - 1.0).abs() > 0.02).then(|| {
        format!(
            "--display-cm {w}x{h} has aspect {display_aspect:.3} but the image ({}x{}) has {image_aspect:.3}: \
             the image is taken to fill the display's width, and the radii follow the width alone",
            resolution[0], resolution[1]
        )
    });
    Ok((display, warning))
}

/// The display model of checked options for an image of `resolution` that fills its width.
#[must_use]
pub fn display_at(
    display_cm: DisplayCm,
    distance_cm: f32,
    resolution: [u32; 2],
) -> DisplayGeometry {
    DisplayGeometry {
        width_cm: display_cm.0[0],
        height_cm: display_cm.0[1],
        distance_cm,
        resolution,
    }
}

/// The radii in pixels of `eccentricity` on `display` (`a = 2·d·tan(e/2)`, Mohanto et al. 2023).
#[must_use]
pub fn eccentricity_radii(eccentricity: Eccentricity, display: &DisplayGeometry) -> [f32; 2] {
    eccentricity
        .0
        .map(|e| eccentricity_to_radius_px(e, display))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_is_a_finite_ev_within_64_stops() {
        assert_eq!(exposure_ev(" -2.5 "), Ok(-2.5));
        assert_eq!(exposure_ev("64"), Ok(64.0));
        for bad in ["65", "-64.5", "nan", "inf", "1e40", "two"] {
            let e = exposure_ev(bad).unwrap_err();
            assert!(
                e.contains("is not a finite EV between -64 and 64"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn parses_and_rejects() {
        let samples = |s: &str| s.parse::<SampleSelection>();
        assert_eq!(samples("8..24"), Ok(SampleSelection::Range([8, 24])));
        for bad in [
            "8..8",
            "9..8",
            "-1..4",
            "0..",
            "4",
            "0..2000000",
            "4/4",
            "1/0",
            "-1/3",
        ] {
            assert!(samples(bad).is_err(), "{bad}");
        }
        // Parts of 1000 samples in 3: 0..333, 333..666, 666..1000.
        let parts: Vec<[u32; 2]> = (0..3)
            .map(|i| samples(&format!("{i}/3")).unwrap().range(1000))
            .collect();
        assert_eq!(parts, [[0, 333], [333, 666], [666, 1000]]);
        assert_eq!("1920x1080".parse::<Resolution>().unwrap().0, [1920, 1080]);
        assert_eq!("64X32".parse::<Resolution>().unwrap().0, [64, 32]);
        assert!("0x10".parse::<Resolution>().is_err());
        assert!("100000x10".parse::<Resolution>().is_err());
        assert!("abc".parse::<Resolution>().is_err());
        assert_eq!("32, 16,8".parse::<SppTriple>().unwrap().0, [32, 16, 8]);
        assert!("0,1,1".parse::<SppTriple>().is_err());
        assert!("1,3,4".parse::<BlockTriple>().is_err());
        assert!("1,2,4".parse::<BlockTriple>().is_ok());
        assert!("1,nan".parse::<PixelPoint>().is_err());
        // Negative and huge values get the range message; a fraction or a word says what it is.
        let err = |e: Result<SppTriple, String>| e.unwrap_err();
        assert_eq!(err("-1,2,3".parse()), "each value must be 1 to 1048576");
        assert_eq!(
            err("99999999999,1,1".parse()),
            "each value must be 1 to 1048576"
        );
        assert_eq!(err("2.5,1,1".parse()), "'2.5' is not a whole number");
        assert_eq!(err("x,1,1".parse()), "'x' is not a valid number");
        assert!("-5x10"
            .parse::<Resolution>()
            .unwrap_err()
            .contains("out of range"));
        assert_eq!(whole_number::<usize>("-2").unwrap_err(), "'-2' is negative");
        assert_eq!(
            whole_number::<u32>("4294967296").unwrap_err(),
            "'4294967296' is too large"
        );
        assert_eq!(whole_number::<u32>("7"), Ok(7));
        assert!("1e9,0".parse::<PixelPoint>().is_err());
        assert!("-100,5000".parse::<PixelPoint>().is_ok());
        assert!("5,2".parse::<RadiiPx>().is_err());
        assert!("5,200".parse::<Eccentricity>().is_err());
        assert!("70x0".parse::<DisplayCm>().is_err());
        assert!("1,-1,1".parse::<Rgb>().is_err());
        let l = "0,1,2,3,4,5".parse::<PointLight>().unwrap().0;
        assert_eq!((l.position[1], l.intensity[2]), (1.0, 5.0));
        assert!("0,1,2".parse::<PointLight>().is_err());
        // Finite in f64 but beyond f32: refused, not turned into infinity.
        assert!("0,0,0,1e39,1,1".parse::<PointLight>().is_err());
        assert!("1e39,0,0".parse::<Point3>().is_err());
        assert_eq!("1e5,2.5,-3".parse::<Point3>().unwrap().0, [1e5, 2.5, -3.0]);
    }

    #[test]
    fn a_display_of_another_aspect_is_warned_about() {
        let d = "70.848x39.852".parse::<DisplayCm>().unwrap();
        assert!(display_geometry(d, 60.0, [3840, 2160]).unwrap().1.is_none());
        let (_, w) = display_geometry(d, 60.0, [1000, 1000]).unwrap();
        assert!(w.unwrap().contains("--display-cm"));
        assert!(display_geometry(d, 0.0, [10, 10]).is_err());
    }
}
