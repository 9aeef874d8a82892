//! The bokeh gather's light-layers cost on three frames (BENCHMARKS.md, "Light layers"): the
//! beauty then six RGB layers alternated, wall and process CPU time a run.
//! `cargo run --release --example gather_ab -- bench|small|focus RUNS` (`small`: f/5.6;
//! `focus`: one 200 px column of blocks out of focus).
#[path = "../benches/common/mod.rs"]
mod common;

use shutter::dof::{CocSource, DofParams, Lens};
use shutter::motion::Algorithm;
use shutter::numeric;
use shutter::process::{self, process_clean, Params};
use std::time::Instant;

fn cpu_ms() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap();
    let rest = &s[s.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = rest.split(' ').collect();
    let (u, k): (f64, f64) = (f[11].parse().unwrap(), f[12].parse().unwrap());
    (u + k) * 10.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let case = args.get(1).map(String::as_str).unwrap_or("bench");
    let runs: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let mut f = common::lens_frame();
    let f_number = match case {
        "small" => 5.6,
        _ => 1.4,
    };
    if case == "focus" {
        // Mostly in focus: one block column of 200 px out of focus (near), the rest at 3 m.
        let w = common::W;
        f.depth = Some(
            (0..common::W * common::H)
                .map(|i| if i % w / 200 == 4 { 1.5 } else { 3.0 })
                .collect(),
        );
    }
    let lens = Lens {
        focal_mm: 50.0,
        f_number,
        focus: 3.0,
        sensor_mm: 36.0,
    };
    let params = Params {
        dof: Some(DofParams {
            max_coc: 32.0,
            ..DofParams::new(CocSource::Lens(lens))
        }),
        ..Params::default()
    };
    let layered = common::with_light_layers(&f);
    let prep = |f: &shutter::frame::Frame| {
        let mut clean = f.clone();
        let _ = numeric::sanitize(&mut clean, process::depth_kind(&params));
        clean
    };
    let (a, b) = (prep(&f), prep(&layered));
    let _ = process_clean(Algorithm::None, &params, a.clone(), 1);
    let _ = process_clean(Algorithm::None, &params, b.clone(), 1);
    let time = |x: &shutter::frame::Frame| {
        let input = x.clone();
        let (c, t) = (cpu_ms(), Instant::now());
        let out = process_clean(Algorithm::None, &params, input, 1);
        let r = (t.elapsed().as_secs_f64() * 1e3, cpu_ms() - c);
        drop(out);
        r
    };
    for _ in 0..runs {
        let (bw, bc) = time(&a);
        let (lw, lc) = time(&b);
        println!(
            "{case} beauty {bw:.1} ms (cpu {bc:.0}) layers {lw:.1} ms (cpu {lc:.0}) ratio {:.2} (cpu {:.2})",
            lw / bw,
            lc / bc
        );
    }
}
