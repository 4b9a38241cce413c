//! Bad input (issue 8): every kind of broken scene, texture and command line gives a clear message that
//! names the file and what is wrong (or a warning and a fallback), never a panic.
//!
//! Scene-level cases call the loaders as a library on the hand-made files in `tests/fixtures/bad/`;
//! command-line cases run the `fovea` binary from the same target folder when it has been built (`cargo
//! test` of the workspace builds it for `cli/tests`); otherwise they say so and skip.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use fovea_core::scene::INVALID_INDEX;
use fovea_scene::bvh::BvhBuildOptions;
use fovea_scene::environment::Environment;
use fovea_scene::error::SceneError;
use fovea_scene::mesh::{LoadOptions, LoadedScene};
use fovea_scene::pack::pack_scene;
use fovea_scene::source::MemoryFiles;
use fovea_scene::texture::{decode_texture_bytes, TextureLimits};
use fovea_scene::{load_scene, load_scene_from};
use fovea_tests::{cornell_box_path, repo_root};

fn fixture(name: &str) -> PathBuf {
    repo_root().join("tests/fixtures/bad").join(name)
}

fn load(name: &str) -> Result<LoadedScene, SceneError> {
    load_scene(&fixture(name), &LoadOptions::default())
}

/// Loads a fixture that must fail; checks the message names the file and contains `needle`.
fn expect_error(name: &str, needle: &str) -> SceneError {
    let e = match load(name) {
        Ok(s) => panic!("{name} loaded ({} triangles)", s.triangle_count()),
        Err(e) => e,
    };
    let text = e.to_string();
    eprintln!("{name}: {text}");
    assert!(
        text.contains(name),
        "{name}: the message does not name the file: {text}"
    );
    assert!(
        text.contains(needle),
        "{name}: expected '{needle}' in: {text}"
    );
    e
}

/// Loads a fixture that must succeed with warnings; returns the scene and its warnings joined.
fn expect_warnings(name: &str) -> (LoadedScene, String) {
    let s = load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    let all = s.warnings.join("\n");
    eprintln!("{name}: {all}");
    assert!(!s.warnings.is_empty(), "{name}: no warning");
    for w in &s.warnings {
        assert!(
            w.contains("bad/"),
            "{name}: a warning does not name its file: {w}"
        );
    }
    (s, all)
}

#[test]
fn missing_file_and_unknown_extension() {
    for name in [
        "no_such_scene.obj",
        "no_such_scene.gltf",
        "no_such_scene.glb",
    ] {
        let e = expect_error(name, "file not found");
        assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
    }
    let e = expect_error(
        "not_a_scene.ply",
        "unsupported scene file extension \"ply\"",
    );
    assert!(matches!(e, SceneError::UnknownExtension { .. }), "{e}");
}

#[test]
fn truncated_and_malformed_obj_and_mtl() {
    let e = expect_error(
        "truncated_face.obj",
        "face index out of range: vertex index 4 with 3 in the file at line 6: \"f 1 3 4\"",
    );
    assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
    let e = expect_error(
        "index_out_of_range.obj",
        "vertex index 9 with 3 in the file at line 4: \"f 1 2 9\"",
    );
    assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
    let e = expect_error(
        "truncated_vertex.obj",
        "malformed OBJ: position parse error at line 3: \"v 0 1\"",
    );
    assert!(matches!(e, SceneError::Obj { .. }), "{e}");
    let e = expect_error(
        "garbage_face.obj",
        "malformed OBJ: face parse error at line 4: \"f 1 x 3\"",
    );
    assert!(matches!(e, SceneError::Obj { .. }), "{e}");
    // A malformed MTL is an error naming the MTL (not the OBJ that uses it).
    let e = load("malformed_mtl.obj").unwrap_err();
    eprintln!("malformed_mtl.obj: {e}");
    assert!(matches!(e, SceneError::Mtl { .. }), "{e}");
    assert!(
        e.to_string().contains("malformed.mtl: malformed MTL"),
        "{e}"
    );
    // A missing MTL is a warning; the faces get the default grey material.
    let (s, all) = expect_warnings("missing_mtl.obj");
    assert!(
        all.contains("no_such.mtl: material library not found"),
        "{all}"
    );
    assert!(all.contains("1 triangles have no material or an unknown one; default grey used"));
    assert_eq!(s.material_names, vec!["default".to_owned()]);
}

