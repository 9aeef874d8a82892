//! The command line: parse (clap, in `args`), resolve to a job (`resolve`: preset merged,
//! flags over preset values, frames listed), run one of the commands (a module each), and
//! report. Only this module prints.

pub mod args;
mod bench;
mod blur;
mod diff;
mod info;
mod presets;
mod resolve;
mod scene;

pub use resolve::resolve;

use clap::Parser;

use crate::error::{Error, Result};

use args::{Cli, Command};

/// Parses the command line, runs it and returns the process exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return e.exit_code();
        }
    };
    if let Err(error) = check_thread_variable() {
        print_error(&error);
        return error.exit_code();
    }
    stop_cleanly_on_signals();
    let result = match cli.command {
        Command::Blur(args) => blur::blur(*args, false),
        Command::Dof(args) => blur::blur(*args, true),
        Command::Info(args) => info::info(args),
        Command::Presets(args) => presets::presets(args),
        Command::Scene(args) => scene::scene(args),
        Command::Bench(args) => bench::bench(args),
        Command::Frames(args) => frames(args),
        Command::Diff(args) => {
            return match diff::diff(args) {
                Ok(code) => code,
                Err(error) => {
                    print_error(&error);
                    // For diff, an unreadable input is not a comparison result: exit 2.
                    2
                }
            };
        }
    };
    match result {
        Ok(()) => 0,
        Err(error) => {
            print_error(&error);
            error.exit_code()
        }
    }
}

/// The thread limit never falls below this, whatever the machine: enough for any farm node's
/// share, and few enough that starting them stays quick. Every pool is started whole (ours,
/// and one per EXR file read or written by the exr crate, sized from RAYON_NUM_THREADS), so a
/// count far above the cores is pure start-up cost: 1024 threads took 6.6 s for three 64×36
/// frames on 2 cores, and 5000 did not finish in a minute (issue 17).
const MIN_THREAD_LIMIT: usize = 256;

/// The most worker threads a run may ask for: the larger of [`MIN_THREAD_LIMIT`] and the
/// cores this machine has. Output does not depend on the count, so the limit changes only
/// the time a run takes.
fn thread_limit() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    MIN_THREAD_LIMIT.max(cores)
}

/// A thread count, as given (`--threads ` or `RAYON_NUM_THREADS=`), within [`thread_limit`].
fn check_threads(threads: usize, given_as: &str) -> Result<()> {
    let limit = thread_limit();
    if threads > limit {
        return Err(Error::usage(format!(
            "{given_as}{threads} is above the limit of {limit} threads (the larger of \
             {MIN_THREAD_LIMIT} and this machine's cores): more threads than cores only add \
             start-up time, and the output is the same for any count"
        )));
    }
    Ok(())
}

/// RAYON_NUM_THREADS above [`thread_limit`] is refused, as `--threads` is: it sizes every
/// pool of the run.
fn check_thread_variable() -> Result<()> {
    let Ok(value) = std::env::var("RAYON_NUM_THREADS") else {
        return Ok(());
    };
    match value.trim().parse::<usize>() {
        Ok(threads) => check_threads(threads, "RAYON_NUM_THREADS="),
        Err(_) => Ok(()),
    }
}

/// The signals that end a run the way SIGTERM does, with their names: every catchable one
/// whose default action ends the process and that a user, a shell, a terminal or a farm
/// sends. SIGHUP: the terminal or ssh connection closed; SIGQUIT: Ctrl-\\; SIGUSR1/2: some
/// schedulers' warning before a kill; SIGALRM: a timer; SIGXCPU: a CPU-time limit (a farm's
/// `ulimit -t`); SIGXFSZ: a file-size limit. SIGPIPE is not among them: Rust ignores it, so
/// a closed pipe is an error on the write that meets it, ended as errors are.
#[cfg(unix)]
pub const STOPPING_SIGNALS: [(i32, &str); 9] = {
    use signal_hook::consts::*;
    [
        (SIGHUP, "SIGHUP"),
        (SIGINT, "SIGINT"),
        (SIGQUIT, "SIGQUIT"),
        (SIGTERM, "SIGTERM"),
        (SIGUSR1, "SIGUSR1"),
        (SIGUSR2, "SIGUSR2"),
        (SIGALRM, "SIGALRM"),
        (SIGXCPU, "SIGXCPU"),
        (SIGXFSZ, "SIGXFSZ"),
    ]
};

