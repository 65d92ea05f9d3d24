//! `incal thermal fit|ramp|apply`, `incal simulate thermal`, `incal plan
//! thermal` and `incal export px4|ardupilot MODEL.json` from outside: the
//! command-line interface (options, outputs, exit codes), and bad input
//! refused in one line.

use crate::common;

use common::*;

fn ramp_model(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let csv = dir.join("ramp.csv");
    let truth = dir.join("truth.json");
    ok(&run(&[
        "simulate",
        "thermal",
        "--seed",
        "4",
        "--rate-hz",
        "1",
        "--hold-s",
        "600",
        "--ramp-c-per-min",
        "2",
        "--temperature-noise-c",
        "0.01",
        "--truth-out",
        p(&truth),
        "-o",
        p(&csv),
    ]));
    let model = dir.join("model.json");
    ok(&run(&[
        "thermal",
        "ramp",
        "--input",
        p(&csv),
        "--rate-hz",
        "1",
        "--quantity",
        "gyro",
        "--json",
        "-o",
        p(&model),
    ]));
    (csv, model)
}

#[test]
fn a_simulated_ramp_reduces_to_the_contract_and_compensates() {
    let dir = workdir("thermal_ramp");
    let (csv, model) = ramp_model(&dir);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(v["procedure"], "thermal");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    for ch in ["gx", "gy", "gz"] {
        let t = &v["thermal"][ch];
        let d = t["degree"].as_u64().unwrap();
        assert_eq!(t["t_ref_c"], 25.0);
        assert!(t["t_min_c"].as_f64().unwrap() < -19.0);
        assert!(t["t_max_c"].as_f64().unwrap() > 59.0);
        assert!(t["hysteresis"]["u"].as_f64().unwrap() > 0.0);
        for k in 0..=d {
            let c = &v["coefficients"][format!("{ch}.c{k}")];
            assert!(c["value"].is_f64(), "{ch}.c{k}");
        }
        assert_eq!(v["coefficients"][format!("{ch}.c1")]["unit"], "deg/s/degC");
        let c1 = v["coefficients"][format!("{ch}.c1")]["value"]
            .as_f64()
            .unwrap();
        let t1 = truth["channels"][ch]["c"][1].as_f64().unwrap();
        assert!(
            (c1 - t1).abs() < 5.0 * v["coefficients"][format!("{ch}.c1")]["u"].as_f64().unwrap()
        );
    }
    assert!(v["lag"]["value"].as_f64().unwrap() > 100.0);
    assert!(v["correlation"]["names"].as_array().unwrap().len() >= 9);

    let out = dir.join("comp.csv");
    let o = run(&[
        "thermal",
        "apply",
        p(&model),
        "--input",
        p(&csv),
        "-o",
        p(&out),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let raw = std::fs::read_to_string(&csv).unwrap();
    let comp = std::fs::read_to_string(&out).unwrap();
    assert_eq!(raw.lines().next(), comp.lines().next(), "same header");
    assert_eq!(raw.lines().count(), comp.lines().count(), "every row");

    // The text form shows the coefficients with their units.
    let text = ok(&run(&[
        "thermal",
        "ramp",
        "--input",
        p(&csv),
        "--rate-hz",
        "1",
        "--quantity",
        "gyro",
    ]));
    assert!(
        text.contains("gx.c1") && text.contains("deg/s/degC"),
        "{text}"
    );
}

#[test]
fn the_exports_write_the_flight_stacks_parameters() {
    let dir = workdir("thermal_export");
    let (_, model) = ramp_model(&dir);
    let px4 = ok(&run(&["export", "px4", p(&model), "--device-id", "3"]));
    for name in [
        "TC_G_ENABLE",
        "TC_G0_ID",
        "TC_G0_TMIN",
        "TC_G0_TMAX",
        "TC_G0_TREF",
        "TC_G0_X3_2",
    ] {
        assert!(
            px4.lines().any(|l| l.split('\t').nth(2) == Some(name)),
            "{name}: {px4}"
        );
    }
    let ap = ok(&run(&["export", "ardupilot", p(&model), "--imu", "2"]));
    for name in [
        "INS_TCAL2_ENABLE,1",
        "INS_TCAL2_TMIN,",
        "INS_TCAL2_GYR1_X,",
        "INS_TCAL2_GYR3_Z,",
    ] {
        assert!(ap.lines().any(|l| l.starts_with(name)), "{name}: {ap}");
    }
    // Axes that are not in the model are named.
    refused(
        &run(&["export", "px4", p(&model), "--axes", "a,b,c"]),
        &["model.json", "a"],
    );
    // A model with no flight-stack unit is refused.
    let csv = dir.join("ramp.csv");
    let generic = dir.join("generic.json");
    ok(&run(&[
        "thermal",
        "ramp",
        "--input",
        p(&csv),
        "--rate-hz",
        "1",
        "--json",
        "-o",
        p(&generic),
    ]));
    refused(
        &run(&["export", "ardupilot", p(&generic)]),
        &["generic.json", "unit"],
    );
    // The noise form of export px4 still needs both results.
    assert_eq!(run(&["export", "px4"]).status.code(), Some(2));
}

/// A tumble recording with a temperature_c column at `t_c`.
fn tumble_at(dir: &std::path::Path, seed: u64, t_c: f64) -> std::path::PathBuf {
    let o = run(&[
        "simulate",
        "tumble",
        "--mount",
        "pendulum",
        "--seed",
        &seed.to_string(),
    ]);
    let text = ok(&o);
    let mut lines = text.lines();
    let mut s = format!("{},temperature_c\n", lines.next().unwrap());
    for l in lines {
        s.push_str(&format!("{l},{t_c}\n"));
    }
    let csv = dir.join(format!("tumble_{seed}.csv"));
    std::fs::write(&csv, s).unwrap();
    let json = dir.join(format!("tumble_{seed}.json"));
    ok(&run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        p(&csv),
        "--serial",
        "A7",
        "--json",
        "-o",
        p(&json),
    ]));
    json
}

