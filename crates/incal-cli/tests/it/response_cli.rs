//! `incal response sine`, `incal plan response-sine` and `incal simulate
//! response-sine` from outside: the contract keys and units, the run
//! sheet, and bad input refused in one line naming the file, the line or
//! dwell, or the option.

use crate::common;

use common::*;

const HEADER: &str = "time_s,freq_hz,reference,output\n";

/// A small recording: 4 dwells (2, 5, 10, 20 Hz) of 200 samples at 200 Hz.
fn small(dir: &std::path::Path) -> std::path::PathBuf {
    let csv = dir.join("sine.csv");
    ok(&run(&[
        "simulate",
        "response-sine",
        "--dwells-hz",
        "2,5,10,20",
        "--seconds-per-dwell",
        "1",
        "--rate-hz",
        "200",
        "--order",
        "first",
        "--corner-hz",
        "8",
        "--seed",
        "5",
        "-o",
        p(&csv),
    ]));
    csv
}

#[test]
fn a_simulated_sweep_reduces_to_the_contract() {
    let dir = workdir("response_contract");
    let csv = small(&dir);
    let v = json_of(&run(&[
        "response",
        "sine",
        "--input",
        p(&csv),
        "--flatness-to-hz",
        "5",
        "--json",
    ]));
    assert_eq!(v["procedure"], "response-sine");
    for (name, unit) in [
        ("k_dc", "output/reference"),
        ("fc_hz", "Hz"),
        ("delay_s", "s"),
        ("bandwidth_hz", "Hz"),
        ("latency_s", "s"),
        ("bandwidth_interp_hz", "Hz"),
        ("flatness_db", "dB"),
    ] {
        assert_eq!(v["coefficients"][name]["unit"], unit, "{name}");
    }
    let t = &v["tables"][0];
    assert_eq!(t["id"], "dwells");
    assert_eq!(t["rows"].as_array().unwrap().len(), 4);
    assert_eq!(v["bode"]["freq_hz"].as_array().unwrap().len(), 80);
    assert_eq!(v["options"]["drift"], "linear");
}

#[test]
fn the_plan_writes_its_run_sheet() {
    let dir = workdir("response_plan");
    let sheet = dir.join("sheet.csv");
    ok(&run(&[
        "plan",
        "response-sine",
        "--dwells-hz",
        "1,10,100,200",
        "--run-sheet",
        p(&sheet),
    ]));
    let s = std::fs::read_to_string(&sheet).unwrap();
    assert!(
        s.starts_with("step,freq_hz,seconds,cycles,amplitude"),
        "{s}"
    );
    assert_eq!(s.lines().count(), 5, "{s}");
}

#[test]
fn bad_input_is_refused_in_one_line() {
    let dir = workdir("response_bad");
    let f = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let missing = f("missing.csv", "time_s,freq_hz,output\n0,1,0\n");
    refused(
        &run(&["response", "sine", "--input", p(&missing)]),
        &["missing.csv", "missing column 'reference'"],
    );
    let text = f("text.csv", &format!("{HEADER}0,1,abc,0\n"));
    refused(
        &run(&["response", "sine", "--input", p(&text)]),
        &["text.csv:2:", "reference"],
    );
    let empty = f("empty.csv", HEADER);
    refused(
        &run(&["response", "sine", "--input", p(&empty)]),
        &["empty.csv", "no data rows"],
    );
    let back = f(
        "back.csv",
        &format!("{HEADER}0,1,0,0\n0.1,1,1,1\n0.05,1,0,0\n"),
    );
    refused(
        &run(&["response", "sine", "--input", p(&back)]),
        &["back.csv:4:", "before the row above"],
    );
    let zero = f("zero.csv", &format!("{HEADER}0,0,0,0\n"));
    refused(
        &run(&["response", "sine", "--input", p(&zero)]),
        &["zero.csv:2:", "not a positive frequency"],
    );
    let no_time = f("notime.csv", "freq_hz,reference,output\n1,0,0\n");
    refused(
        &run(&["response", "sine", "--input", p(&no_time)]),
        &["notime.csv", "rate_hz"],
    );
    let csv = small(&dir);
    refused(
        &run(&["response", "sine", "--input", p(&csv), "--harmonics", "0"]),
        &["--harmonics"],
    );
    refused(
        &run(&["response", "sine", "--input", p(&csv), "--u-k1", "0.1"]),
        &["--u-k1", "--k1"],
    );
    refused(
        &run(&["plan", "response-sine", "--dwells-hz", "1,10,600"]),
        &["--dwells-hz", "Nyquist"],
    );
    refused(
        &run(&["simulate", "response-sine", "--min-cycles", "1"]),
        &["--min-cycles"],
    );
}

