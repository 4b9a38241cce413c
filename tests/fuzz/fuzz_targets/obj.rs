//! OBJ/MTL bytes through loading, validation, BVH build and packing (see `fovea_fuzz` for the layout:
//! `OBJ [SEP MTL [SEP other files]]`).
#![no_main]
use fovea_fuzz::{run, split, FuzzFiles, SIDE_FILE_SEPARATOR};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (scene, rest) = split(data, SIDE_FILE_SEPARATOR);
    let (mtl, other) = match rest {
        Some(rest) => {
            let (mtl, other) = split(rest, SIDE_FILE_SEPARATOR);
            (Some(mtl), other)
        }
        None => (None, None),
    };
    run(&FuzzFiles {
        scene_path: "fuzz/scene.obj".into(),
        scene,
        mtl,
        other,
    });
});
