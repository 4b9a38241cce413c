//! Gaze: samples from an eye tracker over UDP (`fovea view --gaze-source udp:PORT`), and gaze traces
//! (`--gaze-trace FILE`), the one reader that `fovea view` replays and `fovea render` renders frame by
//! frame.
//!
//! # UDP protocol
//!
//! One UDP datagram per sample, ASCII text `t,x,y`, at most 512 bytes, optionally ending in a
//! newline; spaces or tabs around the fields are allowed:
//!
//! ```text
//! 12.5,0.4,0.6
//! ```
//!
//! * `t` is the tracker's timestamp in seconds. It must be a finite number; it is used only for
//!   logging and latency figures, never for timing, so any clock (or `0`) will do.
//! * `x,y` is the gaze point, in one of two conventions (chosen on the command line):
//!   * [`GazeConvention::Normalized`] (the default, as Tobii reports gaze): `0..1` across the
//!     window, origin top-left, so `0.5,0.5` is the centre. Values beyond `-10..10` are rejected.
//!   * [`GazeConvention::PixelsBottomLeft`] (as Pupil Labs exports surface gaze): window pixels,
//!     origin bottom-left. Values beyond `±1e6` are rejected.
//!
//! A datagram may give both eyes' gaze, `t,lx,ly,rx,ry` (the left eye's, then the right's, in the
//! same convention); the view shows one image, so it fixates between them, and `fovea xr` fixates
//! each eye on its own.
//!
//! The viewer drains every pending datagram each frame and uses the newest valid one. A datagram
//! that is not valid UTF-8, is longer than 512 bytes, or does not match `t,x,y` is dropped, counted
//! and reported; it never stops the viewer.
//!
//! A bridge from any eye tracker is a few lines, e.g. in Python:
//!
//! ```text
//! import socket, time
//! PORT = 4242  # the port given to `fovea view --gaze-source udp:PORT`
//! sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
//!
//! def on_gaze(x, y):  # called by your tracker's SDK; x, y in 0..1, origin top-left
//!     sock.sendto(f"{time.time()},{x},{y}\n".encode(), ("127.0.0.1", PORT))
//! ```
//!
//! # Gaze trace files
//!
//! A gaze trace is a CSV file of samples `key,x,y`, one per line, keyed in one of two ways
//! ([`TraceTiming`]), told apart by the header:
//!
//! * `t,x,y` (timed): `t` is seconds (non-decreasing, not negative), counted from the first sample:
//!   a trace whose clock started long before (Unix-epoch timestamps, as many trackers export them)
//!   replays from its first sample;
//! * `frame,x,y` (per frame): `frame` is a frame number (increasing integers).
//!
//! A trace of both eyes names its columns `t,lx,ly,rx,ry` (or `frame,lx,ly,rx,ry`; `left_x, left_y,
//! right_x, right_y` also do): `render --stereo` gives each eye its own gaze, and a single view
//! fixates between them.
//!
//! Fields are separated by commas (another separator is named in the error). A first line whose first
//! field is not a number must be a header, `KEY,x,y`: `frame` makes the trace per frame, `t` (or
//! `time`, `seconds`, `timestamp`) timed; any other first line is an error naming it. Without a header
//! the command's default applies (`view`: timed, `render`: per frame). `x,y` are in the command's
//! [`GazeConvention`]. `#` starts a comment, blank lines are ignored, and a UTF-8 byte-order mark is
//! skipped. A trace holds at most [`MAX_TRACE_SAMPLES`] samples, and `render` makes at most as many
//! frames of it.
//!
//! ```text
//! t,x,y
//! # look from the centre to the top-left corner
//! 0.0,0.5,0.5
//! 0.5,0.1,0.1
//! ```
//!
//! `view` replays a timed trace in real time and a per-frame trace frame by frame; `render` renders a
//! per-frame trace's frames and a timed trace at `--trace-fps` frames per second.
use std::fmt::Write as _;
use std::net::{SocketAddr, UdpSocket};
use std::path::Path;
use std::time::Instant;

/// The longest UDP gaze datagram accepted, in bytes.
pub const MAX_DATAGRAM_BYTES: usize = 512;

/// The largest magnitude of a normalised gaze coordinate (`0..1` spans the window).
pub const MAX_NORMALIZED_COORDINATE: f64 = 10.0;

/// The largest magnitude of a gaze coordinate in pixels.
pub const MAX_PIXEL_COORDINATE: f64 = 1e6;

/// At most this many malformed-datagram messages are returned by one [`UdpGazeSource::poll`]
/// (all are counted in [`UdpGazeSource::malformed_count`]).
pub const MAX_MESSAGES_PER_POLL: usize = 16;

/// At most this many datagrams are drained by one [`UdpGazeSource::poll`], so that a flood of
/// datagrams cannot stall a frame; the rest wait for the next poll.
pub const MAX_DATAGRAMS_PER_POLL: usize = 4096;

/// The most samples a gaze trace may hold (and the most frames `render` makes of a timed one).
pub const MAX_TRACE_SAMPLES: usize = 1_000_000;

/// The longest datagram text quoted in an error message, in characters.
const MAX_QUOTED_CHARS: usize = 64;

/// How the gaze coordinates of a sample are expressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GazeConvention {
    /// `0..1` across the window, origin top-left (as Tobii reports gaze).
    #[default]
    Normalized,
    /// Window pixels, origin bottom-left (as Pupil Labs exports gaze).
    PixelsBottomLeft,
    /// Image pixels, origin top-left (`fovea render`'s traces and `--gaze`).
    PixelsTopLeft,
}

impl GazeConvention {
    /// An example `t,x,y` text in this convention, for error messages.
    fn example(self) -> &'static str {
        match self {
            GazeConvention::Normalized => "12.5,0.4,0.6",
            GazeConvention::PixelsBottomLeft | GazeConvention::PixelsTopLeft => "12.5,640,360",
        }
    }
}

/// One gaze sample, in window pixels with the origin at the top-left, whatever its source's
/// convention.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GazeSample {
    /// The tracker's timestamp in seconds (for a trace, seconds from the start of the replay).
    pub t: f64,
    /// Horizontal window pixel, `0` = left edge.
    pub x: f32,
    /// Vertical window pixel, `0` = top edge.
    pub y: f32,
    /// Each eye's gaze in window pixels, the left's then the right's, where the sample gives both
    /// (`x, y` is then between them): a headset fixates each eye on its own.
    pub eyes: Option<[[f32; 2]; 2]>,
}

/// Converts raw gaze coordinates in `convention` to window pixels with the origin top-left, for a
/// window of `window = [width, height]` pixels.
#[must_use]
pub fn to_window_pixels(
    convention: GazeConvention,
    raw_x: f32,
    raw_y: f32,
    window: [u32; 2],
) -> [f32; 2] {
    let width = window[0] as f32;
    let height = window[1] as f32;
    match convention {
        GazeConvention::Normalized => [raw_x * width, raw_y * height],
        GazeConvention::PixelsBottomLeft => [raw_x, height - raw_y],
        GazeConvention::PixelsTopLeft => [raw_x, raw_y],
    }
}

