//! Manners of the real `incal` binary: exit codes (0 ok, 1 failure, 2 bad
//! usage or input), exactly one stderr line naming the option or file, no
//! panics, `-` for standard input, a UTF-8 byte-order mark accepted.

use crate::common;
use common::*;

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

/// The single stderr line of `o` (fails unless there is exactly one).
fn stderr_line(o: &Output) -> String {
    let s = stderr(o);
    assert!(!s.contains("panicked"), "panic: {s}");
    assert_eq!(s.trim_end().lines().count(), 1, "one stderr line, got: {s}");
    assert!(s.ends_with('\n'), "line ends with a newline: {s:?}");
    s.trim_end().to_string()
}

fn simulated_tumble_csv() -> Vec<u8> {
    let o = run(&["simulate", "tumble", "--seed", "7"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.starts_with(b"angle_deg,output\n"));
    o.stdout
}

#[test]
fn bare_incal_is_bad_usage_with_the_usage_on_stderr() {
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty(), "nothing on stdout");
    let e = stderr(&o);
    assert!(e.contains("Usage: incal"), "{e}");
    assert!(e.contains("tumble"), "lists the commands: {e}");
}

#[test]
fn a_command_group_without_its_subcommand_is_bad_usage() {
    for group in ["plan", "misalign", "simulate", "gfimu"] {
        let o = run(&[group]);
        assert_eq!(o.status.code(), Some(2), "incal {group}");
        assert!(o.stdout.is_empty(), "incal {group}: nothing on stdout");
        let e = stderr(&o);
        assert!(e.contains(&format!("Usage: incal {group}")), "{e}");
    }
    let o = run(&["simulate", "misalign"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("Usage: incal simulate misalign"));
}

#[test]
fn help_and_version_are_success_on_stdout() {
    for args in [
        &["--help"][..],
        &["--version"],
        &["tumble", "--help"],
        &["help"],
    ] {
        let o = run(args);
        assert_eq!(o.status.code(), Some(0), "incal {args:?}");
        assert!(!o.stdout.is_empty(), "incal {args:?}: on stdout");
        assert!(o.stderr.is_empty(), "incal {args:?}: {}", stderr(&o));
    }
}

#[test]
#[cfg(target_os = "linux")]
fn help_to_a_full_stdout_is_a_quiet_failure() {
    for args in [&["--help"][..], &["--version"]] {
        let o = Command::new(env!("CARGO_BIN_EXE_incal"))
            .args(args)
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "incal {args:?} >/dev/full");
        assert!(o.stderr.is_empty(), "quiet: {}", stderr(&o));
    }
}

