//! Unit tests of the reader, the table and the writer.

use super::*;
use proptest::prelude::*;

fn table(bytes: &[u8]) -> Result<Table> {
    Table::from_bytes("f.csv", bytes, &ReadOptions::default())
}

fn cells(t: &Table) -> Vec<Vec<String>> {
    (0..t.row_count())
        .map(|r| {
            (0..t.header().width())
                .map(|c| t.text(r, c).to_string())
                .collect()
        })
        .collect()
}

/// A source that hands out at most `n` bytes per read, to cross every
/// buffer boundary.
struct Trickle<'a> {
    data: &'a [u8],
    n: usize,
}

impl std::io::Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let k = self.n.min(buf.len()).min(self.data.len());
        buf[..k].copy_from_slice(&self.data[..k]);
        self.data = &self.data[k..];
        Ok(k)
    }
}

#[test]
fn one_file_in_every_dress_reads_the_same() {
    let plain = b"angle_deg,output\n0,1.5\n30,2.5\n";
    let dressed = b"\xEF\xBB\xBF# a comment\r\n\r\nangle_deg;output\r\n# note\r\n0;1.5\r\n\r\n30 ; \"2.5\"\r\n";
    let a = table(plain).unwrap();
    let b = table(dressed).unwrap();
    assert_eq!(cells(&a), cells(&b));
    assert_eq!(b.header().delimiter(), b';');
    assert_eq!(b.line(0), 5);
    assert_eq!(b.line(1), 7);
    assert_eq!(b.f64(1, 1).unwrap(), 2.5);
    let tab = table(b"angle_deg\toutput\n0\t1.5\n30\t2.5\n").unwrap();
    assert_eq!(cells(&a), cells(&tab));
    let cr = table(b"angle_deg,output\r0,1.5\r30,2.5\r").unwrap();
    assert_eq!(cells(&a), cells(&cr));
}

#[test]
fn quoted_fields_hold_delimiters_quotes_and_line_breaks() {
    let t =
        table(b"label,x\n\"a, b\",1\n\"say \"\"hi\"\"\",2\n\"two\nlines\",3\n  \"padded\"  ,4\n")
            .unwrap();
    assert_eq!(t.text(0, 0), "a, b");
    assert_eq!(t.text(1, 0), "say \"hi\"");
    assert_eq!(t.text(2, 0), "two\nlines");
    assert_eq!(t.line(2), 4);
    assert_eq!(t.line(3), 6);
    assert_eq!(t.text(3, 0), "padded");
    let e = table(b"a,b\n\"open,1\n").unwrap_err();
    assert_eq!(
        e.to_string(),
        "f.csv:2: quoted field not closed before the end of the file"
    );
    let e = table(b"a,b\n\"x\"y,1\n").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("f.csv:2: text after a closing quote"),
        "{e}"
    );
}

#[test]
fn decimal_comma_is_refused_saying_so() {
    let t = table(b"a;b\n1,5;2\n").unwrap();
    let e = t.f64(0, 0).unwrap_err().to_string();
    assert!(
        e.starts_with("f.csv:2: column 'a': '1,5' has a decimal comma"),
        "{e}"
    );
    // With ',' as delimiter the comma splits the cell: the width is wrong.
    let e = table(b"a,b\n1,5,2\n").unwrap_err().to_string();
    assert_eq!(e, "f.csv:2: 3 fields, but the header has 2");
}

