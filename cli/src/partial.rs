//! Parts of a render split by samples: `fovea render --samples A..B` writes one, `fovea merge` reads
//! them back.
//!
//! fovea's random numbers are keyed by (block, frame, sample, region, seed), so a part holding the
//! samples `A..B` of every block holds exactly the samples one render would have traced for them. A
//! part stores, for every pixel, the sum of its block's samples in the range and their count
//! (`fovea_cpu::render_sample_range`); merging adds the parts' sums and counts and runs the frame's
//! block fill on them (`fovea_cpu::fill_from_sample_sums`).
//!
//! A part file (`.fvpart`) is a text header, then the data:
//! ```text
//! fovea-partial 1
//! fovea 0.1.0 executable 9f3c…           ┐
//! scene-file fnv1a64 …                   │ the identity: every part of one render has the same
//! scene-content fnv1a64 …                │ lines, and `merge` names the first that differs
//! frame-params 0000803f…                 │ (the exact FrameParams: camera, foveation, integrator,
//! fill 0                                 │  size, frame, seed)
//! resolution 640x360 … largest-spp 32     ┘ (readable copies of what frame-params holds)
//! scene-path /data/lost_empire.obj        (for people; not compared)
//! samples 0..8
//! data-bytes 3686400
//! data fnv1a64 …
//! end
//! <data-bytes bytes: width·height·[r, g, b, count] as little-endian f32>
//! ```
//! A truncated or corrupt part fails its length or checksum and is refused by name.
use std::io::Write as _;
use std::path::{Path, PathBuf};

use fovea_core::integrator::FrameParams;

use crate::content_hash::fnv1a64;
use crate::error::{FoveaError, Result};
use crate::output::write_atomically;

/// The first line of every part file.
const MAGIC: &str = "fovea-partial 1";
/// The largest header fovea reads, in bytes (a real one is about 1 KiB).
const MAX_HEADER_BYTES: usize = 64 * 1024;

/// One part of a split render, as written or read.
#[derive(Clone, Debug)]
pub struct Part {
    /// The identity lines, in order: equal for every part of one render.
    pub identity: Vec<(String, String)>,
    /// The scene's path when the part was rendered (for messages only).
    pub scene_path: String,
    /// The frame (camera, foveation, size, frame number, seed), exactly.
    pub frame: FrameParams,
    /// The block fill the merged image is made with (`FILL_BILINEAR` or `FILL_REPLICATE`).
    pub fill_mode: u32,
    /// Sample indices `first..end` of every block (clipped to each block's own count).
    pub samples: [u32; 2],
    /// `[I, N]` for a part rendered as `--samples I/N` (part `I` of `N`, from 0).
    pub of: Option<[u32; 2]>,
    /// Per pixel: the sum of its block's samples in the range, and their count.
    pub sums: Vec<[f32; 4]>,
}

/// What identifies the render a part belongs to, besides its frame: hashes of the scene file and of
/// the packed scene, and of the executable that rendered it.
pub struct RenderIdentity {
    pub scene_file_hash: u64,
    pub scene_content_hash: u64,
    pub executable_hash: Option<u64>,
}

impl RenderIdentity {
    /// The identity of a render of `packed`, loaded from a scene file whose bytes are `scene_bytes`, by
    /// this executable.
    #[must_use]
    pub fn of(scene_bytes: &[u8], packed: &fovea_scene::pack::PackedScene) -> Self {
        Self {
            scene_file_hash: fnv1a64(scene_bytes),
            scene_content_hash: crate::content_hash::packed_scene_hash(packed),
            executable_hash: crate::content_hash::executable_hash(),
        }
    }
}

impl Part {
    /// A new part's header fields for `frame`; `sums` as `render_sample_range` wrote them.
    #[must_use]
    pub fn new(
        identity: &RenderIdentity,
        scene_path: &Path,
        frame: &FrameParams,
        fill_mode: u32,
        samples: [u32; 2],
        of: Option<[u32; 2]>,
        sums: Vec<[f32; 4]>,
    ) -> Self {
        Self {
            identity: identity_lines(identity, frame, fill_mode),
            scene_path: scene_path.display().to_string(),
            frame: *frame,
            fill_mode,
            samples,
            of,
            sums,
        }
    }

