//! The transfer curves of a photo's colour, from its embedded ICC profile: moxcms parses the
//! profile and evaluates its tone curves (`rTRC`, `gTRC`, `bTRC`, or `kTRC` for grey), sRGB's
//! curve (IEC 61966-2-1) when the file embeds none.
//!
//! Input: the profile's bytes as the file stored them (`frame::Photo::icc`). Output: the
//! [`Transfer`] that turns 8/16-bit codes into the profile's own linear light on read
//! (`io::passes::read`) and linear light back into codes on write (`write`). Only the curves
//! are applied, not the primaries: the blur is a linear operation, which commutes with the
//! profile's 3×3 matrix, so blurring in the profile's linear RGB and in XYZ agree, and the
//! output, encoded with the same curves, is in the input's colour space and embeds its
//! profile again. A profile without curves (LUT-based, CMYK, Lab) leaves the colour decoded
//! with sRGB's curve, with a note saying so (and that a profile of another colour space than
//! the output's is not embedded).
//!
//! For an EXR output, which holds no ICC profile, [`chromaticities`] gives the profile's
//! primaries and white as the EXR `chromaticities` attribute wants them.
//!
//! A PNG may say the same without a profile: its gAMA and cHRM chunks, which count where it
//! has no iCCP and no sRGB chunk (PNG 3rd ed., 4.3: iCCP first, then sRGB, then gAMA and
//! cHRM). [`profile_of`] turns them into the profile they describe (moxcms builds it), so
//! that one path reads and writes every photo; a JPEG or TIFF output, which have no such
//! chunks, embeds it, and a PNG output writes the chunks again instead (`write`).

use std::borrow::Cow;
use std::ops::RangeInclusive;

use moxcms::{
    Chromaticity, CicpColorPrimaries, ColorDateTime, ColorPrimaries, ColorProfile, DataColorSpace,
    LocalizableString, Matrix3d, ProfileText, ToneCurveEvaluator, ToneReprCurve,
    TransferCharacteristics, XyY, Xyz,
};

use crate::frame::{Photo, PngColour};

/// A curve from encoded [0, 1] to linear [0, 1].
type Curve = Box<dyn ToneCurveEvaluator + Send + Sync>;

/// The curves of one photo's colour, per channel R, G, B (`None`: the values are linear).
pub struct Transfer {
    curves: Option<[Curve; 3]>,
    /// Whether the profile describes RGB colour, and so may be embedded in an RGB output.
    pub embeds: bool,
    /// Whether the profile describes grey (a `GRAY` profile's `kTRC`): it may be embedded in a
    /// grey output, not in an RGB one.
    pub grey: bool,
    /// What the profile could not give (its curves, or its colour space), for the run's notes.
    pub note: Option<String>,
}

impl std::fmt::Debug for Transfer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Transfer")
            .field("linear", &self.curves.is_none())
            .field("embeds", &self.embeds)
            .field("grey", &self.grey)
            .field("note", &self.note)
            .finish()
    }
}

fn srgb_curves() -> [Curve; 3] {
    let srgb = ColorProfile::new_srgb();
    curves_of(&srgb).expect("moxcms's sRGB profile has its three curves")
}

fn curves_of(profile: &ColorProfile) -> Option<[Curve; 3]> {
    let make = |trc: &Option<ToneReprCurve>| trc.as_ref()?.make_linear_evaluator().ok();
    match profile.color_space {
        DataColorSpace::Rgb => Some([
            make(&profile.red_trc)?,
            make(&profile.green_trc)?,
            make(&profile.blue_trc)?,
        ]),
        DataColorSpace::Gray => Some([
            make(&profile.gray_trc)?,
            make(&profile.gray_trc)?,
            make(&profile.gray_trc)?,
        ]),
        _ => None,
    }
}

impl Transfer {
    /// Values that are linear already (`--linear`, float files).
    pub fn linear() -> Transfer {
        Transfer {
            curves: None,
            embeds: false,
            grey: false,
            note: None,
        }
    }

    /// sRGB's curves: a file with no profile.
    pub fn srgb() -> Transfer {
        Transfer {
            curves: Some(srgb_curves()),
            embeds: false,
            grey: false,
            note: None,
        }
    }