#[test]
fn bad_files_name_file_line_and_column() {
    let e = |b: &[u8]| table(b).unwrap_err().to_string();
    assert_eq!(e(b""), "f.csv: empty file (expected a header row)");
    assert_eq!(
        e(b"# only\n\n"),
        "f.csv: empty file (expected a header row)"
    );
    assert_eq!(e(b"a,b\n"), "f.csv: no data rows after the header");
    assert_eq!(e(b"a,a\n1,2\n"), "f.csv:1: column 'a' appears twice");
    assert_eq!(
        e(b"a,,b\n1,2,3\n"),
        "f.csv:1: empty column name in column 2"
    );
    assert_eq!(
        e(b"a,b\n1,2\n3\n"),
        "f.csv:3: 1 fields, but the header has 2"
    );
    assert_eq!(e(b"a,b\n1,2\n3,\xB0\n"), "f.csv:3: invalid UTF-8");
    let t = table(b"a,b\n1,x\nNaN,1e16\n").unwrap();
    assert_eq!(
        t.f64(0, 1).unwrap_err().to_string(),
        "f.csv:2: column 'b': 'x' is not a number"
    );
    assert_eq!(
        t.f64(1, 0).unwrap_err().to_string(),
        "f.csv:3: column 'a': 'NaN' is not a finite number"
    );
    assert_eq!(
        t.f64(1, 1).unwrap_err().to_string(),
        "f.csv:3: column 'b': 1e16 is out of range (|value| <= 1e15)"
    );
    assert_eq!(
        t.column("c").unwrap_err().to_string(),
        "f.csv: missing column 'c' (columns: a, b)"
    );
}

#[test]
fn rows_of_empty_cells_are_skipped() {
    let t = table(b"a,b\n1,2\n,\n , \n3,4\n").unwrap();
    assert_eq!(t.row_count(), 2);
    assert_eq!(t.line(1), 5);
}

#[test]
fn a_line_without_end_is_refused_within_the_cap() {
    let opts = ReadOptions {
        max_line_bytes: 1000,
        ..ReadOptions::default()
    };
    let zeros = vec![0u8; 100_000];
    let e = Table::read("zero", &zeros[..], &opts, 0)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "zero:1: line longer than 1000 bytes (is this a CSV text file?)"
    );
    let mut long = b"a\n".to_vec();
    long.extend(std::iter::repeat_n(b'1', 5000));
    long.push(b'\n');
    let e = Table::read("long", &long[..], &opts, 0)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "long:2: line longer than 1000 bytes (is this a CSV text file?)"
    );
}

#[test]
fn columns_are_renamed_and_selected() {
    let bytes = b"Time,Angle [deg],Out\n0,30,1.5\n";
    let opts =
        ReadOptions::with_columns(ColumnMap::parse("angle_deg=Angle [deg],output=Out").unwrap());
    let t = Table::from_bytes("f.csv", bytes, &opts).unwrap();
    assert_eq!(t.header().names(), ["Time", "angle_deg", "output"]);
    assert_eq!(t.header().selected(), [1, 2]);
    assert_eq!(t.f64(0, t.column("output").unwrap()).unwrap(), 1.5);
    let opts = ReadOptions::with_columns(ColumnMap::parse("output=Nope").unwrap());
    let e = Table::from_bytes("f.csv", bytes, &opts)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "f.csv:1: no column 'Nope' to read as 'output' (columns: Time, Angle [deg], Out)"
    );
    let opts = ReadOptions::with_columns(ColumnMap::parse("Time=Out").unwrap());
    let e = Table::from_bytes("f.csv", bytes, &opts)
        .unwrap_err()
        .to_string();
    assert_eq!(e, "f.csv:1: column 'Time' appears twice (after --columns)");
}

#[test]
fn the_hash_is_of_every_byte_as_stored() {
    use sha2::Digest;
    let bytes = b"\xEF\xBB\xBFa,b\r\n1,2\r\n# trailing note\r\n";
    let t = table(bytes).unwrap();
    assert_eq!(t.sha256(), hex(&sha2::Sha256::digest(bytes)));
    let one = Table::read(
        "f.csv",
        Trickle { data: bytes, n: 1 },
        &ReadOptions::default(),
        0,
    )
    .unwrap();
    assert_eq!(one.header().names(), ["a", "b"]);
    assert_eq!(one.sha256(), t.sha256());
    assert_eq!(t.summary().bytes, bytes.len() as u64);
}

