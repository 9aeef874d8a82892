//! The sweep: the settings `shutter bench` runs on every scene, each an algorithm with its
//! parameters and a label for the rows ([`Setting`]), grouped by the reference they are scored
//! against ([`Target`]): motion blur alone, depth of field alone, and the two together. A new
//! algorithm or setting worth measuring is added here.

use crate::dof::{BlendForm, CocSource, DofParams, Lens, Method};
use crate::motion::{
    Algorithm, Anchor, CurveKind, Normalize, ReconstructParams, ScatterParams, StretchParams,
    Variant, Weight,
};
use crate::process::Params;
use crate::settings;

/// One point of the sweep: an algorithm with its parameters. The flags that run it come from
/// the settings' definitions ([`settings::flags`]).
#[derive(Clone, Debug)]
pub struct Setting {
    pub label: String,
    pub algorithm: Algorithm,
    pub params: Params,
}

impl Setting {
    /// The `shutter blur` flags that run this setting.
    pub fn flags(&self) -> Vec<String> {
        settings::flags(&settings::Settings::of(self.algorithm, &self.params))
    }
}

impl Setting {
    /// Whether this is what a user gets without setting anything but the algorithm (and,
    /// for depth of field, the lens and the method): each algorithm's default, gather's and
    /// blend's, and their pairs. The bench's rows and plot mark these.
    pub fn is_default(&self) -> bool {
        let motion = Params {
            shutter_offset: 0.0,
            dof: None,
            ..self.params
        } == Params::default();
        let dof = match self.params.dof {
            None => true,
            Some(d) => {
                let gather = DofParams::new(d.source);
                d == gather
                    || d == DofParams {
                        method: Method::Blend,
                        ..gather
                    }
            }
        };
        let any = self.algorithm != Algorithm::None || self.params.dof.is_some();
        motion && dof && any
    }
}

/// The sweep: every algorithm that exists, with its settings. Later issues add theirs here.
pub fn sweep() -> Vec<Setting> {
    let mut settings = vec![Setting {
        label: "none".into(),
        algorithm: Algorithm::None,
        params: Params::default(),
    }];
    let reconstruct = |taps: usize, max_blur: usize, variant: Variant| {
        let name = Variant::ALL
            .iter()
            .find(|(_, v)| *v == variant)
            .map_or("?", |(n, _)| n);
        Setting {
            label: format!("reconstruct {name} S{taps} k{max_blur}"),
            algorithm: Algorithm::Reconstruct,
            params: Params {
                reconstruct: ReconstructParams {
                    taps,
                    max_blur,
                    variant,
                    ..ReconstructParams::default()
                },
                ..Params::default()
            },
        }
    };
    for taps in [5, 9, 15, 25] {
        settings.push(reconstruct(taps, 20, Variant::Paper));
    }
    for max_blur in [10, 40] {
        settings.push(reconstruct(15, max_blur, Variant::Paper));
    }
    settings.push(reconstruct(15, 20, Variant::Dual));
    // The 2014 filter as Blender runs it, and ours (the default: S 31, k 128) against taps
    // and k.
    settings.push(reconstruct(31, 128, Variant::Stable));
    for (taps, max_blur) in [(15, 128), (31, 128), (63, 128), (31, 20)] {
        settings.push(reconstruct(taps, max_blur, Variant::Exposure));
    }
    settings.extend(scatter_sweep());
    settings.extend(stretch_sweep());
    settings
}

/// stretch's settings: the default (centred, texture pre-blur), then one change at a time.
fn stretch_sweep() -> Vec<Setting> {
    let default = StretchParams::default();
    [
        default,
        StretchParams {
            anchor: Anchor::Rear,
            ..default
        },
        StretchParams {
            texture_blur: false,
            ..default
        },
        StretchParams {
            anchor: Anchor::Rear,
            texture_blur: false,
            ..default
        },
        StretchParams {
            extent: 8.0,
            ..default
        },
        StretchParams {
            extent: 32.0,
            ..default
        },
    ]
    .into_iter()
    .map(|p| {
        let anchor = match p.anchor {
            Anchor::Centre => "centre",
            Anchor::Rear => "rear",
        };
        let mut label = format!("stretch {anchor} extent{}", p.extent);
        if !p.texture_blur {
            label += " plain";
        }
        Setting {
            label,
            algorithm: Algorithm::Stretch,
            params: Params {
                stretch: p,
                ..Params::default()
            },
        }
    })
    .collect()
}

/// scatter's settings: the paper's defaults, then one change at a time.
fn scatter_sweep() -> Vec<Setting> {
    let paper = ScatterParams {
        normalize: Normalize::Paper,
        weight: Weight::Gaussian,
        curve: CurveKind::Bezier,
        ..ScatterParams::default()
    };
    let exposure = ScatterParams {
        normalize: Normalize::Exposure,
        weight: Weight::Box,
        ..paper
    };
    let variants = [
        paper,
        ScatterParams {
            background_weight: 1.0,
            ..paper
        },
        ScatterParams {
            background_weight: 20.0,
            ..paper
        },
        ScatterParams {
            curve: CurveKind::Arc,
            ..paper
        },
        exposure,
        ScatterParams {
            curve: CurveKind::Arc,
            ..exposure
        },
        ScatterParams {
            weight: Weight::Gaussian,
            sigma: 0.25,
            ..exposure
        },
        ScatterParams {
            segments: 4,
            ..exposure
        },
        ScatterParams {
            flatness: 0.0,
            segments: 20,
            ..exposure
        },
    ];
    variants.into_iter().map(scatter_setting).collect()
}