    /// The curves of an embedded profile (sRGB's when there is none, or when the profile has
    /// no curves to give, with a note).
    pub fn of(icc: Option<&[u8]>) -> Transfer {
        let Some(icc) = icc else {
            return Transfer::srgb();
        };
        // A profile of no curves: sRGB's stand in. Whether the profile goes out again is
        // said as it is: one of RGB colour is embedded in an RGB output, any other is not.
        let fallback = |embeds: bool, why: String| Transfer {
            curves: Some(srgb_curves()),
            embeds,
            grey: false,
            note: Some(format!(
                "{why}: the colour is linearised with sRGB's curve; {}",
                if embeds {
                    "the profile is embedded in the output again"
                } else {
                    "the profile is not embedded in the output (it does not describe the \
                     output's RGB)"
                }
            )),
        };
        let profile = match ColorProfile::new_from_slice(icc) {
            Ok(profile) => profile,
            Err(e) => {
                return fallback(
                    false,
                    format!("the embedded ICC profile is unreadable ({e})"),
                )
            }
        };
        let embeds = profile.color_space == DataColorSpace::Rgb;
        match curves_of(&profile) {
            Some(curves) => Transfer {
                curves: Some(curves),
                embeds,
                grey: profile.color_space == DataColorSpace::Gray,
                note: None,
            },
            // The decoders turn CMYK into RGB themselves, without the profile: the image
            // crate (and zune-jpeg under it) as R = (1 − C)(1 − K), and so on.
            None if profile.color_space == DataColorSpace::Cmyk => fallback(
                false,
                "the embedded ICC profile is a CMYK one: the decoder converted the CMYK colour \
                 to RGB without the profile (naively, R = (1 − C)(1 − K), not colour-managed)"
                    .into(),
            ),
            None => fallback(
                embeds,
                format!(
                    "the embedded ICC profile ({:?}) has no tone curves (a LUT-based profile)",
                    profile.color_space
                ),
            ),
        }
    }

    /// Turns normalised codes (`code / max`, as `read_planes` gives them) into linear light,
    /// through a table of the curve at every code.
    pub fn linearise(&self, planes: [&mut [f32]; 3], max: u32) {
        let Some(curves) = &self.curves else { return };
        for (plane, curve) in planes.into_iter().zip(curves) {
            let table: Vec<f32> = (0..=max)
                .map(|k| unit(curve.evaluate_value(k as f32 / max as f32)))
                .collect();
            for v in plane.iter_mut() {
                let code = (v.clamp(0.0, 1.0) * max as f32).round() as usize;
                *v = table[code];
            }
        }
    }

    /// The encoder of linear light into codes of `max` (255 or 65535) levels, channel by
    /// channel.
    pub fn encoder(&self, max: u32) -> Encoder {
        let edges = self.curves.as_ref().map(|curves| {
            curves.each_ref().map(|curve| {
                // Entry k: the linear value where code k + 1 starts (the curve at the middle
                // of codes k and k + 1), so that each value takes the code nearest to it in
                // the encoded space, for any increasing curve, without inverting it.
                (0..max)
                    .map(|k| unit(curve.evaluate_value((k as f32 + 0.5) / max as f32)))
                    .collect()
            })
        });
        Encoder { edges, max }
    }
}

/// The PCS illuminant, D50, as ICC.1 (7.2.16) gives it: what a profile's colorants are
/// adapted to.
const D50: [f64; 3] = [0.9642, 1.0, 0.8249];

/// The header's PCS illuminant (bytes 68 to 80) as ICC.1 (7.2.16) has it, D50 in
/// s15Fixed16: moxcms writes a D50 a few units off, which libpng refuses in an iCCP.
const D50_HEADER: [u8; 12] = [0, 0, 0xF6, 0xD6, 0, 1, 0, 0, 0, 0, 0xD3, 0x2D];

/// The gAMA values libpng accepts (png.c, `png_colorspace_check_gamma`: "gamma value out of
/// range" outside them), decoding exponents from 0.00016 to 6250. Outside, a gAMA says
/// nothing a curve can follow, and sRGB's stands in, as for a PNG of none.
const GAMA_RANGE: RangeInclusive<u32> = 16..=625_000_000;

/// sRGB's primaries and white (IEC 61966-2-1): what a PNG of a gAMA and no cHRM is read with.
const SRGB_CHRM: [f32; 8] = [0.3127, 0.3290, 0.64, 0.33, 0.30, 0.60, 0.15, 0.06];

