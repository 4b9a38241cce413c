//! Parts of a render split by samples: `fovea render --samples A..B|I/N` writes one, `fovea merge` (and
//! `fovea report --reference-parts`) reads them back ([`check`]: whether they tile one render, and
//! their sum).
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
//! part 1/4                                (only for --samples I/N)
//! samples 8..16
//! data-bytes 3686400
//! checksum fnv1a64 …                      (of every header byte before this line, then the data)
//! end
//! <data-bytes bytes: width·height·[r, g, b, count] as little-endian f32>
//! ```
//! A truncated, padded or corrupt part fails its length or checksum and is refused by name; so is a
//! header whose frame fovea would not render (sizes, foveation, fill).
mod check;

use std::fs::File;
use std::io::{BufReader, BufWriter, Read as _, Seek as _, SeekFrom, Write as _};
use std::path::Path;

use fovea_core::foveation::blocks::{block_sample_range, count_blocks};
use fovea_core::foveation::fill::{FILL_BILINEAR, FILL_REPLICATE};
use fovea_core::foveation::regions::{FoveationParams, FOVEATION_OK, REGION_COUNT};
use fovea_core::integrator::FrameParams;
use fovea_scene::pack::PackedScene;

pub use check::check_parts;

use crate::content_hash::{executable_hash, fnv1a64, packed_scene_hash, Fnv1a64};
use crate::error::{FoveaError, Result};
use crate::output::write_atomically;
use crate::values::{SampleSelection, MAX_BLOCK_EDGE, MAX_IMAGE_EDGE, MAX_SPP};

/// The first line of every part file.
const MAGIC: &str = "fovea-partial 1";
/// The largest header fovea reads, in bytes (a real one is about 1 KiB).
const MAX_HEADER_BYTES: u64 = 64 * 1024;
/// Bytes of one pixel's `[r, g, b, count]`.
const PIXEL_BYTES: u64 = 16;

/// Which samples a part takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartSpec {
    /// Sample indices `first..end` of every block (clipped to each block's own count).
    pub samples: [u32; 2],
    /// `[I, N]` for a part chosen as `--samples I/N` (part `I` of `N`, from 0).
    pub split: Option<[u32; 2]>,
}

impl PartSpec {
    /// The part `selection` picks of a frame whose blocks take at most `largest_spp` samples; an empty
    /// part, or one that reaches past `largest_spp`, is refused with the reason.
    pub fn new(selection: SampleSelection, largest_spp: u32) -> std::result::Result<Self, String> {
        let samples = selection.range(largest_spp);
        let split = match selection {
            SampleSelection::Range(_) => None,
            SampleSelection::Part { index, count } => Some([index, count]),
        };
        // A split into more parts than samples leaves some parts empty, whichever this one is: refused
        // for every part alike, so that no task of such an array renders.
        if let Some([_, count]) =
            split.filter(|[_, count]| samples[0] == samples[1] || *count > largest_spp)
        {
            return Err(format!(
                "{count} parts of the frame's {largest_spp} samples leave some empty; split into \
                 {largest_spp} parts or fewer"
            ));
        }
        if samples[1] > largest_spp {
            return Err(format!(
                "ends at {}, past the frame's {largest_spp} samples per pixel or block; the parts of a \
                 split tile 0..{largest_spp}",
                samples[1]
            ));
        }
        Ok(Self { samples, split })
    }
}

/// The most samples any block of a frame with `foveation` takes: the parts of a split tile `0..` this.
#[must_use]
pub fn largest_spp(foveation: &FoveationParams) -> u32 {
    foveation.spp[..REGION_COUNT as usize]
        .iter()
        .copied()
        .max()
        .unwrap_or(0)
}

/// The camera samples a part traces: every block's samples in `samples`, summed over the regions.
#[must_use]
pub fn samples_in_part(
    width: u32,
    height: u32,
    foveation: &FoveationParams,
    samples: [u32; 2],
) -> u64 {
    let blocks = count_blocks(width, height, foveation);
    (0..REGION_COUNT as usize)
        .map(|r| {
            let [a, b] = block_sample_range(foveation.spp[r], samples[0], samples[1]);
            blocks[r] * u64::from(b - a)
        })
        .sum()
}

