//! `incal repeatability` from outside: result documents and the records
//! store (`--db --serial --procedure --coefficient`) give the same runs,
//! the day from `--meta day=` or the record's date, and bad input is
//! refused in one line naming the file, the line or the document.

use crate::common;

use common::*;

/// Six gyro rate results of serial G7: two turn-ons on each of three days.
fn results(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for d in 1..=3 {
        for t in 1..=2 {
            let csv = dir.join(format!("r{d}{t}.csv"));
            let json = dir.join(format!("r{d}{t}.json"));
            let seed = (10 * d + t).to_string();
            let b = (3 * d + t).to_string();
            ok(&run(&[
                "simulate",
                "gyro-rate",
                "--seed",
                &seed,
                "--b-deg-h",
                &b,
                "-o",
                p(&csv),
            ]));
            let day = format!("day=2026-11-0{d}");
            ok(&run(&[
                "gyro",
                "rate",
                "--input",
                p(&csv),
                "--latitude-deg",
                "45",
                "--serial",
                "G7",
                "--meta",
                &day,
                "--json",
                "-o",
                p(&json),
            ]));
            out.push(json);
        }
    }
    out
}

#[test]
fn documents_and_the_store_give_the_same_components() {
    let dir = workdir("repeat_store");
    let files = results(&dir);
    let db = dir.join("lab.db");
    for f in &files {
        ok(&run(&["record", "add", p(f), "--db", p(&db)]));
    }
    let mut args = vec!["repeatability", "--coefficient", "B", "--json"];
    args.extend(files.iter().map(|f| p(f)));
    let a = json_of(&run(&args));
    let b = json_of(&run(&[
        "repeatability",
        "--db",
        p(&db),
        "--serial",
        "G7",
        "--procedure",
        "gyro-rate",
        "--coefficient",
        "B",
        "--json",
    ]));
    assert_eq!(a["procedure"], "repeatability");
    for name in [
        "mean",
        "turn_on_repeatability",
        "day_repeatability",
        "repeatability_simple",
    ] {
        let (x, y) = (&a["coefficients"][name], &b["coefficients"][name]);
        assert_eq!(x["value"], y["value"], "{name}");
        assert_eq!(x["unit"], "deg/h", "{name}");
    }
    assert_eq!(b["repeatability"]["days"].as_array().unwrap().len(), 3);
    assert_eq!(b["inputs"].as_array().unwrap().len(), 6);
    // The runs read from documents are drawn again by the Monte Carlo.
    let mc_options = [
        "--coefficient",
        "B",
        "--json",
        "--monte-carlo",
        "200",
        "--seed",
        "4",
    ];
    let mut args = vec!["repeatability"];
    args.extend(mc_options);
    args.extend(files.iter().map(|f| p(f)));
    let m = json_of(&run(&args));
    let mc = &m["monte_carlo"];
    assert_eq!(mc["trials"], 200);
    assert!(mc["coefficients"]["mean"]["std"].as_f64().unwrap() > 0.0);
    assert_eq!(m["coefficients"]["mean"], a["coefficients"]["mean"]);
    // Options after the files are options, not files.
    let mut after = vec!["repeatability"];
    after.extend(files.iter().map(|f| p(f)));
    after.extend(mc_options);
    assert_eq!(json_of(&run(&after))["monte_carlo"], m["monte_carlo"]);
}

#[test]
fn bad_input_is_refused_in_one_line() {
    let dir = workdir("repeat_bad");
    let f = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let neg = f("neg.csv", "day,value,u\na,1,0.1\na,1.1,-0.1\nb,1,0.1\n");
    refused(
        &run(&["repeatability", "--input", p(&neg)]),
        &["neg.csv", "u", "positive"],
    );
    let few = f("few.csv", "value,u\n1,0.1\n1.2,0.1\n");
    refused(
        &run(&["repeatability", "--input", p(&few)]),
        &["few.csv", "turn-on level", "2 runs"],
    );
    let days = f("days.csv", "day,value,u\na,1,0.1\na,1.1,0.1\nb,1,0.1\n");
    refused(
        &run(&["repeatability", "--input", p(&days)]),
        &["days.csv", "day level", "a, b"],
    );
    let files = results(&dir);
    refused(
        &run(&[
            "repeatability",
            "--coefficient",
            "K0",
            p(&files[0]),
            p(&files[1]),
            p(&files[2]),
        ]),
        &["no coefficient 'K0'"],
    );
    refused(&run(&["repeatability"]), &["result documents"]);
}
