//! One packed array as the GPU receives it: its binding, its name and how the kernel reads it.

/// How the GPU reads one packed array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrayRead {
    /// Through the scene texel buffer (`fovea_core::scene::source`), which holds every such array, as
    /// well as through its own storage-buffer binding (for its length).
    Texels,
    /// Through its own storage buffer only.
    Storage,
}

/// One array of a packed scene as the GPU receives it: its binding in `fovea_core::kernel_abi`, a name
/// for error messages, how it is read and its bytes.
#[derive(Clone, Copy, Debug)]
pub struct PackedArray<'a> {
    pub binding: u32,
    pub name: &'static str,
    pub read: ArrayRead,
    pub bytes: &'a [u8],
}

impl<'a> PackedArray<'a> {
    /// The array `data` at `binding`.
    #[must_use]
    pub fn new<T: bytemuck::Pod>(
        binding: u32,
        name: &'static str,
        read: ArrayRead,
        data: &'a [T],
    ) -> Self {
        Self {
            binding,
            name,
            read,
            bytes: bytemuck::cast_slice(data),
        }
    }
}