#[test]
fn malformed_gltf_json_and_glb_chunks() {
    for name in ["truncated.gltf", "not_json.gltf"] {
        let e = expect_error(name, "malformed glTF");
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    }
    for name in [
        "bad_version.glb",
        "truncated_chunk.glb",
        "bad_length.glb",
        "bad_magic.glb",
        "truncated.glb",
    ] {
        let e = expect_error(name, "malformed glTF");
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    }
}

#[test]
fn bad_uris_and_short_buffers() {
    let e = expect_error("bad_data_uri.gltf", "bad data URI");
    assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    let e = expect_error("http_uri.gltf", "unsupported URI scheme");
    assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    // A missing external buffer is an error naming the buffer file.
    let e = load("missing_buffer.gltf").unwrap_err();
    eprintln!("missing_buffer.gltf: {e}");
    assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
    assert!(
        e.to_string().contains("no_such_buffer.bin: file not found"),
        "{e}"
    );
    // Data shorter than the buffer's byteLength.
    let e = expect_error(
        "short_buffer.gltf",
        "buffer 0 (byteLength) needs 36 bytes but its buffer has only 24",
    );
    assert!(matches!(e, SceneError::BufferTooShort { .. }), "{e}");
    // An accessor that reaches past its buffer view.
    let e = expect_error(
        "accessor_past_buffer.gltf",
        "needs 60 bytes but its buffer has only 36",
    );
    assert!(matches!(e, SceneError::BufferTooShort { .. }), "{e}");
    let e = expect_error(
        "index_out_of_range.gltf",
        "uses vertex 7 but has only 3 vertices",
    );
    assert!(matches!(e, SceneError::FaceIndexOutOfRange { .. }), "{e}");
}

#[test]
fn non_finite_attributes_skip_their_triangles_with_counts() {
    let (s, all) = expect_warnings("non_finite.obj");
    // Two good triangles of six survive: one skipped per kind (NaN position, Inf position, NaN normal,
    // NaN texture coordinate).
    assert_eq!(s.triangle_count(), 2, "{all}");
    assert!(
        all.contains("vertices with non-finite positions; 2 triangles using them skipped"),
        "{all}"
    );
    assert!(
        all.contains("vertices with non-finite normals; 1 triangles using them skipped"),
        "{all}"
    );
    assert!(
        all.contains(
            "vertices with non-finite texture coordinates; 1 triangles using them skipped"
        ),
        "{all}"
    );
    let e = expect_error("nan_positions.gltf", "no valid triangles");
    assert!(e.to_string().contains("1 with non-finite positions"), "{e}");
    assert!(matches!(e, SceneError::Empty { .. }), "{e}");
}

#[test]
fn degenerate_triangles_and_zero_area_emitters_are_dropped_with_counts() {
    let (s, all) = expect_warnings("degenerate.obj");
    assert_eq!(s.triangle_count(), 2);
    assert!(
        all.contains(
            "4 degenerate triangles (zero or non-finite area) skipped, 2 of them emissive"
        ),
        "{all}"
    );
    assert_eq!(s.emissive_triangle_count(), 0);
    let packed = pack_scene(s, &Environment::None, &BvhBuildOptions::default());
    assert!(packed.lights.list.is_empty());
}

#[test]
fn empty_scenes_are_errors() {
    let e = expect_error("empty.obj", "the scene has no valid triangles");
    assert!(matches!(e, SceneError::Empty { .. }), "{e}");
    let e = expect_error("no_meshes.gltf", "the scene has no valid triangles");
    assert!(matches!(e, SceneError::Empty { .. }), "{e}");
}