/// The ICC profile that says how a photo's codes are coded, in the order PNG 3rd ed. (4.3)
/// gives: a PNG's cICP where shutter can make its profile ([`cicp_profile_of`]); else the one
/// it embeds; else, for a PNG, the one its gAMA and cHRM describe ([`png_profile`]); else
/// none (sRGB's curve). `grey`: a profile made from a PNG's chunks is a Gray one, for a grey
/// output.
pub fn profile_of(photo: &Photo, grey: bool) -> Option<Cow<'_, [u8]>> {
    if let Some(made) = cicp_profile_of(photo, grey) {
        return Some(Cow::Owned(made));
    }
    match (&photo.icc, &photo.png_colour) {
        (Some(icc), _) => Some(Cow::Borrowed(icc)),
        (None, Some(colour)) => png_profile(colour, grey).map(Cow::Owned),
        (None, None) => None,
    }
}

/// Whether a photo's profile is one [`profile_of`] made from its PNG chunks (which a PNG
/// output writes as those chunks again, not as an iCCP).
pub fn profile_is_made(photo: &Photo) -> bool {
    cicp_profile_of(photo, false).is_some()
        || photo.icc.is_none()
            && photo
                .png_colour
                .is_some_and(|c| png_profile(&c, false).is_some())
}

/// What says how a photo's codes are coded, as [`profile_of`] chooses (`shutter info`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourSource {
    /// A PNG's cICP (one shutter refuses, [`cicp_refusal`], among them).
    Cicp,
    /// The embedded ICC profile.
    Icc,
    /// A PNG's sRGB chunk.
    Srgb,
    /// A PNG's gAMA and cHRM, or either.
    PngChunks,
    /// Nothing: the codes are taken as sRGB's, as readers take them.
    None,
}

impl ColourSource {
    /// Its name in `--json`.
    pub fn name(self) -> &'static str {
        match self {
            ColourSource::Cicp => "cicp",
            ColourSource::Icc => "icc",
            ColourSource::Srgb => "srgb",
            ColourSource::PngChunks => "gama_chrm",
            ColourSource::None => "none",
        }
    }
}

/// What codes a photo's colour ([`ColourSource`]).
pub fn colour_source(photo: &Photo) -> ColourSource {
    let colour = photo.png_colour.unwrap_or_default();
    let cicp = colour
        .cicp
        .filter(|&c| cicp_refusal(c).is_some() || curve_of(c).is_some());
    if cicp.is_some() {
        ColourSource::Cicp
    } else if photo.icc.is_some() {
        ColourSource::Icc
    } else if colour.srgb.is_some() {
        ColourSource::Srgb
    } else if png_profile(&colour, false).is_some() {
        ColourSource::PngChunks
    } else {
        ColourSource::None
    }
}

/// The transfer characteristics of H.273 that are high dynamic range: PQ (SMPTE ST 2084)
/// and HLG (ARIB STD-B67).
const PQ: u8 = 16;
const HLG: u8 = 18;

/// Why a PNG's cICP (primaries, transfer, matrix, full range) cannot be honoured, where it
/// cannot: a high dynamic range transfer, or narrow-range codes. moxcms makes PQ's and HLG's
/// curves, but as tables of 1024 16-bit values (`build_trc_table`): PQ's light reaches 1 at
/// 10000 cd/m², so its darkest tenth of codes (up to 0.3 cd/m²) lands on three values of the
/// table, HLG's darkest twentieth on fourteen (and its curve bakes in one display's system
/// gamma, 1.2), and the blur would flatten those shadows into bands. Narrow
/// range puts black at 16 and white at 235 (× 2^(bits − 8)), which no curve here reads.
pub fn cicp_refusal([_, transfer, _, full]: [u8; 4]) -> Option<String> {
    let hdr = match transfer {
        PQ => Some("PQ (SMPTE ST 2084)"),
        HLG => Some("HLG (ARIB STD-B67)"),
        _ => None,
    };
    if let Some(name) = hdr {
        return Some(format!(
            "its cICP says its codes are high dynamic range, transfer {transfer}, {name}, which \
             an 8/16-bit photo's read cannot hold without flattening its shadows; convert it to \
             linear light in a float EXR first, or give --linear to blur its codes as they are"
        ));
    }
    (full == 0).then(|| {
        "its cICP says its codes are narrow range (black at 16, white at 235), which shutter \
         cannot read; convert it to full range first"
            .to_string()
    })
}

