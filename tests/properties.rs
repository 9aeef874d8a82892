//! Property tests (proptest) over every motion-blur algorithm and depth-of-field method, on
//! random small frames whose values are hostile: NaN, ±∞, ±1e30 and 3e38 colour, denormal,
//! zero, negative and infinite depth, velocities of 1e9 px, positions far off screen. For
//! every frame and pass: the output is finite, each channel within the range of the
//! (sanitised) input's, and the same bits twice and on one thread as on several (issue 17).
//! Bounded time is what lets the cases finish: the frames are small, and no pass may grow
//! with the values (a case that hung would hang the test).

use proptest::collection::vec;
use proptest::prelude::*;

use shutter::dof::{CocSource, DofParams, Lens, Method};
use shutter::frame::{Color, Frame, Positions, Velocity};
use shutter::motion::Algorithm;
use shutter::numeric::{sanitize, DepthKind};
use shutter::process::{process, Params};

const LENS: Lens = Lens {
    focal_mm: 50.0,
    f_number: 1.4,
    focus: 3.0,
    sensor_mm: 36.0,
};

/// Mostly ordinary values, often hostile ones.
fn hostile(ordinary: std::ops::Range<f32>, extremes: &'static [f32]) -> BoxedStrategy<f32> {
    prop_oneof![
        3 => ordinary,
        1 => proptest::sample::select(extremes),
    ]
    .boxed()
}

const COLOUR: &[f32] = &[
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    1e30,
    -1e30,
    3e38,
    0.0,
    -0.0,
    1e-40,
];
const DEPTH: &[f32] = &[
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    0.0,
    -1.0,
    1e-40,
    1e38,
];
const MOTION: &[f32] = &[
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    1e9,
    -1e9,
    0.0,
    1e-40,
];

fn frame() -> impl Strategy<Value = Frame> {
    (1usize..=20, 1usize..=14).prop_flat_map(|(w, h)| {
        let n = w * h;
        (
            vec(hostile(-0.5..4.0, COLOUR), 4 * n),
            vec(hostile(0.5..50.0, DEPTH), n),
            vec(hostile(-20.0..20.0, MOTION), 2 * n),
            vec(hostile(-20.0..20.0, MOTION), 4 * n),
        )
            .prop_map(move |(c, z, v, p)| {
                let mut f = Frame::new(w, h);
                let plane = |values: &[f32], k: usize| values[k * n..(k + 1) * n].to_vec();
                f.color = Some(Color {
                    r: plane(&c, 0),
                    g: plane(&c, 1),
                    b: plane(&c, 2),
                    a: Some(plane(&c, 3)),
                });
                f.depth = Some(z);
                f.velocity = Some(Velocity {
                    x: plane(&v, 0),
                    y: plane(&v, 1),
                });
                // Positions: the pixel centre moved by the (hostile) offsets.
                let at = |k: usize, axis: usize| -> Vec<f32> {
                    (0..n)
                        .map(|i| {
                            let centre = if axis == 0 { i % w } else { i / w } as f32 + 0.5;
                            centre + p[k * n + i]
                        })
                        .collect()
                };
                f.prev = Some(Positions {
                    x: at(0, 0),
                    y: at(1, 1),
                    z: None,
                });
                f.next = Some(Positions {
                    x: at(2, 0),
                    y: at(3, 1),
                    z: None,
                });
                f
            })
    })
}

/// Every pass: each motion-blur algorithm at its defaults, and depth of field's two methods.
fn passes() -> Vec<(&'static str, Algorithm, Params)> {
    let dof = |method| Params {
        dof: Some(DofParams {
            method,
            ..DofParams::new(CocSource::Lens(LENS))
        }),
        ..Params::default()
    };
    vec![
        ("none", Algorithm::None, Params::default()),
        ("reconstruct", Algorithm::Reconstruct, Params::default()),
        ("scatter", Algorithm::Scatter, Params::default()),
        ("stretch", Algorithm::Stretch, Params::default()),
        ("gather", Algorithm::None, dof(Method::Gather)),
        ("blend", Algorithm::None, dof(Method::Blend)),
    ]
}

