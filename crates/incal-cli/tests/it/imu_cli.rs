//! `incal imu ferraris|autocal|multipos|apply` and `incal simulate imu`:
//! the real binary on files. Contract keys (imucal's and imu_tk's), imucal's
//! own example to 1e-9, round trips, and bad input refused with exit 2 and
//! one line.

use crate::common;
use common::*;

const FIX: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../incal/tests/fixtures/imucal/"
);

fn flat(v: &serde_json::Value) -> Vec<f64> {
    match v {
        serde_json::Value::Array(a) => a.iter().flat_map(flat).collect(),
        x => vec![x.as_f64().unwrap()],
    }
}

#[test]
fn ferraris_reproduces_imucal_with_its_keys() {
    let session = format!("{FIX}annotated_session.csv");
    let v = json_of(&run(&[
        "imu",
        "ferraris",
        "--input",
        &session,
        "--rate-hz",
        "204.8",
        // imucal's g (incal's default is the standard 9.80665).
        "--gravity-m-s2",
        "9.81",
        "--json",
    ]));
    let want: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{FIX}example_cal.json")).unwrap())
            .unwrap();
    assert_eq!(v["procedure"], "imu-ferraris");
    for k in ["K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"] {
        let (g, w) = (flat(&v[k]), flat(&want[k]));
        assert_eq!(g.len(), w.len(), "{k}");
        for (a, b) in g.iter().zip(&w) {
            assert!((a - b).abs() <= 1e-9 * b.abs(), "{k}: {a} vs imucal {b}");
        }
    }
    for name in [
        "K_a.xx", "R_a.xy", "b_a.x", "K_g.zz", "R_g.yz", "K_ga.zx", "b_g.y",
    ] {
        let c = &v["coefficients"][name];
        assert!(c["u"].as_f64().unwrap() > 0.0, "{name}");
        assert!(c["U95"].as_f64().is_some(), "{name}");
    }
    assert_eq!(v["coefficients"]["K_a.xx"]["unit"], "output/(m/s^2)");
    assert_eq!(v["coefficients"]["K_g.xx"]["unit"], "output/(deg/s)");
    // The off-diagonal elements of K_a and K_g are zero by the
    // method's construction: not listed as coefficients with u = 0, said
    // in a decision, kept (as 0) in the matrices imucal reads.
    for name in ["K_a.xy", "K_a.zx", "K_g.yz", "K_g.xz"] {
        assert!(v["coefficients"].get(name).is_none(), "{name}");
    }
    assert!(v["coefficients"]
        .as_object()
        .unwrap()
        .values()
        .all(|c| c["u"].as_f64().unwrap() > 0.0));
    assert!(v["decisions"]
        .as_array()
        .unwrap()
        .iter()
        .any(|d| d["code"] == "fixed-by-model"));
    assert_eq!(v["K_a"][0][1], 0.0);
    assert!(
        !warnings_with(&v, "sign-convention").is_empty(),
        "{}",
        v["warnings"]
    );
    // imucal's hand rotations have knocks: found, reported, not changed
    // (the matrices above are imucal's to 1e-9).
    let w = warnings_with(&v, "spikes");
    assert!(w.iter().any(|m| m.contains("not changed")), "{w:?}");
}

#[test]
fn ferraris_refuses_bad_sections() {
    let bad = tmp("bad_part.csv");
    std::fs::write(
        &bad,
        "part,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\nx_p,1,2,3,4,5,6\nx_q,1,2,3,4,5,6\n",
    )
    .unwrap();
    refused(
        &run(&[
            "imu",
            "ferraris",
            "--input",
            bad.to_str().unwrap(),
            "--rate-hz",
            "100",
        ]),
        &["bad_part.csv:3", "'x_q' is not a Ferraris section"],
    );
    let short = tmp("short.csv");
    std::fs::write(
        &short,
        "part,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\nx_p,1,2,3,4,5,6\nx_p,1,2,3,4,5,6\n",
    )
    .unwrap();
    refused(
        &run(&[
            "imu",
            "ferraris",
            "--input",
            short.to_str().unwrap(),
            "--rate-hz",
            "100",
        ]),
        &[
            "short.csv",
            "missing or too short: x_a, y_p, y_a, z_p, z_a, x_rot, y_rot, z_rot",
        ],
    );
    let nogyr = tmp("nogyr.csv");
    std::fs::write(&nogyr, "part,acc_x,acc_y,acc_z\nx_p,1,2,3\n").unwrap();
    refused(
        &run(&[
            "imu",
            "ferraris",
            "--input",
            nogyr.to_str().unwrap(),
            "--rate-hz",
            "100",
        ]),
        &["nogyr.csv", "missing column 'gyr_x'"],
    );
    let session = format!("{FIX}annotated_session.csv");
    refused(
        &run(&["imu", "ferraris", "--input", &session, "--rate-hz", "0"]),
        &["--rate-hz"],
    );
    refused(
        &run(&[
            "imu",
            "ferraris",
            "--input",
            &session,
            "--rate-hz",
            "100",
            "--gravity-m-s2",
            "0",
        ]),
        &["--gravity-m-s2"],
    );
    // imucal's negative-g convention is an option of its own, not a sign.
    refused(
        &run(&[
            "imu",
            "ferraris",
            "--input",
            &session,
            "--rate-hz",
            "100",
            "--gravity-m-s2",
            "-9.81",
        ]),
        &["--gravity-m-s2", "-9.81", "--convention imucal"],
    );
}

