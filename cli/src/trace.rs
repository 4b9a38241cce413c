//! Gaze traces: CSV files with one `frame,x,y` line per frame (a header line and `#` comments are
//! allowed).
use std::path::Path;

use crate::error::{FoveaError, Result};

/// One line of a gaze trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GazeSample {
    pub frame: u32,
    pub gaze: [f32; 2],
}

/// The most frames a trace may hold.
pub const MAX_TRACE_FRAMES: usize = 1_000_000;

/// Parses a gaze trace; errors name the file and the line.
pub fn parse_gaze_trace(path: &Path, text: &str) -> Result<Vec<GazeSample>> {
    let mut out = Vec::new();
    // Frame number -> the line that gave it: two lines for one frame would write the same image twice.
    let mut seen = std::collections::HashMap::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if out.is_empty() && fields.first().is_some_and(|f| f.parse::<f64>().is_err()) && i == 0 {
            continue; // a header such as "frame,x,y"
        }
        let bad = |what: String| {
            FoveaError::file(path, format!("line {line_no}: {what} (expected frame,x,y)"))
        };
        if fields.len() != 3 {
            return Err(bad(format!("{} fields in '{line}'", fields.len())));
        }
        let frame: u32 = fields[0]
            .parse()
            .map_err(|_| bad(format!("'{}' is not a frame number", fields[0])))?;
        let x: f32 = fields[1]
            .parse()
            .map_err(|_| bad(format!("'{}' is not a number", fields[1])))?;
        let y: f32 = fields[2]
            .parse()
            .map_err(|_| bad(format!("'{}' is not a number", fields[2])))?;
        if !x.is_finite() || !y.is_finite() {
            return Err(bad(format!("non-finite gaze '{line}'")));
        }
        if let Some(first) = seen.insert(frame, line_no) {
            return Err(FoveaError::file(
                path,
                format!(
                    "lines {first} and {line_no} both give frame {frame}, whose image would be \
                     written twice; give each frame once"
                ),
            ));
        }
        out.push(GazeSample {
            frame,
            gaze: [x, y],
        });
        if out.len() > MAX_TRACE_FRAMES {
            return Err(FoveaError::file(
                path,
                format!("more than {MAX_TRACE_FRAMES} frames"),
            ));
        }
    }
    if out.is_empty() {
        return Err(FoveaError::file(path, "the gaze trace has no frame lines"));
    }
    Ok(out)
}

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
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if i == 0 && fields.first().is_some_and(|f| f.parse::<f64>().is_err()) {
            continue; // a header
        }
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
        if out.len() > MAX_TRACE_FRAMES {
            return Err(FoveaError::file(
                path,
                format!("more than {MAX_TRACE_FRAMES} frames"),
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

/// Reads and parses a gaze-trace file.
pub fn read_gaze_trace(path: &Path) -> Result<Vec<GazeSample>> {
    let text = std::fs::read_to_string(path).map_err(|e| FoveaError::file(path, e))?;
    parse_gaze_trace(path, &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lines_and_names_bad_ones() {
        let p = Path::new("t.csv");
        let ok = parse_gaze_trace(p, "frame,x,y\n0, 10, 20\n# c\n1,11.5,-3\n").unwrap();
        assert_eq!(ok.len(), 2);
        assert_eq!(
            ok[1],
            GazeSample {
                frame: 1,
                gaze: [11.5, -3.0]
            }
        );
        let err = parse_gaze_trace(p, "0,1,2\n1,abc,2\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 2") && err.contains("abc"), "{err}");
        let err = parse_gaze_trace(p, "0,1\n").unwrap_err().to_string();
        assert!(err.contains("line 1"), "{err}");
        assert!(parse_gaze_trace(p, "").is_err());
        assert!(parse_gaze_trace(p, "0,nan,1").is_err());
    }

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
        for (text, needle) in [
            ("0,0,1,4,0,1\n", "6 fields"),
            ("0,0,1,4,0,1,x\n", "'x'"),
            ("0,0,1,4,0,1,inf\n", "'inf'"),
            ("0,1,1,1,1,1,1\n", "same point"),
            ("0,0,1,4,0,1,0\n0,0,1,4,0,1,0\n", "lines 1 and 2"),
            ("# nothing\n", "no frame lines"),
        ] {
            let e = parse_camera_path(p, text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }

    #[test]
    fn a_frame_given_twice_is_refused_with_both_lines() {
        let e = parse_gaze_trace(Path::new("t.csv"), "frame,x,y\n0,1,2\n1,1,2\n0,3,4\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("lines 2 and 4") && e.contains("frame 0"), "{e}");
        assert_eq!(
            parse_gaze_trace(Path::new("t.csv"), "0,1,2\n1,1,2\n")
                .unwrap()
                .len(),
            2
        );
    }
}
