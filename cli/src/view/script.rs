//! Scripted input for `fovea view --script FILE`: a text file of timed window events that drive the
//! viewer exactly as a person would, frame by frame, so a session can be replayed and tested.
//!
//! # Format
//!
//! ```text
//! # comments and blank lines are ignored; everything after '#' on a line is a comment
//! # FRAME EVENT [ARGS...]   -- the event is applied just before frame FRAME (0-based) is rendered
//! 0 gaze 0.25 0.5        # a gaze sample, normalised window coordinates, origin top-left (0..1; values outside allowed down to -10..10)
//! 0 mouse 320 200        # the pointer moves to window pixel (x, y), origin top-left
//! 2 press U              # a key pressed and released (one action)
//! 2 down W               # a key held down (fly movement) ...
//! 6 up W                 # ... and released
//! 3 button down          # the look button (right mouse button) pressed / `button up` released
//! 4 wheel 2              # mouse-wheel steps (float, may be negative)
//! 5 resize 800 600       # the window is resized to 800x600 (each 1..16384)
//! 6 minimize             # the window is minimised / `restore` restores it
//! 9 close                # the window is closed (the viewer exits 0)
//! ```
//!
//! Fields are separated by spaces or tabs. Event names and key names are case-insensitive. The key
//! names are `W`, `A`, `S`, `D`, `Q`, `E` (fly), `Shift` (fast), `U` (uniform toggle), `O` (region
//! overlay), `N` (denoiser), `C` (cycle sampling configuration), `Space` (pause), `P` (screenshot), `R` (reset),
//! `H` (hide/show the on-screen figures) and `Escape` (or `Esc`, quit).
//!
//! Lines need not be in frame order: events are sorted by frame, and events on the same frame keep
//! the order in which they appear in the file. An empty script (no events) is allowed.
use std::fmt;
use std::path::Path;

/// The largest window side, in pixels, that a `resize` event may ask for.
pub const MAX_WINDOW_SIDE: u32 = 16384;

/// The largest magnitude of a scripted gaze coordinate (normalised; `0..1` spans the window).
pub const MAX_GAZE_COORDINATE: f32 = 10.0;

/// The event names a script line may use, in the order error messages list them.
const EVENT_NAMES: &str =
    "gaze, mouse, press, down, up, button, wheel, resize, minimize, restore, close";

/// A key the viewer responds to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewKey {
    /// Fly forward.
    W,
    /// Fly left.
    A,
    /// Fly backward.
    S,
    /// Fly right.
    D,
    /// Fly down.
    Q,
    /// Fly up.
    E,
    /// Fly fast while held.
    Shift,
    /// Toggle uniform (non-foveated) sampling.
    U,
    /// Toggle the region overlay.
    O,
    /// Toggle the denoiser.
    N,
    /// Cycle the sampling configuration.
    C,
    /// Pause / resume.
    Space,
    /// Save a screenshot.
    P,
    /// Reset the camera and accumulation.
    R,
    /// Hide / show the on-screen figures.
    H,
    /// Quit the viewer.
    Escape,
}

impl ViewKey {
    /// Every key, in the order error messages list them.
    pub const ALL: [ViewKey; 16] = [
        ViewKey::W,
        ViewKey::A,
        ViewKey::S,
        ViewKey::D,
        ViewKey::Q,
        ViewKey::E,
        ViewKey::Shift,
        ViewKey::U,
        ViewKey::O,
        ViewKey::N,
        ViewKey::C,
        ViewKey::Space,
        ViewKey::P,
        ViewKey::R,
        ViewKey::H,
        ViewKey::Escape,
    ];

