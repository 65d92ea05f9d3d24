//! `incal report` through the real binary, for every reducing procedure:
//! simulate, reduce with `--json`, report, then parse the HTML and check
//! that every section, every coefficient, every table of the document and
//! the plots are there, that the file references nothing outside itself
//! and that the instrument's identity is escaped. A file that is not an
//! incal result is refused (exit 2).

use crate::common;
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

/// Every procedure that reduces a simulated recording, with its worked
/// example from the procedure registry.
fn cases() -> Vec<Case> {
    registry_cases()
        .into_iter()
        .map(|c| {
            let file: &'static str = Box::leak(format!("{}.csv", c.id).into_boxed_str());
            (c.id, c.simulate.clone(), file, c.reduce(file))
        })
        .collect()
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
        if procedure == "noise" {
            // A noise result is its Allan family: the deviations with their
            // bounds and the fitted terms, drawn in one plot.
            assert!(kinds.contains(&"allan"), "{procedure}: {kinds:?}");
        } else if doc.get("bode").is_some() {
            // A frequency response: its Bode plots, gain and phase.
            assert_eq!(kinds, ["bode", "bode"], "{procedure}");
        } else if doc.get("mag").is_some() {
            // A magnetometer calibration: the raw field on each plane with
            // the fitted ellipsoid, and the calibrated magnitude.
            assert_eq!(kinds, ["mag", "mag", "mag", "mag"], "{procedure}");
        } else if with_residuals {
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

/// A laboratory profile with both rigs the procedures below need standards
/// for, and a third rig (centrifuge) left out on purpose.
const LAB_TOML: &str = r#"[lab]
name = "Inertial Test Laboratory"
address = "1 Gyro Road, Tianjin 300000, China"
accreditation = "CNAS L0000 (ISO/IEC 17025:2017)"
certificate_prefix = "ITL-"

[[signatory]]
name = "Li Wei"
role = "Head of calibration"

[[standard]]
rig = "dividing-head"
id = "Dividing head DH-01"
certificate = "NIM-2026-0457"
due = "2027-03-31"

[[standard]]
rig = "rate-table"
id = "Rate table RT-02"
certificate = "NIM-2025-0112"
due = "2026-01-15"
"#;

/// Every procedure: (id, simulate words, reduce words before `--input`,
/// reduce words after it).
fn all_procedures() -> Vec<(&'static str, Vec<&'static str>, Vec<&'static str>)> {
    vec![
        (
            "tumble",
            vec!["tumble", "--samples", "3"],
            vec!["tumble", "--mount", "pendulum"],
        ),
        (
            "centrifuge",
            vec!["centrifuge", "--levels-g", "0,1,4,9", "--samples", "3"],
            vec![
                "centrifuge",
                "--k1",
                "1.3",
                "--k0",
                "1.2e-4",
                "--radius-m",
                "0.71",
                "--latitude-deg",
                "39.9",
            ],
        ),
        (
            "misalign-gyro",
            vec!["misalign", "gyro"],
            vec!["misalign", "gyro", "--scale-factor", "-2.9222"],
        ),
        (
            "misalign-accel",
            vec!["misalign", "accel"],
            vec!["misalign", "accel", "--scale-factor", "1.299"],
        ),
        (
            "gfimu-calibrate",
            vec!["gfimu", "--seed", "3"],
            vec!["gfimu", "calibrate"],
        ),
        (
            "gyro-rate",
            vec!["gyro-rate", "--samples", "4"],
            vec!["gyro", "rate", "--latitude-deg", "45"],
        ),
        (
            "gyro-positions",
            vec!["gyro-positions", "--samples", "4"],
            vec![
                "gyro",
                "positions",
                "--latitude-deg",
                "45",
                "--azimuth-deg",
                "90",
                "--k1",
                "0.02",
                "--axial",
                "sa",
            ],
        ),
        (
            "noise",
            vec![
                "noise",
                "--duration-s",
                "200",
                "--rate-hz",
                "100",
                "--seed",
                "3",
                "--format",
                "csv",
            ],
            vec!["noise", "--rate-hz", "100"],
        ),
        (
            "imu-ferraris",
            vec![
                "imu",
                "--sequence",
                "ferraris",
                "--static-s",
                "0.5",
                "--rotation-s",
                "1",
            ],
            vec!["imu", "ferraris", "--rate-hz", "100"],
        ),
        (
            "imu-multipos",
            vec![
                "imu",
                "--sequence",
                "positions",
                "--static-s",
                "0.3",
                "--rotations",
            ],
            vec!["imu", "multipos", "--rate-hz", "100"],
        ),
        (
            "imu-autocal",
            vec![
                "imu",
                "--sequence",
                "random",
                "--orientations",
                "12",
                "--init-static-s",
                "3",
                "--static-s",
                "2",
                "--move-s",
                "1.5",
            ],
            vec!["imu", "autocal", "--rate-hz", "100", "--init-static-s", "3"],
        ),
    ]
}

/// The text of the element with `id`, if any.
fn text_of(page: &Html, id: &str) -> Option<String> {
    page.select(&sel(&format!("#{id}")))
        .next()
        .map(|e| e.text().collect::<String>())
}

/// Headless Chromium and poppler's tools, when installed (the PDF checks
/// below need both; `INCAL_REQUIRE_CHROMIUM=1` makes their absence a
/// failure, as scripts/test.sh sets it after installing them).
fn browser() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser"].into_iter().find(|b| {
        Command::new(b)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    });
    let poppler = Command::new("pdftoppm").arg("-v").output().is_ok();
    if found.is_none() || !poppler {
        assert!(
            std::env::var("INCAL_REQUIRE_CHROMIUM").is_err(),
            "INCAL_REQUIRE_CHROMIUM is set but chromium or pdftoppm is missing"
        );
        eprintln!("certificate PDF checks skipped: chromium or pdftoppm is not installed");
        return None;
    }
    found
}