#[test]
fn numbers_parse_as_std_does() {
    for s in [
        "0",
        "-1.5",
        "+2",
        ".5",
        "5.",
        "1e-7",
        "-3.25E+2",
        "123456789.123456789",
    ] {
        assert_eq!(parse_f64(s.as_bytes()), s.parse::<f64>().ok(), "{s}");
    }
    for s in ["", "1.2.3", "0x10", "1_000", "1,5", "--1", "e5"] {
        assert_eq!(parse_f64(s.as_bytes()), None, "{s}");
    }
}

#[test]
fn the_writer_quotes_what_needs_it_and_refuses_non_finite() {
    let mut w = CsvWriter::new(Vec::new(), &["x", "label"]).unwrap();
    w.row(&[Cell::Num(0.1), Cell::Text("a,b")]).unwrap();
    w.row(&[Cell::Num(-2e-9), Cell::Text("#x")]).unwrap();
    assert!(w.row(&[Cell::Num(f64::NAN), Cell::Text("")]).is_err());
    let mut w = CsvWriter::new(Vec::new(), &["x"]).unwrap();
    w.row(&[Cell::Num(1.0)]).unwrap();
    assert_eq!(w.finish().unwrap(), b"x\n1\n");
}

#[test]
fn csv_text_quotes_what_needs_it_and_nothing_else() {
    assert_eq!(csv_text("plain label"), "plain label");
    assert_eq!(csv_text("a,b"), "\"a,b\"");
    assert_eq!(csv_text("a;b"), "\"a;b\"");
    assert_eq!(csv_text("a\tb"), "\"a\tb\"");
    assert_eq!(csv_text("say \"hi\""), "\"say \"\"hi\"\"\"");
    assert_eq!(csv_text("two\nlines"), "\"two\nlines\"");
    assert_eq!(csv_text("#x"), "\"#x\"");
    assert_eq!(csv_text(" padded"), "\" padded\"");
}

#[test]
fn clip_keeps_a_message_on_one_short_line() {
    assert_eq!(clip("short"), "short");
    assert_eq!(clip("a\nb\tc"), "a?b?c");
    let long = "x".repeat(100);
    assert_eq!(
        clip(&long),
        format!("{}... (100 characters)", "x".repeat(40))
    );
    assert_eq!(clip(&"é".repeat(40)), "é".repeat(40));
}

#[test]
fn sha256_hex_is_sha256sum() {
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    assert_eq!(hex(&[0x00, 0x0f, 0xa0, 0xff]), "000fa0ff");
}

/// An MPU-6050 logger's file: a preamble of `key,value` lines, then the
/// header and the data.
const LOGGER: &[u8] = b"Device,MPU6050\nFs,100\nLogging Type,0\nComment,\"bench, slot 3\"\n\
ax,ay,az,gx,gy,gz\n1,2,3,4,5,6\n7,8,9,10,11,12\n";

#[test]
fn a_preamble_is_found_kept_and_read_past() {
    for chunk in [1, 3, 7, 4096] {
        let mut r = Reader::new(
            "log.csv",
            Trickle {
                data: LOGGER,
                n: chunk,
            },
            &ReadOptions::default(),
        )
        .unwrap();
        assert_eq!(r.header().names(), ["ax", "ay", "az", "gx", "gy", "gz"]);
        assert_eq!(r.header().line(), 5);
        let keys: Vec<(usize, &str, &str)> = r
            .preamble()
            .iter()
            .map(|p| (p.line, p.key.as_str(), p.value.as_str()))
            .collect();
        assert_eq!(
            keys,
            [
                (1, "Device", "MPU6050"),
                (2, "Fs", "100"),
                (3, "Logging Type", "0"),
                (4, "Comment", "bench, slot 3")
            ]
        );
        let mut seen = Vec::new();
        while let Some(row) = r.next_row().unwrap() {
            seen.push((row.line(), row.f64(0).unwrap()));
        }
        assert_eq!(seen, [(6, 1.0), (7, 7.0)]);
        let s = r.finish().unwrap();
        assert_eq!(s.sha256, sha256_hex(LOGGER));
        assert_eq!(stated_rate_hz(&s.preamble), Some((100.0, 2)));
    }
}

