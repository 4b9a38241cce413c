//! A frame's GPU timestamps: one query at its start, one at its end (after the read-back copies), and
//! one after each pass of [`FramePass::ALL`] the frame runs; read back as milliseconds per pass.
use ash::vk;

use fovea_core::passes::FramePass;

/// Timestamp queries of a frame: 0 its start, 1 its end, and `2 + k` after pass `k` of
/// [`FramePass::ALL`] where the frame runs it. The samples end where the last submission starts.
pub(crate) const QUERIES: u32 = 2 + FramePass::ALL.len() as u32;

/// The query written after `pass`.
fn query_after(pass: FramePass) -> u32 {
    2 + FramePass::ALL
        .iter()
        .position(|p| *p == pass)
        .expect("every pass is in FramePass::ALL") as u32
}

/// Resets the frame's queries and writes its start.
pub(crate) fn write_start(device: &ash::Device, cb: vk::CommandBuffer, pool: vk::QueryPool) {
    // SAFETY: the pool has QUERIES queries; they are reset before being written.
    unsafe {
        device.cmd_reset_query_pool(cb, pool, 0, QUERIES);
        device.cmd_write_timestamp(cb, vk::PipelineStageFlags::TOP_OF_PIPE, pool, 0);
    }
}

/// Writes the timestamp that ends `pass`.
pub(crate) fn write_after_pass(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    pool: vk::QueryPool,
    pass: FramePass,
) {
    // SAFETY: the query is below QUERIES, reset by `write_start` in this frame's first submission,
    // which was waited on before this one.
    unsafe {
        device.cmd_write_timestamp(
            cb,
            vk::PipelineStageFlags::BOTTOM_OF_PIPE,
            pool,
            query_after(pass),
        );
    }
}

/// Writes the frame's end.
pub(crate) fn write_end(device: &ash::Device, cb: vk::CommandBuffer, pool: vk::QueryPool) {
    // SAFETY: query 1 of the pool is reset at the frame's start and written once here.
    unsafe {
        device.cmd_write_timestamp(cb, vk::PipelineStageFlags::BOTTOM_OF_PIPE, pool, 1);
    }
}

/// The frame's milliseconds from its start to its end, and each of `passes` (named by
/// [`FramePass::name`], then `read_back` where the frame copied an image back), from the queries the
/// waited-on submissions wrote; `None` where the driver could not return them. `period` is the
/// nanoseconds per tick, `mask` the valid bits.
pub(crate) fn read_frame(
    device: &ash::Device,
    pool: vk::QueryPool,
    passes: &[FramePass],
    read_back: bool,
    period: f32,
    mask: u64,
) -> Option<(f64, Vec<(&'static str, f64)>)> {
    let mut ticks = [0u64; QUERIES as usize];
    let mut read = |first: u32, count: u32| {
        let range = first as usize..(first + count) as usize;
        // SAFETY: the queries read are those written by the submissions waited on before (start,
        // end, and each pass the frame ran); the rest were reset and are not read.
        unsafe {
            device.get_query_pool_results(
                pool,
                first,
                &mut ticks[range],
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .is_ok()
    };
    let mut ok = read(0, 2);
    for &pass in passes {
        ok &= read(query_after(pass), 1);
    }
    if !ok {
        return None;
    }
    let ms = |from: u64, to: u64| (to.wrapping_sub(from) & mask) as f64 * f64::from(period) * 1e-6;
    let mut timings = Vec::new();
    let mut previous = ticks[0];
    for &pass in passes {
        let t = ticks[query_after(pass) as usize];
        timings.push((pass.name(), ms(previous, t)));
        previous = t;
    }
    if read_back {
        timings.push(("read_back", ms(previous, ticks[1])));
    }
    Some((ms(ticks[0], ticks[1]), timings))
}
