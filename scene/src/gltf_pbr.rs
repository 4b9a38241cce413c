//! glTF PBR material extensions mapped onto the Disney parameters of `fovea_core::scene::Material`.
//!
//! glTF's layered model (glTF 2.0 Appendix B and the `KHR_materials_*` specifications) and Burley's
//! principled BRDF share their base (metallic-roughness GGX over a diffuse base); the extensions map as
//! follows, the approximations named:
//!
//! | extension | fovea |
//! |---|---|
//! | `KHR_materials_transmission` (`transmissionFactor`) | `transmission`: the rough dielectric interface of `fovea_core::bsdf::dielectric` (GGX refraction, Walter et al. 2007) with the material's roughness and `ior`, tinted by the base colour, in place of the non-metallic base |
//! | `KHR_materials_volume` (`thicknessFactor` > 0) | the mesh is a closed volume: its front faces are the outside of the interface, and `attenuationColor`/`attenuationDistance` give its inside's absorption (`Material::absorption`, Beer–Lambert, [`absorption_coefficient`]). Without the extension glTF means a thin wall: `MATERIAL_THIN_WALLED`, straight-through transmission (`RoughDielectric::thin`) |
//! | `KHR_materials_ior` (`ior`) | `specular` = F0 / 0.08 with F0 = ((ior − 1) / (ior + 1))² (Burley's dielectric F0 is 0.08 · specular; ior 1.5 gives 0.5, diamond's 2.4 gives 2.1); `ior: 0`, an infinite index, is F0 = 1 (`SPECULAR_MAX`) and transmits nothing; other values below 1 are warned about and read as 1 |
//! | `KHR_materials_specular` (`specularFactor`, `specularColorFactor`) | F0 above × `specularFactor` × the colour's largest component (Burley's specular is not coloured) |
//! | `KHR_materials_clearcoat` (`clearcoatFactor`, `clearcoatRoughnessFactor`) | `clearcoat`, `clearcoat_gloss` = 1 − roughness |
//! | `KHR_materials_sheen` (`sheenColorFactor`) | `sheen` = the colour's largest component, `sheen_tint` 0 (`sheenRoughnessFactor` has no Burley counterpart) |
//! | `KHR_materials_anisotropy` (`anisotropyStrength`) | `anisotropic` (along the shading frame's tangent: `anisotropyRotation` is not read) |
//! | `KHR_materials_unlit` | the base colour (and texture) becomes the emission, the BRDF black, and `MATERIAL_UNLIT` shows it to camera rays only (not a light, not in reflections) |
//! | `KHR_materials_emissive_strength` | read by the loader (`emission` × strength) |
//! | `KHR_texture_transform` (`offset`, `rotation`, `scale`, `texCoord`) | the texture record's coordinate transform ([`texture_transform`]); its `texCoord` overrides the texture's set |
//!
//! The extensions' textures (`transmissionTexture`, `clearcoatTexture`, `clearcoatRoughnessTexture`,
//! `sheenColorTexture`, `specularTexture`, `specularColorTexture`, `anisotropyTexture`) multiply their
//! factor by the channel their specification names (`fovea_core::material::shading`); they are returned
//! as [`ExtensionTexture`]s for the loader to decode.
//!
//! What a material asks for and fovea cannot render (`sheenRoughnessTexture`, `clearcoatNormalTexture`,
//! the anisotropy direction, iridescence, dispersion) is returned as [`Unsupported`] notes: the loader
//! warns once per extension, naming the materials.
use fovea_core::bsdf::disney::SPECULAR_MAX;
use fovea_core::scene::{Material, MATERIAL_LAMBERTIAN, MATERIAL_THIN_WALLED, MATERIAL_UNLIT};
use gltf::json::Value;

/// The extensions this module maps (in part, see the module table): the material extensions of
/// [`apply_material_extensions`] and the texture references' [`texture_transform`].
pub const MAPPED_EXTENSIONS: [&str; 9] = [
    "KHR_texture_transform",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_anisotropy",
    "KHR_materials_unlit",
];

