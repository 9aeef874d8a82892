//! Depth of field, processing only (no I/O), on synthetic 1920×1080 frames:
//!
//! ```text
//! cargo bench --bench dof
//! ```
//!
//! - **out of focus**: 50 mm f/1.4 focused at 3 m on a 36 mm sensor; the frame's 200×150
//!   blocks sit at 1.5 m (CoC −32 px), 3 m (in focus), 6 m (+16 px) and far (+32 px), so the
//!   largest CoC is 32 px and three quarters of the frame is blurred; gather at its
//!   defaults (6 rings) and with 2 and 4 rings and six blades, then blend (the pyramid, its
//!   default, and the talk's two copies);
//! - **in focus**: every pixel at 3 m, beside the time of copying the frame;
//! - **light layers**: the gather at its defaults with six RGB light layers beside the
//!   beauty, against the beauty alone (issue 29's cost bound: at most 1.5×);
//! - **wgpu**: the gather at its defaults and blend with their stages on the GPU, where an
//!   adapter is present (Mesa's software driver included: for the record, not for speed),
//!   with the GPU stages' upload, dispatch and readback timed apart.
//!
//! Median of 5 runs after one warm-up run. Words after `--` keep only the rows whose label
//! contains one of them (`cargo bench --bench dof -- blend round`).

mod common;

use std::time::Instant;

use common::{H, W};
use shutter::dof::{BlendForm, CocSource, DofParams, Lens, Method};
use shutter::motion::Algorithm;
use shutter::process::Params;

const LENS: Lens = Lens {
    focal_mm: 50.0,
    f_number: 1.4,
    focus: 3.0,
    sensor_mm: 36.0,
};

fn dof_params(dof: DofParams) -> Params {
    Params {
        dof: Some(dof),
        ..Params::default()
    }
}

fn median_ms(f: &shutter::frame::Frame, dof: DofParams) -> f64 {
    common::median_ms(Algorithm::None, f, &dof_params(dof), 5)
}

fn main() {
    let chosen = common::chosen_rows();
    println!("threads: {}", rayon::current_num_threads());
    let f = common::lens_frame();
    let gather = DofParams {
        max_coc: 32.0,
        ..DofParams::new(CocSource::Lens(LENS))
    };
    let largest = LENS
        .coc(1.5, W as f64)
        .max(LENS.coc(f64::INFINITY, W as f64));
    println!("largest CoC: {largest:.1} px");
    for (label, dof) in [
        ("gather (6 rings, round)", gather),
        ("gather 2 rings", DofParams { rings: 2, ..gather }),
        ("gather 4 rings", DofParams { rings: 4, ..gather }),
        (
            "gather 6 rings, 6 blades",
            DofParams {
                blades: 6,
                ..gather
            },
        ),
        (
            "blend (pyramid)",
            DofParams {
                method: Method::Blend,
                ..gather
            },
        ),
        (
            "blend, the talk's form",
            DofParams {
                method: Method::Blend,
                blend_form: BlendForm::Talk,
                ..gather
            },
        ),
    ] {
        if !chosen(label) {
            continue;
        }
        println!(
            "1920x1080 out of focus, {label}: {:.1} ms",
            median_ms(&f, dof)
        );
    }
    if chosen("light layers") {
        common::light_layers_row(
            "out of focus, gather (6 rings, round)",
            Algorithm::None,
            &f,
            &dof_params(gather),
        );
    }
    // The GPU rows: the gather with its stages (coc, tile min/max, the bokeh gather) and
    // blend with its (coc, the pyramid) on the GPU, wherever an adapter is present.
    if chosen("wgpu") {
        match common::gpu() {
            Some(gpu) => {
                let blend = DofParams {
                    method: Method::Blend,
                    ..gather
                };
                for (label, dof) in [
                    ("gather (6 rings, round)", gather),
                    ("blend (pyramid)", blend),
                ] {
                    let (ms, t) =
                        common::median_ms_on(&gpu, Algorithm::None, &f, &dof_params(dof), 5);
                    common::print_gpu_row(&format!("out of focus, {label}"), &gpu, (ms, t));
                }
            }
            None => println!("wgpu rows skipped: no GPU adapter"),
        }
    }
    if !chosen("in focus") {
        return;
    }
    let mut sharp = f.clone();
    sharp.depth = Some(vec![3.0; W * H]);
    println!(
        "1920x1080 in focus, gather: {:.2} ms",
        median_ms(&sharp, gather)
    );
    let mut copies: Vec<f64> = (0..5)
        .map(|_| {
            let t = Instant::now();
            let copy = sharp.clone();
            let ms = t.elapsed().as_secs_f64() * 1e3;
            drop(copy);
            ms
        })
        .collect();
    copies.sort_by(f64::total_cmp);
    println!("1920x1080 copying the frame: {:.2} ms", copies[2]);
}
