//! Closest-hit and any-hit traversal with a fixed-size stack.
//!
//! The node layout is [`BvhNode`]'s: children of an interior node are adjacent, so one index names both.
//! Both children's boxes are tested together and the nearer one is visited first; the farther one is pushed
//! with its entry distance and skipped when popped if a closer hit was found meanwhile.
//!
//! The slab test is made conservative so that it never culls a hit the watertight triangle test
//! ([`WatertightRay`]) reports (Woop et al. 2013, Sec. 4, "conservative traversal"): the entry and exit
//! distances are widened by `1 ± 2γ₃` (Ize 2013, "Robust BVH Ray Traversal"), and the boxes written by the
//! builder are themselves a few ulps larger than their triangles. Zero direction components are handled
//! without infinities or NaNs: their inverse is clamped to `±f32::MAX`, so `(bound - origin) * inv` is a
//! huge (or infinite) finite-signed number, and never `0 * ∞`.
use glam::Vec3A;

use crate::geometry::triangle::WatertightRay;
use crate::geometry::Ray;
use crate::material::alpha::is_cut_out;
use crate::scene::{BvhNode, SceneView, INVALID_INDEX, MATERIAL_ALPHA_CUTOUT};

/// Entries of the traversal stack. Traversal pushes at most one node per level, so trees must be shallower
/// than this; `fovea_scene::bvh::build_bvh` guarantees it.
pub const TRAVERSAL_STACK_SIZE: usize = 64;

/// γ₃ = 3u / (1 - 3u) with the unit roundoff u = 2⁻²⁴ (pbrt-v3 Sec. 3.9.1).
const GAMMA3: f32 = 3.0 * (f32::EPSILON * 0.5) / (1.0 - 3.0 * (f32::EPSILON * 0.5));
/// Scales the exit distance of a slab test up to cover its rounding errors (Ize 2013).
const ROUND_UP: f32 = 1.0 + 2.0 * GAMMA3;
/// Scales the (non-negative) entry distance of a slab test down.
const ROUND_DOWN: f32 = 1.0 - 2.0 * GAMMA3;

/// The closest hit of a ray: `triangle` indexes [`SceneView::triangles`] (BVH leaf order) and is
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

/// `1 / d`, clamped to `±f32::MAX` for zero and tiny `d` (whose true inverse overflows).
#[inline]
#[must_use]
fn safe_inverse(d: f32) -> f32 {
    if d.abs() >= f32::MIN_POSITIVE {
        1.0 / d
    } else if d < 0.0 {
        -f32::MAX
    } else {
        f32::MAX
    }
}

#[inline]
fn max3(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let ab = if a > b { a } else { b };
    let cd = if c > d { c } else { d };
    if ab > cd {
        ab
    } else {
        cd
    }
}

#[inline]
fn min3(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let ab = if a < b { a } else { b };
    let cd = if c < d { c } else { d };
    if ab < cd {
        ab
    } else {
        cd
    }
}

/// The per-ray part of the slab test.
#[derive(Clone, Copy)]
struct RayBox {
    // `Vec3A` is SIMD on the CPU and a plain vector in SPIR-V.
    origin: Vec3A,
    inv_dir: Vec3A,
}

impl RayBox {
    #[inline]
    fn new(ray: &Ray) -> Self {
        Self {
            origin: Vec3A::from(ray.origin),
            inv_dir: Vec3A::new(
                safe_inverse(ray.direction.x),
                safe_inverse(ray.direction.y),
                safe_inverse(ray.direction.z),
            ),
        }
    }

    /// The (conservative) entry distance of the ray into `node`'s box within `[0, t_max]`, or infinity
    /// if it misses the box in that interval.
    #[inline]
    fn entry(&self, node: &BvhNode, t_max: f32) -> f32 {
        let t0 = (Vec3A::from(node.bounds_min) - self.origin) * self.inv_dir;
        let t1 = (Vec3A::from(node.bounds_max) - self.origin) * self.inv_dir;
        // No NaN can arise (finite bounds, inverse clamped to ±f32::MAX), so the plain comparisons
        // below need none of `f32::min`'s NaN handling.
        let lo = Vec3A::select(t0.cmplt(t1), t0, t1);
        let hi = Vec3A::select(t0.cmplt(t1), t1, t0);
        let near = max3(lo.x, lo.y, lo.z, 0.0) * ROUND_DOWN;
        let far = min3(hi.x, hi.y, hi.z, t_max) * ROUND_UP;
        if near <= far {
            near
        } else {
            f32::INFINITY
        }
    }
}

/// Whether a candidate hit on `triangle` lies in a cut-out hole. Opaque materials cost one flag test.
#[inline]
#[must_use]
fn hit_is_cut_out(scene: &SceneView, triangle: u32, b1: f32, b2: f32) -> bool {
    let material = scene.triangle_info[triangle as usize].material;
    scene.materials[material as usize].flags & MATERIAL_ALPHA_CUTOUT != 0
        && is_cut_out(scene, triangle, b1, b2)
}

