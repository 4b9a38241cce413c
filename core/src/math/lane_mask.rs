//! Bit masks of four-lane comparisons (bit `i` set where lane `i` compares true), for traversal's slab
//! test, child ordering and triangle blocks, and reading one lane by value.
//!
//! On the CPU these are glam's SIMD comparisons (one compare and one `movmskps`). On the GPU they are
//! written lane by lane: glam's scalar `BVec4A`, which its `Vec4` comparisons return there, builds each
//! lane's mask by indexing a two-entry local array with the boolean, and lavapipe turns every dynamically
//! indexed local array into a loop over its lanes. Both give the same bits.
use glam::{UVec4, Vec4};

/// Lane `k` (0 to 3) of `v`, read by value with selects: indexing a vector in place makes rust-gpu select
/// between pointers, which SPIR-V's logical addressing does not allow.
#[inline(always)]
#[must_use]
pub fn lane(v: Vec4, k: usize) -> f32 {
    if k == 0 {
        v.x
    } else if k == 1 {
        v.y
    } else if k == 2 {
        v.z
    } else {
        v.w
    }
}

/// Lane `k` (0 to 3) of `v`, read by value with selects, as [`lane`] does for floats.
#[inline(always)]
#[must_use]
pub fn lane_u32(v: UVec4, k: usize) -> u32 {
    if k == 0 {
        v.x
    } else if k == 1 {
        v.y
    } else if k == 2 {
        v.z
    } else {
        v.w
    }
}

/// Bit `i` set where `a[i] <= b[i]`.
#[inline(always)]
#[must_use]
pub fn le_mask(a: Vec4, b: Vec4) -> u32 {
    #[cfg(not(target_arch = "spirv"))]
    {
        a.cmple(b).bitmask()
    }
    #[cfg(target_arch = "spirv")]
    {
        u32::from(a.x <= b.x)
            | u32::from(a.y <= b.y) << 1
            | u32::from(a.z <= b.z) << 2
            | u32::from(a.w <= b.w) << 3
    }
}

/// Bit `i` set where `a[i] > b[i]`.
#[inline(always)]
#[must_use]
pub fn gt_mask(a: Vec4, b: Vec4) -> u32 {
    #[cfg(not(target_arch = "spirv"))]
    {
        a.cmpgt(b).bitmask()
    }
    #[cfg(target_arch = "spirv")]
    {
        u32::from(a.x > b.x)
            | u32::from(a.y > b.y) << 1
            | u32::from(a.z > b.z) << 2
            | u32::from(a.w > b.w) << 3
    }
}

/// Bit `i` set where `a[i] == b[i]`.
#[inline(always)]
#[must_use]
pub fn eq_mask(a: Vec4, b: Vec4) -> u32 {
    #[cfg(not(target_arch = "spirv"))]
    {
        a.cmpeq(b).bitmask()
    }
    #[cfg(target_arch = "spirv")]
    {
        u32::from(a.x == b.x)
            | u32::from(a.y == b.y) << 1
            | u32::from(a.z == b.z) << 2
            | u32::from(a.w == b.w) << 3
    }
}

/// `-v` in the lanes where `sign_of` is negative, `v` in the others (exact: only signs change).
#[inline(always)]
#[must_use]
pub fn negate_where_negative(v: Vec4, sign_of: Vec4) -> Vec4 {
    #[cfg(not(target_arch = "spirv"))]
    {
        Vec4::select(sign_of.cmplt(Vec4::ZERO), -v, v)
    }
    #[cfg(target_arch = "spirv")]
    {
        let pick = |v: f32, s: f32| if s < 0.0 { -v } else { v };
        Vec4::new(
            pick(v.x, sign_of.x),
            pick(v.y, sign_of.y),
            pick(v.z, sign_of.z),
            pick(v.w, sign_of.w),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane-by-lane forms (the GPU's) agree with glam's, NaN included.
    #[test]
    fn masks_match_lane_by_lane_comparisons() {
        let values = [-1.0, 0.0, -0.0, 1.0, f32::NAN, f32::INFINITY, 2.5];
        let lanes = |f: &dyn Fn(f32, f32) -> bool, a: Vec4, b: Vec4| -> u32 {
            (0..4).map(|i| u32::from(f(a[i], b[i])) << i).sum()
        };
        for (k, &x) in values.iter().enumerate() {
            let a = Vec4::new(
                x,
                values[(k + 1) % 7],
                values[(k + 3) % 7],
                values[(k + 5) % 7],
            );
            for &y in &values {
                let b = Vec4::new(y, x, values[(k + 2) % 7], y);
                assert_eq!(le_mask(a, b), lanes(&|p, q| p <= q, a, b));
                assert_eq!(gt_mask(a, b), lanes(&|p, q| p > q, a, b));
                assert_eq!(eq_mask(a, b), lanes(&|p, q| p == q, a, b));
                let negated = negate_where_negative(a, b);
                for i in 0..4 {
                    let expected = if b[i] < 0.0 { -a[i] } else { a[i] };
                    assert_eq!(negated[i].to_bits(), expected.to_bits());
                }
            }
        }
    }
}
