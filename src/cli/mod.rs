//! The command line: parse (clap, in `args`), resolve to a job (`resolve`: preset merged,
//! flags over preset values, frames listed), run one of the commands (a module each), and
//! report. Only this module prints.

/// A line on stderr, as `eprintln!` writes it, where a write that fails (a full disk under a
/// farm's log, a log reader gone) is let go: the line is lost, the run goes on, and its exit
/// code is its work's. (`eprintln!` panics there: exit 101, the run stopped.) Every line is
/// one line, its control characters escaped (`error::printable`): a name a file gave a
/// message cannot colour the terminal or break the line.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let line = $crate::error::printable(&format!($($arg)*));
        let _ = writeln!(std::io::stderr(), "{line}");
    }};
}

pub mod args;
mod attributes;
mod bench;
mod blur;
mod diff;
mod info;
mod presets;
mod resolve;
mod scene;
mod vectors;

pub use resolve::resolve;

use clap::Parser;

use crate::error::{Error, Problem, ProblemKind, Result};

use args::{Cli, Command};

/// Parses the command line, runs it and returns the process exit code, stdout flushed.
pub fn main() -> i32 {
    let code = flush_stdout(parse_and_run());
    // A signal being handled ends the process itself, with its own code and (`--json`) its
    // own document: the run must not end first with another.
    if STOPPING.load(std::sync::atomic::Ordering::SeqCst) {
        loop {
            std::thread::park();
        }
    }
    code
}

/// Set once a stopping signal is being handled ([`stop_cleanly_on_signals`]).
static STOPPING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn parse_and_run() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout: a failed write there is the run's error.
            if let Err(error) = e.print() {
                if !e.use_stderr() {
                    let error = stdout_error(error);
                    print_error(&error);
                    return error.exit_code();
                }
            }
            let mut code = e.exit_code();
            // (Lossily: an argument that is not UTF-8, a path from a Latin-1 share, is what
            // clap refused, and `std::env::args` would panic on it.)
            let args: Vec<String> = std::env::args_os()
                .skip(1)
                .map(|a| a.to_string_lossy().into_owned())
                .collect();
            let command = args.first().map_or("", String::as_str);
            // A command line clap cannot parse is a comparison not made: idiff's 4.
            if code == 2 && command == "diff" && args.iter().any(|a| a == "--idiff") {
                code = 4;
            }
            // --json asked for: the error object on stdout, as for any failed run.
            if code != 0 && args.iter().any(|a| a == "--json") {
                // Its first line, and where that ends in a colon, the lines it introduces
                // (the required arguments not given), up to the blank line before the usage.
                let rendered = e.to_string();
                let mut lines = rendered.lines();
                let mut message = lines
                    .next()
                    .unwrap_or_default()
                    .trim_start_matches("error: ")
                    .to_string();
                if message.ends_with(':') {
                    let listed: Vec<&str> = lines
                        .take_while(|l| !l.trim().is_empty())
                        .map(str::trim)
                        .collect();
                    message = format!("{} {}", message, listed.join(", "));
                }
                let error = Error::usage(format!("{message} (see shutter {command} --help)"));
                if let Err(lost) = out_json(&error_json(command, &error, code)) {
                    print_error(&lost);
                }
            }
            return code;
        }
    };
    let (command, json) = match &cli.command {
        Command::Blur(a) => ("blur", a.json),
        Command::Dof(a) => ("dof", a.json),
        Command::Info(a) => ("info", a.json),
        Command::Diff(a) => ("diff", a.json),
        Command::Presets(_) => ("presets", false),
        Command::Scene(_) => ("scene", false),
        Command::Bench(_) => ("bench", false),
        Command::Frames(_) => ("frames", false),
        Command::Vectors(a) => ("vectors", a.json),
    };
    let failed = |error: &Error, code: i32| {
        print_error_of(command, error);
        // Unless the command printed its own document with the error in it (info).
        if json && !JSON_PRINTED.load(std::sync::atomic::Ordering::Relaxed) {
            if let Err(lost) = out_json(&error_json(command, error, code)) {
                print_error(&lost);
            }
        }
        code
    };
    // `--threads` sets the count itself (over the variable), and `frames` and `presets` run
    // no pool.
    let own_count = match &cli.command {
        Command::Blur(args) | Command::Dof(args) => args.threads.is_some(),
        Command::Frames(_) | Command::Presets(_) => true,
        _ => false,
    };
    if !own_count {
        if let Err(error) = check_thread_variable() {
            return failed(&error, error.exit_code());
        }
    }
    stop_cleanly_on_signals(command, json);
    let result = match cli.command {
        Command::Blur(args) => blur::blur(*args, false),
        Command::Dof(args) => blur::blur(*args, true),
        Command::Info(args) => info::info(args),
        Command::Presets(args) => presets::presets(args),
        Command::Scene(args) => scene::scene(args),
        Command::Bench(args) => bench::bench(args),
        Command::Frames(args) => frames(args),
        Command::Diff(args) => {
            let codes = diff::Codes::of(&args);
            return match diff::diff(*args) {
                Ok(code) => code,
                // A comparison not made is not a comparison's result: its own code.
                Err(error) => failed(&error, codes.error(&error)),
            };
        }
        Command::Vectors(args) => {
            return match vectors::vectors(args) {
                Ok(code) => code,
                Err(error) => failed(&error, error.exit_code()),
            };
        }
    };
    match result {
        Ok(()) => 0,
        Err(error) => failed(&error, error.exit_code()),
    }
}