#[test]
fn a_file_without_preamble_reads_as_before() {
    let plain = b"angle_deg,output\n0,1.5\n30,2.5\n";
    let t = table(plain).unwrap();
    assert_eq!(t.header().line(), 1);
    assert_eq!(cells(&t), [["0", "1.5"], ["30", "2.5"]]);
    // No header at all: the first line is taken, and the column asked for
    // is missing from it, as before.
    let t = table(b"1,2\n3,4\n").unwrap();
    let e = t.header().column("x").unwrap_err().to_string();
    assert!(e.contains("missing column 'x' (columns: 1, 2)"), "{e}");
    // A header and a ragged row: the ragged row is the error, as before.
    let e = table(b"a,b\n1,2\n3\n").unwrap_err().to_string();
    assert!(e.contains("f.csv:3: 1 fields, but the header has 2"), "{e}");
}

#[test]
fn the_header_line_can_be_given_and_columns_steer_the_search() {
    let opts = ReadOptions {
        header_line: Some(5),
        ..ReadOptions::default()
    };
    let t = Table::from_bytes("log.csv", LOGGER, &opts).unwrap();
    assert_eq!(t.header().names()[0], "ax");
    for (n, why) in [
        (1, "log.csv:5: 6 fields, but the header has 2"),
        (
            3,
            "log.csv:3: --header-line 3: this line holds '0', not a column name",
        ),
        (9, "--header-line 9: no record starts on line 9"),
    ] {
        let opts = ReadOptions {
            header_line: Some(n),
            ..ReadOptions::default()
        };
        let e = Table::from_bytes("log.csv", LOGGER, &opts).unwrap_err();
        assert!(e.to_string().contains(why), "{e}");
    }
    // Two text-only records of one width before the data: the one the
    // data follows; --columns naming the first makes it the header.
    let two = b"Model,Serial\nax,ay\n1,2\n";
    assert_eq!(table(two).unwrap().header().names(), ["ax", "ay"]);
    let opts = ReadOptions::with_columns(ColumnMap::parse("m=Model").unwrap());
    let t = Table::from_bytes("f.csv", two, &opts).unwrap();
    assert_eq!(t.header().names(), ["m", "Serial"]);
    let opts = ReadOptions::with_columns(ColumnMap::parse("acc_x=ax,acc_y=ay").unwrap());
    let t = Table::from_bytes("f.csv", two, &opts).unwrap();
    assert_eq!(t.header().names(), ["acc_x", "acc_y"]);
    // A tab-separated table after a comma preamble.
    let t = table(b"Fs,100\nax\tay\n1\t2\n").unwrap();
    assert_eq!(cells(&t), [["1", "2"]]);
}

#[test]
fn a_stated_rate_is_recognised_in_its_usual_spellings() {
    let line = |k: &str, v: &str| PreambleLine {
        line: 1,
        key: k.into(),
        value: v.into(),
    };
    for (k, v, want) in [
        ("Fs", "100", Some(100.0)),
        ("Sample Rate (Hz)", "200", Some(200.0)),
        ("sampling_frequency", "400 Hz", Some(400.0)),
        ("ODR", "1.6e3", Some(1600.0)),
        ("Fs", "fast", None),
        ("Fs", "-5", None),
        ("Frames", "100", None),
    ] {
        assert_eq!(stated_rate_hz(&[line(k, v)]).map(|r| r.0), want, "{k},{v}");
    }
}