    /// The key with this name (case-insensitive; `Esc` is accepted for `Escape`), or `None`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<ViewKey> {
        if name.eq_ignore_ascii_case("esc") {
            return Some(ViewKey::Escape);
        }
        Self::ALL
            .into_iter()
            .find(|key| key.name().eq_ignore_ascii_case(name))
    }

    /// Whether the key moves the camera while held (W A S D Q E, Shift).
    #[must_use]
    pub fn is_movement(self) -> bool {
        matches!(
            self,
            Self::W | Self::A | Self::S | Self::D | Self::Q | Self::E | Self::Shift
        )
    }

    /// The key's canonical name, as accepted by [`ViewKey::from_name`].
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ViewKey::W => "W",
            ViewKey::A => "A",
            ViewKey::S => "S",
            ViewKey::D => "D",
            ViewKey::Q => "Q",
            ViewKey::E => "E",
            ViewKey::Shift => "Shift",
            ViewKey::U => "U",
            ViewKey::O => "O",
            ViewKey::N => "N",
            ViewKey::C => "C",
            ViewKey::Space => "Space",
            ViewKey::P => "P",
            ViewKey::R => "R",
            ViewKey::H => "H",
            ViewKey::Escape => "Escape",
        }
    }

    /// All key names joined with `", "`, for error messages.
    fn all_names() -> String {
        Self::ALL
            .iter()
            .map(|key| key.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl fmt::Display for ViewKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One scripted window event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScriptEvent {
    /// A gaze sample in normalised window coordinates, origin top-left (`0..1` spans the window).
    Gaze {
        /// Horizontal position, `0` = left edge, `1` = right edge.
        x: f32,
        /// Vertical position, `0` = top edge, `1` = bottom edge.
        y: f32,
    },
    /// The pointer moves to a window pixel, origin top-left.
    Mouse {
        /// Horizontal pixel position.
        x: f64,
        /// Vertical pixel position.
        y: f64,
    },
    /// A key pressed and released (one action).
    Press(ViewKey),
    /// A key pressed and held.
    Down(ViewKey),
    /// A held key released.
    Up(ViewKey),
    /// The look button (right mouse button) pressed (`down: true`) or released.
    Button {
        /// Whether the button is now held.
        down: bool,
    },
    /// Mouse-wheel steps (may be fractional or negative).
    Wheel(f32),
    /// The window is resized to `width` x `height` pixels (each `1..=16384`).
    Resize {
        /// New width in pixels.
        width: u32,
        /// New height in pixels.
        height: u32,
    },
    /// The window is minimised.
    Minimize,
    /// The window is restored after being minimised.
    Restore,
    /// The window is closed (the viewer exits with status 0).
    Close,
}

/// A [`ScriptEvent`] with the frame it applies before and the script line it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedEvent {
    /// The 0-based frame the event is applied just before.
    pub frame: u64,
    /// The 1-based script line the event was read from.
    pub line: usize,
    /// The event.
    pub event: ScriptEvent,
}

/// A script that does not parse, or a script file that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScriptError {
    path: Option<String>,
    line: Option<usize>,
    message: String,
}

impl ScriptError {
    fn at_line(line: usize, message: String) -> Self {
        Self {
            path: None,
            line: Some(line),
            message,
        }
    }

    /// The 1-based line the error is on, if it is about one line.
    #[must_use]
    #[cfg(test)]
    pub fn line(&self) -> Option<usize> {
        self.line
    }
}

impl fmt::Display for ScriptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("script")?;
        if let Some(path) = &self.path {
            write!(f, " '{path}'")?;
        }
        if let Some(line) = self.line {
            write!(f, " line {line}")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for ScriptError {}

/// A parsed script: its events sorted by frame, and how far playback has got.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Script {
    events: Vec<TimedEvent>,
    next: usize,
}

