//! Hostile input (issue 17): files whose headers lie about their size, streams cut short,
//! chunk tables that point several entries at one chunk, and runaway requests. Each test
//! is named after what it guards; each failed on the code before its fix.

use std::path::Path;
use std::time::{Duration, Instant};

use shutter::error::ProblemKind;
use shutter::io::exr::ExrOptions;
use shutter::io::file::FileInfo;
use shutter::io::image::ImageFormat;

use crate::support::malformed::{self, attribute_value, offset_table};
use crate::support::*;

/// Frames 1..=3 of a small colour sequence `C.####.exr` in `dir`: R, G, B of noise, A = 1.
fn colour_sequence(dir: &Path, w: usize, h: usize, options: ExrOptions) {
    for frame in 1..=3 {
        let n = w * h;
        write_exr_with(
            &dir.join(format!("C.{frame:04}.exr")),
            w,
            h,
            vec![
                ("R", noise(n, frame, 0.0, 1.0)),
                ("G", noise(n, frame + 7, 0.0, 1.0)),
                ("B", noise(n, frame + 9, 0.0, 1.0)),
                ("A", vec![1.0; n]),
            ],
            options,
        );
    }
}

/// Runs `shutter blur --algorithm none` from `input` to `dir/out/o[.####].EXT` with `extra`
/// flags; returns the output and whether anything was written.
fn copy_through(
    dir: &Path,
    input: &str,
    ext: &str,
    extra: &[&str],
) -> (std::process::Output, bool) {
    let out = dir.join("out");
    // A sequence in, a sequence out; a single file in, a single file out.
    let frames = if input.contains('#') { ".####" } else { "" };
    let pattern = format!("{}/o{frames}.{ext}", out.display());
    let mut args = vec![
        "blur",
        "--algorithm",
        "none",
        "--color",
        input,
        "-o",
        &pattern,
    ];
    args.extend_from_slice(extra);
    let o = shutter(&args);
    let wrote = std::fs::read_dir(&out).is_ok_and(|mut d| d.next().is_some());
    (o, wrote)
}

