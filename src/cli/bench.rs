//! `shutter bench`: the time-against-error sweep.

use crate::error::{Error, Result};

use super::args::BenchArgs;
use super::out;
use super::parse_size;

pub fn bench(args: BenchArgs) -> Result<()> {
    let (width, height) = match &args.size {
        Some(size) => parse_size(size)?,
        None => (320, 180),
    };
    let scenes = match &args.scenes {
        Some(list) => list.split(',').map(|s| s.trim().to_string()).collect(),
        None => crate::lab::truth::scenes::SCENES
            .iter()
            .map(|(n, _)| n.to_string())
            .collect(),
    };
    let binary = std::env::current_exe()
        .map_err(|e| Error::usage(format!("cannot find the shutter binary: {e}")))?;
    let options = crate::lab::bench::BenchOptions {
        scenes,
        width,
        height,
        out: args.out.clone(),
        samples: args.samples,
        runs: args.runs,
        shutter_offset: super::parse_shutter_offset(&args.shutter_offset)? as f32,
        binary,
        peers: args.peers.clone(),
        layers: args.layers,
    };
    let started = std::time::Instant::now();
    let report = crate::lab::bench::run(&options, &mut |line| say!("shutter: bench: {line}"))?;
    out(&crate::lab::bench::markdown(&report))?;
    say!(
        "shutter: bench: {} rows in {:.1} s; wrote {}/bench.json, bench.md, pareto.svg, pareto.png, contact/",
        report.rows.len(),
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}
