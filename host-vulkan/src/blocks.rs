//! Host-side work planning: the blocks of a frame, grouped by region, and their split into dispatch
//! chunks of bounded size (one `render_samples` + `reduce_blocks` pair per chunk).
use fovea_core::foveation::blocks::for_each_block;
use fovea_core::foveation::regions::{FoveationParams, REGION_COUNT};
use fovea_core::foveation::OwnedBlock;
use fovea_core::kernel_abi::{SAMPLES_PER_INVOCATION, WORKGROUP_SIZE};

/// Default bound on the samples of one chunk: 2^20 (16 MiB of samples buffer; a few hundred ms of lavapipe
/// time on a small scene, about a millisecond on a desktop GPU).
pub const DEFAULT_MAX_CHUNK_SAMPLES: u32 = 1 << 20;

/// The bound on a software driver (lavapipe), where a chunk of Lost Empire samples takes about a second
/// per 2^18 samples on two cores: far from the per-chunk timeout even for heavier scenes.
pub const SOFTWARE_MAX_CHUNK_SAMPLES: u32 = 1 << 18;

/// Every block of a `width × height` image, one list per region, in the order of core's one walk over
/// the blocks ([`for_each_block`]).
#[must_use]
pub fn enumerate_blocks(width: u32, height: u32, params: &FoveationParams) -> [Vec<OwnedBlock>; 3] {
    let mut out: [Vec<OwnedBlock>; 3] = Default::default();
    for_each_block(width, height, params, |block| {
        out[block.region.min(REGION_COUNT - 1) as usize].push(block);
    });
    out
}

/// One dispatch chunk: `block_count` consecutive blocks of one region starting at `first_block` in the
/// frame's block buffer (whose chunks start at aligned offsets, see [`ChunkPlan::block_offset`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chunk {
    pub region: u32,
    pub spp: u32,
    /// Index of the chunk's first block in the region's list.
    pub first_block: u32,
    pub block_count: u32,
    /// Element index (in `OwnedBlock`s) of the chunk's first block in the block buffer.
    pub buffer_index: u64,
}

impl Chunk {
    /// Samples the chunk renders.
    #[inline]
    #[must_use]
    pub fn samples(&self) -> u64 {
        u64::from(self.block_count) * u64::from(self.spp)
    }

    /// Invocations the chunk's `render_samples` dispatch needs: one per
    /// [`SAMPLES_PER_INVOCATION`] samples (each invocation renders every `n`-th sample).
    #[inline]
    #[must_use]
    pub fn sample_invocations(&self) -> u64 {
        self.samples().div_ceil(u64::from(SAMPLES_PER_INVOCATION))
    }

    /// Workgroups of the chunk's `render_samples` dispatch.
    #[inline]
    #[must_use]
    pub fn sample_workgroups(&self) -> u32 {
        (self
            .sample_invocations()
            .div_ceil(u64::from(WORKGROUP_SIZE))) as u32
    }

    /// Invocations of `render_samples` with no sample to render (only in the chunk's last workgroup, and
    /// only when the chunk has fewer samples than that workgroup has invocations).
    #[inline]
    #[must_use]
    pub fn idle_invocations(&self) -> u64 {
        let dispatched = u64::from(self.sample_workgroups()) * u64::from(WORKGROUP_SIZE);
        dispatched - dispatched.min(self.samples())
    }
}

/// All chunks of a frame plus the sizes of the buffers they need.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ChunkPlan {
    pub chunks: Vec<Chunk>,
    /// Elements of the block buffer (chunks padded to the descriptor offset alignment).
    pub block_buffer_len: u64,
    /// Largest chunk, in blocks (the dynamic descriptor's range).
    pub max_chunk_blocks: u32,
    /// Largest chunk, in samples (the samples buffer's length).
    pub max_chunk_samples: u64,
}

impl ChunkPlan {
    /// Byte offset of `chunk`'s blocks in the block buffer.
    #[inline]
    #[must_use]
    pub fn block_offset(chunk: &Chunk) -> u64 {
        chunk.buffer_index * std::mem::size_of::<OwnedBlock>() as u64
    }

    /// Invocations without work over all `render_samples` dispatches.
    #[must_use]
    pub fn idle_invocations(&self) -> u64 {
        self.chunks.iter().map(Chunk::idle_invocations).sum()
    }