/// A certificate for every procedure carries every item of ISO/IEC 17025
/// §7.8.2.1 (a to p); printed by headless Chromium (when
/// installed) every page carries the number and "page x of y", a tumble
/// certificate fits in three A4 pages with the results on page 1, and
/// every page renders to PNG.
#[test]
fn a_certificate_for_every_procedure_states_what_17025_asks() {
    let dir = workdir("certificates");
    std::fs::write(dir.join("lab.toml"), LAB_TOML).unwrap();
    std::fs::write(
        dir.join("limits.toml"),
        "rule = \"guard-band\"\n[tumble]\nK1 = { min = 9.9, max = 10.1 }\n",
    )
    .unwrap();
    let pdf = browser().is_some();
    for (procedure, sim, reduce) in all_procedures() {
        let csv = format!("{procedure}.csv");
        let json = format!("{procedure}.json");
        let mut args = vec!["simulate"];
        args.extend_from_slice(&sim);
        args.extend_from_slice(&["-o", &csv]);
        ok(&run_in(&dir, &args));
        let mut args = reduce.clone();
        args.extend_from_slice(&["--input", &csv, "--json", "--serial", "SN-7", "-o", &json]);
        ok(&run_in(&dir, &args));
        let html = format!("{procedure}.html");
        let mut args = vec![
            "report",
            &json,
            "--lab",
            "lab.toml",
            "--customer",
            "Acme <Navigation>",
            "--date",
            "2026-11-20",
            "--environment",
            "23.1 +- 0.4 degC",
            "-o",
            &html,
        ];
        if procedure == "tumble" {
            args.extend_from_slice(&["--limits", "limits.toml"]);
        }
        if pdf {
            args.push("--pdf");
        }
        ok(&run_in(&dir, &args));
        let text = std::fs::read_to_string(dir.join(&html)).unwrap();
        assert_self_contained(procedure, &text);
        let page = Html::parse_document(&text);
        let item = |id: &str| {
            text_of(&page, id).unwrap_or_else(|| panic!("{procedure}: no #{id} on the certificate"))
        };
        // §7.8.2.1 a-p, item by item.
        assert_eq!(item("lab-name"), "Inertial Test Laboratory", "{procedure}");
        assert!(item("lab-address").contains("Tianjin"), "{procedure}");
        assert!(item("lab-accreditation").contains("CNAS"), "{procedure}");
        let number = item("certificate-number");
        assert!(
            number.starts_with("ITL-") && number.len() == 16,
            "{procedure}: {number}"
        );
        assert!(
            item("customer").contains("Acme <Navigation>"),
            "{procedure}: escaped, shown"
        );
        assert!(item("item").contains("serial SN-7"), "{procedure}");
        let method = item("method");
        assert!(
            method.len() > 60 && !method.to_lowercase().contains("seed"),
            "{procedure}: {method}"
        );
        assert!(
            item("calibration-date").contains("2026-11-20"),
            "{procedure}"
        );
        assert!(item("issue-date").len() >= 10, "{procedure}");
        assert!(item("environment").contains("23.1"), "{procedure}");
        assert!(
            item("uncertainty-statement").contains("JCGM 100"),
            "{procedure}"
        );
        let trace = item("traceability");
        match procedure {
            "noise" | "imu-autocal" => assert!(trace.contains("no reference standard"), "{trace}"),
            // No centrifuge standard in the profile: said, not hidden.
            "centrifuge" => assert!(trace.contains("traceability is not stated"), "{trace}"),
            p if [
                "misalign-gyro",
                "misalign-accel",
                "gyro-rate",
                "imu-ferraris",
            ]
            .contains(&p) =>
            {
                assert!(
                    trace.contains("RT-02") && trace.contains("overdue"),
                    "{p}: {trace}"
                )
            }
            _ => assert!(
                trace.contains("DH-01") && !trace.contains("overdue"),
                "{procedure}: {trace}"
            ),
        }
        assert!(item("relate-only").contains("relate only to the item calibrated"));
        assert!(item("authorisation").contains("Li Wei"), "{procedure}");
        assert!(item("end-of-certificate").contains(&number), "{procedure}");
        assert!(item("conformity").contains("conformity"), "{procedure}");
        if procedure == "tumble" {
            assert!(
                item("decision-rule").contains("ILAC-G8"),
                "guard band stated"
            );
            assert!(
                item("conformity").contains("limits.toml"),
                "specification named"
            );
        }
        // Results before the annexes; no section holds only its heading.
        assert!(text.find("id=\"coefficients\"") < text.find("id=\"annex-inputs\""));
        let css: String = page.select(&sel("style")).flat_map(|s| s.text()).collect();
        assert!(
            css.contains("counter(page)") && css.contains("counter(pages)"),
            "page x of y"
        );
        assert!(
            css.contains(&format!("Certificate {number}")),
            "number on every page"
        );

        if pdf {
            let pdf_path = dir.join(format!("{procedure}.pdf"));
            let out = Command::new("pdftotext")
                .args(["-layout", pdf_path.to_str().unwrap(), "-"])
                .output()
                .unwrap();
            let all = String::from_utf8_lossy(&out.stdout).to_string();
            let pages: Vec<&str> = all
                .split('\u{c}')
                .filter(|p| !p.trim().is_empty())
                .collect();
            let n = pages.len();
            for (k, p) in pages.iter().enumerate() {
                assert!(
                    p.contains(&format!("page {} of {n}", k + 1)),
                    "{procedure} page {}",
                    k + 1
                );
                assert!(p.contains(&number), "{procedure}: number on page {}", k + 1);
                // No page that holds only a heading and the page furniture.
                assert!(
                    p.lines().filter(|l| !l.trim().is_empty()).count() > 4,
                    "{procedure} page {}",
                    k + 1
                );
            }
            if procedure == "tumble" {
                assert!(n <= 3, "tumble certificate: {n} A4 pages");
                assert!(pages[0].contains("K1") && pages[0].contains("Authorised by"));
            }
            let prefix = dir.join(format!("{procedure}-page"));
            let st = Command::new("pdftoppm")
                .args([
                    "-r",
                    "40",
                    "-png",
                    pdf_path.to_str().unwrap(),
                    prefix.to_str().unwrap(),
                ])
                .status()
                .unwrap();
            assert!(st.success(), "{procedure}: PNG");
            let pngs = std::fs::read_dir(&dir)
                .unwrap()
                .filter_map(Result::ok)
                .filter(|e| {
                    let name = e.file_name().to_string_lossy().to_string();
                    name.starts_with(&format!("{procedure}-page")) && name.ends_with(".png")
                })
                .filter(|e| e.metadata().is_ok_and(|m| m.len() > 1000))
                .count();
            assert_eq!(pngs, n, "{procedure}: one PNG per page");
        }
    }
}