#[test]
fn threads_above_the_limit_fail_at_once() {
    // Before: --threads 5000 (or RAYON_NUM_THREADS=100000) started thousands of threads per
    // pool and a 3-frame 64×36 job did not finish in a minute.
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 16, 8, ExrOptions::default());
    let input = format!("{}/C.####.exr", dir.path().display());
    let start = Instant::now();
    let (o, wrote) = copy_through(dir.path(), &input, "exr", &["--threads", "100000"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("above the limit"), "{}", stderr(&o));
    assert!(!wrote);

    let pattern = format!("{}/out/o.####.exr", dir.path().display());
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
        .args([
            "blur",
            "--algorithm",
            "none",
            "--color",
            &input,
            "-o",
            &pattern,
        ])
        .env("RAYON_NUM_THREADS", "100000")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("RAYON_NUM_THREADS"), "{}", stderr(&o));
    // Refused before any pool starts: well under the minute the old code took. (Not a
    // timing claim: a bound on a hang.)
    assert!(start.elapsed() < Duration::from_secs(30));

    // At the floor of the limit, a run still goes through.
    let (o, wrote) = copy_through(dir.path(), &input, "exr", &["--threads", "4"]);
    assert!(o.status.success() && wrote, "{}", stderr(&o));

    // `--threads` sets the count over the variable, and `frames` runs no pool: neither is
    // refused for the variable (an outside probe: both exited 2, which broke the farm
    // scripts' chunking under a bad environment).
    let shutter_with = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
            .args(args)
            .env("RAYON_NUM_THREADS", "100000")
            .output()
            .unwrap()
    };
    let o = shutter_with(&["blur", "--color", &input, "-o", &pattern, "--threads", "2"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter_with(&["frames", "1-10", "--chunk-size", "3", "--count"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(stdout(&o).trim(), "4");
}

#[test]
fn a_frame_above_max_pixels_fails_in_preflight() {
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 64, 36, ExrOptions::default());
    let input = format!("{}/C.####.exr", dir.path().display());
    // 64 × 36 = 2304 pixels: over a limit of 2000, within one of 2304.
    let (o, wrote) = copy_through(dir.path(), &input, "exr", &["--max-pixels", "2000"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("too large") && err.contains("64x36") && err.contains("2000"),
        "{err}"
    );
    // Every frame is named, before anything is written.
    assert!(err.contains("frame 1") && err.contains("frame 3"), "{err}");
    assert!(!wrote);
    let (o, wrote) = copy_through(dir.path(), &input, "exr", &["--max-pixels", "2304"]);
    assert!(o.status.success() && wrote, "{}", stderr(&o));
}

/// `bytes`, saved as `name`, are refused from their header as `kind` with a detail holding
/// `size`, and a run over them exits 1 having written nothing.
fn refused_from_header(name: &str, bytes: Vec<u8>, kind: ProblemKind, size: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let problem = FileInfo::probe(&path).unwrap_err();
    assert_eq!(problem.kind, kind, "{problem}");
    assert!(problem.detail.contains(size), "{problem}");
    let (o, wrote) = copy_through(dir.path(), &s(&path), "png", &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!wrote);
}

#[test]
fn a_png_declaring_400_million_pixels_is_refused_from_its_header() {
    // A small PNG whose IHDR (CRC fixed) claims 20000×20000: over the default limit, so it
    // is refused without decoding.
    let png = malformed::png_declaring(20000);
    refused_from_header("big.png", png, ProblemKind::TooLarge, "20000x20000");
}

#[test]
fn a_jpeg_declaring_more_than_it_holds_is_an_error_not_invented_pixels() {
    // Before: a 776-byte JPEG whose frame header claimed 12000×12000 decoded to 144 million
    // invented pixels (4 GB, exit 0).
    let jpeg = malformed::jpeg_declaring(12000);
    refused_from_header("big.jpg", jpeg, ProblemKind::Corrupt, "12000x12000");
}

#[test]
fn a_cut_jpeg_stream_is_an_error_not_a_padded_frame() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.jpg");
    std::fs::write(&whole, malformed::image(ImageFormat::Jpeg)).unwrap();
    // The whole file reads.
    let info = FileInfo::probe(&whole).unwrap();
    assert_eq!((info.width, info.height), (16, 12));
    let bytes = std::fs::read(&whole).unwrap();
    let cut = dir.path().join("cut.jpg");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let problem = FileInfo::probe(&cut).unwrap_err();
    assert_eq!(problem.kind, ProblemKind::Corrupt, "{problem}");
    assert!(problem.detail.contains("cut short"), "{problem}");
}

/// A PNG cut short is refused from its chunks' heads before anything is written: its header
/// read fine, so `info` called it whole and a sequence wrote the frames before it and stopped
/// there (an outside probe). Cut inside its image data, and cut at its IEND alone.
#[test]
fn a_cut_png_is_refused_before_any_frame_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64u32, 48u32);
    let pixels: Vec<u8> = noise((w * h * 3) as usize, 7, 0.0, 255.0)
        .iter()
        .map(|&v| v as u8)
        .collect();
    let whole = dir.path().join("p.0001.png");
    image::save_buffer(&whole, &pixels, w, h, image::ColorType::Rgb8).unwrap();
    let bytes = std::fs::read(&whole).unwrap();
    std::fs::write(dir.path().join("p.0003.png"), &bytes).unwrap();
    for (cut, want) in [
        (bytes.len() / 2, "IDAT chunk"),
        (bytes.len() - 12, "no IEND chunk"),
    ] {
        let frame2 = dir.path().join("p.0002.png");
        std::fs::write(&frame2, &bytes[..cut]).unwrap();
        let info = shutter(&["info", &s(&frame2)]);
        assert_eq!(info.status.code(), Some(1), "{}", stderr(&info));
        assert!(stderr(&info).contains(want), "{}", stderr(&info));
        let out = dir.path().join("out");
        let o = shutter(&[
            "blur",
            "--algorithm",
            "none",
            "--color",
            &s(&dir.path().join("p.####.png")),
            "-o",
            &s(&out.join("o.####.png")),
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("p.0002.png, frame 2") && err.contains("truncated"),
            "{err}"
        );
        assert!(!out.exists(), "frames were written before the cut one");
    }
}

/// What the numeric policy replaced is named by the pass's kind and file: a painted CoC map's
/// negative values were warned about as "depth values NaN or negative read as far or 0", with
/// no file (an outside probe); a map's NaN is in focus, not far.
#[test]
fn replaced_values_are_named_by_their_pass_and_file() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 12);
    let n = w * h;
    let grey = vec![0.3; n];
    let mut z = vec![3.0; n];
    z[5] = f32::NAN;
    let colour = dir.path().join("c.exr");
    write_exr(
        &colour,
        w,
        h,
        vec![
            ("R", grey.clone()),
            ("G", grey.clone()),
            ("B", grey),
            ("Z", z),
        ],
    );
    let map = dir.path().join("map.exr");
    write_exr(&map, w, h, vec![("Y", vec![-1.0; n])]);
    let out = dir.path().join("out.exr");
    let o = shutter(&[
        "dof",
        "--color",
        &s(&colour),
        "--coc-map",
        &s(&map),
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("CoC map values NaN or negative read as 0 (in focus) in")
            && err.contains("map.exr")
            && !err.contains("depth values"),
        "{err}"
    );
    let lens = LENS_ARGS;
    let (colour, out) = (s(&colour), s(&out));
    let mut args = vec!["dof", "--color", &colour, "-o", &out];
    args.extend(lens);
    let o = shutter(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("depth values NaN read as far, negative as 0 in") && err.contains("c.exr"),
        "{err}"
    );
}

