//! The pinhole camera: primary rays through jittered film positions.
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::geometry::Ray;
use crate::math::{pack_vec3, vec3_from};

/// A pinhole camera in the GPU layout (64 bytes). `right` and `up` are pre-scaled so that the film spans
/// `[-1, 1]` in both axes: `|up| = tan(fov_y / 2)`, `|right| = |up| · aspect`. The ray through film
/// position `(x, y)` runs along `forward + x · right + y · up`: `forward` is the direction through the
/// film's centre, which is the optical axis for a symmetric frustum ([`Camera::look_at`]) and leans
/// off it for an asymmetric one ([`Camera::from_fov_angles`], a headset's eye).
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
        let (forward, right, up) = Self::basis(forward, up_hint);
        let half_height = crate::math::float::tan(0.5 * fov_y_radians);
        let half_width = half_height * aspect;
        Self {
            position: pack_vec3(eye, 0.0),
            forward: pack_vec3(forward, 0.0),
            right: pack_vec3(right * half_width, 0.0),
            up: pack_vec3(up * half_height, 0.0),
        }
    }

    /// The unit view direction, right and up vectors of a camera looking along `forward` with
    /// `up_hint` roughly up (any perpendicular where they are parallel).
    fn basis(forward: Vec3, up_hint: Vec3) -> (Vec3, Vec3, Vec3) {
        let forward = forward.normalize_or(Vec3::NEG_Z);
        let mut right = forward.cross(up_hint);
        if right.length_squared() < 1e-12 {
            // Looking straight along the up hint: pick any perpendicular.
            right = forward.any_orthonormal_vector();
        }
        let right = right.normalize();
        (forward, right, right.cross(forward))
    }

    /// A camera at `eye` looking along `forward` whose frustum is given by four angles in radians, as
    /// OpenXR's `XrFovf` gives an eye's: `left` and `down` negative, `right` and `up` positive for a
    /// frustum around the view direction; they need not be symmetric (a headset's eyes are not).
    /// `angles` is `[left, right, up, down]`; each must lie in (-π/2, π/2), with `left < right`
    /// and `down < up`.
    #[must_use]
    pub fn from_fov_angles(eye: Vec3, forward: Vec3, up_hint: Vec3, angles: [f32; 4]) -> Self {
        let tan = crate::math::float::tan;
        let (left, right) = (tan(angles[0]), tan(angles[1]));
        let (up, down) = (tan(angles[2]), tan(angles[3]));
        let (axis, right_unit, up_unit) = Self::basis(forward, up_hint);
        let (centre_x, half_width) = (0.5 * (right + left), 0.5 * (right - left));
        let (centre_y, half_height) = (0.5 * (up + down), 0.5 * (up - down));
        Self {
            position: pack_vec3(eye, 0.0),
            forward: pack_vec3(axis + right_unit * centre_x + up_unit * centre_y, 0.0),
            right: pack_vec3(right_unit * half_width, 0.0),
            up: pack_vec3(up_unit * half_height, 0.0),
        }
    }

    /// The same camera moved `offset` along its right vector (negative: to the left), its frustum
    /// unchanged: the eye of a stereo pair with parallel view directions, as a headset's are.
    #[must_use]
    pub fn moved_sideways(&self, offset: f32) -> Self {
        let shift = vec3_from(self.right).normalize_or_zero() * offset;
        Self {
            position: pack_vec3(vec3_from(self.position) + shift, 0.0),
            ..*self
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
        let right2 = right.length_squared().max(f32::MIN_POSITIVE);
        let up2 = up.length_squared().max(f32::MIN_POSITIVE);
        // `right` and `up` are orthogonal; `forward` leans off the optical axis by the frustum's
        // asymmetry (zero for a symmetric one). offset = t · (forward + ndc_x · right + ndc_y · up).
        let lean_x = forward.dot(right) / right2;
        let lean_y = forward.dot(up) / up2;
        let axis = forward - right * lean_x - up * lean_y;
        let axis2 = axis.length_squared().max(f32::MIN_POSITIVE);
        // t · |axis|² along the axis; `inv` = 1 / t.
        let along = offset.dot(axis);
        let inv = if along > 0.0 { axis2 / along } else { 0.0 };
        let ndc_x = offset.dot(right) * inv / right2 - lean_x;
        let ndc_y = offset.dot(up) * inv / up2 - lean_y;
        Vec3::new(
            0.5 * (ndc_x + 1.0) * width as f32,
            0.5 * (1.0 - ndc_y) * height as f32,
            along / crate::math::float::sqrt(axis2),
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

    #[test]
    fn symmetric_angles_give_the_look_at_camera() {
        let (fov_y, aspect) = (0.8f32, 1.5f32);
        let half_y = 0.5 * fov_y;
        let half_x = (half_y.tan() * aspect).atan();
        let eye = Vec3::new(1.0, 2.0, 3.0);
        let forward = Vec3::new(-0.3, 0.1, -1.0);
        let a = Camera::from_forward(eye, forward, Vec3::Y, fov_y, aspect);
        let b = Camera::from_fov_angles(eye, forward, Vec3::Y, [-half_x, half_x, half_y, -half_y]);
        for (u, v) in [(a.forward, b.forward), (a.right, b.right), (a.up, b.up)] {
            assert!((vec3_from(u) - vec3_from(v)).length() < 1e-6, "{u:?} {v:?}");
        }
    }

    #[test]
    fn asymmetric_frustum_spans_its_angles_and_film_position_inverts_it() {
        // A left eye of a headset: more of the view to the left and below.
        let angles = [-0.9f32, 0.7, 0.75, -0.85];
        let cam = Camera::from_fov_angles(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, angles);
        let (w, h) = (160u32, 120u32);
        let angle_x = |d: Vec3| d.x.atan2(-d.z);
        let angle_y = |d: Vec3| d.y.atan2(-d.z);
        let left = cam.generate_ray(Vec2::new(0.0, 60.0), w, h).direction;
        let right = cam.generate_ray(Vec2::new(160.0, 60.0), w, h).direction;
        let top = cam.generate_ray(Vec2::new(80.0, 0.0), w, h).direction;
        let bottom = cam.generate_ray(Vec2::new(80.0, 120.0), w, h).direction;
        assert!(
            (angle_x(left) - angles[0]).abs() < 1e-5,
            "{}",
            angle_x(left)
        );
        assert!((angle_x(right) - angles[1]).abs() < 1e-5);
        assert!((angle_y(top) - angles[2]).abs() < 1e-5);
        assert!((angle_y(bottom) - angles[3]).abs() < 1e-5);
        for (x, y) in [
            (0.5f32, 0.5f32),
            (159.5, 119.5),
            (83.25, 12.75),
            (40.0, 100.0),
        ] {
            let ray = cam.generate_ray(Vec2::new(x, y), w, h);
            let p = cam.film_position(ray.direction * 3.0, w, h);
            assert!(
                (p.x - x).abs() < 1e-3 && (p.y - y).abs() < 1e-3,
                "{p} for ({x}, {y})"
            );
            // The depth is the distance along the optical axis, -z here.
            assert!((p.z - 3.0 * -ray.direction.z).abs() < 1e-4, "{p}");
        }
        assert!(cam.film_position(Vec3::Z, w, h).z < 0.0, "behind the eye");
    }

    #[test]
    fn a_sideways_eye_keeps_the_frustum() {
        let cam = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 1.0, 1.6);
        let eye = cam.moved_sideways(-0.032);
        assert!((vec3_from(eye.position) - Vec3::new(-0.032, 0.0, 0.0)).length() < 1e-7);
        assert_eq!(
            (eye.forward, eye.right, eye.up),
            (cam.forward, cam.right, cam.up)
        );
    }
}
