//! Records for people and programs: the list of records, one record's
//! heading and the history of one coefficient (drift per day,
//! repeatability, En of the latest), as text in engineering units and as
//! JSON (non-finite numbers as `null`). Every front end renders records
//! through these.

use incal_records::{History, RecordSummary, StoredRecord, Verified};
use serde_json::{json, Value};

use crate::format::{dof_text, measured, sig, trimmed};
use crate::text::table;

/// `{"records": [{id, serial, procedure, created_utc, sha256, operator,
/// station, superseded_by}, …], "chain": {"records", "head"}}`: the chain
/// checked whole, and its head (the `record_hash` of the last record) to
/// write down for `incal record verify --head`.
pub fn list_json(records: &[RecordSummary], chain: &Verified) -> Value {
    let rows: Vec<Value> = records
        .iter()
        .map(|r| {
            json!({
                "id": r.id,
                "serial": r.serial,
                "procedure": r.procedure,
                "created_utc": r.created_utc,
                "sha256": r.sha256,
                "operator": r.operator,
                "station": r.station,
                "superseded_by": r.superseded_by,
            })
        })
        .collect();
    json!({ "records": rows, "chain": {"records": chain.records, "head": chain.head} })
}

/// `text` for a terminal: control characters (ESC, newline, …) and the
/// bidirectional overrides and isolates (which reorder what follows) as
/// `\u{…}` escapes, so a name cannot move the cursor, break a line or
/// hide text.
pub fn printable(text: &str) -> String {
    let bidi = |c: char| matches!(c, '\u{200E}' | '\u{200F}' | '\u{061C}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}');
    text.chars()
        .map(|c| {
            if c.is_control() || bidi(c) {
                format!("\\u{{{:04x}}}", c as u32)
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// The records as a table (`no records` when there are none), then the
/// line `chain: N records, hash chain intact; head HEX`.
pub fn list_text(records: &[RecordSummary], chain: &Verified) -> String {
    let foot = format!(
        "chain: {} records, hash chain intact; head {}\n",
        chain.records, chain.head
    );
    if records.is_empty() {
        return format!("no records\n{foot}");
    }
    let dash = |s: &Option<String>| s.as_deref().map_or_else(|| "-".into(), printable);
    let rows: Vec<Vec<String>> = records
        .iter()
        .map(|r| {
            vec![
                r.id.to_string(),
                printable(&r.serial),
                printable(&r.procedure),
                r.created_utc.clone(),
                r.sha256[..16.min(r.sha256.len())].to_string(),
                dash(&r.operator),
                dash(&r.station),
                r.superseded_by.map_or("-".into(), |s| s.to_string()),
            ]
        })
        .collect();
    table(
        &[
            "id",
            "serial",
            "procedure",
            "created_utc",
            "sha256",
            "operator",
            "station",
            "superseded_by",
        ],
        &rows,
    ) + &foot
}

/// The heading of `incal record show`: id, serial, time, hash, who, and
/// what it supersedes or is superseded by.
pub fn header_text(r: &StoredRecord) -> String {
    let mut s = format!(
        "record {} of serial {}, {} (sha256 {})\n",
        r.id,
        printable(&r.serial),
        r.created_utc,
        r.sha256
    );
    let who: Vec<String> = [("operator", &r.operator), ("station", &r.station)]
        .iter()
        .filter_map(|(k, v)| v.as_ref().map(|v| format!("{k} {}", printable(v))))
        .collect();
    if !who.is_empty() {
        s.push_str(&format!("{}\n", who.join(", ")));
    }
    if let Some(sup) = &r.supersedes {
        s.push_str(&format!(
            "supersedes record {}: {}\n",
            sup.old_id,
            printable(&sup.reason)
        ));
    }
    if let Some(by) = r.superseded_by {
        s.push_str(&format!("SUPERSEDED by record {by}\n"));
    }
    s
}

fn num(x: Option<f64>) -> Value {
    x.filter(|v| v.is_finite()).map_or(Value::Null, Value::from)
}

/// The JSON of a history (manual, chapter "Calibration records"):
/// serial, coefficient, unit, points, drift_per_day, repeatability,
/// En_latest, notes.
pub fn history_json(h: &History) -> Value {
    let points: Vec<Value> = h
        .points
        .iter()
        .map(|p| {
            json!({
                "id": p.id,
                "created_utc": p.created_utc,
                "value": num(Some(p.value)),
                "u": num(Some(p.u)),
                "U95": num(Some(p.u95)),
                "dof": num(p.dof),
                "temperature_c": num(p.temperature_c),
            })
        })
        .collect();
    let d = h.drift.as_ref();
    let r = h.repeatability.as_ref();
    json!({
        "serial": h.serial,
        "coefficient": h.coefficient,
        "unit": h.unit.as_str(),
        "points": points,
        "drift_per_day": {
            "value": num(d.map(|d| d.value)),
            "u": num(d.map(|d| d.u)),
            "dof": num(d.and_then(|d| d.dof)),
            "unit": format!("{}/day", h.unit),
            "variance_source": d.map(|d| json!(d.variance_source)),
        },
        "repeatability": {
            "value": num(r.map(|r| r.value)),
            "dof": num(r.map(|r| r.dof)),
        },
        "En_latest": num(h.en_latest),
        "notes": h.notes,
    })
}

/// The readable history of one coefficient.
pub fn history_text(h: &History) -> String {
    let mag = h.points.iter().map(|p| p.value.abs()).fold(0.0, f64::max);
    let (scale, label) = h.unit.engineering_for(mag);
    let dof = dof_text;
    let mut s = format!(
        "{} of serial {}: {} calibration{} (superseded records left out)\n",
        h.coefficient,
        h.serial,
        h.points.len(),
        if h.points.len() == 1 { "" } else { "s" }
    );
    let rows: Vec<Vec<String>> = h
        .points
        .iter()
        .map(|p| {
            let (value, u, u95) = measured(p.value * scale, p.u * scale, p.u95 * scale);
            vec![
                p.id.to_string(),
                p.created_utc.clone(),
                value,
                u,
                u95,
                dof(p.dof),
                label.to_string(),
                p.temperature_c.map_or("-".into(), |t| trimmed(t, 4)),
            ]
        })
        .collect();
    // The temperature column only when some calibration states one.
    let with_t = h.points.iter().any(|p| p.temperature_c.is_some());
    let mut header = vec!["id", "created_utc", "value", "u", "U95", "dof", "unit"];
    let rows: Vec<Vec<String>> = if with_t {
        header.push("temperature_c");
        rows
    } else {
        rows.into_iter()
            .map(|mut r| {
                r.pop();
                r
            })
            .collect()
    };
    s.push_str(&table(&header, &rows));
    s.push('\n');
    match &h.drift {
        Some(d) => {
            let src = match d.variance_source {
                incal::estimation::VarianceSource::Prior => "from the calibrations' u",
                incal::estimation::VarianceSource::Residuals => {
                    "scaled up: the values scatter beyond their u"
                }
            };
            s.push_str(&format!(
                "drift: {} {label}/day, u {} (dof {}; {src})\n",
                sig(d.value * scale, 4),
                sig(d.u * scale, 3),
                dof(d.dof)
            ));
        }
        None => s.push_str("drift: -\n"),
    }
    match &h.repeatability {
        Some(r) => s.push_str(&format!(
            "repeatability: {} {label} (standard deviation of the values, dof {})\n",
            sig(r.value * scale, 3),
            r.dof
        )),
        None => s.push_str("repeatability: -\n"),
    }
    match h.en_latest {
        Some(en) => s.push_str(&format!(
            "En of the latest against the previous: {} ({})\n",
            sig(en, 3),
            if en.abs() <= 1.0 { "agrees" } else { "DIFFERS" }
        )),
        None => s.push_str("En of the latest against the previous: -\n"),
    }
    for n in &h.notes {
        s.push_str(&format!("note: {n}\n"));
    }
    s.push_str("method: drift by weighted least squares x = a + b t (t in days, weights 1/u^2); En = (x_n - x_n-1)/sqrt(U95_n^2 + U95_n-1^2)\n");
    s
}

/// One record as `incal record show --json` writes it: its identity, the
/// chain's hashes, its supersession either way, and the stored document
/// under `result`, verbatim; the error says why a stored document is no
/// longer JSON.
pub fn show_json(r: &StoredRecord) -> Result<String, String> {
    #[derive(serde::Serialize)]
    struct ShowJson<'a> {
        id: i64,
        serial: &'a str,
        procedure: &'a str,
        created_utc: &'a str,
        operator: Option<&'a str>,
        station: Option<&'a str>,
        sha256: &'a str,
        record_hash: &'a str,
        prev_hash: &'a str,
        supersedes: Option<Value>,
        superseded_by: Option<i64>,
        result: &'a serde_json::value::RawValue,
    }
    let raw = serde_json::value::RawValue::from_string(r.document.trim().to_string())
        .map_err(|e| format!("the stored document is not JSON: {e}"))?;
    let j = ShowJson {
        id: r.id,
        serial: &r.serial,
        procedure: &r.procedure,
        created_utc: &r.created_utc,
        operator: r.operator.as_deref(),
        station: r.station.as_deref(),
        sha256: &r.sha256,
        record_hash: &r.record_hash,
        prev_hash: &r.prev_hash,
        supersedes: r
            .supersedes
            .as_ref()
            .map(|s| serde_json::json!({"id": s.old_id, "reason": s.reason})),
        superseded_by: r.superseded_by,
        result: &raw,
    };
    let s = serde_json::to_string_pretty(&j).map_err(|e| format!("cannot print: {e}"))?;
    Ok(format!("{s}\n"))
}

#[cfg(test)]
mod tests {
    #[test]
    fn names_print_without_control_or_bidi_characters() {
        assert_eq!(
            super::printable("SN\u{1b}[2J-1\n"),
            "SN\\u{001b}[2J-1\\u{000a}"
        );
        assert_eq!(super::printable("a\u{202E}b"), "a\\u{202e}b");
        assert_eq!(super::printable("Müller 北京"), "Müller 北京");
    }
}
