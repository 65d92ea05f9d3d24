//! The calibration certificate: what ISO/IEC 17025:2017 §7.8.2–7.8.6 asks
//! a certificate to state, around the same results as the report.
//!
//! A laboratory profile ([`LabProfile`], read from `lab.toml`) gives the
//! laboratory, its authorised signatories and the reference standards of
//! each rig:
//!
//! ```toml
//! [lab]
//! name = "Inertial Test Laboratory"          # required
//! address = "1 Gyro Road, Tianjin, China"     # required
//! accreditation = "CNAS L0000 (ISO/IEC 17025:2017)"  # optional
//! certificate_prefix = "ITL-"                 # optional, before the number
//!
//! [[signatory]]                               # at least one
//! name = "Li Wei"
//! role = "Head of calibration"
//!
//! [[standard]]                                # the rigs' reference standards
//! rig = "dividing-head"   # dividing-head, centrifuge, rate-table, thermal-chamber, reference
//! id = "DH-01 (Ultradex 2\")"
//! certificate = "NIM 2026-0457"
//! due = "2027-03-31"                          # YYYY-MM-DD
//! ```
//!
//! [`Certificate`] adds what belongs to one certificate: its unique number,
//! customer, calibration and issue dates, environmental conditions and, for
//! a correction, the certificate it replaces and why. The layout puts the
//! results, the decision rule, the conformity statement, traceability and
//! the authorisation on the first page; inputs, fits, tables and plots
//! follow as annexes. Every printed page carries the certificate number
//! and "page x of y" (CSS page margin boxes), and the last line is the
//! end-of-certificate mark.

use serde::Deserialize;

use incal::document::limits::DecisionRule;
use incal::document::{Procedure, ResultDocument};
use incal::procedures::registry;

use crate::format::esc;

/// The laboratory (`[lab]` of `lab.toml`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lab {
    /// Name of the laboratory.
    pub name: String,
    /// Postal address (several lines joined by `\n` or `, `).
    pub address: String,
    /// Accreditation (body, number, standard), if any.
    #[serde(default)]
    pub accreditation: Option<String>,
    /// Text before every certificate number (`ITL-`).
    #[serde(default)]
    pub certificate_prefix: Option<String>,
    /// ISO 3166-1 alpha-2 code of the laboratory's country (`CN`, `DE`):
    /// the Digital Calibration Certificate's country (`ZZ` when absent).
    #[serde(default)]
    pub country: Option<String>,
}

/// A person authorised to sign certificates (`[[signatory]]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Signatory {
    /// Name.
    pub name: String,
    /// Role or function.
    pub role: String,
}

/// A reference standard of a rig (`[[standard]]`): what makes the
/// calibration traceable.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Standard {
    /// The rig it belongs to: one of [`RIGS`].
    pub rig: String,
    /// Identification (name, model, serial).
    pub id: String,
    /// Its own calibration certificate number.
    pub certificate: String,
    /// Calibration due date, `YYYY-MM-DD`.
    pub due: String,
}

/// The rigs a standard may belong to.
pub const RIGS: [&str; 8] = [
    "dividing-head",
    "centrifuge",
    "rate-table",
    "shaker",
    "thermal-chamber",
    "helmholtz-coil",
    "shock-machine",
    "reference",
];

/// A laboratory profile (`lab.toml`, module docs).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabProfile {
    /// The laboratory.
    pub lab: Lab,
    /// Authorised signatories (at least one).
    #[serde(default)]
    pub signatory: Vec<Signatory>,
    /// Reference standards.
    #[serde(default)]
    pub standard: Vec<Standard>,
}

/// True for a `YYYY-MM-DD` date with a real year (1 to 9999), month and
/// day.
pub fn is_date(s: &str) -> bool {
    let b = s.as_bytes();
    if b.len() != 10 || b[4] != b'-' || b[7] != b'-' {
        return false;
    }
    let num = |r: std::ops::Range<usize>| s[r].parse::<u32>().ok();
    let (Some(y), Some(m), Some(d)) = (num(0..4), num(5..7), num(8..10)) else {
        return false;
    };
    // Year 0 does not exist (the records' dates start at year 1 too).
    if !s[0..4].bytes().all(|c| c.is_ascii_digit()) || y == 0 {
        return false;
    }
    let leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    let days = match m {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap => 29,
        2 => 28,
        _ => return false,
    };
    (1..=days).contains(&d)
}