#[test]
fn missing_required_option_is_named() {
    let o = run(&["tumble", "--input", "x.csv"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr_line(&o),
        "incal: missing required option --mount <MOUNT> (see 'incal tumble --help')"
    );
    let o = run(&["tumble"]);
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(
        line.contains("--mount") && line.contains("--input"),
        "{line}"
    );
}

#[test]
fn invalid_choice_lists_the_allowed_values() {
    let o = run(&["tumble", "--mount", "sideways", "--input", "x.csv"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr_line(&o),
        "incal: invalid value 'sideways' for '--mount <MOUNT>' (possible values: pendulum, gate)"
    );
}

#[test]
fn unknown_option_is_named_with_a_suggestion() {
    let o = run(&["tumble", "--bogus"]);
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(line.contains("'--bogus'"), "{line}");
    assert!(line.contains("incal tumble --help"), "{line}");

    let o = run(&["tumble", "--mount", "gate", "--input", "x.csv", "--jsn"]);
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(
        line.contains("'--jsn'") && line.contains("'--json'"),
        "{line}"
    );

    let o = run(&["tumbel"]);
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(
        line.contains("'tumbel'") && line.contains("'tumble'"),
        "{line}"
    );
}

#[test]
fn bad_number_is_one_line_naming_the_option() {
    let o = run(&["simulate", "tumble", "--seed", "abc"]);
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(line.contains("--seed") && line.contains("'abc'"), "{line}");
}

#[test]
#[cfg(target_os = "linux")]
fn unwritable_output_file_is_a_failure() {
    let o = run(&["simulate", "tumble", "--output", "/dev/full"]);
    assert_eq!(o.status.code(), Some(1));
    let line = stderr_line(&o);
    assert!(line.contains("/dev/full"), "{line}");
    assert!(line.contains("No space left on device"), "{line}");
}

#[test]
#[cfg(target_os = "linux")]
fn full_stdout_is_a_failure() {
    let o = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["simulate", "tumble"])
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let line = stderr_line(&o);
    assert!(line.contains("stdout"), "{line}");
}

#[test]
fn dash_reads_standard_input_through_a_pipe() {
    let mut sim = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["simulate", "tumble", "--seed", "7"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["tumble", "--mount", "pendulum", "--input", "-"])
        .stdin(Stdio::from(sim.stdout.take().unwrap()))
        .output()
        .unwrap();
    assert!(sim.wait().unwrap().success());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(o.stderr.is_empty(), "{}", stderr(&o));
    // The report names the input as given (`-`) with its hash.
    assert!(String::from_utf8_lossy(&o.stdout).contains("input: - (sha256 "));
}

#[test]
fn bad_standard_input_is_named_stdin() {
    let o = run_with_stdin(&["tumble", "--mount", "pendulum", "--input", "-"], b"");
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(line.starts_with("incal: <stdin>: "), "{line}");

    let o = run_with_stdin(
        &["tumble", "--mount", "pendulum", "--input", "-"],
        b"angle_deg,output\n0,abc\n",
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr_line(&o).starts_with("incal: <stdin>:2: "));
}

#[test]
fn a_leading_bom_is_accepted() {
    let csv = simulated_tumble_csv();
    let plain = write("plain.csv", &csv);
    let mut with_bom = b"\xEF\xBB\xBF".to_vec();
    with_bom.extend_from_slice(&csv);
    let bom = write("bom.csv", &with_bom);
    let run = |p: &PathBuf| {
        let o = run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            p.to_str().unwrap(),
            "--json",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["coefficients"].clone()
    };
    let a = run(&plain);
    assert!(a.is_object(), "{a}");
    assert_eq!(a, run(&bom), "same coefficients with and without a BOM");

    // On standard input too.
    let o = run_with_stdin(
        &["tumble", "--mount", "pendulum", "--input", "-", "--json"],
        &with_bom,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn unreadable_input_is_bad_input_naming_the_file() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("incal-cli-manners-{}", std::process::id()));
    let missing = dir.join("no-such-file.csv");
    let o = run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let line = stderr_line(&o);
    assert!(
        line.starts_with(&format!("incal: {}: cannot read: ", missing.display())),
        "{line}"
    );
}

/// Every subcommand path below `prefix`, found from the `Commands:`
/// section of its help (so a new command is covered without a list here).
fn command_paths(prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut args: Vec<&str> = prefix.iter().map(String::as_str).collect();
    args.push("--help");
    let help = ok(&run(&args));
    out.push(prefix.clone());
    let mut listing = false;
    for line in help.lines() {
        if line.starts_with("Commands:") {
            listing = true;
        } else if listing && line.trim().is_empty() {
            break;
        } else if listing {
            let name = line.split_whitespace().next().unwrap_or("");
            if !name.is_empty() && name != "help" {
                let mut next = prefix.clone();
                next.push(name.to_string());
                command_paths(next, out);
            }
        }
    }
}

/// Product text names papers by their bibliographic reference. The
/// internal "seed 00x" labels and the workspace-external
/// methods note must not reach any help page, the demo or the schemas.
#[test]
fn product_text_names_no_internal_document() {
    let mut paths = Vec::new();
    command_paths(Vec::new(), &mut paths);
    assert!(paths.len() > 20, "every command walked: {}", paths.len());
    let mut texts: Vec<(String, String)> = paths
        .iter()
        .map(|p| {
            let mut a: Vec<&str> = p.iter().map(String::as_str).collect();
            a.push("--help");
            (format!("incal {} --help", p.join(" ")), ok(&run(&a)))
        })
        .collect();
    texts.push(("incal demo".into(), ok(&run(&["demo"]))));
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../schema");
    for f in ["result.schema.json", "plan.schema.json"] {
        texts.push((f.into(), std::fs::read_to_string(root.join(f)).unwrap()));
    }
    for (what, text) in &texts {
        let lower = text.to_lowercase();
        for bad in ["seed 00", "seed-00", "seed00", "methods.md"] {
            assert!(!lower.contains(bad), "{what} says {bad:?}");
        }
    }
}

/// Every CSV incal writes is read by `pandas.read_csv(path)`
/// with default arguments: a header, then rows as wide as it, no comment
/// lines before or after (truth and run notes go to a side file, the JSON
/// or standard error).
#[test]
fn every_csv_incal_writes_is_plain() {
    let dir = workdir("plain-csv");
    let sims: Vec<Vec<&str>> = vec![
        vec!["tumble", "--passes", "2"],
        vec!["centrifuge"],
        vec!["misalign", "gyro"],
        vec!["misalign", "accel"],
        vec!["gfimu", "--truth-out", "gfimu_truth.json"],
        vec!["gfimu", "--kind", "motion"],
        vec!["gyro-rate"],
        vec!["gyro-positions"],
        vec![
            "imu",
            "--sequence",
            "ferraris",
            "--static-s",
            "0.5",
            "--rotation-s",
            "1",
        ],
        vec![
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "10",
            "--seed",
            "1",
            "--format",
            "csv",
        ],
    ];
    let plain = |what: &str, text: &str| {
        let mut lines = text.lines();
        let width = lines.next().unwrap().split(',').count();
        for (k, l) in lines.enumerate() {
            assert!(!l.starts_with('#'), "{what}: line {}: {l}", k + 2);
            assert_eq!(l.split(',').count(), width, "{what}: line {}: {l}", k + 2);
        }
    };
    for (k, sim) in sims.iter().enumerate() {
        let out = format!("s{k}.csv");
        let mut args = vec!["simulate"];
        args.extend_from_slice(sim);
        args.extend_from_slice(&["-o", &out]);
        let o = run_in(&dir, &args);
        assert!(o.status.success(), "{sim:?}: {}", stderr(&o));
        plain(
            &format!("{sim:?}"),
            &std::fs::read_to_string(dir.join(&out)).unwrap(),
        );
    }
    // The gyro-free unit's truth is beside the CSV.
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("gfimu_truth.json")).unwrap())
            .unwrap();
    assert!(truth["notes"]
        .as_array()
        .unwrap()
        .iter()
        .any(|n| n.as_str().unwrap().starts_with("truth a:")));
    // A streamed gyro-free solution: rows only, mode on stderr.
    ok(&run_in(
        &dir,
        &["simulate", "gfimu", "--seed", "3", "-o", "static.csv"],
    ));
    ok(&run_in(
        &dir,
        &[
            "gfimu",
            "calibrate",
            "--input",
            "static.csv",
            "--json",
            "-o",
            "cal.json",
        ],
    ));
    let o = run_in(
        &dir,
        &[
            "gfimu",
            "solve",
            "--calibration",
            "cal.json",
            "--input",
            "s5.csv",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    plain("gfimu solve", &stdout(&o));
    assert!(stderr(&o).contains("note: solution mode"), "{}", stderr(&o));
}
