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
//!    starts with `crypto`, after a renderer's prefix, or is Unreal's `ActorHitProxyMask…`)
//!    is data: its values are IDs and coverage ranks, not light;
//! 2. a channel any of whose layer's dot-separated names is a known data name is data —
//!    Arnold writes its normals as `N.R`, `N.G`, `N.B`, colour by their letters alone. A name
//!    is compared in lower case, without leading underscores (RenderMan's `__Pworld`), `_`
//!    and `-` (`object_id`, `Op_Id`), and without a renderer's prefix (V-Ray's `VRay…`,
//!    Unreal Movie Render Queue's `FinalImageMovieRenderQueue_…`), against [`DATA_LAYERS`]:
//!    depth (`z`, `depth`, `zdepth`, `mist`, `worlddepth`, `scenedepth`, Mantra's `pz`),
//!    motion (`velocity`, `vel`, `mv`, `vector`, `motionvector(s)`, `forward`, `backward`,
//!    Nuke's `disparityL`/`R`), positions and normals (`p`, `position`, `worldposition`,
//!    `pref`, `pworld`, `n`, `nn`, `ng`, `normal(s)`, `bumpnormals`, `nworld`, V-Ray's
//!    `samplerinfo`, RenderMan's `dpdtime`), texture coordinates (`uv`, `uvw`, `st`), IDs
//!    (`id`, `objectid`, `materialid`, `mtlid`, `renderid`, `primid`, `opid`, `indexob`,
//!    `indexma`) and the counts a renderer keeps per pixel
//!    (`coverage`, `cputime`, `raycount`);
//! 3. a channel whose own name is R, G, B, A or Y (any case; `red`, `green`, `blue`,
//!    `alpha` too) is colour: `diffuse.R`, `ViewLayer.Emit.G`, a layer's own `specular.A`;
//! 4. every other channel is data: `Z`, `velocity.X`, `ViewLayer.Normal.X`, `uv.U`.
//!
//! A rule that cannot see a layer's meaning by its name errs towards data, which comes back
//! as it was: a light layer misread as data is left sharp (and visible as such), while data
//! misread as colour would be averaged into values that mean nothing.
//!
//! Masks and mattes (`mask`, `matte`, V-Ray's MultiMatte, Redshift's PuzzleMatte) are
//! colour: each is the coverage of some of the beauty's objects, as alpha is of all of them,
//! and averages as alpha does, so blurred with the beauty's weights it still cuts out the
//! blurred object (a sharp matte would leave the object's streak outside it). V-Ray's
//! `coverage` is not: it belongs to the render ID beside it (the share of the pixel that ID
//! covers), and the IDs, data, stay sharp, so it stays sharp with them, as Cryptomatte's
//! ranks do. `albedo` is the surface's colour and blurs with it.
//!
//! Whatever a name says, a channel that a run's preset reads as a pass (depth, vectors) is
//! data in that run, with the rest of its layer (`io::passes::carried`); a preset's
//! `[layers]` table overrides both.

pub use crate::frame::LayerClass;

/// The known names of data layers (rule 2), as [`normalised`] gives them.
const DATA_LAYERS: &[&str] = &[
    // Depth.
    "depth",
    "z",
    "zdepth",
    "mist",
    "worlddepth",
    "scenedepth",
    "pz",
    "volumez",
    // Motion.
    "vector",
    "vectors",
    "velocity",
    "vel",
    "mv",
    "motion",
    "motionvector",
    "motionvectors",
    "forward",
    "backward",
    "disparity",
    "disparityl",
    "disparityr",
    "dpdtime",
    "dpcameradtime",
    // Positions and normals.
    "position",
    "worldposition",
    "p",
    "pref",
    "pworld",
    "n",
    "nn",
    "ng",
    "normal",
    "normals",
    "worldnormal",
    "bumpnormals",
    "nworld",
    "samplerinfo",
    // Texture coordinates.
    "uv",
    "uvw",
    "st",
    // IDs, and what a renderer counts per pixel.
    "id",
    "objectid",
    "materialid",
    "mtlid",
    "renderid",
    "primid",
    "opid",
    "indexob",
    "indexma",
    "coverage",
    "cputime",
    "raycount",
];