/// Parses one gaze datagram `t,x,y` in `convention` into a sample in window pixels (origin
/// top-left) for a window of `window = [width, height]` pixels.
///
/// # Errors
/// A message saying what is wrong with the text and showing the expected form.
pub fn parse_sample(
    text: &str,
    convention: GazeConvention,
    window: [u32; 2],
) -> Result<GazeSample, String> {
    let (t, [x, y], right) =
        parse_fields(text, convention, TraceTiming::Seconds, None).map_err(|problem| {
            format!(
                "malformed gaze datagram {}: {problem}",
                quote(text.trim_end())
            )
        })?;
    // Both eyes' gaze: the view shows one image, fixated between them.
    let eyes = right.map(|[rx, ry]| {
        [
            to_window_pixels(convention, x, y, window),
            to_window_pixels(convention, rx, ry, window),
        ]
    });
    let [x, y] = match right {
        Some([rx, ry]) => [0.5 * (x + rx), 0.5 * (y + ry)],
        None => [x, y],
    };
    let [x, y] = to_window_pixels(convention, x, y, window);
    Ok(GazeSample { t, x, y, eyes })
}

/// The columns of a trace: one gaze per line (`KEY,x,y`), or each eye's (`KEY,lx,ly,rx,ry`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GazeColumns {
    OneGaze,
    BothEyes,
}

/// The timing and columns a header line names (`t,x,y`, `frame,x,y`, `t,lx,ly,rx,ry`, ...; case and
/// spaces aside); the error says why the line is neither a header nor a sample.
fn parse_header(line: &str) -> Result<(TraceTiming, GazeColumns), String> {
    let fields: Vec<String> = line
        .split(',')
        .map(|f| f.trim().to_ascii_lowercase())
        .collect();
    let neither = || {
        format!(
            "{} is neither a header (\"t,x,y\", \"frame,x,y\", or \"t,lx,ly,rx,ry\" for both eyes) \
             nor a sample of numbers",
            quote(line)
        )
    };
    if fields.len() == 1 {
        if let Some(sep) = other_separator(line) {
            return Err(format!(
                "{}: the fields are separated by {sep}; gaze traces separate them by commas",
                quote(line)
            ));
        }
    }
    let named = |names: &[&str]| fields[1..].iter().zip(names).all(|(f, n)| f == n);
    let timing = |key: &str| TraceTiming::from_header(key).ok_or_else(neither);
    match fields.as_slice() {
        [key, _, _] if named(&["x", "y"]) => Ok((timing(key)?, GazeColumns::OneGaze)),
        [key, _, _, _, _]
            if named(&["lx", "ly", "rx", "ry"])
                || named(&["left_x", "left_y", "right_x", "right_y"]) =>
        {
            Ok((timing(key)?, GazeColumns::BothEyes))
        }
        [_, _, _] if fields.iter().any(|f| f == "x") && fields.iter().any(|f| f == "y") => {
            Err(format!(
                "header {}: the columns must be KEY,x,y in that order (t,x,y or frame,x,y)",
                quote(line)
            ))
        }
        [_, _, _, _, _] => Err(format!(
            "header {}: a trace of both eyes names its columns KEY,lx,ly,rx,ry in that order \
             (t,lx,ly,rx,ry or frame,lx,ly,rx,ry)",
            quote(line)
        )),
        _ => Err(neither()),
    }
}

/// The separator a line without commas uses instead, by name, where it splits the line into three
/// or five fields (`;`, tabs, spaces).
fn other_separator(line: &str) -> Option<&'static str> {
    crate::csv_lines::other_separator(line, &[3, 5])
}

/// A line's key (seconds or frame), its gaze (the left eye's of two) and the right eye's, raw.
type ParsedFields = (f64, [f32; 2], Option<[f32; 2]>);

/// Parses `t,x,y` (or `t,lx,ly,rx,ry`) into raw `(t, [x, y], right eye's [x, y])`; `columns` is the
/// trace's, or `None` for a datagram, which may give either. The error describes the problem
/// (without saying where).
fn parse_fields(
    text: &str,
    convention: GazeConvention,
    timing: TraceTiming,
    columns: Option<GazeColumns>,
) -> Result<ParsedFields, String> {
    let (key, example) = match timing {
        TraceTiming::Seconds => ("t", convention.example().to_string()),
        TraceTiming::Frames => ("frame", convention.example().replacen("12.5", "12", 1)),
    };
    let expected = match columns {
        Some(GazeColumns::BothEyes) => {
            format!("expected \"{key},lx,ly,rx,ry\" with five numbers, as the header says")
        }
        _ => format!("expected \"{key},x,y\" with three numbers (e.g. \"{example}\")"),
    };
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    let n = fields.len();
    let fits = match columns {
        None => n == 3 || n == 5,
        Some(GazeColumns::OneGaze) => n == 3,
        Some(GazeColumns::BothEyes) => n == 5,
    };
    if !fits {
        if let (1, Some(sep)) = (n, other_separator(text)) {
            return Err(format!(
                "the fields are separated by {sep}; {expected}, separated by commas"
            ));
        }
        let plural = if n == 1 { "" } else { "s" };
        if n == 5 && columns == Some(GazeColumns::OneGaze) {
            return Err(format!(
                "5 fields; {expected}, or for both eyes a first line \"{key},lx,ly,rx,ry\" naming \
                 the columns"
            ));
        }
        return Err(format!("{n} field{plural}; {expected}"));
    }
    let number = |name: &str, field: &str| -> Result<f64, String> {
        let value: f64 = field
            .parse()
            .map_err(|_| format!("{name} {} is not a number; {expected}", quote(field)))?;
        if value.is_finite() {
            Ok(value)
        } else {
            Err(format!(
                "{name} {} is not a finite number; {expected}",
                quote(field)
            ))
        }
    };
    let coordinate = |name: &str, field: &str| -> Result<f32, String> {
        let value = number(name, field)?;
        let (limit, what) = match convention {
            GazeConvention::Normalized => (
                MAX_NORMALIZED_COORDINATE,
                "for normalised gaze (0..1 spans the window)",
            ),
            GazeConvention::PixelsBottomLeft | GazeConvention::PixelsTopLeft => {
                (MAX_PIXEL_COORDINATE, "pixels")
            }
        };
        if value.abs() > limit {
            return Err(format!(
                "{name} {} is outside -{limit}..{limit} {what}",
                quote(field)
            ));
        }
        Ok(value as f32)
    };
    let t = number(key, fields[0])?;
    let left = [coordinate("x", fields[1])?, coordinate("y", fields[2])?];
    let right = if n == 5 {
        Some([coordinate("rx", fields[3])?, coordinate("ry", fields[4])?])
    } else {
        None
    };
    Ok((t, left, right))
}

/// `text` in double quotes with escapes, cut to [`MAX_QUOTED_CHARS`] characters.
fn quote(text: &str) -> String {
    let mut shown: String = text.chars().take(MAX_QUOTED_CHARS).collect();
    let cut = shown.len() < text.len();
    shown = format!("{shown:?}");
    if cut {
        shown.push_str("...");
    }
    shown
}

/// What one [`UdpGazeSource::poll`] found.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct GazePoll {
    /// The last valid sample in arrival order, with the instant it was drained; `None` if no valid
    /// datagram was pending.
    pub newest: Option<(GazeSample, Instant)>,
    /// One message per dropped datagram (malformed, not UTF-8, or too long), naming the sender, and
    /// one per receive error; at most [`MAX_MESSAGES_PER_POLL`].
    pub malformed: Vec<String>,
}

