//! Hardening regression tests: each malformed, degenerate or out-of-range
//! input (a constant output, a non-finite truth, a huge cell, a latitude
//! beyond 90°, an oversized document...) exits 2 with one line naming the
//! file (and line) or the option, or gives a correct result. One test per
//! defect, named after it.

use crate::common;
use common::*;

use std::path::PathBuf;

#[test]
fn tumble_with_constant_output_is_refused() {
    let mut s = String::from("angle_deg,output\n");
    for k in 0..12 {
        s.push_str(&format!("{},1.5\n{},1.5\n", 30 * k, 30 * k));
    }
    let f = write("const.csv", &s);
    refused(
        &run(&["tumble", "--mount", "pendulum", "--input", p(&f)]),
        &["const.csv", "scale factor is not observable"],
    );
}

#[test]
fn tumble_with_output_unrelated_to_the_input_is_refused() {
    // Outputs that follow a pseudo-random pattern, not the angle: K1 is
    // not different from zero.
    let mut s = String::from("angle_deg,output\n");
    for k in 0..24 {
        let v = ((k * 7919) % 13) as f64 - 6.0;
        s.push_str(&format!("{},{v}\n", 30 * (k / 2)));
    }
    let f = write("noise.csv", &s);
    refused(
        &run(&["tumble", "--mount", "pendulum", "--input", p(&f)]),
        &["noise.csv", "K1 is not observable"],
    );
}

fn centrifuge_csv() -> PathBuf {
    let f = tmp("c.csv");
    ok(&run(&["simulate", "centrifuge", "-o", p(&f)]));
    f
}

#[test]
fn centrifuge_with_negative_k1_is_refused_not_sign_flipped() {
    let f = centrifuge_csv();
    refused(
        &run(&[
            "centrifuge",
            "--input",
            p(&f),
            "--k0",
            "0",
            "--u-k0",
            "1e-6",
            "--k1",
            "-1.3",
            "--u-k1",
            "1e-5",
            "--radius-m",
            "0.71",
            "--latitude-deg",
            "39.9",
        ]),
        &["c.csv", "radius", "not positive", "K1"],
    );
}

#[test]
fn centrifuge_with_huge_u_k1_is_refused() {
    let f = centrifuge_csv();
    refused(
        &run(&[
            "centrifuge",
            "--input",
            p(&f),
            "--k0",
            "0",
            "--u-k0",
            "1e-6",
            "--k1",
            "1.3",
            "--u-k1",
            "1e300",
            "--radius-m",
            "0.71",
            "--latitude-deg",
            "39.9",
        ]),
        &["--u-k1"],
    );
}

#[test]
fn latitude_beyond_90_is_refused_everywhere() {
    let f = centrifuge_csv();
    refused(
        &run(&[
            "centrifuge",
            "--input",
            p(&f),
            "--k0",
            "0",
            "--u-k0",
            "1e-6",
            "--k1",
            "1.3",
            "--u-k1",
            "1e-5",
            "--radius-m",
            "0.71",
            "--latitude-deg",
            "200",
        ]),
        &["--latitude-deg", "200"],
    );
    refused(
        &run(&["simulate", "misalign", "gyro", "--latitude-deg", "-91"]),
        &["--latitude-deg"],
    );
    refused(
        &run(&["simulate", "centrifuge", "--latitude-deg", "95"]),
        &["--latitude-deg"],
    );
}

#[test]
fn huge_cell_in_a_gyro_time_series_is_refused_at_its_line() {
    let f = tmp("g.csv");
    ok(&run(&[
        "simulate",
        "misalign",
        "gyro",
        "--time-series",
        "-o",
        p(&f),
    ]));
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[5].split(',').map(String::from).collect();
    *cells.last_mut().unwrap() = "1e308".into();
    lines[5] = cells.join(",");
    let g = write("g_big.csv", &(lines.join("\n") + "\n"));
    refused(
        &run(&["misalign", "gyro", "--input", p(&g), "--k1", "-2.9222"]),
        &["g_big.csv:6", "out of range"],
    );
}