/// What a material uses that fovea leaves out: the extension and what is lost.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unsupported {
    pub extension: String,
    pub what: String,
}

impl Unsupported {
    fn new(extension: &str, what: &str) -> Self {
        Self {
            extension: extension.to_owned(),
            what: what.to_owned(),
        }
    }
}

/// What an unknown extension's absence means, for the warning.
fn consequence(extension: &str) -> &'static str {
    match extension {
        "KHR_materials_iridescence" => "has no thin-film iridescence",
        "KHR_materials_dispersion" => "has no dispersion",
        "KHR_materials_diffuse_transmission" => "has no diffuse transmission",
        "KHR_materials_variants" => "shows its default variant",
        _ => "ignores what the extension describes",
    }
}

/// A number field of an extension object, or `default` (also for a non-finite or non-number value).
fn number(ext: &Value, key: &str, default: f32) -> f32 {
    match ext.get(key).and_then(Value::as_f64) {
        Some(v) if v.is_finite() => v as f32,
        _ => default,
    }
}

/// An RGB field, or `default`.
fn rgb(ext: &Value, key: &str, default: [f32; 3]) -> [f32; 3] {
    match ext.get(key).and_then(Value::as_array) {
        Some(a) if a.len() == 3 => {
            let mut out = default;
            for (o, v) in out.iter_mut().zip(a) {
                match v.as_f64() {
                    Some(x) if x.is_finite() => *o = x as f32,
                    _ => return default,
                }
            }
            out
        }
        _ => default,
    }
}

/// A texture reference's `KHR_texture_transform`: `uv' = T R S uv` (the extension's offset, rotation in
/// radians, counter-clockwise in UV space, and scale), as the row-major 2 × 3 matrix `[m0 m1 tx; m2 m3
/// ty]` stored in `matrix` (`[m0, m1, m2, m3, tx, ty]`), and its `texCoord` override if any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureTransform {
    pub matrix: [f32; 6],
    pub tex_coord: Option<u32>,
}

/// The `KHR_texture_transform` of a texture reference's `extensions` object, if it has one.
#[must_use]
pub fn texture_transform(
    extensions: Option<&serde_json::Map<String, Value>>,
) -> Option<TextureTransform> {
    let e = extensions?.get("KHR_texture_transform")?;
    let pair = |key: &str, default: [f32; 2]| match e.get(key).and_then(Value::as_array) {
        Some(a) if a.len() == 2 => match (a[0].as_f64(), a[1].as_f64()) {
            (Some(x), Some(y)) if x.is_finite() && y.is_finite() => [x as f32, y as f32],
            _ => default,
        },
        _ => default,
    };
    let [ox, oy] = pair("offset", [0.0, 0.0]);
    let [sx, sy] = pair("scale", [1.0, 1.0]);
    let r = number(e, "rotation", 0.0);
    let (sin, cos) = r.sin_cos();
    Some(TextureTransform {
        matrix: [cos * sx, sin * sy, -sin * sx, cos * sy, ox, oy],
        tex_coord: e.get("texCoord").and_then(Value::as_u64).map(|t| t as u32),
    })
}

/// The texture-coordinate set a texture reference reads: its `KHR_texture_transform`'s `texCoord` if it
/// has one (which overrides), else its own `texCoord`.
#[must_use]
pub fn coordinate_set(tex_coord: u32, transform: Option<&TextureTransform>) -> u32 {
    transform.and_then(|t| t.tex_coord).unwrap_or(tex_coord)
}