#[test]
fn a_dwell_above_nyquist_in_a_recording_is_named_with_its_lines() {
    let dir = workdir("response_nyquist");
    let mut s = String::from(HEADER);
    for k in 0..40 {
        let t = k as f64 / 100.0;
        s.push_str(&format!(
            "{t},60,{},{}\n",
            (k as f64).sin(),
            (k as f64).cos()
        ));
    }
    let path = dir.join("fast.csv");
    std::fs::write(&path, s).unwrap();
    refused(
        &run(&["response", "sine", "--input", p(&path)]),
        &["fast.csv", "dwell 1 (60 Hz, lines 2-41)", "Nyquist"],
    );
}

#[test]
fn a_broadband_record_reduces_to_the_contract() {
    let dir = workdir("response_broadband");
    let csv = dir.join("bb.csv");
    ok(&run(&[
        "simulate",
        "response-broadband",
        "--duration-s",
        "8",
        "--seed",
        "3",
        "-o",
        p(&csv),
    ]));
    let v = json_of(&run(&[
        "response",
        "broadband",
        "--input",
        p(&csv),
        "--segment-samples",
        "512",
        "--json",
    ]));
    assert_eq!(v["procedure"], "response-broadband");
    for name in [
        "k_dc",
        "fn_hz",
        "zeta",
        "delay_s",
        "bandwidth_hz",
        "latency_s",
    ] {
        assert!(
            v["coefficients"][name]["U95"].as_f64().unwrap() > 0.0,
            "{name}"
        );
    }
    assert_eq!(v["tables"][0]["id"], "spectrum");
    assert_eq!(v["tables"][0]["rows"].as_array().unwrap().len(), 256);
    assert_eq!(v["welch"]["segment_samples"], 512);
    assert_eq!(v["options"]["align"], "latency");
}

#[test]
fn a_broadband_record_with_a_gap_or_a_contradicting_rate_is_refused() {
    let dir = workdir("response_broadband_bad");
    let mut s = String::from("time_s,reference,output\n");
    for k in 0..3000 {
        let t = if k < 1500 { k } else { k + 10 } as f64 / 1000.0;
        let x = ((k * 7919) % 1000) as f64 / 1000.0;
        s.push_str(&format!("{t},{x},{x}\n"));
    }
    let gap = dir.join("gap.csv");
    std::fs::write(&gap, &s).unwrap();
    refused(
        &run(&["response", "broadband", "--input", p(&gap)]),
        &["gap.csv", "line 1502", "gap"],
    );
    let csv = dir.join("bb.csv");
    ok(&run(&[
        "simulate",
        "response-broadband",
        "--duration-s",
        "3",
        "-o",
        p(&csv),
    ]));
    refused(
        &run(&[
            "response",
            "broadband",
            "--input",
            p(&csv),
            "--rate-hz",
            "500",
        ]),
        &["--rate-hz", "contradicts"],
    );
    refused(
        &run(&[
            "response",
            "broadband",
            "--input",
            p(&csv),
            "--segment-samples",
            "4096",
        ]),
        &["bb.csv", "segments of 4096"],
    );
    refused(
        &run(&["plan", "response-broadband", "--f-max-hz", "50"]),
        &["--f-max-hz", "bandwidth_hz is not determined"],
    );
}

#[test]
fn limits_judge_the_bandwidth_and_delay_and_the_report_draws_the_bode_plot() {
    let dir = workdir("response_limits");
    let csv = small(&dir);
    let limits = dir.join("limits.toml");
    std::fs::write(
        &limits,
        "[response-sine]\nbandwidth_hz = { min = 7 }\ndelay_s = { max = 0.003 }\n",
    )
    .unwrap();
    let doc = dir.join("r.json");
    ok(&run(&[
        "response",
        "sine",
        "--input",
        p(&csv),
        "--limits",
        p(&limits),
        "--json",
        "-o",
        p(&doc),
    ]));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&doc).unwrap()).unwrap();
    assert_eq!(v["verdicts"]["bandwidth_hz"]["verdict"], "pass");
    assert_eq!(v["verdicts"]["delay_s"]["verdict"], "pass");
    let html = dir.join("r.html");
    ok(&run(&["report", p(&doc), "-o", p(&html)]));
    let h = std::fs::read_to_string(&html).unwrap();
    assert!(h.contains("Frequency response: gain (dB)"), "no gain plot");
    assert!(
        h.contains("Frequency response: phase (deg)"),
        "no phase plot"
    );
}