/// On any of [`STOPPING_SIGNALS`]: stop writing, remove the temporary files of frames in
/// flight, release the output locks (the library's registries, [`crate::io::abandon`]), say
/// so in one line and exit 128 + the signal's number, as a shell reports it (130 for SIGINT,
/// 143 for SIGTERM, 129 for SIGHUP, 152 for SIGXCPU). Frames already renamed into place are
/// whole; `--skip-existing` finishes the run. A thread of its own waits for the signal
/// (signal-hook), so the cleanup is ordinary code, not a signal handler's.
#[cfg(unix)]
fn stop_cleanly_on_signals() {
    let numbers = STOPPING_SIGNALS.map(|(number, _)| number);
    let Ok(mut signals) = signal_hook::iterator::Signals::new(numbers) else {
        // Without the handler the default applies: the process dies, and the next run over
        // the same outputs removes what it left.
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            let name = STOPPING_SIGNALS
                .iter()
                .find(|(number, _)| *number == signal)
                .map_or("a signal", |(_, name)| name);
            let abandoned = crate::io::abandon();
            eprintln!(
                "shutter: stopped by {name}: {} unfinished temporary file{} removed, frames \
                 written before are whole; rerun with --skip-existing to finish",
                abandoned.temporaries,
                if abandoned.temporaries == 1 { "" } else { "s" }
            );
            std::process::exit(128 + signal);
        }
    });
}

#[cfg(not(unix))]
fn stop_cleanly_on_signals() {}

/// `shutter frames`: a frame spec expanded and cut into chunks, each printed as a spec.
fn frames(args: args::FramesArgs) -> Result<()> {
    use crate::io::sequence::{chunks, format_frames, parse_frames};
    let frames = parse_frames(&args.spec)?;
    let size = match args.chunk_size {
        Some(0) => return Err(Error::usage("--chunk-size must be at least 1")),
        Some(size) => size,
        None => frames.len(),
    };
    let chunks = chunks(&frames, size);
    if args.count {
        out(&format!("{}\n", chunks.len()));
        return Ok(());
    }
    match args.chunk {
        Some(k) => match chunks.get(k) {
            Some(chunk) => out(&format!("{}\n", format_frames(chunk))),
            None => {
                return Err(Error::usage(format!(
                    "--chunk {k}: the spec makes {} chunks of {size} (0 to {})",
                    chunks.len(),
                    chunks.len().saturating_sub(1)
                )))
            }
        },
        None => {
            let text: String = chunks.iter().map(|c| format_frames(c) + "\n").collect();
            out(&text);
        }
    }
    Ok(())
}

/// Writes `text` to stdout, the one way every command prints its results. A reader that
/// closed the pipe early (`| head`) is not an error, so nothing panics.
fn out(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// The most problems printed one by one; the rest are counted.
const MAX_PRINTED_PROBLEMS: usize = 20;

fn print_error(error: &Error) {
    match error {
        Error::Usage(message) | Error::Device(message) => eprintln!("shutter: error: {message}"),
        Error::Files(problems) => {
            for problem in problems.iter().take(MAX_PRINTED_PROBLEMS) {
                eprintln!("shutter: error: {problem}");
            }
            if problems.len() > MAX_PRINTED_PROBLEMS {
                eprintln!(
                    "shutter: error: ... and {} more problems",
                    problems.len() - MAX_PRINTED_PROBLEMS
                );
            }
            if problems.len() > 1 {
                eprintln!(
                    "shutter: {} problems found; nothing was written for the frames concerned",
                    problems.len()
                );
            }
        }
    }
}

/// Parses `WxH`.
pub fn parse_size(text: &str) -> Result<(usize, usize)> {
    let bad = || Error::usage(format!("bad size '{text}': use WxH, e.g. 640x360"));
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: usize = w.trim().parse().map_err(|_| bad())?;
    let h: usize = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(bad());
    }
    Ok((w, h))
}

/// Parses a shutter offset as blur's `--shutter-offset` takes it: `centre`, `start`, `end` or
/// a number from −0.5 to 0.5 (`motion::Shutter`).
pub fn parse_shutter_offset(text: &str) -> Result<f64> {
    let def = crate::settings::def("shutter-offset").expect("the shutter-offset setting");
    match def.parse(text) {
        Ok(crate::settings::Value::Number(v)) => Ok(v),
        _ => Err(Error::usage(format!(
            "bad --shutter-offset '{text}': use {}",
            def.expect()
        ))),
    }
}
