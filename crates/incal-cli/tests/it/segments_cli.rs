//! Continuous rig logs (docs/src/recordings.md, "Segments from a rig
//! channel"): a labelled recording turned into the log a rig writes (the
//! channel jitters at rest, moves between positions, the output rings
//! while it settles) reduces with `--segment-by` to the labelled file's
//! coefficients; a plateau missing from the plan is refused naming its
//! time.

use crate::common;
use common::*;
use serde_json::Value;

/// A small deterministic jitter in [-1, 1] (no RNG needed here).
fn jitter(k: usize) -> f64 {
    let x = ((k as f64) * 12.9898).sin() * 43758.5453;
    2.0 * (x - x.floor()) - 1.0
}

/// The log a rig writes for the labelled recording `text`, segmented by
/// column `col` (jitter `amp` at rest, `excursion` away while moving): at
/// 10 Hz, before each group of rows with one label, 10 rows of motion and
/// 10 rows of settling (the channel at rest, the output off by 1); the
/// labelled rows follow with the channel jittered. `skip`: a group left
/// out (a missing plateau).
fn rig_log(
    text: &str,
    col: &str,
    amp: f64,
    excursion: f64,
    skip: Option<usize>,
) -> (String, String) {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let c = header.iter().position(|h| *h == col).unwrap();
    let o = header.iter().position(|h| *h == "output").unwrap();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let mut out = format!("time_s,{}\n", header.join(","));
    // The labelled rows with their time stamps, as a labelled file with time_s.
    let mut labelled = out.clone();
    let (mut k, mut group) = (0usize, 0usize);
    let mut i = 0;
    while i < rows.len() {
        let label: Vec<&String> = rows[i]
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != o)
            .map(|x| x.1)
            .collect();
        let mut end = i;
        while end < rows.len()
            && rows[end]
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != o)
                .map(|x| x.1)
                .collect::<Vec<_>>()
                == label
        {
            end += 1;
        }
        if skip != Some(group) {
            let value: f64 = rows[i][c].parse().unwrap();
            let mut emit = |cells: &[String], v: f64, extra: f64, k: &mut usize| {
                let mut r = cells.to_vec();
                r[c] = format!("{v}");
                if extra != 0.0 {
                    let y: f64 = r[o].parse().unwrap();
                    r[o] = format!("{}", y + extra);
                }
                out.push_str(&format!("{},{}\n", *k as f64 * 0.1, r.join(",")));
                *k += 1;
            };
            for m in 0..10 {
                emit(&rows[i], value + excursion * (1.0 + m as f64), 1.0, &mut k);
            }
            for _ in 0..10 {
                emit(&rows[i], value + amp * jitter(k), 1.0, &mut k);
            }
            for r in &rows[i..end] {
                labelled.push_str(&format!("{},{}\n", k as f64 * 0.1, r.join(",")));
                emit(r, value + amp * jitter(k), 0.0, &mut k);
            }
        }
        group += 1;
        i = end;
    }
    (out, labelled)
}

/// Each coefficient of `b` within `share` of its U95 of `a`'s; the
/// largest share found.
fn agree(a: &Value, b: &Value, share: f64, what: &str) -> f64 {
    let (a, b) = (coefficient_values(a), coefficient_values(b));
    assert_eq!(a.len(), b.len(), "{what}");
    let mut most: f64 = 0.0;
    for ((n, x, u), (m, y, _)) in a.iter().zip(&b) {
        assert_eq!(n, m, "{what}");
        assert!(
            (x - y).abs() <= share * u,
            "{what} {n}: {x} vs {y} (U95 {u})"
        );
        most = most.max((x - y).abs() / u);
    }
    most
}

/// The distinct values of column `col` in file order, as the plan lists them.
fn plan_values(text: &str, col: &str) -> String {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let c = lines
        .next()
        .unwrap()
        .split(',')
        .position(|h| h == col)
        .unwrap();
    let mut out: Vec<String> = Vec::new();
    let mut last = String::new();
    for l in lines {
        let v = l.split(',').nth(c).unwrap().to_string();
        if v != last {
            out.push(v.clone());
            last = v;
        }
    }
    out.join(",")
}

/// The simulator's words, the reduction's, the rig channel, its jitter at
/// rest and its excursion while moving.
type Case = (
    &'static [&'static str],
    &'static [&'static str],
    &'static str,
    f64,
    f64,
);