/// `--convention imucal` runs the map with -g: on a session whose `_p`
/// positions read +g, R_a comes out negated, the warning names the other
/// convention, and the document records the convention (the default one
/// is not recorded).
#[test]
fn ferraris_convention_imucal_is_recorded_and_flips_r_a() {
    let session = format!("{FIX}annotated_session.csv");
    let args = |conv: &'static str| {
        let mut a = vec![
            "imu",
            "ferraris",
            "--input",
            session.as_str(),
            "--rate-hz",
            "204.8",
            "--gravity-m-s2",
            "9.81",
            "--json",
        ];
        if !conv.is_empty() {
            a.extend(["--convention", conv]);
        }
        a
    };
    let standard = json_of(&run(&args("")));
    let imucal = json_of(&run(&args("imucal")));
    assert!(standard["options"].get("convention").is_none());
    assert_eq!(imucal["options"]["convention"], "imucal");
    assert_eq!(imucal["options"]["gravity_m_s2"], 9.81);
    let (s, i) = (flat(&standard["R_a"]), flat(&imucal["R_a"]));
    for (a, b) in s.iter().zip(&i) {
        assert!((a + b).abs() <= 1e-12 * a.abs().max(1.0), "{a} vs {b}");
    }
    let warned = imucal["warnings"].as_array().unwrap().iter().any(|w| {
        w["message"]
            .as_str()
            .unwrap()
            .contains("--convention standard")
    });
    assert!(warned, "{}", imucal["warnings"]);
}