/// The curve of a cICP's transfer and the white and primaries of its colour primaries (CIE
/// x, y: white, red, green, blue), where moxcms knows both: `None` for numbers it does not
/// (unspecified, reserved, unknown).
fn curve_of([primaries, transfer, _, _]: [u8; 4]) -> Option<(ToneReprCurve, [f32; 8])> {
    let curve = ToneReprCurve::try_from(TransferCharacteristics::try_from(transfer).ok()?).ok()?;
    let cicp = CicpColorPrimaries::try_from(primaries).ok()?;
    let p = ColorPrimaries::try_from(cicp).ok()?;
    // H.273, table 2: every white is D65 but these.
    let (wx, wy) = match primaries {
        4 | 8 => (0.310, 0.316),
        10 => (1.0 / 3.0, 1.0 / 3.0),
        11 => (0.314, 0.351),
        _ => (0.3127, 0.3290),
    };
    let [r, g, b] = [p.red, p.green, p.blue];
    Some((curve, [wx, wy, r.x, r.y, g.x, g.y, b.x, b.y]))
}

/// The ICC profile a PNG's cICP describes, where shutter honours it: not refused
/// ([`cicp_refusal`]) and of numbers moxcms knows (`curve_of`).
pub fn cicp_profile_of(photo: &Photo, grey: bool) -> Option<Vec<u8>> {
    let cicp = photo.png_colour?.cicp?;
    if cicp_refusal(cicp).is_some() {
        return None;
    }
    let (curve, xy) = curve_of(cicp)?;
    let [p, t, ..] = cicp;
    made_profile(curve, xy, grey, format!("A PNG's cICP {p}/{t}/0/1"))
}

/// The note of a PNG whose cICP is passed over: its numbers are ones moxcms has no curve or
/// primaries for, so the chunks after it in PNG's order say how the codes are coded.
pub fn cicp_note(photo: &Photo) -> Option<String> {
    let cicp = photo.png_colour?.cicp?;
    let matrix = photo.png_colour?.cicp_matrix_read_as_0.map(|m| {
        format!(
            "the PNG's cICP gives matrix coefficients {m}, which PNG does not use (its samples \
             are RGB: 0); read as 0"
        )
    });
    if cicp_refusal(cicp).is_some() || curve_of(cicp).is_some() {
        return matrix;
    }
    let [p, t, m, f] = cicp;
    let then = match colour_source(&Photo {
        png_colour: photo.png_colour.map(|c| PngColour { cicp: None, ..c }),
        ..photo.clone()
    }) {
        ColourSource::Icc => "its ICC profile",
        ColourSource::Srgb => "its sRGB chunk",
        ColourSource::PngChunks => "its gAMA and cHRM",
        _ => "sRGB's curve, as for a PNG of none",
    };
    let passed = format!(
        "the PNG's cICP {p}/{t}/{m}/{f} names primaries or a transfer shutter has no curve \
         for: its colour is read by {then}"
    );
    Some(matrix.map_or(passed.clone(), |matrix| format!("{matrix}; {passed}")))
}

/// The ICC profile a PNG's gAMA and cHRM describe, where no sRGB chunk overrides them (PNG
/// 3rd ed., 11.3.2.2 and 11.3.2.3): the curve light = code^(100000 / gAMA), gAMA holding the
/// exponent that encoded the light ×100000 (45455 for 1/2.2), sRGB's curve where it has no
/// gAMA in libpng's range ([`GAMA_RANGE`]); the primaries and white of its cHRM, sRGB's where
/// it has none (what its readers assume). `None` where the chunks say nothing: an sRGB
/// chunk, or neither a usable gAMA nor a cHRM.
fn png_profile(colour: &PngColour, grey: bool) -> Option<Vec<u8>> {
    if colour.srgb.is_some() {
        return None;
    }
    let gamma = colour.gamma.filter(|g| GAMA_RANGE.contains(g));
    if gamma.is_none() && colour.chromaticities.is_none() {
        return None;
    }
    let curve = match gamma {
        Some(g) => ToneReprCurve::Parametric(vec![(100_000.0 / g as f64) as f32]),
        None => ColorProfile::new_srgb().red_trc?,
    };
    let xy = colour
        .chromaticities
        .map_or(SRGB_CHRM, |c| c.map(|v| v as f32 / 100_000.0));
    let gamma = gamma.map_or("sRGB's curve".into(), |g| format!("gAMA {g}"));
    let chrm = colour
        .chromaticities
        .map_or("sRGB's primaries", |_| "its cHRM");
    made_profile(curve, xy, grey, format!("A PNG's {gamma} and {chrm}"))
}

