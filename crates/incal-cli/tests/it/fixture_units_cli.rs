//! Several units on one fixture (`incal batch … --units`): each unit's
//! result equals the one-unit file's, one bad unit never stops the
//! others, records are written in order, and a mapping file gives
//! serials, slots and a unit's own options.

use std::path::{Path, PathBuf};

use crate::common::*;

/// Three tumble units (seeds 1, 2, 3) in one file `angle_deg,out_1,out_2,
/// out_3`; unit 3's sample on row `bad` is not a number. Returns the
/// fixture's file and the single-unit files.
fn fixture(dir: &Path, bad: Option<usize>) -> (PathBuf, Vec<PathBuf>) {
    let mut singles = Vec::new();
    let mut columns: Vec<Vec<String>> = Vec::new();
    let mut angles = Vec::new();
    for seed in 1..=3 {
        let f = dir.join(format!("single_{seed}.csv"));
        ok(&run(&[
            "simulate",
            "tumble",
            "--seed",
            &seed.to_string(),
            "-o",
            p(&f),
        ]));
        let text = std::fs::read_to_string(&f).unwrap();
        let rows: Vec<Vec<String>> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .skip(1)
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        angles = rows.iter().map(|r| r[0].clone()).collect();
        columns.push(rows.iter().map(|r| r[1].clone()).collect());
        singles.push(f);
    }
    let mut text = String::from("angle_deg,out_1,out_2,out_3\n");
    for (k, a) in angles.iter().enumerate() {
        let third = if Some(k) == bad {
            "x"
        } else {
            columns[2][k].as_str()
        };
        text.push_str(&format!(
            "{a},{},{},{third}\n",
            columns[0][k], columns[1][k]
        ));
    }
    let fix = dir.join("fixture.csv");
    std::fs::write(&fix, text).unwrap();
    (fix, singles)
}

#[test]
fn each_unit_is_its_own_result_equal_to_its_own_file() {
    let dir = workdir("units_each");
    let (fix, singles) = fixture(&dir, None);
    let out = dir.join("res");
    let db = dir.join("line.db");
    let batch = |extra: &[&str]| {
        let mut args = vec![
            "batch",
            "tumble",
            p(&fix),
            "--units",
            "SN-1=out_1,SN-2=out_2,SN-3=out_3",
            "--db",
            p(&db),
            "--json",
        ];
        args.extend(extra);
        args.extend(["--", "--mount", "pendulum"]);
        run(&args)
    };
    let o = batch(&["--out-dir", p(&out)]);
    let summary = json_of(&o);
    assert_eq!(summary["ok"], 3);
    for (k, single) in singles.iter().enumerate() {
        let item = &summary["results"][k];
        let serial = format!("SN-{}", k + 1);
        assert_eq!(item["unit"], serial.as_str());
        assert_eq!(
            item["record"],
            (k + 1) as i64,
            "records in the order of the units"
        );
        let doc = &item["result"];
        assert_eq!(doc["instrument"]["serial"], serial.as_str());
        let alone = json_of(&run(&[
            "tumble",
            "--input",
            p(single),
            "--mount",
            "pendulum",
            "--json",
        ]));
        assert_eq!(
            coefficient_values(doc),
            coefficient_values(&alone),
            "unit {serial}"
        );
        let written = std::fs::read_to_string(out.join(format!("fixture.{serial}.json"))).unwrap();
        assert_eq!(
            serde_json::from_str::<serde_json::Value>(&written).unwrap(),
            *doc
        );
    }
    // The units' results differ: each read its own column.
    let values: Vec<f64> = (0..3)
        .map(|k| {
            summary["results"][k]["result"]["coefficients"]["K1"]["value"]
                .as_f64()
                .unwrap()
        })
        .collect();
    assert!(
        values[0] != values[1] && values[1] != values[2],
        "{values:?}"
    );
    // Run twice: nothing stored twice.
    let again = json_of(&batch(&[]));
    assert!((0..3).all(|k| again["results"][k]["already_stored"] == true));
}