#[test]
fn an_offset_table_pointing_every_line_at_one_chunk_is_an_error_not_black_lines() {
    // Before: every entry of the table pointing at the first chunk read as a frame whose
    // other lines were black, with exit 0.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 12);
    let uncompressed = ExrOptions {
        compression: exr::compression::Compression::Uncompressed,
        half: false,
    };
    colour_sequence(dir.path(), w, h, uncompressed);
    let path = dir.path().join("C.0002.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    // One scan line per chunk without compression.
    let table = offset_table(&bytes, h);
    let first: [u8; 8] = bytes[table..table + 8].try_into().unwrap();
    for k in 1..h {
        bytes[table + 8 * k..table + 8 * k + 8].copy_from_slice(&first);
    }
    std::fs::write(&path, &bytes).unwrap();
    let problem = FileInfo::probe(&path).unwrap_err();
    assert_eq!(problem.kind, ProblemKind::Corrupt, "{problem}");
    assert!(problem.detail.contains("already holds"), "{problem}");
    // The run stops in preflight, naming frame 2, before frame 1 is written.
    let (o, wrote) = copy_through(
        dir.path(),
        &format!("{}/C.####.exr", dir.path().display()),
        "exr",
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("frame 2"), "{}", stderr(&o));
    assert!(!wrote);
}

#[test]
fn a_chunk_outside_the_data_window_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 12);
    let uncompressed = ExrOptions {
        compression: exr::compression::Compression::Uncompressed,
        half: false,
    };
    colour_sequence(dir.path(), w, h, uncompressed);
    let path = dir.path().join("C.0001.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    let table = offset_table(&bytes, h);
    // The last chunk: its first 4 bytes are its line's y; move it far below the window.
    let last = u64::from_le_bytes(
        bytes[table + 8 * (h - 1)..table + 8 * h]
            .try_into()
            .unwrap(),
    ) as usize;
    bytes[last..last + 4].copy_from_slice(&1000i32.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let problem = FileInfo::probe(&path).unwrap_err();
    assert_eq!(problem.kind, ProblemKind::Corrupt, "{problem}");
    assert!(problem.detail.contains("line 1000"), "{problem}");
    // Untouched files of every layout still pass: the check has no false alarms there.
    for frame in [2, 3] {
        FileInfo::probe(&dir.path().join(format!("C.{frame:04}.exr"))).unwrap();
    }
}

/// The warnings of a run's JSON summary.
fn json_warnings(o: &std::process::Output) -> Vec<String> {
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("a JSON summary");
    report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn flags_the_output_format_cannot_use_are_warned_about() {
    // Before: --bit-depth 16 with a .jpg, --half with a .png and --layer matching nothing
    // were dropped in silence.
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 16, 8, ExrOptions::default());
    let input = format!("{}/C.####.exr", dir.path().display());
    let cases: [(&str, &[&str], &str); 5] = [
        ("jpg", &["--bit-depth", "16"], "JPEG is always 8-bit"),
        (
            "png",
            &["--jpeg-quality", "80"],
            "--jpeg-quality applies to JPEG output",
        ),
        ("png", &["--half"], "--half applies to EXR output"),
        (
            "tif",
            &["--compression", "piz"],
            "--compression applies to EXR output",
        ),
        (
            "exr",
            &["--layer", "nothing"],
            "--layer nothing: preset shutter names no channel",
        ),
    ];
    for (ext, flags, expected) in cases {
        let mut extra = flags.to_vec();
        extra.push("--json");
        let (o, wrote) = copy_through(dir.path(), &input, ext, &extra);
        assert!(o.status.success() && wrote, "{}", stderr(&o));
        let warnings = json_warnings(&o);
        assert!(
            warnings.iter().any(|w| w.contains(expected)),
            "{ext} {flags:?}: {warnings:?}"
        );
    }
    // The same flags where they apply: no warning.
    let (o, _) = copy_through(dir.path(), &input, "png", &["--bit-depth", "16", "--json"]);
    assert!(json_warnings(&o).is_empty(), "{:?}", json_warnings(&o));
}

/// A preset over the defaults that lists no velocity channel (`[velocity] channels = []`):
/// the run needs vectors, and the problem says the preset lists none, where it said a
/// channel of no name was not in the file ("channel : not in the file").
#[test]
fn a_preset_listing_no_channels_for_a_pass_it_needs_says_so() {
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 16, 8, ExrOptions::default());
    let preset = dir.path().join("novectors.toml");
    std::fs::write(&preset, "[velocity]\nchannels = []\n").unwrap();
    let input = format!("{}/C.####.exr", dir.path().display());
    let out = dir.path().join("out");
    let pattern = format!("{}/o.####.exr", out.display());
    let (preset, algorithm) = (s(&preset), "reconstruct");
    let o = shutter(&[
        "blur",
        "--algorithm",
        algorithm,
        "--preset",
        &preset,
        "--color",
        &input,
        "-o",
        &pattern,
    ]);
    let wrote = std::fs::read_dir(&out).is_ok_and(|mut d| d.next().is_some());
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("velocity pass: preset")
            && err.contains("lists no channels for this pass ([velocity] channels is empty)"),
        "{err}"
    );
    assert!(!err.contains("channel :"), "{err}");
    assert!(!wrote);
}