/// A log at 10 Hz: (angle, rows) plateaus with 5 moving rows before each.
fn head_log(plateaus: &[(f64, usize)]) -> String {
    let mut out = String::from("# a rig log\ntime_s,angle_deg,output\n");
    let mut k = 0;
    for &(a, n) in plateaus {
        for m in 0..5 {
            out.push_str(&format!(
                "{},{},9\n",
                k as f64 / 10.0,
                a + 3.0 * (m + 1) as f64
            ));
            k += 1;
        }
        for j in 0..n {
            let jitter = [0.0, 2e-4, -2e-4][j % 3];
            out.push_str(&format!("{},{},{}\n", k as f64 / 10.0, a + jitter, a));
            k += 1;
        }
    }
    out
}

#[test]
fn a_log_is_cut_into_plateaus_on_its_own_lines() {
    let text = head_log(&[(0.0, 30), (90.0, 30), (180.0, 30)]);
    let t = Table::from_bytes("head.csv", text.as_bytes(), &ReadOptions::default()).unwrap();
    let spec = SegmentSpec {
        column: "angle_deg".into(),
        values: vec![0.0, 90.0, 180.0],
        ..SegmentSpec::default()
    };
    let s = crate::segments::segment(&t, &spec).unwrap();
    assert_eq!(s.segments.len(), 3);
    assert_eq!(s.moving_rows, 15);
    // 1 s settles: 10 rows dropped, 20 kept, each on its own file line.
    assert!(s
        .segments
        .iter()
        .all(|g| (g.rows_kept, g.rows_dropped) == (20, 10)));
    let out = String::from_utf8(s.text).unwrap();
    let lines: Vec<&str> = out.lines().collect();
    let orig: Vec<&str> = text.lines().collect();
    assert_eq!(lines[1], "time_s,angle_deg,output");
    let first = s.segments[1].lines.0;
    assert_eq!(lines[first - 1].split(',').nth(1), Some("90"));
    assert_eq!(
        lines[first - 1].split(',').next(),
        orig[first - 1].split(',').next()
    );
    assert!(lines[first - 2].starts_with('#'));
    // Means instead of a plan: the jitter's mean, 0 at rest.
    let means = crate::segments::segment(
        &t,
        &SegmentSpec {
            values: vec![],
            ..spec.clone()
        },
    )
    .unwrap();
    assert_eq!(means.segments[0].value, 0.0);
    assert!((means.segments[1].value - 90.0).abs() < 1e-4);
    // A plateau the plan lacks, and a planned one the log lacks.
    let extra = SegmentSpec {
        values: vec![0.0, 180.0],
        ..spec.clone()
    };
    let e = crate::segments::segment(&t, &extra)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("head.csv:53: a plateau at t = 4 s (mean 90")
            && e.contains("next planned value 180"),
        "{e}"
    );
    let more = SegmentSpec {
        values: vec![0.0, 90.0, 180.0, 270.0],
        ..spec
    };
    let e = crate::segments::segment(&t, &more).unwrap_err().to_string();
    assert!(
        e.contains("plateau at 270 is missing: the log ends at t = 10.4 s after 3 of 4"),
        "{e}"
    );
}

#[test]
fn the_header_search_keeps_old_files_readable() {
    // Over 128 KiB of comments before the header: read as before.
    let mut text = "# a long note\n".repeat(20_000);
    text.push_str("x,y\n1,2\n");
    let t = table(text.as_bytes()).unwrap();
    assert_eq!((t.header().line(), t.row_count()), (20_001, 1));
    // A later row that its own delimiter cannot split ends the search.
    let t = table(b"label;x\na,\"b\";1\n").unwrap();
    assert_eq!(cells(&t), [["a,\"b\"", "1"]]);
}

