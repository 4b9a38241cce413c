//! glTF JSON / GLB bytes through loading, validation, BVH build and packing (see `fovea_fuzz` for the
//! layout: `glTF-or-GLB [SEP bytes of every external buffer or image]`).
#![no_main]
use fovea_fuzz::{run, split, FuzzFiles, SIDE_FILE_SEPARATOR};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (scene, other) = split(data, SIDE_FILE_SEPARATOR);
    run(&FuzzFiles {
        scene_path: "fuzz/scene.gltf".into(),
        scene,
        mtl: None,
        other,
    });
});
