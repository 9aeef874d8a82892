//! Every setting's one definition (`shutter::settings::DEFS`) against what users read: the
//! help text, `shutter presets keys`, the built-in defaults preset and the README; and where an
//! invalid value is reported from.

use shutter::settings::{Section, Value, DEFS};

use crate::support::*;

#[test]
fn blur_help_states_every_default_and_preset_key_from_the_definitions() {
    for command in ["blur", "dof"] {
        let help = stdout(&shutter(&[command, "--help"]));
        for def in DEFS {
            let line = help
                .lines()
                .find(|l| l.trim_start().starts_with(&format!("--{} ", def.flag())))
                .unwrap_or_else(|| panic!("no --{} in `{command} --help`", def.flag()));
            let stated = format!(
                "[default: {}; preset key {}.{}]",
                def.default_text(),
                def.section.table(),
                def.key()
            );
            assert!(line.ends_with(&stated), "{line}\nshould end with {stated}");
        }
        // The scatter defaults the help once got wrong.
        for (flag, default) in [("weight", "box"), ("normalize", "exposure")] {
            let line = help
                .lines()
                .find(|l| l.trim_start().starts_with(&format!("--{flag} ")))
                .unwrap();
            assert!(line.contains(&format!("[default: {default};")), "{line}");
        }
    }
}

#[test]
fn presets_keys_lists_every_key_with_its_default() {
    let o = shutter(&["presets", "keys"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for def in DEFS {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(def.key().as_str()))
            .unwrap_or_else(|| panic!("no {} in `presets keys`", def.key()));
        let words: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(words[1], format!("--{}", def.flag()), "{line}");
        assert_eq!(
            words[2..4],
            ["default", def.default_text().split(' ').next().unwrap()]
        );
    }
}

#[test]
fn the_defaults_preset_sets_no_setting_of_its_own() {
    // Defaults live in the parameter structs; a copy in presets/shutter.toml could drift.
    let preset = shutter::io::preset::Preset::builtin("shutter").unwrap();
    for section in Section::ALL {
        assert!(preset.settings(section).is_empty(), "{section:?}");
    }
}

#[test]
fn readme_settings_tables_match_the_definitions() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let text = std::fs::read_to_string(&path).unwrap();
    let expected = shutter::settings::readme_with_tables(&text).expect("README has the markers");
    if std::env::var_os("SHUTTER_BLESS").is_some() {
        std::fs::write(&path, &expected).unwrap();
        return;
    }
    assert!(
        text == expected,
        "README.md's settings tables differ from src/settings/: run \
         `SHUTTER_BLESS=1 cargo test readme` and review the diff"
    );
    // Every setting has its row.
    for def in DEFS {
        assert!(
            text.contains(&format!("| `{}` |", def.key())),
            "{}",
            def.key()
        );
    }
}

/// `shutter blur` on the canonical frame written in `dir` (as `write_canonical_frame` names
/// its files), run from `dir`, writing `out.exr`, with `extra` flags.
fn blur_canonical_frame(dir: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let passes = [
        "--color",
        "C.exr",
        "--depth",
        "Z.exr",
        "--velocity",
        "V.exr",
    ];
    std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
        .current_dir(dir)
        .arg("blur")
        .args(passes)
        .args(["-o", "out.exr"])
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn an_invalid_value_names_the_flag_or_the_preset_key_it_came_from() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 6);
    let run = |extra: &[&str]| {
        let o = blur_canonical_frame(dir.path(), extra);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(!dir.path().join("out.exr").exists());
        stderr(&o)
    };
    for (flag, value, expect) in [
        ("--method", "foo", "--method foo: use blend or gather"),
        ("--weight", "foo", "--weight foo: use box or gaussian"),
        (
            "--algorithm",
            "foo",
            "--algorithm foo: use none, reconstruct, scatter or stretch",
        ),
        (
            "--samples",
            "16",
            "--samples 16: use an odd whole number from 1 to 255",
        ),
        ("--shutter", "2", "--shutter 2: use a number from 0 to 1"),
        ("--blades", "2", "--blades 2: use 0 (round) or 3 to 32"),
    ] {
        let message = run(&[flag, value]);
        assert!(message.contains(expect), "{message}");
        assert!(!message.contains("----"), "{message}");
    }
    std::fs::write(dir.path().join("mine.toml"), "[blur]\nsamples = 4\n").unwrap();
    let message = run(&["--preset", "mine.toml"]);
    assert!(
        message.contains("preset mine.toml: [blur] samples = 4: use an odd whole number"),
        "{message}"
    );
    assert!(!message.contains("--samples"), "{message}");
    // Merged presets: the message names the one that set the key.
    let message = run(&["--preset", "final", "--preset", "mine.toml"]);
    assert!(
        message.contains("preset mine.toml: [blur] samples"),
        "{message}"
    );
    std::fs::write(dir.path().join("typo.toml"), "[blur]\nsampels = 5\n").unwrap();
    let message = run(&["--preset", "typo.toml"]);
    assert!(
        message.contains("unknown key [blur] sampels") && message.contains("samples"),
        "{message}"
    );
}