/// The prefixes renderers put before a pass's name, lower case, without `_`: V-Ray's render
/// elements (`VRayVelocity`, `VRayZDepth`, `VRayNormals`), Unreal Movie Render Queue's
/// post-process passes (`FinalImageMovieRenderQueue_WorldDepth`), longest first.
const RENDERER_PREFIXES: &[&str] = &["finalimagemovierenderqueue", "movierenderqueue", "vray"];

/// One dot-separated name of a layer as rule 2 compares it: lower case, without leading
/// underscores, `_` and `-`, and without a renderer's prefix ([`RENDERER_PREFIXES`]).
fn normalised(part: &str) -> String {
    let bare: String = (part.trim_start_matches('_').chars())
        .filter(|c| !matches!(c, '_' | '-'))
        .flat_map(char::to_lowercase)
        .collect();
    RENDERER_PREFIXES
        .iter()
        .find_map(|prefix| bare.strip_prefix(prefix).filter(|rest| !rest.is_empty()))
        .map_or(bare.clone(), str::to_string)
}

/// Whether a layer (`ViewLayer.Normal`, `VRayVelocity`) holds data by its names (rule 2).
fn is_data_layer(layer: &str) -> bool {
    layer
        .split('.')
        .any(|part| DATA_LAYERS.contains(&normalised(part).as_str()))
}

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
    layers.get(layer_key(name)).copied()
}

/// The keys of a preset's `[layers]` table that name no layer of a file whose channels are
/// `names` but nearly name one, each with the layer it likely meant: the same but for case,
/// or one edit away (two for names of eight letters or more) from a layer of four letters or
/// more, or the end of a layer's name after a dot (`DiffCol` for `ViewLayer.DiffCol`: a key
/// names a layer whole). A key naming a layer the file lacks is not a mistake (one preset serves shots
/// rendered with different AOVs); a near miss is a typo that leaves the meant layer in its
/// default class without a word.
pub fn near_misses<'a>(
    keys: impl IntoIterator<Item = &'a String>,
    names: &[&str],
) -> Vec<(String, String)> {
    let layers: std::collections::BTreeSet<&str> = names
        .iter()
        .map(|n| match split(n) {
            ("", own) => own,
            (layer, _) => layer,
        })
        .collect();
    let mut misses = Vec::new();
    for key in keys {
        if layers.contains(key.as_str()) {
            continue;
        }
        let near = layers.iter().find(|layer| {
            let allowed = match layer.chars().count() {
                0..=3 => 0,
                4..=7 => 1,
                _ => 2,
            };
            layer.eq_ignore_ascii_case(key)
                || edits(layer, key) <= allowed
                || (layer.to_ascii_lowercase()).ends_with(&format!(".{}", key.to_ascii_lowercase()))
        });
        if let Some(layer) = near {
            misses.push((key.clone(), layer.to_string()));
        }
    }
    misses
}

/// The Levenshtein distance between `a` and `b`, by characters.
fn edits(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The class of channel `name`; `crypto_layers` are the layer names the file's
/// `cryptomatte/<key>/name` attributes give.
pub fn class_of(name: &str, crypto_layers: &[String]) -> LayerClass {
    let (layer, component) = split(name);
    if is_crypto(name, crypto_layers) || is_data_layer(layer) {
        return LayerClass::Data;
    }
    if COLOUR_COMPONENTS.contains(&component.to_ascii_lowercase().as_str()) {
        LayerClass::Colour
    } else {
        LayerClass::Data
    }
}

/// Whether channel `name` is a Cryptomatte layer's: a layer `crypto_layers` (the file's
/// `cryptomatte/<key>/name` attributes) names, or one named `crypto…` after a renderer's
/// prefix (`VRayCryptomatte`), or Unreal's `ActorHitProxyMask…` (Movie Render Queue's
/// Object ID pass, written to the Cryptomatte specification).
pub fn is_crypto(name: &str, crypto_layers: &[String]) -> bool {
    let (layer, _) = split(name);
    crypto_layers
        .iter()
        .any(|c| !c.is_empty() && layer.starts_with(c.as_str()))
        || layer
            .split('.')
            .map(normalised)
            .any(|part| part.starts_with("crypto") || part.starts_with("actorhitproxymask"))
}

/// The key a channel's layer goes by, in a preset's `[layers]` table and among the layers a
/// run reads passes from: its layer's name (`diffuse` for `diffuse.R`), or, for a channel of
/// no layer (`Z`), its own name.
pub fn layer_key(name: &str) -> &str {
    match split(name) {
        ("", own) => own,
        (layer, _) => layer,
    }
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
            exr::meta::attribute::AttributeValue::Text(text) => Some(name_of(text)),
            _ => None,
        })
        .collect();
    names.sort();
    names
}