#[test]
fn missing_textures_warn_and_fall_back() {
    let (s, all) = expect_warnings("missing_texture.obj");
    assert!(
        all.contains("no_such_texture.png: texture file not found"),
        "{all}"
    );
    assert_eq!(s.materials[0].base_color_texture, INVALID_INDEX);
    assert_eq!(
        &s.materials[0].base_color[..3],
        &[0.25, 0.5, 0.75],
        "Kd is the fallback colour"
    );
    let (s, all) = expect_warnings("missing_image.gltf");
    assert!(
        all.contains("no_such_image.png not found; using the factor only"),
        "{all}"
    );
    assert_eq!(s.materials[0].base_color_texture, INVALID_INDEX);
    assert_eq!(s.materials[0].base_color, [0.2, 0.4, 0.6, 1.0]);
}

#[test]
fn absurd_texture_headers_hit_the_decode_limits() {
    let start = std::time::Instant::now();
    // A texture of an OBJ claiming 100000 x 100000 texels: an error naming the image, no allocation.
    let e = load("huge_texture.obj").unwrap_err();
    eprintln!("huge_texture.obj: {e}");
    assert!(matches!(e, SceneError::TextureTooLarge { .. }), "{e}");
    assert!(
        e.to_string().contains(
            "huge.png: texture over the size limit: the header claims 100000x100000 texels; \
                 limits are 16384 texels per side and 1073741824 bytes"
        ),
        "{e}"
    );
    // Within the edge limit but 2 GiB as RGBA16: the decoder's allocation limit refuses it.
    let bytes = std::fs::read(fixture("huge_16bit.png")).unwrap();
    let e = decode_texture_bytes(&bytes, "huge_16bit.png", true, &TextureLimits::default())
        .unwrap_err();
    eprintln!("huge_16bit.png: {e}");
    assert!(matches!(e, SceneError::TextureTooLarge { .. }), "{e}");
    // Not an image at all.
    let bytes = std::fs::read(fixture("not_an_image.png")).unwrap();
    let e = decode_texture_bytes(&bytes, "not_an_image.png", true, &TextureLimits::default())
        .unwrap_err();
    eprintln!("not_an_image.png: {e}");
    assert!(matches!(e, SceneError::Texture { .. }), "{e}");
    // An environment map header claiming 100000 x 100000 texels.
    let e = Environment::load_map(&fixture("huge.hdr"), [1.0; 3]).unwrap_err();
    eprintln!("huge.hdr: {e}");
    assert!(matches!(e, SceneError::TextureTooLarge { .. }), "{e}");
    assert!(e.to_string().contains("huge.hdr"), "{e}");
    assert!(e.to_string().contains("claims 100000x100000 texels"), "{e}");
    let e = Environment::load_map(&fixture("no_such_map.hdr"), [1.0; 3]).unwrap_err();
    assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
    assert!(start.elapsed().as_secs() < 10, "{:?}", start.elapsed());
}