fn scatter_setting(p: ScatterParams) -> Setting {
    let normalize = match p.normalize {
        Normalize::Paper => "paper",
        Normalize::Exposure => "exposure",
    };
    let weight = match p.weight {
        Weight::Gaussian => "gaussian",
        Weight::Box => "box",
    };
    let curve = match p.curve {
        CurveKind::Bezier => "bezier",
        CurveKind::Arc => "arc",
    };
    let mut label = format!("scatter {normalize} {curve} {weight}");
    if p.weight == Weight::Gaussian {
        label += &format!(" σ{}", p.sigma);
    }
    if p.normalize == Normalize::Paper {
        label += &format!(" wb{}", p.background_weight);
    }
    label += &format!(" Δ{}", p.segments);
    if p.flatness == 0.0 {
        label += " fixed";
    }
    Setting {
        label,
        algorithm: Algorithm::Scatter,
        params: Params {
            scatter: p,
            ..Params::default()
        },
    }
}

/// What a scene is scored on: one of its references and the settings scored against it.
#[derive(Clone, Debug)]
pub struct Target {
    /// The scene's name in the rows, plots and contact sheets ("layers", "layers dof").
    pub label: String,
    /// The reference file's role: reference, reference_dof or reference_both.
    pub reference: &'static str,
    pub settings: Vec<Setting>,
}

/// A scene's targets: the motion-blur sweep against its motion reference and, for a scene
/// with a lens, the depth-of-field sweep against the lens reference and depth of field with
/// motion blur against the reference with both.
pub fn targets(name: &str, lens: Option<Lens>) -> Vec<Target> {
    let mut targets = vec![Target {
        label: name.to_string(),
        reference: "reference",
        settings: sweep(),
    }];
    if let Some(lens) = lens {
        targets.push(Target {
            label: format!("{name} dof"),
            reference: "reference_dof",
            settings: dof_sweep(lens),
        });
        targets.push(Target {
            label: format!("{name} dof+motion"),
            reference: "reference_both",
            settings: combined_sweep(lens),
        });
    }
    targets
}

/// A depth-of-field setting (with a motion-blur algorithm after it, or none).
fn dof_setting(label: String, algorithm: Algorithm, dof: DofParams) -> Setting {
    Setting {
        label,
        algorithm,
        params: Params {
            dof: Some(dof),
            ..Params::default()
        },
    }
}

/// Depth of field alone: the sharp frame, then gather and blend with their quality settings.
fn dof_sweep(lens: Lens) -> Vec<Setting> {
    let gather = DofParams::new(CocSource::Lens(lens));
    let blend = DofParams {
        method: Method::Blend,
        ..gather
    };
    let mut settings = vec![Setting {
        label: "none".into(),
        algorithm: Algorithm::None,
        params: Params::default(),
    }];
    for rings in [1, 2, 4, 6] {
        let p = DofParams { rings, ..gather };
        settings.push(dof_setting(format!("gather R{rings}"), Algorithm::None, p));
    }
    let hexagon = DofParams {
        blades: 6,
        ..gather
    };
    settings.push(dof_setting(
        "gather R6 6 blades".into(),
        Algorithm::None,
        hexagon,
    ));
    settings.push(dof_setting("blend".into(), Algorithm::None, blend));
    // The talk's form: two copies, the 2n one at E; and the talk's example n = 5 passes.
    let talk = DofParams {
        blend_form: BlendForm::Talk,
        ..blend
    };
    settings.push(dof_setting("blend talk".into(), Algorithm::None, talk));
    let example = DofParams {
        passes: Some(5),
        ..talk
    };
    settings.push(dof_setting(
        "blend talk n5".into(),
        Algorithm::None,
        example,
    ));
    let wide = DofParams {
        epsilon: 3.0,
        ..blend
    };
    settings.push(dof_setting("blend eps3".into(), Algorithm::None, wide));
    settings
}

/// Depth of field then motion blur, against the reference with both; each alone too.
fn combined_sweep(lens: Lens) -> Vec<Setting> {
    let gather = DofParams::new(CocSource::Lens(lens));
    let blend = DofParams {
        method: Method::Blend,
        ..gather
    };
    let motion = |label: &str, algorithm: Algorithm| Setting {
        label: label.into(),
        algorithm,
        params: Params::default(),
    };
    vec![
        motion("none", Algorithm::None),
        motion("scatter", Algorithm::Scatter),
        dof_setting("gather".into(), Algorithm::None, gather),
        dof_setting("gather + scatter".into(), Algorithm::Scatter, gather),
        dof_setting(
            "gather + reconstruct".into(),
            Algorithm::Reconstruct,
            gather,
        ),
        dof_setting("blend + scatter".into(), Algorithm::Scatter, blend),
    ]
}

/// Whether a setting runs any stage that has a GPU twin: depth of field's, reconstruct's,
/// scatter's and stretch's.
pub(super) fn has_twin(setting: &Setting) -> bool {
    setting.params.dof.is_some()
        || matches!(
            setting.algorithm,
            Algorithm::Reconstruct | Algorithm::Scatter | Algorithm::Stretch
        )
}