#[test]
fn ferraris_round_trip_from_the_simulator() {
    let csv = unique("fe.csv");
    let truth = tmp("fe_truth.json");
    let o = run(&[
        "simulate",
        "imu",
        "--sequence",
        "ferraris",
        "--truth-seed",
        "4",
        "-o",
        csv.to_str().unwrap(),
        "--truth-out",
        truth.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = json_of(&run(&[
        "imu",
        "ferraris",
        "--input",
        csv.to_str().unwrap(),
        "--rate-hz",
        "100",
        "--json",
    ]));
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    for (k, name) in [
        ("K_a", "K_a.yy"),
        ("R_a", "R_a.xz"),
        ("K_g", "K_g.zz"),
        ("R_g", "R_g.yx"),
    ] {
        let (i, j) = (
            (name.as_bytes()[name.len() - 2] - b'x') as usize,
            (name.as_bytes()[name.len() - 1] - b'x') as usize,
        );
        let want = t["imucal"][k][i][j].as_f64().unwrap();
        let c = &v["coefficients"][name];
        let (x, u95) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
        assert!(
            (x - want).abs() < 2.0 * u95,
            "{name}: {x} vs truth {want} (U95 {u95})"
        );
    }
}

#[test]
fn autocal_contract_keys_and_round_trip() {
    let csv = tmp("ac.csv");
    let truth = tmp("ac_truth.json");
    let o = run(&[
        "simulate",
        "imu",
        "--sequence",
        "random",
        "--orientations",
        "24",
        "--init-static-s",
        "10",
        "--no-g-sensitivity",
        "-o",
        csv.to_str().unwrap(),
        "--truth-out",
        truth.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    for method in ["incal", "tedaldi"] {
        let v = json_of(&run(&[
            "imu",
            "autocal",
            "--input",
            csv.to_str().unwrap(),
            "--rate-hz",
            "100",
            "--init-static-s",
            "10",
            "--method",
            method,
            "--json",
        ]));
        assert_eq!(v["procedure"], "imu-autocal");
        assert_eq!(v["options"]["method"], method);
        for tri in ["acc", "gyr"] {
            assert_eq!(flat(&v[tri]["T"]).len(), 9);
            assert_eq!(flat(&v[tri]["K"]).len(), 9);
            assert_eq!(flat(&v[tri]["b"]).len(), 3);
        }
        let iv = v["intervals"].as_array().unwrap();
        assert_eq!(iv.len(), 25, "{method}: still start + 24 orientations");
        assert!(iv[1]["start_s"].as_f64().unwrap() < iv[1]["end_s"].as_f64().unwrap());
        for (name, tri, m, i, j) in [
            ("acc.s_x", "acc", "K", 0, 0),
            ("acc.m_yz", "acc", "T", 0, 1),
            ("gyr.s_z", "gyr", "K", 2, 2),
            ("gyr.m_xz", "gyr", "T", 1, 0),
        ] {
            let c = &v["coefficients"][name];
            let (x, u95) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
            let mut want = t["imu_tk"][tri][m][i][j].as_f64().unwrap();
            if name == "gyr.s_z" {
                // Gyro scales in (deg/s)/output; imu_tk's K in (rad/s)/output.
                assert_eq!(c["unit"], "(deg/s)/output");
                want = want.to_degrees();
            }
            if name == "acc.m_yz" {
                want = -want; // T_xy = -m_yz
            }
            assert!(u95 > 0.0);
            assert!(
                (x - want).abs() < 3.0 * u95,
                "{method} {name}: {x} vs truth {want} (U95 {u95})"
            );
        }
        assert_eq!(v["coefficients"]["acc.b_x"]["unit"], "output");
    }
}

#[test]
fn autocal_says_how_many_intervals_it_found() {
    let csv = tmp("few.csv");
    let o = run(&[
        "simulate",
        "imu",
        "--sequence",
        "random",
        "--orientations",
        "5",
        "--init-static-s",
        "10",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    refused(
        &run(&[
            "imu",
            "autocal",
            "--input",
            csv.to_str().unwrap(),
            "--rate-hz",
            "100",
            "--init-static-s",
            "10",
            "--method",
            "tedaldi",
        ]),
        &["few.csv", "the most found was 6", "need at least 12"],
    );
}

#[test]
fn multipos_labels_or_directions_and_apply() {
    let csv = tmp("mp.csv");
    let o = run(&[
        "simulate",
        "imu",
        "--sequence",
        "positions",
        "--rotations",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cal = tmp("mp.json");
    let o = run(&[
        "imu",
        "multipos",
        "--input",
        csv.to_str().unwrap(),
        "--rate-hz",
        "100",
        "--json",
        "-o",
        cal.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    assert_eq!(v["procedure"], "imu-multipos");
    for k in [
        "acc.S_x", "acc.M_xy", "acc.b_z", "gyr.G_xy", "gyr.S_z", "gyr.M_zy",
    ] {
        assert!(v["coefficients"][k]["u"].as_f64().unwrap() > 0.0, "{k}");
    }
    // fx,fy,fz alone give the same fit for the static positions (rotations
    // need their labels).
    let text = std::fs::read_to_string(&csv).unwrap();
    let dirs: String = text
        .lines()
        .filter(|l| !l.contains("_rot"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let mut g = vec![f[0]];
            g.extend(&f[2..]);
            g.join(",") + "\n"
        })
        .collect();
    let dcsv = tmp("mp_dirs.csv");
    std::fs::write(&dcsv, dirs).unwrap();
    let d = json_of(&run(&[
        "imu",
        "multipos",
        "--input",
        dcsv.to_str().unwrap(),
        "--rate-hz",
        "100",
        "--json",
    ]));
    let (a, b) = (
        d["coefficients"]["acc.A_xy"]["value"].as_f64().unwrap(),
        v["coefficients"]["acc.A_xy"]["value"].as_f64().unwrap(),
    );
    assert!((a - b).abs() < 1e-9 * b.abs().max(1.0));
    // Apply: every static sample calibrates to |f| = g within the noise.
    let o = run(&[
        "imu",
        "apply",
        "--calibration",
        cal.to_str().unwrap(),
        "--input",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    let mut lines = out.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,acc_x_m_s2,acc_y_m_s2,acc_z_m_s2,gyr_x_deg_s,gyr_y_deg_s,gyr_z_deg_s,position,fx,fy,fz"
    );
    let mut mean_norm = 0.0;
    let mut n = 0.0;
    for l in lines.take(300) {
        let f: Vec<f64> = l.split(',').take(7).map(|x| x.parse().unwrap()).collect();
        mean_norm += (f[1] * f[1] + f[2] * f[2] + f[3] * f[3]).sqrt();
        n += 1.0;
    }
    assert!((mean_norm / n - 9.80665).abs() < 0.01, "{}", mean_norm / n);
    // Every other column (the label here, a temperature and a
    // quoted note below) is carried through, as read.
    assert!(out.lines().nth(1).unwrap().contains(",x_p,"), "{out:.300}");
    let extra = tmp("mp_extra.csv");
    std::fs::write(
        &extra,
        "time_s,acc_x,temperature_c,acc_y,acc_z,gyr_x,gyr_y,gyr_z,note\n0,2038.7,23.5,-52.5,-28.0,0.1,0.2,0.3,\"a, b\"\n",
    )
    .unwrap();
    let o = run(&[
        "imu",
        "apply",
        "--calibration",
        cal.to_str().unwrap(),
        "--input",
        extra.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    let mut lines = out.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,acc_x_m_s2,acc_y_m_s2,acc_z_m_s2,gyr_x_deg_s,gyr_y_deg_s,gyr_z_deg_s,temperature_c,note"
    );
    assert!(lines.next().unwrap().ends_with(",23.5,\"a, b\""), "{out}");
}

#[test]
fn multipos_refusals_name_line_and_term() {
    let contra = tmp("contra.csv");
    std::fs::write(
        &contra,
        "position,fx,fy,fz,acc_x,acc_y,acc_z\nx_p,1,0,0,1,2,3\nx_p,0,1,0,1,2,3\n",
    )
    .unwrap();
    refused(
        &run(&[
            "imu",
            "multipos",
            "--input",
            contra.to_str().unwrap(),
            "--rate-hz",
            "100",
        ]),
        &["contra.csv:3", "position 'x_p' points"],
    );
    let badlabel = tmp("badlabel.csv");
    std::fs::write(&badlabel, "position,acc_x,acc_y,acc_z\nx_p+x_a,1,2,3\n").unwrap();
    refused(
        &run(&[
            "imu",
            "multipos",
            "--input",
            badlabel.to_str().unwrap(),
            "--rate-hz",
            "100",
        ]),
        &["badlabel.csv:2", "names the x axis twice"],
    );
    // Every position about the z axis: the z terms are not separable.
    let csv = tmp("plane.csv");
    let o = run(&[
        "simulate",
        "imu",
        "--sequence",
        "positions",
        "--positions",
        "x_p,x_a,y_p,y_a,x_p+y_p,x_a+y_a,x_p+y_a,x_a+y_p",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    refused(
        &run(&[
            "imu",
            "multipos",
            "--input",
            csv.to_str().unwrap(),
            "--rate-hz",
            "100",
        ]),
        &["plane.csv", "cannot separate", "acc.A_xz"],
    );
}

#[test]
fn apply_refuses_a_calibration_of_another_procedure() {
    let cal = tmp("notimu.json");
    let tumble = tmp("tumble.csv");
    let o = run(&["simulate", "tumble", "-o", tumble.to_str().unwrap()]);
    assert!(o.status.success());
    let o = run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        tumble.to_str().unwrap(),
        "--json",
        "-o",
        cal.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let raw = tmp("raw.csv");
    std::fs::write(&raw, "acc_x,acc_y,acc_z\n1,2,3\n").unwrap();
    refused(
        &run(&[
            "imu",
            "apply",
            "--calibration",
            cal.to_str().unwrap(),
            "--input",
            raw.to_str().unwrap(),
        ]),
        &["notimu.json", "$.procedure", "not an IMU calibration"],
    );
    // The export to imucal refuses it the same way.
    refused(
        &run(&["export", "imucal", cal.to_str().unwrap()]),
        &["notimu.json", "$.procedure", "not an IMU calibration"],
    );
}

#[test]
fn export_imucal_copies_a_ferraris_calibration_verbatim() {
    let raw = unique("fe.csv");
    ok(&run(&[
        "simulate",
        "imu",
        "--sequence",
        "ferraris",
        "--static-s",
        "0.5",
        "--rotation-s",
        "1",
        "-o",
        p(&raw),
    ]));
    let doc = json_of(&run(&[
        "imu",
        "ferraris",
        "--rate-hz",
        "100",
        "--json",
        "--input",
        p(&raw),
    ]));
    let cal = tmp("fe.json");
    std::fs::write(&cal, doc.to_string()).unwrap();
    let out = json_of(&run(&["export", "imucal", p(&cal)]));
    for k in [
        "K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g", "acc_unit", "gyr_unit", "cal_type",
    ] {
        assert_eq!(out[k], doc[k], "{k}");
    }
    assert_eq!(out["_format_version"], "2.0.0");
    assert_eq!(out["from_acc_unit"], "a.u.");
}

/// One default gravity, the standard 9.80665 m/s² (it was 9.81
/// for the IMU commands and 9.80665 elsewhere).
#[test]
fn every_imu_command_defaults_to_standard_gravity() {
    for cmd in [
        &["imu", "ferraris"][..],
        &["imu", "multipos"],
        &["imu", "autocal"],
        &["simulate", "imu"],
        &["centrifuge"],
        &["plan", "centrifuge"],
    ] {
        let mut args = cmd.to_vec();
        args.push("--help");
        let help = String::from_utf8(run(&args).stdout).unwrap();
        let at = help
            .find("--gravity-m-s2")
            .unwrap_or_else(|| panic!("{cmd:?}"));
        let rest = &help[at..];
        let default = &rest[rest.find("[default: ").unwrap()..];
        assert!(
            default.starts_with("[default: 9.80665]"),
            "{cmd:?}: {default:.40}"
        );
    }
}
