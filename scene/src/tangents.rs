//! Vertex tangents for the triangles that need one (a normal map or anisotropy) and lack one in the file:
//! MikkTSpace (Mikkelsen 2008, the `mikktspace` crate), the tangent space glTF asks for ("When tangents
//! are not specified, client implementations SHOULD calculate tangents using default MikkTSpace
//! algorithms") and the one normal maps are baked against.
//!
//! MikkTSpace gives a tangent per triangle corner; corners of one vertex that disagree (a UV seam, a
//! mirrored half) get copies of the vertex. Conventions as in glTF: the tangent runs along +u and the
//! bitangent `w · (n × t)` up the image (decreasing v, glTF's v running down), so MikkTSpace is given
//! `(u, 1 − v)`. A scene without shading normals keeps the per-triangle tangent that shading derives
//! from the texture coordinates (`fovea_core::material::shading`); without texture coordinates there is
//! no tangent (and no normal map to read).
use glam::Vec3;

use crate::mesh::{unit_tangent, LoadedScene};

/// The triangles MikkTSpace runs on, and its per-corner results.
struct Faces<'a> {
    scene: &'a LoadedScene,
    faces: &'a [usize],
    corners: Vec<[f32; 4]>,
}

impl Faces<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.scene.triangles[self.faces[face]][vert] as usize
    }
}

impl mikktspace::Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.faces.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.scene.positions[self.vertex(face, vert)]
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let n = self.scene.normals[self.vertex(face, vert)];
        if n != [0.0; 3] {
            return n;
        }
        // A vertex without a normal: the face's.
        let p = |k| Vec3::from(self.position(face, k));
        (p(1) - p(0))
            .cross(p(2) - p(0))
            .normalize_or_zero()
            .to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let [u, v] = self.scene.uvs[self.vertex(face, vert)];
        [u, 1.0 - v]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.corners[3 * face + vert] = tangent;
    }
}