impl LabProfile {
    /// Parse and check a profile. Errors name the line and the key:
    /// unknown keys, a missing name or address, no signatory, an unknown
    /// rig, a due date that is not `YYYY-MM-DD`.
    pub fn parse(text: &str) -> Result<LabProfile, String> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let line_of = |at: usize| 1 + text[..at.min(text.len())].matches('\n').count();
        let p: LabProfile = toml::from_str(text).map_err(|e| {
            let mut msg = e.message().replace('\n', " ");
            if msg.chars().count() > 200 {
                msg = msg.chars().take(200).collect::<String>() + "…";
            }
            match e.span() {
                Some(s) => format!("line {}: {msg}", line_of(s.start)),
                None => msg,
            }
        })?;
        // Where a key of the n-th `[[table]]` is (its own line, else the
        // table's), for the checks below.
        let nth_line = |table: &str, n: usize, key: &str| -> String {
            let head = format!("[[{table}]]");
            let lines: Vec<&str> = text.lines().collect();
            let Some(start) = lines
                .iter()
                .enumerate()
                .filter(|(_, l)| l.trim_start().starts_with(&head))
                .nth(n)
                .map(|(k, _)| k)
            else {
                return String::new();
            };
            let at = lines[start + 1..]
                .iter()
                .take_while(|l| !l.trim_start().starts_with('['))
                .position(|l| {
                    l.trim_start()
                        .strip_prefix(key)
                        .is_some_and(|r| r.trim_start().starts_with('='))
                })
                .map_or(start, |k| start + 1 + k);
            format!("line {}: ", at + 1)
        };
        if p.lab.name.trim().is_empty() {
            return Err("[lab] name: empty (the laboratory's name is on every certificate)".into());
        }
        if p.lab.address.trim().is_empty() {
            return Err("[lab] address: empty (ISO/IEC 17025 §7.8.2.1 b)".into());
        }
        if p.signatory.is_empty() {
            return Err(
                "no [[signatory]]: give at least one person who authorises certificates (name, role)"
                    .into(),
            );
        }
        for (k, s) in p.signatory.iter().enumerate() {
            if s.name.trim().is_empty() {
                return Err(format!(
                    "{}[[signatory]] name: empty",
                    nth_line("signatory", k, "name")
                ));
            }
        }
        for (k, s) in p.standard.iter().enumerate() {
            let at = |key: &str| nth_line("standard", k, key);
            if !RIGS.contains(&s.rig.as_str()) {
                return Err(format!(
                    "{}[[standard]] rig: '{}' is not a rig ({})",
                    at("rig"),
                    incal_io::clip(&s.rig),
                    RIGS.join(", ")
                ));
            }
            if !is_date(&s.due) {
                return Err(format!(
                    "{}[[standard]] due: '{}' is not a date YYYY-MM-DD",
                    at("due"),
                    incal_io::clip(&s.due)
                ));
            }
            if s.id.trim().is_empty() || s.certificate.trim().is_empty() {
                return Err(format!(
                    "{}[[standard]]: give its id and certificate",
                    at("id")
                ));
            }
        }
        Ok(p)
    }
}

/// What belongs to one certificate besides the result.
#[derive(Debug, Clone, PartialEq)]
pub struct Certificate {
    /// The laboratory profile.
    pub profile: LabProfile,
    /// The unique certificate number (prefix included).
    pub number: String,
    /// The customer, if given.
    pub customer: Option<String>,
    /// Date(s) of calibration, `YYYY-MM-DD` (`None`: not stated).
    pub calibration_date: Option<String>,
    /// Where the calibration date comes from (`--date`, the record).
    pub calibration_date_source: String,
    /// Date of issue, `YYYY-MM-DD`.
    pub issue_date: String,
    /// Environmental conditions during the calibration, if known.
    pub environment: Option<String>,
    /// For a correction: the certificate number it replaces and why.
    pub replaces: Option<(String, String)>,
    /// For a record corrected since: the certificate number that replaces
    /// this one. The certificate then says on its first page that it is
    /// withdrawn.
    pub superseded_by: Option<String>,
}