    /// Samples over all chunks, per region.
    #[must_use]
    pub fn samples_per_region(&self) -> [u64; 3] {
        let mut s = [0u64; 3];
        for c in &self.chunks {
            s[c.region as usize] += c.samples();
        }
        s
    }
}

/// Splits each region's blocks into chunks of at most `max_chunk_samples` samples (at least one block per
/// chunk). Each chunk's first block sits at a multiple of `align_blocks` in the block buffer, so the chunk
/// can be bound with a dynamic offset that meets `minStorageBufferOffsetAlignment`.
#[must_use]
pub fn plan_chunks(
    blocks: &[Vec<OwnedBlock>; 3],
    spp: [u32; 3],
    max_chunk_samples: u32,
    align_blocks: u64,
) -> ChunkPlan {
    let align = align_blocks.max(1);
    let mut plan = ChunkPlan::default();
    let mut next = 0u64;
    for region in 0..3 {
        let s = spp[region].max(1);
        let per_chunk = (max_chunk_samples / s).max(1);
        let n = blocks[region].len() as u32;
        let mut first = 0;
        while first < n {
            let count = per_chunk.min(n - first);
            let chunk = Chunk {
                region: region as u32,
                spp: s,
                first_block: first,
                block_count: count,
                buffer_index: next,
            };
            plan.max_chunk_blocks = plan.max_chunk_blocks.max(count);
            plan.max_chunk_samples = plan.max_chunk_samples.max(chunk.samples());
            next = (next + u64::from(count)).div_ceil(align) * align;
            plan.chunks.push(chunk);
            first += count;
        }
    }
    // The last chunk is bound with the full range, so the buffer extends that far past its start.
    plan.block_buffer_len = plan
        .chunks
        .iter()
        .map(|c| c.buffer_index + u64::from(plan.max_chunk_blocks))
        .max()
        .unwrap_or(1)
        .max(1);
    plan
}

/// The block buffer's contents for `plan` (padding entries are zero and never read).
#[must_use]
pub fn block_buffer_contents(blocks: &[Vec<OwnedBlock>; 3], plan: &ChunkPlan) -> Vec<OwnedBlock> {
    let mut out = vec![OwnedBlock::default(); plan.block_buffer_len as usize];
    for c in &plan.chunks {
        let src = &blocks[c.region as usize]
            [c.first_block as usize..(c.first_block + c.block_count) as usize];
        let dst = c.buffer_index as usize;
        out[dst..dst + src.len()].copy_from_slice(src);
    }
    out
}

/// Workgroup counts `[x, y]` covering `items` invocations with at most `max_x` groups in x (the kernel
/// reads its index as `id.x + id.y · num_workgroups.x · 64`).
#[must_use]
pub fn workgroups_2d(items: u64, max_x: u32) -> [u32; 2] {
    let groups = items.div_ceil(u64::from(WORKGROUP_SIZE)).max(1);
    let x = groups.min(u64::from(max_x.max(1)));
    [x as u32, groups.div_ceil(x) as u32]
}

#[cfg(test)]
mod tests {
    use super::*;
    use fovea_core::foveation::blocks::{count_blocks, count_samples, owning_block};

    fn params(gaze: [f32; 2], r: [f32; 2], blocks: [u32; 3]) -> FoveationParams {
        FoveationParams {
            gaze,
            radius_fovea: r[0],
            radius_intermediate: r[1],
            spp: [32, 16, 8, 0],
            block_size: [blocks[0], blocks[1], blocks[2], 0],
        }
    }

    /// Brute force: every pixel whose owning block starts there.
    fn brute_force(w: u32, h: u32, p: &FoveationParams) -> [Vec<OwnedBlock>; 3] {
        let mut out: [Vec<OwnedBlock>; 3] = Default::default();
        for y in 0..h {
            for x in 0..w {
                let b = owning_block(x, y, p);
                if b.origin == [x, y] {
                    out[b.region as usize].push(OwnedBlock {
                        origin: b.origin,
                        size: b.size,
                        region: b.region,
                    });
                }
            }
        }
        out
    }

