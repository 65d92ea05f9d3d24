//! One reader serves every reducing command: the same recording written
//! with a UTF-8 BOM, a `#` comment line, CRLF line ends and `;` delimiters
//! gives every command the same coefficients as the plain file.

use crate::common;
use common::*;

/// `(name, simulate args, reduce args)`; the reduce args get `--input`:
/// every procedure that reduces a simulated recording, with its worked
/// example from the procedure registry.
fn cases() -> Vec<(&'static str, Vec<&'static str>, Vec<&'static str>)> {
    registry_cases()
        .into_iter()
        .map(|c| {
            let mut sim = vec!["simulate"];
            sim.extend_from_slice(&c.simulate);
            let mut reduce = c.command.to_vec();
            reduce.extend_from_slice(c.options);
            (c.id, sim, reduce)
        })
        .collect()
}

/// The file as another acquisition system writes it: BOM, a comment line,
/// CRLF, `;` between fields.
fn foreign(plain: &str) -> String {
    let mut s = String::from("\u{feff}# exported by a data-acquisition system\r\n");
    for line in plain.lines() {
        s.push_str(&line.replace(',', ";"));
        s.push_str("\r\n");
    }
    s
}

#[test]
fn every_reducing_command_reads_bom_comment_crlf_and_semicolons() {
    for (name, sim, reduce) in cases() {
        let plain = tmp(&format!("{name}.csv"));
        let mut s = sim.clone();
        s.extend_from_slice(&["-o", p(&plain)]);
        ok(&run(&s));
        let text = std::fs::read_to_string(&plain).unwrap();
        assert!(text.contains(','), "{name}: a CSV");
        let other = write(&format!("{name}-foreign.csv"), &foreign(&text));
        let result = |file: &std::path::Path| {
            let mut a = reduce.clone();
            a.extend_from_slice(&["--input", p(file), "--json"]);
            json_of(&run(&a))
        };
        let (a, b) = (result(&plain), result(&other));
        assert!(
            a["coefficients"].as_object().is_some_and(|c| !c.is_empty())
                || a["channels"].as_object().is_some_and(|c| !c.is_empty()),
            "{name}: {a}"
        );
        assert_eq!(a["coefficients"], b["coefficients"], "{name}");
        assert_eq!(a["channels"], b["channels"], "{name}");
        assert_eq!(a["inputs"][0]["rows"], b["inputs"][0]["rows"], "{name}");
        assert_ne!(a["inputs"][0]["sha256"], b["inputs"][0]["sha256"], "{name}");
    }
}
