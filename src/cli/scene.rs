//! `shutter scene`: write a truth scene's passes and references.

use std::io::IsTerminal;

use crate::error::Result;

use super::args::SceneArgs;
use super::parse_size;

pub fn scene(args: SceneArgs) -> Result<()> {
    let (width, height) = match &args.size {
        Some(size) => parse_size(size)?,
        None => crate::lab::truth::write::DEFAULT_SIZE,
    };
    let options = crate::lab::truth::write::SceneOptions {
        width,
        height,
        frames: args.frames,
        samples: args.samples,
        shutter: args.shutter,
        shutter_offset: super::parse_shutter_offset(&args.shutter_offset)?,
        seed: args.seed,
        layers: args.layers,
        max_memory: args.max_memory.map(|mib| mib.saturating_mul(1 << 20)),
    };
    let verbose = std::io::stderr().is_terminal();
    let description = crate::lab::truth::write::write_scene(
        &args.name,
        &args.output,
        &options,
        &mut |frame, _| {
            if verbose {
                say!("shutter: scene {} frame {frame} written", args.name);
            }
        },
    )?;
    if verbose {
        say!(
            "shutter: {} frames of {} in {}",
            description.frames,
            description.scene,
            args.output.display()
        );
    }
    Ok(())
}