/// Shared traversal loop: the closest hit in `(0, t_max)`, or (with `any`) the first one found.
#[inline]
fn traverse(scene: &SceneView, ray: &Ray, t_max: f32, any: bool) -> Hit {
    let mut best = Hit::miss();
    if scene.nodes.is_empty() {
        return best;
    }
    let watertight = WatertightRay::new(ray);
    let ray_box = RayBox::new(ray);
    let mut closest = t_max;
    if ray_box.entry(&scene.nodes[0], closest) == f32::INFINITY {
        return best;
    }

    let mut stack_node = [0u32; TRAVERSAL_STACK_SIZE];
    let mut stack_t = [0.0f32; TRAVERSAL_STACK_SIZE];
    let mut stack_len = 0usize;
    let mut node_index = 0u32;
    loop {
        let node = scene.nodes[node_index as usize];
        let mut descend = false;
        if node.is_leaf() {
            let end = node.left_or_first + node.triangle_count;
            let mut i = node.left_or_first;
            while i < end {
                let h = watertight.intersect(&scene.triangles[i as usize], closest);
                if h.hit && !hit_is_cut_out(scene, i, h.b1, h.b2) {
                    closest = h.t;
                    best = Hit {
                        t: h.t,
                        triangle: i,
                        b1: h.b1,
                        b2: h.b2,
                    };
                    if any {
                        return best;
                    }
                }
                i += 1;
            }
        } else {
            let left = node.left_or_first;
            let t_left = ray_box.entry(&scene.nodes[left as usize], closest);
            let t_right = ray_box.entry(&scene.nodes[left as usize + 1], closest);
            let (near, t_near, far, t_far) = if t_left <= t_right {
                (left, t_left, left + 1, t_right)
            } else {
                (left + 1, t_right, left, t_left)
            };
            if t_near != f32::INFINITY {
                // The builder keeps trees shallower than the stack, so the guard never drops a node.
                if t_far != f32::INFINITY && stack_len < TRAVERSAL_STACK_SIZE {
                    stack_node[stack_len] = far;
                    stack_t[stack_len] = t_far;
                    stack_len += 1;
                }
                node_index = near;
                descend = true;
            }
        }
        if !descend {
            // Pop the next node that may still hold a closer hit.
            let mut found = false;
            while stack_len > 0 && !found {
                stack_len -= 1;
                if stack_t[stack_len] <= closest {
                    node_index = stack_node[stack_len];
                    found = true;
                }
            }
            if !found {
                return best;
            }
        }
    }
}

/// The closest hit of `ray` with `0 < t < t_max` over the scene's BVH, skipping alpha cut-out holes;
/// [`Hit::miss`] if there is none or the scene has no nodes.
#[must_use]
pub fn closest_hit(scene: &SceneView, ray: &Ray, t_max: f32) -> Hit {
    traverse(scene, ray, t_max, false)
}

