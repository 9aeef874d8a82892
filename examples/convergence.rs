//! Reference convergence: RMSE between references with N and 2N samples (different seeds),
//! over the region blur changes, beside the error of the unblurred frame.
//!
//! ```text
//! cargo run --release --example convergence -- 192 108 256
//! ```

use shutter::lab::metrics::{changed_region, rmse, Rgb};
use shutter::lab::truth::render::{render_passes, render_reference, Reference, RenderSettings};
use shutter::lab::truth::scenes::{build, SCENES};

fn rgb(planes: &[Vec<f32>; 3], w: usize, h: usize) -> Rgb<'_> {
    Rgb {
        width: w,
        height: h,
        planes: [&planes[0], &planes[1], &planes[2]],
    }
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let (w, h, n) = (args[0], args[1], args[2]);
    for (name, _) in SCENES {
        let scene = build(name, w, h, 1).expect("scene");
        let kinds: &[Reference] = if scene.lens.is_some() {
            &[
                Reference::MotionBlur,
                Reference::DepthOfField,
                Reference::Both,
            ]
        } else {
            &[Reference::MotionBlur]
        };
        for &kind in kinds {
            let s = |samples, seed| RenderSettings {
                samples,
                shutter: 0.5,
                shutter_offset: 0.0,
                seed,
            };
            let a = render_reference(&scene, 0.0, kind, &s(n, 1));
            let b = render_reference(&scene, 0.0, kind, &s(2 * n, 2));
            let sharp = render_passes(&scene, 0.0, 2 * n, 2).color.expect("colour");
            let sharp = [sharp.r, sharp.g, sharp.b];
            let region = changed_region(&rgb(&sharp, w, h), &rgb(&b, w, h), 1e-3);
            let count = region.iter().filter(|&&m| m).count();
            let noise = rmse(&rgb(&a, w, h), &rgb(&b, w, h), Some(&region));
            let none = rmse(&rgb(&sharp, w, h), &rgb(&b, w, h), Some(&region));
            println!(
                "{name:9} {kind:?}: region {count:6} px, N vs 2N {noise:.5}, none {none:.5}, ratio {:.1}",
                none / noise.max(1e-12)
            );
        }
    }
}
