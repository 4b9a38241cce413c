//! On-screen figures (the heads-up display) rendered as a small RGBA8 image.
//!
//! Text is drawn with the public-domain 8x8 bitmap font from `font8x8` onto a
//! dark, opaque panel. Pixels are `u32` RGBA8 with red in the low byte, so the
//! little-endian bytes of each pixel are R, G, B, A.

use font8x8::legacy::BASIC_LEGACY;

/// Largest width (and height) of a HUD image, in pixels.
pub const MAX_HUD_DIMENSION: u32 = 4096;

/// Background colour of the HUD panel (opaque, RGB 16,16,16).
pub const HUD_BACKGROUND: u32 = rgba(16, 16, 16, 255);

/// Colour of the HUD text (opaque, RGB 235,235,235).
pub const HUD_TEXT: u32 = rgba(235, 235, 235, 255);

/// Side of a glyph cell at scale 1, in pixels.
const GLYPH: u32 = 8;

/// Packs 8-bit channels into a `u32` pixel with R in the low byte.
#[must_use]
pub const fn rgba(r: u8, g: u8, b: u8, a: u8) -> u32 {
    (r as u32) | ((g as u32) << 8) | ((b as u32) << 16) | ((a as u32) << 24)
}

/// A small RGBA8 image holding the rendered HUD panel.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HudImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels, row-major, top row first; RGBA8 with R in the low byte.
    pub pixels: Vec<u32>,
}

/// The 8x8 bitmap of `c`: ASCII characters from the font (control characters
/// are blank), anything outside ASCII is drawn as `'?'`.
fn glyph(c: char) -> [u8; 8] {
    let code = if c.is_ascii() {
        c as usize
    } else {
        '?' as usize
    };
    BASIC_LEGACY.get(code).copied().unwrap_or([0; 8])
}

/// Renders `lines` as light text on a dark, opaque panel.
///
/// `scale` (clamped to `1..=4`) multiplies the 8x8 font. The panel has a
/// margin of `4 * scale` pixels on each side, lines are `8 * scale` pixels high
/// and separated by `2 * scale` pixels. The panel is at most
/// [`MAX_HUD_DIMENSION`] pixels wide and high: longer lines are truncated and
/// lines that do not fit are dropped. Empty `lines` gives a 0x0 image.
#[must_use]
pub fn render_hud(lines: &[String], scale: u32) -> HudImage {
    if lines.is_empty() {
        return HudImage::default();
    }
    let scale = scale.clamp(1, 4);
    let margin = 4 * scale;
    let cell = GLYPH * scale;
    let spacing = 2 * scale;

    let max_chars = ((MAX_HUD_DIMENSION - 2 * margin) / cell) as usize;
    // n lines take n * cell + (n - 1) * spacing pixels.
    let max_lines = ((MAX_HUD_DIMENSION - 2 * margin + spacing) / (cell + spacing)) as usize;
    let lines = &lines[..lines.len().min(max_lines)];

    let widest = lines
        .iter()
        .map(|line| line.chars().count().min(max_chars))
        .max()
        .unwrap_or(0);
    // Both products are bounded by MAX_HUD_DIMENSION, so these casts are exact.
    let width = 2 * margin + widest as u32 * cell;
    let n = lines.len() as u32;
    let height = 2 * margin + n * cell + n.saturating_sub(1) * spacing;

    let mut pixels = vec![HUD_BACKGROUND; width as usize * height as usize];
    let stride = width as usize;
    for (row_index, line) in lines.iter().enumerate() {
        let top = (margin + row_index as u32 * (cell + spacing)) as usize;
        for (col_index, c) in line.chars().take(max_chars).enumerate() {
            let left = margin as usize + col_index * cell as usize;
            let bitmap = glyph(c);
            for (gy, bits) in bitmap.iter().enumerate() {
                for gx in 0..GLYPH as usize {
                    // Bit 0 is the leftmost pixel of the row.
                    if bits & (1 << gx) == 0 {
                        continue;
                    }
                    for sy in 0..scale as usize {
                        let y = top + gy * scale as usize + sy;
                        let x0 = left + gx * scale as usize;
                        let start = y * stride + x0;
                        if let Some(run) = pixels.get_mut(start..start + scale as usize) {
                            run.fill(HUD_TEXT);
                        }
                    }
                }
            }
        }
    }
    HudImage {
        width,
        height,
        pixels,
    }
}