/// The profile of a picture made from an EXR of the primaries and white `xy` (x, y of white,
/// red, green, blue: its `chromaticities`), encoded with sRGB's curve, or holding linear
/// light (`linear`: `--linear`, a float TIFF), so a viewer shows ACEScg or P3 light in its
/// own colours and not as sRGB's. `Ok(None)` for Rec. 709's primaries and D65 (sRGB's: the
/// picture needs no profile, as before); `Err`, saying why, for primaries that make no
/// profile (not finite, outside 0 to 1, or on one line).
pub fn primaries_profile(xy: [f32; 8], linear: bool) -> Result<Option<Vec<u8>>, String> {
    if xy.iter().zip(SRGB_CHRM).all(|(a, b)| (a - b).abs() < 1e-3) {
        return Ok(None);
    }
    let [wx, wy, rx, ry, gx, gy, bx, by] = xy.map(f64::from);
    let area = ((gx - rx) * (by - ry) - (bx - rx) * (gy - ry)).abs() / 2.0;
    let inside = xy.iter().all(|v| v.is_finite() && *v > 0.0 && *v < 1.0);
    if !inside || wx + wy >= 1.0 {
        return Err("a primary or the white is not within 0 to 1".into());
    }
    if area < 1e-4 {
        return Err("the primaries lie on one line".into());
    }
    let unmade = || "moxcms made no profile of them".to_string();
    let curve = if linear {
        ToneReprCurve::Parametric(vec![1.0])
    } else {
        ColorProfile::new_srgb().red_trc.ok_or_else(unmade)?
    };
    let description = if linear {
        "Linear light in the EXR's chromaticities (shutter)"
    } else {
        "sRGB's curve in the EXR's chromaticities (shutter)"
    };
    made_profile(curve, xy, false, description.into())
        .map(Some)
        .ok_or_else(unmade)
}

/// A profile of linear light in the primaries and white of the RGB matrix profile `icc`: what
/// a float TIFF of an 8/16-bit photo holds (its codes turned to linear light through `icc`'s
/// curves), so a viewer shows an Adobe RGB or ProPhoto photo in its own colours and not as
/// linear sRGB (an outside probe: such a TIFF carried no profile). `None` for a profile that
/// gives no primaries (LUT-based, grey, CMYK).
pub fn linear_profile_of(icc: &[u8]) -> Option<Vec<u8>> {
    let [(rx, ry), (gx, gy), (bx, by), (wx, wy)] = chromaticities(icc)?;
    let xy = [wx, wy, rx, ry, gx, gy, bx, by].map(|v| v as f32);
    let gamma_one = ToneReprCurve::Parametric(vec![1.0]);
    made_profile(gamma_one, xy, false, "Linear light (shutter)".into())
}

/// An ICC profile of one `curve` for every channel and the white and primaries `xy` (x, y
/// of white, red, green, blue), described as `description`. Built by moxcms: the colorants
/// adapted to D50 by Bradford, a `chad` that adapts the white to D50 (moxcms's own is its
/// cone matrix), no CICP, a fixed creation date (the same chunks make the same bytes), the
/// header's D50 as ICC gives it. `grey`: a Gray profile of the curve.
fn made_profile(
    curve: ToneReprCurve,
    [wx, wy, rx, ry, gx, gy, bx, by]: [f32; 8],
    grey: bool,
    description: String,
) -> Option<Vec<u8>> {
    let mut profile = ColorProfile::new_srgb();
    let white = XyY::new(wx as f64, wy as f64, 1.0);
    profile.update_rgb_colorimetry(
        white,
        ColorPrimaries {
            red: Chromaticity::new(rx, ry),
            green: Chromaticity::new(gx, gy),
            blue: Chromaticity::new(bx, by),
        },
    );
    let d50 = Xyz::new(D50[0] as f32, D50[1] as f32, D50[2] as f32);
    profile.chromatic_adaptation = Some(moxcms::adaption_matrix_d(
        Chromaticity::new(wx, wy).to_xyz(),
        d50,
    ));
    profile.media_white_point = Some(white.to_xyzd());
    profile.cicp = None;
    if grey {
        profile.color_space = DataColorSpace::Gray;
        (profile.red_trc, profile.green_trc, profile.blue_trc) = (None, None, None);
        profile.gray_trc = Some(curve);
    } else {
        profile.red_trc = Some(curve.clone());
        profile.green_trc = Some(curve.clone());
        profile.blue_trc = Some(curve);
    }
    profile.description = Some(ProfileText::Localizable(vec![LocalizableString::new(
        "en".into(),
        "US".into(),
        description,
    )]));
    profile.copyright = None;
    // 2000-01-01 00:00:00.
    const DATE: [u8; 12] = [7, 208, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0];
    profile.creation_date_time = ColorDateTime::new_from_slice(&DATE).ok()?;
    let mut icc = profile.encode().ok()?;
    icc.get_mut(68..80)?.copy_from_slice(&D50_HEADER);
    // moxcms 0.8 writes the time of encoding as the header's date whatever the profile says:
    // the fixed date in its place (bytes 24 to 35), or the same frame would give other bytes
    // each second.
    icc.get_mut(24..36)?.copy_from_slice(&DATE);
    Some(icc)
}