#[test]
fn soak_results_fit_into_polynomials_per_coefficient() {
    let dir = workdir("thermal_fit");
    let temps = [-20.0, 5.0, 25.0, 45.0, 70.0];
    let docs: Vec<_> = temps
        .iter()
        .enumerate()
        .map(|(i, &t)| tumble_at(&dir, 30 + i as u64, t))
        .collect();
    let first: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&docs[0]).unwrap()).unwrap();
    assert_eq!(first["environment"]["temperature_c"]["mean"], -20.0);
    let mut args = vec!["thermal", "fit"];
    args.extend(docs.iter().map(|d| p(d)));
    args.extend(["--t-ref-c", "-5", "--json"]);
    let v = json_of(&run(&args));
    assert_eq!(v["procedure"], "thermal");
    assert_eq!(v["instrument"]["serial"], "A7");
    let th = v["thermal"].as_object().unwrap();
    for name in ["K0", "K1"] {
        let e = &th[name];
        assert_eq!(e["t_min_c"], -20.0);
        assert_eq!(e["t_max_c"], 70.0);
        assert_eq!(e["t_ref_c"], -5.0);
        assert!(e["degree"].as_u64().unwrap() <= 3);
        assert!(v["coefficients"][format!("{name}.c0")]["value"].is_f64());
    }
    // A degree the plateaus cannot give is refused naming the term.
    let mut args = vec!["thermal", "fit"];
    args.extend(docs[..3].iter().map(|d| p(d)));
    args.extend(["--degree", "3"]);
    refused(&run(&args), &["K0.c3"]);
    // A result without a temperature is refused naming the file.
    let bare = dir.join("bare.json");
    let mut doc = first.clone();
    doc.as_object_mut().unwrap().remove("environment");
    std::fs::write(&bare, doc.to_string()).unwrap();
    refused(
        &run(&["thermal", "fit", p(&bare), p(&docs[1])]),
        &["bare.json", "temperature_c"],
    );
}

#[test]
fn plans_and_bad_input_are_answered_in_one_line() {
    let o = ok(&run(&[
        "plan",
        "thermal",
        "--plateaus-c",
        "-40,-10,25,60,85",
        "--u",
        "1e-5",
        "--degree",
        "2",
    ]));
    assert!(o.contains("c2"), "{o}");
    refused(
        &run(&[
            "plan",
            "thermal",
            "--plateaus-c",
            "-40,25,85",
            "--u",
            "1e-5",
            "--degree",
            "3",
        ]),
        &["c3"],
    );
    let dir = workdir("thermal_bad");
    let bad = dir.join("no_temp.csv");
    std::fs::write(&bad, "time_s,gx\n0,1\n1,2\n").unwrap();
    refused(
        &run(&["thermal", "ramp", "--input", p(&bad), "--rate-hz", "1"]),
        &["no_temp.csv", "temperature_c"],
    );
    let text = dir.join("text.csv");
    std::fs::write(&text, "temperature_c,gx\n20,1\nhot,2\n").unwrap();
    refused(
        &run(&["thermal", "ramp", "--input", p(&text), "--rate-hz", "1"]),
        &["text.csv:3", "temperature_c"],
    );
}

