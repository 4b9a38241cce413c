//! The pinhole camera: primary rays through jittered film positions.
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::geometry::Ray;
use crate::math::{pack_vec3, vec3_from};

/// A pinhole camera in the GPU layout (64 bytes). `right` and `up` are pre-scaled so that the film spans
/// `[-1, 1]` in both axes: `|up| = tan(fov_y / 2)`, `|right| = |up| · aspect`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Camera {
    pub position: [f32; 4],
    pub forward: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
}

impl Camera {
    /// A camera at `eye` looking at `target` with vertical field of view `fov_y_radians` on a film of
    /// aspect ratio `aspect` (width / height). `up_hint` need not be orthogonal to the view direction.
    #[must_use]
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up_hint: Vec3,
        fov_y_radians: f32,
        aspect: f32,
    ) -> Self {
        let forward = (target - eye).normalize_or(Vec3::NEG_Z);
        Self::from_forward(eye, forward, up_hint, fov_y_radians, aspect)
    }

    /// A camera at `eye` looking along `forward` (see [`Camera::look_at`]).
    #[must_use]
    pub fn from_forward(
        eye: Vec3,
        forward: Vec3,
        up_hint: Vec3,
        fov_y_radians: f32,
        aspect: f32,
    ) -> Self {
        let forward = forward.normalize_or(Vec3::NEG_Z);
        let mut right = forward.cross(up_hint);
        if right.length_squared() < 1e-12 {
            // Looking straight along the up hint: pick any perpendicular.
            right = forward.any_orthonormal_vector();
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let half_height = crate::math::float::tan(0.5 * fov_y_radians);
        let half_width = half_height * aspect;
        Self {
            position: pack_vec3(eye, 0.0),
            forward: pack_vec3(forward, 0.0),
            right: pack_vec3(right * half_width, 0.0),
            up: pack_vec3(up * half_height, 0.0),
        }
    }

    /// The primary ray through continuous film position `pixel` (in pixels, (0, 0) the top-left corner of the
    /// image, pixel centres at half-integers) of a `width` × `height` film.
    #[inline]
    #[must_use]
    pub fn generate_ray(&self, pixel: Vec2, width: u32, height: u32) -> Ray {
        let ndc_x = 2.0 * pixel.x / width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * pixel.y / height as f32;
        let direction =
            vec3_from(self.forward) + vec3_from(self.right) * ndc_x + vec3_from(self.up) * ndc_y;
        Ray::new(vec3_from(self.position), direction.normalize())
    }

    /// The inverse of [`Camera::generate_ray`]: where the ray towards `offset` (a direction from the
    /// camera's position, or a point minus the position; need not be unit) crosses the film of a
    /// `width` × `height` image, as (film x, film y, depth along `forward`). A point behind the camera has a
    /// depth `<= 0` and its film position is meaningless.
    #[inline]
    #[must_use]
    pub fn film_position(&self, offset: Vec3, width: u32, height: u32) -> Vec3 {
        let forward = vec3_from(self.forward);
        let right = vec3_from(self.right);
        let up = vec3_from(self.up);
        let depth = offset.dot(forward);
        // offset = depth · (forward + ndc_x · right + ndc_y · up), the three axes orthogonal.
        let inv = if depth > 0.0 { 1.0 / depth } else { 0.0 };
        let ndc_x = offset.dot(right) * inv / right.length_squared().max(f32::MIN_POSITIVE);
        let ndc_y = offset.dot(up) * inv / up.length_squared().max(f32::MIN_POSITIVE);
        Vec3::new(
            0.5 * (ndc_x + 1.0) * width as f32,
            0.5 * (1.0 - ndc_y) * height as f32,
            depth,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_forward_and_corners_span_the_fov() {
        let fov = 60f32.to_radians();
        let cam = Camera::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::Y, fov, 2.0);
        let r = cam.generate_ray(Vec2::new(50.0, 25.0), 100, 50);
        assert!((r.direction - Vec3::NEG_Z).length() < 1e-6);
        let top = cam.generate_ray(Vec2::new(50.0, 0.0), 100, 50);
        let angle = top.direction.angle_between(Vec3::NEG_Z);
        assert!((angle - fov / 2.0).abs() < 1e-5);
        assert!(top.direction.y > 0.0, "top of the image looks up");
        let right = cam.generate_ray(Vec2::new(100.0, 25.0), 100, 50);
        assert!(right.direction.x > 0.0, "right of the image looks right");
    }

    #[test]
    fn film_position_inverts_generate_ray() {
        let cam = Camera::look_at(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-2.0, 0.5, -4.0),
            Vec3::Y,
            0.9,
            1.7,
        );
        for (x, y) in [
            (0.5f32, 0.5f32),
            (170.0, 100.0),
            (83.25, 12.75),
            (169.5, 0.0),
        ] {
            let ray = cam.generate_ray(Vec2::new(x, y), 170, 100);
            let p = cam.film_position(ray.direction * 7.5, 170, 100);
            assert!(
                (p.x - x).abs() < 1e-3 && (p.y - y).abs() < 1e-3,
                "{p} for ({x}, {y})"
            );
            assert!(p.z > 0.0);
        }
        let behind = cam.film_position(-vec3_from(cam.forward), 170, 100);
        assert!(behind.z < 0.0);
    }
}