/// How far from the identity a `chad` may be and still be an adaptation between two
/// daylight-like whites (D65 to D50 by Bradford differs from it by 0.05 at most; D93 or
/// illuminant A by under 0.25). moxcms before 0.9 writes the Bradford cone matrix itself as
/// `chad` (its off-diagonal 0.75 and 1.71), which adapts nothing: such a tag is not trusted.
const CHAD_FROM_IDENTITY: f64 = 0.25;

/// The primaries and white of an RGB matrix profile as CIE xy chromaticities, `[red, green,
/// blue, white]`, for the EXR `chromaticities` attribute; `None` for a profile that is not
/// RGB, has no colorants (LUT-based), or cannot be read.
///
/// ICC v2 and v4 store the colorants (rXYZ, gXYZ, bXYZ) adapted to D50. The adaptation is
/// undone by the profile's `chad` (v4, and v2 profiles that carry one) when it is a
/// plausible adaptation ([`CHAD_FROM_IDENTITY`]); else, where the media white point (`wtpt`,
/// the actual white in v2 profiles) is not D50, by Bradford's from D50 to it (moxcms's
/// [`moxcms::adaption_matrix_d`]), as v2 profile makers adapted it; else the colorants are
/// taken as they are: a v2 profile of a D50 `wtpt` and no `chad` says no other white, and
/// its D50-adapted primaries with a D50 white give the same RGB-to-XYZ matrix as the
/// profile's own. The white is the sum of the three primaries' XYZ.
pub fn chromaticities(icc: &[u8]) -> Option<[(f64, f64); 4]> {
    let profile = ColorProfile::new_from_slice(icc).ok()?;
    if profile.color_space != DataColorSpace::Rgb {
        return None;
    }
    let colorants = profile.colorant_matrix();
    let near_identity = |m: &Matrix3d| {
        (0..3).all(|i| (0..3).all(|j| (m.v[i][j] - f64::from(i == j)).abs() < CHAD_FROM_IDENTITY))
    };
    let xyz = |v: [f64; 3]| Xyz::new(v[0] as f32, v[1] as f32, v[2] as f32);
    let actual = match (profile.chromatic_adaptation, profile.media_white_point) {
        (Some(chad), _) if near_identity(&chad) => chad.inverse().mat_mul(colorants),
        (_, Some(white))
            if (0..3).any(|i| ([white.x, white.y, white.z][i] - D50[i]).abs() > 1e-3) =>
        {
            moxcms::adaption_matrix_d(xyz(D50), xyz([white.x, white.y, white.z])).mat_mul(colorants)
        }
        _ => colorants,
    };
    let xy = |[x, y, z]: [f64; 3]| {
        let sum = x + y + z;
        (sum > 0.0 && sum.is_finite()).then(|| (x / sum, y / sum))
    };
    let column = |j: usize| [actual.v[0][j], actual.v[1][j], actual.v[2][j]];
    let white = [0, 1, 2].map(|i| actual.v[i].iter().sum::<f64>());
    Some([xy(column(0))?, xy(column(1))?, xy(column(2))?, xy(white)?])
}

