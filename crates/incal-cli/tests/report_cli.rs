//! `incal report` through the real binary, for every reducing procedure:
//! simulate, reduce with `--json`, report, then parse the HTML and check
//! that every section, every coefficient, every table of the document and
//! the plots are there, that the file references nothing outside itself
//! and that the instrument's identity is escaped. A file that is not an
//! incal result is refused (exit 2).

mod common;
use common::*;

use std::process::Command;

use scraper::{Html, Selector};
use serde_json::Value;

fn sel(s: &str) -> Selector {
    Selector::parse(s).unwrap()
}

/// Nothing loads from elsewhere: no attribute that references (`src`,
/// `href`, …), no element that loads, no CSS `url(`/`@import`, no address.
fn assert_self_contained(name: &str, html: &str) {
    let doc = Html::parse_document(html);
    for el in doc.select(&sel("*")) {
        for (attr, value) in el.value().attrs() {
            assert!(
                !matches!(
                    attr,
                    "src" | "href" | "srcset" | "action" | "data" | "xlink:href" | "poster"
                ),
                "{name}: <{} {attr}=\"{value}\">",
                el.value().name()
            );
            assert!(!value.contains("url("), "{name}: {attr}=\"{value}\"");
        }
    }
    for tag in ["script", "link", "iframe", "object", "embed", "img", "base"] {
        assert_eq!(doc.select(&sel(tag)).count(), 0, "{name}: <{tag}>");
    }
    let css: String = doc.select(&sel("style")).flat_map(|s| s.text()).collect();
    assert!(!css.contains("url(") && !css.contains("@import"), "{name}");
    assert!(!html.contains("://"), "{name}: an address in the file");
}

/// (procedure, simulate args, input file, reduce args).
type Case = (
    &'static str,
    Vec<&'static str>,
    &'static str,
    Vec<&'static str>,
);

fn cases() -> Vec<Case> {
    vec![
        (
            "tumble",
            vec!["tumble", "--seed", "11", "--passes", "2"],
            "tumble.csv",
            vec!["tumble", "--mount", "pendulum", "--input", "tumble.csv"],
        ),
        (
            "centrifuge",
            vec!["centrifuge", "--seed", "12", "--levels-g", "0,1,4,10,18,25"],
            "centrifuge.csv",
            vec![
                "centrifuge",
                "--input",
                "centrifuge.csv",
                "--k0",
                "1.2e-4",
                "--u-k0",
                "2e-6",
                "--k1",
                "1.3",
                "--u-k1",
                "1.3e-6",
                "--radius-m",
                "0.71",
                "--latitude-deg",
                "39.9",
            ],
        ),
        (
            "misalign-gyro",
            vec!["misalign", "gyro", "--seed", "13"],
            "gyro.csv",
            vec![
                "misalign",
                "gyro",
                "--input",
                "gyro.csv",
                "--scale-factor",
                "-2.9222",
            ],
        ),
        (
            "misalign-accel",
            vec!["misalign", "accel", "--seed", "14"],
            "accel.csv",
            vec![
                "misalign",
                "accel",
                "--input",
                "accel.csv",
                "--scale-factor",
                "1.299",
            ],
        ),
        (
            "gfimu-calibrate",
            vec!["gfimu", "--seed", "15"],
            "gfimu.csv",
            vec!["gfimu", "calibrate", "--input", "gfimu.csv"],
        ),
    ]
}

const EVIL: &str = "<script>alert(1)</script>";

