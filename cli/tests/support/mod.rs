//! What several of the CLI's test binaries share (a folder, so that cargo does not build it as a test
//! of its own).
use std::path::Path;

/// The RGB pixels of the EXR file `path` (its first RGBA layer, row by row); panics naming the file if
/// it cannot be read.
pub fn read_exr(path: &Path) -> Vec<[f32; 3]> {
    struct Pixels {
        width: usize,
        data: Vec<[f32; 3]>,
    }
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| Pixels {
            width: size.width(),
            data: vec![[0.0; 3]; size.width() * size.height()],
        },
        |p: &mut Pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = pos.y() * p.width + pos.x();
            p.data[i] = [r, g, b];
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.layer_data.channel_data.pixels.data
}
