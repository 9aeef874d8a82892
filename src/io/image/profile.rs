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

use moxcms::{ColorProfile, DataColorSpace, Matrix3d, ToneCurveEvaluator, ToneReprCurve, Xyz};

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

    #[test]
    fn an_unreadable_profile_falls_back_to_srgb_with_a_note() {
        let transfer = Transfer::of(Some(b"not a profile"));
        assert!(!transfer.embeds);
        assert!(transfer.note.unwrap().contains("unreadable"));
    }
}
