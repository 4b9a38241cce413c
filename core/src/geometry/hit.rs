//! Where a ray hit the scene: its distance, its triangle and the barycentrics there.
use crate::scene::INVALID_INDEX;

/// The closest hit of a ray: `triangle` indexes [`GeometryArrays::triangle_info`](crate::scene::GeometryArrays::triangle_info) (BVH leaf order) and is
/// [`INVALID_INDEX`] on a miss; `b1`, `b2` are the barycentrics of `v1`, `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub b1: f32,
    pub b2: f32,
}

impl Hit {
    /// No hit (`t` infinite).
    #[inline]
    #[must_use]
    pub fn miss() -> Self {
        Self {
            t: f32::INFINITY,
            triangle: INVALID_INDEX,
            b1: 0.0,
            b2: 0.0,
        }
    }

    /// Whether this is a hit.
    #[inline]
    #[must_use]
    pub fn is_hit(&self) -> bool {
        self.triangle != INVALID_INDEX
    }
}
