//! Watertight ray-triangle intersection (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1)).
//!
//! The ray is transformed (translate, permute, shear, scale) so that it starts at the origin and runs along
//! +z; the test then reduces to three 2D edge functions of the transformed vertices. Each transformed
//! vertex is a deterministic function of the vertex and the ray only, and each edge function is computed by
//! the same expression (with the operands swapped) in the two triangles sharing the edge, so neighbours
//! always agree on which side of an edge the ray passes: rays cannot slip through shared edges or vertices.
//!
//! **Edge cases.** An edge function computed in single precision is either zero or has the exact sign of
//! the true 2D determinant of the (rounded) transformed coordinates, because rounding is monotonic. The
//! paper re-computes the edge functions in double precision when one of them is zero. Doubles are not
//! available on the GPU, so we re-compute them with Kahan's FMA-based difference of products instead
//! ([`difference_of_products`]), which is accurate to 1.5 ulp and so has the same (exact) sign as the
//! paper's double-precision result, barring underflow. Zeros that remain are true zeros (the ray passes
//! exactly through an edge or vertex in the transformed space) and count as inside, so such a ray hits
//! both (all) adjoining triangles rather than none. Backface culling is off: both windings hit.
use glam::{Vec3, Vec4};

use super::ray::Ray;
use crate::math::float::fma;
use crate::math::lane_mask::{eq_mask, gt_mask, lane, negate_where_negative};
use crate::scene::{Features, SceneSource, SceneView, TriangleBlock, TrianglePositions};

/// The result of one ray-triangle test: `hit` is true if the ray meets the triangle at `0 < t < t_max`;
/// `b1` and `b2` are then the barycentric coordinates of `v1` and `v2` (`v0`'s is `1 - b1 - b2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
    pub hit: bool,
}

impl TriangleHit {
    /// No intersection.
    #[inline]
    #[must_use]
    pub fn miss() -> Self {
        Self {
            t: f32::INFINITY,
            b1: 0.0,
            b2: 0.0,
            hit: false,
        }
    }
}

/// What [`WatertightRay::test_block`] found for the four lanes of a [`TriangleBlock`]: which lanes may
/// be hit, and for each the numbers that [`WatertightRay::block_lane_hit`] finishes it from, computed
/// four lanes at a time.
#[derive(Clone, Copy, Debug)]
pub struct BlockTest {
    /// Bit `k` set: lane `k` may be hit in `(0, t_max)` for the `t_max` the block was tested with
    /// (finish it with [`WatertightRay::block_lane_hit`]).
    pub candidates: u32,
    /// Bit `k` set: an edge function of lane `k` rounded to zero, so its sign test needs the exact
    /// recomputation, which [`WatertightRay::block_lane_hit`] does for that lane alone.
    exact: u32,
    /// Per lane (outside `exact`): the scaled distance and determinant with the determinant's sign
    /// taken out, the distance and the barycentrics of `v1` and `v2`.
    t_scaled: Vec4,
    det_abs: Vec4,
    t: Vec4,
    b1: Vec4,
    b2: Vec4,
}

/// Per-ray precomputation of the watertight test (Woop et al. 2013, Sec. 3.1): the axis permutation
/// `kz` = dominant axis of the direction, `kx`, `ky` the other two (swapped if `direction[kz] < 0` to keep
/// the winding), and the shear/scale `Sx = d[kx]/d[kz]`, `Sy = d[ky]/d[kz]`, `Sz = 1/d[kz]`.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    /// The ray origin, permuted to `(o[kx], o[ky], o[kz])`.
    pub origin: Vec3,
    pub kx: u32,
    pub ky: u32,
    pub kz: u32,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
}

/// `v[k]` for `k` in 0..3. The CPU indexes a local copy (no branches: `k` varies from ray to ray, so
/// branches on it are mispredicted), the GPU selects (a dynamically indexed local array is a loop over
/// the lanes on lavapipe).
#[inline(always)]
#[must_use]
fn component(v: Vec3, k: u32) -> f32 {
    #[cfg(not(target_arch = "spirv"))]
    {
        [v.x, v.y, v.z, 0.0][(k & 3) as usize]
    }
    #[cfg(target_arch = "spirv")]
    {
        if k == 0 {
            v.x
        } else if k == 1 {
            v.y
        } else {
            v.z
        }
    }
}

