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
//! | `KHR_materials_sheen` (`sheenColorFactor`) | `sheen` = the colour's largest component, `sheen_tint` 0 (`sheenRoughnessFactor` has no Burley counterpart: range-checked, and named when not 0) |
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
//!
//! Every number is checked against its specification's range while it is still the file's own value
//! ([`checked_number`]): a value outside it, one that is not a number, or one that single precision
//! cannot hold (1e39, 1e-50) is replaced (clamped into the range, or the default) and returned as a
//! note in [`ExtensionsApplied::replaced`] naming the field, the file's value and what fovea used.
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

/// A specification's range for a number field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecRange {
    pub min: f64,
    pub max: f64,
    /// The range is above `min`, not from it (`attenuationDistance`).
    pub min_exclusive: bool,
}

impl SpecRange {
    /// 0 to 1: factors, weights, colours.
    pub const UNIT: Self = Self {
        min: 0.0,
        max: 1.0,
        min_exclusive: false,
    };
    /// 0 or more: thickness, specular colour.
    pub const NON_NEGATIVE: Self = Self {
        min: 0.0,
        max: f64::INFINITY,
        min_exclusive: false,
    };
    /// Above 0: a distance.
    pub const POSITIVE: Self = Self {
        min: 0.0,
        max: f64::INFINITY,
        min_exclusive: true,
    };
    /// Any number: texture transforms.
    pub const ANY: Self = Self {
        min: f64::NEG_INFINITY,
        max: f64::INFINITY,
        min_exclusive: false,
    };

    /// Whether the file's value `v` lies in the range.
    #[must_use]
    pub fn contains(&self, v: f64) -> bool {
        let above_min = if self.min_exclusive {
            v > self.min
        } else {
            v >= self.min
        };
        above_min && v <= self.max
    }

    /// The range in words, for messages.
    fn describe(&self) -> String {
        match (
            self.min_exclusive,
            self.min.is_finite(),
            self.max.is_finite(),
        ) {
            (_, false, false) => "any number".into(),
            (true, _, false) => format!("above {}", self.min),
            (false, _, false) => format!("{} or more", self.min),
            _ => format!("{} to {}", self.min, self.max),
        }
    }

    /// What fovea uses for the file's value `v` (a finite f64): `v` in f32, saturated to f32's largest
    /// magnitude, then clamped into the range, or `default` below an exclusive minimum.
    fn fix(&self, v: f64, default: f32) -> f32 {
        if self.min_exclusive && v <= self.min {
            return default;
        }
        let clamped = v.clamp(self.min, self.max);
        clamped.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32
    }
}

/// `v` for a message: plain where that is short (`1`, `0.5`), else with an exponent (`3.4028235e38`).
fn shown(v: f32) -> String {
    if v == 0.0 || (v.is_finite() && (1e-4..1e16).contains(&v.abs())) {
        format!("{v}")
    } else {
        format!("{v:?}")
    }
}

/// Several values for a message: `[1, 0.5, 1]`.
fn shown_all(v: &[f32]) -> String {
    let parts: Vec<String> = v.iter().map(|&x| shown(x)).collect();
    format!("[{}]", parts.join(", "))
}

/// Whether `used` is the file's value `v` up to f32 rounding (which is not a change).
fn same_value(used: f32, v: f64) -> bool {
    (f64::from(used) - v).abs() <= 1e-6 * v.abs()
}

/// Number `key` of an extension object as fovea uses it: the file's value when it is a number in
/// `range` that f32 holds; otherwise the value clamped into the range, or `default` (missing, not a
/// number, or not above an exclusive minimum), with a note in `replaced` naming the field, the file's
/// value, why and what is used.
pub fn checked_number(
    ext: &Value,
    key: &str,
    default: f32,
    range: SpecRange,
    replaced: &mut Vec<String>,
) -> f32 {
    let Some(raw) = ext.get(key) else {
        return default;
    };
    let Some(v) = raw.as_f64().filter(|v| v.is_finite()) else {
        replaced.push(format!(
            "{key} {raw} is not a number; used the default {}",
            shown(default)
        ));
        return default;
    };
    let used = range.fix(v, default);
    if !same_value(used, v) {
        let why = if range.contains(v) {
            "is beyond single precision".to_string()
        } else {
            format!(
                "is outside the specification's range ({})",
                range.describe()
            )
        };
        replaced.push(format!("{key} {raw} {why}; used {}", shown(used)));
    }
    used
}

