//! The class of every channel of a colour file (issue 29): *colour*, which holds light and is
//! blurred with exactly the weights the beauty gets, or *data*, which describes the surface
//! (depth, vectors, positions, normals, UVs, IDs, Cryptomatte) and comes back unchanged.
//!
//! In: a channel's name (and, for Cryptomatte, the header's `cryptomatte/*/name`
//! attributes). Out: its [`LayerClass`]. Used by the read (which channels ride with the
//! beauty and which are passed through) and by `shutter info`, which prints each class.
//!
//! The rule, in order:
//! 1. a channel of a layer that a `cryptomatte/<key>/name` attribute names (or whose layer
//!    starts with `crypto`) is data: its values are IDs and coverage ranks, not light;
//! 2. a channel any of whose layer's dot-separated names is a known data name (`depth`, `z`,
//!    `mist`, `vector`, `velocity`, `motion`, `motionvector`, `forward`, `backward`,
//!    `position`, `p`, `pref`, `pworld`, `n`, `normal`, `nworld`, `uv`, `st`, `id`,
//!    `objectid`, `materialid`, `indexob`, `indexma`, any case) is data — Arnold writes its
//!    normals as `N.R`, `N.G`, `N.B`, colour by their letters alone;
//! 3. a channel whose own name is R, G, B, A or Y (any case; `red`, `green`, `blue`,
//!    `alpha` too) is colour: `diffuse.R`, `ViewLayer.Emit.G`, a layer's own `specular.A`;
//! 4. every other channel is data: `Z`, `velocity.X`, `ViewLayer.Normal.X`, `uv.U`.
//!
//! A rule that cannot see a layer's meaning by its name errs towards data, which comes back
//! as it was: a light layer misread as data is left sharp (and visible as such), while data
//! misread as colour would be averaged into values that mean nothing.

pub use crate::frame::LayerClass;

/// The known names of data layers (rule 2), lower case.
const DATA_LAYERS: &[&str] = &[
    "depth",
    "z",
    "zdepth",
    "mist",
    "vector",
    "vectors",
    "velocity",
    "motion",
    "motionvector",
    "motionvectors",
    "forward",
    "backward",
    "position",
    "p",
    "pref",
    "pworld",
    "n",
    "normal",
    "normals",
    "nworld",
    "uv",
    "st",
    "id",
    "objectid",
    "object_id",
    "materialid",
    "material_id",
    "indexob",
    "indexma",
];

/// The names of colour components (rule 3), lower case.
const COLOUR_COMPONENTS: &[&str] = &["r", "g", "b", "a", "y", "red", "green", "blue", "alpha"];

/// A channel name split at its last dot: (layer, component); the layer is empty for a
/// channel of no layer (`R`, `Z`).
pub fn split(name: &str) -> (&str, &str) {
    match name.rfind('.') {
        Some(dot) => (&name[..dot], &name[dot + 1..]),
        None => ("", name),
    }
}

/// The class a preset's `[layers]` table gives channel `name` (as the read names it:
/// `part.channel` where the part has a name): its layer's (`diffuse` for `diffuse.R`), or, for
/// a channel of no layer (`Z`), its own name's.
pub fn preset_class(
    layers: &std::collections::BTreeMap<String, LayerClass>,
    name: &str,
) -> Option<LayerClass> {
    match split(name) {
        ("", own) => layers.get(own).copied(),
        (layer, _) => layers.get(layer).copied(),
    }
}

/// The class of channel `name`; `crypto_layers` are the layer names the file's
/// `cryptomatte/<key>/name` attributes give.
pub fn class_of(name: &str, crypto_layers: &[String]) -> LayerClass {
    let (layer, component) = split(name);
    let lower = layer.to_ascii_lowercase();
    if is_crypto(name, crypto_layers) || lower.split('.').any(|part| DATA_LAYERS.contains(&part)) {
        return LayerClass::Data;
    }
    if COLOUR_COMPONENTS.contains(&component.to_ascii_lowercase().as_str()) {
        LayerClass::Colour
    } else {
        LayerClass::Data
    }
}

/// Whether channel `name` is a Cryptomatte layer's: a layer `crypto_layers` (the file's
/// `cryptomatte/<key>/name` attributes) names, or one named `crypto…`.
pub fn is_crypto(name: &str, crypto_layers: &[String]) -> bool {
    let (layer, _) = split(name);
    crypto_layers
        .iter()
        .any(|c| !c.is_empty() && layer.starts_with(c.as_str()))
        || layer
            .to_ascii_lowercase()
            .split('.')
            .any(|part| part.starts_with("crypto"))
}

/// The layer names a header's `cryptomatte/<key>/name` attributes give (the Cryptomatte
/// specification's way of naming its layers).
pub fn crypto_layers(header: &exr::meta::header::Header) -> Vec<String> {
    let mut names: Vec<String> = header
        .own_attributes
        .other
        .iter()
        .chain(header.shared_attributes.other.iter())
        .filter(|(key, _)| {
            let key = key.to_string();
            key.starts_with("cryptomatte/") && key.ends_with("/name")
        })
        .filter_map(|(_, value)| match value {
            exr::meta::attribute::AttributeValue::Text(text) => Some(text.to_string()),
            _ => None,
        })
        .collect();
    names.sort();
    names
}

#[cfg(test)]
mod tests {
    use super::*;
    use LayerClass::{Colour, Data};

    #[test]
    fn light_layers_are_colour_and_surface_layers_data() {
        for (name, class) in [
            ("R", Colour),
            ("A", Colour),
            ("diffuse.R", Colour),
            ("specular.B", Colour),
            ("specular.A", Colour),
            ("ViewLayer.DiffCol.G", Colour),
            ("emission.red", Colour),
            ("Z", Data),
            ("depth.Z", Data),
            ("velocity.X", Data),
            ("forward.u", Data),
            ("ViewLayer.Vector.W", Data),
            ("ViewLayer.Normal.X", Data),
            // Arnold's normals and positions, RGB by their letters.
            ("N.R", Data),
            ("P.G", Data),
            ("ViewLayer.Depth.Z", Data),
            ("uv.U", Data),
            ("id.R", Data),
            ("ViewLayer.CryptoObject00.R", Data),
            ("crypto_material.G", Data),
        ] {
            assert_eq!(class_of(name, &[]), class, "{name}");
        }
    }

    #[test]
    fn a_layer_the_cryptomatte_attributes_name_is_data() {
        let named = vec!["objects".to_string()];
        assert_eq!(class_of("objects00.R", &named), Data);
        assert_eq!(class_of("objects00.R", &[]), Colour);
    }

    #[test]
    fn a_name_splits_at_its_last_dot() {
        assert_eq!(split("ViewLayer.Combined.R"), ("ViewLayer.Combined", "R"));
        assert_eq!(split("R"), ("", "R"));
    }
}
