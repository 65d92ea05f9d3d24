//! `incal warmup`, `incal plan warmup` and `incal simulate warmup` from
//! outside: the contract keys and units, limits by name, and bad input
//! refused in one line naming the file, the line or the option.

use crate::common;

use common::*;

fn small(dir: &std::path::Path) -> std::path::PathBuf {
    let csv = dir.join("warmup.csv");
    ok(&run(&[
        "simulate",
        "warmup",
        "--duration-s",
        "900",
        "--rate-hz",
        "1",
        "--tau-s",
        "100",
        "--seed",
        "5",
        "-o",
        p(&csv),
    ]));
    csv
}

#[test]
fn a_simulated_warmup_reduces_to_the_contract() {
    let dir = workdir("warmup_contract");
    let csv = small(&dir);
    let limits = dir.join("limits.toml");
    std::fs::write(
        &limits,
        "[warmup]\nsettling_time_s = { max = 1800 }\ntau_s = { max = 10 }\n",
    )
    .unwrap();
    let v = json_of(&run(&[
        "warmup",
        "--input",
        p(&csv),
        "--json",
        "--limits",
        p(&limits),
    ]));
    assert_eq!(v["procedure"], "warmup");
    for (name, unit) in [
        ("bias_settled", "output"),
        ("amplitude", "output"),
        ("tau_s", "s"),
        ("settling_time_s", "s"),
        ("warmup_drift", "output"),
        ("turn_on_time_s", "s"),
    ] {
        assert_eq!(v["coefficients"][name]["unit"], unit, "{name}");
    }
    let t = v["coefficients"]["turn_on_time_s"]["value"]
        .as_f64()
        .unwrap();
    assert!((1.0..=4.0).contains(&t), "turn-on {t}");
    let tau = v["coefficients"]["tau_s"]["value"].as_f64().unwrap();
    assert!((80.0..=120.0).contains(&tau), "tau {tau}");
    assert_eq!(v["warmup"]["shape"], "exp1");
    assert_eq!(v["verdict"], "fail", "tau_s over its limit of 10 s");
    let s = serde_json::to_string(&v["verdicts"]).unwrap();
    assert!(s.contains("settling_time_s") && s.contains("tau_s"), "{s}");
    let plan = json_of(&run(&[
        "plan",
        "warmup",
        "--duration-s",
        "900",
        "--tau-s",
        "100",
        "--rate-hz",
        "1",
        "--json",
    ]));
    assert!(plan["predicted_u"]["tau_s"].as_f64().unwrap() > 0.0);
}

#[test]
fn bad_input_is_refused_in_one_line() {
    let dir = workdir("warmup_bad");
    let f = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let mut gap = String::from("time_s,output\n");
    for k in 0..40 {
        let t = if k < 30 { k } else { k + 5 };
        gap.push_str(&format!("{t},{}\n", 1.0 + (k as f64 * 0.3).sin() * 0.01));
    }
    let gap = f("gap.csv", &gap);
    refused(
        &run(&["warmup", "--input", p(&gap)]),
        &["gap.csv", "line 32", "gap"],
    );
    let text = f("text.csv", "time_s,output\n0,1\n1,abc\n");
    refused(
        &run(&["warmup", "--input", p(&text)]),
        &["text.csv:3", "output", "not a number"],
    );
    let none = f("none.csv", "time_s,signal\n0,1\n");
    refused(
        &run(&["warmup", "--input", p(&none)]),
        &["none.csv", "output"],
    );
    let csv = small(&dir);
    refused(
        &run(&["warmup", "--input", p(&csv), "--settle-band", "-1"]),
        &["settle-band"],
    );
    refused(
        &run(&[
            "warmup",
            "--input",
            p(&csv),
            "--valid-min",
            "2",
            "--valid-max",
            "1",
        ]),
        &["valid-min", "not below"],
    );
    refused(
        &run(&["warmup", "--input", p(&csv), "--power-on-s", "5000"]),
        &["power_on_s"],
    );
    refused(
        &run(&["plan", "warmup", "--duration-s", "200", "--tau-s", "100"]),
        &["duration-s", "3 tau"],
    );
    refused(&run(&["simulate", "warmup", "--tau-s", "0"]), &["tau-s"]);
}