/// The first of the chars that stand for a byte of a name that is not UTF-8: byte `b`
/// (0x80 to 0xFF; ASCII is always UTF-8) is `ESCAPE_BASE + b`, U+F800 to U+F87F in the
/// private use area (the "UTF-8b" escape of Python's `surrogateescape`, moved out of the
/// surrogates, which a Rust `char` cannot hold).
const ESCAPE_BASE: u32 = 0xF780;

/// The char that stands for byte `byte` of a name that is not UTF-8.
fn escaped(byte: u8) -> char {
    char::from_u32(ESCAPE_BASE + u32::from(byte)).unwrap_or(char::REPLACEMENT_CHARACTER)
}

/// The byte char `c` stands for, where it is one of the escapes of [`name_of`].
fn unescaped(c: char) -> Option<u8> {
    u32::from(c)
        .checked_sub(ESCAPE_BASE)
        .and_then(|b| u8::try_from(b).ok())
        .filter(|b| *b >= 0x80)
}

/// A channel's, layer's, part's or view's name as its file stores it (EXR text, which
/// OpenEXR 3 writes as UTF-8), as shutter holds it: the UTF-8 decoded (`Vordergrund_ü.R`,
/// `前景.R`), so that `--layers`, presets and messages see the name the user typed. The exr
/// crate's `Display` reads a char a byte (Latin-1): `Vordergrund_Ã¼.R`, which nothing typed
/// matched. A byte that is not part of UTF-8 (a Latin-1 writer's `beaut\xE9.R`) becomes
/// the escape char U+F780 + byte, and an escape char the file really holds is escaped byte
/// by byte too, so [`name_text`] gives back the file's bytes exactly, whatever they are.
pub fn name_of(text: &exr::meta::attribute::Text) -> String {
    let mut name = String::with_capacity(text.bytes().len());
    for chunk in text.bytes().utf8_chunks() {
        for c in chunk.valid().chars() {
            if unescaped(c).is_some() {
                let mut utf8 = [0; 4];
                name.extend(c.encode_utf8(&mut utf8).bytes().map(escaped));
            } else {
                name.push(c);
            }
        }
        name.extend(chunk.invalid().iter().copied().map(escaped));
    }
    name
}