/// The environment the recording itself recorded (its `temperature_c` and
/// `humidity_pct` columns, summarised in the result's `environment`):
/// `temperature 20.1 degC (19.8 to 20.4), relative humidity 45 % (…), from
/// the recording`.
pub fn recorded_environment(doc: &incal::document::ResultDocument) -> Option<String> {
    let env = doc.extra.get("environment")?.as_object()?;
    let part = |key: &str, what: &str, unit: &str| {
        let e = env.get(key)?;
        let (m, lo, hi) = (
            e.get("mean")?.as_f64()?,
            e.get("min")?.as_f64()?,
            e.get("max")?.as_f64()?,
        );
        Some(format!("{what} {m:.1} {unit} ({lo:.1} to {hi:.1})"))
    };
    let parts: Vec<String> = [
        part("temperature_c", "temperature", "degC"),
        part("humidity_pct", "relative humidity", "%"),
    ]
    .into_iter()
    .flatten()
    .collect();
    (!parts.is_empty()).then(|| format!("{}, from the recording", parts.join(", ")))
}

/// The rig whose reference standards make a procedure traceable (`None`:
/// no rig standard enters the result), from the procedure registry.
pub fn rig_of(p: Procedure) -> Option<&'static str> {
    registry::first_of(p).and_then(|e| e.rig)
}

/// The rig of one result: the `rig` its options record when it is one of
/// [`RIGS`] (a procedure run on more than one kind of rig, such as the
/// dynamic response on a rate table or a shaker), else [`rig_of`] its
/// procedure.
pub fn rig_of_document(doc: &ResultDocument) -> Option<&'static str> {
    let chosen = doc.options.get("rig").and_then(|v| v.as_str());
    match chosen.and_then(|r| RIGS.iter().find(|x| **x == r)) {
        Some(r) if rig_of(doc.procedure).is_some() => Some(r),
        _ => rig_of(doc.procedure),
    }
}

/// The method of a procedure: the standards and the paper it follows, by
/// title, authors, venue and year, from the procedure registry.
pub fn method_of(p: Procedure) -> &'static str {
    registry::first_of(p).map_or("", |e| e.method)
}

/// The decision rule as stated on a certificate (ILAC-G8:09/2019).
pub fn decision_rule_text(rule: DecisionRule) -> &'static str {
    match rule {
        DecisionRule::Simple => "Simple acceptance (ILAC-G8:09/2019 §4.2.1, guard band w = 0): a value inside the tolerance interval passes, whatever its uncertainty. The probability of a false acceptance can reach 50 % for a value at a limit.",
        DecisionRule::GuardBand => "Guarded acceptance (ILAC-G8:09/2019 §4.2.2, guard band w = U, the expanded uncertainty for about 95 % coverage): pass when the value minus and plus U lies inside the tolerance interval, fail when it lies wholly outside; otherwise conditional pass (value inside) or conditional fail (value outside), with a probability of a false decision of up to 50 %. A pass or fail so stated carries a risk of a false decision below 2.5 %.",
    }
}

/// The conformity statement for an overall verdict word.
fn conformity_text(verdict: &str) -> &'static str {
    match verdict {
        "pass" => "The item conforms to the specification.",
        "conditional-pass" => "The measured values conform to the specification, but conformity cannot be stated at the 95 % level for every coefficient (conditional pass).",
        "not-determined" => "Conformity cannot be stated: a specified coefficient was not determined by this calibration.",
        "conditional-fail" => "A measured value lies outside the specification, but non-conformity cannot be stated at the 95 % level (conditional fail).",
        _ => "The item does not conform to the specification.",
    }
}

