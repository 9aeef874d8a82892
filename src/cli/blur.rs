//! `shutter blur` and `shutter dof`: resolve the job, run the pipeline with a progress bar
//! or per-frame lines, print the summary.

use std::io::IsTerminal;

use crate::error::{Error, Result};
use crate::pipeline::{run, Event};

use super::args::BlurArgs;
use super::out_text;
use super::resolve;

pub fn blur(args: BlurArgs, dof: bool) -> Result<()> {
    if let Some(threads) = args.threads {
        if threads == 0 {
            return Err(Error::usage("--threads must be at least 1"));
        }
        super::check_threads(threads, "--threads ")?;
        // The exr crate, where it runs in parallel itself, builds its own pool and sizes it
        // from this variable (EXR outputs are deflated on ours, src/io/exr_zip.rs): set it
        // so --threads bounds every pool. Nothing else runs yet.
        std::env::set_var("RAYON_NUM_THREADS", threads.to_string());
        // Fails only if the pool was already built, which cannot happen this early.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global();
    }
    let job = resolve(&args)?;
    if dof && job.params.dof.is_none() {
        return Err(Error::usage(
            "shutter dof needs a lens (--focal-length, --f-stop and --focus-distance) or a \
             painted map (--coc-map PATH)",
        ));
    }
    let terminal = std::io::stderr().is_terminal();
    let verbose = args.verbose;
    let quiet = args.quiet;
    let mut bar: Option<indicatif::ProgressBar> = None;
    let mut on_event = |event: Event| match event {
        Event::Started { frames } => {
            if terminal && !verbose {
                let b = indicatif::ProgressBar::new(frames as u64);
                b.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{bar:40} {pos}/{len} frames  {msg}  eta {eta}",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                bar = Some(b);
            } else if verbose {
                say!("shutter: {frames} frames to write");
            }
        }
        Event::Written { path, .. } => match &bar {
            Some(b) => {
                b.inc(1);
                let seconds = b.elapsed().as_secs_f64().max(1e-9);
                b.set_message(format!("{:.2} frames/s", b.position() as f64 / seconds));
            }
            None if verbose => say!("shutter: wrote {}", path.display()),
            None => {}
        },
        Event::Skipped { path, .. } => {
            if verbose || terminal {
                say!("shutter: skipped {} (exists)", path.display());
            }
        }
        // Every warning, one line, on a terminal or a pipe (a farm's log), unless --quiet.
        Event::Warning(_) if quiet => {}
        Event::Warning(message) => match &bar {
            Some(b) => b.println(format!(
                "shutter: warning: {}",
                crate::error::printable(&message)
            )),
            None => say!("shutter: warning: {message}"),
        },
    };
    let result = run(&job, &mut on_event);
    if let Some(b) = bar.take() {
        b.finish_and_clear();
    }
    let mut report = result?;
    report.command = if dof { "dof" } else { "blur" };
    if args.json {
        super::out_json(&report)?;
    } else if args.dry_run {
        // One line a frame: what it would do, its output, and why a redo.
        let text: String = report
            .planned
            .iter()
            .map(|p| {
                let frame = p
                    .frame
                    .map_or("still".to_string(), |f| format!("frame {f}"));
                let why = p.why.as_ref().map_or(String::new(), |w| format!(" ({w})"));
                format!("{frame}: {} {}{why}\n", p.action, p.output.display())
            })
            .collect();
        out_text(&text)?;
    } else if verbose || terminal {
        say!(
            "shutter: {} frames written, {} skipped in {:.2} s (read {:.2} s, process {:.2} s, write {:.2} s)",
            report.frames_written,
            report.frames_skipped,
            report.wall_seconds,
            report.read_seconds,
            report.process_seconds,
            report.write_seconds
        );
    }
    Ok(())
}