#[test]
fn a_bad_unit_never_stops_the_others() {
    let dir = workdir("units_bad");
    let (fix, _) = fixture(&dir, Some(5));
    let o = run(&[
        "batch",
        "tumble",
        p(&fix),
        "--units",
        "out_1,out_2,out_3",
        "--",
        "--mount",
        "pendulum",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let text = stdout(&o);
    assert!(text.contains("ok    "), "{text}");
    assert!(text.contains(&format!("{} [out_2]", p(&fix))), "{text}");
    assert!(
        text.contains("fixture.csv:7: column 'output': 'x' is not a number (unit out_3)"),
        "{text}"
    );
    assert!(text.contains("2 of 3 units reduced, 1 failed"), "{text}");
    assert!(stderr(&o).contains("batch: 1 of 3 units refused (named above)"));
}

#[test]
fn a_mapping_file_gives_serials_slots_and_a_units_own_options() {
    let dir = workdir("units_map");
    let (fix, singles) = fixture(&dir, None);
    let map = dir.join("units.csv");
    std::fs::write(
        &map,
        "serial,columns,slot,options\nA-7,out_1,1,--mount gate\nB-9,output=out_3,3,--mount pendulum\n",
    )
    .unwrap();
    let summary = json_of(&run(&[
        "batch",
        "tumble",
        p(&fix),
        "--units",
        p(&map),
        "--json",
    ]));
    assert_eq!(summary["ok"], 2);
    let b = &summary["results"][1]["result"];
    assert_eq!(b["instrument"]["serial"], "B-9");
    assert_eq!(b["instrument"]["slot"], "3");
    let alone = json_of(&run(&[
        "tumble",
        "--input",
        p(&singles[2]),
        "--mount",
        "pendulum",
        "--json",
    ]));
    assert_eq!(coefficient_values(b), coefficient_values(&alone));
    // Unit A-7 is read with its own mount.
    assert_eq!(summary["results"][0]["result"]["options"]["mount"], "gate");
    // Refusals before anything runs.
    let units = |units: &str, rest: &[&str]| {
        let mut args = vec!["batch", "tumble", p(&fix), "--units", units];
        args.extend(rest);
        run(&args)
    };
    std::fs::write(&map, "serial,columns\nA-7,out_1\nA-7,out_2\n").unwrap();
    refused(&units(p(&map), &[]), &["--units: serial 'A-7' given twice"]);
    std::fs::write(&map, "serial,columns\nA-7,\n").unwrap();
    refused(
        &units(p(&map), &[]),
        &["units.csv:2: a unit needs its serial and its columns"],
    );
    refused(
        &units("out_1,", &["--", "--mount", "pendulum"]),
        &["--units: '': give COLUMN or SERIAL=COLUMN"],
    );
    refused(
        &units("out_1", &["--", "--serial", "X"]),
        &["batch: --serial is set by the batch"],
    );
    refused(
        &units("a/b=out_1", &["--", "--mount", "pendulum"]),
        &["--units: serial 'a/b' holds '/'"],
    );
    refused(
        &units("SN-a=out_1,sn-A=out_2", &["--", "--mount", "pendulum"]),
        &["--units: serial 'sn-A' given twice"],
    );
    // A unit's own options that the command refuses: named before any run.
    std::fs::write(
        &map,
        "serial,columns,options\nA-7,out_1,--mount pendulum\nB-9,out_2,--mount sideways\n",
    )
    .unwrap();
    refused(
        &units(p(&map), &[]),
        &["--units: unit B-9: invalid value 'sideways' for '--mount"],
    );
    std::fs::write(&map, "serial,columns,options\nA-7,out_1,--serial X\n").unwrap();
    refused(
        &units(p(&map), &[]),
        &["--units: unit A-7: --serial is set by the batch"],
    );
}
