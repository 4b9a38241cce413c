//! Parsing of the comma- and x-separated option values (`1920x1080`, `32,16,8`, `1.5,2,-3`).
use crate::error::{FoveaError, Result};

/// Splits `text` at `sep` into exactly `N` values parsed as `T`.
pub fn list<T: std::str::FromStr + Copy + Default, const N: usize>(
    option: &'static str,
    text: &str,
    sep: char,
) -> Result<[T; N]> {
    let parts: Vec<&str> = text.split(sep).map(str::trim).collect();
    if parts.len() != N {
        return Err(FoveaError::option(
            option,
            format!("expected {N} values separated by '{sep}', got '{text}'"),
        ));
    }
    let mut out = [T::default(); N];
    for (slot, part) in out.iter_mut().zip(&parts) {
        *slot = part.parse().map_err(|_| {
            FoveaError::option(
                option,
                format!("'{part}' is not a valid number in '{text}'"),
            )
        })?;
    }
    Ok(out)
}

/// Finite floats.
pub fn floats<const N: usize>(option: &'static str, text: &str, sep: char) -> Result<[f32; N]> {
    let v: [f32; N] = list(option, text, sep)?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(FoveaError::option(
            option,
            format!("'{text}' contains a non-finite value"),
        ));
    }
    Ok(v)
}

/// `--point-light X,Y,Z,R,G,B` values: point lights at world position X,Y,Z with intensity R,G,B in W/sr
/// (radiant intensity per channel, as KHR_lights_punctual's candela without the photometric factor).
pub fn point_lights(texts: &[String]) -> Result<Vec<fovea_core::scene::Light>> {
    texts
        .iter()
        .map(|text| {
            let [x, y, z, r, g, b] = floats::<6>("--point-light", text, ',')?;
            if [r, g, b].iter().any(|&v| v < 0.0) {
                return Err(FoveaError::option(
                    "--point-light",
                    format!("'{text}': intensity must not be negative"),
                ));
            }
            Ok(fovea_core::scene::Light {
                kind: fovea_core::scene::LIGHT_POINT,
                position: [x, y, z, 0.0],
                intensity: [r, g, b, 0.0],
                ..Default::default()
            })
        })
        .collect()
}

/// `--eye`, `--target` and `--up`, parsed (their consistency is checked where the camera is made).
pub struct CameraOptions {
    pub eye: Option<[f32; 3]>,
    pub target: Option<[f32; 3]>,
    pub up: [f32; 3],
}

/// Parses the camera options shared by `render` and `report`.
pub fn camera_options(args: &crate::args::CameraArgs) -> Result<CameraOptions> {
    let point = |option: &'static str, text: &Option<String>| {
        text.as_deref()
            .map(|t| floats::<3>(option, t, ','))
            .transpose()
    };
    Ok(CameraOptions {
        eye: point("--eye", &args.eye)?,
        target: point("--target", &args.target)?,
        up: floats::<3>("--up", &args.up, ',')?,
    })
}

/// The largest image edge fovea accepts.
pub const MAX_IMAGE_EDGE: u32 = 32_768;
/// The most samples per pixel or block fovea accepts.
pub const MAX_SPP: u32 = 1 << 20;

/// `WxH` with both in 1..=[`MAX_IMAGE_EDGE`].
pub fn resolution(text: &str) -> Result<[u32; 2]> {
    let lower = text.to_ascii_lowercase();
    let [w, h]: [u32; 2] = list("--resolution", &lower, 'x')?;
    if w == 0 || h == 0 || w > MAX_IMAGE_EDGE || h > MAX_IMAGE_EDGE {
        return Err(FoveaError::option(
            "--resolution",
            format!("{w}x{h} is out of range (each edge 1 to {MAX_IMAGE_EDGE} pixels)"),
        ));
    }
    Ok([w, h])
}

/// The display from `--display-cm WxH` and `--distance-cm D`, filled by an image of `resolution` (so
/// pixels per centimetre, radii and pixels per degree scale with the rendered width).
pub fn display_geometry(
    display_cm: &str,
    distance_cm: f32,
    resolution: [u32; 2],
) -> Result<fovea_core::foveation::display::DisplayGeometry> {
    let size: [f32; 2] = floats("--display-cm", &display_cm.to_ascii_lowercase(), 'x')?;
    if size.iter().any(|&v| v <= 0.0) {
        return Err(FoveaError::option(
            "--display-cm",
            "both sizes must be positive",
        ));
    }
    if !(distance_cm.is_finite() && distance_cm > 0.0) {
        return Err(FoveaError::option(
            "--distance-cm",
            "the viewing distance must be positive",
        ));
    }
    Ok(fovea_core::foveation::display::DisplayGeometry {
        width_cm: size[0],
        height_cm: size[1],
        distance_cm,
        resolution,
    })
}

/// The region radii in pixels from `--eccentricity E1,E2` (degrees) on `display`.
pub fn eccentricity_radii(
    text: &str,
    display: &fovea_core::foveation::display::DisplayGeometry,
) -> Result<[f32; 2]> {
    use fovea_core::foveation::display::eccentricity_to_radius_px;
    let e: [f32; 2] = floats("--eccentricity", text, ',')?;
    if e[0] < 0.0 || e[1] < e[0] || e[1] >= 180.0 {
        return Err(FoveaError::option(
            "--eccentricity",
            "need 0 <= E1 <= E2 < 180 degrees",
        ));
    }
    Ok([
        eccentricity_to_radius_px(e[0], display),
        eccentricity_to_radius_px(e[1], display),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        assert_eq!(resolution("1920x1080").unwrap(), [1920, 1080]);
        assert_eq!(resolution("64X32").unwrap(), [64, 32]);
        assert!(resolution("0x10").is_err());
        assert!(resolution("100000x10").is_err());
        assert!(resolution("abc").is_err());
        assert_eq!(
            list::<u32, 3>("--spp", "32,16,8", ',').unwrap(),
            [32, 16, 8]
        );
        assert!(list::<u32, 3>("--spp", "32,16", ',').is_err());
        assert!(floats::<2>("--gaze", "1,nan", ',').is_err());
        assert_eq!(
            floats::<3>("--eye", "-1, 2.5,3", ',').unwrap(),
            [-1.0, 2.5, 3.0]
        );
    }
}