#[test]
fn clipped_runs_need_a_rail_that_is_the_columns_extreme() {
    let mut text = String::from("time_s,gx,status,gy\n");
    for k in 0..50 {
        let gx = if (10..13).contains(&k) {
            "+32767".to_string()
        } else {
            format!("{}", k % 7)
        };
        let gy = if k < 2 { "-32768" } else { "-32769" };
        text.push_str(&format!("{k},{gx},65535,{gy}\n"));
    }
    let mut r = Reader::new("f.csv", text.as_bytes(), &ReadOptions::default()).unwrap();
    while r.next_row().unwrap().is_some() {}
    let s = r.finish().unwrap();
    // gx: 3 rows at +32767; status always 65535 (a status word); gy below
    // -32768 elsewhere (not its extreme).
    assert_eq!(s.clipped.len(), 1, "{:?}", s.clipped);
    assert_eq!(
        (s.clipped[0].column.as_str(), s.clipped[0].samples),
        ("gx", 3)
    );
    assert_eq!(s.clipped[0].lines, [(12, 14)]);
}

#[test]
fn a_plan_of_one_value_matches_within_ten_tolerances() {
    let text = head_log(&[(50.0, 30)]);
    let t = Table::from_bytes("head.csv", text.as_bytes(), &ReadOptions::default()).unwrap();
    let spec = SegmentSpec {
        column: "angle_deg".into(),
        values: vec![100.0],
        ..SegmentSpec::default()
    };
    let e = crate::segments::segment(&t, &spec).unwrap_err().to_string();
    assert!(
        e.contains("a plateau at t = 0.5 s (mean 50") && e.contains("next planned value 100"),
        "{e}"
    );
}

proptest! {
    /// Whatever a table holds, writing it and reading it back in chunks of
    /// any size gives the same cells, numbers bit for bit.
    #[test]
    fn written_tables_read_back(
        rows in proptest::collection::vec(
            (any::<f64>().prop_filter("finite", |x| x.is_finite() && x.abs() <= 1e15),
             "[ -~]{0,12}"),
            1..40),
        chunk in 1usize..64,
    ) {
        let mut w = CsvWriter::new(Vec::new(), &["x", "label", "y"]).unwrap();
        for (x, s) in &rows {
            w.row(&[Cell::Num(*x), Cell::Text(s), Cell::Num(1.0)]).unwrap();
        }
        let bytes = w.finish().unwrap();
        let t = Table::read("p.csv", Trickle { data: &bytes, n: chunk }, &ReadOptions::default(), 0);
        // A row whose label is empty or blank... is still a row (x and y are there).
        let t = t.unwrap();
        prop_assert_eq!(t.row_count(), rows.len());
        for (r, (x, s)) in rows.iter().enumerate() {
            prop_assert_eq!(t.f64(r, 0).unwrap().to_bits(), x.to_bits());
            prop_assert_eq!(t.text(r, 1), s.trim_matches(|c| c == ' ' || c == '\t'));
        }
    }

    /// Any bytes: an error or a table, never a panic.
    #[test]
    fn any_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400), chunk in 1usize..32) {
        let opts = ReadOptions { max_line_bytes: 128, ..ReadOptions::default() };
        if let Ok(t) = Table::read("b", Trickle { data: &bytes, n: chunk }, &opts, 0) {
            for r in 0..t.row_count() {
                for c in 0..t.header().width() {
                    let _ = t.f64(r, c);
                }
            }
        }
    }
}

/// A file whose rows are all names (a mapping file of serials and
/// columns): the first row is the header, every other row data.
#[test]
fn rows_of_names_are_data_after_the_first() {
    let t = crate::Table::from_bytes(
        "m.csv",
        b"serial,columns\nA-7,out_1\nB-2,out_2\n",
        &crate::ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(t.row_count(), 2);
    assert_eq!(t.text(1, 1), "out_2");
}

/// A preamble and a header without data rows: refused for that, not read
/// from the preamble.
#[test]
fn a_preamble_and_a_header_without_rows_has_no_data_rows() {
    let e = crate::Table::from_bytes(
        "p.csv",
        b"Fs,100\nLogging Type,0\nax,ay,az\n",
        &crate::ReadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no data rows after the header"), "{e}");
}