#[test]
fn scene_size_limits_are_errors_not_allocations() {
    let options = LoadOptions {
        max_triangles: 1,
        ..LoadOptions::default()
    };
    let e = load_scene(&cornell_box_path(), &options).unwrap_err();
    eprintln!("{e}");
    assert!(matches!(e, SceneError::TooLarge { .. }), "{e}");
    assert!(
        e.to_string().contains("36 triangles; the limit is 1"),
        "{e}"
    );
    // A glTF whose sparse POSITION accessor (no buffer view) declares 2^30 vertices.
    let json = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
        "accessors":[{"componentType":5126,"count":1073741824,"type":"VEC3","min":[0,0,0],"max":[1,1,1],
          "sparse":{"count":1,"indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":1}}}],
        "bufferViews":[{"buffer":0,"byteLength":4},{"buffer":0,"byteOffset":4,"byteLength":12}],
        "buffers":[{"byteLength":16,"uri":"data:application/octet-stream;base64,AAAAAAAAgD8AAAAAAAAAAA=="}]}"#;
    let files = MemoryFiles::new().with("mem/sparse.gltf", json);
    let e = load_scene_from(
        &files,
        Path::new("mem/sparse.gltf"),
        &LoadOptions::default(),
    )
    .unwrap_err();
    eprintln!("{e}");
    assert!(matches!(e, SceneError::TooLarge { .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with("mem/sparse.gltf: scene too large: 1073741824 vertices"),
        "{e}"
    );
}

#[test]
fn a_scene_without_lights_packs_without_lights() {
    let (s, all) = expect_warnings("no_light.obj");
    assert!(all.contains("2 triangles have no material"), "{all}");
    let packed = pack_scene(s, &Environment::None, &BvhBuildOptions::default());
    assert!(packed.lights.list.is_empty() && packed.lights.cdf.is_empty());
    assert_eq!(packed.globals.light_count, 0);
}

#[test]
fn every_fixture_is_handled_without_panicking() {
    // Whatever each fixture gives, loading and (when it loads) packing must not panic.
    let dir = repo_root().join("tests/fixtures/bad");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    assert!(names.len() >= 30);
    for path in names {
        if let Ok(s) = load_scene(&path, &LoadOptions::default()) {
            let packed = pack_scene(s, &Environment::None, &BvhBuildOptions::default());
            assert!(packed.triangle_count() > 0);
        }
    }
}

#[test]
fn fuzz_seeds_load_and_pack() {
    // The fuzz seeds (tests/fuzz/seeds/{obj,gltf}) are real scenes: the scene file, then the side files after
    // a separator line. They must load, so that fuzzing starts from inputs that reach packing.
    const SEP: &[u8] = b"\n#%FOVEA-FILE%#\n";
    fn split(data: &[u8]) -> (&[u8], Option<&[u8]>) {
        match data.windows(SEP.len()).position(|w| w == SEP) {
            Some(i) => (&data[..i], Some(&data[i + SEP.len()..])),
            None => (data, None),
        }
    }
    for (kind, scene_name) in [("obj", "seed.obj"), ("gltf", "seed.gltf")] {
        let dir = repo_root().join("tests/fuzz/seeds").join(kind);
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let data = std::fs::read(&path).unwrap();
            let (scene, rest) = split(&data);
            let mut files = MemoryFiles::new().with(scene_name, scene.to_vec());
            // Side files as the fuzz targets serve them: the MTL (OBJ) and one file for everything else.
            let (mtl, other) = match (kind, rest) {
                ("obj", Some(rest)) => {
                    let (m, o) = split(rest);
                    (Some(m), o)
                }
                (_, rest) => (None, rest),
            };
            let text = String::from_utf8_lossy(&data);
            for word in text.split(|c: char| c.is_whitespace() || c == '"') {
                let word = word.trim_end_matches(',');
                if word.ends_with(".mtl") {
                    if let Some(m) = mtl {
                        files.insert(word, m.to_vec());
                    }
                } else if [".png", ".bin"].iter().any(|e| word.ends_with(e)) && !word.contains(':')
                {
                    if let Some(o) = other {
                        files.insert(word, o.to_vec());
                    }
                }
            }
            let s = load_scene_from(&files, Path::new(scene_name), &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(s.triangle_count() > 0);
            let _ = pack_scene(s, &Environment::None, &BvhBuildOptions::default());
        }
    }
}

// ---- The command line (the `fovea` binary) ----

/// The `fovea` binary next to this test's target folder, if it has been built.
fn fovea_binary() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let profile_dir = exe.parent()?.parent()?;
    let bin = profile_dir.join(format!("fovea{}", std::env::consts::EXE_SUFFIX));
    if bin.is_file() {
        Some(bin)
    } else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "{} is not built, and CI must run these tests (cargo test --workspace builds it)",
            bin.display()
        );
        eprintln!(
            "skipped: {} is not built (run `cargo build -p fovea-cli` or the whole workspace's tests)",
            bin.display()
        );
        None
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fovea-bad-input-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SMALL: [&str; 9] = [
    "--backend",
    "cpu",
    "--resolution",
    "32x24",
    "--spp",
    "2,1,1",
    "--radii",
    "4,8",
    "-q",
];