#[test]
fn a_bad_lab_profile_or_date_is_refused_at_its_line() {
    let dir = workdir("bad-lab");
    ok(&run_in(
        &dir,
        &["simulate", "tumble", "--samples", "3", "-o", "t.csv"],
    ));
    ok(&run_in(
        &dir,
        &[
            "tumble", "--mount", "pendulum", "--input", "t.csv", "--json", "-o", "t.json",
        ],
    ));
    std::fs::write(
        dir.join("lab.toml"),
        LAB_TOML.replace("rig = \"rate-table\"", "rig = \"rate table\""),
    )
    .unwrap();
    let o = run_in(&dir, &["report", "t.json", "--lab", "lab.toml"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("lab.toml: line 18: [[standard]] rig: 'rate table' is not a rig"),
        "{e}"
    );
    std::fs::write(dir.join("lab.toml"), LAB_TOML).unwrap();
    let o = run_in(
        &dir,
        &[
            "report",
            "t.json",
            "--lab",
            "lab.toml",
            "--date",
            "2026-02-30",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--date: '2026-02-30' is not a date YYYY-MM-DD"));
    // Without --date nor a record, the date of calibration says it is missing.
    let html = ok(&run_in(&dir, &["report", "t.json", "--lab", "lab.toml"]));
    let page = Html::parse_document(&html);
    assert!(text_of(&page, "calibration-date")
        .unwrap()
        .contains("not stated"));
    // The same document always gets the same number.
    let again = ok(&run_in(&dir, &["report", "t.json", "--lab", "lab.toml"]));
    assert_eq!(
        text_of(&page, "certificate-number"),
        text_of(&Html::parse_document(&again), "certificate-number")
    );
}

/// A stored result gets its record's number and calibration date; a
/// correction says which certificate it replaces and why.
#[test]
fn a_stored_certificate_is_numbered_by_its_record_and_a_correction_says_what_it_replaces() {
    let dir = workdir("stored-certificate");
    std::fs::write(dir.join("lab.toml"), LAB_TOML).unwrap();
    for (seed, file) in [("1", "a"), ("2", "b")] {
        ok(&run_in(
            &dir,
            &[
                "simulate",
                "tumble",
                "--samples",
                "3",
                "--seed",
                seed,
                "-o",
                &format!("{file}.csv"),
            ],
        ));
        ok(&run_in(
            &dir,
            &[
                "tumble",
                "--mount",
                "pendulum",
                "--input",
                &format!("{file}.csv"),
                "--serial",
                "SN-9",
                "--json",
                "-o",
                &format!("{file}.json"),
            ],
        ));
    }
    ok(&run_in(
        &dir,
        &[
            "record",
            "add",
            "a.json",
            "--db",
            "s.db",
            "--created-utc",
            "2026-10-01T09:00:00Z",
        ],
    ));
    ok(&run_in(
        &dir,
        &[
            "record",
            "supersede",
            "1",
            "b.json",
            "--db",
            "s.db",
            "--reason",
            "wrong mount entered",
            "--created-utc",
            "2026-10-02",
        ],
    ));
    let html = ok(&run_in(
        &dir,
        &["report", "b.json", "--lab", "lab.toml", "--db", "s.db"],
    ));
    let page = Html::parse_document(&html);
    assert_eq!(text_of(&page, "certificate-number").unwrap(), "ITL-000002");
    assert!(text_of(&page, "calibration-date")
        .unwrap()
        .contains("2026-10-02"));
    let r = text_of(&page, "replaces").unwrap();
    assert!(
        r.contains("ITL-000001") && r.contains("wrong mount entered"),
        "{r}"
    );
    // The first record's certificate replaces nothing.
    let html = ok(&run_in(
        &dir,
        &[
            "report",
            "a.json",
            "--lab",
            "lab.toml",
            "--db",
            "s.db",
            "--date",
            "2026-09-30",
        ],
    ));
    let page = Html::parse_document(&html);
    assert_eq!(text_of(&page, "certificate-number").unwrap(), "ITL-000001");
    assert!(text_of(&page, "replaces").is_none());
    assert!(text_of(&page, "calibration-date")
        .unwrap()
        .contains("2026-09-30 (as given)"));
}