/// `(YYYY, MM, DD)` ordering of two dates as text (both `YYYY-MM-DD`).
fn before(a: &str, b: &str) -> bool {
    a < b
}

/// A two-column table row `label | value` with an id for checks.
fn row(id: &str, label: &str, value_html: &str) -> String {
    format!(
        "<tr id=\"{id}\"><th>{}</th><td>{value_html}</td></tr>\n",
        esc(label)
    )
}

/// The traceability statement (ISO/IEC 17025 §7.8.4.1 c): the rig's
/// reference standards from the laboratory profile, each overdue one
/// flagged, or why no rig standard enters the result.
fn traceability(s: &mut String, doc: &ResultDocument, c: &Certificate) {
    s.push_str("<div id=\"traceability\">");
    match rig_of_document(doc) {
        None => s.push_str("<p><b>Traceability.</b> The results are derived from the instrument's own record and its time base; no reference standard of a rig enters them.</p>"),
        Some(rig) => {
            let used: Vec<&Standard> = c.profile.standard.iter().filter(|x| x.rig == rig).collect();
            if used.is_empty() {
                s.push_str(&format!(
                    "<p><b>Traceability.</b> <span class=\"missing\">No reference standard of the {rig} is listed in the laboratory profile: traceability is not stated.</span></p>"
                ));
            } else {
                s.push_str(&format!("<p><b>Traceability.</b> The reference standards of the {rig} used are calibrated with metrological traceability to the International System of Units (SI):</p>\n<table class=\"standards\"><thead><tr><th>standard</th><th>certificate</th><th>due</th></tr></thead><tbody>\n"));
                for x in used {
                    let overdue = c
                        .calibration_date
                        .as_deref()
                        .is_some_and(|d| before(&x.due, d));
                    s.push_str(&format!(
                        "<tr><td>{}</td><td>{}</td><td>{}{}</td></tr>\n",
                        esc(&x.id),
                        esc(&x.certificate),
                        esc(&x.due),
                        if overdue {
                            " <span class=\"missing\">overdue on the date of calibration</span>"
                        } else {
                            ""
                        }
                    ));
                }
                s.push_str("</tbody></table>");
            }
        }
    }
    s.push_str("</div>\n");
}