impl Script {
    /// Parses script text (see the [module documentation](self) for the format). Events are sorted
    /// by frame; events on the same frame keep their order in the text.
    ///
    /// # Errors
    /// A [`ScriptError`] naming the first bad line and what is wrong with it.
    pub fn parse(text: &str) -> Result<Script, ScriptError> {
        let mut events = Vec::new();
        for (index, raw) in text.lines().enumerate() {
            let line = index + 1;
            let content = raw.split('#').next().unwrap_or("");
            let words: Vec<&str> = content.split_whitespace().collect();
            if words.is_empty() {
                continue;
            }
            let (frame, event) =
                parse_line(&words).map_err(|message| ScriptError::at_line(line, message))?;
            events.push(TimedEvent { frame, line, event });
        }
        // `sort_by_key` is stable: same-frame events keep their order in the file.
        events.sort_by_key(|event| event.frame);
        Ok(Script { events, next: 0 })
    }

    /// Reads and parses a script file.
    ///
    /// # Errors
    /// A [`ScriptError`] naming the path and the OS error if the file cannot be read, or the path
    /// and the first bad line if it does not parse.
    pub fn read(path: &Path) -> Result<Script, ScriptError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| ScriptError {
            path: Some(shown.clone()),
            line: None,
            message: format!("cannot read it: {error}"),
        })?;
        Self::parse(&text).map_err(|error| ScriptError {
            path: Some(shown),
            ..error
        })
    }

    /// Returns, in order, every event not yet returned whose frame is `<= frame`, and marks them
    /// returned.
    pub fn due(&mut self, frame: u64) -> Vec<ScriptEvent> {
        let start = self.next.min(self.events.len());
        let count = self.events[start..]
            .iter()
            .take_while(|event| event.frame <= frame)
            .count();
        self.next = start + count;
        self.events[start..self.next]
            .iter()
            .map(|event| event.event)
            .collect()
    }

    /// Whether every event has been returned by [`Script::due`] (true at once for an empty script).
    #[must_use]
    pub fn is_finished(&self) -> bool {
        self.next >= self.events.len()
    }

    /// The frame of the last event, or `None` for an empty script.
    #[must_use]
    #[cfg(test)]
    pub fn last_frame(&self) -> Option<u64> {
        self.events.last().map(|event| event.frame)
    }

    /// All events, sorted by frame (including those already returned by [`Script::due`]).
    #[must_use]
    #[cfg(test)]
    pub fn events(&self) -> &[TimedEvent] {
        &self.events
    }
}

/// Parses the words of one non-empty line into its frame and event.
fn parse_line(words: &[&str]) -> Result<(u64, ScriptEvent), String> {
    let frame = parse_frame(words[0])?;
    let Some(&name) = words.get(1) else {
        return Err(format!(
            "frame {frame} has no event; expected FRAME EVENT [ARGS...] (events: {EVENT_NAMES})"
        ));
    };
    let args = &words[2..];
    let lower = name.to_ascii_lowercase();
    let event = match lower.as_str() {
        "gaze" => {
            expect_args(name, args, &["X", "Y"])?;
            ScriptEvent::Gaze {
                x: parse_gaze(name, "x", args[0])?,
                y: parse_gaze(name, "y", args[1])?,
            }
        }
        "mouse" => {
            expect_args(name, args, &["X", "Y"])?;
            ScriptEvent::Mouse {
                x: parse_mouse(name, "x", args[0])?,
                y: parse_mouse(name, "y", args[1])?,
            }
        }
        "press" => {
            expect_args(name, args, &["KEY"])?;
            ScriptEvent::Press(parse_key(args[0])?)
        }
        "down" => {
            expect_args(name, args, &["KEY"])?;
            ScriptEvent::Down(parse_key(args[0])?)
        }
        "up" => {
            expect_args(name, args, &["KEY"])?;
            ScriptEvent::Up(parse_key(args[0])?)
        }
        "button" => {
            expect_args(name, args, &["down|up"])?;
            let down = if args[0].eq_ignore_ascii_case("down") {
                true
            } else if args[0].eq_ignore_ascii_case("up") {
                false
            } else {
                return Err(format!(
                    "button state '{}' is neither 'down' nor 'up' (write `button down` or `button up`)",
                    args[0]
                ));
            };
            ScriptEvent::Button { down }
        }
        "wheel" => {
            expect_args(name, args, &["STEPS"])?;
            // Any finite f64 is finite as f32 only below f32::MAX; check after narrowing.
            let steps = parse_float(name, "steps", args[0])? as f32;
            if !steps.is_finite() {
                return Err(format!(
                    "wheel steps '{}' is too large; use a small number of steps such as 1 or -2",
                    args[0]
                ));
            }
            ScriptEvent::Wheel(steps)
        }
        "resize" => {
            expect_args(name, args, &["WIDTH", "HEIGHT"])?;
            ScriptEvent::Resize {
                width: parse_side("width", args[0])?,
                height: parse_side("height", args[1])?,
            }
        }
        "minimize" => {
            expect_args(name, args, &[])?;
            ScriptEvent::Minimize
        }
        "restore" => {
            expect_args(name, args, &[])?;
            ScriptEvent::Restore
        }
        "close" => {
            expect_args(name, args, &[])?;
            ScriptEvent::Close
        }
        _ => return Err(format!("unknown event '{name}' (events: {EVENT_NAMES})")),
    };
    Ok((frame, event))
}

