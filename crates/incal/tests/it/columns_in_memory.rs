//! Every procedure reduces columns in memory (the canonical column form
//! of `incal_io::frames`, what the Python package hands the core) to the
//! same document as the CSV text with the same cells: only `inputs` (the
//! name and the hash of the bytes read) differ.

use std::borrow::Cow;

use incal::procedures::registry::REGISTRY;
use incal::procedures::Silent;
use incal_io::frames::{Column, Columns};
use incal_io::{ReadOptions, Table};

/// The columns of a CSV text: a column whose every cell is a number as
/// binary numbers, any other as text.
fn columns_of(table: &Table) -> Vec<(String, Column<'static>)> {
    (0..table.header().width())
        .map(|c| {
            let name = table.header().names()[c].clone();
            match table.column_f64(c) {
                Ok(v) => (name, Column::F64(Cow::Owned(v))),
                Err(_) => {
                    let t = (0..table.row_count()).map(|r| table.text(r, c).into_owned());
                    (name, Column::Text(Cow::Owned(t.collect())))
                }
            }
        })
        .collect()
}

/// The registry example's simulator words (`--seed 11 --rotations`) as
/// the typed simulator's options (`{"seed": 11, "rotations": true}`).
fn simulate_options(words: &[&str]) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    let mut k = 0;
    while k < words.len() {
        let key = words[k].trim_start_matches("--").replace('-', "_");
        match words.get(k + 1).filter(|w| !w.starts_with("--")) {
            Some(v) => {
                let value = serde_json::from_str(v).unwrap_or_else(|_| serde_json::json!(v));
                m.insert(key, value);
                k += 2;
            }
            None => {
                m.insert(key, serde_json::json!(true));
                k += 1;
            }
        }
    }
    serde_json::Value::Object(m)
}

#[test]
fn every_reduction_gives_the_same_document_from_columns_as_from_csv() {
    let mut checked = Vec::new();
    for e in REGISTRY {
        let (Some(red), Some(sim)) = (e.reduction, e.simulator) else {
            continue;
        };
        let example = (red.example.expect("a reduction has an example"))();
        let words = e.example.map_or(&[][..], |x| x.simulate);
        let mut csv = Vec::new();
        (sim.run)(&simulate_options(words), &mut csv)
            .unwrap_or_else(|err| panic!("{}: simulate with defaults: {err}", e.id));
        let read = ReadOptions::default();
        let from_csv = (red.run)("sim.csv", &mut &csv[..], &read, &example, &Silent, None)
            .unwrap_or_else(|err| panic!("{}: reduce the CSV: {err}", e.id));
        let table = Table::from_bytes("sim.csv", &csv, &read).unwrap();
        let mut cols = Columns::new();
        for (name, col) in columns_of(&table) {
            cols.push(&name, col).unwrap();
        }
        let frames = ReadOptions {
            frames: true,
            ..ReadOptions::default()
        };
        let from_cols = (red.run)("<DataFrame>", &mut cols, &frames, &example, &Silent, None)
            .unwrap_or_else(|err| panic!("{}: reduce the columns: {err}", e.id));
        let mut a = serde_json::to_value(&from_csv).unwrap();
        let mut b = serde_json::to_value(&from_cols).unwrap();
        let (ia, ib) = (a["inputs"].take(), b["inputs"].take());
        assert_eq!(a, b, "{}: the documents differ", e.id);
        assert_eq!(ia[0]["rows"], ib[0]["rows"], "{}", e.id);
        assert_eq!(ib[0]["path"], "<DataFrame>", "{}", e.id);
        assert_ne!(ia[0]["sha256"], ib[0]["sha256"], "{}", e.id);
        checked.push(e.id);
    }
    assert!(checked.len() >= 10, "only {checked:?} were checked");
}