#[test]
fn continuous_logs_reduce_to_the_labelled_files_coefficient_values() {
    let dir = workdir("segments_logs");
    let cases: [Case; 3] = [
        (
            &["simulate", "tumble", "--samples", "100", "--noise", "3e-4"],
            &["tumble", "--mount", "pendulum"],
            "angle_deg",
            5e-4,
            5.0,
        ),
        (
            &[
                "simulate",
                "gyro-rate",
                "--samples",
                "100",
                "--noise",
                "1e-3",
            ],
            &["gyro", "rate", "--latitude-deg", "45"],
            "rate_deg_s",
            1e-3,
            3.0,
        ),
        (
            &[
                "simulate",
                "centrifuge",
                "--samples",
                "100",
                "--noise",
                "1e-4",
            ],
            &[
                "centrifuge",
                "--k0",
                "1.2e-4",
                "--k1",
                "1.3",
                "--u-k0",
                "2e-6",
                "--u-k1",
                "1e-6",
                "--radius-m",
                "0.71",
                "--latitude-deg",
                "39.9",
            ],
            "omega_rad_s",
            2e-5,
            0.5,
        ),
    ];
    for (sim, reduce, col, amp, excursion) in cases {
        let labelled = dir.join(format!("{col}.csv"));
        let mut a = sim.to_vec();
        a.extend(["--seed", "3", "-o", p(&labelled)]);
        ok(&run(&a));
        let text = std::fs::read_to_string(&labelled).unwrap();
        let log = dir.join(format!("{col}_log.csv"));
        let (log_text, stamped) = rig_log(&text, col, amp, excursion, None);
        std::fs::write(&log, log_text).unwrap();
        std::fs::write(&labelled, stamped).unwrap();
        let with = |file: &std::path::Path, extra: &[&str]| {
            let mut a = reduce.to_vec();
            a.extend(["--input", p(file), "--json"]);
            a.extend_from_slice(extra);
            json_of(&run(&a))
        };
        let want = with(&labelled, &[]);
        let values = plan_values(&text, col);
        // The plan's values: the labelled file's rows, exactly.
        let planned = with(
            &log,
            &[
                "--segment-by",
                col,
                "--segment-settle-s",
                "1",
                "--segment-values",
                &values,
            ],
        );
        assert_eq!(
            coefficient_values(&planned),
            coefficient_values(&want),
            "{col}"
        );
        let seg = &planned["segmentation"];
        assert_eq!(seg["column"], col);
        let table = planned["tables"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["id"] == "segments")
            .unwrap();
        assert_eq!(
            table["rows"].as_array().unwrap().len(),
            seg["plateaus"].as_u64().unwrap() as usize
        );
        // The plateaus' own means carry the channel's jitter (5e-4 deg
        // of an encoder is 8.7e-5 of the output at K1 = 10): within 0.25
        // U95 here (measured: 0.10 for tumble's K_ip, below 0.01 else).
        let means = with(&log, &["--segment-by", col, "--segment-settle-s", "1"]);
        let most = agree(&want, &means, 0.25, col);
        println!("{col}: plateau means within {most:.3} U95 of the labelled file");
        // Not segmented, the log's settling rows and moves spoil it (the test can fail).
        let raw = run(&[reduce, &["--input", p(&log), "--json"]].concat());
        if raw.status.success() {
            let v: Value = serde_json::from_slice(&raw.stdout).unwrap();
            assert_ne!(coefficient_values(&v), coefficient_values(&want), "{col}");
        }
        // A plateau missing from the log is refused naming its time.
        let short = dir.join(format!("{col}_short.csv"));
        std::fs::write(&short, rig_log(&text, col, amp, excursion, Some(2)).0).unwrap();
        let mut a = reduce.to_vec();
        a.extend([
            "--input",
            p(&short),
            "--segment-by",
            col,
            "--segment-values",
            &values,
        ]);
        refused(
            &run(&a),
            &["is missing", "the log goes on to the plateau at t = "],
        );
    }
}

#[test]
fn segmenting_refuses_what_it_cannot_do() {
    let dir = workdir("segments_refusals");
    let f = dir.join("t.csv");
    std::fs::write(&f, "angle_deg,output\n0,1\n0,1\n").unwrap();
    refused(
        &run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            p(&f),
            "--segment-by",
            "angle_deg",
        ]),
        &["--segment-by angle_deg: a log needs time_s"],
    );
    refused(
        &run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            p(&f),
            "--segment-values",
            "0,90",
        ]),
        &["--segment-values: needs --segment-by COLUMN"],
    );
    let g = dir.join("g.csv");
    std::fs::write(&g, "time_s,encoder,angle_deg,output\n0,0,0,1\n0.1,0,0,1\n").unwrap();
    let tumble = |extra: &[&str]| {
        let mut a = vec!["tumble", "--mount", "pendulum", "--input", p(&g)];
        a.extend_from_slice(extra);
        run(&a)
    };
    refused(
        &tumble(&["--segment-by", "encoder"]),
        &[
            "--segment-by encoder: no default tolerance",
            "--segment-tolerance",
        ],
    );
    refused(
        &tumble(&["--segment-by", "angle_deg"]),
        &["no plateau found"],
    );
    refused(
        &tumble(&["--segment-by", "angle_deg", "--segment-tolerance", "-1"]),
        &["--segment-tolerance: -1 is not a positive tolerance"],
    );
}
