//! Orthonormal frames for moving directions between world space and a local shading space whose `z` axis
//! is the normal.
use glam::Vec3;

/// An orthonormal basis (`x`, `y`, `z`), `z` the shading normal.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// A frame around unit `n`, branchless and continuous except on a measure-zero set (Duff et al. 2017,
    /// "Building an Orthonormal Basis, Revisited").
    #[inline]
    #[must_use]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { x, y, z: n }
    }

    /// A frame around unit `n` whose `x` axis follows `tangent` projected onto the tangent plane
    /// (Gram-Schmidt); falls back to [`Frame::from_normal`] when `tangent` is (nearly) parallel to `n`.
    #[inline]
    #[must_use]
    pub fn from_normal_tangent(n: Vec3, tangent: Vec3) -> Self {
        let t = tangent - n * n.dot(tangent);
        let len2 = t.length_squared();
        if !(len2 > 1e-12) {
            return Self::from_normal(n);
        }
        let x = t * (1.0 / super::float::sqrt(len2));
        Self {
            x,
            y: n.cross(x),
            z: n,
        }
    }

    /// World to local.
    #[inline]
    #[must_use]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    /// Local to world.
    #[inline]
    #[must_use]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal() {
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(1e-7, 0.0, -1.0).normalize(),
        ];
        for n in normals {
            let f = Frame::from_normal(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5);
            assert!((f.y.length() - 1.0).abs() < 1e-5);
            assert!(
                f.x.dot(f.y).abs() < 1e-5 && f.x.dot(n).abs() < 1e-5 && f.y.dot(n).abs() < 1e-5
            );
            let v = Vec3::new(0.2, -0.7, 0.5);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