#[test]
fn a_flag_for_another_algorithm_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 6);
    let o = blur_canonical_frame(
        dir.path(),
        &["--algorithm", "reconstruct", "--segments", "4", "--verbose"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--segments applies to scatter, not reconstruct"),
        "{}",
        stderr(&o)
    );
}

/// Depth of field's flags that would not be read (an outside probe: each ran silently, the
/// output the same as without it, and the lens given beside a map was even recorded in the
/// output's settings): `--coc-scale` with a lens, `--passes` with the pyramid, warned about;
/// a lens beside `--coc-map`, refused as `--depth` beside it is.
#[test]
fn dof_flags_that_would_not_be_read_are_warned_about_or_refused() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 6);
    let (c, z) = (dir.path().join("C.exr"), dir.path().join("Z.exr"));
    let out = dir.path().join("out.exr");
    let lens = [
        "--focal-length",
        "50",
        "--f-stop",
        "1.4",
        "--focus-distance",
        "3",
    ];
    let dof = |extra: &[&str], depth: &[&str]| {
        let mut args = vec![
            "dof",
            "--color",
            c.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(depth);
        args.extend(extra);
        shutter(&args)
    };
    let with_depth = ["--depth", z.to_str().unwrap()];
    for (extra, warning) in [
        (
            &["--coc-scale", "200"][..],
            "--coc-scale applies to a painted map",
        ),
        (
            &["--method", "blend", "--passes", "7"][..],
            "--passes applies to blend's talk form",
        ),
    ] {
        let mut args = lens.to_vec();
        args.extend(extra);
        let o = dof(&args, &with_depth);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains(warning), "{extra:?}: {}", stderr(&o));
    }
    // The talk's form reads --passes: no warning.
    let mut args = lens.to_vec();
    args.extend(["--method", "blend", "--blend-form", "talk", "--passes", "7"]);
    let o = dof(&args, &with_depth);
    assert!(
        o.status.success() && !stderr(&o).contains("--passes"),
        "{}",
        stderr(&o)
    );
    // A lens beside a painted map.
    std::fs::remove_file(&out).unwrap();
    let o = dof(
        &["--focus-distance", "3"],
        &["--coc-map", z.to_str().unwrap()],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--focus-distance would not be read"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

/// A number a message shows is short (an outside probe: 5e-324 and 1e308 came back as 300
/// digits), and an unbounded range says it wants a finite number (inf is "above 0" and was
/// refused as not).
#[test]
fn numbers_in_messages_are_short_and_ranges_say_finite() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 6);
    let c = dir.path().join("C.exr");
    let z = dir.path().join("Z.exr");
    let out = dir.path().join("out.exr");
    let dof = |focus: &str| {
        shutter(&[
            "dof",
            "--color",
            &s(&c),
            "--depth",
            &s(&z),
            "-o",
            &s(&out),
            "--focal-length",
            "50",
            "--f-stop",
            "1.4",
            "--focus-distance",
            focus,
        ])
    };
    let o = dof("5e-324");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("focus distance 5e-324:"),
        "{}",
        stderr(&o)
    );
    let o = dof("inf");
    assert!(
        stderr(&o).contains("a finite number above 0"),
        "{}",
        stderr(&o)
    );
    std::fs::write(dir.path().join("p.toml"), "[blur]\nshutter = 1e308\n").unwrap();
    let o = shutter(&[
        "blur",
        "--preset",
        &s(&dir.path().join("p.toml")),
        "--color",
        &s(&c),
        "-o",
        &s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("shutter = 1e308: use"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn switches_turn_their_default_over() {
    let jitter = shutter::settings::def("jitter").unwrap();
    assert_eq!(jitter.flag(), "no-jitter");
    assert_eq!(jitter.default_value(), Value::Switch(true));
    let half = shutter::settings::def("half").unwrap();
    assert_eq!(half.default_value(), Value::Switch(false));
}

/// `shutter presets keys | head -1`: the reader is gone before the listing is written. Not a
/// panic (println! panicked, before); an error on the write that meets it (README: exit 1,
/// named on stderr), no longer a success with the listing lost.
#[test]
fn listings_into_a_closed_pipe_fail_without_panicking() {
    let fixture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/canonical/color.0001.exr"
    );
    for args in [vec!["presets", "keys"], vec!["info", fixture]] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
            .args(&args)
            .stdout(writer)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("standard output"),
            "{args:?}: {}",
            stderr(&o)
        );
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn every_bench_setting_round_trips_through_its_flags() {
    // The bench runs `shutter blur` with the flags the definitions make for each setting of
    // the sweep: read back through the same definitions, they give the same settings.
    use shutter::settings::{resolve, Given, Kind, Settings, DEFS};
    let lens = shutter::dof::Lens {
        focal_mm: 50.0,
        f_number: 1.4,
        focus: 3.0,
        sensor_mm: 36.0,
    };
    let preset = shutter::io::preset::Preset::builtin("shutter").unwrap();
    for target in shutter::lab::bench::targets("layers", Some(lens)) {
        for setting in target.settings {
            let flags = setting.flags();
            let mut given = Given::default();
            let mut words = flags.iter();
            while let Some(flag) = words.next() {
                let name = flag.trim_start_matches("--");
                let d = DEFS
                    .iter()
                    .find(|d| d.flag() == name)
                    .unwrap_or_else(|| panic!("{}: {flag} is no setting", setting.label));
                let value = match d.kind {
                    Kind::Switch => "true".to_string(),
                    _ => words.next().unwrap().clone(),
                };
                given.values.push((d.name, value));
            }
            let (read, _) = resolve(&given, &preset).unwrap();
            assert_eq!(
                read,
                Settings::of(setting.algorithm, &setting.params),
                "{} {flags:?}",
                setting.label
            );
        }
    }
}

#[test]
fn shutter_offset_takes_names_numbers_a_preset_key_and_reports_bad_values() {
    use shutter::settings::{resolve, Given};
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("opens.toml");
    std::fs::write(
        &toml,
        "description = \"opens at the frame\"\n[blur]\nshutter_offset = \"start\"\n",
    )
    .unwrap();
    let preset = shutter::io::preset::Preset::load(&[s(&toml)]).unwrap();
    let offset = |given: &[(&'static str, &str)], preset: &shutter::io::preset::Preset| {
        let mut g = Given::default();
        for (name, value) in given {
            g.values.push((name, value.to_string()));
        }
        resolve(&g, preset).map(|(s, _)| s.params.shutter_offset)
    };
    let plain = shutter::io::preset::Preset::builtin("shutter").unwrap();
    assert_eq!(offset(&[], &plain).unwrap(), 0.0, "centred by default");
    assert_eq!(offset(&[], &preset).unwrap(), 0.5, "the preset key");
    assert_eq!(offset(&[("shutter-offset", "end")], &preset).unwrap(), -0.5);
    assert_eq!(
        offset(&[("shutter-offset", "Centre")], &preset).unwrap(),
        0.0
    );
    assert_eq!(
        offset(&[("shutter-offset", "-0.25")], &plain).unwrap(),
        -0.25
    );
    for bad in ["0.7", "sideways", "nan"] {
        let message = format!(
            "{:#}",
            offset(&[("shutter-offset", bad)], &plain).unwrap_err()
        );
        assert!(
            message.contains("--shutter-offset") && message.contains("start"),
            "{bad}: {message}"
        );
    }
    // The flags the bench passes to `shutter blur` name the offset as it was chosen.
    let settings = shutter::settings::Settings::of(
        shutter::motion::Algorithm::Scatter,
        &shutter::process::Params {
            shutter_offset: 0.5,
            ..Default::default()
        },
    );
    let flags = shutter::settings::flags(&settings);
    assert!(
        flags.windows(2).any(|w| w == ["--shutter-offset", "start"]),
        "{flags:?}"
    );
}