/// A curve's value held to [0, 1], NaN 0: an ICC tone curve maps [0, 1] onto [0, 1]. moxcms
/// evaluates a pure gamma (a `curv` of one entry: ProPhoto's and Apple RGB's 1.8) with
/// pxfm's `dirty_powf`, through log₂ and exp₂, which is within 10⁻⁶ of x^γ everywhere but at
/// 0: there γ 1.8 gave −1.65·10⁸ and γ 1.5 −5·10¹⁹, the black of every ProPhoto photo, which
/// then darkened every blur that reached it.
fn unit(v: f32) -> f32 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0)
    }
}

/// Linear light to codes, through tables of code boundaries.
pub struct Encoder {
    edges: Option<[Vec<f32>; 3]>,
    max: u32,
}

impl Encoder {
    /// The code of a linear value in channel `c` (0, 1, 2); NaN takes code 0.
    pub fn encode(&self, v: f32, c: usize) -> u32 {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        match &self.edges {
            Some(edges) => edges[c].partition_point(|&edge| edge <= v) as u32,
            None => (v * self.max as f32 + 0.5) as u32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_profile_is_srgb() {
        // 50% sRGB grey is 21.4% linear (IEC 61966-2-1).
        let transfer = Transfer::of(None);
        let mut plane = vec![128.0 / 255.0];
        transfer.linearise([&mut plane, &mut [0.0], &mut [1.0]], 255);
        assert!((plane[0] - 0.215_861).abs() < 1e-5, "{}", plane[0]);
        assert_eq!(transfer.encoder(255).encode(plane[0], 0), 128);
    }

    #[test]
    fn every_code_round_trips_through_a_gamma_profile() {
        let icc = ColorProfile::new_adobe_rgb().encode().unwrap();
        let transfer = Transfer::of(Some(&icc));
        assert!(transfer.embeds && transfer.note.is_none());
        for max in [255u32, 65535] {
            let encoder = transfer.encoder(max);
            let codes: Vec<f32> = (0..=max).map(|k| k as f32 / max as f32).collect();
            let mut planes = [codes.clone(), codes.clone(), codes];
            let [r, g, b] = &mut planes;
            transfer.linearise([r, g, b], max);
            for (k, &v) in planes[0].iter().enumerate() {
                assert_eq!(encoder.encode(v, 0), k as u32, "max {max}");
            }
            // Adobe RGB (1998): a pure gamma of 563/256.
            let half = planes[1][(max / 2) as usize];
            let expected = ((max / 2) as f32 / max as f32).powf(563.0 / 256.0);
            assert!((half - expected).abs() < 1e-5, "{half} {expected}");
        }
    }

    /// Pure gamma curves of every common size, ProPhoto's 1.8 (and 1.5, 2.0) among them: code
    /// 0 is black (moxcms's own evaluator gave −1.65·10⁸ at 1.8), every code is x^γ to f32
    /// rounding, and every code round-trips.
    #[test]
    fn pure_gamma_profiles_are_x_to_the_gamma_from_black_up() {
        for wanted in [1.5f32, 1.8, 2.0, 2.2, 563.0 / 256.0] {
            // As the profile stores it: u8Fixed8 (1.8 is 461/256).
            let fixed = (wanted * 256.0).round() as u16;
            let gamma = f32::from(fixed) / 256.0;
            let mut profile = ColorProfile::new_pro_photo_rgb();
            let curve = ToneReprCurve::Lut(vec![fixed]);
            profile.red_trc = Some(curve.clone());
            profile.green_trc = Some(curve.clone());
            profile.blue_trc = Some(curve);
            let icc = profile.encode().unwrap();
            let transfer = Transfer::of(Some(&icc));
            assert!(transfer.note.is_none(), "{gamma}: {:?}", transfer.note);
            for max in [255u32, 65535] {
                let codes: Vec<f32> = (0..=max).map(|k| k as f32 / max as f32).collect();
                let mut planes = [codes.clone(), codes.clone(), codes.clone()];
                let [r, g, b] = &mut planes;
                transfer.linearise([r, g, b], max);
                assert_eq!(planes[0][0], 0.0, "γ {gamma}: black");
                let encoder = transfer.encoder(max);
                for (k, &v) in planes[0].iter().enumerate() {
                    let expected = (k as f64 / max as f64).powf(gamma as f64) as f32;
                    assert!((v - expected).abs() <= 1e-6, "γ {gamma} code {k}: {v}");
                    assert_eq!(encoder.encode(v, 0), k as u32, "γ {gamma}, max {max}");
                }
            }
        }
    }

    /// Adobe RGB (1998)'s primaries and D65 white (Adobe RGB (1998) Color Image Encoding,
    /// 4.2.1), from moxcms's profile (a D65 `wtpt` and a `chad` that adapts nothing) and
    /// from one of the v4 form (a D50 `wtpt` and a true Bradford `chad`).
    #[test]
    fn adobe_rgbs_primaries_come_back_from_its_d50_colorants() {
        let adobe = [(0.64, 0.33), (0.21, 0.71), (0.15, 0.06), (0.3127, 0.3290)];
        let moxcms_form = ColorProfile::new_adobe_rgb();
        let mut v4_form = ColorProfile::new_adobe_rgb();
        let d65 = Xyz::new(0.9504559, 1.0, 1.0890578);
        v4_form.chromatic_adaptation = Some(moxcms::adaption_matrix_d(
            d65,
            Xyz::new(0.9642, 1.0, 0.8249),
        ));
        v4_form.media_white_point = Some(moxcms::Xyzd::new(0.9642, 1.0, 0.8249));
        for profile in [moxcms_form, v4_form] {
            let got = chromaticities(&profile.encode().unwrap()).unwrap();
            for (g, a) in got.iter().zip(adobe) {
                assert!(
                    (g.0 - a.0).abs() < 1e-3 && (g.1 - a.1).abs() < 1e-3,
                    "{got:?}"
                );
            }
        }
        let mut grey = ColorProfile::new_srgb();
        grey.color_space = DataColorSpace::Gray;
        assert_eq!(chromaticities(&grey.encode().unwrap_or_default()), None);
    }

    #[test]
    fn a_cmyk_profiles_note_says_it_is_not_embedded() {
        let mut icc = ColorProfile::new_srgb().encode().unwrap();
        icc[16..20].copy_from_slice(b"CMYK");
        let transfer = Transfer::of(Some(&icc));
        let note = transfer.note.unwrap();
        assert!(!transfer.embeds, "{note}");
        assert!(
            note.contains("CMYK") && note.contains("not embedded"),
            "{note}"
        );
        assert!(!note.contains("is kept"), "{note}");
    }

    /// What a PNG's chunks make: nothing beside an sRGB chunk or without a usable gAMA or a
    /// cHRM; else a profile of light = code^(100000 / gAMA) (sRGB's curve without a gAMA),
    /// the same bytes each time.
    #[test]
    fn a_pngs_gama_and_chrm_make_the_profile_they_describe() {
        let colour = |gamma, chromaticities, srgb| PngColour {
            gamma,
            chromaticities,
            srgb,
            ..PngColour::default()
        };
        let adobe = Some([31270, 32900, 64000, 33000, 21000, 71000, 15000, 6000]);
        assert_eq!(
            png_profile(&colour(Some(45455), adobe, Some(0)), false),
            None
        );
        assert_eq!(png_profile(&colour(Some(15), None, None), false), None);
        assert_eq!(png_profile(&colour(None, None, None), false), None);
        let linear = png_profile(&colour(Some(100_000), None, None), false).unwrap();
        let mut planes = [vec![0.25, 0.5], vec![0.0, 1.0], vec![0.75, 0.5]];
        let [r, g, b] = &mut planes;
        Transfer::of(Some(&linear)).linearise([r, g, b], 255);
        let codes = |v: f32| (v * 255.0).round() / 255.0;
        assert_eq!(planes[0], [codes(0.25), codes(0.5)]);
        let made = png_profile(&colour(None, adobe, None), false).unwrap();
        assert_eq!(
            made,
            png_profile(&colour(None, adobe, None), false).unwrap()
        );
        let mut plane = vec![128.0 / 255.0];
        Transfer::of(Some(&made)).linearise([&mut plane, &mut [0.0], &mut [0.0]], 255);
        assert!(
            (plane[0] - 0.215_861).abs() < 1e-5,
            "sRGB's curve: {}",
            plane[0]
        );
        let got = chromaticities(&made).unwrap();
        assert!(
            (got[1].0 - 0.21).abs() < 1e-4 && (got[3].1 - 0.329).abs() < 1e-4,
            "{got:?}"
        );
    }

    #[test]
    fn an_unreadable_profile_falls_back_to_srgb_with_a_note() {
        let transfer = Transfer::of(Some(b"not a profile"));
        assert!(!transfer.embeds);
        assert!(transfer.note.unwrap().contains("unreadable"));
    }
}