/// Whether anything (other than alpha cut-out holes) blocks the open segment `(0, t_max)` of `ray`; for
/// shadow rays. Stops at the first hit found.
#[must_use]
pub fn any_hit(scene: &SceneView, ray: &Ray, t_max: f32) -> bool {
    traverse(scene, ray, t_max, true).is_hit()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use crate::math::pack_vec3;
    use crate::scene::{Material, SceneGlobals, TriangleInfo, TrianglePositions};

    fn tri(a: Vec3, b: Vec3, c: Vec3) -> TrianglePositions {
        TrianglePositions {
            v0: pack_vec3(a, 0.0),
            v1: pack_vec3(b, 0.0),
            v2: pack_vec3(c, 0.0),
        }
    }

    fn view<'a>(
        nodes: &'a [BvhNode],
        triangles: &'a [TrianglePositions],
        info: &'a [TriangleInfo],
        materials: &'a [Material],
    ) -> SceneView<'a> {
        SceneView {
            globals: SceneGlobals::default(),
            nodes,
            triangles,
            triangle_info: info,
            normals: &[],
            uvs: &[],
            materials,
            textures: &[],
            texels: &[],
            lights: &[],
            light_cdf: &[],
            triangle_light: &[],
            environment_texels: &[],
            environment_marginal_cdf: &[],
            environment_conditional_cdf: &[],
        }
    }

    /// Two unit quads' worth of triangles at z = 1 (material 1) and z = 2 (material 0) under one root and
    /// two leaves.
    fn two_layers() -> ([BvhNode; 3], [TrianglePositions; 2], [TriangleInfo; 2]) {
        let near = tri(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(3.0, -1.0, 1.0),
            Vec3::new(-1.0, 3.0, 1.0),
        );
        let far = tri(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(-1.0, 3.0, 2.0),
            Vec3::new(3.0, -1.0, 2.0),
        );
        // Boxes slightly larger than their triangles, as the builder writes them.
        let leaf = |i: u32, z: f32| BvhNode {
            bounds_min: [-1.001, -1.001, z - 0.001],
            left_or_first: i,
            bounds_max: [3.001, 3.001, z + 0.001],
            triangle_count: 1,
        };
        // The far triangle is the left child, to check near-first ordering does not matter.
        let nodes = [
            BvhNode {
                bounds_min: [-1.001, -1.001, 0.999],
                left_or_first: 1,
                bounds_max: [3.001, 3.001, 2.001],
                triangle_count: 0,
            },
            leaf(0, 2.0),
            leaf(1, 1.0),
        ];
        let info = [
            TriangleInfo {
                vertices: [0, 1, 2],
                material: 0,
            },
            TriangleInfo {
                vertices: [3, 4, 5],
                material: 1,
            },
        ];
        (nodes, [far, near], info)
    }

    #[test]
    fn empty_scene_has_no_hits() {
        let materials = [Material::default()];
        let scene = view(&[], &[], &[], &materials);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(!closest_hit(&scene, &ray, f32::INFINITY).is_hit());
        assert!(!any_hit(&scene, &ray, f32::INFINITY));
        assert_eq!(Hit::miss().triangle, INVALID_INDEX);
    }

    #[test]
    fn closest_and_any_hit_on_two_layers() {
        let (nodes, triangles, info) = two_layers();
        let materials = [Material::default(), Material::default()];
        let scene = view(&nodes, &triangles, &info, &materials);
        // Axis-aligned rays (two zero direction components) through the interior, an edge and a vertex.
        for origin in [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(-1.0, 0.5, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(-1.0, 3.0, 0.0),
        ] {
            let ray = Ray::new(origin, Vec3::Z);
            let h = closest_hit(&scene, &ray, f32::INFINITY);
            assert!(h.is_hit());
            assert_eq!(h.triangle, 1);
            assert!((h.t - 1.0).abs() < 1e-6);
        }
        let ray = Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z);
        let h = closest_hit(&scene, &ray, f32::INFINITY);
        assert!((h.b1 - 0.3125).abs() < 1e-6 && (h.b2 - 0.375).abs() < 1e-6);
        assert!(any_hit(&scene, &ray, 1.5));
        assert!(!any_hit(&scene, &ray, 1.0));
        assert!(!closest_hit(&scene, &ray, 0.5).is_hit());
        // From between the layers, looking either way.
        let up = Ray::new(Vec3::new(0.0, 0.0, 1.5), Vec3::Z);
        assert_eq!(closest_hit(&scene, &up, f32::INFINITY).triangle, 0);
        let down = Ray::new(Vec3::new(0.0, 0.0, 1.5), -Vec3::Z);
        assert_eq!(closest_hit(&scene, &down, f32::INFINITY).triangle, 1);
        // Missing everything.
        let away = Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::Z);
        assert!(!closest_hit(&scene, &away, f32::INFINITY).is_hit());
        assert!(!any_hit(&scene, &away, f32::INFINITY));
    }

    #[test]
    fn alpha_cut_out_triangles_are_skipped() {
        let (nodes, triangles, info) = two_layers();
        let hole = Material {
            flags: MATERIAL_ALPHA_CUTOUT,
            base_color: [0.8, 0.8, 0.8, 0.0],
            ..Material::default()
        };
        let materials = [Material::default(), hole];
        let scene = view(&nodes, &triangles, &info, &materials);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::Z);
        let h = closest_hit(&scene, &ray, f32::INFINITY);
        assert_eq!(h.triangle, 0);
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!(!any_hit(&scene, &ray, 1.5));
        assert!(any_hit(&scene, &ray, 2.5));

        // Opaque enough: alpha above the cutoff blocks again.
        let solid = Material {
            base_color: [0.8, 0.8, 0.8, 0.9],
            ..hole
        };
        let materials = [Material::default(), solid];
        let scene = view(&nodes, &triangles, &info, &materials);
        assert_eq!(closest_hit(&scene, &ray, f32::INFINITY).triangle, 1);
    }

    #[test]
    fn slab_test_has_no_nan_for_zero_directions() {
        let node = BvhNode {
            bounds_min: [0.0, 0.0, 0.0],
            left_or_first: 0,
            bounds_max: [1.0, 1.0, 1.0],
            triangle_count: 1,
        };
        let cases = [
            (Vec3::new(0.0, 0.5, 0.5), Vec3::X, true),
            (Vec3::new(-1.0, 0.0, 0.0), Vec3::X, true),
            // (A ray exactly in a box's max plane and parallel to it may miss the box; no triangle can be
            // hit there because built boxes strictly contain their triangles.)
            (Vec3::new(-1.0, 0.999, 0.999), Vec3::X, true),
            (Vec3::new(-1.0, 1.5, 0.5), Vec3::X, false),
            (Vec3::new(0.5, 0.5, 0.5), Vec3::ZERO, true),
            (Vec3::new(2.0, 0.5, 0.5), Vec3::ZERO, false),
            (Vec3::new(2.0, 0.5, 0.5), Vec3::new(-0.0, 0.0, -1.0), false),
            (Vec3::new(0.5, 0.5, 2.0), Vec3::new(-0.0, 0.0, -1.0), true),
        ];
        for (origin, dir, expect) in cases {
            let rb = RayBox::new(&Ray::new(origin, dir));
            assert!(rb.inv_dir.is_finite());
            let t = rb.entry(&node, f32::INFINITY);
            assert!(!t.is_nan());
            assert_eq!(t != f32::INFINITY, expect, "{origin:?} {dir:?}");
        }
    }
}

