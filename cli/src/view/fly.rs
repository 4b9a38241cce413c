//! Fly-through camera controls for the live viewer.
//!
//! Right-handed coordinates with a configurable world up (usually +Y). The
//! view direction is stored as yaw (a right-hand-rule rotation about world up,
//! so turning right decreases it) and pitch (elevation above the horizontal
//! plane, clamped to ±89°). With +Y up, yaw 0 and pitch 0 look along -Z.

use glam::Vec3;

/// Largest pitch magnitude, in degrees.
const MAX_PITCH_DEGREES: f32 = 89.0;
/// Smallest movement speed, in scene units per second.
const MIN_SPEED: f32 = 1e-4;
/// Largest movement speed, in scene units per second.
const MAX_SPEED: f32 = 1e7;
/// Smallest initial speed derived from the scene size.
const MIN_INITIAL_SPEED: f32 = 1e-3;
/// Longest time step that [`FlyCamera::update`] integrates, in seconds.
const MAX_DT_SECONDS: f32 = 0.25;
/// Speed multiplier while [`Movement::fast`] is held.
const FAST_MULTIPLIER: f32 = 4.0;
/// Field of view used when the given one is not finite.
const DEFAULT_FOV_Y_DEGREES: f32 = 45.0;

/// A camera basis ready to be turned into the renderer's camera type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// Eye position.
    pub eye: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit world up; not necessarily perpendicular to `forward`.
    pub up_hint: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
}

/// Which movement keys are held.
///
/// W/S forward/back, A/D strafe left/right, E up / Q down along world up,
/// Shift for fast (4x) movement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Movement {
    /// Move along the view direction (W).
    pub forward: bool,
    /// Move against the view direction (S).
    pub back: bool,
    /// Strafe left (A).
    pub left: bool,
    /// Strafe right (D).
    pub right: bool,
    /// Move along world up (E).
    pub up: bool,
    /// Move against world up (Q).
    pub down: bool,
    /// Move four times faster (Shift).
    pub fast: bool,
}

impl Movement {
    /// Whether any direction key is held (ignores `fast`).
    #[must_use]
    #[cfg(test)]
    pub fn any(&self) -> bool {
        self.forward || self.back || self.left || self.right || self.up || self.down
    }
}

/// A free-flying camera driven by keyboard movement and mouse look.
#[derive(Clone, Debug, PartialEq)]
pub struct FlyCamera {
    position: Vec3,
    /// Radians, right-hand rule about `world_up`, in (-π, π].
    yaw: f32,
    /// Radians, clamped to ±89°.
    pitch: f32,
    /// Unit world up.
    world_up: Vec3,
    fov_y_degrees: f32,
    /// Scene units per second.
    speed: f32,
}

/// `world_up` normalised, or +Y when it is zero or not finite.
fn sanitize_up(world_up: Vec3) -> Vec3 {
    let up = world_up.normalize_or_zero();
    if up == Vec3::ZERO || !up.is_finite() {
        Vec3::Y
    } else {
        up
    }
}

/// The horizontal directions at yaw 0: `(forward0, right0)`, both unit and
/// perpendicular to `up` (which must be unit). `forward0` is -Z projected onto
/// the horizontal plane (-Y when up is ±Z), `right0 = forward0 × up`.
fn reference_frame(up: Vec3) -> (Vec3, Vec3) {
    let mut forward0 = Vec3::ZERO;
    for candidate in [Vec3::NEG_Z, Vec3::NEG_Y, Vec3::X] {
        forward0 = (candidate - up * candidate.dot(up)).normalize_or_zero();
        if forward0 != Vec3::ZERO {
            break;
        }
    }
    let right0 = forward0.cross(up).normalize_or_zero();
    (forward0, right0)
}

fn max_pitch() -> f32 {
    MAX_PITCH_DEGREES.to_radians()
}

/// Wraps an angle into (-π, π].
fn wrap_angle(angle: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let wrapped = (angle + PI).rem_euclid(TAU) - PI;
    if wrapped <= -PI {
        wrapped + TAU
    } else {
        wrapped
    }
}