/// What identifies the render a part belongs to, besides its frame.
pub struct RenderIdentity {
    /// FNV-1a-64 of the scene file's bytes.
    pub scene_file_hash: u64,
    /// [`packed_scene_hash`]: what the loaders made of the file and its side files.
    pub scene_content_hash: u64,
    /// [`executable_hash`]: another build may trace other samples.
    pub executable_hash: Option<u64>,
}

impl RenderIdentity {
    /// The identity of a render of `packed`, loaded from a scene file whose bytes are `scene_bytes`, by
    /// this executable.
    #[must_use]
    pub fn of(scene_bytes: &[u8], packed: &PackedScene) -> Self {
        Self {
            scene_file_hash: fnv1a64(scene_bytes),
            scene_content_hash: packed_scene_hash(packed),
            executable_hash: executable_hash(),
        }
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
        ("largest-spp", largest_spp(f).to_string()),
    ];
    lines.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

/// Writes a part to `path`, atomically (nothing is left behind on failure): the header for `identity`
/// (its [`identity_lines`]), `scene_path` and `spec`, then `sums` as `render_sample_range` wrote them.
pub fn write_part(
    path: &Path,
    identity: &[(String, String)],
    scene_path: &Path,
    spec: PartSpec,
    sums: &[[f32; 4]],
) -> Result<()> {
    let mut header = format!("{MAGIC}\n");
    for (k, v) in identity {
        header += &format!("{k} {v}\n");
    }
    header += &format!(
        "scene-path {}\n",
        scene_path.display().to_string().replace('\n', " ")
    );
    if let Some([i, n]) = spec.split {
        header += &format!("part {i}/{n}\n");
    }
    header += &format!(
        "samples {}..{}\ndata-bytes {}\n",
        spec.samples[0],
        spec.samples[1],
        sums.len() as u64 * PIXEL_BYTES
    );
    let mut hash = Fnv1a64::default();
    hash.write(header.as_bytes());
    for p in sums {
        for v in p {
            hash.write(&v.to_le_bytes());
        }
    }
    header += &format!("checksum fnv1a64 {:016x}\nend\n", hash.finish());
    write_atomically(path, |tmp| {
        let mut file = BufWriter::new(File::create(tmp).map_err(|e| e.to_string())?);
        file.write_all(header.as_bytes())
            .map_err(|e| e.to_string())?;
        for p in sums {
            for v in p {
                file.write_all(&v.to_le_bytes())
                    .map_err(|e| e.to_string())?;
            }
        }
        let file = file.into_inner().map_err(|e| e.to_string())?;
        file.sync_all().map_err(|e| e.to_string())
    })
}

/// A part file's header, read and checked; its data is read by [`PartHeader::add_data_to`].
#[derive(Clone, Debug)]
pub struct PartHeader {
    /// The identity lines, in order: equal for every part of one render.
    pub identity: Vec<(String, String)>,
    /// The frame (camera, foveation, size, frame number, seed), exactly.
    pub frame: FrameParams,
    /// The block fill the merged image is made with (`FILL_BILINEAR` or `FILL_REPLICATE`).
    pub fill_mode: u32,
    /// Which samples the part holds.
    pub spec: PartSpec,
    /// Where the data starts in the file.
    data_offset: u64,
    /// The checksum's state after the header bytes it covers.
    header_hash: Fnv1a64,
    /// The checksum the header states.
    checksum: u64,
}

impl PartHeader {
    /// Reads and checks the header of the part file at `path`, and that the file holds exactly the data
    /// the header announces (its checksum is checked as the data is read).
    pub fn read(path: &Path) -> Result<Self> {
        let not_a_part = |why: &str| {
            FoveaError::file(
                path,
                format!(
                    "not a part of a fovea render ({why}); parts are written by \
                     `fovea render --samples A..B -o FILE.fvpart`"
                ),
            )
        };
        let file = File::open(path).map_err(|e| FoveaError::file(path, e))?;
        let file_bytes = file
            .metadata()
            .map_err(|e| FoveaError::file(path, e))?
            .len();
        let mut head = Vec::new();
        file.take(MAX_HEADER_BYTES)
            .read_to_end(&mut head)
            .map_err(|e| FoveaError::file(path, e))?;
        let first_line = head.split(|&b| b == b'\n').next().unwrap_or_default();
        if first_line != MAGIC.as_bytes() {
            return Err(not_a_part(&format!("its first line is not '{MAGIC}'")));
        }
        let end_marker = b"\nend\n";
        let header_end = head
            .windows(end_marker.len())
            .position(|w| w == end_marker)
            .ok_or_else(|| not_a_part("its header has no 'end' line"))?
            + end_marker.len();
        let header = std::str::from_utf8(&head[..header_end])
            .map_err(|_| not_a_part("its header is not text"))?;
        let checksum_at = header
            .find("\nchecksum ")
            .ok_or_else(|| not_a_part("its 'checksum' line is missing"))?
            + 1;
        let mut header_hash = Fnv1a64::default();
        header_hash.write(&head[..checksum_at]);

        let mut identity = Vec::new();
        let (mut samples, mut data_bytes, mut checksum, mut split) = (None, None, None, None);
        for line in header.lines().skip(1) {
            let (key, value) = line.split_once(' ').unwrap_or((line, ""));
            match key {
                "end" => break,
                "scene-path" => {}
                "samples" => samples = parse_pair(value, "..").filter(|[a, b]| a < b),
                "part" => {
                    split = parse_pair(value, "/").filter(|&[i, n]| i < n && n <= MAX_SPP);
                    if split.is_none() {
                        return Err(not_a_part("its 'part' line is malformed"));
                    }
                }
                "data-bytes" => data_bytes = value.parse::<u64>().ok(),
                "checksum" => {
                    checksum = value
                        .strip_prefix("fnv1a64 ")
                        .and_then(|h| u64::from_str_radix(h, 16).ok());
                }
                _ => identity.push((key.to_string(), value.to_string())),
            }
        }
        let field = |name: &str| not_a_part(&format!("its '{name}' line is missing or malformed"));
        let samples = samples.ok_or_else(|| field("samples"))?;
        let data_bytes = data_bytes.ok_or_else(|| field("data-bytes"))?;
        let checksum = checksum.ok_or_else(|| field("checksum"))?;
        let line = |name: &str| {
            identity
                .iter()
                .find(|(k, _)| k == name)
                .map(|(_, v)| v.as_str())
        };
        let frame = line("frame-params")
            .and_then(parse_hex)
            .filter(|b| b.len() == std::mem::size_of::<FrameParams>())
            .map(|b| bytemuck::pod_read_unaligned::<FrameParams>(&b))
            .ok_or_else(|| field("frame-params"))?;
        let fill_mode = line("fill")
            .and_then(|v| v.parse().ok())
            .filter(|&m| m == FILL_BILINEAR || m == FILL_REPLICATE)
            .ok_or_else(|| field("fill"))?;
        let f = &frame.foveation;
        let edges_ok = [frame.width, frame.height]
            .iter()
            .all(|e| (1..=MAX_IMAGE_EDGE).contains(e));
        let blocks_ok = f.block_size[..3].iter().all(|&b| b <= MAX_BLOCK_EDGE);
        let spp_ok = f.spp[..3].iter().all(|&s| s <= MAX_SPP);
        if !edges_ok || !blocks_ok || !spp_ok || f.validate() != FOVEATION_OK {
            return Err(not_a_part(
                "its frame-params hold a size or foveation fovea does not render",
            ));
        }
        let largest = largest_spp(f);
        if samples[1] > largest {
            return Err(field("samples"));
        }
        if let Some([index, count]) = split {
            if (SampleSelection::Part { index, count }).range(largest) != samples {
                return Err(not_a_part("its 'part' and 'samples' lines disagree"));
            }
        }
        let expected = u64::from(frame.width) * u64::from(frame.height) * PIXEL_BYTES;
        if data_bytes != expected {
            return Err(not_a_part(&format!(
                "its data-bytes, {data_bytes}, do not fit a {}x{} image",
                frame.width, frame.height
            )));
        }
        let stored = file_bytes.saturating_sub(header_end as u64);
        if stored != data_bytes {
            return Err(FoveaError::file(
                path,
                format!(
                    "truncated or padded: {stored} data bytes where the header says {data_bytes}; \
                     render this part again"
                ),
            ));
        }
        Ok(Self {
            identity,
            frame,
            fill_mode,
            spec: PartSpec { samples, split },
            data_offset: header_end as u64,
            header_hash,
            checksum,
        })
    }