/// The document `--json` prints on stdout when a command fails (README: "JSON"): the schema,
/// the command, `"ok": false` and an error object with the exit code, the kind of error and
/// every problem (file, frame, pass, channel, what went wrong).
pub fn error_json(command: &str, error: &Error, code: i32) -> serde_json::Value {
    let kind = match error {
        Error::Usage(_) => "usage",
        Error::Device(_) => "device",
        Error::Files(_) if code == crate::error::TRANSIENT_EXIT => "transient",
        Error::Files(_) => "files",
    };
    let problems: Vec<serde_json::Value> = error
        .problems()
        .iter()
        .map(|p| {
            serde_json::json!({
                "kind": p.kind.name(),
                "path": p.path,
                "frame": p.frame,
                "pass": p.pass,
                "channel": p.channel,
                "detail": p.detail,
                "message": p.to_string(),
            })
        })
        .collect();
    let message = match error {
        Error::Usage(m) | Error::Device(m) => m.clone(),
        Error::Files(_) => error.to_string(),
    };
    serde_json::json!({
        "schema": crate::JSON_SCHEMA,
        "command": command,
        "ok": false,
        "error": {
            "exit_code": code,
            "kind": kind,
            "message": message,
            "problems": problems,
        }
    })
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
fn stop_cleanly_on_signals(command: &'static str, json: bool) {
    let json = json.then_some(command);
    // Only blur and dof take --skip-existing; another command is run again whole.
    let finish = if matches!(command, "blur" | "dof") {
        "rerun with --skip-existing to finish"
    } else {
        "run it again to finish"
    };
    let numbers = STOPPING_SIGNALS.map(|(number, _)| number);
    let Ok(mut signals) = signal_hook::iterator::Signals::new(numbers) else {
        // Without the handler the default applies: the process dies, and the next run over
        // the same outputs removes what it left.
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            STOPPING.store(true, std::sync::atomic::Ordering::SeqCst);
            // The `--json` document is this one (unless the run printed its own already):
            // claimed before the writes are stopped, whose failures the run would report.
            let json =
                json.filter(|_| !JSON_PRINTED.swap(true, std::sync::atomic::Ordering::SeqCst));
            let name = STOPPING_SIGNALS
                .iter()
                .find(|(number, _)| *number == signal)
                .map_or("a signal", |(_, name)| name);
            let abandoned = crate::io::abandon();
            let message = format!(
                "stopped by {name}: {} unfinished temporary file{} removed, frames written \
                 before are whole; {finish}",
                abandoned.temporaries,
                if abandoned.temporaries == 1 { "" } else { "s" }
            );
            say!("shutter: {message}");
            // `--json`: the error object a caller reads, as for any run that fails (an
            // outside probe: stdout was empty, and a farm's parser failed on it).
            if let Some(command) = json {
                let _ = print_json(&serde_json::json!({
                    "schema": crate::JSON_SCHEMA,
                    "command": command,
                    "ok": false,
                    "error": {
                        "exit_code": 128 + signal,
                        "kind": "interrupted",
                        "message": message,
                        "problems": [],
                    }
                }));
            }
            std::process::exit(128 + signal);
        }
    });
}