/// Burley's `specular` for a dielectric of index `ior` and a glTF specular weight: F0 / 0.08, with
/// F0 = ((ior − 1) / (ior + 1))² · weight at most 1. `KHR_materials_ior`'s `ior: 0` means an infinite
/// index, F0 = 1 (what converted specular-glossiness assets use); other values below 1 are invalid and
/// read as 1 (the loader warns).
#[must_use]
pub fn specular_from_ior(ior: f32, weight: f32) -> f32 {
    let f0 = if ior == 0.0 {
        1.0
    } else {
        let ior = ior.max(1.0);
        ((ior - 1.0) / (ior + 1.0)).powi(2)
    };
    ((f0 * weight).min(1.0) / 0.08).clamp(0.0, SPECULAR_MAX)
}

/// A material field that one of the extensions' textures fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExtensionTextureSlot {
    Transmission,
    Clearcoat,
    ClearcoatRoughness,
    Sheen,
    Specular,
    SpecularColor,
    Anisotropy,
}

impl ExtensionTextureSlot {
    /// The field of `material` that holds the texture.
    pub fn field(self, material: &mut Material) -> &mut u32 {
        match self {
            Self::Transmission => &mut material.transmission_texture,
            Self::Clearcoat => &mut material.clearcoat_texture,
            Self::ClearcoatRoughness => &mut material.clearcoat_roughness_texture,
            Self::Sheen => &mut material.sheen_texture,
            Self::Specular => &mut material.specular_texture,
            Self::SpecularColor => &mut material.specular_color_texture,
            Self::Anisotropy => &mut material.anisotropy_texture,
        }
    }

    /// Whether the texture holds a colour, which glTF stores sRGB-encoded (`sheenColorTexture`,
    /// `specularColorTexture`); the others hold linear data.
    #[must_use]
    pub fn srgb(self) -> bool {
        matches!(self, Self::Sheen | Self::SpecularColor)
    }
}

/// A texture an extension names (a glTF `textureInfo`: `{"index", "texCoord", "extensions"}`), for the
/// loader to decode and store in `slot`.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtensionTexture {
    pub slot: ExtensionTextureSlot,
    /// The JSON key (`"transmissionTexture"`), for messages.
    pub role: &'static str,
    /// The glTF texture index.
    pub index: usize,
    pub tex_coord: u32,
    pub transform: Option<TextureTransform>,
}

/// What [`apply_material_extensions`] leaves to the loader: the textures to decode and what cannot be
/// rendered.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExtensionsApplied {
    pub textures: Vec<ExtensionTexture>,
    pub unsupported: Vec<Unsupported>,
}

/// The absorption coefficient σₐ = −ln(c) / d of `KHR_materials_volume`'s `attenuationColor` c and
/// `attenuationDistance` d (world units): light that travels d inside keeps the fraction c. Zero for the
/// defaults (white, infinite distance); a zero channel of c absorbs as 10⁻⁶ does.
#[must_use]
pub fn absorption_coefficient(attenuation_color: [f32; 3], attenuation_distance: f32) -> [f32; 3] {
    if !(attenuation_distance > 0.0 && attenuation_distance.is_finite()) {
        return [0.0; 3];
    }
    // A tiny distance overflows to +inf: as opaque as f32 allows.
    attenuation_color
        .map(|c| (-c.clamp(1e-6, 1.0).ln() / attenuation_distance).clamp(0.0, f32::MAX))
}