/// An array field of `N` numbers (an RGB colour, a texture transform's pair), each checked as
/// [`checked_number`] checks one (one note for the field); not `N` numbers is `default`, with a note.
pub fn checked_array<const N: usize>(
    ext: &Value,
    key: &str,
    default: [f32; N],
    range: SpecRange,
    replaced: &mut Vec<String>,
) -> [f32; N] {
    let Some(raw) = ext.get(key) else {
        return default;
    };
    let values: Option<Vec<f64>> = raw.as_array().filter(|a| a.len() == N).and_then(|a| {
        a.iter()
            .map(|v| v.as_f64().filter(|x| x.is_finite()))
            .collect()
    });
    let Some(v) = values else {
        replaced.push(format!(
            "{key} {raw} is not {N} numbers; used the default {}",
            shown_all(&default)
        ));
        return default;
    };
    let used: [f32; N] = std::array::from_fn(|c| range.fix(v[c], default[c]));
    if (0..N).any(|c| !same_value(used[c], v[c])) {
        let why = if v.iter().all(|&x| range.contains(x)) {
            "is beyond single precision".to_string()
        } else {
            format!(
                "is outside the specification's range ({})",
                range.describe()
            )
        };
        replaced.push(format!("{key} {raw} {why}; used {}", shown_all(&used)));
    }
    used
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
/// Values it replaces (beyond single precision, or not numbers) are noted in `replaced`.
pub fn texture_transform(
    extensions: Option<&serde_json::Map<String, Value>>,
    replaced: &mut Vec<String>,
) -> Option<TextureTransform> {
    let e = extensions?.get("KHR_texture_transform")?;
    let [ox, oy] = checked_array(e, "offset", [0.0, 0.0], SpecRange::ANY, replaced);
    let [sx, sy] = checked_array(e, "scale", [1.0, 1.0], SpecRange::ANY, replaced);
    let r = checked_number(e, "rotation", 0.0, SpecRange::ANY, replaced);
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
    /// Values the file gave outside their specification's range (or not numbers, or beyond single
    /// precision), each with what fovea used instead ([`checked_number`]).
    pub replaced: Vec<Unsupported>,
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
///
/// Long because each supported extension is one block, in the order of the module's table, and later
/// ones read what earlier ones set (IOR before specular, transmission before volume).
pub fn apply_material_extensions(
    extensions: &serde_json::Map<String, Value>,
    material: &mut Material,
) -> ExtensionsApplied {
    let mut out = ExtensionsApplied::default();
    // The values an extension's object replaced, as notes for `out.replaced`.
    let replaced = |name: &str, notes: Vec<String>, out: &mut ExtensionsApplied| {
        out.replaced
            .extend(notes.iter().map(|what| Unsupported::new(name, what)));
    };
    let texture =
        |ext: &Value, name: &str, key: &'static str, slot, out: &mut ExtensionsApplied| {
            let Some(info) = ext.get(key) else { return };
            match info.get("index").and_then(Value::as_u64) {
                Some(index) => {
                    let mut notes = Vec::new();
                    let transform = texture_transform(
                        info.get("extensions").and_then(Value::as_object),
                        &mut notes,
                    );
                    out.replaced.extend(notes.iter().map(|what| {
                        Unsupported::new("KHR_texture_transform", &format!("{key}: {what}"))
                    }));
                    out.textures.push(ExtensionTexture {
                        slot,
                        role: key,
                        index: index as usize,
                        tex_coord: info.get("texCoord").and_then(Value::as_u64).unwrap_or(0) as u32,
                        transform,
                    });
                }
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
    let ior = match extensions.get("KHR_materials_ior") {
        // The spec allows 0 (an infinite index, Fresnel 1) and 1 upwards.
        Some(e) if e.get("ior").and_then(Value::as_f64) == Some(0.0) => 0.0,
        Some(e) => {
            let mut notes = Vec::new();
            let from_one = SpecRange {
                min: 1.0,
                ..SpecRange::NON_NEGATIVE
            };
            let ior = checked_number(e, "ior", 1.5, from_one, &mut notes);
            replaced("KHR_materials_ior", notes, &mut out);
            ior
        }
        None => 1.5,
    };
    let mut specular_weight = 1.0;
    if let Some(e) = extensions.get("KHR_materials_specular") {
        let name = "KHR_materials_specular";
        let mut notes = Vec::new();
        let colour = checked_array(
            e,
            "specularColorFactor",
            [1.0; 3],
            SpecRange::NON_NEGATIVE,
            &mut notes,
        );
        specular_weight = checked_number(e, "specularFactor", 1.0, SpecRange::UNIT, &mut notes)
            * colour.iter().fold(0.0f32, |m, &c| m.max(c));
        replaced(name, notes, &mut out);
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
        let mut notes = Vec::new();
        let factor = checked_number(e, "transmissionFactor", 0.0, SpecRange::UNIT, &mut notes);
        replaced("KHR_materials_transmission", notes, &mut out);
        // ior 0: Fresnel 1 reflects everything, so nothing is transmitted.
        material.transmission = if ior == 0.0 { 0.0 } else { factor };
        // glTF allows 1 (no refraction); the dielectric needs a little above it.
        material.ior = ior.max(1.01);
        texture(
            e,
            "KHR_materials_transmission",
            "transmissionTexture",
            ExtensionTextureSlot::Transmission,
            &mut out,
        );
        let volume = extensions.get("KHR_materials_volume").map(|v| {
            let mut notes = Vec::new();
            let range = SpecRange::NON_NEGATIVE;
            let thickness = checked_number(v, "thicknessFactor", 0.0, range, &mut notes);
            let colour =
                checked_array(v, "attenuationColor", [1.0; 3], SpecRange::UNIT, &mut notes);
            let distance = checked_number(
                v,
                "attenuationDistance",
                f32::INFINITY,
                SpecRange::POSITIVE,
                &mut notes,
            );
            replaced("KHR_materials_volume", notes, &mut out);
            (thickness, colour, distance)
        });
        match volume {
            Some((thickness, colour, distance)) if thickness > 0.0 => {
                // A closed volume: its inside may absorb.
                material.absorption = absorption_coefficient(colour, distance);
            }
            // No volume: glTF's thin wall, which light passes straight through.
            _ => material.flags |= MATERIAL_THIN_WALLED,
        }
    }
    if let Some(e) = extensions.get("KHR_materials_clearcoat") {
        let name = "KHR_materials_clearcoat";
        let mut notes = Vec::new();
        material.clearcoat = checked_number(e, "clearcoatFactor", 0.0, SpecRange::UNIT, &mut notes);
        material.clearcoat_gloss = 1.0
            - checked_number(
                e,
                "clearcoatRoughnessFactor",
                0.0,
                SpecRange::UNIT,
                &mut notes,
            );
        replaced(name, notes, &mut out);
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
        let name = "KHR_materials_sheen";
        let mut notes = Vec::new();
        let colour = checked_array(e, "sheenColorFactor", [0.0; 3], SpecRange::UNIT, &mut notes);
        let roughness = checked_number(e, "sheenRoughnessFactor", 0.0, SpecRange::UNIT, &mut notes);
        replaced(name, notes, &mut out);
        if roughness != 0.0 {
            out.unsupported.push(Unsupported::new(
                name,
                "sheenRoughnessFactor is not read (Burley's sheen has no roughness)",
            ));
        }
        material.sheen = colour.iter().fold(0.0f32, |m, &c| m.max(c));
        material.sheen_tint = 0.0;
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
        let mut notes = Vec::new();
        material.anisotropic =
            checked_number(e, "anisotropyStrength", 0.0, SpecRange::UNIT, &mut notes);
        let rotation = checked_number(e, "anisotropyRotation", 0.0, SpecRange::ANY, &mut notes);
        replaced("KHR_materials_anisotropy", notes, &mut out);
        if rotation != 0.0 {
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
        // Between 0 and 1 the index is invalid: read as 1, with a note naming it.
        let (m, applied) = apply_all(r#"{"KHR_materials_ior":{"ior":0.5}}"#);
        assert_eq!(m.specular, 0.0);
        assert_eq!(
            applied.replaced[0].what,
            "ior 0.5 is outside the specification's range (1 or more); used 1"
        );
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
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(notes[0].what.contains("sheenRoughnessFactor is not read"));
        assert!(notes[1].what.contains("anisotropyRotation"));
        // Out-of-range values are clamped and malformed ones take the default, each with a note.
        let (m, applied) = apply_all(
            r#"{"KHR_materials_clearcoat":{"clearcoatFactor":7},"KHR_materials_sheen":{"sheenColorFactor":"red"}}"#,
        );
        assert_eq!((m.clearcoat, m.clearcoat_gloss, m.sheen), (1.0, 1.0, 0.0));
        let notes: Vec<String> = applied.replaced.iter().map(|n| n.what.clone()).collect();
        assert_eq!(
            notes,
            [
                "clearcoatFactor 7 is outside the specification's range (0 to 1); used 1",
                "sheenColorFactor \"red\" is not 3 numbers; used the default [0, 0, 0]"
            ]
        );
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

    /// Whether no float parameter of `m` is NaN.
    fn no_nan(m: &Material) -> bool {
        let scalars = [
            m.metallic,
            m.roughness,
            m.anisotropic,
            m.specular,
            m.sheen,
            m.clearcoat,
            m.clearcoat_gloss,
            m.transmission,
            m.ior,
        ];
        scalars
            .iter()
            .chain(&m.base_color)
            .chain(&m.emission)
            .chain(&m.absorption)
            .all(|v| !v.is_nan())
    }

    #[test]
    fn a_value_the_file_gives_out_of_range_is_named_with_what_fovea_used() {
        let notes = |json: &str| -> Vec<String> {
            let (m, applied) = apply_all(json);
            assert!(no_nan(&m), "{json}: {m:?}");
            applied
                .replaced
                .iter()
                .map(|n| format!("{} {}", n.extension, n.what))
                .collect()
        };
        let glass = r#""KHR_materials_transmission":{"transmissionFactor":1}"#;
        // A volume's attenuation distance of 0 or less is not "clear glass" without a word.
        assert_eq!(
            notes(&format!(r#"{{{glass},"KHR_materials_volume":{{"thicknessFactor":1,"attenuationDistance":0}}}}"#)),
            ["KHR_materials_volume attenuationDistance 0 is outside the specification's range (above 0); used inf"]
        );
        assert_eq!(
            notes(&format!(r#"{{{glass},"KHR_materials_volume":{{"thicknessFactor":1,"attenuationColor":[2,0.5,1]}}}}"#)),
            ["KHR_materials_volume attenuationColor [2,0.5,1] is outside the specification's range (0 to 1); used [1, 0.5, 1]"]
        );
        // Beyond single precision: overflow and underflow.
        // (serde_json reads 1e-50 as 9.999999999999999e-51: the message shows the value as read.)
        let underflow = notes(r#"{"KHR_materials_clearcoat":{"clearcoatFactor":1e-50}}"#);
        assert!(
            underflow.len() == 1
                && underflow[0].starts_with("KHR_materials_clearcoat clearcoatFactor ")
                && underflow[0].ends_with("e-51 is beyond single precision; used 0"),
            "{underflow:?}"
        );
        let (m, applied) = apply_all(
            r#"{"KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatTexture":{"index":0,
                "extensions":{"KHR_texture_transform":{"scale":[1e39,2],"rotation":"x"}}}}}"#,
        );
        let notes: Vec<&str> = applied.replaced.iter().map(|n| n.what.as_str()).collect();
        assert_eq!(
            notes,
            [
                "clearcoatTexture: scale [1e+39,2] is beyond single precision; used [3.4028235e38, 2]",
                "clearcoatTexture: rotation \"x\" is not a number; used the default 0"
            ]
        );
        assert!(applied.textures[0]
            .transform
            .unwrap()
            .matrix
            .iter()
            .all(|v| v.is_finite()));
        assert_eq!(m.clearcoat, 1.0);
    }

    /// Every number field of every mapped extension set to -1, 0, 2, 1e39, 1e-50 and a string: a value
    /// outside the specification's range, or one single precision cannot hold, gets a note naming it
    /// (no silent change), one inside gets none, and no material parameter is NaN.
    #[test]
    fn a_sweep_of_every_field_finds_no_silent_change() {
        const IOR: &str = "ior";
        // (extension, field, values per field, range; `IOR` also allows 0), and the extensions it
        // needs beside it.
        let fields: [(&str, &str, usize, SpecRange, &str); 13] = [
            (
                "KHR_materials_ior",
                "ior",
                1,
                SpecRange {
                    min: 1.0,
                    ..SpecRange::NON_NEGATIVE
                },
                "",
            ),
            (
                "KHR_materials_specular",
                "specularFactor",
                1,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_specular",
                "specularColorFactor",
                3,
                SpecRange::NON_NEGATIVE,
                "",
            ),
            (
                "KHR_materials_transmission",
                "transmissionFactor",
                1,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_volume",
                "thicknessFactor",
                1,
                SpecRange::NON_NEGATIVE,
                "glass",
            ),
            (
                "KHR_materials_volume",
                "attenuationColor",
                3,
                SpecRange::UNIT,
                "glass",
            ),
            (
                "KHR_materials_volume",
                "attenuationDistance",
                1,
                SpecRange::POSITIVE,
                "glass",
            ),
            (
                "KHR_materials_clearcoat",
                "clearcoatFactor",
                1,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_clearcoat",
                "clearcoatRoughnessFactor",
                1,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_sheen",
                "sheenColorFactor",
                3,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_sheen",
                "sheenRoughnessFactor",
                1,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_anisotropy",
                "anisotropyStrength",
                1,
                SpecRange::UNIT,
                "",
            ),
            (
                "KHR_materials_anisotropy",
                "anisotropyRotation",
                1,
                SpecRange::ANY,
                "",
            ),
        ];
        let values: [(&str, Option<f64>); 6] = [
            ("-1", Some(-1.0)),
            ("0", Some(0.0)),
            ("2", Some(2.0)),
            ("1e39", None),
            ("1e-50", None),
            ("\"NaN\"", None),
        ];
        let (mut cases, mut silent, mut spurious) = (0, Vec::new(), Vec::new());
        let mut check = |json: String, field: &str, expect_note: bool| {
            let (m, applied) = apply_all(&json);
            assert!(no_nan(&m), "{json}: {m:?}");
            let noted = applied.replaced.iter().any(|n| n.what.contains(field));
            cases += 1;
            if expect_note && !noted {
                silent.push(json);
            } else if !expect_note && !applied.replaced.is_empty() {
                spurious.push(format!("{json}: {:?}", applied.replaced));
            }
        };
        for (extension, field, n, range, needs) in fields {
            for (text, value) in values {
                let value_json = if n == 1 {
                    text.to_string()
                } else {
                    format!("[{text},{text},{text}]")
                };
                let glass = if needs == "glass" {
                    r#""KHR_materials_transmission":{"transmissionFactor":1},"#
                } else {
                    ""
                };
                let json = format!(r#"{{{glass}"{extension}":{{"{field}":{value_json}}}}}"#);
                // Representable values keep their meaning; the others must be named.
                let fine = value.is_some_and(|v| range.contains(v) || (field == IOR && v == 0.0));
                check(json, field, !fine);
            }
        }
        for (key, n) in [("offset", 2), ("scale", 2), ("rotation", 1)] {
            for (text, value) in values {
                let value_json = if n == 1 {
                    text.to_string()
                } else {
                    format!("[{text},{text}]")
                };
                let json = format!(
                    r#"{{"KHR_materials_clearcoat":{{"clearcoatTexture":{{"index":0,
                        "extensions":{{"KHR_texture_transform":{{"{key}":{value_json}}}}}}}}}}}"#
                );
                check(json, key, value.is_none());
            }
        }
        assert_eq!(cases, 16 * 6);
        assert!(silent.is_empty(), "silent changes: {silent:#?}");
        assert!(
            spurious.is_empty(),
            "notes for values in range: {spurious:#?}"
        );
    }

    #[test]
    fn unknown_extensions_are_reported_with_their_consequence() {
        let (m, notes) = apply(r#"{"KHR_materials_iridescence":{"iridescenceFactor":1}}"#);
        assert_eq!(m, Material::default());
        assert_eq!(notes.len(), 1);
        assert!(notes[0].what.contains("iridescence"));
    }
}