/// A non-blocking UDP socket that receives gaze datagrams (see the [module documentation](self)).
#[derive(Debug)]
pub struct UdpGazeSource {
    socket: UdpSocket,
    local_addr: SocketAddr,
    convention: GazeConvention,
    malformed_count: u64,
    buffer: Vec<u8>,
}

impl UdpGazeSource {
    /// Binds a non-blocking UDP socket on `addr` (port 0 picks a free port; see
    /// [`UdpGazeSource::local_addr`]).
    ///
    /// # Errors
    /// A message naming the port and address, and what to do, if the socket cannot be bound.
    pub fn bind(addr: SocketAddr, convention: GazeConvention) -> Result<Self, String> {
        let socket = UdpSocket::bind(addr).map_err(|error| {
            let port = addr.port();
            let ip = addr.ip();
            match error.kind() {
                std::io::ErrorKind::AddrInUse => format!(
                    "UDP port {port} on {ip} is in use by another program; \
                     choose another with --gaze-source udp:PORT"
                ),
                std::io::ErrorKind::PermissionDenied => format!(
                    "cannot listen for gaze on UDP port {port} on {ip}: permission denied \
                     (ports below 1024 need privileges); choose another with --gaze-source udp:PORT"
                ),
                std::io::ErrorKind::AddrNotAvailable => format!(
                    "cannot listen for gaze on UDP port {port} on {ip}: \
                     {ip} is not an address of this machine"
                ),
                _ => format!("cannot listen for gaze on UDP port {port} on {ip}: {error}"),
            }
        })?;
        socket.set_nonblocking(true).map_err(|error| {
            format!("cannot make the gaze socket on UDP {addr} non-blocking: {error}")
        })?;
        let local_addr = socket.local_addr().map_err(|error| {
            format!("cannot read the address of the gaze socket {addr}: {error}")
        })?;
        Ok(Self {
            socket,
            local_addr,
            convention,
            malformed_count: 0,
            // Larger than the limit, so that an over-long datagram is seen as such.
            buffer: vec![0; 4 * MAX_DATAGRAM_BYTES],
        })
    }

    /// The address the socket is bound to (with the actual port when bound to port 0).
    #[must_use]
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// The convention the datagrams' coordinates are read in.
    #[must_use]
    #[cfg(test)]
    pub fn convention(&self) -> GazeConvention {
        self.convention
    }

    /// Drains every pending datagram without blocking (at most [`MAX_DATAGRAMS_PER_POLL`]),
    /// converting valid samples to window pixels for a window of `window = [width, height]`.
    pub fn poll(&mut self, window: [u32; 2]) -> GazePoll {
        let mut result = GazePoll::default();
        let report = |result: &mut GazePoll, message: String| {
            if result.malformed.len() < MAX_MESSAGES_PER_POLL {
                result.malformed.push(message);
            }
        };
        for _ in 0..MAX_DATAGRAMS_PER_POLL {
            let (length, sender) = match self.socket.recv_from(&mut self.buffer) {
                Ok(received) => received,
                Err(error) => match error.kind() {
                    std::io::ErrorKind::WouldBlock => break,
                    // An interrupted call, or (on Windows) an ICMP "port unreachable" for an
                    // earlier send: neither says anything about pending datagrams.
                    std::io::ErrorKind::Interrupted | std::io::ErrorKind::ConnectionReset => {
                        continue
                    }
                    _ => {
                        report(
                            &mut result,
                            format!("receiving gaze on UDP {} failed: {error}", self.local_addr),
                        );
                        break;
                    }
                },
            };
            let drained = Instant::now();
            let outcome = if length > MAX_DATAGRAM_BYTES {
                Err(format!(
                    "gaze datagram is longer than {MAX_DATAGRAM_BYTES} bytes ({}{length} bytes); \
                     send one \"t,x,y\" sample per datagram",
                    if length >= self.buffer.len() {
                        "at least "
                    } else {
                        ""
                    }
                ))
            } else {
                match std::str::from_utf8(&self.buffer[..length]) {
                    Ok(text) => parse_sample(text, self.convention, window),
                    Err(_) => Err(format!(
                        "gaze datagram is not UTF-8 text; send ASCII \"t,x,y\" (e.g. \"{}\")",
                        self.convention.example()
                    )),
                }
            };
            match outcome {
                Ok(sample) => result.newest = Some((sample, drained)),
                Err(message) => {
                    self.malformed_count += 1;
                    let mut message = message;
                    let _ = write!(message, " (from {sender})");
                    report(&mut result, message);
                }
            }
        }
        result
    }

    /// How many datagrams have been dropped as malformed since the socket was bound.
    #[must_use]
    pub fn malformed_count(&self) -> u64 {
        self.malformed_count
    }
}

/// One raw trace sample: seconds from the start of the replay and coordinates in the trace's
/// convention.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RawSample {
    t: f64,
    x: f32,
    y: f32,
    /// The right eye's gaze in a trace of both eyes (`x, y` is then the left eye's).
    right: Option<[f32; 2]>,
}

impl RawSample {
    /// The gaze between the eyes (the only one of a one-gaze trace).
    fn between(&self) -> [f32; 2] {
        match self.right {
            Some([rx, ry]) => [0.5 * (self.x + rx), 0.5 * (self.y + ry)],
            None => [self.x, self.y],
        }
    }

    /// Each eye's gaze: the left's and the right's (one gaze for both where the trace gives one).
    fn eyes(&self) -> [[f32; 2]; 2] {
        [[self.x, self.y], self.right.unwrap_or([self.x, self.y])]
    }
}

/// How a trace's lines are keyed (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceTiming {
    /// `t,x,y`: seconds from the start of the replay.
    Seconds,
    /// `frame,x,y`: frame numbers.
    Frames,
}

impl TraceTiming {
    /// The timing a header's first field names, if any.
    fn from_header(field: &str) -> Option<Self> {
        match field.to_ascii_lowercase().as_str() {
            "frame" => Some(Self::Frames),
            "t" | "time" | "seconds" | "timestamp" => Some(Self::Seconds),
            _ => None,
        }
    }
}

/// The frames of a timed trace spanning `span` seconds at `fps` whose clock started at `start`: one
/// at 0 and one every `1 / fps` up to the span, a frame that falls on the last sample included up to
/// the rounding of the timestamps (which grows with `start`: Unix-epoch seconds keep about 0.2 µs).
#[must_use]
fn timed_frame_count(span: f64, fps: f64, start: f64) -> u64 {
    let rounding = ((start.abs() + span) * 8.0 * f64::EPSILON * fps + 1.0e-9).min(0.5);
    ((span * fps + rounding).floor() as u64).saturating_add(1)
}

/// The frames `render` and `report` make of a `--gaze-trace`, and one line saying what may surprise
/// about them (a timed trace whose clock does not start at 0, a per-frame trace that skips frame
/// numbers).
#[derive(Clone, Debug, PartialEq)]
pub struct TraceFrames {
    /// Frame numbers and the gaze in pixels of the image (between the eyes for a trace of both).
    pub frames: Vec<(u32, [f32; 2])>,
    /// For a trace of both eyes, each frame's left and right gaze, in the order of `frames`.
    pub eyes: Option<Vec<[[f32; 2]; 2]>>,
    pub note: Option<String>,
}