/// Gives the triangles that need a tangent and have a vertex without one MikkTSpace tangents, copying
/// vertices whose corners disagree; returns how many triangles got them. Needs shading normals and
/// texture coordinates (without them it does nothing).
pub fn generate_missing_tangents(scene: &mut LoadedScene) -> usize {
    let n = scene.positions.len();
    if scene.normals.len() != n || scene.uvs.len() != n {
        return 0;
    }
    if scene.tangents.len() != n {
        scene.tangents = vec![[0.0; 4]; n];
    }
    let has = |t: &[f32; 4]| *t != [0.0; 4];
    let faces: Vec<usize> = (0..scene.triangles.len())
        .filter(|&f| {
            scene.materials[scene.triangle_materials[f] as usize].reads_tangent()
                && scene.triangles[f]
                    .iter()
                    .any(|&v| !has(&scene.tangents[v as usize]))
        })
        .collect();
    if faces.is_empty() {
        if !scene.tangents.iter().any(has) {
            scene.tangents.clear();
        }
        return 0;
    }
    let mut geometry = Faces {
        scene,
        faces: &faces,
        corners: vec![[0.0; 4]; 3 * faces.len()],
    };
    if !mikktspace::generate_tangents(&mut geometry) {
        return 0;
    }
    let corners = geometry.corners;

    // Which vertices this pass gave a tangent, and the copies made for disagreeing corners.
    let mut assigned = vec![false; n];
    let mut copies: std::collections::HashMap<(u32, [u32; 4]), u32> = Default::default();
    for (i, &f) in faces.iter().enumerate() {
        for k in 0..3 {
            let v = scene.triangles[f][k];
            let vi = v as usize;
            let Some(t) = unit_tangent(corners[3 * i + k]) else {
                continue;
            };
            // Only the file's vertices are visited (copies are made below and never revisited).
            debug_assert!(vi < n);
            if has(&scene.tangents[vi]) && !assigned[vi] {
                // The file's own tangent: kept.
                continue;
            }
            if !assigned[vi] {
                scene.tangents[vi] = t;
                assigned[vi] = true;
                continue;
            }
            let close = |a: [f32; 4], b: [f32; 4]| {
                a[3] == b[3]
                    && Vec3::new(a[0], a[1], a[2]).dot(Vec3::new(b[0], b[1], b[2])) > 0.9999
            };
            if close(scene.tangents[vi], t) {
                continue;
            }
            let key = (v, t.map(f32::to_bits));
            let copy = *copies.entry(key).or_insert_with(|| {
                scene.positions.push(scene.positions[vi]);
                scene.normals.push(scene.normals[vi]);
                scene.uvs.push(scene.uvs[vi]);
                if !scene.colors.is_empty() {
                    scene.colors.push(scene.colors[vi]);
                }
                scene.tangents.push(t);
                (scene.positions.len() - 1) as u32
            });
            scene.triangles[f][k] = copy;
        }
    }
    faces.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use fovea_core::scene::{Material, INVALID_INDEX};

    /// A unit quad in the xy plane facing +z, normal-mapped, with the texture upright (u along +x, v
    /// down the image, so along −y).
    fn quad(u_sign: f32) -> LoadedScene {
        LoadedScene {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            uvs: [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
                .map(|[u, v]| [0.5 + u_sign * (u - 0.5), v])
                .to_vec(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            triangle_materials: vec![0, 0],
            materials: vec![Material {
                normal_texture: 0,
                ..Material::default()
            }],
            material_names: vec!["m".into()],
            ..LoadedScene::default()
        }
    }

    /// An upright texture: tangent +x, bitangent `w (n × t)` = +y (up the image), so w = +1. Mirrored
    /// in u: tangent −x and w = −1, so the bitangent still points up the image.
    #[test]
    fn tangents_follow_u_and_the_bitangent_points_up_the_image() {
        for (u_sign, want) in [(1.0, [1.0, 0.0, 0.0, 1.0]), (-1.0, [-1.0, 0.0, 0.0, -1.0])] {
            let mut s = quad(u_sign);
            assert_eq!(generate_missing_tangents(&mut s), 2);
            assert_eq!(s.positions.len(), 4, "no seam, no copies");
            for t in &s.tangents {
                for c in 0..4 {
                    assert!((t[c] - want[c]).abs() < 1e-5, "{u_sign}: {t:?}");
                }
            }
        }
    }

    /// Triangles that need no tangent get none, and neither do scenes without texture coordinates; a
    /// file's own tangents are kept.
    #[test]
    fn only_triangles_that_need_one_and_lack_one_get_tangents() {
        let mut s = quad(1.0);
        s.materials[0].normal_texture = INVALID_INDEX;
        assert_eq!(generate_missing_tangents(&mut s), 0);
        assert!(s.tangents.is_empty());
        let mut s = quad(1.0);
        s.uvs.clear();
        assert_eq!(generate_missing_tangents(&mut s), 0);
        let mut s = quad(1.0);
        s.tangents = vec![[0.0, 1.0, 0.0, -1.0]; 4];
        assert_eq!(generate_missing_tangents(&mut s), 0);
        assert_eq!(s.tangents[2], [0.0, 1.0, 0.0, -1.0]);
    }

    /// A vertex whose corners disagree (the quad's second triangle mirrored against the first across
    /// their shared diagonal) is copied, and each triangle reads its own handedness.
    #[test]
    fn disagreeing_corners_get_their_own_vertex() {
        let mut s = quad(1.0);
        // Reflect vertex 3's coordinates across the diagonal's (from (0, 1) to (1, 0)).
        s.uvs[3] = [1.0, 1.0];
        generate_missing_tangents(&mut s);
        assert!(s.positions.len() > 4, "the shared vertices are copied");
        assert_eq!(s.positions.len(), s.tangents.len());
        assert_eq!(s.uvs.len(), s.tangents.len());
        assert_eq!(s.normals.len(), s.tangents.len());
        let w = |t: usize| s.triangles[t].map(|v| s.tangents[v as usize][3]);
        assert_eq!(w(0), [1.0; 3]);
        assert_eq!(w(1), [-1.0; 3]);
        // The copies sit where the originals do.
        for t in &s.triangles {
            for &v in t {
                assert!(s.positions[v as usize][2] == 0.0);
            }
        }
    }
}
