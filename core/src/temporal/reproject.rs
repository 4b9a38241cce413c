//! Reprojection: where the surface a pixel sees now was on the previous frame's film, and the previous
//! history found there (a bilinear blend of four texels, each weighted by how well its previous G-buffer
//! texel agrees with this surface: strolle's and kajiya's 4-tap validity).
//!
//! The point is the pixel's G-buffer hit (`camera + direction · distance`); a pixel that sees the sky
//! reprojects its direction, the point at infinity. A tap's weight is its bilinear weight times
//!
//! - a plane test `2^(-40 |(p − q) · n'| / d)`: `q` and `n'` are the tap's previous hit and normal, `d`
//!   the point's distance from the previous camera. It is kajiya's depth test `2^(-40 |dz| / (z + z'))`
//!   measured along the tap's normal instead of the view axis, so that a slanted plane, whose depth
//!   changes from texel to texel, still agrees with itself;
//! - a normal test, ramping from 0 at `n · n' = 0.75` to 1 at `0.95`;
//! - sky against sky 1, sky against a surface 0.
//!
//! Their sum is the history's validity: 1 where the surface was seen as it is now, 0 where it was hidden
//! (a disocclusion) or off the film. Where all four taps agree and the 4x4 texels around them lie on one
//! surface, the colour and moments are resampled with Catmull-Rom instead of bilinearly ([`sharpen`]):
//! bilinear resampling every frame of a camera move blurs sharp textures.
use glam::{Vec2, Vec3};

use super::gbuffer::GBufferTexel;
use super::params::{TemporalParams, TEMPORAL_CAMERA_MOVED, TEMPORAL_HISTORY_VALID};
use super::texel::HistoryTexel;
use crate::integrator::FrameParams;
use crate::math::float::{abs, exp2, floor};
use crate::math::vec3_from;

/// The previous history as seen from one pixel of this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reprojected {
    /// The blend of the valid taps (zero where there are none).
    pub history: HistoryTexel,
    /// The sum of the taps' weights, in [0, 1]: how much of the history is this surface's.
    pub validity: f32,
}

impl Reprojected {
    /// No history.
    pub const NONE: Self = Self {
        history: HistoryTexel::EMPTY,
        validity: 0.0,
    };
}

/// Taps whose summed weight is below this are a disocclusion.
pub const MIN_VALIDITY: f32 = 1.0e-3;

/// How well the previous G-buffer texel `seen`, whose hit is `seen_point`, agrees with the surface
/// at `point` (the sky when `sky`) with normal `normal`, `distance` from the previous camera; in [0, 1].
#[inline]
#[must_use]
pub fn tap_agreement(
    sky: bool,
    point: Vec3,
    normal: Vec3,
    distance: f32,
    seen: &GBufferTexel,
    seen_point: Vec3,
) -> f32 {
    if sky || seen.is_sky() {
        return if sky && seen.is_sky() { 1.0 } else { 0.0 };
    }
    let off_plane = abs((point - seen_point).dot(seen.normal()));
    let plane = exp2(-40.0 * off_plane / distance.max(f32::MIN_POSITIVE));
    let facing = ((normal.dot(seen.normal()) - 0.75) / 0.2).clamp(0.0, 1.0);
    plane * facing
}