/// `--gaze-trace FILE` for `render` and `report`: its frames and their gaze in pixels of an `image`
/// (a per-frame trace's lines, or a timed trace sampled at `fps` from its first sample), with
/// `--gaze-normalized` read as 0..1 of the image. The errors name the option; a timed trace that
/// would make more than [`MAX_TRACE_SAMPLES`] frames is refused with its span.
pub fn read_trace_frames(
    path: &std::path::Path,
    fps: f64,
    normalized: bool,
    image: [u32; 2],
) -> crate::error::Result<TraceFrames> {
    use crate::error::FoveaError;
    if !(fps > 0.0 && fps <= 10_000.0) {
        return Err(FoveaError::option(
            "--trace-fps",
            format!("{fps} is not in (0, 10000] frames per second"),
        ));
    }
    let convention = if normalized {
        GazeConvention::Normalized
    } else {
        GazeConvention::PixelsTopLeft
    };
    let trace = GazeTrace::read(path, convention, TraceTiming::Frames)
        .map_err(|e| FoveaError::option("--gaze-trace", e))?;
    let shown = path.display();
    let note = match trace.timing {
        TraceTiming::Seconds => {
            let span = trace.samples.last().map_or(0.0, |s| s.t);
            let count = timed_frame_count(span, fps, trace.start) as f64;
            if count > MAX_TRACE_SAMPLES as f64 {
                return Err(FoveaError::option(
                    "--gaze-trace",
                    format!(
                        "'{shown}' spans {span} s (timestamps {} to {}): at --trace-fps {fps} that \
                         is {count} frames, more than {MAX_TRACE_SAMPLES}; lower --trace-fps or cut \
                         the trace",
                        trace.start,
                        trace.start + span
                    ),
                ));
            }
            (trace.start != 0.0).then(|| {
                format!(
                    "gaze trace '{shown}': its timestamps start at {} s; its {count} frames at {fps} \
                     fps are timed from its first sample",
                    trace.start
                )
            })
        }
        TraceTiming::Frames => {
            let first = trace.samples.first().map_or(0.0, |s| s.t);
            let last = trace.samples.last().map_or(0.0, |s| s.t);
            let skipped = (last - first + 1.0) as u64 - trace.samples.len() as u64;
            (skipped > 0).then(|| {
                format!(
                    "gaze trace '{shown}': {} frames from {first} to {last}, skipping {skipped} \
                     frame number(s); only the frames it gives are rendered",
                    trace.samples.len()
                )
            })
        }
    };
    let eyes = trace.has_both_eyes().then(|| {
        trace
            .eye_frames(fps, image)
            .into_iter()
            .map(|(_, eyes)| eyes)
            .collect()
    });
    Ok(TraceFrames {
        frames: trace.frames(fps, image),
        eyes,
        note,
    })
}

/// A recorded gaze trace (`--gaze-trace FILE`; see the [module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct GazeTrace {
    /// Sorted by `t` (seconds from the first sample, or frame numbers for [`TraceTiming::Frames`]).
    samples: Vec<RawSample>,
    convention: GazeConvention,
    timing: TraceTiming,
    columns: GazeColumns,
    /// A timed trace's first timestamp as the file gives it (its samples are kept from it); 0 for a
    /// per-frame trace.
    start: f64,
}

impl GazeTrace {
    /// Parses trace text; `path_for_messages` names the file in error messages; `timing` applies
    /// where no header names one. Coordinates are kept raw and converted to window pixels by
    /// [`GazeTrace::sample_at`].
    ///
    /// # Errors
    /// A message naming the file and line and saying what is wrong (a malformed line, a decreasing
    /// or negative timestamp, a frame number that is not an increasing integer), or that the trace
    /// has no samples.
    pub fn parse(
        path_for_messages: &str,
        text: &str,
        convention: GazeConvention,
        timing: TraceTiming,
    ) -> Result<Self, String> {
        let mut timing = timing;
        let mut columns = GazeColumns::OneGaze;
        let mut samples: Vec<RawSample> = Vec::new();
        // Frame number -> the line that gave it (a per-frame trace): two lines for one frame would
        // render it twice.
        let mut frame_lines = std::collections::HashMap::new();
        let mut previous_line = 0;
        let mut seen_content = false;
        // A UTF-8 byte-order mark (spreadsheet exports write one) is not part of the first field.
        let text = crate::csv_lines::strip_bom(text);
        for (index, raw) in text.lines().enumerate() {
            let line = index + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let first_content = !seen_content;
            seen_content = true;
            let at = |problem: String| {
                format!("gaze trace '{path_for_messages}' line {line}: {problem}")
            };
            let first_field = content.split(',').next().unwrap_or("").trim();
            if first_content && first_field.parse::<f64>().is_err() {
                // A header: `t,x,y` or `frame,x,y` (their names, in that order).
                (timing, columns) = parse_header(content).map_err(at)?;
                continue;
            }
            let (t, [x, y], right) =
                parse_fields(content, convention, timing, Some(columns)).map_err(at)?;
            match timing {
                TraceTiming::Seconds => {
                    if t < 0.0 {
                        return Err(at(format!(
                            "timestamp {t} is negative; trace timestamps are seconds from the start of the replay"
                        )));
                    }
                    if let Some(last) = samples.last() {
                        if t < last.t {
                            return Err(at(format!(
                                "timestamp {t} is earlier than {} on line {previous_line}; \
                                 timestamps must not decrease",
                                last.t
                            )));
                        }
                    }
                }
                TraceTiming::Frames => {
                    if !(t >= 0.0 && t <= f64::from(u32::MAX) && t.fract() == 0.0) {
                        return Err(at(format!(
                            "frame {t} is not a frame number (0, 1, 2, ...)"
                        )));
                    }
                    if let Some(first) = frame_lines.insert(t as u32, line) {
                        return Err(at(format!(
                            "lines {first} and {line} both give frame {t}, whose image would be \
                             rendered twice; give each frame once"
                        )));
                    }
                    if let Some(last) = samples.last() {
                        if t < last.t {
                            return Err(at(format!(
                                "frame {t} comes after frame {} on line {previous_line}; frames must \
                                 increase",
                                last.t
                            )));
                        }
                    }
                }
            }
            if samples.len() >= MAX_TRACE_SAMPLES {
                return Err(at(format!("more than {MAX_TRACE_SAMPLES} samples")));
            }
            samples.push(RawSample { t, x, y, right });
            previous_line = line;
        }
        if samples.is_empty() {
            return Err(format!(
                "gaze trace '{path_for_messages}' has no samples; expected lines \"t,x,y\" \
                 (e.g. \"{}\"), t in seconds from the start of the replay, or \"frame,x,y\" \
                 after a header line \"frame,x,y\"",
                convention.example()
            ));
        }
        // A timed trace replays from its first sample, whatever clock its timestamps come from.
        let start = match timing {
            TraceTiming::Seconds => samples[0].t,
            TraceTiming::Frames => 0.0,
        };
        for s in &mut samples {
            s.t -= start;
        }
        Ok(Self {
            samples,
            convention,
            timing,
            columns,
            start,
        })
    }

