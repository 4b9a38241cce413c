//! Camera paths (`fovea render --camera-path`): CSV files with one
//! `frame,eye_x,eye_y,eye_z,target_x,target_y,target_z` line per frame (a header line and `#` comments
//! are allowed).
use std::path::Path;

use crate::error::{FoveaError, Result};

/// The most frames a camera path may hold.
pub const MAX_PATH_FRAMES: usize = 1_000_000;

/// A camera path's columns, each with the names its header may give it.
const CAMERA_PATH_COLUMNS: &[&[&str]] = &[
    &["frame"],
    &["eye_x", "ex"],
    &["eye_y", "ey"],
    &["eye_z", "ez"],
    &["target_x", "tx"],
    &["target_y", "ty"],
    &["target_z", "tz"],
];

/// One line of a camera path: where the camera is and what it looks at in one frame (world
/// coordinates, as `--eye` and `--target`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    pub frame: u32,
    pub eye: [f64; 3],
    pub target: [f64; 3],
}

/// Parses a camera path: lines `frame,eye_x,eye_y,eye_z,target_x,target_y,target_z` (a header line and
/// `#` comments allowed); errors name the file and the line.
pub fn parse_camera_path(path: &Path, text: &str) -> Result<Vec<CameraKey>> {
    let mut out: Vec<CameraKey> = Vec::new();
    let mut seen = std::collections::HashMap::new();
    let mut first = true;
    for (i, line) in crate::csv_lines::strip_bom(text).lines().enumerate() {
        let line_no = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if std::mem::take(&mut first)
            && crate::csv_lines::is_header(line, CAMERA_PATH_COLUMNS, "a camera path")
                .map_err(|e| FoveaError::file(path, format!("line {line_no}: {e}")))?
        {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let bad = |what: String| {
            FoveaError::file(
                path,
                format!("line {line_no}: {what} (expected frame,eye_x,eye_y,eye_z,target_x,target_y,target_z)"),
            )
        };
        if fields.len() != 7 {
            return Err(bad(format!("{} fields in '{line}'", fields.len())));
        }
        let frame: u32 = fields[0]
            .parse()
            .map_err(|_| bad(format!("'{}' is not a frame number", fields[0])))?;
        let mut v = [0.0f64; 6];
        for (k, f) in fields[1..].iter().enumerate() {
            v[k] = f
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && x.abs() <= f64::from(f32::MAX))
                .ok_or_else(|| bad(format!("'{f}' is not a finite coordinate")))?;
        }
        let (eye, target) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
        if eye == target {
            return Err(bad("the eye and the target are the same point".into()));
        }
        if let Some(first) = seen.insert(frame, line_no) {
            return Err(FoveaError::file(
                path,
                format!(
                    "lines {first} and {line_no} both give frame {frame}; give each frame once"
                ),
            ));
        }
        out.push(CameraKey { frame, eye, target });
        if out.len() > MAX_PATH_FRAMES {
            return Err(FoveaError::file(
                path,
                format!("more than {MAX_PATH_FRAMES} frames"),
            ));
        }
    }
    if out.is_empty() {
        return Err(FoveaError::file(path, "the camera path has no frame lines"));
    }
    Ok(out)
}

/// Reads and parses a camera-path file.
pub fn read_camera_path(path: &Path) -> Result<Vec<CameraKey>> {
    let text = std::fs::read_to_string(path).map_err(|e| FoveaError::file(path, e))?;
    parse_camera_path(path, &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_paths_parse_and_name_bad_lines() {
        let p = Path::new("c.csv");
        let ok = parse_camera_path(
            p,
            "frame,ex,ey,ez,tx,ty,tz\n0,0,1,4,0,1,0\n1, 0.1,1,4, 0,1,0\n",
        )
        .unwrap();
        assert_eq!(ok.len(), 2);
        assert_eq!(ok[1].eye, [0.1, 1.0, 4.0]);
        // A byte-order mark before a data line keeps frame 0 (it was taken for a header).
        let bom = parse_camera_path(p, "\u{feff}0,0,1,4,0,1,0\n1,0,1,4,0,1,0\n").unwrap();
        assert_eq!(bom.len(), 2);
        assert_eq!(bom[0].frame, 0);
        for (text, needle) in [
            ("0,0,1,4,0,1\n", "6 fields"),
            ("0,0,1,4,0,1,x\n", "'x'"),
            ("0,0,1,4,0,1,inf\n", "'inf'"),
            ("0,1,1,1,1,1,1\n", "same point"),
            ("0,0,1,4,0,1,0\n0,0,1,4,0,1,0\n", "lines 1 and 2"),
            ("# nothing\n", "no frame lines"),
            ("frame,tx,ty,tz,ex,ey,ez\n0,0,1,4,0,1,0\n", "in that order"),
            (
                "time,a,b,c,d,e,f\n0,0,1,4,0,1,0\n",
                "line 1: 'time,a,b,c,d,e,f' is neither",
            ),
            ("0;0;1;4;0;1;0\n", "separated by semicolons"),
            (
                "0,0,1,4,0,1,0\nframe,ex,ey,ez,tx,ty,tz\n",
                "line 2: 'frame' is not a frame number",
            ),
        ] {
            let e = parse_camera_path(p, text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }
}