/// The previous history of pixel (`x`, `y`) of `frame`, reprojected ([`TemporalParams`] says where the
/// previous camera was and whether there is a previous frame at all). `gbuffer` is this frame's,
/// `previous_gbuffer` and `previous_history` the previous frame's (`previous_size` pixels each).
#[must_use]
pub fn reproject_history(
    frame: &FrameParams,
    temporal: &TemporalParams,
    gbuffer: &[GBufferTexel],
    previous_gbuffer: &[GBufferTexel],
    previous_history: &[HistoryTexel],
    x: u32,
    y: u32,
) -> Reprojected {
    if temporal.flags & TEMPORAL_HISTORY_VALID == 0 {
        return Reprojected::NONE;
    }
    let [pw, ph] = temporal.previous_size;
    let p = (y * frame.width + x) as usize;
    if temporal.flags & TEMPORAL_CAMERA_MOVED == 0 && pw == frame.width && ph == frame.height {
        // The same rays as last frame: the history is this pixel's own, without a bilinear blur.
        return Reprojected {
            history: previous_history[p],
            validity: 1.0,
        };
    }
    let g = gbuffer[p];
    let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let ray = frame.camera.generate_ray(centre, frame.width, frame.height);
    let previous_position = vec3_from(temporal.previous_camera.position);
    let sky = g.is_sky();
    let point = ray.origin + ray.direction * g.distance();
    let offset = if sky {
        ray.direction
    } else {
        point - previous_position
    };
    let distance = offset.length();
    let film = temporal.previous_camera.film_position(offset, pw, ph);
    if !(film.z > 0.0) {
        return Reprojected::NONE;
    }
    // Bilinear taps around the film position (texel centres at half-integers).
    let fx = film.x - 0.5;
    let fy = film.y - 0.5;
    if !(fx > -1.0 && fy > -1.0 && fx < pw as f32 && fy < ph as f32) {
        return Reprojected::NONE;
    }
    let x0 = floor(fx);
    let y0 = floor(fy);
    let tx = fx - x0;
    let ty = fy - y0;
    let normal = g.normal();
    let mut sum = HistoryTexel::EMPTY;
    let mut total = 0.0f32;
    let mut k = 0u32;
    while k < 4 {
        let dx = k & 1;
        let dy = k >> 1;
        let ix = x0 as i32 + dx as i32;
        let iy = y0 as i32 + dy as i32;
        let wx = if dx == 0 { 1.0 - tx } else { tx };
        let wy = if dy == 0 { 1.0 - ty } else { ty };
        if ix >= 0 && iy >= 0 && (ix as u32) < pw && (iy as u32) < ph {
            let q = (iy as u32 * pw + ix as u32) as usize;
            let seen = previous_gbuffer[q];
            let tap_centre = Vec2::new(ix as f32 + 0.5, iy as f32 + 0.5);
            let tap_ray = temporal.previous_camera.generate_ray(tap_centre, pw, ph);
            let seen_point = tap_ray.origin + tap_ray.direction * seen.distance();
            let agreement = tap_agreement(sky, point, normal, distance, &seen, seen_point);
            let w = wx * wy * agreement;
            if w > 0.0 {
                sum = sum.add_scaled(&previous_history[q], w);
                total += w;
            }
        }
        k += 1;
    }
    if !(total >= MIN_VALIDITY) {
        return Reprojected::NONE;
    }
    let mut history = sum.scaled(1.0 / total);
    if total > SHARP_VALIDITY {
        sharpen(
            &mut history,
            previous_gbuffer,
            previous_history,
            [pw, ph],
            [x0, y0],
            [tx, ty],
        );
    }
    Reprojected {
        history,
        validity: total.min(1.0),
    }
}

/// Bilinear validity above which the colour and moments are resampled with Catmull-Rom instead
/// (every bilinear tap agrees with the surface).
pub const SHARP_VALIDITY: f32 = 0.95;

/// Catmull-Rom weights of the four taps around `t` in [0, 1) (taps at -1, 0, 1, 2).
#[inline]
#[must_use]
fn catmull_rom(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        -0.5 * t3 + t2 - 0.5 * t,
        1.5 * t3 - 2.5 * t2 + 1.0,
        -1.5 * t3 + 2.0 * t2 + 0.5 * t,
        0.5 * t3 - 0.5 * t2,
    ]
}