impl FlyCamera {
    /// A camera at `eye` looking at `target`.
    ///
    /// A zero or non-finite `world_up` falls back to +Y; `eye == target` (or a
    /// non-finite direction) falls back to yaw 0, pitch 0 (-Z with +Y up). A
    /// direction steeper than ±89° is clamped. A non-finite `eye` becomes the
    /// origin, a non-finite field of view 45°, and the field of view is clamped
    /// to 1°..=179°. The initial speed is `scene_diagonal / 8` units per second,
    /// at least 1e-3.
    #[must_use]
    pub fn new(
        eye: Vec3,
        target: Vec3,
        world_up: Vec3,
        fov_y_degrees: f32,
        scene_diagonal: f32,
    ) -> Self {
        let up = sanitize_up(world_up);
        let (forward0, right0) = reference_frame(up);
        let position = if eye.is_finite() { eye } else { Vec3::ZERO };
        let dir = (target - position).normalize_or_zero();
        let (yaw, pitch) = if dir == Vec3::ZERO || !dir.is_finite() {
            (0.0, 0.0)
        } else {
            let vertical = dir.dot(up);
            let horizontal = (dir - up * vertical).length();
            let yaw = (-dir.dot(right0)).atan2(dir.dot(forward0));
            let pitch = vertical.atan2(horizontal);
            (wrap_angle(yaw), pitch.clamp(-max_pitch(), max_pitch()))
        };
        let fov_y_degrees = if fov_y_degrees.is_finite() {
            fov_y_degrees.clamp(1.0, 179.0)
        } else {
            DEFAULT_FOV_Y_DEGREES
        };
        let speed = if scene_diagonal.is_finite() {
            (scene_diagonal / 8.0).clamp(MIN_INITIAL_SPEED, MAX_SPEED)
        } else {
            MIN_INITIAL_SPEED
        };
        Self {
            position,
            yaw,
            pitch,
            world_up: up,
            fov_y_degrees,
            speed,
        }
    }

    /// Unit horizontal view direction (perpendicular to world up).
    fn heading(&self) -> Vec3 {
        let (forward0, right0) = reference_frame(self.world_up);
        forward0 * self.yaw.cos() - right0 * self.yaw.sin()
    }

    /// Unit strafe-right direction, perpendicular to the view direction and
    /// world up.
    #[must_use]
    pub fn right(&self) -> Vec3 {
        let (forward0, right0) = reference_frame(self.world_up);
        right0 * self.yaw.cos() + forward0 * self.yaw.sin()
    }