fn run(bin: &Path, args: &[&str]) -> Output {
    let out = Command::new(bin).arg("render").args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!(
        "fovea render {args:?}\n  -> {}: {}",
        out.status,
        stderr.trim()
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    out
}

fn expect_cli_failure(bin: &Path, args: &[&str], needle: &str, output: &Path) {
    let out = run(bin, args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure for {args:?}");
    assert!(
        stderr.contains(needle),
        "stderr for {args:?} lacks '{needle}': {stderr}"
    );
    assert!(!output.exists(), "no output may be written for {args:?}");
}

#[test]
fn cli_reports_bad_scenes_and_options_without_writing() {
    let Some(bin) = fovea_binary() else { return };
    let dir = temp_dir("cli");
    let png = dir.join("out.png");
    let o = png.to_str().unwrap();
    let cornell = cornell_box_path();
    let cornell = cornell.to_str().unwrap();
    let f = |name: &str| fixture(name).to_str().unwrap().to_owned();
    let mut cases: Vec<(Vec<String>, &str)> = vec![
        (vec![f("no_such.obj")], "no_such.obj: file not found"),
        (
            vec![f("not_a_scene.ply")],
            "unsupported scene file extension",
        ),
        (vec![f("truncated_face.obj")], "face index out of range"),
        (vec![f("truncated.gltf")], "malformed glTF"),
        (vec![f("short_buffer.gltf")], "needs 36 bytes"),
        (vec![f("empty.obj")], "no valid triangles"),
        (vec![f("huge_texture.obj")], "texture over the size limit"),
        (
            vec![cornell.into(), "--mtl".into(), f("no_such.mtl")],
            "no_such.mtl: file not found",
        ),
        (
            vec![
                cornell.into(),
                "--resolution".into(),
                "100000x100000".into(),
            ],
            "out of range",
        ),
        (
            vec![cornell.into(), "--resolution".into(), "0x0".into()],
            "out of range",
        ),
        (
            vec![cornell.into(), "--spp".into(), "0,1,1".into()],
            "--spp",
        ),
        (
            vec![cornell.into(), "--spp".into(), "99999999,1,1".into()],
            "--spp",
        ),
        (
            vec![cornell.into(), "--gaze".into(), "1e9,0".into()],
            "absurdly far off the image",
        ),
        (
            vec![
                cornell.into(),
                "--gaze-trace".into(),
                f("gaze_trace_bad.csv"),
            ],
            "line 4: x \"abc\" is not a number",
        ),
        (
            vec![
                cornell.into(),
                "--gaze-trace".into(),
                f("gaze_trace_fields.csv"),
            ],
            "line 2: 2 fields",
        ),
        (
            vec![cornell.into(), "--env-map".into(), f("huge.hdr")],
            "texture over the size limit",
        ),
        (
            vec![cornell.into(), "--no-such-option".into()],
            "--no-such-option",
        ),
        (
            vec![cornell.into(), "--mtl-diffuse".into(), "phong".into()],
            "invalid value 'phong' for '--mtl-diffuse",
        ),
        (
            vec![cornell.into(), "--point-light".into(), "0,1,2".into()],
            "expected 6 values",
        ),
        (
            vec![
                cornell.into(),
                "--point-light".into(),
                "0,1,2,-1,1,1".into(),
            ],
            "intensity must not be negative",
        ),
        (
            vec![
                cornell.into(),
                "--point-light".into(),
                "0,1,nan,1,1,1".into(),
            ],
            "non-finite",
        ),
    ];
    for (args, needle) in cases.drain(..) {
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        // The small-render options the case does not set itself.
        for pair in SMALL[..8].chunks(2) {
            if !all.contains(&pair[0]) {
                all.extend(pair);
            }
        }
        all.push("-q");
        all.extend(["-o", o]);
        expect_cli_failure(&bin, &all, needle, &png);
    }
    // Output checks come before any rendering: an absurd amount of work still fails at once.
    let start = std::time::Instant::now();
    let heavy = [
        cornell,
        "--backend",
        "cpu",
        "--resolution",
        "8192x8192",
        "--uniform",
        "--spp",
        "4096,1,1",
        "-q",
    ];
    let bmp = dir.join("out.bmp");
    let mut args = heavy.to_vec();
    args.extend(["-o", bmp.to_str().unwrap()]);
    expect_cli_failure(&bin, &args, "unknown image extension '.bmp'", &bmp);
    let nested = dir.join("no/such/folder/out.png");
    let mut args = heavy.to_vec();
    args.extend(["-o", nested.to_str().unwrap()]);
    expect_cli_failure(&bin, &args, "does not exist", &nested);
    assert!(start.elapsed().as_secs() < 30, "{:?}", start.elapsed());
    let leftovers: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(dir).ok();
}

/// `--mtl-diffuse lambert` renders the Cornell box's purely diffuse walls Lambertian: a different image
/// from the default Disney diffuse, from the same seed.
#[test]
fn cli_mtl_diffuse_switches_the_diffuse_lobe() {
    let Some(bin) = fovea_binary() else { return };
    let dir = temp_dir("mtl_diffuse");
    let cornell = cornell_box_path();
    let mut images = Vec::new();
    for model in ["disney", "lambert"] {
        let png = dir.join(format!("{model}.png"));
        let mut args = vec![cornell.to_str().unwrap()];
        args.extend(SMALL);
        args.extend(["--mtl-diffuse", model, "-o", png.to_str().unwrap()]);
        let out = run(&bin, &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        images.push(image::open(&png).unwrap().to_rgb8());
    }
    assert!(images[1].pixels().any(|p| p.0 != [0, 0, 0]), "black image");
    assert_ne!(
        images[0], images[1],
        "--mtl-diffuse lambert changed nothing"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// A scene with a light that reaches nothing the camera sees (a one-sided quad facing the camera, the
/// point light behind it) renders black: the warning says so, in stderr and in --stats.
#[test]
fn a_black_image_from_a_lit_scene_is_named() {
    let Some(bin) = fovea_binary() else { return };
    let dir = temp_dir("black");
    let png = dir.join("out.png");
    let stats = dir.join("stats.json");
    let scene = fixture("no_light.obj");
    let mut args = vec![scene.to_str().unwrap()];
    args.extend(SMALL);
    args.extend(["--point-light", "0,0,-2,4,4,4"]);
    args.extend([
        "--stats",
        stats.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    let out = run(&bin, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("no light and no sky"), "{stderr}");
    assert!(
        stderr.contains("warning: the image is black: no light reached the camera"),
        "{stderr}"
    );
    assert!(stderr.contains("--sky R,G,B"), "{stderr}");
    let image = image::open(&png).unwrap().to_rgb8();
    assert!(image.pixels().all(|p| p.0 == [0, 0, 0]), "not black");
    let json = std::fs::read_to_string(&stats).unwrap();
    assert!(json.contains("the image is black"), "{json}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn cli_warns_and_renders_when_it_can() {
    let Some(bin) = fovea_binary() else { return };
    let dir = temp_dir("warn");
    let png = dir.join("out.png");
    let o = png.to_str().unwrap();
    // No light and no sky: a warning, and a (black) image.
    let scene = fixture("no_light.obj");
    let mut args = vec![scene.to_str().unwrap()];
    args.extend(SMALL);
    args.extend(["-o", o]);
    let out = run(&bin, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("no light and no sky: the image will be black"),
        "{stderr}"
    );
    assert!(png.is_file());
    std::fs::remove_file(&png).unwrap();
    // The same scene lit by a point light from the command line: no warning, and light in the image.
    let stats = dir.join("stats.json");
    let mut args = vec![scene.to_str().unwrap()];
    args.extend(SMALL);
    args.extend([
        "--point-light",
        "0,0,2,4,4,4",
        "--stats",
        stats.to_str().unwrap(),
    ]);
    args.extend(["-o", o]);
    let out = run(&bin, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("no light"), "{stderr}");
    assert!(!stderr.contains("image is black"), "{stderr}");
    let json = std::fs::read_to_string(&stats).unwrap();
    assert!(json.contains("\"lights\": 1"), "{json}");
    assert!(json.contains("punctual_lights"), "{json}");
    let lit = image::open(&png).unwrap().to_rgb8();
    assert!(
        lit.pixels().any(|p| p.0[0] > 0),
        "the point light lights nothing"
    );
    std::fs::remove_file(&png).unwrap();
    std::fs::remove_file(&stats).unwrap();
    // Skipped triangles and missing textures are warnings listed with --verbose.
    for (name, needle) in [
        ("non_finite.obj", "2 triangles using them skipped"),
        ("degenerate.obj", "4 degenerate triangles"),
        (
            "missing_texture.obj",
            "no_such_texture.png: texture file not found",
        ),
        ("missing_mtl.obj", "no_such.mtl: material library not found"),
    ] {
        let scene = fixture(name);
        let mut args = vec![scene.to_str().unwrap(), "--verbose", "--sky", "1,1,1"];
        args.extend(SMALL);
        args.extend(["-o", o]);
        let out = run(&bin, &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{name}: {stderr}");
        assert!(stderr.contains(needle), "{name}: {stderr}");
        assert!(png.is_file());
        std::fs::remove_file(&png).unwrap();
    }
    // A gaze off the image is allowed (the fovea is then off-screen; documented in --help).
    let cornell = cornell_box_path();
    let mut args = vec![cornell.to_str().unwrap(), "--gaze", "-100,5000"];
    args.extend(SMALL);
    args.extend(["-o", o]);
    let out = run(&bin, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.is_file());
    std::fs::remove_dir_all(dir).ok();
}

/// The PNG and the EXR of a render are byte-identical with 1 and 2 threads (the EXR is compressed
/// serially: the exr crate's parallel writer stores blocks in completion order).
#[test]
fn cli_images_are_byte_identical_with_one_and_two_threads() {
    let Some(bin) = fovea_binary() else { return };
    let dir = temp_dir("threads");
    let cornell = cornell_box_path();
    for extension in ["png", "exr"] {
        let mut images = Vec::new();
        for threads in ["1", "2"] {
            let output = dir.join(format!("t{threads}.{extension}"));
            let mut args = vec![
                cornell.to_str().unwrap(),
                "--eye",
                "0,1,3.9",
                "--target",
                "0,1,0",
                "--seed",
                "7",
                "--threads",
                threads,
            ];
            // SMALL, but with 32 compressed EXR blocks: the parallel writer put them out of order in
            // 4 of 6 runs at this size.
            args.extend(
                SMALL
                    .iter()
                    .map(|&a| if a == "32x24" { "256x512" } else { a }),
            );
            args.extend(["-o", output.to_str().unwrap()]);
            let out = run(&bin, &args);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            images.push(std::fs::read(&output).unwrap());
        }
        assert!(images[0].len() > 100);
        assert_eq!(
            images[0], images[1],
            "the {extension} files differ between 1 and 2 threads"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

/// With no Vulkan driver at all (the loader pointed at a missing ICD file), `--backend vulkan` fails
/// with a message that says so and writes nothing, and `--backend auto` notes it and renders on the CPU.
#[test]
fn cli_without_a_vulkan_driver_fails_clearly_or_falls_back() {
    let Some(bin) = fovea_binary() else {
        return;
    };
    let dir = temp_dir("no-vulkan");
    let scene = fovea_tests::cornell_box_path();
    let scene = scene.to_str().unwrap();
    let no_driver = |backend: &str, out: &Path| {
        Command::new(&bin)
            .arg("render")
            .arg(scene)
            .args([
                "--backend",
                backend,
                "--resolution",
                "32x24",
                "--spp",
                "1,1,1",
            ])
            .arg("-o")
            .arg(out)
            .env("VK_ICD_FILENAMES", dir.join("missing-icd.json"))
            .env("VK_DRIVER_FILES", dir.join("missing-icd.json"))
            .output()
            .unwrap()
    };
    let vulkan_png = dir.join("vulkan.png");
    let out = no_driver("vulkan", &vulkan_png);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("Vulkan")
            && (stderr.contains("no Vulkan device") || stderr.contains("loader")),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!vulkan_png.exists());

    let auto_png = dir.join("auto.png");
    let out = no_driver("auto", &auto_png);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("rendering on the CPU"), "{stderr}");
    assert!(auto_png.is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// An output that names one of the run's inputs (here the environment map) is refused before anything is
/// read or written: fovea never overwrites its input.
#[test]
fn cli_refuses_to_overwrite_an_input() {
    let Some(bin) = fovea_binary() else {
        return;
    };
    let dir = temp_dir("overwrite-input");
    let map = dir.join("sky.exr");
    let scene = fovea_tests::cornell_box_path();
    let mut args: Vec<&str> = vec![scene.to_str().unwrap()];
    args.extend_from_slice(&SMALL);
    args.extend_from_slice(&[
        "--env-map",
        map.to_str().unwrap(),
        "-o",
        map.to_str().unwrap(),
    ]);
    expect_cli_failure(&bin, &args, "never overwrites its input", &map);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `fovea bench rays` traces a ray file (closest-hit and occlusion records) and reports what it found;
/// a malformed ray file or an absurd `--count` is an error that names it, with no JSON written.
#[test]
fn cli_bench_rays_reads_ray_files_and_rejects_bad_ones() {
    let Some(bin) = fovea_binary() else { return };
    let dir = temp_dir("bench-rays");
    let record = |v: [f32; 8]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    // From the middle of the Cornell box: towards the back wall (a hit), straight up for half a unit
    // (free) and straight down to beyond the floor (blocked).
    let mut rays = record([0.0, 1.0, 0.0, 0.0, 0.0, -1.0, f32::INFINITY, 0.0]);
    rays.extend(record([0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.5, 1.0]));
    rays.extend(record([0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 5.0, 1.0]));
    let ray_file = dir.join("rays.bin");
    std::fs::write(&ray_file, rays).unwrap();
    let json = dir.join("rays.json");
    let cornell = cornell_box_path();
    let bench = |extra: &[&str]| -> Output {
        let mut args = vec![
            "bench",
            "--threads",
            "1",
            "--json",
            json.to_str().unwrap(),
            "rays",
            cornell.to_str().unwrap(),
        ];
        args.extend(extra);
        let out = Command::new(&bin).args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        eprintln!("fovea {args:?}\n  -> {}: {}", out.status, stderr.trim());
        assert!(!stderr.contains("panicked"), "{stderr}");
        out
    };
    let out = bench(&["--rays", ray_file.to_str().unwrap(), "--runs", "1"]);
    assert!(out.status.success());
    let figures: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(figures["closest_rays"], 1);
    assert_eq!(figures["closest_hits"], 1);
    assert_eq!(figures["occlusion_rays"], 2);
    assert_eq!(figures["occluded"], 1);
    std::fs::remove_file(&json).unwrap();

    let out = bench(&["--count", "1000", "--runs", "1"]);
    assert!(out.status.success());
    let figures: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(figures["closest_rays"], 500);
    // Every closest-hit ray starts inside the closed box (its bounds), so nearly all of them hit.
    assert!(figures["closest_hits"].as_u64().unwrap() > 400, "{figures}");
    std::fs::remove_file(&json).unwrap();

    let short = dir.join("short.bin");
    std::fs::write(&short, [0u8; 31]).unwrap();
    for (extra, needle) in [
        (vec!["--rays", short.to_str().unwrap()], "short.bin"),
        (vec!["--rays", "no_such_rays.bin"], "no_such_rays.bin"),
        (vec!["--count", "0"], "--count"),
        (vec!["--runs", "0"], "--runs"),
    ] {
        let out = bench(&extra);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{extra:?} succeeded");
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
        assert!(!json.exists(), "{extra:?} wrote {}", json.display());
    }
    std::fs::remove_dir_all(dir).ok();
}