/// The first page: laboratory, identification, results, decision rule and
/// conformity, traceability, statements and authorisation.
pub(crate) fn front_html(
    doc: &ResultDocument,
    c: &Certificate,
    results_html: &str,
    record_html: Option<String>,
) -> String {
    let lab = &c.profile.lab;
    let mut s = String::from("<header id=\"certificate\">\n<div id=\"lab\">");
    s.push_str(&format!(
        "<div id=\"lab-name\">{}</div><div id=\"lab-address\">{}</div>",
        esc(&lab.name),
        esc(&lab.address).replace('\n', "<br>")
    ));
    if let Some(a) = &lab.accreditation {
        s.push_str(&format!(
            "<div id=\"lab-accreditation\">Accreditation: {}</div>",
            esc(a)
        ));
    }
    s.push_str("</div>\n");
    s.push_str(&format!(
        "<h1>Calibration certificate <span id=\"certificate-number\">{}</span><span class=\"sub\">{}</span></h1>\n",
        esc(&c.number),
        esc(&doc.title)
    ));
    if let Some(new) = &c.superseded_by {
        s.push_str(&format!(
            "<p id=\"superseded\" class=\"replaces\"><strong>Withdrawn:</strong> this certificate was replaced by certificate {}; it is not valid.</p>\n",
            esc(new)
        ));
    }
    if let Some((old, why)) = &c.replaces {
        s.push_str(&format!(
            "<p id=\"replaces\" class=\"replaces\">This certificate replaces certificate {}. Reason: {}</p>\n",
            esc(old),
            esc(why)
        ));
    }
    let inst = &doc.instrument;
    let mut item = Vec::new();
    if let Some(m) = &inst.model {
        item.push(format!("model {}", esc(m)));
    }
    item.push(format!(
        "serial {}",
        esc(inst.serial.as_deref().unwrap_or("not given"))
    ));
    for (k, v) in &inst.meta {
        item.push(format!("{} {}", esc(k), esc(v)));
    }
    s.push_str("<table class=\"identity certificate\">\n<tbody>\n");
    s.push_str(&row(
        "customer",
        "Customer",
        &esc(c.customer.as_deref().unwrap_or("not stated")),
    ));
    s.push_str(&row("item", "Item calibrated", &item.join(", ")));
    s.push_str(&row("method", "Method", &esc(method_of(doc.procedure))));
    s.push_str(&row(
        "calibration-date",
        "Date of calibration",
        &match &c.calibration_date {
            Some(d) => format!("{} ({})", esc(d), esc(&c.calibration_date_source)),
            None => "<span class=\"missing\">not stated (give --date)</span>".into(),
        },
    ));
    s.push_str(&row("issue-date", "Date of issue", &esc(&c.issue_date)));
    s.push_str(&row(
        "environment",
        "Environmental conditions",
        &match (&c.environment, recorded_environment(doc)) {
            (Some(e), _) => esc(e),
            (None, Some(e)) => esc(&e),
            (None, None) => "<span class=\"missing\">not recorded</span>".into(),
        },
    ));
    if let Some(r) = record_html {
        s.push_str(&row("record", "Record", &r));
    }
    // Data preprocessing (outliers removed, gaps filled, drift removed):
    // what was done to the record before the results, stated up front.
    if let Some(steps) = doc.extra.get("preprocessing").and_then(|v| v.as_array()) {
        let lines: Vec<String> = steps
            .iter()
            .filter_map(|s| s.get("summary").and_then(|v| v.as_str()))
            .map(esc)
            .collect();
        s.push_str(&row(
            "preprocessing",
            "Data preprocessing",
            &format!(
                "{} (row by row in the annex table “preprocessing”)",
                lines.join("; ")
            ),
        ));
    }
    s.push_str("</tbody>\n</table>\n</header>\n");

    s.push_str(results_html);

    // Decision rule and conformity (ISO/IEC 17025 §7.8.6).
    s.push_str("<section id=\"statements\">\n");
    match (doc.decision_rule, doc.verdict) {
        (Some(rule), Some(v)) => {
            let spec = doc
                .inputs
                .iter()
                .find(|i| i.role == "limits")
                .map_or("the limits given".to_string(), |i| {
                    format!(
                        "limits file {} (SHA-256 {})",
                        i.path,
                        &i.sha256[..i.sha256.len().min(16)]
                    )
                });
            s.push_str(&format!(
                "<p id=\"decision-rule\"><b>Decision rule.</b> {}</p>\n",
                esc(decision_rule_text(rule))
            ));
            s.push_str(&format!(
                "<p id=\"conformity\"><b>Statement of conformity</b> (specification: {}): <span class=\"verdict verdict-{v}\">{v}</span>. {}</p>\n",
                esc(&spec),
                esc(conformity_text(v.as_str()))
            ));
        }
        _ => s.push_str(
            "<p id=\"conformity\"><b>Statement of conformity:</b> none requested (no specification given); the results are reported without a decision rule.</p>\n",
        ),
    }
    s.push_str("<p id=\"uncertainty-statement\">The expanded uncertainty U95 = k95·u is the standard uncertainty multiplied by the coverage factor k95 from the Student t distribution for the stated degrees of freedom, giving a coverage probability of about 95 %; it was evaluated according to JCGM 100:2008 (GUM).</p>\n");

    // Traceability (§7.8.4.1 c, via the reference standards).
    traceability(&mut s, doc, c);
    s.push_str("<p id=\"relate-only\">The results relate only to the item calibrated. This certificate shall not be reproduced except in full without the written approval of the laboratory.</p>\n");

    // Authorisation (§7.8.2.1 o).
    s.push_str(
        "<div id=\"authorisation\"><b>Authorised by</b><table class=\"signatories\"><tbody>\n",
    );
    for sg in &c.profile.signatory {
        s.push_str(&format!(
            "<tr class=\"signatory\"><td>{}</td><td>{}</td><td class=\"signature\">signature: ____________________</td></tr>\n",
            esc(&sg.name),
            esc(&sg.role)
        ));
    }
    s.push_str("</tbody></table></div>\n</section>\n");
    s
}