/// `a * b - c * d` with Kahan's FMA algorithm: the error of `c * d` is recovered exactly by an FMA, so the
/// result is within 1.5 ulp of the exact value and in particular has its exact sign (barring underflow).
#[inline]
#[must_use]
pub fn difference_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let cd = c * d;
    let error = fma(-c, d, cd);
    let dop = fma(a, b, -cd);
    dop + error
}

impl WatertightRay {
    /// Precomputes the permutation and shear for `ray`. A zero (or non-finite) direction never hits.
    #[inline]
    #[must_use]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.direction;
        let a = d.abs();
        // The dominant axis (x before y before z on ties) and the two others, from comparisons turned
        // into integers rather than branches, which the ray-to-ray changes of axis would mispredict.
        let x_dominant = u32::from(a.x >= a.y) & u32::from(a.x >= a.z);
        let y_over_z = u32::from(a.y >= a.z);
        let kz = (1 - x_dominant) * (2 - y_over_z);
        // The cyclic successors: 0 -> 1 -> 2 -> 0.
        let next = |k: u32| (k + 1) * u32::from(k != 2);
        let (kx, ky) = (next(kz), next(next(kz)));
        let dz = component(d, kz);
        // Swapped towards -z, to keep the winding.
        let swap = (kx ^ ky) * u32::from(dz < 0.0);
        let (kx, ky) = (kx ^ swap, ky ^ swap);
        let (sx, sy, sz) = if dz != 0.0 {
            (component(d, kx) / dz, component(d, ky) / dz, 1.0 / dz)
        } else {
            // Zero direction: Sz = 0 makes every scaled t zero, which the `t > 0` test rejects.
            (0.0, 0.0, 0.0)
        };
        let o = ray.origin;
        Self {
            origin: Vec3::new(component(o, kx), component(o, ky), component(o, kz)),
            kx,
            ky,
            kz,
            sx,
            sy,
            sz,
        }
    }

    /// `v - origin` in the permuted frame. Both versions move the same values: the CPU indexes a local
    /// copy of the vertex (no branches; `& 3` lets the compiler drop the bounds checks; selects were
    /// 1.6 % slower on the small peer scene), the GPU selects (a dynamically indexed local array is a
    /// loop over the lanes on lavapipe; selects made its frames up to 6 % faster).
    #[inline]
    #[must_use]
    fn relative(&self, v: Vec4) -> Vec3 {
        #[cfg(not(target_arch = "spirv"))]
        let p = {
            let v = v.to_array();
            Vec3::new(
                v[(self.kx & 3) as usize],
                v[(self.ky & 3) as usize],
                v[(self.kz & 3) as usize],
            )
        };
        #[cfg(target_arch = "spirv")]
        let p = {
            let v = v.truncate();
            Vec3::new(
                component(v, self.kx),
                component(v, self.ky),
                component(v, self.kz),
            )
        };
        p - self.origin
    }

    /// Intersects the triangle (Woop et al. 2013, Fig. 4/5 without backface culling). A hit needs
    /// `0 < t < t_max`; degenerate triangles (zero determinant) never hit.
    #[inline]
    #[must_use]
    pub fn intersect(&self, tri: &TrianglePositions, t_max: f32) -> TriangleHit {
        let a = self.relative(tri.v0);
        let b = self.relative(tri.v1);
        let c = self.relative(tri.v2);

        // Shear the vertices into the ray's frame (the ray now runs along +z from the origin).
        let ax = a.x - self.sx * a.z;
        let ay = a.y - self.sy * a.z;
        let bx = b.x - self.sx * b.z;
        let by = b.y - self.sy * b.z;
        let cx = c.x - self.sx * c.z;
        let cy = c.y - self.sy * c.z;

        // Scaled barycentrics: edge functions of the edges opposite v0, v1, v2.
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        self.intersect_sheared([ax, ay, bx, by, cx, cy], [u, v, w], [a.z, b.z, c.z], t_max)
    }

    /// The four triangles of `block` at once: which lanes may be hit in `(0, t_max)` (the lanes
    /// [`Self::intersect`] would not reject; lanes whose edge functions rounded to zero are included,
    /// since their exact test is scalar) and, for every lane, the distance and barycentrics that
    /// [`Self::block_lane_hit`] then checks against the closest hit so far. Every lane's numbers are
    /// computed by the same operations as [`Self::intersect`]'s, so a lane's result is bit-identical.
    #[inline(always)]
    #[must_use]
    pub fn test_block(&self, block: &TriangleBlock, t_max: f32) -> BlockTest {
        // A vertex's components (four lanes each) relative to the origin, in the permuted frame, as
        // `relative` computes one vertex.
        let (o, (kx, ky, kz)) = (self.origin, (self.kx, self.ky, self.kz));
        let relative = |x: Vec4, y: Vec4, z: Vec4| -> [Vec4; 3] {
            // As `component`: indexed on the CPU, selected on the GPU.
            let pick = |k: u32| -> Vec4 {
                #[cfg(not(target_arch = "spirv"))]
                {
                    [x, y, z, z][(k & 3) as usize]
                }
                #[cfg(target_arch = "spirv")]
                {
                    if k == 0 {
                        x
                    } else if k == 1 {
                        y
                    } else {
                        z
                    }
                }
            };
            [
                pick(kx) - Vec4::splat(o.x),
                pick(ky) - Vec4::splat(o.y),
                pick(kz) - Vec4::splat(o.z),
            ]
        };
        let a = relative(block.v0x, block.v0y, block.v0z);
        let b = relative(block.v1x, block.v1y, block.v1z);
        let c = relative(block.v2x, block.v2y, block.v2z);
        let (sx, sy) = (Vec4::splat(self.sx), Vec4::splat(self.sy));
        let ax = a[0] - sx * a[2];
        let ay = a[1] - sy * a[2];
        let bx = b[0] - sx * b[2];
        let by = b[1] - sy * b[2];
        let cx = c[0] - sx * c[2];
        let cy = c[1] - sy * c[2];
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let exact = (eq_mask(u, zero) | eq_mask(v, zero) | eq_mask(w, zero)) & 0xF;
        let negative = gt_mask(zero, u) | gt_mask(zero, v) | gt_mask(zero, w);
        let positive = gt_mask(u, zero) | gt_mask(v, zero) | gt_mask(w, zero);
        // `intersect_sheared`'s arithmetic, four lanes at a time (meaningless for `exact` lanes).
        let det = u + v + w;
        let sz = Vec4::splat(self.sz);
        let t_scaled = u * (sz * a[2]) + v * (sz * b[2]) + w * (sz * c[2]);
        let t_scaled = negate_where_negative(t_scaled, det);
        let det_abs = negate_where_negative(det, det);
        let inv_det = Vec4::ONE / det;
        let t = t_scaled / det_abs;
        // Lanes that pass every test that does not involve `t_max`, and whose distance is below it;
        // `block_lane_hit` repeats the tests that do, against the closest hit by then.
        let inside = !(negative & positive) & !eq_mask(det, zero);
        let in_range = gt_mask(t_scaled, zero) & gt_mask(Vec4::splat(t_max), t);
        BlockTest {
            candidates: exact | (inside & in_range & !exact & 0xF),
            exact,
            t_scaled,
            det_abs,
            t,
            b1: v * inv_det,
            b2: w * inv_det,
        }
    }

    /// Lane `k` of a [`Self::test_block`] result of `block` tested in `(0, t_max)`: the hit
    /// [`Self::intersect`] gives that triangle. `t_max` may be below the block test's.
    #[inline(always)]
    #[must_use]
    pub fn block_lane_hit(
        &self,
        block: &TriangleBlock,
        test: &BlockTest,
        k: usize,
        t_max: f32,
    ) -> TriangleHit {
        if test.exact & (1 << k) != 0 {
            // Rare: an edge function rounded to zero; the whole single-triangle test, for its exact
            // recomputation.
            return self.intersect(&block.lane_positions(k), t_max);
        }
        let (t_scaled, det_abs, t) = (
            lane(test.t_scaled, k),
            lane(test.det_abs, k),
            lane(test.t, k),
        );
        // `intersect_sheared`'s range tests (`t_scaled > 0` is already in the candidates).
        if t_scaled < t_max * det_abs && t > 0.0 && t < t_max {
            TriangleHit {
                t,
                b1: lane(test.b1, k),
                b2: lane(test.b2, k),
                hit: true,
            }
        } else {
            TriangleHit::miss()
        }
    }

    /// [`Self::intersect`] from the sheared vertices `[ax, ay, bx, by, cx, cy]`, their edge functions
    /// `[u, v, w]` and the permuted (unscaled) depths `[az, bz, cz]` on.
    #[inline]
    #[must_use]
    fn intersect_sheared(
        &self,
        sheared: [f32; 6],
        edges: [f32; 3],
        depth: [f32; 3],
        t_max: f32,
    ) -> TriangleHit {
        let [ax, ay, bx, by, cx, cy] = sheared;
        let [mut u, mut v, mut w] = edges;

        // Fallback (paper: double precision) when an edge function rounded to zero.
        if u == 0.0 || v == 0.0 || w == 0.0 {
            u = difference_of_products(cx, by, cy, bx);
            v = difference_of_products(ax, cy, ay, cx);
            w = difference_of_products(bx, ay, by, ax);
        }

        // Outside if the signs differ (zero counts as inside, for either winding).
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return TriangleHit::miss();
        }
        let det = u + v + w;
        if det == 0.0 {
            return TriangleHit::miss();
        }

        // Scaled hit distance, range-checked against the scaled interval before dividing.
        let az = self.sz * depth[0];
        let bz = self.sz * depth[1];
        let cz = self.sz * depth[2];
        let t_scaled = u * az + v * bz + w * cz;
        let (t_scaled, det_abs) = if det < 0.0 {
            (-t_scaled, -det)
        } else {
            (t_scaled, det)
        };
        // Written so that NaN fails the test too.
        let in_range = t_scaled > 0.0 && t_scaled < t_max * det_abs;
        if !in_range {
            return TriangleHit::miss();
        }

        let inv_det = 1.0 / det;
        let t = t_scaled / det_abs;
        // The division may round onto the interval's ends; keep the open interval exact.
        let in_range = t > 0.0 && t < t_max;
        if !in_range {
            return TriangleHit::miss();
        }
        TriangleHit {
            t,
            b1: v * inv_det,
            b2: w * inv_det,
            hit: true,
        }
    }
}