    #[test]
    fn enumeration_matches_brute_force_and_counts() {
        let cases = [
            (64, 48, params([32.0, 24.0], [8.0, 20.0], [1, 2, 4])),
            (67, 45, params([10.0, 40.0], [5.5, 13.0], [1, 2, 4])),
            (50, 31, params([-20.0, 5.0], [30.0, 45.0], [2, 4, 8])),
            (33, 17, params([16.0, 8.0], [0.0, 0.0], [1, 3, 6])),
            (40, 40, FoveationParams::uniform(4)),
        ];
        for (w, h, p) in cases {
            let fast = enumerate_blocks(w, h, &p);
            let mut slow = brute_force(w, h, &p);
            let mut fast_sorted = fast.clone();
            for r in 0..3 {
                let key = |b: &OwnedBlock| (b.origin[1], b.origin[0]);
                fast_sorted[r].sort_by_key(key);
                slow[r].sort_by_key(key);
                assert_eq!(fast_sorted[r], slow[r], "region {r} of {w}x{h}");
            }
            let counts = count_blocks(w, h, &p);
            for r in 0..3 {
                assert_eq!(fast[r].len() as u64, counts[r]);
            }
            let plan = plan_chunks(&fast, [p.spp[0], p.spp[1], p.spp[2]], 100, 4);
            assert_eq!(plan.samples_per_region(), count_samples(w, h, &p));
        }
    }

    #[test]
    fn chunks_are_bounded_aligned_and_cover_every_block_once() {
        let p = params([30.0, 20.0], [9.0, 21.0], [1, 2, 4]);
        let blocks = enumerate_blocks(61, 43, &p);
        let plan = plan_chunks(&blocks, [32, 16, 8], 200, 4);
        let mut seen = [0u32; 3];
        let mut last_end = 0;
        for c in &plan.chunks {
            assert!(c.samples() <= 200);
            assert_eq!(c.buffer_index % 4, 0);
            assert!(c.buffer_index >= last_end, "chunks overlap in the buffer");
            last_end = c.buffer_index + u64::from(c.block_count);
            assert_eq!(c.first_block, seen[c.region as usize]);
            seen[c.region as usize] += c.block_count;
            assert!(c.idle_invocations() < u64::from(WORKGROUP_SIZE));
            assert!(c.buffer_index + u64::from(plan.max_chunk_blocks) <= plan.block_buffer_len);
        }
        for r in 0..3 {
            assert_eq!(seen[r] as usize, blocks[r].len());
        }
        let contents = block_buffer_contents(&blocks, &plan);
        for c in &plan.chunks {
            let i = c.buffer_index as usize;
            assert_eq!(
                contents[i],
                blocks[c.region as usize][c.first_block as usize]
            );
        }
        // spp larger than the bound still makes progress: one block per chunk.
        let big = plan_chunks(&blocks, [1000, 1000, 1000], 200, 1);
        assert!(big.chunks.iter().all(|c| c.block_count == 1));
    }

    #[test]
    fn invocations_cover_their_samples_and_idle_only_in_small_chunks() {
        let per = u64::from(SAMPLES_PER_INVOCATION);
        let c = Chunk {
            region: 0,
            spp: 32,
            first_block: 0,
            block_count: 3,
            buffer_index: 0,
        };
        // 96 samples: ceil(96 / per) invocations in one workgroup, of which those beyond the 96th idle.
        assert_eq!(c.sample_invocations(), 96u64.div_ceil(per));
        assert_eq!(c.sample_workgroups(), 1);
        assert_eq!(c.idle_invocations(), 64u64.saturating_sub(96));
        let c = Chunk {
            spp: 1,
            block_count: 10,
            ..c
        };
        assert_eq!(c.idle_invocations(), 64 - 10);
        // A large chunk: every dispatched invocation has samples.
        let c = Chunk {
            spp: 32,
            block_count: 4096,
            ..c
        };
        assert_eq!(
            u64::from(c.sample_workgroups()) * 64,
            (4096 * 32 / per).div_ceil(64) * 64
        );
        assert_eq!(c.idle_invocations(), 0);
    }

    #[test]
    fn workgroups_cover_items_within_the_limit() {
        assert_eq!(workgroups_2d(64, 65535), [1, 1]);
        assert_eq!(workgroups_2d(65, 65535), [2, 1]);
        assert_eq!(workgroups_2d(0, 65535), [1, 1]);
        let items = 3840u64 * 2160;
        let [x, y] = workgroups_2d(items, 65535);
        assert!(x <= 65535);
        assert!(u64::from(x) * u64::from(y) * 64 >= items);
        assert!(u64::from(x) * u64::from(y - 1) * 64 < items);
    }
}