#[test]
fn a_step_reduces_to_the_contract_and_bad_steps_are_refused() {
    let dir = workdir("response_step");
    let csv = dir.join("step.csv");
    ok(&run(&[
        "simulate",
        "response-step",
        "--seed",
        "4",
        "-o",
        p(&csv),
    ]));
    let v = json_of(&run(&["response", "step", "--input", p(&csv), "--json"]));
    assert_eq!(v["procedure"], "response-step");
    for (name, unit) in [
        ("delay_s", "s"),
        ("rise_time_s", "s"),
        ("settling_time_s", "s"),
        ("overshoot_pct", "%"),
        ("bandwidth_hz", "Hz"),
    ] {
        assert_eq!(v["coefficients"][name]["unit"], unit, "{name}");
    }
    assert_eq!(v["tables"][0]["id"], "step");
    assert!(v["step"]["u_t0_s"].as_f64().unwrap() > 0.0);
    let flat = dir.join("flat.csv");
    let mut s = String::from("time_s,reference,output\n");
    for k in 0..200 {
        s.push_str(&format!(
            "{},{},{}\n",
            k as f64 / 100.0,
            1.0,
            (k % 7) as f64
        ));
    }
    std::fs::write(&flat, s).unwrap();
    refused(
        &run(&["response", "step", "--input", p(&flat)]),
        &["flat.csv", "does not step"],
    );
    refused(
        &run(&[
            "plan",
            "response-step",
            "--corner-hz",
            "1",
            "--order",
            "first",
        ]),
        &["--duration-s", "settling_time_s is not determined"],
    );
}

#[test]
fn a_reference_clock_is_read_and_its_bad_stamps_are_refused() {
    let dir = workdir("response_clock");
    let csv = dir.join("clock.csv");
    ok(&run(&[
        "simulate",
        "response-sine",
        "--dwells-hz",
        "2,5,10,20",
        "--rate-hz",
        "200",
        "--reference-clock-offset-s",
        "0.003",
        "--order",
        "first",
        "--corner-hz",
        "8",
        "-o",
        p(&csv),
    ]));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("time_s,time_ref_s,freq_hz,reference,output"));
    let v = json_of(&run(&["response", "sine", "--input", p(&csv), "--json"]));
    let (d, u) = (
        v["coefficients"]["delay_s"]["value"].as_f64().unwrap(),
        v["coefficients"]["delay_s"]["U95"].as_f64().unwrap(),
    );
    assert!((d - 0.002).abs() <= u, "delay {d} ± {u}");
    let back = dir.join("back.csv");
    std::fs::write(
        &back,
        "time_s,time_ref_s,freq_hz,reference,output\n0,0.1,1,0,0\n0.01,0.05,1,1,1\n",
    )
    .unwrap();
    refused(
        &run(&["response", "sine", "--input", p(&back)]),
        &["back.csv:3:", "time_ref_s", "before the row above"],
    );
    let alone = dir.join("alone.csv");
    std::fs::write(&alone, "time_ref_s,freq_hz,reference,output\n0,1,0,0\n").unwrap();
    refused(
        &run(&["response", "sine", "--input", p(&alone), "--rate-hz", "100"]),
        &["alone.csv", "needs 'time_s'"],
    );
}

