//! Content hashes that identify what an image depends on: the scene's bytes and packed content, and the
//! running executable. The reference cache ([`crate::report`]) keys on them, and the parts of a split
//! render ([`crate::partial`]) carry them, so that parts of different renders are never merged.
use fovea_scene::pack::PackedScene;

/// FNV-1a, 64 bits: a small, stable hash (unlike `std`'s `DefaultHasher`, which may change between Rust
/// releases).
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a64(u64);

impl Default for Fnv1a64 {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a64 {
    /// Adds `bytes` to the hash.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// The hash so far.
    #[must_use]
    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// FNV-1a-64 of `bytes`.
#[must_use]
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a64::default();
    h.write(bytes);
    h.finish()
}

/// Hash of the packed scene's content that does not depend on the BVH's triangle order: materials,
/// textures, texels, lights, the environment and the globals, plus the triangle count and exact bounds.
#[must_use]
pub fn packed_scene_hash(packed: &PackedScene) -> u64 {
    let mut h = Fnv1a64::default();
    h.write(bytemuck::bytes_of(&packed.globals));
    h.write(bytemuck::cast_slice(&packed.materials.list));
    h.write(bytemuck::cast_slice(&packed.materials.textures));
    h.write(bytemuck::cast_slice(&packed.materials.texels));
    h.write(&(packed.lights.list.len() as u64).to_le_bytes());
    h.write(bytemuck::cast_slice(&packed.lights.list));
    h.write(bytemuck::cast_slice(&packed.environment.texels));
    h.write(&(packed.triangle_count() as u64).to_le_bytes());
    for v in [packed.bounds_min, packed.bounds_max] {
        for c in v.to_array() {
            h.write(&c.to_bits().to_le_bytes());
        }
    }
    h.finish()
}

/// FNV-1a-64 of the running executable's bytes, or `None` when it cannot be read. Hashed once per run
/// (a test-profile binary is a few hundred MB), so a later rebuild of the file on disk does not change it.
#[must_use]
pub fn executable_hash() -> Option<u64> {
    static HASH: std::sync::OnceLock<Option<u64>> = std::sync::OnceLock::new();
    *HASH.get_or_init(|| {
        let path = std::env::current_exe().ok()?;
        std::fs::read(path).ok().map(|bytes| fnv1a64(&bytes))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a64_matches_published_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
        let mut h = Fnv1a64::default();
        h.write(b"foo");
        h.write(b"bar");
        assert_eq!(h.finish(), fnv1a64(b"foobar"));
    }
}