fn colour(f: &Frame) -> [&[f32]; 4] {
    let c = f.color.as_ref().expect("colour");
    [&c.r, &c.g, &c.b, c.a.as_deref().expect("alpha")]
}

fn bits(f: &Frame) -> Vec<u32> {
    colour(f)
        .iter()
        .flat_map(|p| p.iter().map(|v| v.to_bits()))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn every_pass_is_finite_in_range_and_deterministic_on_hostile_frames(f in frame()) {
        // The input as the passes see it: the numeric policy applied.
        let mut clean = f.clone();
        sanitize(&mut clean, DepthKind::Depth);
        let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        for (name, algorithm, params) in passes() {
            let (out, _) = process(algorithm, &params, f.clone(), 7);
            for (k, (o, i)) in colour(&out).iter().zip(colour(&clean)).enumerate() {
                let lo = i.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = i.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                // Sums of many values round: a relative slack on the range's magnitude.
                let slack = 1e-4 * hi.abs().max(lo.abs()).max(1.0);
                for v in o.iter() {
                    prop_assert!(v.is_finite(), "{name}: channel {k} has {v}");
                    prop_assert!(
                        *v >= lo - slack && *v <= hi + slack,
                        "{name}: channel {k} has {v}, outside [{lo}, {hi}]"
                    );
                }
            }
            let again = process(algorithm, &params, f.clone(), 7).0;
            prop_assert_eq!(bits(&again), bits(&out), "{}: not the same twice", name);
            let single = one_thread.install(|| process(algorithm, &params, f.clone(), 7).0);
            prop_assert_eq!(bits(&single), bits(&out), "{}: not the same on one thread", name);
        }
    }
}

/// One item of a frame spec and the frames it stands for, built independently of the parser:
/// a single frame, or a range from `first` by `step` over `count` frames, written `A-B:S`
/// (or `A-B` for a step of 1) with a last frame `B` up to a step past the last one reached.
fn spec_item() -> impl Strategy<Value = (String, Vec<i64>)> {
    prop_oneof![
        (-300i64..300).prop_map(|f| (f.to_string(), vec![f])),
        (-300i64..300, 1usize..40, -7i64..8, 0i64..7).prop_filter_map(
            "a step of 0",
            |(first, count, step, over)| {
                if step == 0 {
                    return None;
                }
                let frames: Vec<i64> = (0..count as i64).map(|k| first + k * step).collect();
                let last = frames[count - 1];
                // Any end between the last frame and the next one reaches the same frames.
                let end = last + step.signum() * over.min(step.abs() - 1);
                let text = if step == 1 {
                    format!("{first}-{end}")
                } else {
                    format!("{first}-{end}:{step}")
                };
                Some((text, frames))
            }
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn chunks_of_any_spec_hold_every_frame_once_and_write_back_exactly(
        items in vec(spec_item(), 1..6),
        size in 1usize..30,
    ) {
        use shutter::io::sequence::{chunks, format_frames, parse_frames};
        let spec: Vec<&str> = items.iter().map(|(text, _)| text.as_str()).collect();
        let spec = spec.join(",");
        // The frames the items stand for, in order, each once.
        let mut expected = Vec::new();
        for (_, frames) in &items {
            for &f in frames {
                if !expected.contains(&f) {
                    expected.push(f);
                }
            }
        }
        let frames = parse_frames(&spec).unwrap();
        prop_assert_eq!(&frames, &expected, "{}", spec);
        let parts = chunks(&frames, size);
        // Every chunk but the last is full; together they are the frames, in order, once.
        for part in &parts[..parts.len() - 1] {
            prop_assert_eq!(part.len(), size);
        }
        prop_assert_eq!(parts.concat(), frames.clone());
        // Each chunk as a spec (what a farm task is given) parses back to itself.
        for part in &parts {
            let text = format_frames(part);
            prop_assert_eq!(parse_frames(&text).unwrap(), part.to_vec(), "{}", text);
        }
    }
}