/// Applies the material extensions of `extensions` (the material's `extensions` object, as JSON) to
/// `material` (whose textures are already set: unlit emits the base colour texture); returns the
/// extensions' textures for the loader to decode and what could not be rendered.
pub fn apply_material_extensions(
    extensions: &serde_json::Map<String, Value>,
    material: &mut Material,
) -> ExtensionsApplied {
    let mut out = ExtensionsApplied::default();
    let texture =
        |ext: &Value, name: &str, key: &'static str, slot, out: &mut ExtensionsApplied| {
            let Some(info) = ext.get(key) else { return };
            match info.get("index").and_then(Value::as_u64) {
                Some(index) => out.textures.push(ExtensionTexture {
                    slot,
                    role: key,
                    index: index as usize,
                    tex_coord: info.get("texCoord").and_then(Value::as_u64).unwrap_or(0) as u32,
                    transform: texture_transform(info.get("extensions").and_then(Value::as_object)),
                }),
                None => out.unsupported.push(Unsupported::new(
                    name,
                    &format!("{key} has no texture index; ignored"),
                )),
            }
        };
    let texture_ignored = |ext: &Value, name: &str, keys: &[&str], out: &mut ExtensionsApplied| {
        for key in keys {
            if ext.get(*key).is_some() {
                out.unsupported
                    .push(Unsupported::new(name, &format!("{key} is not read")));
            }
        }
    };
    let ior = extensions
        .get("KHR_materials_ior")
        .map_or(1.5, |e| number(e, "ior", 1.5));
    // The spec allows 0 (an infinite index) and 1 upwards.
    if ior != 0.0 && !(ior >= 1.0) {
        out.unsupported.push(Unsupported::new(
            "KHR_materials_ior",
            &format!("ior {ior} is neither 0 nor at least 1 (the spec's values); read as 1"),
        ));
    }
    let mut specular_weight = 1.0;
    if let Some(e) = extensions.get("KHR_materials_specular") {
        let colour = rgb(e, "specularColorFactor", [1.0; 3]);
        specular_weight = number(e, "specularFactor", 1.0).max(0.0)
            * colour.iter().fold(0.0f32, |m, &c| m.max(c)).max(0.0);
        let name = "KHR_materials_specular";
        texture(
            e,
            name,
            "specularTexture",
            ExtensionTextureSlot::Specular,
            &mut out,
        );
        texture(
            e,
            name,
            "specularColorTexture",
            ExtensionTextureSlot::SpecularColor,
            &mut out,
        );
    }
    if extensions.contains_key("KHR_materials_ior")
        || extensions.contains_key("KHR_materials_specular")
    {
        material.specular = specular_from_ior(ior, specular_weight);
    }
    if let Some(e) = extensions.get("KHR_materials_transmission") {
        // ior 0: Fresnel 1 reflects everything, so nothing is transmitted.
        material.transmission = if ior == 0.0 {
            0.0
        } else {
            number(e, "transmissionFactor", 0.0).clamp(0.0, 1.0)
        };
        // glTF allows 1 (no refraction); the dielectric needs a little above it.
        material.ior = ior.max(1.01);
        texture(
            e,
            "KHR_materials_transmission",
            "transmissionTexture",
            ExtensionTextureSlot::Transmission,
            &mut out,
        );
        match extensions.get("KHR_materials_volume") {
            Some(v) if number(v, "thicknessFactor", 0.0) > 0.0 => {
                // A closed volume: its inside may absorb.
                material.absorption = absorption_coefficient(
                    rgb(v, "attenuationColor", [1.0; 3]),
                    number(v, "attenuationDistance", f32::INFINITY),
                );
            }
            // No volume: glTF's thin wall, which light passes straight through.
            _ => material.flags |= MATERIAL_THIN_WALLED,
        }
    }
    if let Some(e) = extensions.get("KHR_materials_clearcoat") {
        material.clearcoat = number(e, "clearcoatFactor", 0.0).clamp(0.0, 1.0);
        material.clearcoat_gloss = 1.0 - number(e, "clearcoatRoughnessFactor", 0.0).clamp(0.0, 1.0);
        let name = "KHR_materials_clearcoat";
        texture(
            e,
            name,
            "clearcoatTexture",
            ExtensionTextureSlot::Clearcoat,
            &mut out,
        );
        texture(
            e,
            name,
            "clearcoatRoughnessTexture",
            ExtensionTextureSlot::ClearcoatRoughness,
            &mut out,
        );
        texture_ignored(e, name, &["clearcoatNormalTexture"], &mut out);
    }
    if let Some(e) = extensions.get("KHR_materials_sheen") {
        let colour = rgb(e, "sheenColorFactor", [0.0; 3]);
        material.sheen = colour.iter().fold(0.0f32, |m, &c| m.max(c)).clamp(0.0, 1.0);
        material.sheen_tint = 0.0;
        let name = "KHR_materials_sheen";
        texture(
            e,
            name,
            "sheenColorTexture",
            ExtensionTextureSlot::Sheen,
            &mut out,
        );
        texture_ignored(e, name, &["sheenRoughnessTexture"], &mut out);
    }
    if let Some(e) = extensions.get("KHR_materials_anisotropy") {
        material.anisotropic = number(e, "anisotropyStrength", 0.0).clamp(0.0, 1.0);
        if number(e, "anisotropyRotation", 0.0) != 0.0 {
            out.unsupported.push(Unsupported::new(
                "KHR_materials_anisotropy",
                "anisotropyRotation is not read (the highlight follows the tangent)",
            ));
        }
        let name = "KHR_materials_anisotropy";
        texture(
            e,
            name,
            "anisotropyTexture",
            ExtensionTextureSlot::Anisotropy,
            &mut out,
        );
        if e.get("anisotropyTexture").is_some() {
            out.unsupported.push(Unsupported::new(
                name,
                "anisotropyTexture's direction (RG) is not read, only its strength (B)",
            ));
        }
    }
    if extensions.contains_key("KHR_materials_unlit") {
        let [r, g, b, _] = material.base_color;
        material.emission = [r, g, b, 0.0];
        material.emission_texture = material.base_color_texture;
        material.base_color = [0.0, 0.0, 0.0, material.base_color[3]];
        material.metallic = 0.0;
        material.specular = 0.0;
        material.sheen = 0.0;
        material.clearcoat = 0.0;
        material.flags |= MATERIAL_UNLIT | MATERIAL_LAMBERTIAN;
    }
    for name in extensions.keys() {
        if !MAPPED_EXTENSIONS.contains(&name.as_str()) {
            out.unsupported
                .push(Unsupported::new(name, consequence(name)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(json: &str) -> (Material, Vec<Unsupported>) {
        let (m, applied) = apply_all(json);
        (m, applied.unsupported)
    }

    fn apply_all(json: &str) -> (Material, ExtensionsApplied) {
        let map: serde_json::Map<String, Value> = serde_json::from_str(json).unwrap();
        let mut m = Material::default();
        let applied = apply_material_extensions(&map, &mut m);
        (m, applied)
    }

    #[test]
    fn ior_sets_the_dielectric_reflectance() {
        assert!((specular_from_ior(1.5, 1.0) - 0.5).abs() < 1e-6);
        let (m, notes) = apply(r#"{"KHR_materials_ior":{"ior":1.33}}"#);
        let f0 = (0.33f32 / 2.33).powi(2);
        assert!((m.specular - f0 / 0.08).abs() < 1e-6, "{}", m.specular);
        assert!(notes.is_empty());
        assert_eq!(
            apply(r#"{"KHR_materials_ior":{"ior":1.0}}"#).0.specular,
            0.0
        );
        // Beyond Burley's 1: diamond's F0 of 0.17.
        let diamond = apply(r#"{"KHR_materials_ior":{"ior":2.4}}"#).0.specular;
        assert!(
            (diamond - (1.4f32 / 3.4).powi(2) / 0.08).abs() < 1e-5,
            "{diamond}"
        );
        // ior 0: an infinite index, Fresnel 1 (F0 = 1), and nothing transmits.
        let (m, notes) = apply(
            r#"{"KHR_materials_ior":{"ior":0},"KHR_materials_transmission":{"transmissionFactor":1}}"#,
        );
        assert_eq!((m.specular, m.transmission), (SPECULAR_MAX, 0.0));
        assert!(notes.is_empty(), "{notes:?}");
        // Between 0 and 1 the index is invalid: read as 1, with a warning naming it.
        let (m, notes) = apply(r#"{"KHR_materials_ior":{"ior":0.5}}"#);
        assert_eq!(m.specular, 0.0);
        assert!(notes.iter().any(|n| n.what.contains("0.5")), "{notes:?}");
    }

    #[test]
    fn specular_scales_f0_and_names_its_textures() {
        let (m, applied) = apply_all(
            r#"{"KHR_materials_specular":{"specularFactor":0.5,"specularColorFactor":[0.2,0.8,0.4],
                "specularTexture":{"index":0},"specularColorTexture":{"index":2,"texCoord":1}}}"#,
        );
        assert!(
            (m.specular - 0.5 * 0.5 * 0.8).abs() < 1e-6,
            "{}",
            m.specular
        );
        assert!(applied.unsupported.is_empty(), "{:?}", applied.unsupported);
        let t = &applied.textures;
        assert_eq!(t.len(), 2);
        assert_eq!(
            (t[0].slot, t[0].index, t[0].tex_coord),
            (ExtensionTextureSlot::Specular, 0, 0)
        );
        assert_eq!(
            (t[1].slot, t[1].index, t[1].tex_coord),
            (ExtensionTextureSlot::SpecularColor, 2, 1)
        );
        assert!(!t[0].slot.srgb() && t[1].slot.srgb());
    }

    #[test]
    fn every_extension_texture_fills_its_slot() {
        let (_, applied) = apply_all(
            r#"{"KHR_materials_transmission":{"transmissionFactor":1,"transmissionTexture":{"index":1}},
                "KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatTexture":{"index":2},
                    "clearcoatRoughnessTexture":{"index":3,
                        "extensions":{"KHR_texture_transform":{"scale":[2,2]}}},
                    "clearcoatNormalTexture":{"index":4}},
                "KHR_materials_sheen":{"sheenColorFactor":[1,1,1],"sheenColorTexture":{"index":5},
                    "sheenRoughnessTexture":{"index":6}},
                "KHR_materials_anisotropy":{"anisotropyStrength":1,"anisotropyTexture":{"index":7}},
                "KHR_materials_specular":{"specularTexture":{"texCoord":0}}}"#,
        );
        let mut m = Material::default();
        for t in &applied.textures {
            *t.slot.field(&mut m) = t.index as u32;
        }
        assert_eq!(
            [
                m.transmission_texture,
                m.clearcoat_texture,
                m.clearcoat_roughness_texture,
                m.sheen_texture,
                m.anisotropy_texture
            ],
            [1, 2, 3, 5, 7]
        );
        let scaled = applied.textures[2].transform.expect("transform read");
        assert_eq!(scaled.matrix[0], 2.0);
        // Read nowhere: the clear coat's own normal map, sheen roughness, the anisotropy direction
        // and a reference without an index.
        let notes: Vec<&str> = applied
            .unsupported
            .iter()
            .map(|u| u.what.as_str())
            .collect();
        assert_eq!(notes.len(), 4, "{notes:?}");
        for key in [
            "clearcoatNormalTexture",
            "sheenRoughnessTexture",
            "direction",
            "no texture index",
        ] {
            assert!(notes.iter().any(|n| n.contains(key)), "{key}: {notes:?}");
        }
    }

    #[test]
    fn clearcoat_sheen_and_anisotropy_set_their_lobes() {
        let (m, notes) = apply(
            r#"{"KHR_materials_clearcoat":{"clearcoatFactor":0.8,"clearcoatRoughnessFactor":0.25},
                "KHR_materials_sheen":{"sheenColorFactor":[0.1,0.6,0.3],"sheenRoughnessFactor":0.5},
                "KHR_materials_anisotropy":{"anisotropyStrength":0.7,"anisotropyRotation":1.0}}"#,
        );
        assert_eq!((m.clearcoat, m.clearcoat_gloss), (0.8, 0.75));
        assert_eq!((m.sheen, m.sheen_tint), (0.6, 0.0));
        assert_eq!(m.anisotropic, 0.7);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].what.contains("anisotropyRotation"));
        // Out-of-range values are clamped; malformed ones take the default.
        let (m, _) = apply(
            r#"{"KHR_materials_clearcoat":{"clearcoatFactor":7},"KHR_materials_sheen":{"sheenColorFactor":"red"}}"#,
        );
        assert_eq!((m.clearcoat, m.clearcoat_gloss, m.sheen), (1.0, 1.0, 0.0));
    }

    #[test]
    fn unlit_emits_its_base_colour_and_is_no_light() {
        let map: serde_json::Map<String, Value> =
            serde_json::from_str(r#"{"KHR_materials_unlit":{}}"#).unwrap();
        let mut m = Material {
            base_color: [0.2, 0.4, 0.6, 0.9],
            base_color_texture: 3,
            ..Material::default()
        };
        assert_eq!(
            apply_material_extensions(&map, &mut m),
            ExtensionsApplied::default()
        );
        assert_eq!(m.emission, [0.2, 0.4, 0.6, 0.0]);
        assert_eq!(m.emission_texture, 3);
        assert_eq!(m.base_color, [0.0, 0.0, 0.0, 0.9]);
        assert_eq!((m.metallic, m.specular), (0.0, 0.0));
        assert_ne!(m.flags & MATERIAL_UNLIT, 0);
        assert_ne!(m.flags & MATERIAL_LAMBERTIAN, 0);
    }

    #[test]
    fn transmission_and_volume_make_a_refracting_interface() {
        let (m, notes) = apply(
            r#"{"KHR_materials_transmission":{"transmissionFactor":0.9},"KHR_materials_ior":{"ior":1.45},
                "KHR_materials_volume":{"thicknessFactor":0.5}}"#,
        );
        assert_eq!((m.transmission, m.ior), (0.9, 1.45));
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!(m.flags & MATERIAL_THIN_WALLED, 0);
        assert_eq!(m.absorption, [0.0; 3]);
        // No volume: a thin wall, which absorbs nothing.
        let (m, notes) = apply(r#"{"KHR_materials_transmission":{"transmissionFactor":1}}"#);
        assert_eq!((m.transmission, m.ior), (1.0, 1.5));
        assert_ne!(m.flags & MATERIAL_THIN_WALLED, 0);
        assert!(notes.is_empty(), "{notes:?}");
        // A volume with attenuation: light that travels 2 units keeps half its red.
        let (m, notes) = apply(
            r#"{"KHR_materials_transmission":{"transmissionFactor":1},
                "KHR_materials_volume":{"thicknessFactor":1,"attenuationColor":[0.5,1,0],"attenuationDistance":2}}"#,
        );
        assert!(notes.is_empty(), "{notes:?}");
        assert!((m.absorption[0] - std::f32::consts::LN_2 / 2.0).abs() < 1e-6);
        assert_eq!(m.absorption[1], 0.0);
        assert!((m.absorption[2] - 1e-6f32.ln().abs() / 2.0).abs() < 1e-4);
        assert!((-m.absorption[0] * 2.0).exp() - 0.5 < 1e-6);
        // The default distance is infinite: no absorption.
        assert_eq!(absorption_coefficient([0.5; 3], f32::INFINITY), [0.0; 3]);
        assert_eq!(absorption_coefficient([0.5; 3], -1.0), [0.0; 3]);
        assert_eq!(absorption_coefficient([0.5; 3], 1e-45), [f32::MAX; 3]);
    }

    #[test]
    fn unknown_extensions_are_reported_with_their_consequence() {
        let (m, notes) = apply(r#"{"KHR_materials_iridescence":{"iridescenceFactor":1}}"#);
        assert_eq!(m, Material::default());
        assert_eq!(notes.len(), 1);
        assert!(notes[0].what.contains("iridescence"));
    }
}