    /// The data bytes: every pixel's `[r, g, b, count]` as little-endian f32.
    fn data(&self) -> Vec<u8> {
        self.sums
            .iter()
            .flat_map(|p| p.iter().flat_map(|v| v.to_le_bytes()))
            .collect()
    }

    /// Writes the part to `path` (atomically: nothing is left behind on failure).
    pub fn write(&self, path: &Path) -> Result<()> {
        let data = self.data();
        let mut header = format!("{MAGIC}\n");
        for (k, v) in &self.identity {
            header += &format!("{k} {v}\n");
        }
        header += &format!("scene-path {}\n", self.scene_path.replace('\n', " "));
        if let Some([i, n]) = self.of {
            header += &format!("part {i}/{n}\n");
        }
        header += &format!(
            "samples {}..{}\ndata-bytes {}\ndata fnv1a64 {:016x}\nend\n",
            self.samples[0],
            self.samples[1],
            data.len(),
            fnv1a64(&data)
        );
        write_atomically(path, |tmp| {
            let mut file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
            file.write_all(header.as_bytes())
                .and_then(|()| file.write_all(&data))
                .and_then(|()| file.sync_all())
                .map_err(|e| e.to_string())
        })
    }

    /// Reads and checks a part file: its header, its length and its checksum.
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| FoveaError::file(path, e))?;
        let not_a_part = |why: &str| {
            FoveaError::file(
                path,
                format!("not a part of a fovea render ({why}); parts are written by `fovea render --samples A..B -o FILE.fvpart`"),
            )
        };
        if !bytes.starts_with(MAGIC.as_bytes()) {
            return Err(not_a_part(&format!("it does not start with '{MAGIC}'")));
        }
        let header_end = find(&bytes[..bytes.len().min(MAX_HEADER_BYTES)], b"\nend\n")
            .ok_or_else(|| not_a_part("its header has no 'end' line"))?
            + b"\nend\n".len();
        let header = std::str::from_utf8(&bytes[..header_end])
            .map_err(|_| not_a_part("its header is not text"))?;
        let data = &bytes[header_end..];
        let mut identity = Vec::new();
        let (mut scene_path, mut samples, mut data_bytes, mut checksum) = (None, None, None, None);
        let mut of = None;
        for line in header.lines().skip(1) {
            let (key, value) = line.split_once(' ').unwrap_or((line, ""));
            match key {
                "end" => break,
                "scene-path" => scene_path = Some(value.to_string()),
                "samples" => samples = parse_range(value),
                "part" => {
                    of = value
                        .split_once('/')
                        .and_then(|(i, n)| Some([i.parse().ok()?, n.parse().ok()?]))
                        .filter(|[i, n]: &[u32; 2]| i < n);
                    if of.is_none() {
                        return Err(not_a_part("its 'part' line is malformed"));
                    }
                }
                "data-bytes" => data_bytes = value.parse::<usize>().ok(),
                "data" => checksum = value.strip_prefix("fnv1a64 ").map(str::to_string),
                _ => identity.push((key.to_string(), value.to_string())),
            }
        }
        let field = |name: &str| not_a_part(&format!("its '{name}' line is missing or malformed"));
        let samples = samples.ok_or_else(|| field("samples"))?;
        let data_bytes = data_bytes.ok_or_else(|| field("data-bytes"))?;
        let checksum = checksum.ok_or_else(|| field("data"))?;
        let frame = identity
            .iter()
            .find(|(k, _)| k == "frame-params")
            .and_then(|(_, v)| parse_hex(v))
            .filter(|b| b.len() == std::mem::size_of::<FrameParams>())
            .map(|b| bytemuck::pod_read_unaligned::<FrameParams>(&b))
            .ok_or_else(|| field("frame-params"))?;
        let fill_mode = identity
            .iter()
            .find(|(k, _)| k == "fill")
            .and_then(|(_, v)| v.parse().ok())
            .ok_or_else(|| field("fill"))?;
        if samples[0] >= samples[1] || samples[1] > largest_spp(&frame) {
            return Err(field("samples"));
        }
        let pixels = u64::from(frame.width) * u64::from(frame.height);
        if data_bytes as u64 != pixels * 16 {
            return Err(not_a_part(&format!(
                "its data-bytes, {data_bytes}, do not fit a {}x{} image",
                frame.width, frame.height
            )));
        }
        if data.len() != data_bytes {
            return Err(FoveaError::file(
                path,
                format!(
                    "truncated or padded: {} data bytes where the header says {data_bytes}; render this part again",
                    data.len()
                ),
            ));
        }
        if format!("{:016x}", fnv1a64(data)) != checksum {
            return Err(FoveaError::file(
                path,
                "corrupt: its data does not match the checksum in its header; render this part again",
            ));
        }
        let sums = data
            .chunks_exact(16)
            .map(|p| {
                let v = |i: usize| f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
                [v(0), v(4), v(8), v(12)]
            })
            .collect();
        Ok(Self {
            identity,
            scene_path: scene_path.unwrap_or_default(),
            frame,
            fill_mode,
            samples,
            of,
            sums,
        })
    }
}