#[test]
fn history_keeps_one_temperature_when_asked_and_says_when_it_mixes() {
    let dir = workdir("thermal_history");
    let db = dir.join("t.db");
    for (i, (t, date)) in [
        (-20.0, "2026-01-05"),
        (25.0, "2026-02-05"),
        (70.0, "2026-03-05"),
        (25.0, "2026-04-05"),
    ]
    .iter()
    .enumerate()
    {
        let f = tumble_at(&dir, 50 + i as u64, *t);
        ok(&run(&[
            "record",
            "add",
            p(&f),
            "--db",
            p(&db),
            "--created-utc",
            date,
        ]));
    }
    let all = json_of(&run(&[
        "record",
        "history",
        "--serial",
        "A7",
        "--coefficient",
        "K1",
        "--db",
        p(&db),
        "--json",
    ]));
    assert_eq!(all["points"].as_array().unwrap().len(), 4);
    assert_eq!(all["points"][0]["temperature_c"], -20.0);
    assert!(
        all["notes"].to_string().contains("-20 to 70 degC"),
        "{}",
        all["notes"]
    );
    let at25 = json_of(&run(&[
        "record",
        "history",
        "--serial",
        "A7",
        "--coefficient",
        "K1",
        "--db",
        p(&db),
        "--at-temperature-c",
        "25",
        "--json",
    ]));
    let pts = at25["points"].as_array().unwrap();
    assert_eq!(pts.len(), 2);
    assert!(pts.iter().all(|p| p["temperature_c"] == 25.0));
    refused(
        &run(&[
            "record",
            "history",
            "--serial",
            "A7",
            "--coefficient",
            "K1",
            "--db",
            p(&db),
            "--at-temperature-c",
            "-40",
        ]),
        &["within 2 degC of -40"],
    );
}

/// `plan thermal --json` is an `incal.plan/1` document that validates
/// against the checked-in plan schema, soak and ramp alike, and its run
/// sheet lists the plateaus or the set points in order.
#[test]
fn thermal_plans_are_schema_valid_plan_documents_with_run_sheets() {
    let dir = workdir("thermal_plan_doc");
    let schema: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../schema/plan.schema.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let soak = [
        "plan",
        "thermal",
        "--plateaus-c",
        "-40,-10,25,60,85",
        "--u",
        "2e-6",
        "--degree",
        "2",
        "--json",
        "--run-sheet",
        "soak.csv",
    ];
    let ramp = [
        "plan",
        "thermal",
        "--ramp-c-per-min",
        "1",
        "--noise",
        "0.02",
        "--degree",
        "2",
        "--rate-hz",
        "10",
        "--json",
        "--run-sheet",
        "ramp.csv",
    ];
    for (args, kind, terms) in [
        (&soak[..], "thermal-plateaus", 3),
        (&ramp[..], "thermal-ramp", 4),
    ] {
        let v = json_of(&run_in(&dir, args));
        assert!(
            validator.is_valid(&v),
            "{kind}: not a valid incal.plan/1: {v}"
        );
        assert_eq!(v["schema"], "incal.plan/1");
        assert_eq!(v["procedure"], "thermal");
        assert_eq!(v["plan"], kind);
        let u = v["predicted_u"].as_object().unwrap();
        assert_eq!(u.len(), terms, "{kind}: {u:?}");
        assert_eq!(v["predicted_U95"].as_object().unwrap().len(), terms);
        assert!(v["predicted_dof"].as_f64().unwrap() >= 1.0);
    }
    let soak_sheet = std::fs::read_to_string(dir.join("soak.csv")).unwrap();
    assert_eq!(
        soak_sheet,
        "step,plateau_c,samples\n1,-40,1\n2,-10,1\n3,25,1\n4,60,1\n5,85,1\n"
    );
    let ramp_sheet = std::fs::read_to_string(dir.join("ramp.csv")).unwrap();
    assert!(
        ramp_sheet
            .starts_with("step,set_point_c,ramp_c_per_min,hold_s,samples\n1,-20,1,1800,1\n2,60,"),
        "{ramp_sheet}"
    );
    // A ramp plan needs its noise: the option is named.
    refused(
        &run(&["plan", "thermal", "--ramp-c-per-min", "1", "--degree", "2"]),
        &["--noise"],
    );
}

/// `incal batch` reduces chamber ramps, by the registry id or by the
/// document id, each result equal to the one-file run.
#[test]
fn batch_reduces_thermal_ramps() {
    let dir = workdir("thermal_batch");
    std::fs::create_dir_all(dir.join("ramps")).unwrap();
    for seed in ["1", "2"] {
        let out = format!("ramps/r{seed}.csv");
        ok(&run_in(
            &dir,
            &[
                "simulate",
                "thermal",
                "--seed",
                seed,
                "--t-low-c",
                "20",
                "--t-high-c",
                "40",
                "--ramp-c-per-min",
                "20",
                "--hold-s",
                "30",
                "--lag-s",
                "5",
                "--rate-hz",
                "1",
                "-o",
                &out,
            ],
        ));
    }
    for id in ["thermal-ramp", "thermal"] {
        let v = json_of(&run_in(
            &dir,
            &["batch", id, "ramps", "--json", "--", "--rate-hz", "1"],
        ));
        assert_eq!(v["procedure"], "thermal-ramp", "{id}");
        assert_eq!(v["ok"], 2, "{id}: {v}");
        let one = json_of(&run_in(
            &dir,
            &[
                "thermal",
                "ramp",
                "--input",
                "ramps/r1.csv",
                "--rate-hz",
                "1",
                "--json",
            ],
        ));
        assert_eq!(v["results"][0]["result"], one, "{id}");
    }
    refused(
        &run_in(&dir, &["batch", "thermal-fit", "ramps"]),
        &["thermal-fit", "is not a procedure", "thermal-ramp"],
    );
}