    /// Adds the part's data at `path` (whose header this is) to `sums`, pixel by pixel, and checks the
    /// checksum: a corrupt part is an error, and `sums` is then not to be used. Returns how many of
    /// the part's pixel sums hold a NaN or an infinity (a render's non-finite samples, which the
    /// merged image then shows).
    pub fn add_data_to(&self, path: &Path, sums: &mut [[f32; 4]]) -> Result<usize> {
        let mut non_finite = 0;
        let mut sums = sums.iter_mut();
        self.read_data(path, |pixel| {
            if let Some(sum) = sums.next() {
                non_finite += usize::from(!pixel.iter().all(|v| v.is_finite()));
                for (c, v) in sum.iter_mut().zip(pixel) {
                    *c += v;
                }
            }
        })?;
        Ok(non_finite)
    }

    /// Reads the part's data at `path` through and checks it against the checksum, keeping nothing:
    /// whether a part whose header disagrees with the others' was edited or damaged (then corrupt)
    /// rather than rendered differently.
    pub fn verify(&self, path: &Path) -> Result<()> {
        self.read_data(path, |_| {})
    }

    /// Streams the part's pixel sums (one per pixel of its frame, in order) to `each`, then checks the
    /// checksum over its header and data.
    fn read_data(&self, path: &Path, mut each: impl FnMut([f32; 4])) -> Result<()> {
        let io = |e: std::io::Error| FoveaError::file(path, e);
        let mut file = File::open(path).map_err(io)?;
        file.seek(SeekFrom::Start(self.data_offset)).map_err(io)?;
        let mut reader = BufReader::with_capacity(1 << 20, file);
        let mut hash = self.header_hash;
        let mut pixel = [0u8; PIXEL_BYTES as usize];
        let pixels = u64::from(self.frame.width) * u64::from(self.frame.height);
        for _ in 0..pixels {
            reader.read_exact(&mut pixel).map_err(io)?;
            hash.write(&pixel);
            let mut sum = [0.0f32; 4];
            for (c, bytes) in sum.iter_mut().zip(pixel.chunks_exact(4)) {
                *c = f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
            }
            each(sum);
        }
        if hash.finish() != self.checksum {
            return Err(FoveaError::file(
                path,
                "corrupt: its header or data does not match its checksum; render this part again",
            ));
        }
        Ok(())
    }
}

/// `A<sep>B` as `[A, B]`.
fn parse_pair(text: &str, sep: &str) -> Option<[u32; 2]> {
    let (a, b) = text.split_once(sep)?;
    Some([a.trim().parse().ok()?, b.trim().parse().ok()?])
}

/// Hexadecimal digits as bytes (`frame-params`).
fn parse_hex(text: &str) -> Option<Vec<u8>> {
    if !text.len().is_multiple_of(2) {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    /// A 3x2 frame of the paper's 32/16/8 with seed `seed`.
    fn frame(seed: u32) -> FrameParams {
        let mut f: FrameParams = bytemuck::Zeroable::zeroed();
        f.width = 3;
        f.height = 2;
        f.seed = seed;
        f.foveation = FoveationParams::paper([1.0, 1.0], 1.0, 2.0);
        f
    }

    fn identity(frame: &FrameParams) -> Vec<(String, String)> {
        let hashes = RenderIdentity {
            scene_file_hash: 1,
            scene_content_hash: 2,
            executable_hash: Some(3),
        };
        identity_lines(&hashes, frame, FILL_BILINEAR)
    }

    fn sums(count: u32) -> Vec<[f32; 4]> {
        (0..6)
            .map(|i| [i as f32, 0.5, 1.0e-3, count as f32])
            .collect()
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fovea-partial-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Writes a part of `frame(seed)` and reads its header back.
    fn part(d: &Path, name: &str, spec: PartSpec, seed: u32) -> (PathBuf, PartHeader) {
        let path = d.join(name);
        let [a, b] = spec.samples;
        write_part(
            &path,
            &identity(&frame(seed)),
            Path::new("s.obj"),
            spec,
            &sums(b - a),
        )
        .unwrap();
        let header = PartHeader::read(&path).unwrap();
        (path, header)
    }

    fn range(a: u32, b: u32) -> PartSpec {
        PartSpec {
            samples: [a, b],
            split: None,
        }
    }

    fn error(r: Result<impl Sized>) -> String {
        r.err().expect("an error").to_string()
    }

    /// A property test of the part reader (run in CI, bounded: `FOVEA_FUZZ_CASES`, 3000 by
    /// default): random byte edits, insertions, deletions and truncations of a real part, read and
    /// merged, are refused with a message naming the file or read as a part, never a panic.
    #[test]
    fn mutated_parts_are_refused_or_read_never_a_panic() {
        let d = dir("mutate");
        // Every sample of the frame: unharmed, it merges.
        let (path, _) = part(&d, "a.fvpart", range(0, 32), 7);
        let good = std::fs::read(&path).unwrap();
        let cases: u64 = std::env::var("FOVEA_FUZZ_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(3000);
        let mut rng = crate::content_hash::Fnv1a64::default();
        let mut next = |n: usize| {
            rng.write(b"x");
            (rng.finish() % n.max(1) as u64) as usize
        };
        let mutated = d.join("m.fvpart");
        let mut refused = 0u64;
        for _ in 0..cases {
            let mut bytes = good.clone();
            for _ in 0..1 + next(4) {
                let at = next(bytes.len());
                match next(4) {
                    0 => bytes[at] ^= 1 << next(8),
                    1 => bytes.insert(at, next(256) as u8),
                    2 => {
                        bytes.remove(at);
                    }
                    _ => bytes.truncate(at),
                }
                if bytes.is_empty() {
                    break;
                }
            }
            std::fs::write(&mutated, &bytes).unwrap();
            let result = std::panic::catch_unwind(|| {
                let header = PartHeader::read(&mutated)?;
                check::check_parts(vec![(mutated.clone(), header)])?
                    .merged()
                    .map(|(image, _)| image)
            });
            match result {
                Err(_) => panic!("a panic on {} mutated bytes", bytes.len()),
                Ok(Err(e)) => {
                    refused += 1;
                    assert!(e.to_string().contains("m.fvpart"), "{e}");
                }
                Ok(Ok(_)) => {}
            }
        }
        assert!(refused > cases / 2, "{refused} of {cases} refused");
    }

    #[test]
    fn a_part_reads_back_as_written_and_a_damaged_one_is_refused() {
        let d = dir("roundtrip");
        let (path, header) = part(&d, "a.fvpart", range(8, 16), 7);
        assert_eq!(header.spec, range(8, 16));
        assert_eq!(header.frame, frame(7));
        assert_eq!(header.identity, identity(&frame(7)));
        let mut added = vec![[1.0f32; 4]; 6];
        header.add_data_to(&path, &mut added).unwrap();
        let expected: Vec<[f32; 4]> = sums(8).iter().map(|p| p.map(|v| v + 1.0)).collect();
        assert_eq!(added, expected);

        let bytes = std::fs::read(&path).unwrap();
        let damaged = d.join("damaged.fvpart");
        let read_damaged = |bytes: &[u8]| {
            std::fs::write(&damaged, bytes).unwrap();
            let header = PartHeader::read(&damaged)?;
            header.add_data_to(&damaged, &mut [[0.0; 4]; 6])
        };
        assert!(error(read_damaged(&bytes[..bytes.len() - 5])).contains("truncated"));
        let mut flipped = bytes.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(error(read_damaged(&flipped)).contains("corrupt"));
        // The header is under the checksum too: an edited readable line is caught.
        let text = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]).into_owned();
        let at = text.find("seed 7").unwrap() + 5;
        let mut edited = bytes.clone();
        edited[at] = b'8';
        assert!(error(read_damaged(&edited)).contains("corrupt"));
        let mut other_magic = bytes.clone();
        other_magic.splice(0..0, *b"fovea-partial 10\n");
        assert!(error(read_damaged(&other_magic)).contains("first line"));
        assert!(error(read_damaged(b"P6\n3 2\n255\n")).contains("not a part of a fovea render"));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_header_with_a_frame_fovea_would_not_render_is_refused() {
        let d = dir("frames");
        let mut cases = Vec::new();
        let mut f = frame(1);
        f.width = 0;
        cases.push((f, "size or foveation"));
        let mut f = frame(1);
        f.foveation.block_size = [1, 0, 4, 0];
        cases.push((f, "size or foveation"));
        let mut f = frame(1);
        f.width = 1 << 31;
        f.height = 1 << 31;
        cases.push((f, "size or foveation"));
        for (i, (f, needle)) in cases.into_iter().enumerate() {
            let path = d.join(format!("{i}.fvpart"));
            write_part(&path, &identity(&f), Path::new("s"), range(0, 4), &[]).unwrap();
            let e = error(PartHeader::read(&path));
            assert!(e.contains(needle), "{i}: {e}");
        }
        // A part past the frame's samples, and `part` and `samples` lines that disagree.
        let path = d.join("past.fvpart");
        write_part(
            &path,
            &identity(&frame(1)),
            Path::new("s"),
            range(16, 40),
            &sums(8),
        )
        .unwrap();
        assert!(error(PartHeader::read(&path)).contains("'samples'"));
        let wrong = PartSpec {
            samples: [0, 8],
            split: Some([1, 4]),
        };
        write_part(&path, &identity(&frame(1)), Path::new("s"), wrong, &sums(8)).unwrap();
        assert!(error(PartHeader::read(&path)).contains("disagree"));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn parts_must_tile_the_samples_of_one_render() {
        let d = dir("tile");
        let p = |name: &str, a, b, seed| part(&d, name, range(a, b), seed);
        // The paper's 32/16/8: parts must tile 0..32.
        let ok = check_parts(vec![p("b", 16, 32, 7), p("a", 0, 16, 7)]).unwrap();
        assert_eq!(ok.parts[0].0, d.join("a"), "sorted by sample");
        let (merged, non_finite) = ok.merged().unwrap();
        assert!(non_finite.is_empty());
        assert_eq!(merged.pixels.len(), 6);

        let e = error(check_parts(vec![p("a", 0, 8, 7), p("c", 16, 24, 7)]));
        assert!(
            e.contains("samples 8..16, 24..32 of 0..32 are missing")
                && e.contains("--samples 8..16, --samples 24..32"),
            "{e}"
        );
        let e = error(check_parts(vec![p("a", 0, 20, 7), p("b", 16, 32, 7)]));
        assert!(e.contains("overlap") && e.contains("/a'"), "{e}");
        let e = error(check_parts(vec![p("a", 0, 16, 7), p("b", 16, 32, 8)]));
        assert!(
            e.contains("another render") && e.contains("frame-params"),
            "{e}"
        );

        // Parts of a `--samples I/N` split name the array tasks to resubmit.
        let task = |i: u32| {
            let spec = PartSpec::new(SampleSelection::Part { index: i, count: 4 }, 32).unwrap();
            part(&d, &format!("t{i}"), spec, 7)
        };
        let e = error(check_parts(vec![task(0), task(1), task(3)]));
        assert!(
            e.contains("samples 16..24 of 0..32 are missing") && e.contains("parts 2 of 4"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_part_spec_is_refused_where_empty_or_past_the_frame() {
        let part = |i, n| SampleSelection::Part { index: i, count: n };
        assert_eq!(
            PartSpec::new(part(1, 4), 32),
            Ok(PartSpec {
                samples: [8, 16],
                split: Some([1, 4])
            })
        );
        assert!(PartSpec::new(part(40, 64), 32)
            .unwrap_err()
            .contains("empty"));
        assert!(PartSpec::new(SampleSelection::Range([16, 48]), 32)
            .unwrap_err()
            .contains("past the frame's 32 samples"));
    }
}