/// The identity lines of a part of `frame` (see the module's documentation): equal for every part of one
/// render.
#[must_use]
pub fn identity_lines(
    identity: &RenderIdentity,
    frame: &FrameParams,
    fill_mode: u32,
) -> Vec<(String, String)> {
    let f = &frame.foveation;
    let hex = |bytes: &[u8]| bytes.iter().map(|b| format!("{b:02x}")).collect::<String>();
    let executable = identity
        .executable_hash
        .map_or_else(|| "unknown".to_string(), |h| format!("{h:016x}"));
    let lines = [
        (
            "fovea",
            format!("{} executable {executable}", env!("CARGO_PKG_VERSION")),
        ),
        (
            "scene-file",
            format!("fnv1a64 {:016x}", identity.scene_file_hash),
        ),
        (
            "scene-content",
            format!("fnv1a64 {:016x}", identity.scene_content_hash),
        ),
        ("frame-params", hex(bytemuck::bytes_of(frame))),
        ("fill", fill_mode.to_string()),
        ("resolution", format!("{}x{}", frame.width, frame.height)),
        ("gaze", format!("{},{}", f.gaze[0], f.gaze[1])),
        ("spp", format!("{},{},{}", f.spp[0], f.spp[1], f.spp[2])),
        (
            "blocks",
            format!(
                "{},{},{}",
                f.block_size[0], f.block_size[1], f.block_size[2]
            ),
        ),
        ("frame", frame.frame_index.to_string()),
        ("seed", frame.seed.to_string()),
        ("largest-spp", largest_spp(frame).to_string()),
    ];
    lines.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

/// The most samples any block of `frame` takes: the parts of a split must tile `0..` this.
#[must_use]
pub fn largest_spp(frame: &FrameParams) -> u32 {
    frame.foveation.spp[..3].iter().copied().max().unwrap_or(0)
}

/// Where every part was rendered as `--samples I/N` with one `N`: the indices `I` whose ranges fall in
/// `gaps`, as `1, 3 of 4` (the job-array tasks to resubmit).
fn missing_parts(parts: &[(PathBuf, Part)], gaps: &[[u32; 2]], total: u32) -> Option<String> {
    let counts: Vec<u32> = parts
        .iter()
        .map(|(_, p)| p.of.map(|[_, n]| n))
        .collect::<Option<_>>()?;
    let n = counts[0];
    if counts.iter().any(|&c| c != n) {
        return None;
    }
    let at = |i: u32| (u64::from(i) * u64::from(total) / u64::from(n)) as u32;
    let missing: Vec<String> = (0..n)
        .filter(|&i| {
            let (a, b) = (at(i), at(i + 1));
            a < b && gaps.iter().any(|g| a < g[1] && g[0] < b)
        })
        .map(|i| i.to_string())
        .collect();
    Some(format!("{} of {n}", missing.join(", ")))
}

/// `A..B` as `[A, B]`.
fn parse_range(text: &str) -> Option<[u32; 2]> {
    let (a, b) = text.split_once("..")?;
    Some([a.trim().parse().ok()?, b.trim().parse().ok()?])
}

fn parse_hex(text: &str) -> Option<Vec<u8>> {
    if !text.len().is_multiple_of(2) {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

/// The parts of one render, checked to belong together and to tile its samples, in sample order.
pub struct CheckedParts {
    pub parts: Vec<(PathBuf, Part)>,
}

/// Checks that `parts` come from one render (the same identity lines) and that their sample ranges
/// tile `0..largest-spp` with no gap and no overlap. A gap names the missing ranges and the
/// `--samples` options that render them.
pub fn check_parts(mut parts: Vec<(PathBuf, Part)>) -> Result<CheckedParts> {
    let Some((first_path, first)) = parts.first().cloned() else {
        return Err(FoveaError::option("PARTS", "no part files given"));
    };
    for (path, part) in &parts[1..] {
        if let Some(((key, _), _)) = first
            .identity
            .iter()
            .zip(&part.identity)
            .find(|(a, b)| a != b)
        {
            return Err(FoveaError::file(
                path,
                format!(
                    "belongs to another render than '{}': their '{key}' lines differ",
                    first_path.display()
                ),
            ));
        }
        if part.identity.len() != first.identity.len() {
            return Err(FoveaError::file(
                path,
                format!(
                    "belongs to another render than '{}': its header has other lines",
                    first_path.display()
                ),
            ));
        }
    }
    parts.sort_by_key(|(_, p)| p.samples);
    let total = largest_spp(&first.frame);
    let mut gaps = Vec::new();
    let mut covered = 0u32;
    for (i, (path, part)) in parts.iter().enumerate() {
        let [a, b] = part.samples;
        if a < covered {
            let (other, _) = &parts[i - 1];
            return Err(FoveaError::file(
                path,
                format!(
                    "its samples {a}..{b} overlap those of '{}'; merge each sample once",
                    other.display()
                ),
            ));
        }
        if a > covered {
            gaps.push([covered, a]);
        }
        covered = b;
    }
    if covered < total {
        gaps.push([covered, total]);
    }
    if !gaps.is_empty() {
        let ranges: Vec<String> = gaps.iter().map(|[a, b]| format!("{a}..{b}")).collect();
        let options: Vec<String> = ranges.iter().map(|r| format!("--samples {r}")).collect();
        let mut message = format!(
            "samples {} of 0..{total} are missing; render them ({}) and merge again",
            ranges.join(", "),
            options.join(", ")
        );
        if let Some(tasks) = missing_parts(&parts, &gaps, total) {
            message +=
                &format!(" (parts {tasks} of the --samples I/N split: resubmit those array tasks)");
        }
        return Err(FoveaError::option("PARTS", message));
    }
    Ok(CheckedParts { parts })
}

impl CheckedParts {
    /// Checks that these are parts of the render whose identity lines are `expected`
    /// ([`identity_lines`]), naming the first line that differs.
    pub fn expect_identity(&self, expected: &[(String, String)], what: &str) -> Result<()> {
        let (path, part) = &self.parts[0];
        match expected
            .iter()
            .zip(&part.identity)
            .find(|(a, b)| a != b)
            .map(|(a, _)| a.0.as_str())
            .or((expected.len() != part.identity.len()).then_some("header"))
        {
            None => Ok(()),
            Some(key) => Err(FoveaError::file(
                path,
                format!("is not a part of {what}: its '{key}' line differs"),
            )),
        }
    }

    /// The merged image: every block's samples added over the parts, then the frame's block fill.
    #[must_use]
    pub fn merged(&self) -> fovea_cpu::FrameImage {
        fovea_cpu::fill_from_sample_sums(self.frame(), &self.summed(), self.fill_mode())
    }

    /// Every pixel's sum and count over the parts, added in sample order.
    #[must_use]
    pub fn summed(&self) -> Vec<[f32; 4]> {
        let mut sums = self.parts[0].1.sums.clone();
        for (_, part) in &self.parts[1..] {
            for (s, p) in sums.iter_mut().zip(&part.sums) {
                for c in 0..4 {
                    s[c] += p[c];
                }
            }
        }
        sums
    }

    /// The frame every part renders.
    #[must_use]
    pub fn frame(&self) -> &FrameParams {
        &self.parts[0].1.frame
    }

    /// The block fill every part names.
    #[must_use]
    pub fn fill_mode(&self) -> u32 {
        self.parts[0].1.fill_mode
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fovea_core::foveation::regions::FoveationParams;

    fn frame() -> FrameParams {
        let mut f: FrameParams = bytemuck::Zeroable::zeroed();
        f.width = 3;
        f.height = 2;
        f.seed = 7;
        f.foveation = FoveationParams::paper([1.0, 1.0], 1.0, 2.0);
        f
    }

    fn part(samples: [u32; 2], seed: u32) -> Part {
        let mut frame = frame();
        frame.seed = seed;
        let identity = RenderIdentity {
            scene_file_hash: 1,
            scene_content_hash: 2,
            executable_hash: Some(3),
        };
        let sums = (0..6)
            .map(|i| [i as f32, 0.5, 1.0e-3, (samples[1] - samples[0]) as f32])
            .collect();
        Part::new(
            &identity,
            Path::new("s.obj"),
            &frame,
            0,
            samples,
            None,
            sums,
        )
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fovea-partial-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_part_reads_back_as_written_and_a_damaged_one_is_refused() {
        let d = dir("roundtrip");
        let path = d.join("a.fvpart");
        let written = part([8, 16], 7);
        written.write(&path).unwrap();
        let read = Part::read(&path).unwrap();
        assert_eq!(read.samples, [8, 16]);
        assert_eq!(read.sums, written.sums);
        assert_eq!(read.identity, written.identity);
        assert_eq!(read.frame, written.frame);

        let bytes = std::fs::read(&path).unwrap();
        let damaged = d.join("damaged.fvpart");
        std::fs::write(&damaged, &bytes[..bytes.len() - 5]).unwrap();
        let e = Part::read(&damaged).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        let mut flipped = bytes.clone();
        *flipped.last_mut().unwrap() ^= 1;
        std::fs::write(&damaged, &flipped).unwrap();
        let e = Part::read(&damaged).unwrap_err().to_string();
        assert!(e.contains("corrupt"), "{e}");
        std::fs::write(&damaged, b"P6\n3 2\n255\n").unwrap();
        let e = Part::read(&damaged).unwrap_err().to_string();
        assert!(e.contains("not a part of a fovea render"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn parts_must_tile_the_samples_of_one_render() {
        let p = |name: &str, samples, seed| (PathBuf::from(name), part(samples, seed));
        // The paper's 32/16/8: parts must tile 0..32.
        let ok = check_parts(vec![p("b", [16, 32], 7), p("a", [0, 16], 7)]).unwrap();
        assert_eq!(ok.parts[0].0, PathBuf::from("a"), "sorted by sample");
        assert_eq!(ok.summed()[5], [10.0, 1.0, 2.0e-3, 32.0]);

        let e = check_parts(vec![p("a", [0, 8], 7), p("c", [16, 24], 7)])
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("samples 8..16, 24..32 of 0..32 are missing")
                && e.contains("--samples 8..16, --samples 24..32"),
            "{e}"
        );
        let e = check_parts(vec![p("a", [0, 20], 7), p("b", [16, 32], 7)])
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("overlap") && e.contains("'a'"), "{e}");
        let e = check_parts(vec![p("a", [0, 16], 7), p("b", [16, 32], 8)])
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("another render") && e.contains("frame-params"),
            "{e}"
        );

        // Parts of a `--samples I/N` split name the array tasks to resubmit.
        let task = |i: u32| {
            let mut part = part([i * 8, i * 8 + 8], 7);
            part.of = Some([i, 4]);
            (PathBuf::from(format!("p{i}")), part)
        };
        let e = check_parts(vec![task(0), task(1), task(3)])
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("samples 16..24 of 0..32 are missing") && e.contains("parts 2 of 4"),
            "{e}"
        );
    }
}