/// Vertex positions of `triangle`.
#[inline]
#[must_use]
pub fn triangle_vertices<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
) -> [Vec3; 3] {
    let t = source.triangle(scene, triangle);
    [t.v0.truncate(), t.v1.truncate(), t.v2.truncate()]
}

/// The unnormalised geometric normal `(v1 - v0) × (v2 - v0)` (its length is twice the area); the front
/// face is the side it points to (counter-clockwise winding).
#[inline]
#[must_use]
pub fn scaled_geometric_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0])
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    use crate::test_support::SplitMix64 as TestRng;

    fn tri(a: Vec3, b: Vec3, c: Vec3) -> TrianglePositions {
        TrianglePositions {
            v0: a.extend(0.0),
            v1: b.extend(0.0),
            v2: c.extend(0.0),
        }
    }

    /// Whether any triangle of `mesh` is hit by `ray`.
    fn hits_any(mesh: &[TrianglePositions], ray: &Ray) -> bool {
        let w = WatertightRay::new(ray);
        mesh.iter().any(|t| w.intersect(t, f32::INFINITY).hit)
    }

    /// A closed unit cube `[-1, 1]^3`, two triangles per face, outward (counter-clockwise) winding.
    fn cube(center: Vec3, half: f32) -> Vec<TrianglePositions> {
        let p = |x: f32, y: f32, z: f32| center + Vec3::new(x, y, z) * half;
        let corners = [
            p(-1.0, -1.0, -1.0),
            p(1.0, -1.0, -1.0),
            p(1.0, 1.0, -1.0),
            p(-1.0, 1.0, -1.0),
            p(-1.0, -1.0, 1.0),
            p(1.0, -1.0, 1.0),
            p(1.0, 1.0, 1.0),
            p(-1.0, 1.0, 1.0),
        ];
        let quads = [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [1, 2, 6, 5],
            [0, 4, 7, 3],
        ];
        let mut out = Vec::new();
        for q in quads {
            out.push(tri(corners[q[0]], corners[q[1]], corners[q[2]]));
            out.push(tri(corners[q[0]], corners[q[2]], corners[q[3]]));
        }
        out
    }

    fn octahedron(center: Vec3, r: f32) -> Vec<TrianglePositions> {
        let axes = [Vec3::X, Vec3::Y, Vec3::Z];
        let mut out = Vec::new();
        for sx in [-1.0f32, 1.0] {
            for sy in [-1.0f32, 1.0] {
                for sz in [-1.0f32, 1.0] {
                    let a = center + axes[0] * sx * r;
                    let b = center + axes[1] * sy * r;
                    let c = center + axes[2] * sz * r;
                    if sx * sy * sz > 0.0 {
                        out.push(tri(a, b, c));
                    } else {
                        out.push(tri(a, c, b));
                    }
                }
            }
        }
        out
    }

    /// Vertices and triangles of a bumpy `n x n` grid over `[0, 1]^2` (z random), alternating diagonals.
    fn grid(n: usize, rng: &mut TestRng) -> (Vec<Vec3>, Vec<TrianglePositions>) {
        let mut verts = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                verts.push(Vec3::new(
                    i as f32 / n as f32 + rng.range(-0.2, 0.2) / n as f32,
                    j as f32 / n as f32 + rng.range(-0.2, 0.2) / n as f32,
                    rng.range(-0.1, 0.1) / n as f32,
                ));
            }
        }
        let idx = |i: usize, j: usize| j * (n + 1) + i;
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                if (i + j) % 2 == 0 {
                    tris.push(tri(verts[a], verts[b], verts[c]));
                    tris.push(tri(verts[a], verts[c], verts[d]));
                } else {
                    tris.push(tri(verts[a], verts[b], verts[d]));
                    tris.push(tri(verts[b], verts[c], verts[d]));
                }
            }
        }
        (verts, tris)
    }

    /// Edge points and vertices of a mesh: every vertex, every edge midpoint and random points on edges.
    fn targets(mesh: &[TrianglePositions], rng: &mut TestRng) -> Vec<Vec3> {
        let mut out = Vec::new();
        for t in mesh {
            let v = [t.v0.truncate(), t.v1.truncate(), t.v2.truncate()];
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                out.push(a);
                out.push((a + b) * 0.5);
                for _ in 0..4 {
                    out.push(a.lerp(b, rng.uniform()));
                }
            }
        }
        out
    }

    /// The block test finishes every lane exactly as the single-triangle test does: same hits, same
    /// bits, for random and grid triangles (shared edges and vertices, so edge functions that round to
    /// zero), rays aimed at edges and vertices, and padded lanes (degenerate, never hit).
    #[test]
    fn block_lanes_match_the_single_triangle_test() {
        let mut rng = TestRng(17);
        let (_, mut mesh) = grid(6, &mut rng);
        let origin = Vec3::new(0.4, 0.3, 2.0);
        let mut rays: Vec<Ray> = targets(&mesh, &mut rng)
            .into_iter()
            .map(|p| Ray::new(origin, p - origin))
            .collect();
        for _ in 0..300 {
            let o = rng.in_cube(2.0);
            let d = rng.in_cube(1.0);
            rays.push(Ray::new(o, d));
        }
        for _ in 0..200 {
            let (a, b, c) = (rng.in_cube(1.0), rng.in_cube(1.0), rng.in_cube(1.0));
            mesh.push(tri(a, b, c));
        }
        // Degenerate lanes, as the packer pads a leaf's last block with.
        mesh.push(TrianglePositions::default());
        for chunk in mesh.chunks(4) {
            let mut block = TriangleBlock::EMPTY;
            for (k, t) in chunk.iter().enumerate() {
                block.set_lane(k, t, k as u32);
            }
            for ray in &rays {
                let w = WatertightRay::new(ray);
                // The block tested against a farther closest hit than its lanes are (as after an
                // earlier lane's hit) and against the same.
                for (block_t_max, t_max) in [
                    (f32::INFINITY, f32::INFINITY),
                    (f32::INFINITY, 1.5),
                    (1.5, 1.5),
                    (1.5, 0.7),
                    (0.7, 0.7),
                ] {
                    let test = w.test_block(&block, block_t_max);
                    for k in 0..4 {
                        let lane = if k < chunk.len() {
                            chunk[k]
                        } else {
                            TrianglePositions::default()
                        };
                        let single = w.intersect(&lane, t_max);
                        let by_block = if test.candidates & (1 << k) != 0 {
                            w.block_lane_hit(&block, &test, k, t_max)
                        } else {
                            TriangleHit::miss()
                        };
                        assert_eq!(single.hit, by_block.hit, "lane {k} of {chunk:?}, {ray:?}");
                        if single.hit {
                            assert_eq!(
                                (single.t.to_bits(), single.b1.to_bits(), single.b2.to_bits()),
                                (
                                    by_block.t.to_bits(),
                                    by_block.b1.to_bits(),
                                    by_block.b2.to_bits()
                                )
                            );
                        }
                    }
                }
            }
        }
    }

    /// The branch-free axis choice equals the plain one: dominant axis `kz` (x before y before z on
    /// ties), `kx`, `ky` its cyclic successors, swapped for a negative `d[kz]`.
    #[test]
    fn axis_permutation_matches_the_definition() {
        let values = [0.0f32, -0.0, 1.0, -1.0, 2.0, -2.0, 0.5, -0.5];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let d = Vec3::new(x, y, z);
                    let a = d.abs();
                    let kz = if a.x >= a.y && a.x >= a.z {
                        0
                    } else if a.y >= a.z {
                        1
                    } else {
                        2
                    };
                    let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
                    if d[kz as usize] < 0.0 {
                        core::mem::swap(&mut kx, &mut ky);
                    }
                    let w = WatertightRay::new(&Ray::new(Vec3::new(1.0, 2.0, 3.0), d));
                    assert_eq!((w.kx, w.ky, w.kz), (kx, ky, kz), "{d:?}");
                    let o = [1.0, 2.0, 3.0];
                    assert_eq!(
                        w.origin,
                        Vec3::new(o[kx as usize], o[ky as usize], o[kz as usize])
                    );
                }
            }
        }
    }

    #[test]
    fn known_triangle_t_and_barycentrics() {
        let t = tri(
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::new(4.0, 0.0, 5.0),
            Vec3::new(0.0, 2.0, 5.0),
        );
        let ray = Ray::new(Vec3::new(1.0, 0.5, 1.0), Vec3::Z);
        let h = WatertightRay::new(&ray).intersect(&t, f32::INFINITY);
        assert!(h.hit);
        assert!((h.t - 4.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6);
        assert!((h.b2 - 0.25).abs() < 1e-6);

        // An oblique, non-unit direction: t is in units of the direction's length.
        let target = Vec3::new(0.0, 0.0, 5.0) * 0.2
            + Vec3::new(4.0, 0.0, 5.0) * 0.3
            + Vec3::new(0.0, 2.0, 5.0) * 0.5;
        let origin = Vec3::new(-3.0, 7.0, -2.0);
        let ray = Ray::new(origin, (target - origin) * 0.5);
        let h = WatertightRay::new(&ray).intersect(&t, f32::INFINITY);
        assert!(h.hit);
        assert!((h.t - 2.0).abs() < 1e-5, "{}", h.t);
        assert!((h.b1 - 0.3).abs() < 1e-5);
        assert!((h.b2 - 0.5).abs() < 1e-5);

        // Open interval (0, t_max).
        let ray = Ray::new(Vec3::new(1.0, 0.5, 1.0), Vec3::Z);
        let w = WatertightRay::new(&ray);
        assert!(!w.intersect(&t, 4.0).hit);
        assert!(w.intersect(&t, 4.0001).hit);
        let behind = Ray::new(Vec3::new(1.0, 0.5, 9.0), Vec3::Z);
        assert!(!WatertightRay::new(&behind).intersect(&t, f32::INFINITY).hit);
        let outside = Ray::new(Vec3::new(3.0, 1.5, 1.0), Vec3::Z);
        assert!(
            !WatertightRay::new(&outside)
                .intersect(&t, f32::INFINITY)
                .hit
        );
    }

    #[test]
    fn both_windings_hit_with_consistent_barycentrics() {
        let mut rng = TestRng(7);
        for _ in 0..2000 {
            let v0 = rng.in_cube(1.0);
            let v1 = rng.in_cube(1.0);
            let v2 = rng.in_cube(1.0);
            if (v1 - v0).cross(v2 - v0).length() < 1e-2 {
                continue;
            }
            let (b1, b2) = (rng.range(0.05, 0.45), rng.range(0.05, 0.45));
            let p = v0 * (1.0 - b1 - b2) + v1 * b1 + v2 * b2;
            let n = (v1 - v0).cross(v2 - v0).normalize();
            let dir = rng.unit_vector();
            if dir.dot(n).abs() < 0.2 {
                continue; // grazing rays are tested elsewhere; here t is compared to tight tolerances
            }
            let origin = p + dir * rng.range(0.5, 3.0);
            let ray = Ray::new(origin, p - origin);
            let w = WatertightRay::new(&ray);
            let front = w.intersect(&tri(v0, v1, v2), f32::INFINITY);
            let back = w.intersect(&tri(v0, v2, v1), f32::INFINITY);
            assert!(front.hit && back.hit);
            assert!(
                (front.t - 1.0).abs() < 1e-4 && (back.t - front.t).abs() < 1e-6,
                "{front:?} {back:?}"
            );
            assert!((front.b1 - b1).abs() < 1e-3 && (front.b2 - b2).abs() < 1e-3);
            assert!((back.b1 - front.b2).abs() < 1e-6 && (back.b2 - front.b1).abs() < 1e-6);
        }
    }

    /// Rays aimed exactly at vertices and edges of closed convex meshes always hit: rays that enter the
    /// solid through the target (from outside, continuing to an interior point) and rays that leave through
    /// it (from an interior point), including directions with one or two zero components.
    #[test]
    fn closed_meshes_have_no_cracks() {
        let mut rng = TestRng(42);
        // (mesh, centre, size, is a cube). Strictly inside, in units of the size: the cube's max norm or the
        // octahedron's 1-norm below 1.
        let inside = |q: Vec3, is_cube: bool| {
            if is_cube {
                q.abs().max_element() < 0.999
            } else {
                q.abs().element_sum() < 0.999
            }
        };
        let meshes = [
            (cube(Vec3::ZERO, 1.0), Vec3::ZERO, 1.0, true),
            (
                cube(Vec3::new(3.7, -1.3, 100.0), 0.37),
                Vec3::new(3.7, -1.3, 100.0),
                0.37,
                true,
            ),
            (octahedron(Vec3::ZERO, 1.0), Vec3::ZERO, 1.0, false),
            (
                octahedron(Vec3::new(-0.3, 1e3, 7.0), 2.3),
                Vec3::new(-0.3, 1e3, 7.0),
                2.3,
                false,
            ),
        ];
        let mut rays = 0;
        let mut axis_rays = 0;
        for (mesh, centre, size, is_cube) in &meshes {
            for target in targets(mesh, &mut rng) {
                // Interior points: random ones, and the target with one or two coordinates moved to the
                // centre's (which gives directions with zero components).
                let mut interiors = Vec::new();
                for _ in 0..6 {
                    interiors.push(*centre + rng.unit_vector() * *size * rng.range(0.0, 0.5));
                }
                for mask in 1..7u32 {
                    let mut q = target;
                    for k in 0..3 {
                        if mask & (1 << k) != 0 {
                            q[k] = centre[k];
                        }
                    }
                    if inside((q - *centre) / *size, *is_cube) {
                        interiors.push(q);
                        axis_rays += 1;
                    }
                }
                for q in interiors {
                    let d = q - target;
                    let outside = target - d * rng.range(1.0, 20.0);
                    assert!(
                        hits_any(mesh, &Ray::new(outside, d)),
                        "{outside:?} -> {target:?}"
                    );
                    assert!(hits_any(mesh, &Ray::new(q, -d)), "{q:?} -> {target:?}");
                    rays += 2;
                }
            }
        }
        assert!(rays > 5000 && axis_rays > 100);
    }

    /// Rays through vertices and edges of a finely tessellated height field (no facet steeper than the
    /// rays, so no ray merely grazes) always hit.
    #[test]
    fn tessellated_grid_has_no_cracks() {
        let mut rng = TestRng(3);
        let n = 24;
        let (verts, mesh) = grid(n, &mut rng);
        let m = n as f32;
        let interior =
            |p: Vec3| p.x > 0.5 / m && p.x < 1.0 - 0.5 / m && p.y > 0.5 / m && p.y < 1.0 - 0.5 / m;
        let mut targets_inside = Vec::new();
        for v in verts.iter().copied().filter(|v| interior(*v)) {
            targets_inside.push(v);
        }
        for t in targets(&mesh, &mut rng) {
            if interior(t) {
                targets_inside.push(t);
            }
        }
        assert!(targets_inside.len() > 1000);
        for target in targets_inside {
            for _ in 0..3 {
                let mut dir = rng.unit_vector();
                dir.z = dir.z.signum() * 4.0;
                let dir = dir.normalize();
                let origin = target - dir * rng.range(0.1, 10.0);
                assert!(hits_any(&mesh, &Ray::new(origin, dir)));
                assert!(hits_any(&mesh, &Ray::new(origin, target - origin)));
            }
            assert!(hits_any(&mesh, &Ray::new(target + Vec3::Z, -Vec3::Z)));
            assert!(hits_any(&mesh, &Ray::new(target - Vec3::Z, Vec3::Z)));
        }
    }

    #[test]
    fn degenerate_inputs_give_no_nan() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        let degenerate = [
            tri(p, p, p),
            tri(p, p + Vec3::X, p + 2.0 * Vec3::X),
            tri(p, p + Vec3::X, p),
            tri(Vec3::ZERO, Vec3::ZERO, Vec3::X),
        ];
        let rays = [
            Ray::new(Vec3::new(1.0, 2.0, 0.0), Vec3::Z),
            Ray::new(Vec3::new(1.5, 2.0, 0.0), Vec3::Z),
            Ray::new(Vec3::new(0.0, 2.0, 3.0), Vec3::X),
            Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z),
            Ray::new(Vec3::new(1.0, 2.0, 0.0), Vec3::ZERO),
        ];
        for r in &rays {
            let w = WatertightRay::new(r);
            assert!(w.sx.is_finite() && w.sy.is_finite() && w.sz.is_finite());
            for t in &degenerate {
                let h = w.intersect(t, f32::INFINITY);
                assert!(!h.t.is_nan() && !h.b1.is_nan() && !h.b2.is_nan());
                assert!(!h.hit);
            }
        }
        // Zero direction components still hit a proper triangle; a zero direction hits nothing.
        let t = tri(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        );
        for d in [Vec3::Z, -Vec3::Z] {
            let origin = Vec3::new(0.0, 0.0, 2.0) - d * 3.0;
            let h = WatertightRay::new(&Ray::new(origin, d)).intersect(&t, f32::INFINITY);
            assert!(h.hit && (h.t - 3.0).abs() < 1e-6);
        }
        let h = WatertightRay::new(&Ray::new(Vec3::ZERO, Vec3::ZERO)).intersect(&t, f32::INFINITY);
        assert!(!h.hit && !h.t.is_nan());
        // A ray in the triangle's plane.
        let h = WatertightRay::new(&Ray::new(Vec3::new(-5.0, 0.0, 2.0), Vec3::X))
            .intersect(&t, f32::INFINITY);
        assert!(!h.hit && !h.t.is_nan());
    }

    #[test]
    fn difference_of_products_has_exact_sign() {
        // a*b and c*d round to the same float but differ exactly.
        let a = 1.0 + f32::EPSILON;
        let b = 1.0 - f32::EPSILON;
        assert_eq!(a * b - 1.0, 0.0);
        assert!(difference_of_products(a, b, 1.0, 1.0) < 0.0);
        assert!(difference_of_products(1.0, 1.0, a, b) > 0.0);
        assert_eq!(difference_of_products(3.0, 5.0, 5.0, 3.0), 0.0);
    }
}