#[test]
fn every_procedure_gets_a_complete_self_contained_report() {
    let dir = workdir("all");
    for (procedure, sim, file, reduce) in cases() {
        let mut args = vec!["simulate"];
        args.extend_from_slice(&sim);
        args.extend_from_slice(&["--output", file]);
        ok(&run_in(&dir, &args));
        let json = format!("{procedure}.json");
        let mut args = reduce.clone();
        args.extend_from_slice(&[
            "--json",
            "--serial",
            EVIL,
            "--meta",
            "operator=<b>lee</b>",
            "-o",
            &json,
        ]);
        ok(&run_in(&dir, &args));
        let doc: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(&json)).unwrap()).unwrap();
        let html_file = format!("{procedure}.html");
        assert_eq!(
            ok(&run_in(&dir, &["report", &json, "-o", &html_file])),
            "",
            "{procedure}: written to the file"
        );
        let html = std::fs::read_to_string(dir.join(&html_file)).unwrap();
        assert_self_contained(procedure, &html);
        assert!(!html.contains(EVIL), "{procedure}: serial not escaped");
        assert!(!html.contains("<b>lee"), "{procedure}: meta not escaped");
        let page = Html::parse_document(&html);

        for id in ["header", "coefficients", "fits", "notes", "tables", "plots"] {
            assert_eq!(
                page.select(&sel(&format!("#{id}"))).count(),
                1,
                "{procedure}: #{id}"
            );
        }
        let header: String = page.select(&sel("header")).flat_map(|h| h.text()).collect();
        assert!(header.contains(EVIL), "{procedure}: the serial, as text");
        assert!(header.contains(procedure));
        assert!(header.contains(doc["incal_version"].as_str().unwrap()));
        assert!(header.contains(doc["inputs"][0]["sha256"].as_str().unwrap()));

        // Every coefficient, in order, with a verdict column.
        let names: Vec<String> = page
            .select(&sel("table.coefficients tbody td:first-child span"))
            .map(|c| c.value().attr("data-name").unwrap_or_default().to_string())
            .collect();
        let typed = incal::document::ResultDocument::from_json(
            &std::fs::read_to_string(dir.join(&json)).unwrap(),
        )
        .unwrap();
        assert_eq!(names, typed.coefficients.names(), "{procedure}");
        let th: Vec<String> = page
            .select(&sel("table.coefficients th"))
            .map(|c| c.text().collect())
            .collect();
        for col in ["value", "U95", "unit", "verdict"] {
            assert!(th.iter().any(|h| h == col), "{procedure}: {col} in {th:?}");
        }

        // Every document table, with all its rows.
        for t in doc["tables"].as_array().unwrap() {
            let id = t["id"].as_str().unwrap();
            let rows = page
                .select(&sel(&format!(
                    "div.doc-table[data-table=\"{id}\"] tbody tr"
                )))
                .count();
            assert_eq!(
                rows,
                t["rows"].as_array().unwrap().len(),
                "{procedure}: table {id}"
            );
        }
        let fits = page.select(&sel("table.fits tbody tr")).count();
        assert_eq!(fits, doc["fits"].as_array().unwrap().len(), "{procedure}");

        // Plots: inline SVG, residual and fitted wherever a table has residuals.
        let kinds: Vec<&str> = page
            .select(&sel("#plots figure.plot"))
            .map(|f| f.value().attr("data-plot").unwrap())
            .collect();
        assert!(!kinds.is_empty(), "{procedure}: no plot");
        for f in page.select(&sel("#plots figure.plot")) {
            assert_eq!(f.select(&sel("svg")).count(), 1, "{procedure}");
            assert!(f.select(&sel("svg circle")).count() >= 1, "{procedure}");
        }
        let with_residuals = doc["tables"].as_array().unwrap().iter().any(|t| {
            t["columns"]
                .as_array()
                .unwrap()
                .iter()
                .any(|c| c["name"] == "residual")
        });
        if with_residuals {
            assert!(kinds.contains(&"residual"), "{procedure}: {kinds:?}");
            assert!(kinds.contains(&"fitted"), "{procedure}: {kinds:?}");
        } else {
            assert!(kinds.contains(&"coefficients"), "{procedure}: {kinds:?}");
        }
        if procedure == "centrifuge" {
            // Twelve series (six stations, two polarities): one panel per station.
            let stations = doc["tables"]
                .as_array()
                .unwrap()
                .iter()
                .find(|t| t["id"] == "stations")
                .unwrap()["rows"]
                .as_array()
                .unwrap()
                .len();
            assert_eq!(stations, 6);
            assert_eq!(kinds.iter().filter(|k| **k == "residual").count(), stations);
            assert_eq!(kinds.iter().filter(|k| **k == "fitted").count(), stations);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_report_goes_to_stdout_without_o_and_a_non_result_is_refused() {
    let dir = workdir("misc");
    ok(&run_in(
        &dir,
        &[
            "simulate", "misalign", "accel", "--seed", "2", "-o", "a.csv",
        ],
    ));
    let json = ok(&run_in(
        &dir,
        &[
            "misalign",
            "accel",
            "--input",
            "a.csv",
            "--scale-factor",
            "1.299",
            "--json",
        ],
    ));
    std::fs::write(dir.join("a.json"), &json).unwrap();
    let html = ok(&run_in(&dir, &["report", "a.json"]));
    assert!(html.starts_with("<!DOCTYPE html>"));
    // Standard input, as everywhere.
    let mut child = Command::new(env!("CARGO_BIN_EXE_incal"))
        .current_dir(&dir)
        .args(["report", "-"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::Write;
        child
            .stdin
            .take()
            .unwrap()
            .write_all(json.as_bytes())
            .unwrap();
    }
    assert!(ok(&child.wait_with_output().unwrap()).contains("id=\"coefficients\""));

    for (file, text, message) in [
        (
            "other.json",
            "{\"coefficients\": {}}",
            "other.json: $.schema",
        ),
        ("a.csv", "", "a.csv: line 1: not valid JSON"),
        ("empty.json", "", "empty.json: empty file"),
    ] {
        if !text.is_empty() || file == "empty.json" {
            std::fs::write(dir.join(file), text).unwrap();
        }
        let o = run_in(&dir, &["report", file, "-o", "x.html"]);
        assert_eq!(o.status.code(), Some(2), "{file}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(message), "{file}: {err}");
        assert!(!dir.join("x.html").exists(), "{file}: no report written");
    }
    let o = run_in(&dir, &["report", "missing.json"]);
    assert_eq!(o.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `incal report --limits FILE --db PATH`: verdicts in the certificate and
/// a history plot of each limited coefficient once the store holds two or
/// more calibrations of the instrument.
#[test]
fn report_with_limits_and_history_from_the_store() {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("incal-report-db-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_incal"))
            .current_dir(&d)
            .args(args)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    };
    std::fs::write(
        d.join("l.toml"),
        "rule = \"guard-band\"\n[tumble]\nK0 = { min = 7900, max = 8100, unit = \"ug\" }\n",
    )
    .unwrap();
    for seed in ["1", "2", "3"] {
        run(&["simulate", "tumble", "--seed", seed, "-o", "t.csv"]);
        run(&[
            "tumble", "--mount", "pendulum", "--input", "t.csv", "--serial", "SN-7", "--json",
            "-o", "r.json",
        ]);
        run(&["record", "add", "r.json", "--db", "s.db"]);
    }
    run(&[
        "report", "r.json", "--limits", "l.toml", "--db", "s.db", "-o", "r.html",
    ]);
    let html = std::fs::read_to_string(d.join("r.html")).unwrap();
    assert!(html.contains("id=\"history\""), "history section");
    assert!(html.contains("verdict-pass"), "K0 judged");
    // Without a store nothing breaks: no history section.
    run(&["report", "r.json", "--limits", "l.toml", "-o", "n.html"]);
    let html = std::fs::read_to_string(d.join("n.html")).unwrap();
    assert!(!html.contains("id=\"history\""));
    let _ = std::fs::remove_dir_all(&d);
}