    /// Unit view direction.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        let dir = self.heading() * self.pitch.cos() + self.world_up * self.pitch.sin();
        dir.normalize_or(self.heading())
    }

    /// The camera basis for rendering.
    #[must_use]
    pub fn pose(&self) -> CameraPose {
        CameraPose {
            eye: self.position,
            forward: self.forward(),
            up_hint: self.world_up,
            fov_y_degrees: self.fov_y_degrees,
        }
    }

    /// Moves the camera for `dt_seconds` (clamped to 0..=0.25 s) with the held
    /// `movement` keys at [`speed`](Self::speed) (4x with `fast`). Opposite keys
    /// cancel; the combined direction is normalised so diagonal movement is
    /// not faster. Returns whether the camera moved.
    pub fn update(&mut self, dt_seconds: f32, movement: &Movement) -> bool {
        let dt = if dt_seconds.is_finite() {
            dt_seconds.clamp(0.0, MAX_DT_SECONDS)
        } else {
            0.0
        };
        let axis = |plus: bool, minus: bool| f32::from(u8::from(plus)) - f32::from(u8::from(minus));
        let dir = self.forward() * axis(movement.forward, movement.back)
            + self.right() * axis(movement.right, movement.left)
            + self.world_up * axis(movement.up, movement.down);
        let dir = dir.normalize_or_zero();
        let multiplier = if movement.fast { FAST_MULTIPLIER } else { 1.0 };
        let step = dir * (self.speed * multiplier * dt);
        let next = self.position + step;
        if step == Vec3::ZERO || !next.is_finite() || next == self.position {
            return false;
        }
        self.position = next;
        true
    }

    /// Mouse look: `dx_pixels` to the right turns right, `dy_pixels` down
    /// looks down, each pixel turning by `radians_per_pixel`. Pitch is clamped
    /// to ±89°. Returns whether the view direction changed.
    pub fn look(&mut self, dx_pixels: f64, dy_pixels: f64, radians_per_pixel: f32) -> bool {
        let rate = f64::from(radians_per_pixel);
        let d_yaw = dx_pixels * rate;
        let d_pitch = dy_pixels * rate;
        if !d_yaw.is_finite() || !d_pitch.is_finite() {
            return false;
        }
        // Reduce large turns before narrowing to f32 to keep precision.
        let d_yaw = d_yaw.rem_euclid(std::f64::consts::TAU) as f32;
        let yaw = wrap_angle(self.yaw - d_yaw);
        let pitch = (f64::from(self.pitch) - d_pitch)
            .clamp(-f64::from(max_pitch()), f64::from(max_pitch())) as f32;
        let changed = yaw != self.yaw || pitch != self.pitch;
        self.yaw = yaw;
        self.pitch = pitch;
        changed
    }

    /// Scales the speed by `1.25^steps` (scroll wheel), clamped to
    /// 1e-4..=1e7 units per second. Non-finite `steps` are ignored.
    pub fn scroll(&mut self, steps: f32) {
        if !steps.is_finite() {
            return;
        }
        let speed = self.speed * 1.25f32.powf(steps);
        self.speed = if speed.is_nan() {
            self.speed
        } else {
            speed.clamp(MIN_SPEED, MAX_SPEED)
        };
    }

    /// Movement speed in scene units per second.
    #[must_use]
    pub fn speed(&self) -> f32 {
        self.speed
    }

    /// Eye position.
    #[must_use]
    #[cfg(test)]
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// Yaw in radians (right-hand rule about world up, in (-π, π]).
    #[must_use]
    #[cfg(test)]
    pub fn yaw(&self) -> f32 {
        self.yaw
    }

    /// Pitch in radians (positive looks up), within ±89°.
    #[must_use]
    #[cfg(test)]
    pub fn pitch(&self) -> f32 {
        self.pitch
    }

    /// Vertical field of view in degrees.
    #[must_use]
    pub fn fov_y_degrees(&self) -> f32 {
        self.fov_y_degrees
    }

    /// Restores position, orientation, field of view and speed from `other`
    /// (e.g. the start pose kept by the viewer).
    pub fn reset_to(&mut self, other: &FlyCamera) {
        self.clone_from(other);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    fn assert_close(a: Vec3, b: Vec3, tol: f32) {
        assert!(close(a, b, tol), "{a} vs {b}");
    }

    fn finite_pose(cam: &FlyCamera) {
        let pose = cam.pose();
        assert!(pose.eye.is_finite() && pose.forward.is_finite() && pose.up_hint.is_finite());
        assert!((pose.forward.length() - 1.0).abs() < 1e-5);
        assert!(pose.fov_y_degrees.is_finite() && cam.speed().is_finite());
    }

    #[test]
    fn pose_reproduces_eye_to_target_direction() {
        let ups = [Vec3::Y, Vec3::Z, Vec3::new(0.3, 1.0, -0.2), Vec3::NEG_X];
        let dirs = [
            Vec3::NEG_Z,
            Vec3::Z,
            Vec3::X,
            Vec3::NEG_X,
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-3.0, -1.0, 0.5),
            Vec3::new(0.2, -0.7, -4.0),
        ];
        for up in ups {
            for dir in dirs {
                let eye = Vec3::new(1.0, -2.0, 3.0);
                let cam = FlyCamera::new(eye, eye + dir * 5.0, up, 40.0, 10.0);
                let expected = dir.normalize();
                // Skip directions beyond the pitch clamp for this up vector.
                if expected.dot(up.normalize()).abs() > max_pitch().sin() {
                    continue;
                }
                let pose = cam.pose();
                assert_close(pose.forward, expected, 1e-5);
                assert_eq!(pose.eye, eye);
                assert_close(pose.up_hint, up.normalize(), 1e-6);
                assert_eq!(pose.fov_y_degrees, 40.0);
            }
        }
    }

    #[test]
    fn yaw_zero_looks_along_negative_z_with_y_up() {
        let cam = FlyCamera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 45.0, 8.0);
        assert!(cam.yaw().abs() < 1e-6 && cam.pitch().abs() < 1e-6);
        assert_close(cam.right(), Vec3::X, 1e-6);
        assert_eq!(cam.speed(), 1.0);
    }

    #[test]
    fn nearly_vertical_direction_is_clamped() {
        for sign in [1.0f32, -1.0] {
            let dir = Vec3::new(0.001, sign, -0.002);
            let cam = FlyCamera::new(Vec3::ZERO, dir, Vec3::Y, 45.0, 1.0);
            assert!((cam.pitch() - sign * max_pitch()).abs() < 1e-6);
            let f = cam.pose().forward;
            assert!((f.y - sign * max_pitch().sin()).abs() < 1e-5);
            // Heading preserved.
            let h = Vec3::new(dir.x, 0.0, dir.z).normalize();
            assert_close(Vec3::new(f.x, 0.0, f.z).normalize(), h, 1e-4);
        }
        // Exactly vertical: still finite, clamped.
        let cam = FlyCamera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 45.0, 1.0);
        finite_pose(&cam);
        assert!((cam.pitch() - max_pitch()).abs() < 1e-6);
    }

    #[test]
    fn degenerate_inputs_do_not_produce_nan() {
        let nan = Vec3::splat(f32::NAN);
        let inf = Vec3::splat(f32::INFINITY);
        let cases = [
            (Vec3::ONE, Vec3::ONE, Vec3::Y, 45.0, 1.0),
            (Vec3::ZERO, Vec3::NEG_Z, Vec3::ZERO, 45.0, 1.0),
            (Vec3::ZERO, Vec3::NEG_Z, nan, f32::NAN, f32::NAN),
            (nan, Vec3::X, Vec3::Y, f32::INFINITY, f32::INFINITY),
            (Vec3::ZERO, nan, Vec3::Y, -10.0, -5.0),
            (inf, Vec3::ZERO, inf, 0.0, 0.0),
            (Vec3::ZERO, Vec3::splat(f32::MAX), Vec3::Y, 45.0, f32::MAX),
        ];
        for (eye, target, up, fov, diag) in cases {
            let mut cam = FlyCamera::new(eye, target, up, fov, diag);
            finite_pose(&cam);
            let all = Movement {
                forward: true,
                right: true,
                up: true,
                fast: true,
                ..Movement::default()
            };
            cam.update(f32::NAN, &all);
            cam.update(f32::INFINITY, &all);
            cam.update(0.1, &all);
            cam.look(f64::NAN, 1.0, 0.01);
            cam.look(1e300, -1e300, f32::MAX);
            cam.look(3.0, 4.0, f32::NAN);
            cam.scroll(f32::NAN);
            cam.scroll(1e30);
            cam.scroll(-1e30);
            finite_pose(&cam);
        }
        // Fallback: eye == target looks along -Z with +Y up.
        let cam = FlyCamera::new(Vec3::ONE, Vec3::ONE, Vec3::ZERO, 45.0, 0.0);
        assert_close(cam.pose().forward, Vec3::NEG_Z, 1e-6);
        assert_eq!(cam.pose().up_hint, Vec3::Y);
        assert_eq!(cam.speed(), 1e-3);
    }

    #[test]
    fn forward_moves_along_view_direction() {
        let dir = Vec3::new(1.0, 0.5, -2.0);
        let mut cam = FlyCamera::new(Vec3::ZERO, dir, Vec3::Y, 45.0, 16.0);
        assert_eq!(cam.speed(), 2.0);
        let w = Movement {
            forward: true,
            ..Movement::default()
        };
        assert!(cam.update(0.1, &w));
        assert_close(cam.position(), dir.normalize() * 0.2, 1e-5);
        let s = Movement {
            back: true,
            ..Movement::default()
        };
        assert!(cam.update(0.1, &s));
        assert_close(cam.position(), Vec3::ZERO, 1e-5);
        // Fast is 4x; dt is clamped to 0.25 s.
        let fast = Movement { fast: true, ..w };
        assert!(cam.update(10.0, &fast));
        assert_close(cam.position(), dir.normalize() * 2.0, 1e-5);
    }

    #[test]
    fn strafe_is_perpendicular_and_vertical_is_along_up() {
        let up = Vec3::new(0.0, 0.0, 1.0);
        let dir = Vec3::new(1.0, 2.0, 0.7);
        let mut cam = FlyCamera::new(Vec3::ZERO, dir, up, 45.0, 8.0);
        let d = Movement {
            right: true,
            ..Movement::default()
        };
        assert!(cam.update(0.25, &d));
        let moved = cam.position();
        assert!((moved.length() - 0.25).abs() < 1e-5);
        assert!(moved.dot(cam.forward()).abs() < 1e-5);
        assert!(moved.dot(up).abs() < 1e-5);
        // Right-handed: forward × up points right.
        assert!(moved.dot(cam.forward().cross(up)) > 0.0);
        let a = Movement {
            left: true,
            ..Movement::default()
        };
        assert!(cam.update(0.25, &a));
        assert_close(cam.position(), Vec3::ZERO, 1e-5);

        let e = Movement {
            up: true,
            ..Movement::default()
        };
        assert!(cam.update(0.25, &e));
        assert_close(cam.position(), up * 0.25, 1e-6);
        let q = Movement {
            down: true,
            ..Movement::default()
        };
        assert!(cam.update(0.25, &q));
        assert_close(cam.position(), Vec3::ZERO, 1e-6);
    }

    #[test]
    fn no_movement_without_keys_zero_dt_or_cancelling_keys() {
        let mut cam = FlyCamera::new(Vec3::ZERO, Vec3::X, Vec3::Y, 45.0, 8.0);
        assert!(!cam.update(0.1, &Movement::default()));
        let w = Movement {
            forward: true,
            ..Movement::default()
        };
        assert!(!cam.update(0.0, &w));
        assert!(!cam.update(-1.0, &w));
        let cancel = Movement {
            forward: true,
            back: true,
            left: true,
            right: true,
            up: true,
            down: true,
            fast: true,
        };
        assert!(cancel.any());
        assert!(!cam.update(0.1, &cancel));
        assert_eq!(cam.position(), Vec3::ZERO);
    }

    #[test]
    fn look_turns_and_returns() {
        let mut cam = FlyCamera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 45.0, 8.0);
        let start = cam.forward();
        assert!(cam.look(100.0, 0.0, 0.002));
        // Turning right with +Y up and -Z forward swings towards +X.
        assert!(cam.forward().x > 0.0);
        assert!(cam.look(-100.0, 0.0, 0.002));
        assert_close(cam.forward(), start, 1e-6);
        // Dragging down looks down.
        assert!(cam.look(0.0, 50.0, 0.002));
        assert!(cam.forward().y < 0.0);
        assert!(cam.look(0.0, -50.0, 0.002));
        assert_close(cam.forward(), start, 1e-6);
        // Many full turns come back too.
        let turns = 10.0 * std::f64::consts::TAU / 0.002;
        cam.look(turns, 0.0, 0.002);
        cam.look(-turns, 0.0, 0.002);
        assert_close(cam.forward(), start, 1e-4);
        assert!(!cam.look(0.0, 0.0, 0.002));
    }

    #[test]
    fn pitch_clamps() {
        let mut cam = FlyCamera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 45.0, 8.0);
        assert!(cam.look(0.0, -1e6, 0.01));
        assert!((cam.pitch() - max_pitch()).abs() < 1e-6);
        assert!(!cam.look(0.0, -10.0, 0.01));
        assert!(cam.look(0.0, 1e6, 0.01));
        assert!((cam.pitch() + max_pitch()).abs() < 1e-6);
        finite_pose(&cam);
    }

    #[test]
    fn scroll_scales_and_clamps_speed() {
        let mut cam = FlyCamera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 45.0, 8.0);
        cam.scroll(1.0);
        assert!((cam.speed() - 1.25).abs() < 1e-6);
        cam.scroll(-2.0);
        assert!((cam.speed() - 0.8).abs() < 1e-6);
        cam.scroll(1000.0);
        assert_eq!(cam.speed(), 1e7);
        cam.scroll(-10_000.0);
        assert_eq!(cam.speed(), 1e-4);
    }

    #[test]
    fn reset_restores_start_pose() {
        let start = FlyCamera::new(Vec3::ONE, Vec3::ZERO, Vec3::Y, 45.0, 8.0);
        let mut cam = start.clone();
        cam.look(30.0, 20.0, 0.01);
        cam.scroll(3.0);
        cam.update(
            0.2,
            &Movement {
                forward: true,
                ..Movement::default()
            },
        );
        assert_ne!(cam, start);
        cam.reset_to(&start);
        assert_eq!(cam, start);
    }
}