fn parse_frame(word: &str) -> Result<u64, String> {
    if let Ok(frame) = word.parse::<u64>() {
        return Ok(frame);
    }
    if word
        .strip_prefix('-')
        .is_some_and(|rest| rest.parse::<u64>().is_ok())
    {
        return Err(format!(
            "frame '{word}' is negative; frames count from 0 (the first frame rendered)"
        ));
    }
    Err(format!(
        "frame '{word}' is not a whole number; each line is FRAME EVENT [ARGS...], e.g. `0 press U`"
    ))
}

fn expect_args(event: &str, args: &[&str], expected: &[&str]) -> Result<(), String> {
    if args.len() == expected.len() {
        return Ok(());
    }
    let usage = std::iter::once(event.to_ascii_lowercase())
        .chain(expected.iter().map(|word| (*word).to_string()))
        .collect::<Vec<_>>()
        .join(" ");
    let takes = match expected.len() {
        0 => "no arguments".to_string(),
        1 => "1 argument".to_string(),
        n => format!("{n} arguments"),
    };
    let found = if args.is_empty() {
        "none".to_string()
    } else {
        format!("{} ('{}')", args.len(), args.join(" "))
    };
    Err(format!(
        "event '{event}' takes {takes} (`FRAME {usage}`), found {found}"
    ))
}

fn parse_float(event: &str, field: &str, word: &str) -> Result<f64, String> {
    let value: f64 = word
        .parse()
        .map_err(|_| format!("{event} {field} '{word}' is not a number"))?;
    if !value.is_finite() {
        return Err(format!(
            "{event} {field} '{word}' is not a finite number; write an ordinary decimal such as 0.5"
        ));
    }
    Ok(value)
}

fn parse_gaze(event: &str, field: &str, word: &str) -> Result<f32, String> {
    let value = parse_float(event, field, word)?;
    if value.abs() > f64::from(MAX_GAZE_COORDINATE) {
        return Err(format!(
            "{event} {field} '{word}' is outside -{MAX_GAZE_COORDINATE}..{MAX_GAZE_COORDINATE} \
             (gaze is normalised: 0..1 spans the window)"
        ));
    }
    Ok(value as f32)
}

/// A scripted pointer position in window pixels, bounded as every gaze in pixels is
/// ([`crate::values::MAX_GAZE_OFFSET`] off the window at most).
fn parse_mouse(event: &str, field: &str, word: &str) -> Result<f64, String> {
    let value = parse_float(event, field, word)?;
    let limit = f64::from(crate::values::MAX_GAZE_OFFSET);
    if value.abs() > limit {
        return Err(format!(
            "{event} {field} '{word}' is outside -{limit}..{limit} window pixels"
        ));
    }
    Ok(value)
}

fn parse_key(word: &str) -> Result<ViewKey, String> {
    ViewKey::from_name(word)
        .ok_or_else(|| format!("unknown key '{word}' (keys: {})", ViewKey::all_names()))
}

