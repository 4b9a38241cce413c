//! Height (bump) maps turned into tangent-space normal maps at load, for OBJ `map_Bump`/`bump` images
//! that hold heights rather than normals.
//!
//! **The rule.** The height is an image's mean RGB in [0, 1] (8-bit data, not sRGB-decoded); its slope
//! per texel is the Sobel gradient (3 × 3, divided by 8, so a ramp that climbs `Δ` per texel has slope
//! `Δ`), wrapping at the edges as the texture does. The normal of the height field `bm · h`, measured in
//! texels, is `normalize(−bm ∂h/∂x, −bm ∂h/∂y, 1)`: a height step of `1 / bm` per texel tilts it by 45°.
//! `x` runs along the image's rows (+u) and `y` down its columns (+v, glTF's orientation, which
//! `fovea_core::material::shading`'s frame follows: its bitangent is `n × t`, along +v), so a surface
//! that climbs towards +u leans towards −u, as a displaced surface does. The result is encoded like any
//! normal map, `(n + 1) / 2` per channel.
use crate::texture::{pack_rgba8, Texture};

/// The normal map of the height map `heights` with bump multiplier `strength` (MTL `-bm`, 1 by
/// default); same size, linear, sampled like the source.
#[must_use]
pub fn normal_map_from_heights(heights: &Texture, strength: f32) -> Texture {
    let (w, h) = (heights.width as usize, heights.height as usize);
    let height_at = |x: usize, y: usize| -> f32 {
        let [r, g, b, _] = heights.texel(x as u32, y as u32);
        (f32::from(r) + f32::from(g) + f32::from(b)) / (3.0 * 255.0)
    };
    let strength = if strength.is_finite() { strength } else { 1.0 };
    let mut texels = Vec::with_capacity(w * h);
    for y in 0..h {
        let (up, down) = ((y + h - 1) % h, (y + 1) % h);
        for x in 0..w {
            let (left, right) = ((x + w - 1) % w, (x + 1) % w);
            let column = |x: usize| height_at(x, up) + 2.0 * height_at(x, y) + height_at(x, down);
            let row = |y: usize| height_at(left, y) + 2.0 * height_at(x, y) + height_at(right, y);
            let dx = (column(right) - column(left)) / 8.0;
            let d_row = (row(down) - row(up)) / 8.0;
            let n = glam::Vec3::new(-strength * dx, strength * d_row, 1.0).normalize();
            let encode = |c: f32| ((c * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
            texels.push(pack_rgba8([encode(n.x), encode(n.y), encode(n.z), 255]));
        }
    }
    let mut out = Texture::new(
        format!("{} (heights as normals)", heights.name),
        heights.width,
        heights.height,
        false,
        texels,
    );
    out.sampler = heights.sampler;
    out.transform = heights.transform;
    out
}

/// The bump multiplier of an MTL texture statement (`-bm 0.5 bump.png`), or 1 without one.
#[must_use]
pub fn bump_multiplier(statement: &str) -> Option<f32> {
    let mut tokens = statement.split_whitespace();
    while let Some(t) = tokens.next() {
        if t == "-bm" {
            return tokens.next().and_then(|v| v.parse::<f32>().ok());
        }
    }
    Some(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, height: impl Fn(u32, u32) -> u8) -> Texture {
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let v = height(x, y);
                pack_rgba8([v, v, v, 255])
            })
            .collect();
        Texture::new("h.png".to_owned(), w, h, false, texels)
    }

    fn normal(t: &Texture, x: u32, y: u32) -> glam::Vec3 {
        let [r, g, b, _] = t.texels[(y * t.width + x) as usize].to_le_bytes();
        glam::Vec3::new(f32::from(r), f32::from(g), f32::from(b)) / 127.5 - 1.0
    }

    /// A ramp that climbs 0.1 per texel along x leans towards −x by atan(bm · 0.1); one that climbs
    /// down the rows leans up the image (+y of the normal map); a flat map stays flat.
    #[test]
    fn ramps_lean_against_their_slope_by_the_rule() {
        let ramp_x = image(16, 8, |x, _| (x * 255 / 10).min(255) as u8);
        let n = normal(&normal_map_from_heights(&ramp_x, 2.0), 4, 4);
        let want = glam::Vec3::new(-2.0 * 0.1, 0.0, 1.0).normalize();
        assert!((n - want).length() < 0.02, "{n} against {want}");
        let ramp_y = image(8, 16, |_, y| (y * 255 / 10).min(255) as u8);
        let n = normal(&normal_map_from_heights(&ramp_y, 1.0), 4, 4);
        let want = glam::Vec3::new(0.0, 0.1, 1.0).normalize();
        assert!((n - want).length() < 0.02, "{n} against {want}");
        let flat = image(4, 4, |_, _| 77);
        let n = normal(&normal_map_from_heights(&flat, 5.0), 1, 2);
        assert!((n - glam::Vec3::Z).length() < 0.01, "{n}");
        // A negative multiplier inverts the bumps.
        let n = normal(&normal_map_from_heights(&ramp_x, -2.0), 4, 4);
        assert!(n.x > 0.15, "{n}");
    }

    #[test]
    fn bump_multiplier_is_read_from_the_statement() {
        assert_eq!(bump_multiplier("-bm 0.25 bump.png"), Some(0.25));
        assert_eq!(bump_multiplier("bump.png"), Some(1.0));
        assert_eq!(bump_multiplier("-bm x bump.png"), None);
    }
}