/// The size `[width, height]` of the part of `hud` that fits inside a
/// `dst_width` x `dst_height` frame when placed at (`x`, `y`); zero in either
/// dimension when nothing is visible. Suitable as a GPU copy extent.
#[must_use]
#[cfg(test)]
pub fn clipped_size(hud: &HudImage, dst_width: u32, dst_height: u32, x: u32, y: u32) -> [u32; 2] {
    let w = hud.width.min(dst_width.saturating_sub(x));
    let h = hud.height.min(dst_height.saturating_sub(y));
    if w == 0 || h == 0 {
        [0, 0]
    } else {
        [w, h]
    }
}

/// Copies `hud` over the RGBA8 frame `dst` (`dst_width` x `dst_height`,
/// row-major) with its top-left corner at (`x`, `y`), clipped at the frame's
/// edges.
///
/// Does nothing when `dst` holds fewer than `dst_width * dst_height` pixels or
/// `hud.pixels` fewer than `hud.width * hud.height`; never panics.
#[cfg(test)]
pub fn blit_into(dst: &mut [u32], dst_width: u32, dst_height: u32, hud: &HudImage, x: u32, y: u32) {
    let dst_len = u64::from(dst_width) * u64::from(dst_height);
    let hud_len = u64::from(hud.width) * u64::from(hud.height);
    if (dst.len() as u64) < dst_len || (hud.pixels.len() as u64) < hud_len {
        return;
    }
    let [w, h] = clipped_size(hud, dst_width, dst_height, x, y);
    let (w, x) = (w as usize, x as usize);
    for row in 0..h as usize {
        let src_start = row * hud.width as usize;
        let dst_start = (y as usize + row) * dst_width as usize + x;
        let (Some(src), Some(out)) = (
            hud.pixels.get(src_start..src_start + w),
            dst.get_mut(dst_start..dst_start + w),
        ) else {
            return;
        };
        out.copy_from_slice(src);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(items: &[&str]) -> Vec<String> {
        items.iter().map(|s| (*s).to_string()).collect()
    }

    fn at(hud: &HudImage, x: u32, y: u32) -> u32 {
        hud.pixels[(y * hud.width + x) as usize]
    }

    #[test]
    fn pixel_layout_is_r_in_low_byte() {
        assert_eq!(rgba(1, 2, 3, 4).to_le_bytes(), [1, 2, 3, 4]);
        assert_eq!(HUD_BACKGROUND.to_le_bytes(), [16, 16, 16, 255]);
    }

    #[test]
    fn empty_input_gives_empty_image() {
        let hud = render_hud(&[], 2);
        assert_eq!((hud.width, hud.height), (0, 0));
        assert!(hud.pixels.is_empty());
        let mut frame = vec![7u32; 16];
        blit_into(&mut frame, 4, 4, &hud, 0, 0);
        assert!(frame.iter().all(|&p| p == 7));
        assert_eq!(clipped_size(&hud, 4, 4, 0, 0), [0, 0]);
    }

    #[test]
    fn text_lights_pixels_and_background_is_background() {
        let hud = render_hud(&lines(&["spp 128", "12.5 Mray/s"]), 1);
        assert_eq!(hud.width, 8 + 11 * 8);
        assert_eq!(hud.height, 8 + 2 * 8 + 2);
        assert_eq!(hud.pixels.len(), (hud.width * hud.height) as usize);
        assert!(hud.pixels.contains(&HUD_TEXT));
        assert!(hud
            .pixels
            .iter()
            .all(|&p| p == HUD_TEXT || p == HUD_BACKGROUND));
        assert_eq!(at(&hud, 0, 0), HUD_BACKGROUND);
        assert_eq!(at(&hud, hud.width - 1, hud.height - 1), HUD_BACKGROUND);
    }

    #[test]
    fn glyph_one_at_scale_1_and_2() {
        // '1' in font8x8 (bit 0 = leftmost pixel).
        let expected: [u8; 8] = [0x0C, 0x0E, 0x0C, 0x0C, 0x0C, 0x0C, 0x3F, 0x00];
        for scale in [1u32, 2] {
            let hud = render_hud(&lines(&["1"]), scale);
            let margin = 4 * scale;
            assert_eq!(hud.width, 2 * margin + 8 * scale);
            assert_eq!(hud.height, 2 * margin + 8 * scale);
            for y in 0..hud.height {
                for x in 0..hud.width {
                    let inside = (margin..margin + 8 * scale).contains(&x)
                        && (margin..margin + 8 * scale).contains(&y);
                    let lit = inside && {
                        let (gx, gy) = ((x - margin) / scale, (y - margin) / scale);
                        expected[gy as usize] & (1 << gx) != 0
                    };
                    let want = if lit { HUD_TEXT } else { HUD_BACKGROUND };
                    assert_eq!(at(&hud, x, y), want, "scale {scale} pixel ({x},{y})");
                }
            }
            let lit = hud.pixels.iter().filter(|&&p| p == HUD_TEXT).count();
            let bits: u32 = expected.iter().map(|b| b.count_ones()).sum();
            assert_eq!(lit as u32, bits * scale * scale);
        }
    }

    #[test]
    fn non_ascii_is_question_mark_and_scale_is_clamped() {
        assert_eq!(render_hud(&lines(&["é"]), 1), render_hud(&lines(&["?"]), 1));
        assert_eq!(render_hud(&lines(&["x"]), 0), render_hud(&lines(&["x"]), 1));
        assert_eq!(
            render_hud(&lines(&["x"]), 99),
            render_hud(&lines(&["x"]), 4)
        );
    }

    #[test]
    fn width_and_height_are_capped() {
        let long = "W".repeat(10_000);
        let hud = render_hud(&[long], 4);
        assert!(hud.width <= MAX_HUD_DIMENSION);
        assert_eq!(hud.pixels.len(), (hud.width * hud.height) as usize);
        let many = vec!["x".to_string(); 10_000];
        let hud = render_hud(&many, 1);
        assert!(hud.height <= MAX_HUD_DIMENSION);
        assert_eq!(hud.pixels.len(), (hud.width * hud.height) as usize);
    }

    #[test]
    fn blit_copies_and_clips_at_edges() {
        let hud = HudImage {
            width: 3,
            height: 2,
            pixels: vec![1, 2, 3, 4, 5, 6],
        };
        let mut frame = vec![0u32; 16];
        blit_into(&mut frame, 4, 4, &hud, 0, 0);
        assert_eq!(&frame[0..4], &[1, 2, 3, 0]);
        assert_eq!(&frame[4..8], &[4, 5, 6, 0]);

        let mut frame = vec![0u32; 16];
        blit_into(&mut frame, 4, 4, &hud, 2, 3);
        assert_eq!(clipped_size(&hud, 4, 4, 2, 3), [2, 1]);
        assert_eq!(&frame[12..16], &[0, 0, 1, 2]);
        assert_eq!(frame.iter().filter(|&&p| p != 0).count(), 2);

        // Fully outside: nothing changes.
        for (x, y) in [(4, 0), (0, 4), (u32::MAX, u32::MAX)] {
            let mut frame = vec![0u32; 16];
            blit_into(&mut frame, 4, 4, &hud, x, y);
            assert!(frame.iter().all(|&p| p == 0));
            assert_eq!(clipped_size(&hud, 4, 4, x, y), [0, 0]);
        }
    }

    #[test]
    fn blit_ignores_short_buffers() {
        let hud = render_hud(&lines(&["hi"]), 1);
        let mut frame = vec![0u32; 10];
        blit_into(&mut frame, 100, 100, &hud, 0, 0);
        assert!(frame.iter().all(|&p| p == 0));
        let broken = HudImage {
            width: 10,
            height: 10,
            pixels: vec![1; 3],
        };
        let mut frame = vec![0u32; 400];
        blit_into(&mut frame, 20, 20, &broken, 0, 0);
        assert!(frame.iter().all(|&p| p == 0));
        blit_into(&mut [], u32::MAX, u32::MAX, &hud, 0, 0);
    }
}