fn parse_side(field: &str, word: &str) -> Result<u32, String> {
    let out_of_range = || {
        format!("resize {field} '{word}' is out of range; it must be 1..{MAX_WINDOW_SIDE} pixels")
    };
    match word.parse::<u64>() {
        Ok(value) if (1..=u64::from(MAX_WINDOW_SIDE)).contains(&value) => {
            u32::try_from(value).map_err(|_| out_of_range())
        }
        Ok(_) => Err(out_of_range()),
        Err(_)
            if word
                .strip_prefix('-')
                .is_some_and(|rest| rest.parse::<u64>().is_ok()) =>
        {
            Err(out_of_range())
        }
        Err(_) => Err(format!(
            "resize {field} '{word}' is not a whole number of pixels (1..{MAX_WINDOW_SIDE})"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        Script::parse(text).unwrap_err().to_string()
    }

    #[test]
    fn every_event_parses() {
        let text = "\
0 gaze 0.25 0.5
0 mouse 320 200.5
2 press U
2 down W
6 up W
3 button down
3 button up
4 wheel -2.5
5 resize 800 600
6 minimize
7 restore
9 close
";
        let script = Script::parse(text).unwrap();
        let events: Vec<_> = script.events().iter().map(|e| e.event).collect();
        assert_eq!(
            events,
            vec![
                ScriptEvent::Gaze { x: 0.25, y: 0.5 },
                ScriptEvent::Mouse { x: 320.0, y: 200.5 },
                ScriptEvent::Press(ViewKey::U),
                ScriptEvent::Down(ViewKey::W),
                ScriptEvent::Button { down: true },
                ScriptEvent::Button { down: false },
                ScriptEvent::Wheel(-2.5),
                ScriptEvent::Resize {
                    width: 800,
                    height: 600
                },
                ScriptEvent::Up(ViewKey::W),
                ScriptEvent::Minimize,
                ScriptEvent::Restore,
                ScriptEvent::Close,
            ]
        );
        assert_eq!(script.last_frame(), Some(9));
    }

    #[test]
    fn module_doc_example_parses() {
        let text = "\
# comments and blank lines are ignored; everything after '#' on a line is a comment
# FRAME EVENT [ARGS...]   -- the event is applied just before frame FRAME (0-based) is rendered
0 gaze 0.25 0.5        # a gaze sample, normalised window coordinates, origin top-left (0..1; values outside allowed down to -10..10)
0 mouse 320 200        # the pointer moves to window pixel (x, y), origin top-left
2 press U              # a key pressed and released (one action)
2 down W               # a key held down (fly movement) ...
6 up W                 # ... and released
3 button down          # the look button (right mouse button) pressed / `button up` released
4 wheel 2              # mouse-wheel steps (float, may be negative)
5 resize 800 600       # the window is resized to 800x600 (each 1..16384)
6 minimize             # the window is minimised / `restore` restores it
9 close                # the window is closed (the viewer exits 0)
";
        let script = Script::parse(text).unwrap();
        assert_eq!(script.events().len(), 10);
    }

    #[test]
    fn keys_round_trip_and_are_case_insensitive() {
        for key in ViewKey::ALL {
            assert_eq!(ViewKey::from_name(key.name()), Some(key));
            assert_eq!(
                ViewKey::from_name(&key.name().to_ascii_lowercase()),
                Some(key)
            );
            assert_eq!(
                ViewKey::from_name(&key.name().to_ascii_uppercase()),
                Some(key)
            );
        }
        assert_eq!(ViewKey::from_name("Esc"), Some(ViewKey::Escape));
        assert_eq!(ViewKey::from_name("ESC"), Some(ViewKey::Escape));
        assert_eq!(ViewKey::from_name("X"), None);
        assert_eq!(ViewKey::from_name(""), None);
    }

    #[test]
    fn comments_blank_lines_and_whitespace() {
        let text = "# header\n\n   \n\t1\tpress\tspace # pause\n2 PRESS esc#quit\r\n# 3 close\n";
        let script = Script::parse(text).unwrap();
        assert_eq!(
            script.events(),
            &[
                TimedEvent {
                    frame: 1,
                    line: 4,
                    event: ScriptEvent::Press(ViewKey::Space)
                },
                TimedEvent {
                    frame: 2,
                    line: 5,
                    event: ScriptEvent::Press(ViewKey::Escape)
                },
            ]
        );
    }

    #[test]
    fn empty_script_is_allowed() {
        let mut script = Script::parse("# nothing\n\n").unwrap();
        assert!(script.is_finished());
        assert_eq!(script.last_frame(), None);
        assert!(script.due(100).is_empty());
        assert!(Script::parse("").unwrap().is_finished());
    }

    #[test]
    fn events_are_stably_sorted_by_frame() {
        let text = "5 press A\n1 press S\n5 press C\n0 press D\n1 press E\n";
        let script = Script::parse(text).unwrap();
        let order: Vec<_> = script.events().iter().map(|e| (e.frame, e.line)).collect();
        assert_eq!(order, vec![(0, 4), (1, 2), (1, 5), (5, 1), (5, 3)]);
    }

    #[test]
    fn due_returns_each_event_once_in_order() {
        let text = "0 press A\n2 press S\n2 press D\n5 close\n";
        let mut script = Script::parse(text).unwrap();
        assert!(!script.is_finished());
        assert_eq!(script.due(0), vec![ScriptEvent::Press(ViewKey::A)]);
        assert!(script.due(0).is_empty());
        assert!(script.due(1).is_empty());
        assert_eq!(
            script.due(3),
            vec![
                ScriptEvent::Press(ViewKey::S),
                ScriptEvent::Press(ViewKey::D)
            ]
        );
        assert!(!script.is_finished());
        // Skipping frames still delivers late events.
        assert_eq!(script.due(100), vec![ScriptEvent::Close]);
        assert!(script.is_finished());
        assert!(script.due(200).is_empty());
        // An earlier frame after a later one returns nothing new.
        assert!(script.due(0).is_empty());
        assert_eq!(script.last_frame(), Some(5));
    }

    #[test]
    fn unknown_event_lists_the_events() {
        let message = err("0 press U\n\n7 jump 3\n");
        assert!(message.starts_with("script line 3: "), "{message}");
        assert!(message.contains("'jump'"), "{message}");
        assert!(message.contains("gaze, mouse, press"), "{message}");
    }

    #[test]
    fn unknown_key_lists_the_keys() {
        let message = err("\n\n\n\n\n\n2 press X\n");
        assert!(message.starts_with("script line 7: "), "{message}");
        assert!(message.contains("unknown key 'X'"), "{message}");
        assert!(
            message.contains("W, A, S, D, Q, E, Shift, U, O, N, C, Space, P, R, H, Escape"),
            "{message}"
        );
        assert!(err("0 down Ctrl").contains("'Ctrl'"));
        assert!(err("0 up F1").contains("'F1'"));
    }

    #[test]
    fn wrong_argument_counts() {
        for (text, word) in [
            ("0 gaze 0.5", "'gaze'"),
            ("0 gaze 0.5 0.5 0.5", "'gaze'"),
            ("0 mouse 1", "'mouse'"),
            ("0 press", "'press'"),
            ("0 press U W", "'press'"),
            ("0 button", "'button'"),
            ("0 wheel", "'wheel'"),
            ("0 resize 800", "'resize'"),
            ("0 minimize now", "'minimize'"),
            ("0 restore 1", "'restore'"),
            ("0 close 1", "'close'"),
        ] {
            let message = err(text);
            assert!(message.starts_with("script line 1: "), "{message}");
            assert!(message.contains(word), "{message}");
            assert!(message.contains("takes"), "{message}");
        }
        let message = err("4");
        assert!(
            message.contains("line 1") && message.contains("no event"),
            "{message}"
        );
    }

    #[test]
    fn bad_numbers() {
        for (text, word) in [
            ("0 gaze abc 0.5", "'abc'"),
            ("0 gaze 0.5 NaN", "'NaN'"),
            ("0 gaze inf 0.5", "'inf'"),
            ("0 mouse 1 -inf", "'-inf'"),
            ("0 mouse x 1", "'x'"),
            ("0 mouse 1e300 1", "'1e300'"),
            ("0 mouse 5 -2000000", "'-2000000'"),
            ("0 wheel two", "'two'"),
            ("0 wheel nan", "'nan'"),
            ("0 wheel 1e300", "'1e300'"),
            ("0 resize 800.5 600", "'800.5'"),
            ("0 resize 800 tall", "'tall'"),
        ] {
            let message = err(&format!("\n{text}"));
            assert!(message.starts_with("script line 2: "), "{message}");
            assert!(message.contains(word), "{message}");
        }
    }

    #[test]
    fn bad_frames() {
        let message = err("-1 press U");
        assert!(
            message.contains("line 1") && message.contains("'-1'"),
            "{message}"
        );
        assert!(message.contains("negative"), "{message}");
        let message = err("0 press U\nfirst press U");
        assert!(
            message.contains("line 2") && message.contains("'first'"),
            "{message}"
        );
        let message = err("1.5 press U");
        assert!(message.contains("'1.5'"), "{message}");
    }

    #[test]
    fn resize_limits() {
        for (text, word) in [
            ("0 resize 0 600", "'0'"),
            ("0 resize 800 0", "'0'"),
            ("0 resize 16385 600", "'16385'"),
            (
                "0 resize 800 99999999999999999999",
                "'99999999999999999999'",
            ),
            ("0 resize -5 600", "'-5'"),
        ] {
            let message = err(text);
            assert!(message.contains("line 1"), "{message}");
            assert!(message.contains(word), "{message}");
            assert!(message.contains("1..16384"), "{message}");
        }
        let script = Script::parse("0 resize 1 16384").unwrap();
        assert_eq!(
            script.events()[0].event,
            ScriptEvent::Resize {
                width: 1,
                height: 16384
            }
        );
    }

    #[test]
    fn gaze_limits() {
        let script = Script::parse("0 gaze -10 10\n1 gaze 1.5 -0.25").unwrap();
        assert_eq!(
            script.events()[0].event,
            ScriptEvent::Gaze { x: -10.0, y: 10.0 }
        );
        for (text, word) in [("0 gaze 10.5 0", "'10.5'"), ("0 gaze 0 -11", "'-11'")] {
            let message = err(text);
            assert!(
                message.contains("line 1") && message.contains(word),
                "{message}"
            );
            assert!(message.contains("-10..10"), "{message}");
        }
    }

    #[test]
    fn bad_button_state() {
        let message = err("3 button left");
        assert!(
            message.contains("line 1") && message.contains("'left'"),
            "{message}"
        );
    }

    #[test]
    fn read_names_the_path() {
        let dir = std::env::temp_dir().join(format!("fovea-script-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.txt");
        std::fs::write(&good, "1 close\n").unwrap();
        let script = Script::read(&good).unwrap();
        assert_eq!(script.last_frame(), Some(1));

        let bad = dir.join("bad.txt");
        std::fs::write(&bad, "0 press U\n1 press X\n").unwrap();
        let message = Script::read(&bad).unwrap_err().to_string();
        assert!(
            message.starts_with(&format!("script '{}' line 2: ", bad.display())),
            "{message}"
        );
        assert!(message.contains("'X'"), "{message}");

        let missing = dir.join("missing.txt");
        let error = Script::read(&missing).unwrap_err();
        assert_eq!(error.line(), None);
        let message = error.to_string();
        assert!(
            message.starts_with(&format!("script '{}': cannot read it: ", missing.display())),
            "{message}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