    /// Reads and parses a trace file.
    ///
    /// # Errors
    /// A message naming the path and the OS error if the file cannot be read, or as
    /// [`GazeTrace::parse`].
    pub fn read(
        path: &Path,
        convention: GazeConvention,
        timing: TraceTiming,
    ) -> Result<Self, String> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|error| format!("gaze trace '{shown}': cannot read it: {error}"))?;
        Self::parse(&shown, &text, convention, timing)
    }

    /// How the trace is keyed.
    #[must_use]
    #[cfg(test)]
    pub fn timing(&self) -> TraceTiming {
        self.timing
    }

    /// The newest sample with `key <= at` (`None` before the first sample), converted to window
    /// pixels (origin top-left) for a window of `window = [width, height]`; for a trace of both eyes,
    /// the gaze between them. `at` is seconds for a timed trace, a frame number for a per-frame one
    /// ([`Self::sample_for`] picks).
    #[must_use]
    pub fn sample_at(&self, at: f64, window: [u32; 2]) -> Option<GazeSample> {
        let sample = self.raw_at(at)?;
        let [x, y] = sample.between();
        let [x, y] = to_window_pixels(self.convention, x, y, window);
        Some(GazeSample {
            t: sample.t,
            x,
            y,
            eyes: None,
        })
    }

    /// The newest raw sample with `key <= at`.
    fn raw_at(&self, at: f64) -> Option<&RawSample> {
        let count = self.samples.partition_point(|sample| sample.t <= at);
        self.samples.get(count.checked_sub(1)?)
    }

    /// The sample for the replay's `seconds` (a timed trace) or its `frame` (a per-frame trace).
    #[must_use]
    pub fn sample_for(&self, seconds: f64, frame: u64, window: [u32; 2]) -> Option<GazeSample> {
        match self.timing {
            TraceTiming::Seconds => self.sample_at(seconds, window),
            TraceTiming::Frames => self.sample_at(frame as f64, window),
        }
    }

    /// The frames `fovea render` renders from this trace, with their gaze in pixels of an `image`
    /// (between the eyes for a trace of both): a per-frame trace's lines, or a timed trace sampled at
    /// `fps` frames per second from 0 to its last timestamp.
    #[must_use]
    pub fn frames(&self, fps: f64, image: [u32; 2]) -> Vec<(u32, [f32; 2])> {
        self.frames_with(fps, |s| {
            let [x, y] = s.between();
            to_window_pixels(self.convention, x, y, image)
        })
    }

    /// [`Self::frames`] with each eye's gaze, the left's then the right's (the one gaze for both
    /// where the trace gives one).
    #[must_use]
    pub fn eye_frames(&self, fps: f64, image: [u32; 2]) -> Vec<(u32, [[f32; 2]; 2])> {
        self.frames_with(fps, |s| {
            s.eyes()
                .map(|[x, y]| to_window_pixels(self.convention, x, y, image))
        })
    }

    /// Whether the trace gives each eye's gaze.
    #[must_use]
    pub fn has_both_eyes(&self) -> bool {
        self.columns == GazeColumns::BothEyes
    }

    /// The frames of [`Self::frames`], each with `gaze` of its sample.
    fn frames_with<T>(&self, fps: f64, gaze: impl Fn(&RawSample) -> T) -> Vec<(u32, T)> {
        match self.timing {
            TraceTiming::Frames => self.samples.iter().map(|s| (s.t as u32, gaze(s))).collect(),
            TraceTiming::Seconds => {
                let last = self.samples.last().map_or(0.0, |s| s.t);
                let count =
                    timed_frame_count(last, fps, self.start).min(MAX_TRACE_SAMPLES as u64) as u32;
                (0..count)
                    .filter_map(|frame| {
                        let s = self.raw_at(f64::from(frame) / fps)?;
                        Some((frame, gaze(s)))
                    })
                    .collect()
            }
        }
    }

    /// The timestamp of the last sample: seconds from the start of the replay to its end.
    #[must_use]
    #[cfg(test)]
    pub fn duration(&self) -> f64 {
        self.samples.last().map_or(0.0, |sample| sample.t)
    }

    /// The number of samples.
    #[must_use]
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether there are no samples (never true for a parsed trace).
    #[must_use]
    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The convention the trace's coordinates are read in.
    #[must_use]
    #[cfg(test)]
    pub fn convention(&self) -> GazeConvention {
        self.convention
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::{IpAddr, Ipv4Addr};
    use std::time::Duration;

    const WINDOW: [u32; 2] = [800, 600];

    fn frames_of(text: &str, fps: f64) -> crate::error::Result<TraceFrames> {
        let dir = std::env::temp_dir().join(format!("fovea-gaze-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path = dir.join(format!("t{n}.csv"));
        std::fs::write(&path, text).unwrap();
        let out = read_trace_frames(&path, fps, true, [100, 100]);
        let _ = std::fs::remove_file(&path);
        out
    }

    #[test]
    fn epoch_timestamps_replay_from_the_first_sample_and_say_so() {
        // Unix-epoch seconds, as trackers export them: 3 frames at 10 fps, not 17e9.
        let t = frames_of(
            "t,x,y\n1700000000.0,0.5,0.5\n1700000000.1,0.2,0.2\n1700000000.2,0.1,0.1\n",
            10.0,
        )
        .unwrap();
        assert_eq!(t.frames.len(), 3, "{t:?}");
        assert_eq!(t.frames[0], (0, [50.0, 50.0]));
        assert!(t.note.unwrap().contains("start at 1700000000 s"));
        // One sample after 5 s: one frame, not none.
        let t = frames_of("t,x,y\n5.01,0.5,0.5\n", 30.0).unwrap();
        assert_eq!(t.frames.len(), 1);
        // From 0 to 1e9 s: refused with the span, not a million frames.
        let e = frames_of("t,x,y\n0,0.5,0.5\n1e9,0.5,0.5\n", 30.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("spans 1000000000 s") && e.contains("--trace-fps"),
            "{e}"
        );
        // A trace that starts at 0 says nothing.
        assert_eq!(
            frames_of("t,x,y\n0,0.5,0.5\n1,0.5,0.5\n", 2.0)
                .unwrap()
                .note,
            None
        );
    }

    #[test]
    fn a_per_frame_trace_that_skips_frames_says_so() {
        let t = frames_of("frame,x,y\n0,0.5,0.5\n1,0.5,0.5\n5,0.5,0.5\n", 30.0).unwrap();
        assert_eq!(t.frames.iter().map(|f| f.0).collect::<Vec<_>>(), [0, 1, 5]);
        assert!(t.note.unwrap().contains("skipping 3 frame number(s)"));
    }

    /// A property test of the trace, camera-path and views-file readers (run in CI, bounded: `FOVEA_FUZZ_CASES`,
    /// 3000 by default): random edits of valid files (bytes flipped, inserted, deleted, lines
    /// repeated, separators and numbers swapped for odd ones) parse or are refused with a message
    /// naming the file, never a panic; a trace that parses gives frames without a panic either.
    #[test]
    fn mutated_traces_camera_paths_and_views_files_are_refused_or_read_never_a_panic() {
        let cases: u64 = std::env::var("FOVEA_FUZZ_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(3000);
        let seeds = [
            "t,x,y\n0,0.5,0.5\n0.0083,0.51,0.49\n0.5,0.2,0.3\n2,0.7,0.6\n",
            "frame,x,y\n0,10,10\n1,12,9\n# a comment\n\n2,14,8\n",
            "frame,ex,ey,ez,tx,ty,tz\n0,0,1,3.9,0,1,0\n1,0.1,1,3.9,0,1,0\n",
            "frame,eye,x,y,z,qx,qy,qz,qw,l,r,u,d\n0,left,-0.03,1.6,0,0,0,0,1,-0.9,0.8,0.8,-0.9\n\
             0,right,0.03,1.6,0,0,0,0,1,-0.8,0.9,0.8,-0.9\n",
        ];
        let odd = [
            ",",
            ";",
            "\t",
            " ",
            "\n",
            "#",
            "-",
            "e",
            "1e9",
            "NaN",
            "inf",
            "-0",
            "\u{feff}",
            "1e308",
            "18446744073709551616",
            "0.000000001",
            "t",
            "frame",
        ];
        let mut rng = crate::content_hash::Fnv1a64::default();
        let mut next = |n: usize| {
            rng.write(b"x");
            (rng.finish() % n.max(1) as u64) as usize
        };
        let (mut parsed, mut refused) = (0u64, 0u64);
        for case in 0..cases {
            let seed = seeds[case as usize % seeds.len()];
            let mut text = seed.to_string();
            for _ in 0..1 + next(4) {
                let chars: Vec<char> = text.chars().collect();
                let at = next(chars.len() + 1);
                let (head, tail): (String, String) =
                    (chars[..at].iter().collect(), chars[at..].iter().collect());
                text = match next(5) {
                    0 => format!("{head}{}{tail}", odd[next(odd.len())]),
                    1 => format!(
                        "{head}{}",
                        tail.chars().skip(1 + next(3)).collect::<String>()
                    ),
                    2 => {
                        let line = text.lines().nth(next(5)).unwrap_or("").to_string();
                        format!("{text}\n{line}")
                    }
                    3 => format!(
                        "{head}{}{tail}",
                        char::from_u32(next(0x3000) as u32).unwrap_or('?')
                    ),
                    _ => head,
                };
            }
            let result = std::panic::catch_unwind(|| {
                if seed.starts_with("frame,ex") {
                    crate::camera_path::parse_camera_path(Path::new("p.csv"), &text)
                        .map(|k| k.len())
                        .map_err(|e| e.to_string())
                } else if seed.starts_with("frame,eye") {
                    crate::stereo::parse_eye_views(Path::new("p.csv"), &text)
                        .map(|v| v.len())
                        .map_err(|e| e.to_string())
                } else {
                    GazeTrace::parse(
                        "p.csv",
                        &text,
                        GazeConvention::Normalized,
                        TraceTiming::Frames,
                    )
                    .map(|t| t.frames(30.0, [64, 48]).len())
                }
            });
            match result {
                Err(_) => panic!("a panic on {text:?}"),
                Ok(Err(e)) => {
                    refused += 1;
                    assert!(e.contains("p.csv"), "{e}");
                }
                Ok(Ok(_)) => parsed += 1,
            }
        }
        assert!(
            parsed > 0 && refused > 0,
            "{parsed} parsed, {refused} refused"
        );
    }

    #[test]
    fn a_trace_of_both_eyes_is_told_apart_by_its_header() {
        // frames_of reads 0..1 of a 100 x 100 image.
        let t = frames_of(
            "frame,lx,ly,rx,ry\n0,0.25,0.5,0.75,0.5\n1,0.5,0.125,0.75,0.375\n",
            30.0,
        )
        .unwrap();
        assert_eq!(
            t.frames,
            [(0, [50.0, 50.0]), (1, [62.5, 25.0])],
            "between the eyes"
        );
        let eyes = t.eyes.expect("both eyes");
        assert_eq!(eyes[1], [[50.0, 12.5], [75.0, 37.5]]);
        // Timed, with the long names.
        let t = frames_of(
            "t,left_x,left_y,right_x,right_y\n0,0.125,0.125,0.25,0.125\n0.1,0.125,0.125,0.25,0.125\n",
            30.0,
        )
        .unwrap();
        assert_eq!(t.frames.len(), 4);
        assert_eq!(t.eyes.unwrap()[3], [[12.5, 12.5], [25.0, 12.5]]);
        // One gaze: no eyes.
        assert!(frames_of("frame,x,y\n0,0.5,0.5\n", 30.0)
            .unwrap()
            .eyes
            .is_none());
        for (text, needle) in [
            ("frame,x,y\n0,0.2,0.5,0.3,0.5\n", "lx,ly,rx,ry"),
            ("0,0.2,0.5,0.3,0.5\n", "lx,ly,rx,ry"),
            ("frame,lx,ly,rx,ry\n0,0.2,0.5\n", "five numbers"),
            (
                "frame,rx,ry,lx,ly\n0,0.2,0.5,0.3,0.5\n",
                "KEY,lx,ly,rx,ry in that order",
            ),
            ("frame,lx,ly,rx,ry\n0,0.2,0.5,0.3,nan\n", "rx"),
        ] {
            let e = frames_of(text, 30.0).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
        // A datagram of both eyes: the view fixates between them.
        let s = parse_sample(
            "1.5,0.2,0.4,0.4,0.6",
            GazeConvention::Normalized,
            [100, 100],
        )
        .unwrap();
        assert!(
            (s.x - 30.0).abs() < 1e-4 && (s.y - 50.0).abs() < 1e-4,
            "{s:?}"
        );
        // ... and keeps each eye's, for a headset's two views.
        let [l, r] = s.eyes.expect("both eyes");
        assert!(
            (l[0] - 20.0).abs() < 1e-4 && (l[1] - 40.0).abs() < 1e-4,
            "{l:?}"
        );
        assert!(
            (r[0] - 40.0).abs() < 1e-4 && (r[1] - 60.0).abs() < 1e-4,
            "{r:?}"
        );
        assert_eq!(
            parse_sample("1.5,0.2,0.4", GazeConvention::Normalized, [100, 100])
                .unwrap()
                .eyes,
            None
        );
    }

    #[test]
    fn headers_are_recognised_by_their_names_and_other_first_lines_are_named() {
        // A byte-order mark before the header.
        let t = frames_of("\u{feff}t,x,y\n0,0.5,0.5\n", 30.0).unwrap();
        assert_eq!(t.frames.len(), 1);
        // A byte-order mark before data: frame 0 is kept, not taken for a header.
        let t = frames_of("\u{feff}0,0.5,0.5\n1,0.6,0.5\n", 30.0).unwrap();
        assert_eq!(t.frames.len(), 2);
        for (text, needle) in [
            ("time_ms;gx;gy\n0;0.5;0.5\n", "semicolons"),
            ("hello world\n0,0.5,0.5\n", "neither a header"),
            ("x,y,t\n0.5,0.5,0\n", "KEY,x,y in that order"),
            ("t,x,y\n0 0.5 0.5\n", "separated by spaces"),
            ("t,x,y\n0;0.5;0.5\n", "separated by semicolons"),
            ("t,x,y\n0\t0.5\t0.5\n", "separated by tabs"),
        ] {
            let e = frames_of(text, 30.0).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
            assert!(e.contains("--gaze-trace"), "{e}");
        }
    }

    fn loopback() -> SocketAddr {
        SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 0)
    }

    #[test]
    fn conversion_to_window_pixels() {
        assert_eq!(
            to_window_pixels(GazeConvention::Normalized, 0.25, 0.5, WINDOW),
            [200.0, 300.0]
        );
        assert_eq!(
            to_window_pixels(GazeConvention::PixelsBottomLeft, 100.0, 150.0, WINDOW),
            [100.0, 450.0]
        );
        assert_eq!(GazeConvention::default(), GazeConvention::Normalized);
    }

    #[test]
    fn parses_sample_forms() {
        let expected = GazeSample {
            t: 12.5,
            x: 320.0,
            y: 360.0,
            eyes: None,
        };
        for text in [
            "12.5,0.4,0.6",
            "12.5,0.4,0.6\n",
            "12.5,0.4,0.6\r\n",
            " 12.5 , 0.4 ,\t0.6 \n",
        ] {
            assert_eq!(
                parse_sample(text, GazeConvention::Normalized, WINDOW),
                Ok(expected),
                "{text:?}"
            );
        }
        assert_eq!(
            parse_sample("1e3,100,150\n", GazeConvention::PixelsBottomLeft, WINDOW),
            Ok(GazeSample {
                t: 1000.0,
                x: 100.0,
                y: 450.0,
                eyes: None,
            })
        );
        // Slightly outside the window is fine.
        assert!(parse_sample("0,-0.5,1.5", GazeConvention::Normalized, WINDOW).is_ok());
        assert!(parse_sample("0,-10,10", GazeConvention::Normalized, WINDOW).is_ok());
        assert!(parse_sample("-3,-20,900", GazeConvention::PixelsBottomLeft, WINDOW).is_ok());
    }

    #[test]
    fn rejects_malformed_samples() {
        let message = parse_sample("abc", GazeConvention::Normalized, WINDOW).unwrap_err();
        assert_eq!(
            message,
            "malformed gaze datagram \"abc\": 1 field; expected \"t,x,y\" with three numbers \
             (e.g. \"12.5,0.4,0.6\")"
        );
        for (text, word) in [
            ("", "\"\""),
            ("1,2", "\"1,2\""),
            ("1,0.2,0.3,0.4", "\"1,0.2,0.3,0.4\""),
            ("1 0.2 0.3", "\"1 0.2 0.3\""),
            ("t,x,y", "\"t\""),
            ("1,left,0.3", "\"left\""),
            ("1,0.2,", "\"\""),
            ("NaN,0.2,0.3", "\"NaN\""),
            ("1,nan,0.3", "\"nan\""),
            ("1,0.2,inf", "\"inf\""),
            ("1,-inf,0.3", "\"-inf\""),
            ("1,10.5,0.3", "\"10.5\""),
            ("1,0.5,-11", "\"-11\""),
        ] {
            let message = parse_sample(text, GazeConvention::Normalized, WINDOW).unwrap_err();
            assert!(message.starts_with("malformed gaze datagram "), "{message}");
            assert!(message.contains(word), "{text:?}: {message}");
            if !message.contains("outside") {
                assert!(message.contains("expected \"t,x,y\""), "{message}");
            }
        }
        let message =
            parse_sample("1,2e6,3", GazeConvention::PixelsBottomLeft, WINDOW).unwrap_err();
        assert!(
            message.contains("\"2e6\"") && message.contains("pixels"),
            "{message}"
        );
        let message = parse_sample("1,x,3", GazeConvention::PixelsBottomLeft, WINDOW).unwrap_err();
        assert!(message.contains("12.5,640,360"), "{message}");
        // Long junk is quoted only in part.
        let junk = "x".repeat(1000);
        let message = parse_sample(&junk, GazeConvention::Normalized, WINDOW).unwrap_err();
        assert!(message.len() < 200, "{message}");
    }

    /// Polls until `done` or two seconds have passed, merging what each poll found.
    fn poll_until(source: &mut UdpGazeSource, done: impl Fn(&GazePoll, u64) -> bool) -> GazePoll {
        let deadline = Instant::now() + Duration::from_secs(2);
        let mut all = GazePoll::default();
        loop {
            let poll = source.poll(WINDOW);
            if poll.newest.is_some() {
                all.newest = poll.newest;
            }
            all.malformed.extend(poll.malformed);
            if done(&all, source.malformed_count()) || Instant::now() > deadline {
                return all;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn udp_round_trip() {
        let mut source = UdpGazeSource::bind(loopback(), GazeConvention::Normalized).unwrap();
        let target = source.local_addr();
        assert_eq!(target.ip(), IpAddr::V4(Ipv4Addr::LOCALHOST));
        assert_ne!(target.port(), 0);
        assert_eq!(source.convention(), GazeConvention::Normalized);

        // Nothing pending: returns at once with nothing.
        let empty = source.poll(WINDOW);
        assert_eq!(empty.newest, None);
        assert!(empty.malformed.is_empty());

        let sender = UdpSocket::bind(loopback()).unwrap();
        let before = Instant::now();
        for datagram in ["1.0,0.1,0.2\n", "garbage", " 2.0 , 0.5 , 0.25 \n"] {
            sender.send_to(datagram.as_bytes(), target).unwrap();
        }
        let found = poll_until(&mut source, |poll, malformed| {
            malformed == 1 && poll.newest.is_some_and(|(sample, _)| sample.t == 2.0)
        });
        let (sample, drained) = found.newest.unwrap();
        assert_eq!(
            sample,
            GazeSample {
                t: 2.0,
                x: 400.0,
                y: 150.0,
                eyes: None,
            }
        );
        assert!(drained >= before);
        assert_eq!(found.malformed.len(), 1, "{:?}", found.malformed);
        assert!(
            found.malformed[0].contains("\"garbage\""),
            "{:?}",
            found.malformed
        );
        assert!(
            found.malformed[0].contains(&sender.local_addr().unwrap().to_string()),
            "{:?}",
            found.malformed
        );
        assert_eq!(source.malformed_count(), 1);
        assert_eq!(source.poll(WINDOW), GazePoll::default());
    }

    #[test]
    fn udp_rejects_long_and_non_utf8_datagrams() {
        let mut source = UdpGazeSource::bind(loopback(), GazeConvention::PixelsBottomLeft).unwrap();
        let sender = UdpSocket::bind(loopback()).unwrap();
        let target = source.local_addr();
        let long = format!("1,2,3{}", " ".repeat(600));
        sender.send_to(long.as_bytes(), target).unwrap();
        sender.send_to(&[0xff, 0xfe, b',', b'1'], target).unwrap();
        sender.send_to(b"5,100,150", target).unwrap();
        let found = poll_until(&mut source, |poll, malformed| {
            malformed == 2 && poll.newest.is_some()
        });
        assert_eq!(source.malformed_count(), 2);
        assert!(
            found.malformed[0].contains("longer than 512 bytes"),
            "{found:?}"
        );
        assert!(found.malformed[1].contains("not UTF-8"), "{found:?}");
        assert_eq!(
            found.newest.map(|(sample, _)| sample),
            Some(GazeSample {
                t: 5.0,
                x: 100.0,
                y: 450.0,
                eyes: None,
            })
        );
    }

    #[test]
    fn udp_port_in_use() {
        let first = UdpGazeSource::bind(loopback(), GazeConvention::Normalized).unwrap();
        let taken = first.local_addr();
        let message = UdpGazeSource::bind(taken, GazeConvention::Normalized).unwrap_err();
        assert_eq!(
            message,
            format!(
                "UDP port {} on 127.0.0.1 is in use by another program; \
                 choose another with --gaze-source udp:PORT",
                taken.port()
            )
        );
    }

    #[test]
    fn trace_parses_and_looks_up() {
        let text =
            "t,x,y\n# start centred\n0.0,0.5,0.5\n\n0.5, 0.25, 0.75 # left\n0.5,0.1,0.1\n2,1,1\r\n";
        let trace = GazeTrace::parse(
            "f.csv",
            text,
            GazeConvention::Normalized,
            TraceTiming::Seconds,
        )
        .unwrap();
        assert_eq!(trace.len(), 4);
        assert!(!trace.is_empty());
        assert_eq!(trace.duration(), 2.0);
        assert_eq!(trace.sample_at(-0.1, WINDOW), None);
        assert_eq!(trace.sample_at(f64::NAN, WINDOW), None);
        let at = |seconds| trace.sample_at(seconds, WINDOW).unwrap();
        assert_eq!(
            at(0.0),
            GazeSample {
                t: 0.0,
                x: 400.0,
                y: 300.0,
                eyes: None,
            }
        );
        assert_eq!(at(0.49).t, 0.0);
        // Equal timestamps: the later line wins.
        assert_eq!(
            at(0.5),
            GazeSample {
                t: 0.5,
                x: 80.0,
                y: 60.0,
                eyes: None,
            }
        );
        assert_eq!(at(1.99).t, 0.5);
        assert_eq!(at(2.0).x, 800.0);
        assert_eq!(at(100.0).y, 600.0);

        // Without a header, in pixels with the origin bottom-left.
        let trace = GazeTrace::parse(
            "p.csv",
            "0,10,20\n1,30,40\n",
            GazeConvention::PixelsBottomLeft,
            TraceTiming::Seconds,
        )
        .unwrap();
        assert_eq!(
            trace.sample_at(1.0, WINDOW),
            Some(GazeSample {
                t: 1.0,
                x: 30.0,
                y: 560.0,
                eyes: None,
            })
        );
        assert_eq!(trace.convention(), GazeConvention::PixelsBottomLeft);
    }

    #[test]
    fn trace_errors_name_file_and_line() {
        let parse = |text: &str| {
            GazeTrace::parse(
                "f.csv",
                text,
                GazeConvention::Normalized,
                TraceTiming::Seconds,
            )
        };
        for (text, line, word) in [
            ("t,x,y\n0,0.5,0.5\n1,0.5\n", 3, "\"t,x,y\""),
            ("0,0.5,0.5\n1,0.5,0.5,9\n", 2, "\"t,x,y\""),
            ("0,0.5,0.5\nt,x,y\n", 2, "\"t\""),
            ("# c\n\n0,0.5,0.5\n1,up,0.5\n", 4, "\"up\""),
            ("0,0.5,NaN\n", 1, "\"NaN\""),
            ("inf,0.5,0.5\n", 1, "\"inf\""),
            ("0,0.5,0.5\n0,20,0.5\n", 2, "\"20\""),
            ("-1,0.5,0.5\n", 1, "negative"),
            (
                "0,0.5,0.5\n2,0.5,0.5\n\n1.5,0.5,0.5\n",
                4,
                "earlier than 2 on line 2",
            ),
        ] {
            let message = parse(text).unwrap_err();
            assert!(
                message.starts_with(&format!("gaze trace 'f.csv' line {line}: ")),
                "{text:?}: {message}"
            );
            assert!(message.contains(word), "{text:?}: {message}");
        }
        for text in ["", "t,x,y\n", "# nothing\n\n"] {
            let message = parse(text).unwrap_err();
            assert!(
                message.starts_with("gaze trace 'f.csv' has no samples"),
                "{message}"
            );
        }
    }

    #[test]
    fn trace_read_names_the_path() {
        let dir = std::env::temp_dir().join(format!("fovea-gaze-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("trace.csv");
        std::fs::write(&good, "t,x,y\n0,0.5,0.5\n3,0.5,0.5\n").unwrap();
        let trace =
            GazeTrace::read(&good, GazeConvention::Normalized, TraceTiming::Seconds).unwrap();
        assert_eq!(trace.duration(), 3.0);

        let bad = dir.join("bad.csv");
        std::fs::write(&bad, "0,0.5,0.5\n0,0.5\n").unwrap();
        let message =
            GazeTrace::read(&bad, GazeConvention::Normalized, TraceTiming::Seconds).unwrap_err();
        assert!(
            message.starts_with(&format!("gaze trace '{}' line 2: ", bad.display())),
            "{message}"
        );

        let missing = dir.join("missing.csv");
        let message = GazeTrace::read(&missing, GazeConvention::Normalized, TraceTiming::Seconds)
            .unwrap_err();
        assert!(
            message.starts_with(&format!(
                "gaze trace '{}': cannot read it: ",
                missing.display()
            )),
            "{message}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn per_frame_traces_are_told_apart_by_the_header() {
        let parse = |text: &str, timing| {
            GazeTrace::parse("f.csv", text, GazeConvention::PixelsTopLeft, timing)
        };
        // The header decides, whatever the command's default.
        let frames = parse(
            "frame,x,y\n0, 10, 20\n# c\n3,11.5,-3\n",
            TraceTiming::Seconds,
        )
        .unwrap();
        assert_eq!(frames.timing(), TraceTiming::Frames);
        assert_eq!(
            frames.frames(30.0, WINDOW),
            vec![(0, [10.0, 20.0]), (3, [11.5, -3.0])]
        );
        assert_eq!(frames.sample_for(100.0, 2, WINDOW).unwrap().x, 10.0);
        assert_eq!(frames.sample_for(0.0, 3, WINDOW).unwrap().x, 11.5);
        let timed = parse("t,x,y\n0,1,2\n0.1,3,4\n", TraceTiming::Frames).unwrap();
        assert_eq!(timed.timing(), TraceTiming::Seconds);
        assert_eq!(
            timed.frames(20.0, WINDOW),
            vec![(0, [1.0, 2.0]), (1, [1.0, 2.0]), (2, [3.0, 4.0])]
        );
        // Without a header, the default.
        assert_eq!(
            parse("0,1,2\n1,1,2\n", TraceTiming::Frames)
                .unwrap()
                .timing(),
            TraceTiming::Frames
        );
        for (text, needle) in [
            (
                "frame,x,y\n0,1,2\n1,1,2\n1,3,4\n",
                "lines 3 and 4 both give frame 1",
            ),
            ("frame,x,y\n1,1,2\n0,3,4\n", "comes after frame 1"),
            ("frame,x,y\n1.5,1,2\n", "not a frame number"),
            ("frame,x,y\n-1,1,2\n", "not a frame number"),
        ] {
            let e = parse(text, TraceTiming::Seconds).unwrap_err();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }
}