#[test]
fn dwells_are_found_without_freq_hz_and_a_shaker_is_traced_to_its_standards() {
    let dir = workdir("response_found");
    let csv = dir.join("found.csv");
    ok(&run(&[
        "simulate",
        "response-sine",
        "--dwells-hz",
        "3,8,20,50",
        "--seconds-per-dwell",
        "4",
        "--frequency-error-pct",
        "0.2",
        "--no-freq-column",
        "-o",
        p(&csv),
    ]));
    let head = std::fs::read_to_string(&csv).unwrap();
    assert!(
        head.starts_with("time_s,reference,output\n"),
        "no freq_hz column"
    );
    let doc = dir.join("r.json");
    ok(&run(&[
        "response",
        "sine",
        "--input",
        p(&csv),
        "--rig",
        "shaker",
        "--order",
        "second",
        "--json",
        "-o",
        p(&doc),
    ]));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&doc).unwrap()).unwrap();
    assert_eq!(v["options"]["rig"], "shaker");
    let t = &v["tables"][0];
    assert_eq!(t["id"], "dwells");
    let cols: Vec<&str> = t["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    let (fc, uc) = (
        cols.iter().position(|c| *c == "freq_hz").unwrap(),
        cols.iter().position(|c| *c == "u_freq_hz").unwrap(),
    );
    let rows = t["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4, "four dwells found");
    for (row, nominal) in rows.iter().zip([3.0, 8.0, 20.0, 50.0]) {
        let (f, u) = (row[fc].as_f64().unwrap(), row[uc].as_f64().unwrap());
        assert!(
            (f - 1.002 * nominal).abs() < 4.0 * u.max(1e-9),
            "{f} ± {u} for {nominal}"
        );
    }
    // The certificate lists the shaker's standard, not the rate table's.
    let lab = dir.join("lab.toml");
    std::fs::write(
        &lab,
        "[lab]\nname = \"L\"\naddress = \"A\"\naccreditation = \"C\"\ncertificate_prefix = \"X-\"\n\n[[signatory]]\nname = \"S\"\nrole = \"R\"\n\n[[standard]]\nrig = \"shaker\"\nid = \"Reference accelerometer RA-9\"\ncertificate = \"NIM-1\"\ndue = \"2030-01-01\"\n\n[[standard]]\nrig = \"rate-table\"\nid = \"Rate table RT-02\"\ncertificate = \"NIM-2\"\ndue = \"2030-01-01\"\n",
    )
    .unwrap();
    let html = dir.join("c.html");
    ok(&run(&["report", p(&doc), "--lab", p(&lab), "-o", p(&html)]));
    let h = std::fs::read_to_string(&html).unwrap();
    assert!(h.contains("RA-9") && !h.contains("RT-02"), "shaker traced");
    // A recording without freq_hz and without a held frequency: refused.
    let sweep = dir.join("sweep.csv");
    let mut text = String::from("time_s,reference,output\n");
    for i in 0..4000 {
        let t = i as f64 / 1000.0;
        let r = (std::f64::consts::TAU * (1.0 + 5.0 * t) * t).sin();
        text.push_str(&format!("{t},{r},{}\n", 0.9 * r));
    }
    std::fs::write(&sweep, text).unwrap();
    refused(
        &run(&["response", "sine", "--input", p(&sweep)]),
        &["sweep.csv", "no dwell found", "dwell_window_s"],
    );
    refused(
        &run(&[
            "response",
            "sine",
            "--input",
            p(&sweep),
            "--dwell-window-s",
            "0",
        ]),
        &["--dwell-window-s"],
    );
}

#[test]
fn broadband_and_step_records_read_the_reference_clock_and_refuse_a_drifting_one() {
    let dir = workdir("response_clocks");
    let bb = dir.join("bb.csv");
    ok(&run(&[
        "simulate",
        "response-broadband",
        "--duration-s",
        "10",
        "--excitation",
        "multisine",
        "--reference-clock-offset-s",
        "0.00037",
        "-o",
        p(&bb),
    ]));
    let text = std::fs::read_to_string(&bb).unwrap();
    assert!(
        text.starts_with("time_s,time_ref_s,reference,output\n"),
        "own clock"
    );
    let v = json_of(&run(&[
        "response",
        "broadband",
        "--input",
        p(&bb),
        "--window",
        "rectangular",
        "--json",
    ]));
    let d = &v["coefficients"]["delay_s"];
    let (val, u95) = (d["value"].as_f64().unwrap(), d["U95"].as_f64().unwrap());
    assert!((val - 0.002).abs() <= u95, "delay {val} ± {u95}");
    assert_eq!(v["options"]["window"], "rectangular");
    // The reference's clock runs 1 % fast: the offset moves by 0.1 s.
    let drift: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                return format!("{l}\n");
            }
            let mut c: Vec<String> = l.split(',').map(str::to_string).collect();
            let t: f64 = c[0].parse().unwrap();
            c[1] = format!("{}", t * 1.01);
            format!("{}\n", c.join(","))
        })
        .collect();
    let bad = dir.join("drift.csv");
    std::fs::write(&bad, drift).unwrap();
    refused(
        &run(&["response", "broadband", "--input", p(&bad)]),
        &["drift.csv", "line", "drift apart", "one clock"],
    );
    let st = dir.join("st.csv");
    ok(&run(&[
        "simulate",
        "response-step",
        "--reference-clock-offset-s",
        "0.00037",
        "--truth-out",
        p(&dir.join("t.json")),
        "-o",
        p(&st),
    ]));
    let v = json_of(&run(&[
        "response",
        "step",
        "--input",
        p(&st),
        "--order",
        "second",
        "--json",
    ]));
    let d = &v["coefficients"]["delay_s"];
    let (val, u95) = (d["value"].as_f64().unwrap(), d["U95"].as_f64().unwrap());
    assert!((val - 0.002).abs() <= u95, "step delay {val} ± {u95}");
    // time_ref_s without time_s is refused naming the header.
    let lone = dir.join("lone.csv");
    std::fs::write(&lone, "time_ref_s,reference,output\n0,1,1\n").unwrap();
    refused(
        &run(&["response", "step", "--input", p(&lone), "--rate-hz", "100"]),
        &["lone.csv", "time_ref_s", "time_s"],
    );
}