#[test]
fn simulated_gyro_time_series_with_default_records_reduces() {
    let f = tmp("g2.csv");
    ok(&run(&[
        "simulate",
        "misalign",
        "gyro",
        "--time-series",
        "-o",
        p(&f),
    ]));
    let out = ok(&run(&[
        "misalign",
        "gyro",
        "--input",
        p(&f),
        "--k1",
        "-2.9222",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    // 5 configurations x 3 rates x 2 signs x 2 records.
    assert_eq!(v["procedure"], "misalign-gyro");
    let y2 = v["coefficients"]["dtheta_y2"]["value"].as_f64().unwrap();
    assert!(
        (y2 - (-162.2f64).to_radians() / 3600.0).abs() < 1e-5,
        "{y2}"
    );
}

#[test]
fn repeated_time_in_a_raw_record_is_counted_in_its_record() {
    let f = tmp("g3.csv");
    ok(&run(&[
        "simulate",
        "misalign",
        "gyro",
        "--time-series",
        "-o",
        p(&f),
    ]));
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let prev_time = lines[8].split(',').nth(3).unwrap().to_string();
    let mut cells: Vec<String> = lines[9].split(',').map(String::from).collect();
    cells[3] = prev_time;
    lines[9] = cells.join(",");
    let g = write("g_time.csv", &(lines.join("\n") + "\n"));
    // Under the time-stamp policy a repeated stamp is accepted (time
    // gives only the measured table rate) and counted in its record's
    // warning, which names the record's first line.
    let v = json_of(&run(&[
        "misalign",
        "gyro",
        "--input",
        p(&g),
        "--k1",
        "-2.9222",
        "--json",
    ]));
    let w = warnings_with(&v, "time-repeats");
    assert!(
        w.len() == 1
            && w[0].starts_with("line 2: record alpha=0 beta=0 rate=20: 1 time_s stamps repeat"),
        "{w:?}"
    );
}

/// The JSON result of `incal tumble` on a simulated tumble test written
/// to `csv`.
fn tumble_result_json(csv: &str) -> String {
    let t = tmp(csv);
    ok(&run(&["simulate", "tumble", "-o", p(&t)]));
    ok(&run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        p(&t),
        "--json",
    ]))
}

/// `incal` with the words of `args` (no word holds a space) then `extra`.
fn run_words(args: &str, extra: &[&str]) -> std::process::Output {
    let mut a: Vec<&str> = args.split(' ').collect();
    a.extend_from_slice(extra);
    run(&a)
}

#[test]
fn compare_overflow_gives_a_finite_en() {
    let out = tumble_result_json("t.csv");
    let mut a: serde_json::Value = serde_json::from_str(&out).unwrap();
    let mut b = a.clone();
    for (d, v) in [(&mut a, 1e200), (&mut b, -1e200)] {
        let k95 = d["coefficients"]["K0"]["k95"].as_f64().unwrap();
        d["coefficients"]["K0"]["value"] = serde_json::json!(v);
        d["coefficients"]["K0"]["u"] = serde_json::json!(1e180);
        d["coefficients"]["K0"]["U95"] = serde_json::json!(k95 * 1e180);
    }
    let fa = write("a.json", &a.to_string());
    let fb = write("b.json", &b.to_string());
    let out = ok(&run(&["compare", p(&fa), p(&fb), "--json"]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let text = v.to_string();
    assert!(
        !text.contains("null") || !text.contains("\"En\":null"),
        "{text}"
    );
    let out = ok(&run(&["compare", p(&fa), p(&fb)]));
    let k0 = out.lines().find(|l| l.starts_with("K0")).unwrap();
    assert!(k0.contains("DIFFERS"), "{k0}");
}

#[test]
fn simulators_refuse_non_finite_truths() {
    refused(
        &run(&["simulate", "centrifuge", "--r-plus-m", "1e300"]),
        &["--r-plus-m"],
    );
    refused(
        &run(&["simulate", "misalign", "accel", "--betas-deg", "1e300,0"]),
        &["--betas-deg"],
    );
}

#[test]
fn simulator_sizes_are_limited_with_the_limit_named() {
    for args in [
        &[
            "simulate",
            "misalign",
            "gyro",
            "--time-series",
            "--turns",
            "1e300",
        ][..],
        &[
            "simulate",
            "misalign",
            "gyro",
            "--time-series",
            "--turns",
            "1e6",
        ][..],
        &[
            "simulate",
            "misalign",
            "gyro",
            "--time-series",
            "--samples-per-turn",
            "1000000",
        ][..],
        &["simulate", "misalign", "gyro", "--records", "100000000000"][..],
        &["simulate", "centrifuge", "--samples", "1000000000"][..],
    ] {
        let o = run(args);
        refused(&o, &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("10000000") || err.contains("at most 1000"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn plan_tumble_with_two_points_is_refused() {
    refused(
        &run(&["plan", "tumble", "--points", "2"]),
        &["at least 4", "got 2"],
    );
    refused(&run(&["plan", "tumble", "--points", "1000000"]), &["3600"]);
}

#[test]
fn empty_pass_label_is_refused() {
    let f = tmp("t2.csv");
    ok(&run(&["simulate", "tumble", "--passes", "2", "-o", p(&f)]));
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[3] = lines[3].rsplit_once(',').unwrap().0.to_string() + ",";
    let g = write("t_empty.csv", &(lines.join("\n") + "\n"));
    refused(
        &run(&["tumble", "--mount", "pendulum", "--input", p(&g)]),
        &["t_empty.csv:4", "pass", "empty"],
    );
}

#[test]
fn position_and_force_columns_together_are_refused() {
    let f = tmp("s.csv");
    ok(&run(&["simulate", "gfimu", "-o", p(&f)]));
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    assert!(header.contains("position"), "{header}");
    let mut s = format!("{header},fx_g,fy_g,fz_g\n");
    for l in lines {
        s.push_str(&format!("{l},0,0,1\n"));
    }
    let g = write("s_both.csv", &s);
    refused(
        &run(&["gfimu", "calibrate", "--input", p(&g)]),
        &["s_both.csv", "position", "fx_g"],
    );
}

#[test]
fn geometry_with_extra_elements_or_bad_names_is_refused() {
    let f = tmp("s2.csv");
    ok(&run(&["simulate", "gfimu", "-o", p(&f)]));
    let acc = |name: &str, pos: &str| {
        format!("[[accelerometer]]\nname = \"{name}\"\nposition_m = {pos}\ndirection = [0.0, 0.0, 1.0]\n")
    };
    let mut g = acc("a", "[0.1, 0.0, 0.0, 99]");
    for n in ["b", "c", "d", "e", "f"] {
        g.push_str(&acc(n, "[0.0, 0.1, 0.0]"));
    }
    let gf = write("g_extra.toml", &g);
    refused(
        &run(&["gfimu", "calibrate", "--input", p(&f), "--geometry", p(&gf)]),
        &[
            "g_extra.toml",
            "accelerometer[0].position_m",
            "3 numbers, got 4",
        ],
    );
    for bad in ["a,b", "time_s", "#c"] {
        let mut g = acc(bad, "[0.1, 0.0, 0.0]");
        for n in ["b2", "c", "d", "e", "f"] {
            g.push_str(&acc(n, "[0.0, 0.1, 0.0]"));
        }
        let gf = write("g_name.toml", &g);
        refused(
            &run(&["gfimu", "calibrate", "--input", p(&f), "--geometry", p(&gf)]),
            &["g_name.toml", "cannot be a CSV column"],
        );
    }
}

#[test]
fn huge_lever_arm_and_long_cells_are_not_echoed_whole() {
    refused(
        &run(&[
            "gfimu",
            "calibrate",
            "--input",
            "x.csv",
            "--lever-arm-m",
            "1e300",
        ]),
        &["--lever-arm-m", "1.000000e300"],
    );
    let long = "9".repeat(100_000) + "x";
    let f = write("long.csv", &format!("angle_deg,output\n0,{long}\n"));
    refused(
        &run(&["tumble", "--mount", "pendulum", "--input", p(&f)]),
        &["long.csv:2", "characters"],
    );
}

#[test]
fn json_with_a_bom_is_read_everywhere() {
    let out = tumble_result_json("t3.csv");
    let f = write("bom.json", &format!("\u{feff}{out}"));
    ok(&run(&["compare", p(&f), p(&f)]));
    ok(&run(&["report", p(&f), "-o", p(&tmp("bom.html"))]));
    let c = centrifuge_csv();
    ok(&run(&[
        "centrifuge",
        "--input",
        p(&c),
        "--from",
        p(&f),
        "--radius-m",
        "0.71",
        "--latitude-deg",
        "39.9",
    ]));
}

#[test]
fn misalign_warns_when_angles_are_too_large_for_the_linear_model() {
    let f = tmp("acc_big.csv");
    ok(&run(&[
        "simulate",
        "misalign",
        "accel",
        "--dtheta-y2-arcsec",
        "7200",
        "-o",
        p(&f),
    ]));
    let out = ok(&run(&[
        "misalign",
        "accel",
        "--input",
        p(&f),
        "--scale-factor",
        "1.299",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let w = warnings_with(&v, "model-range");
    assert!(w.iter().any(|m| m.contains("dtheta_y2")), "{w:?}");
    // The paper's angles (arcseconds) stay silent.
    let f = tmp("acc_small.csv");
    ok(&run(&["simulate", "misalign", "accel", "-o", p(&f)]));
    let out = ok(&run(&[
        "misalign",
        "accel",
        "--input",
        p(&f),
        "--scale-factor",
        "1.299",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .all(|w| w["code"] != "model-range"));
}

#[test]
fn plan_gfimu_predicts_and_refuses() {
    let out = ok(&run(&[
        "plan",
        "gfimu",
        "--noise",
        "2e-4",
        "--samples",
        "50",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["plan"], "gfimu");
    let u = v["predicted_u"]["a.K0"].as_f64().unwrap();
    // σ/√(6·50) for the six-position test.
    assert!((u - 2e-4 / 300f64.sqrt()).abs() < 1e-9, "{u}");
    assert_eq!(v["motion"]["rank"], 6);
    assert_eq!(v["motion"]["mode"], "feedback");
    refused(
        &run(&[
            "plan",
            "gfimu",
            "--noise",
            "2e-4",
            "--positions",
            "+x,-x,+q",
        ]),
        &["--positions", "+q"],
    );
    refused(
        &run(&[
            "plan",
            "gfimu",
            "--noise",
            "2e-4",
            "--positions",
            "+x,-x,+y,-y",
        ]),
        &["positions", "need at least 6"],
    );
}

/// The centrifuge static radius includes u(ω).
#[test]
fn centrifuge_static_radius_carries_the_rate_uncertainty() {
    let csv = tmp("cf_uomega.csv");
    ok(&run(&[
        "simulate",
        "centrifuge",
        "--seed",
        "1",
        "-o",
        p(&csv),
    ]));
    let base = [
        "centrifuge",
        "--input",
        p(&csv),
        "--k1",
        "1.3",
        "--k0",
        "1e-4",
        "--radius-m",
        "0.71",
        "--latitude-deg",
        "39.9",
        "--json",
    ];
    let static_u = |extra: &[&str]| -> (f64, f64) {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        let v: serde_json::Value = serde_json::from_str(&ok(&run(&a))).unwrap();
        let r = &v["radius"]["static"]["R_plus_m"];
        (r["value"].as_f64().unwrap(), r["u"].as_f64().unwrap())
    };
    let (r0, u0) = static_u(&[]);
    let (r1, u1) = static_u(&["--u-omega-ppm", "100"]);
    assert_eq!(r0, r1);
    let added = (u1 * u1 - u0 * u0).sqrt() / r1;
    assert!((added / 200e-6 - 1.0).abs() < 1e-3, "{added}");
    let mut a = base.to_vec();
    a.extend_from_slice(&["--u-omega-ppm", "-5"]);
    refused(&run(&a), &["--u-omega-ppm"]);
}

/// Second hardening round: one gyro axis dead in its rotation section gave
/// `K_g.zz = 0.063 ± 0.002` (truth about 16.7) with exit 0. Now refused
/// naming the section and the column, in `imu ferraris` and `imu
/// multipos`.
#[test]
fn a_dead_gyro_axis_in_its_rotation_section_is_refused() {
    for (sequence, command, extra) in [
        ("ferraris", "ferraris", &[][..]),
        ("positions", "multipos", &["--rotations"][..]),
    ] {
        let f = tmp(&format!("{sequence}.csv"));
        let mut args = vec!["simulate", "imu", "--sequence", sequence, "-o", p(&f)];
        args.extend_from_slice(extra);
        ok(&run(&args));
        let text = std::fs::read_to_string(&f).unwrap();
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let header = lines.iter().position(|l| !l.starts_with('#')).unwrap();
        let cols: Vec<String> = lines[header].split(',').map(String::from).collect();
        let (cp, cz) = (
            cols.iter()
                .position(|c| c == "part" || c == "position")
                .unwrap(),
            cols.iter().position(|c| c == "gyr_z").unwrap(),
        );
        for l in lines.iter_mut().skip(header + 1) {
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            if cells[cp] == "z_rot" {
                cells[cz] = "-312".into();
                *l = cells.join(",");
            }
        }
        let g = write(&format!("{sequence}_dead.csv"), &(lines.join("\n") + "\n"));
        refused(
            &run(&["imu", command, "--input", p(&g), "--rate-hz", "100"]),
            &[
                p(&g),
                "rotation section z_rot",
                "column gyr_z is -312",
                "dead gyro channel",
            ],
        );
    }
}

/// Second hardening round: `gyro positions --from R.json` took K1 whatever
/// its unit, its u (1.0 against K1 = 0.02) or its dof (−3, 0). Each is now
/// refused naming the JSON path.
#[test]
fn gyro_positions_from_checks_the_unit_u_and_dof_of_k1() {
    let r = tmp("rate.csv");
    ok(&run(&["simulate", "gyro-rate", "-o", p(&r)]));
    let text = ok(&run(&[
        "gyro",
        "rate",
        "--input",
        p(&r),
        "--latitude-deg",
        "45",
        "--json",
    ]));
    let pos = tmp("pos.csv");
    ok(&run_words(
        "simulate gyro-positions --latitude-deg 30 --azimuths-deg 60 --axial oa -o",
        &[p(&pos)],
    ));
    let positions = |from: &std::path::Path| {
        run_words(
            "gyro positions --latitude-deg 30 --azimuth-deg 60 --axial oa --input",
            &[p(&pos), "--from", p(from)],
        )
    };
    ok(&positions(&write_unique("good.json", &text)));
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let k1 = doc["coefficients"]["K1"]["value"].as_f64().unwrap();
    for (name, key, value, needle) in [
        (
            "unit.json",
            "unit",
            serde_json::json!("output/g"),
            "$.coefficients.K1.unit",
        ),
        (
            "u.json",
            "u",
            serde_json::json!(2.0 * k1.abs()),
            "$.coefficients.K1.u",
        ),
        (
            "dof.json",
            "dof",
            serde_json::json!(-3.0),
            "$.coefficients.K1.dof",
        ),
        (
            "dof0.json",
            "dof",
            serde_json::json!(0.0),
            "$.coefficients.K1.dof",
        ),
    ] {
        let mut d = doc.clone();
        d["coefficients"]["K1"][key] = value;
        if key == "u" {
            let k95 = d["coefficients"]["K1"]["k95"].as_f64().unwrap();
            d["coefficients"]["K1"]["U95"] = serde_json::json!(2.0 * k1.abs() * k95);
        }
        let f = write(name, &serde_json::to_string_pretty(&d).unwrap());
        refused(&positions(&f), &[p(&f), needle]);
    }
}

/// Second hardening round: `compare` took a negative u and a U95 that is
/// not k95·u (En = 4.9e207); `report` took a negative u, rows shorter than
/// their header, panicked on a longer one, and never finished on values
/// of 1e308. A document is now checked before use, the error naming the
/// JSON path.
#[test]
fn result_documents_are_checked_before_compare_and_report() {
    let out = tumble_result_json("tc.csv");
    let good = write_unique("good.json", &out);
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    type Change = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(&str, Change, &str)> = vec![
        (
            "negu.json",
            Box::new(|d| d["coefficients"]["K0"]["u"] = serde_json::json!(-1.0)),
            "$.coefficients.K0.u",
        ),
        (
            "u95.json",
            Box::new(|d| d["coefficients"]["K0"]["U95"] = serde_json::json!(1e200)),
            "$.coefficients.K0.U95",
        ),
        (
            "huge.json",
            Box::new(|d| d["coefficients"]["K0"]["value"] = serde_json::json!(1e300)),
            "$.coefficients.K0.value",
        ),
        (
            "long.json",
            Box::new(|d| {
                let row = &mut d["tables"][0]["rows"][0];
                row.as_array_mut().unwrap().push(serde_json::json!(1.0));
            }),
            "$.tables[0].rows[0]",
        ),
        (
            "short.json",
            Box::new(|d| {
                let row = &mut d["tables"][0]["rows"][0];
                row.as_array_mut().unwrap().pop();
            }),
            "$.tables[0].rows[0]",
        ),
        (
            "cell.json",
            Box::new(|d| d["tables"][0]["rows"][0][0] = serde_json::json!(-1e308)),
            "$.tables[0].rows[0][0]",
        ),
    ];
    for (name, change, needle) in cases {
        let mut d = doc.clone();
        change(&mut d);
        let f = write(name, &d.to_string());
        refused(&run(&["compare", p(&good), p(&f)]), &[p(&f), needle]);
        refused(
            &run(&["report", p(&f), "-o", p(&tmp("r.html"))]),
            &[p(&f), needle],
        );
    }
}

/// Second hardening round: `imu multipos` never parsed fx,fy,fz on
/// rotation rows (text there was accepted). Now every cell present is a
/// number or the row is refused naming its line and column.
#[test]
fn multipos_parses_the_direction_columns_on_rotation_rows() {
    let f = tmp("mp.csv");
    ok(&run_words(
        "simulate imu --sequence positions --rotations -o",
        &[p(&f)],
    ));
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    let cols: Vec<String> = lines[header].split(',').map(String::from).collect();
    let (cp, cx) = (
        cols.iter().position(|c| c == "position").unwrap(),
        cols.iter().position(|c| c == "fx").unwrap(),
    );
    let k = (header + 1..lines.len())
        .find(|&k| lines[k].split(',').nth(cp) == Some("y_rot"))
        .unwrap();
    let mut cells: Vec<String> = lines[k].split(',').map(String::from).collect();
    cells[cx] = "abc".into();
    lines[k] = cells.join(",");
    let g = write("mp_text.csv", &(lines.join("\n") + "\n"));
    refused(
        &run(&["imu", "multipos", "--input", p(&g), "--rate-hz", "100"]),
        &[
            &format!("{}:{}:", p(&g), k + 1),
            "'fx'",
            "'abc' is not a number",
        ],
    );
}

/// Second hardening round: `plan centrifuge` took `--u-k1` at or above
/// |K1|, `--u-k0 200` and an alignment tolerance of 1e300 deg (and
/// `--u-k1 1e300` predicted u = 0). Each is refused naming the option.
#[test]
fn plan_centrifuge_checks_its_uncertainties_against_their_quantities() {
    for (opt, value) in [
        ("--u-k1", "1e300"),
        ("--u-k0", "200"),
        ("--alignment-tolerance-deg", "1e300"),
    ] {
        let o = run(&["plan", "centrifuge", opt, value]);
        refused(&o, &[opt]);
    }
}

/// Second hardening round: simulators wrote `inf` and `NaN` for options
/// past what they can represent (`simulate centrifuge --positions
/// ip:1e300`, `simulate imu --rate-hz 1e-320`, `simulate gfimu` with
/// huge rates). Whatever slips past the option checks, no simulator writes
/// a non-finite number: exit 2 naming the line, and no file left.
#[test]
fn no_simulator_writes_a_non_finite_number() {
    for (name, args) in [
        (
            "c.csv",
            vec!["simulate", "centrifuge", "--positions", "ip:1e300"],
        ),
        ("i.csv", vec!["simulate", "imu", "--rate-hz", "1e-320"]),
        (
            "g.csv",
            vec![
                "simulate",
                "gfimu",
                "--kind",
                "motion",
                "--angular-accel-rad-s2",
                "1e300",
            ],
        ),
        (
            "w.csv",
            vec![
                "simulate",
                "gfimu",
                "--kind",
                "motion",
                "--omega0-rad-s",
                "1e300,0,0",
            ],
        ),
    ] {
        let f = tmp(name);
        let mut a = args.clone();
        a.extend(["-o", p(&f)]);
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert_eq!(stderr(&o).lines().count(), 1, "{}", stderr(&o));
        assert!(
            !f.exists()
                || !std::fs::read_to_string(&f)
                    .unwrap()
                    .to_lowercase()
                    .contains("inf")
        );
    }
}

/// Second hardening round: `tumble` with angles offset by 3.6e14 deg gave
/// K1 9.9944 for 10 and K2 of the wrong sign; a `# note` after a pass or
/// run label made a new pass; NUL bytes in labels were accepted. Each is
/// now refused naming the cell.
#[test]
fn angles_and_labels_are_checked_where_they_are_read() {
    let f = write(
        "far.csv",
        "angle_deg,output\n360000000000000,1\n360000000000090,2\n",
    );
    refused(
        &run(&["tumble", "--mount", "pendulum", "--input", p(&f)]),
        &["far.csv:2", "'angle_deg'", "1e4 deg"],
    );
    for (name, text, needle) in [
        (
            "note.csv",
            "angle_deg,output,pass\n0,1,cw\n90,2,cw # redo\n",
            "'#'",
        ),
        (
            "nul.csv",
            "angle_deg,output,pass\n0,1,cw\n90,2,c\u{0}w\n",
            "control characters",
        ),
    ] {
        let f = write(name, text);
        refused(
            &run(&["tumble", "--mount", "pendulum", "--input", p(&f)]),
            &[&format!("{name}:3"), "'pass'", needle],
        );
    }
    let f = write(
        "run.csv",
        "rate_deg_s,output,run\n10,1,a\n-10,2,a # again\n",
    );
    refused(
        &run(&["gyro", "rate", "--input", p(&f), "--latitude-deg", "45"]),
        &["run.csv:3", "'run'", "'#'"],
    );
}

#[test]
fn gfimu_calibrations_and_geometries_are_checked_for_what_they_can_hold() {
    let st = unique("st.csv");
    ok(&run(&["simulate", "gfimu", "--seed", "1", "-o", p(&st)]));
    let cal = unique("cal.json");
    ok(&run_words(
        "gfimu calibrate --json --input",
        &[p(&st), "-o", p(&cal)],
    ));
    let mo = unique("mo.csv");
    ok(&run(&[
        "simulate",
        "gfimu",
        "--kind",
        "motion",
        "--seed",
        "2",
        "-o",
        p(&mo),
    ]));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    // K0 beyond the outputs' range was blamed on motion.csv; a sample
    // noise of 1e-201 made the solve spin for ever.
    let cases: [(&str, &str, f64, &str); 3] = [
        (
            "k0.json",
            "/accelerometers/a/K0/value",
            1e200,
            "$.accelerometers.a.K0.value",
        ),
        (
            "tiny.json",
            "/accelerometers/a/noise_output",
            1e-201,
            "$.accelerometers.a.noise_output",
        ),
        (
            "ks.json",
            "/accelerometers/b/Ks/value/2",
            1e300,
            "$.accelerometers.b.Ks.value",
        ),
    ];
    for (name, path, v, needle) in cases {
        let mut d = doc.clone();
        *d.pointer_mut(path).unwrap() = serde_json::json!(v);
        let f = write_unique(name, &serde_json::to_string(&d).unwrap());
        let out = unique("x.csv");
        refused(
            &run(&[
                "gfimu",
                "solve",
                "--calibration",
                p(&f),
                "--input",
                p(&mo),
                "-o",
                p(&out),
            ]),
            &[name, needle],
        );
    }
    // An accelerometer 1e308 m from the origin is the geometry's fault.
    let g = write_unique(
        "far.toml",
        "[[accelerometer]]\nname = \"a\"\nposition_m = [1e308, 0, 0]\ndirection = [0, 0, 1]\n",
    );
    refused(
        &run(&["gfimu", "calibrate", "--geometry", p(&g), "--input", p(&st)]),
        &["far.toml", "accelerometer[0].position_m", "beyond 10 m"],
    );
}

#[test]
fn binary_noise_samples_beyond_the_readable_range_are_refused() {
    for (name, big) in [("n16.f64", 1e16), ("n300.f64", 1e300)] {
        let mut bytes = Vec::new();
        for k in 0..2000 {
            let v = if k == 1234 {
                big
            } else {
                ((k * 7919) % 101) as f64 * 0.01
            };
            bytes.extend_from_slice(&f64::to_le_bytes(v));
        }
        let f = write_unique(name, &bytes);
        refused(
            &run_words(
                "noise --format f64le --channels 1 --rate-hz 100 --input",
                &[p(&f)],
            ),
            &[name, "sample 1235 of ch1", "beyond the readable range"],
        );
    }
}

#[test]
fn documents_read_whole_are_capped_in_size() {
    // /dev/zero as a result document grew memory without end.
    for args in [
        vec!["report", "/dev/zero"],
        vec!["compare", "/dev/zero", "/dev/zero"],
        vec!["record", "add", "/dev/zero", "--db", "never.db"],
    ] {
        refused(&run(&args), &["/dev/zero", "larger than 64 MiB"]);
    }
}

#[test]
fn limits_errors_name_their_line() {
    let t = unique("t.csv");
    ok(&run(&["simulate", "tumble", "--seed", "7", "-o", p(&t)]));
    let head = "rule = \"simple\"\n[tumble]\nK0 = { min = -1, max = 1 }\n";
    for (text, needles) in [
        (
            format!("{head}K2 = {{ min = \"x\" }}\n"),
            vec!["line 4", "invalid type"],
        ),
        (
            format!("{head}K2 = {{ mni = 3 }}\n"),
            vec!["line 4", "unknown field `mni`"],
        ),
        (
            format!("{head}K2 = {{ min = 3, max = 2 }}\n"),
            vec!["line 4", "[tumble] K2", "min 3 is above max 2"],
        ),
        (format!("{head}K2 = 3\n"), vec!["line 4"]),
        (
            format!("{head}[tumbel]\nK1 = {{ max = 1 }}\n"),
            vec!["line 4", "[tumbel]: not a procedure", "imu-autocal"],
        ),
        (
            "\n\nrule = \"simpel\"\n[tumble]\nK0 = { max = 1 }\n".to_string(),
            vec!["line 3", "simpel"],
        ),
    ] {
        let f = write_unique("l.toml", &text);
        let mut needles = needles;
        needles.push("l.toml");
        refused(
            &run_words(
                "tumble --mount pendulum --limits",
                &[p(&f), "--input", p(&t)],
            ),
            &needles,
        );
    }
}

#[test]
fn messages_name_the_file_they_are_about() {
    // An empty serial in the document names the document.
    let mut d: serde_json::Value = serde_json::from_str(&tumble_result_json("msg_t.csv")).unwrap();
    d["instrument"]["serial"] = serde_json::json!(" ");
    let f = write_unique("blank.json", &serde_json::to_string(&d).unwrap());
    refused(
        &run(&["record", "add", p(&f), "--db", p(&unique("s.db"))]),
        &["blank.json", "$.instrument.serial: empty"],
    );
    // A full output device is named.
    let raw = unique("imu.csv");
    ok(&run(&["simulate", "imu", "--seed", "3", "-o", p(&raw)]));
    let cal = unique("fr.json");
    ok(&run_words(
        "imu ferraris --rate-hz 100 --json --input",
        &[p(&raw), "-o", p(&cal)],
    ));
    let o = run_words(
        "imu apply -o /dev/full --input",
        &[p(&raw), "--calibration", p(&cal)],
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).starts_with("incal: /dev/full: cannot write"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn plan_misalign_sizes_are_capped_and_never_built_row_by_row() {
    let plan = |n: &str| {
        run_words(
            "plan misalign --scale-factor 1 --noise 0.01 --json --readings",
            &[n],
        )
    };
    refused(&plan("1000000000000"), &["samples", "100000000"]);
    // 10^6 readings predict u / 1000 of one reading, without a 10^6-row
    // design (it took 25 s and 5.4 GB).
    let u = |n: &str| json_of(&plan(n))["predicted_u"]["gamma"].as_f64().unwrap();
    let (one, many) = (u("1"), u("1000000"));
    assert!((many * 1000.0 / one - 1.0).abs() < 1e-9, "{one} {many}");
}

#[test]
fn plan_tumble_checks_its_options_without_a_prediction() {
    // One position was accepted when k1 and noise were not given.
    refused(
        &run(&["plan", "tumble", "--angles-deg", "0"]),
        &["cannot separate", "K1"],
    );
    refused(
        &run(&[
            "plan",
            "tumble",
            "--range-g",
            "0.5",
            "--step-resolution-deg",
            "1e300",
        ]),
        &["step resolution", "at most 18"],
    );
}

#[test]
fn duplicated_positions_and_dead_scale_factors_are_refused() {
    refused(
        &run_words("plan centrifuge --positions ip:0,io:90,ip:360", &[]),
        &["positions", "ip:360"],
    );
    for c in ["gyro", "accel"] {
        refused(
            &run_words("simulate misalign", &[c, "--scale-factor", "0"]),
            &["--scale-factor", "non-zero"],
        );
    }
}