#[cfg(not(unix))]
fn stop_cleanly_on_signals(_command: &'static str, _json: bool) {}

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
        return out(&format!("{}\n", chunks.len()));
    }
    match args.chunk {
        Some(k) => match chunks.get(k) {
            Some(chunk) => out(&format!("{}\n", format_frames(chunk))),
            None => Err(Error::usage(format!(
                "--chunk {k}: the spec makes {} chunks of {size} (0 to {})",
                chunks.len(),
                chunks.len().saturating_sub(1)
            ))),
        },
        None => {
            let text: String = chunks.iter().map(|c| format_frames(c) + "\n").collect();
            out(&text)
        }
    }
}

/// Whether a `--json` document went to stdout (one per run).
static JSON_PRINTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Prints a `--json` document on stdout (see [`out`]).
/// Only the first is printed: a signal stopping the run as it ends must not add a second.
fn out_json(document: &impl serde::Serialize) -> Result<()> {
    if JSON_PRINTED.swap(true, std::sync::atomic::Ordering::SeqCst) {
        return Ok(());
    }
    print_json(document)
}

/// Prints a `--json` document, the slot claimed.
fn print_json(document: &impl serde::Serialize) -> Result<()> {
    out(&(serde_json::to_string_pretty(document).unwrap_or_default() + "\n"))
}

/// Writes `text` to stdout and flushes it, the one way every command prints its results. A
/// write that fails is an error on the write that meets it: a full disk (ENOSPC, exit 75,
/// as wherever it is found) or a reader that closed the pipe (Rust ignores SIGPIPE, so the
/// write fails with EPIPE: exit 1, an output that cannot be written).
fn out(text: &str) -> Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(stdout_error)
}

/// Writes a command's text that quotes names from files (`info`, `diff`, `vectors`, a dry
/// run's list) as [`out`] does, the control characters in each line escaped
/// (`error::printable_lines`): the guard for a name that was not escaped where it was put in.
fn out_text(text: &str) -> Result<()> {
    out(&crate::error::printable_lines(text))
}

/// A failed write or flush of stdout, as the file problem it is: what was printed there is
/// lost.
fn stdout_error(error: std::io::Error) -> Error {
    Problem::new(
        ProblemKind::of_output_error(&error),
        "standard output",
        format!("{error}: what this run printed there is lost"),
    )
    .into()
}

/// The end of every run: stdout flushed and the flush checked, so nothing printed is lost
/// without a word. A run that succeeded (`code` 0) fails with the flush's error; one that
/// failed keeps its code, and the flush's error is said too.
fn flush_stdout(code: i32) -> i32 {
    use std::io::Write;
    match std::io::stdout().lock().flush() {
        Ok(()) => code,
        Err(error) => {
            let error = stdout_error(error);
            print_error(&error);
            if code == 0 {
                error.exit_code()
            } else {
                code
            }
        }
    }
}

/// The most problems printed one by one; the rest are counted.
const MAX_PRINTED_PROBLEMS: usize = 20;

fn print_error(error: &Error) {
    print_error_of("", error);
}

/// [`print_error`] of a failed `command`, whose summary of several problems says what the
/// command left undone in its own words: blur writes no frame a problem concerns; diff
/// compares nothing when an input cannot be read (it writes no output of a run it stops).
fn print_error_of(command: &str, error: &Error) {
    match error {
        Error::Usage(message) | Error::Device(message) => say!("shutter: error: {message}"),
        Error::Files(problems) => {
            for problem in problems.iter().take(MAX_PRINTED_PROBLEMS) {
                say!("shutter: error: {problem}");
            }
            if problems.len() > MAX_PRINTED_PROBLEMS {
                say!(
                    "shutter: error: ... and {} more problems",
                    problems.len() - MAX_PRINTED_PROBLEMS
                );
            }
            if problems.len() > 1 {
                let left = match command {
                    "blur" | "dof" => {
                        "; nothing was written (every frame is checked before any is)"
                    }
                    "diff" => "; nothing was compared",
                    _ => "",
                };
                say!("shutter: {} problems found{left}", problems.len());
            }
        }
    }
}

/// The largest side `scene --size` and `bench --size` take, in pixels: a 16K frame.
pub const MAX_SIDE: usize = 16384;

/// Parses `WxH`, each side 1 to [`MAX_SIDE`].
pub fn parse_size(text: &str) -> Result<(usize, usize)> {
    let bad = || {
        Error::usage(format!(
            "bad size '{text}': use WxH, each side 1 to {MAX_SIDE} pixels, e.g. 640x360"
        ))
    };
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: usize = w.trim().parse().map_err(|_| bad())?;
    let h: usize = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
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