/// Print CSS of a certificate: the number and "page x of y" on every
/// page, annexes from the second page on, no page that holds only a
/// heading.
pub(crate) fn print_css(number: &str) -> String {
    // The number is quoted as a CSS string: escaped for that context.
    let quoted = crate::format::css_string(number);
    format!(
        r#"
#lab-name {{ font-size: 1.3em; font-weight: bold; }}
#lab {{ border-bottom: 2px solid #333; padding-bottom: 0.3em; margin-bottom: 0.6em; }}
table.certificate th {{ width: 13em; }}
.missing {{ color: #b00000; font-weight: bold; }}
.replaces {{ border: 1px solid #b00000; padding: 0.3em; }}
#statements p {{ margin: 0.35em 0; }}
td.signature {{ color: #555; }}
#end-of-certificate {{ text-align: center; margin-top: 1.5em; font-weight: bold; }}
.annex-start {{ margin-top: 2em; }}
@media print {{
  @page {{
    size: A4; margin: 15mm 15mm 18mm;
    @bottom-left {{ content: "Certificate {quoted}"; font-size: 8pt; }}
    @bottom-right {{ content: "page " counter(page) " of " counter(pages); font-size: 8pt; }}
  }}
  section {{ page-break-before: auto; break-before: auto; }}
  .annex-start {{ page-break-before: always; break-before: page; margin-top: 0; }}
  h2, h3 {{ page-break-after: avoid; break-after: avoid; }}
  #statements, #authorisation, table.certificate {{ page-break-inside: avoid; break-inside: avoid; }}
  figure.plot svg {{ max-height: 95mm; }}
}}
"#
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAB: &str = r#"
[lab]
name = "ITL"
address = "1 Gyro Road"
[[signatory]]
name = "Li Wei"
role = "Head"
[[standard]]
rig = "dividing-head"
id = "DH-01"
certificate = "C-1"
due = "2027-03-31"
"#;

    #[test]
    fn a_profile_is_read_and_checked_at_its_line() {
        let p = LabProfile::parse(LAB).unwrap();
        assert_eq!(p.standard[0].rig, "dividing-head");
        let bad = LAB.replace("dividing-head", "dividing head");
        let e = LabProfile::parse(&bad).unwrap_err();
        assert!(e.starts_with("line 9: [[standard]] rig:"), "{e}");
        let e = LabProfile::parse(&LAB.replace("2027-03-31", "2027-02-30")).unwrap_err();
        assert!(e.starts_with("line 12: [[standard]] due:"), "{e}");
        let e = LabProfile::parse(&LAB.replace("role = \"Head\"", "role = \"Head\"\nrank = 1"))
            .unwrap_err();
        assert!(e.starts_with("line 8:") && e.contains("rank"), "{e}");
        let e = LabProfile::parse(
            &LAB.replace("[[signatory]]\nname = \"Li Wei\"\nrole = \"Head\"\n", ""),
        )
        .unwrap_err();
        assert!(e.contains("signatory"), "{e}");
    }

    #[test]
    fn dates_are_real_days() {
        assert!(is_date("2024-02-29"));
        assert!(!is_date("2023-02-29"));
        assert!(!is_date("2026-13-01"));
        assert!(!is_date("2026-1-01"));
        assert!(!is_date("+026-01-01"));
    }

    #[test]
    fn every_procedure_has_a_method_and_a_rig_or_says_why_not() {
        for p in Procedure::all() {
            assert!(method_of(p).len() > 40, "{p}");
            assert!(!method_of(p).to_lowercase().contains("seed"), "{p}");
            if let Some(r) = rig_of(p) {
                assert!(RIGS.contains(&r));
            }
        }
    }
}