/// Replaces `history`'s colour and luminance moments (bilinear so far) with a Catmull-Rom resampling of
/// the 4x4 texels around the bilinear taps (`origin` the top-left bilinear tap, `t` the fractions),
/// where all sixteen lie on the image and on the same surface as the tap nearest the point (distance
/// within 5 %, normals within about 25 degrees). Repeated bilinear resampling blurs the history a little
/// every frame the camera moves (the usual TAA blur, worst on sharp textures); the sharper kernel
/// keeps it. Its overshoot is cut at zero here and by the neighbourhood clamp after.
fn sharpen(
    history: &mut HistoryTexel,
    previous_gbuffer: &[GBufferTexel],
    previous_history: &[HistoryTexel],
    size: [u32; 2],
    origin: [f32; 2],
    t: [f32; 2],
) {
    let (x0, y0) = (origin[0] as i32 - 1, origin[1] as i32 - 1);
    if x0 < 0 || y0 < 0 || x0 + 3 >= size[0] as i32 || y0 + 3 >= size[1] as i32 {
        return;
    }
    let near = |dx: f32| if dx < 0.5 { 1 } else { 2 };
    let centre = (((y0 + near(t[1])) as u32) * size[0] + (x0 + near(t[0])) as u32) as usize;
    let reference = previous_gbuffer[centre];
    let wx = catmull_rom(t[0]);
    let wy = catmull_rom(t[1]);
    let mut colour = Vec3::ZERO;
    let mut moments = Vec2::ZERO;
    let mut k = 0u32;
    while k < 16 {
        let (i, j) = (k % 4, k / 4);
        let q = (((y0 as u32) + j) * size[0] + (x0 as u32) + i) as usize;
        let seen = previous_gbuffer[q];
        let same_sky = seen.is_sky() == reference.is_sky();
        let same_surface = reference.is_sky()
            || (abs(seen.distance() - reference.distance()) <= 0.05 * reference.distance()
                && seen.normal().dot(reference.normal()) >= 0.9);
        if !(same_sky && same_surface) {
            return;
        }
        let w = wx[i as usize] * wy[j as usize];
        let h = previous_history[q];
        colour += vec3_from(h.mean) * w;
        moments += Vec2::new(h.moments[0], h.moments[1]) * w;
        k += 1;
    }
    let colour = colour.max(Vec3::ZERO);
    let first = moments.x.max(0.0);
    history.mean = [colour.x, colour.y, colour.z, history.mean[3]];
    history.moments[0] = first;
    history.moments[1] = moments.y.max(first * first);
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::camera::Camera;
    use crate::foveation::{FoveationParams, FILL_BILINEAR};
    use crate::integrator::IntegratorSettings;

    const W: u32 = 32;
    const H: u32 = 24;

    fn frame(eye: Vec3) -> FrameParams {
        FrameParams {
            camera: Camera::look_at(eye, eye + Vec3::NEG_Z, Vec3::Y, 0.8, W as f32 / H as f32),
            foveation: FoveationParams::uniform(1),
            integrator: IntegratorSettings::default(),
            width: W,
            height: H,
            frame_index: 0,
            seed: 0,
        }
    }

    /// The G-buffer of a wall at z = -5 facing +z (analytic).
    fn wall(frame: &FrameParams) -> Vec<GBufferTexel> {
        let mut g = Vec::new();
        for y in 0..H {
            for x in 0..W {
                let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let ray = frame.camera.generate_ray(c, W, H);
                let t = (ray.origin.z + 5.0) / -ray.direction.z;
                g.push(GBufferTexel {
                    normal_distance: [0.0, 0.0, 1.0, t],
                    albedo: [1.0; 4],
                });
            }
        }
        g
    }

    /// A history whose texels hold their own film position (a linear function, which bilinear taps
    /// reproduce exactly).
    fn film_positions() -> Vec<HistoryTexel> {
        let mut h = Vec::new();
        for y in 0..H {
            for x in 0..W {
                h.push(HistoryTexel {
                    mean: [x as f32 + 0.5, y as f32 + 0.5, 0.0, 1.0],
                    moments: [0.0, 0.0, 1.0, 1.0],
                    fill: [0.0; 4],
                });
            }
        }
        h
    }

    #[test]
    fn a_moved_camera_finds_the_surface_where_it_was() {
        let previous = frame(Vec3::ZERO);
        let current = frame(Vec3::new(0.13, -0.07, 0.2));
        let temporal =
            TemporalParams::after(Some((previous.camera, [W, H])), &current, FILL_BILINEAR);
        assert_ne!(temporal.flags & TEMPORAL_CAMERA_MOVED, 0);
        let (g, g_prev, h_prev) = (wall(&current), wall(&previous), film_positions());
        let mut interior = 0;
        for y in 0..H {
            for x in 0..W {
                let r = reproject_history(&current, &temporal, &g, &g_prev, &h_prev, x, y);
                let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let ray = current.camera.generate_ray(c, W, H);
                let point = ray.origin + ray.direction * g[(y * W + x) as usize].distance();
                let want = previous.camera.film_position(point, W, H);
                let inside = want.x > 1.0
                    && want.y > 1.0
                    && want.x < W as f32 - 1.0
                    && want.y < H as f32 - 1.0;
                if inside {
                    interior += 1;
                    assert!(r.validity > 0.99, "({x}, {y}): {r:?}");
                    assert!(
                        (r.history.mean[0] - want.x).abs() < 2e-3,
                        "({x}, {y}) {r:?} {want}"
                    );
                    assert!(
                        (r.history.mean[1] - want.y).abs() < 2e-3,
                        "({x}, {y}) {r:?} {want}"
                    );
                }
            }
        }
        assert!(interior > 300, "{interior}");
    }

    #[test]
    fn a_surface_that_was_hidden_has_no_history() {
        let previous = frame(Vec3::ZERO);
        let current = frame(Vec3::new(0.1, 0.0, 0.0));
        let temporal =
            TemporalParams::after(Some((previous.camera, [W, H])), &current, FILL_BILINEAR);
        let g = wall(&current);
        // Last frame something nearer covered the view.
        let mut g_prev = wall(&previous);
        for t in &mut g_prev {
            t.normal_distance[3] = 2.0;
        }
        let r = reproject_history(&current, &temporal, &g, &g_prev, &film_positions(), 16, 12);
        assert_eq!(r, Reprojected::NONE);
        // And a sky pixel never takes a surface's history.
        let mut sky = g.clone();
        sky[12 * W as usize + 16] = GBufferTexel::SKY;
        let r = reproject_history(
            &current,
            &temporal,
            &sky,
            &wall(&previous),
            &film_positions(),
            16,
            12,
        );
        assert_eq!(r, Reprojected::NONE);
    }

    #[test]
    fn a_resting_camera_reads_its_own_texel() {
        let f = frame(Vec3::ZERO);
        let temporal = TemporalParams::after(Some((f.camera, [W, H])), &f, FILL_BILINEAR);
        assert_eq!(temporal.flags, TEMPORAL_HISTORY_VALID);
        let h = film_positions();
        let r = reproject_history(&f, &temporal, &wall(&f), &wall(&f), &h, 5, 7);
        assert_eq!(r.history, h[(7 * W + 5) as usize]);
        let none = TemporalParams::after(None, &f, FILL_BILINEAR);
        assert_eq!(
            reproject_history(&f, &none, &wall(&f), &wall(&f), &h, 5, 7),
            Reprojected::NONE
        );
    }
}