#[test]
fn a_depth_channel_the_colour_pass_reads_is_said_to_be_taken_not_missing() {
    // Before: "channel Z …: not in the file …; the file has A, B, G, R, Z".
    let dir = tempfile::tempdir().unwrap();
    let n = 16 * 8;
    write_exr_with(
        &dir.path().join("C.0001.exr"),
        16,
        8,
        vec![
            ("R", noise(n, 1, 0.0, 1.0)),
            ("G", noise(n, 2, 0.0, 1.0)),
            ("B", noise(n, 3, 0.0, 1.0)),
            ("Z", vec![2.0; n]),
        ],
        ExrOptions::default(),
    );
    let preset = dir.path().join("zgrey.toml");
    std::fs::write(&preset, "[color]\nchannels = [[\"Z\", \"Z\", \"Z\"]]\n").unwrap();
    let input = format!("{}/C.####.exr", dir.path().display());
    let out = dir.path().join("out");
    let pattern = format!("{}/o.####.exr", out.display());
    let preset = s(&preset);
    let o = shutter(&[
        "dof",
        "--preset",
        &preset,
        "--color",
        &input,
        "--f-stop",
        "2",
        "--focal-length",
        "50",
        "--focus-distance",
        "3",
        "-o",
        &pattern,
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("depth pass")
            && err.contains("Z is in the file, but preset")
            && err.contains("[color] channels read it as colour"),
        "{err}"
    );
    assert!(!err.contains("not in the file"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_preset_without_colour_channels_is_a_preset_error() {
    // Before: `[color] channels = []` failed per frame as "channel : not in the file".
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 16, 8, ExrOptions::default());
    let preset = dir.path().join("empty.toml");
    std::fs::write(
        &preset,
        "[color]\nchannels = []\n[depth]\nchannels = [\"Z\"]\n\
         [velocity]\nchannels = []\nmeaning = \"velocity\"\n\
         [prev]\nchannels = []\nmeaning = \"prev_position\"\n\
         [next]\nchannels = []\nmeaning = \"next_position\"\n",
    )
    .unwrap();
    let input = format!("{}/C.####.exr", dir.path().display());
    let (o, wrote) = copy_through(dir.path(), &input, "exr", &["--preset", &s(&preset)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("[color] channels is empty"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!wrote);
}

#[test]
fn headers_decoding_would_refuse_stop_the_run_before_any_frame_is_written() {
    // Before: preflight read attributes leniently and did not validate, so frame 1 was
    // written and the run failed at frame 2's decoding.
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 16, 8, ExrOptions::default());
    // Frame 2: a line order out of range.
    let two = dir.path().join("C.0002.exr");
    let mut bytes = std::fs::read(&two).unwrap();
    let at = attribute_value(&bytes, "lineOrder", "lineOrder");
    bytes[at] = 7;
    std::fs::write(&two, &bytes).unwrap();
    // Frame 3: channels A, B, G, R listed as R, B, G, A (all there, not sorted).
    let three = dir.path().join("C.0003.exr");
    let mut bytes = std::fs::read(&three).unwrap();
    let list = attribute_value(&bytes, "channels", "chlist");
    // Each entry: name, NUL, 16 bytes; the names are one letter each.
    assert_eq!((bytes[list], bytes[list + 18 * 3]), (b'A', b'R'));
    bytes.swap(list, list + 18 * 3);
    std::fs::write(&three, &bytes).unwrap();

    let (o, wrote) = copy_through(
        dir.path(),
        &format!("{}/C.####.exr", dir.path().display()),
        "exr",
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("frame 2") && err.contains("line order"),
        "{err}"
    );
    assert!(
        err.contains("frame 3") && err.contains("not sorted"),
        "{err}"
    );
    assert!(
        !wrote,
        "frame 1 was written before the bad frames were found"
    );

    // `shutter info` reports the same problems, with exit 1.
    for path in [&two, &three] {
        let o = shutter(&["info", &s(path)]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    }
    let o = shutter(&["info", &s(&dir.path().join("C.0001.exr"))]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn an_inverted_data_window_is_an_error_not_a_size() {
    // Before: `shutter info` printed an inverted data window as if it were valid.
    let dir = tempfile::tempdir().unwrap();
    colour_sequence(dir.path(), 16, 8, ExrOptions::default());
    let path = dir.path().join("C.0001.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    let at = attribute_value(&bytes, "dataWindow", "box2i");
    // xMin, yMin, xMax, yMax: make xMin larger than xMax.
    bytes[at..at + 4].copy_from_slice(&100i32.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let o = shutter(&["info", &s(&path)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!stdout(&o).contains("size:"), "{}", stdout(&o));
}

#[test]
fn a_colour_problem_is_reported_once_not_as_size_mismatches() {
    // Before: a colour header problem also gave "size mismatch … color pass is 0x0" for
    // every other pass.
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 16, 8);
    std::fs::write(dir.path().join("C.exr"), b"not an image at all").unwrap();
    let o = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--depth",
        &s(&dir.path().join("Z.exr")),
        "--velocity",
        &s(&dir.path().join("V.exr")),
        "-o",
        &s(&dir.path().join("out/o.exr")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(!err.contains("size mismatch"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn coc_map_problems_name_the_coc_map() {
    // Before: a missing or broken --coc-map was reported as the "depth pass".
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 16, 8);
    let o = shutter(&[
        "dof",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--coc-map",
        &s(&dir.path().join("missing.exr")),
        "-o",
        &s(&dir.path().join("out/o.exr")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("coc-map pass") && !err.contains("depth pass"),
        "{err}"
    );
}

#[test]
fn every_malformed_file_fails_with_a_message_and_writes_nothing() {
    // The corpus in fixtures/malformed: each file named after its one defect. Its only
    // promise: never a panic, never a frame written (partial or whole), exit 1 and one
    // message naming the file.
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/malformed");
    let corpus = malformed::corpus();
    if std::env::var_os("SHUTTER_BLESS").is_some() {
        std::fs::create_dir_all(&folder).unwrap();
        for (name, bytes) in &corpus {
            std::fs::write(folder.join(name), bytes).unwrap();
        }
    }
    let mut files: Vec<_> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    // Every defect made has its file.
    for (name, _) in &corpus {
        assert!(
            folder.join(name).exists(),
            "{name} missing: SHUTTER_BLESS=1"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    for file in files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let out = dir.path().join(&name);
        let o = shutter(&[
            "blur",
            "--algorithm",
            "none",
            "--color",
            &s(&file),
            "-o",
            &s(&out.join("o.exr")),
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        let first = err.lines().next().unwrap_or("");
        assert!(
            first.starts_with("shutter: error: ") && first.contains(&name),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name}: something was written");
    }
}

#[test]
fn none_and_in_focus_depth_of_field_write_finite_frames_and_count_what_they_replaced() {
    // The probe found NaN and ±Inf written unchanged by `--algorithm none` and by depth of
    // field on a frame that is all in focus: one policy now covers every written frame.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 8);
    let n = w * h;
    let mut r = noise(n, 1, 0.0, 1.0);
    r[3] = f32::NAN;
    r[4] = f32::INFINITY;
    r[5] = f32::NEG_INFINITY;
    write_exr(
        &dir.path().join("C.exr"),
        w,
        h,
        vec![("R", r), ("G", vec![0.5; n]), ("B", vec![0.5; n])],
    );
    // Everything at the focus distance: the frame is in focus, depth of field returns it.
    write_exr(&dir.path().join("Z.exr"), w, h, vec![("Z", vec![3.0; n])]);
    let colour = s(&dir.path().join("C.exr"));
    let depth = s(&dir.path().join("Z.exr"));
    let runs: [(&str, Vec<&str>); 2] = [
        (
            "none",
            vec!["blur", "--algorithm", "none", "--color", &colour],
        ),
        (
            "in focus",
            [
                &["dof", "--color", &colour, "--depth", &depth][..],
                &LENS_ARGS,
            ]
            .concat(),
        ),
    ];
    for (what, mut args) in runs {
        let out = dir.path().join(format!("{}.exr", what.replace(' ', "-")));
        let out = s(&out);
        args.extend(["-o", &out, "--json"]);
        let o = shutter(&args);
        assert!(o.status.success(), "{what}: {}", stderr(&o));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(report["replaced"]["color"], 3, "{what}: {report}");
        assert!(
            json_warnings(&o)
                .iter()
                .any(|w| w.contains("colour values NaN")),
            "{what}: {report}"
        );
        let written = read_exr_reference(Path::new(&out));
        let red = channel(&written, "R");
        assert!(red.iter().all(|v| v.is_finite()), "{what}: {:?}", &red[..8]);
        // NaN reads as 0; infinities are clamped to ±1e30.
        assert_eq!((red[3], red[4], red[5]), (0.0, 1e30, -1e30), "{what}");
    }
}

/// Valid files of kinds the decoders do not read are "not supported", with what to do, not
/// "corrupt" with a decoder's text (issue 30): a 12-bit JPEG and an arithmetic-coded one
/// (a baseline JPEG's frame header changed to say so, as such files carry it), a TIFF
/// of 32-bit integers, and a YCbCr and an indexed-colour TIFF, which say what to do.
#[test]
fn unsupported_kinds_of_valid_files_are_told_from_damaged_ones() {
    let dir = tempfile::tempdir().unwrap();
    let baseline = dir.path().join("baseline.jpg");
    image::RgbImage::from_pixel(16, 16, image::Rgb([90, 120, 200]))
        .save(&baseline)
        .unwrap();
    let bytes = std::fs::read(&baseline).unwrap();
    let sof = bytes
        .windows(2)
        .position(|w| w == [0xFF, 0xC0])
        .expect("a baseline frame header");
    let mut twelve = bytes.clone();
    (twelve[sof + 1], twelve[sof + 4]) = (0xC1, 12);
    let mut arithmetic = bytes.clone();
    arithmetic[sof + 1] = 0xC9;
    let tiff = dir.path().join("u32.tif");
    {
        let file = std::fs::File::create(&tiff).unwrap();
        let mut encoder = tiff::encoder::TiffEncoder::new(file).unwrap();
        encoder
            .write_image::<tiff::encoder::colortype::RGB32>(4, 4, &[7u32; 48])
            .unwrap();
    }
    // An RGB TIFF told to be YCbCr (as a JPEG-compressed TIFF is) or indexed colour, by its
    // PhotometricInterpretation (tag 262, SHORT, one value: 2 is RGB).
    let rgb_tiff = {
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut encoder = tiff::encoder::TiffEncoder::new(&mut bytes).unwrap();
        encoder
            .write_image::<tiff::encoder::colortype::RGB8>(4, 4, &[90u8; 48])
            .unwrap();
        bytes.into_inner()
    };
    let photometric = |value: u8| {
        let entry = [0x06, 0x01, 0x03, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02, 0x00];
        let at = (rgb_tiff.windows(10))
            .position(|w| w == entry)
            .expect("an RGB PhotometricInterpretation");
        let mut bytes = rgb_tiff.clone();
        bytes[at + 8] = value;
        bytes
    };
    for (name, bytes, why) in [
        ("ycbcr.tif", Some(photometric(6)), "a YCbCr TIFF"),
        (
            "palette.tif",
            Some(photometric(3)),
            "an indexed-colour (palette) TIFF",
        ),
        ("twelve.jpg", Some(twelve), "a 12-bit JPEG"),
        (
            "arithmetic.jpg",
            Some(arithmetic),
            "an arithmetic-coded JPEG",
        ),
        ("u32.tif", None, "Unhandled TIFF sample format"),
    ] {
        let path = dir.path().join(name);
        if let Some(bytes) = bytes {
            std::fs::write(&path, bytes).unwrap();
        }
        let problem = FileInfo::probe(&path).unwrap_err();
        assert_eq!(problem.kind, ProblemKind::Unsupported, "{name}: {problem}");
        assert!(problem.to_string().contains(why), "{name}: {problem}");
    }
    // The files they were made from are read.
    assert!(FileInfo::probe(&baseline).is_ok());
    let rgb = dir.path().join("rgb.tif");
    std::fs::write(&rgb, &rgb_tiff).unwrap();
    assert!(FileInfo::probe(&rgb).is_ok());
}

/// A zlib stream of `n` zero bytes, written by hand (fixed Huffman codes: a literal 0, then
/// copies of 258 bytes at distance 1) so a test can make a gigabyte's worth in a few MB.
fn zlib_of_zeros(n: usize) -> Vec<u8> {
    struct Bits {
        out: Vec<u8>,
        acc: u64,
        count: u32,
    }
    impl Bits {
        fn put(&mut self, value: u64, bits: u32) {
            self.acc |= value << self.count;
            self.count += bits;
            while self.count >= 8 {
                self.out.push(self.acc as u8);
                self.acc >>= 8;
                self.count -= 8;
            }
        }
        /// A Huffman code, most significant bit first.
        fn code(&mut self, code: u64, bits: u32) {
            let reversed = (0..bits).fold(0, |r, i| r | ((code >> i) & 1) << (bits - 1 - i));
            self.put(reversed, bits);
        }
    }
    let mut bits = Bits {
        out: vec![0x78, 0x01],
        acc: 0,
        count: 0,
    };
    bits.put(1, 1); // final block
    bits.put(1, 2); // fixed Huffman codes
    bits.code(0x30, 8); // literal 0
    let mut left = n - 1;
    while left >= 258 {
        bits.code(0b1100_0101, 8); // length 258 (code 285)
        bits.code(0, 5); // distance 1
        left -= 258;
    }
    for _ in 0..left {
        bits.code(0x30, 8);
    }
    bits.code(0, 7); // end of block (code 256)
    bits.put(0, 7);
    let mut out = bits.out;
    let adler = ((n % 65521) as u32) << 16 | 1;
    out.extend(adler.to_be_bytes());
    out
}

/// A PNG whose colour-profile chunk inflates to 1 GB (issue 30): the profile is capped before
/// it is inflated, so opening it costs what any small PNG does (peak RSS under 200 MB, of
/// which the program is most; it was 530 MB), and the picture is read.
#[test]
fn a_profile_that_inflates_to_a_gigabyte_is_not_inflated() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bomb.png");
    {
        let file = std::fs::File::create(&path).unwrap();
        let mut encoder = png::Encoder::new(file, 8, 8);
        encoder.set_color(png::ColorType::Rgb);
        let mut writer = encoder.write_header().unwrap();
        let mut iccp = b"bomb\0\0".to_vec();
        iccp.extend(zlib_of_zeros(1 << 30));
        writer
            .write_chunk(png::chunk::ChunkType(*b"iCCP"), &iccp)
            .unwrap();
        writer.write_image_data(&[128u8; 8 * 8 * 3]).unwrap();
    }
    let out = dir.path().join("out.png");
    let o = shutter(&["blur", "--color", &s(&path), "-o", &s(&out), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    if let Some(peak) = report["peak_rss_mib"].as_f64() {
        assert!(peak < 200.0, "peak RSS {peak} MiB");
    }
}

/// A 550 KB PNG declaring 12000×12000 (within the pixel limit) needs gigabytes decoded
/// (issue 30): under a 2 GB address-space cap the run is refused in the preflight with exit 1
/// and the figures, nothing left behind; before, the allocation failed mid-run and the
/// process aborted, leaving its temporary file and lock.
#[cfg(unix)]
#[test]
fn a_frame_that_would_not_fit_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.png");
    {
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut encoder = png::Encoder::new(file, 12000, 12000);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().unwrap();
        let mut stream = writer.stream_writer().unwrap();
        let row = vec![0u8; 12000 * 4];
        for _ in 0..12000 {
            std::io::Write::write_all(&mut stream, &row).unwrap();
        }
        stream.finish().unwrap();
    }
    let out_dir = dir.path().join("out");
    let out = format!("{}/o.png", out_dir.display());
    let o = shutter_capped(2_000_000, &["blur", "--color", &s(&path), "-o", &out]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("too large") && err.contains("max-memory allows"),
        "{err}"
    );
    assert!(!out_dir.exists(), "the output folder was made");
    // Given the memory, the same limit written out refuses it too, whatever the machine.
    let o = shutter(&[
        "blur",
        "--color",
        &s(&path),
        "-o",
        &s(&out_dir.join("o.png")),
        "--max-memory",
        "1024",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("over the 1024 MiB max-memory allows"),
        "{}",
        stderr(&o)
    );
}

/// A backend that may run on a GPU needs more memory on the host (the driver's side, and
/// with a software driver its device memory and shader compiler: lavapipe's 1080p runs peak
/// at 3–4 times the CPU's): the same small frame fits 200 MiB on the CPU, and is refused
/// there with `--backend wgpu`, in the preflight, before any GPU is looked for.
#[cfg(feature = "gpu")]
#[test]
fn a_gpu_backend_is_counted_in_the_memory_a_run_needs() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 8);
    let color = s(&dir.path().join("C.exr"));
    let out = s(&dir.path().join("o.exr"));
    let run = |backend: &str| {
        shutter(&[
            "blur",
            "--color",
            &color,
            "-o",
            &out,
            "--max-memory",
            "200",
            "--backend",
            backend,
        ])
    };
    let o = run("cpu");
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run("wgpu");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("max-memory allows"), "{}", stderr(&o));
}

/// Stretch holds a second copy of the light layers (packed, its input and output side by
/// side): the preflight counts it, and counts it for stretch alone. A 512×512 frame with ten
/// RGB layers (30 planes of 1 MiB) needs 30 MiB more through stretch than through
/// reconstruct.
#[test]
fn stretch_counts_its_copy_of_the_light_layers_in_the_memory_a_run_needs() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (512, 512);
    let n = w * h;
    let mut channels: Vec<(String, Vec<f32>)> = ["R", "G", "B", "A", "Z"]
        .iter()
        .map(|c| (c.to_string(), vec![1.0; n]))
        .collect();
    channels.push(("velocity.X".into(), vec![4.0; n]));
    channels.push(("velocity.Y".into(), vec![0.0; n]));
    for k in 0..10 {
        for c in ["R", "G", "B"] {
            channels.push((format!("light{k}.{c}"), vec![0.5; n]));
        }
    }
    let path = dir.path().join("layered.exr");
    let channels = channels
        .iter()
        .map(|(n, p)| (n.as_str(), p.clone()))
        .collect();
    crate::support::write_exr(&path, w, h, channels);
    let needs = |algorithm: &str| -> u64 {
        let (c, o) = (s(&path), s(&dir.path().join("o.exr")));
        estimate_mib(&["blur", "--algorithm", algorithm, "--color", &c, "-o", &o])
    };
    assert_eq!(needs("stretch") - needs("reconstruct"), 30);
}

/// Memory the system refuses for a frame's planes (an 8000×8000 frame under a 600 MB
/// address-space cap, with `--max-memory` letting the preflight pass) is "too large" (exit 1)
/// with what to do, not a "corrupt file": the file is fine.
#[cfg(unix)]
#[test]
fn memory_the_system_refuses_is_too_large_not_corrupt() {
    use exr::prelude::{f16, Image, SpecificChannels, WritableImage};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.exr");
    let zero = f16::from_f32(0.0);
    Image::from_channels((8000, 8000), SpecificChannels::rgb(|_| (zero, zero, zero)))
        .write()
        .to_file(&path)
        .unwrap();
    let out = s(&dir.path().join("o.exr"));
    let args = [
        "blur",
        "--max-memory",
        "100000",
        "--color",
        &s(&path),
        "-o",
        &out,
    ];
    let o = shutter_capped(600_000, &[&args[..], &["--json"]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let text = report.to_string();
    assert!(text.contains("\"too_large\""), "{text}");
    assert!(!text.contains("\"corrupt\""), "{text}");
}

/// Under an address-space limit (`ulimit -v`, as SGE's `h_vmem` sets it) of 300 MB, the
/// default `max-memory` leaves room for a small frame, which runs: the room kept for the
/// program (768 MiB) was taken whole from any limit, so every job under 1.2 GB was refused
/// ("over the 0 MiB max-memory allows"). Under a limit too tight for the frame, the message
/// names the limit that set the default.
#[cfg(unix)]
#[test]
fn a_small_frame_runs_under_a_tight_address_space_limit_and_a_refusal_names_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 48);
    let n = w * h;
    let color = dir.path().join("color.exr");
    write_exr(
        &color,
        w,
        h,
        vec![
            ("R", noise(n, 1, 0.0, 1.0)),
            ("G", noise(n, 2, 0.0, 1.0)),
            ("B", noise(n, 3, 0.0, 1.0)),
            ("Z", vec![3.0; n]),
            ("velocity.X", vec![4.0; n]),
            ("velocity.Y", vec![0.0; n]),
        ],
    );
    let out = s(&dir.path().join("o.exr"));
    let args = [
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&color),
        "-o",
        &out,
    ];
    let o = shutter_capped(300_000, &args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter_capped(120_000, &args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("too large") && err.contains("address-space limit (ulimit -v)"),
        "{err}"
    );
}

/// The preflight counts what the bokeh gather holds besides the frames (its padded planes and
/// prefilter levels: 1.5× the decoded planes) and each thread's own memory (3 MiB a thread):
/// an outside tester's 4K gather peaked at 1.38× the estimate, 1.83× with 64 threads.
#[test]
fn the_memory_estimate_counts_the_gathers_planes_and_every_thread() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (512, 512);
    let n = w * h;
    let path = dir.path().join("c.exr");
    // Four float planes of 512 × 512: 4 MiB decoded.
    let channels = vec![
        ("R", vec![0.5; n]),
        ("G", vec![0.5; n]),
        ("B", vec![0.5; n]),
        ("Z", vec![9.0; n]),
    ];
    crate::support::write_exr(&path, w, h, channels);
    let needs = |method: &str, threads: &str| -> u64 {
        let mut args = vec!["dof", "--method", method, "--threads", threads];
        let (c, o) = (s(&path), s(&dir.path().join("o.exr")));
        args.extend(["--color", &c, "-o", &o]);
        args.extend(LENS_ARGS);
        estimate_mib(&args)
    };
    assert_eq!(needs("gather", "2") - needs("blend", "2"), 6);
    assert_eq!(needs("blend", "10") - needs("blend", "2"), 24);
}

/// The memory the preflight says a run of `args` needs, in MiB: the run made to stop there
/// with `--max-memory 64`.
fn estimate_mib(args: &[&str]) -> u64 {
    let run = shutter(&[args, &["--max-memory", "64"]].concat());
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    let at = err.find("needs about ").expect("the estimate") + "needs about ".len();
    err[at..].split(' ').next().unwrap().parse().unwrap()
}

/// A channel named with an ESC sequence, a quote and a newline (an outside tester's
/// `Z"\x1b[31m\n`): `info` printed it raw, colouring the terminal and breaking the table's
/// line, where it escapes values; a missing-channel error quoting the file's channels printed
/// it raw too. Both now show it escaped as values are, each on one line; JSON carries the name
/// itself.
#[test]
fn a_channel_name_with_control_characters_is_printed_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ctl.exr");
    let hostile = "Z\"\u{1b}[31m\n";
    write_exr(
        &path,
        4,
        2,
        vec![
            ("R", vec![0.5; 8]),
            ("G", vec![0.5; 8]),
            ("B", vec![0.5; 8]),
            (hostile, vec![1.0; 8]),
        ],
    );
    let o = shutter(&["info", &s(&path)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        !text.contains('\u{1b}'),
        "an ESC reached the terminal:\n{text}"
    );
    let line = (text.lines().find(|l| l.trim_start().starts_with("Z\"")))
        .unwrap_or_else(|| panic!("no line for the channel:\n{text}"));
    assert!(
        line.contains("Z\"\\u{1b}[31m\\n") && line.contains("f32"),
        "{line}"
    );

    let o = shutter(&["info", &s(&path), "--json"]);
    let document: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let names: Vec<&str> = (document["files"][0]["channels"].as_array().unwrap().iter())
        .filter_map(|c| c["name"].as_str())
        .collect();
    assert!(names.contains(&hostile), "{names:?}");

    let out = dir.path().join("o.exr");
    let o = shutter(&[
        "blur",
        "--color",
        &s(&path),
        "-o",
        &s(&out),
        "--algorithm",
        "reconstruct",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        !err.contains('\u{1b}'),
        "an ESC reached the terminal:\n{err}"
    );
    assert!(err.contains("Z\"\\u{1b}[31m\\n"), "{err}");
    assert!(
        err.lines().all(|l| l.starts_with("shutter: ")),
        "a line was broken:\n{err}"
    );
}

/// A TIFF cut short said "failed to fill whole buffer" (the standard library's words for a
/// read past the end), where a cut PNG, JPEG or EXR says it is truncated (an outside
/// tester's deflate TIFF). Both cuts: one through the image data after the header (a
/// deflated strip, the directory first), one through the directory a writer put after the
/// data (the tiff crate's LZW).
#[test]
fn a_truncated_tiff_is_named_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u16, 32u16);
    let pixels: Vec<u8> = (noise(w as usize * h as usize * 3, 5, 0.0, 255.0).iter())
        .map(|&v| v as u8)
        .collect();
    // Little-endian TIFF, its directory at byte 8 and the deflated strip after it.
    let strip = miniz_oxide::deflate::compress_to_vec_zlib(&pixels, 6);
    let (bits_at, data_at) = (8 + 2 + 10 * 12 + 4, 8 + 2 + 10 * 12 + 4 + 6);
    let mut deflated = b"II*\0\x08\0\0\0".to_vec();
    deflated.extend(10u16.to_le_bytes());
    let short = |tag: u16, count: u32, value: u32| (tag, 3u16, count, value);
    for (tag, kind, count, value) in [
        short(256, 1, w.into()),
        short(257, 1, h.into()),
        short(258, 3, bits_at as u32),
        short(259, 1, 8),
        short(262, 1, 2),
        (273, 4, 1, data_at as u32),
        short(277, 1, 3),
        short(278, 1, h.into()),
        (279, 4, 1, strip.len() as u32),
        short(284, 1, 1),
    ] {
        deflated.extend(tag.to_le_bytes());
        deflated.extend(kind.to_le_bytes());
        deflated.extend(count.to_le_bytes());
        deflated.extend(value.to_le_bytes());
    }
    deflated.extend(0u32.to_le_bytes());
    deflated.extend([8, 0, 8, 0, 8, 0]);
    assert_eq!(deflated.len(), data_at);
    deflated.extend(&strip);
    let mut lzw = std::io::Cursor::new(Vec::new());
    (tiff::encoder::TiffEncoder::new(&mut lzw).unwrap())
        .with_compression(tiff::encoder::Compression::Lzw)
        .write_image::<tiff::encoder::colortype::RGB8>(w.into(), h.into(), &pixels)
        .unwrap();
    let lzw = lzw.into_inner();
    for (name, bytes) in [("deflated.tif", deflated), ("lzw.tif", lzw)] {
        // Whole, it is read.
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        let out = dir.path().join("o.png");
        let blur = |path: &std::path::Path| {
            let args = [
                "blur",
                "--color",
                &s(path),
                "-o",
                &s(&out),
                "--algorithm",
                "none",
            ];
            shutter(&args)
        };
        let o = blur(&path);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        std::fs::remove_file(&out).unwrap();
        let cut = dir.path().join(format!("cut_{name}"));
        std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
        let info = shutter(&["info", &s(&cut)]);
        let o = blur(&cut);
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        for err in [stderr(&o), stderr(&info)].iter().filter(|e| !e.is_empty()) {
            assert!(
                err.contains(&format!("cut_{name}")) && err.contains("truncated"),
                "{name}: {err}"
            );
            assert!(!err.contains("fill whole buffer"), "{name}: {err}");
        }
        assert!(!out.exists(), "{name}: written from a cut file");
    }
}