/// A name as the EXR text a file stores: its UTF-8, each escape char of [`name_of`] the one
/// byte it stands for. `name_text(&name_of(t)) == t` for every text `t`. Never panics (the
/// exr crate's `Text::from(&str)` writes Latin-1 and panics above U+00FF).
pub fn name_text(name: &str) -> exr::meta::attribute::Text {
    let mut bytes = exr::meta::attribute::TextBytes::new();
    for c in name.chars() {
        match unescaped(c) {
            Some(byte) => bytes.push(byte),
            None => bytes.extend_from_slice(c.encode_utf8(&mut [0; 4]).as_bytes()),
        }
    }
    exr::meta::attribute::Text::from_bytes_unchecked(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layers_key_one_typo_from_a_layer_is_a_near_miss() {
        let names = [
            "R",
            "G",
            "B",
            "specular.R",
            "ViewLayer.DiffCol.G",
            "Z",
            "albedo.R",
        ];
        let keys: Vec<String> = [
            "specualr",
            "specular",
            "viewlayer.diffcol",
            "ViewLayer.DifCol",
            "normal",
            "z",
            "Y",
            "albedos",
            "alb",
            "diffcol",
        ]
        .map(String::from)
        .into();
        let pairs = |v: &[(&str, &str)]| -> Vec<(String, String)> {
            v.iter()
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect()
        };
        // Present keys, far keys (normal), and one letter off a name under four letters (Y
        // against R, G, B; alb against nothing) are not near misses.
        assert_eq!(
            near_misses(&keys, &names),
            pairs(&[
                ("specualr", "specular"),
                ("viewlayer.diffcol", "ViewLayer.DiffCol"),
                ("ViewLayer.DifCol", "ViewLayer.DiffCol"),
                ("z", "Z"),
                ("albedos", "albedo"),
                ("diffcol", "ViewLayer.DiffCol"),
            ])
        );
    }

    #[test]
    fn names_round_trip_as_the_bytes_the_file_holds() {
        use exr::meta::attribute::Text;
        for (bytes, name) in [
            (
                "Vordergrund_ü.Combined.R".as_bytes(),
                "Vordergrund_ü.Combined.R",
            ),
            ("前景.R".as_bytes(), "前景.R"),
            ("beauté.R".as_bytes(), "beauté.R"),
            (b"Z".as_slice(), "Z"),
            // Latin-1, not UTF-8: each byte escaped, the rest as it is.
            (b"beaut\xE9.R".as_slice(), "beaut\u{F869}.R"),
            (b"\xFF\x80".as_slice(), "\u{F87F}\u{F800}"),
            // A valid escape char is escaped byte by byte, so it too comes back.
            ("a\u{F800}".as_bytes(), "a\u{F86F}\u{F820}\u{F800}"),
            // Cut-short UTF-8.
            (b"\xE5\x89".as_slice(), "\u{F865}\u{F809}"),
        ] {
            let text = Text::from_slice_unchecked(bytes);
            assert_eq!(name_of(&text), name, "{bytes:?}");
            assert_eq!(name_text(name).bytes(), bytes, "{name:?}");
            assert_eq!(name_text(&name_of(&text)), text);
        }
        // What the exr crate would have panicked on.
        assert_eq!(name_text("前景.R").bytes(), "前景.R".as_bytes());
    }
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
            // What renderers name their data (F12: these were colour, and blurred).
            ("VRayVelocity.R", Data),
            ("VRayZDepth.R", Data),
            ("VRayNormals.G", Data),
            ("VRayBumpNormals.B", Data),
            ("VRayRenderID.R", Data),
            ("VRayMtlID.G", Data),
            ("VRaySamplerInfo.R", Data),
            ("VRayCryptomatte00.R", Data),
            ("VRayCoverage.R", Data),
            ("FinalImageMovieRenderQueue_MotionVectors.R", Data),
            ("FinalImageMovieRenderQueue_WorldDepth.G", Data),
            ("ActorHitProxyMask00.R", Data),
            ("Nn.R", Data),
            ("Ng.B", Data),
            ("mv.R", Data),
            ("vel.G", Data),
            ("disparityL.R", Data),
            ("__Pworld.R", Data),
            ("__depth.R", Data),
            ("Op_Id.R", Data),
            ("Pz.R", Data),
            ("motion_vector.G", Data),
            ("WorldPosition.B", Data),
            ("coverage.R", Data),
            // Light, whatever prefix it has; mattes blur with the beauty (module doc).
            ("VRayLighting.R", Colour),
            ("VRayReflection.G", Colour),
            ("VRayDenoiser.B", Colour),
            ("FinalImageMovieRenderQueue_Beauty.R", Colour),
            ("mask.R", Colour),
            ("matte.G", Colour),
            ("VRayMultiMatte.B", Colour),
            ("albedo.R", Colour),
            ("Nothing.R", Colour),
            ("vray.R", Colour),
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
