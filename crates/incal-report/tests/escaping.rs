//! No string that is not incal's own constant can put markup, a script or
//! a style into a report or certificate: every string field of real result
//! documents (one at a time), every field of the laboratory profile and of
//! the certificate, and what a store contributes (its path, the record
//! dates), each filled with HTML, CSS, SVG and script payloads, and the
//! page parsed as a browser parses it. Each lands escaped for its context
//! (HTML text, attribute, CSS string, inline SVG).

use incal::document::ResultDocument;
use incal::procedures::registry;
use incal_report::certificate::{Certificate, Lab, LabProfile, Signatory, Standard};
use incal_report::{render_html_with, HistoryPoint, HistorySeries, RecordStamp, RenderOptions};
use scraper::{Html, Selector};
use serde_json::Value;

/// Payloads for every output context: closing the style element, an
/// attribute break-out, an SVG handler, a comment that would swallow the
/// rest, a CSS string break-out and a backslash at the end.
const PAYLOADS: [&str; 6] = [
    "</style><script>alert(1)</script>",
    "\"><img src=x onerror=alert(2)>",
    "'><svg onload=alert(3)></svg>",
    "<!-- x",
    "\"; } body { background: red } #x { content: \"",
    "x\\",
];

fn sel(s: &str) -> Selector {
    Selector::parse(s).unwrap()
}

/// The structure of a style sheet: its quotes, braces and semicolons (the
/// same count with and without a payload means no string, rule or
/// declaration was ended or started by it).
fn css_shape(css: &str) -> [usize; 4] {
    ['"', '{', '}', ';'].map(|c| css.matches(c).count())
}

/// The page as a browser reads it: no active element, no handler, one
/// style element that holds no markup and has the shape of incal's own
/// (`css`), and the page whole (its last element present, not commented
/// out).
fn assert_inert(html: &str, css: [usize; 4], what: &str) {
    let doc = Html::parse_document(html);
    for tag in [
        "script",
        "img",
        "iframe",
        "object",
        "embed",
        "link",
        "base",
        "form",
        "foreignObject",
    ] {
        assert_eq!(
            doc.select(&sel(tag)).count(),
            0,
            "{what}: a <{tag}> element"
        );
    }
    for el in doc.select(&sel("*")) {
        for (name, value) in el.value().attrs() {
            assert!(
                !name.to_ascii_lowercase().starts_with("on"),
                "{what}: handler {name}=\"{value}\" on <{}>",
                el.value().name()
            );
            assert!(!value.contains("javascript:"), "{what}: {name}=\"{value}\"");
        }
    }
    let styles: Vec<String> = doc
        .select(&sel("style"))
        .map(|s| s.text().collect())
        .collect();
    assert_eq!(styles.len(), 1, "{what}: one style element");
    assert!(!styles[0].contains('<'), "{what}: markup in the CSS");
    assert_eq!(
        css_shape(&styles[0]),
        css,
        "{what}: the CSS's shape changed"
    );
    assert!(
        doc.select(&sel("footer, #end-of-certificate")).count() > 0,
        "{what}: the page ends where incal ends it"
    );
}

/// A result document of the registry's worked case of `id`.
fn real(id: &str) -> ResultDocument {
    let e = registry::find(id).unwrap();
    let sim = e.simulator.unwrap();
    let red = e.reduction.unwrap();
    let mut csv = Vec::new();
    let opts = match id {
        "tumble" => serde_json::json!({"seed": 11, "passes": 2}),
        _ => serde_json::json!({"seed": 16, "samples": 4}),
    };
    (sim.run)(&opts, &mut csv).unwrap();
    let example = (red.example.unwrap())();
    let read = incal_io::ReadOptions::default();
    let mut doc = (red.run)(
        "rec.csv",
        &mut &csv[..],
        &read,
        &example,
        &incal::procedures::Silent,
        None,
    )
    .unwrap();
    doc.instrument.serial = Some("SN-1".into());
    doc
}

/// Every string leaf of `v`, as a list of paths (object keys and array
/// indices).
fn string_leaves(v: &Value, path: &mut Vec<Value>, out: &mut Vec<Vec<Value>>) {
    match v {
        Value::String(_) => out.push(path.clone()),
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                path.push(i.into());
                string_leaves(x, path, out);
                path.pop();
            }
        }
        Value::Object(m) => {
            for (k, x) in m {
                path.push(k.clone().into());
                string_leaves(x, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

fn at<'a>(v: &'a mut Value, path: &[Value]) -> &'a mut Value {
    path.iter().fold(v, |v, k| match k {
        Value::String(s) => &mut v[s.as_str()],
        Value::Number(i) => &mut v[i.as_u64().unwrap() as usize],
        _ => unreachable!(),
    })
}

fn hostile_profile(p: &str) -> LabProfile {
    LabProfile {
        lab: Lab {
            name: p.into(),
            address: format!("{p}\n{p}"),
            accreditation: Some(p.into()),
            certificate_prefix: Some(p.into()),
            country: Some(p.into()),
        },
        signatory: vec![Signatory {
            name: p.into(),
            role: p.into(),
        }],
        standard: vec![Standard {
            rig: "dividing-head".into(),
            id: p.into(),
            certificate: p.into(),
            due: "2099-01-01".into(),
        }],
    }
}

fn hostile_options(p: &str) -> RenderOptions {
    RenderOptions {
        date: Some(p.into()),
        record: Some(RecordStamp {
            store: format!("/lab/{p}.db"),
            id: Some(3),
            records: 3,
            head: p.into(),
        }),
        certificate: Some(Certificate {
            profile: hostile_profile(p),
            number: format!("{p}000003"),
            customer: Some(p.into()),
            calibration_date: Some(p.into()),
            calibration_date_source: p.into(),
            issue_date: p.into(),
            environment: Some(p.into()),
            replaces: Some((p.into(), p.into())),
            superseded_by: Some(p.into()),
        }),
    }
}

fn hostile_history(doc: &ResultDocument, p: &str) -> Vec<HistorySeries> {
    let (name, c) = doc.coefficients.iter().next().unwrap();
    vec![HistorySeries {
        coefficient: format!("{name}{p}"),
        unit: c.unit.clone(),
        points: (0..3)
            .map(|i| HistoryPoint {
                id: i,
                created_utc: format!("2026-0{}-01T00:00:00Z{p}", i + 1),
                value: c.value,
                u95: c.u.max(1e-9),
            })
            .collect(),
        min: None,
        max: None,
        drift: None,
    }]
}

/// The shape of the CSS of a certificate of `doc` with plain text.
fn plain_css(doc: &ResultDocument) -> [usize; 4] {
    let html = render_html_with(doc, &[], &hostile_options("plain")).unwrap();
    let parsed = Html::parse_document(&html);
    let css: String = parsed
        .select(&sel("style"))
        .next()
        .unwrap()
        .text()
        .collect();
    css_shape(&css)
}

#[test]
fn every_certificate_profile_store_and_history_field_is_escaped() {
    let doc = real("tumble");
    let css = plain_css(&doc);
    for p in PAYLOADS {
        let html = render_html_with(&doc, &hostile_history(&doc, p), &hostile_options(p)).unwrap();
        assert_inert(
            &html,
            css,
            &format!("payload {p:?} in the profile and certificate"),
        );
        let parsed = Html::parse_document(&html);
        let text: String = parsed.root_element().text().collect();
        assert!(text.contains(p), "{p:?} reads as text on the page");
    }
}

#[test]
fn every_string_of_real_documents_is_escaped_wherever_it_lands() {
    let mut fields = 0;
    for id in ["tumble", "gyro-rate"] {
        let doc = real(id);
        let css = plain_css(&doc);
        let base = serde_json::to_value(&doc).unwrap();
        let mut leaves = Vec::new();
        string_leaves(&base, &mut Vec::new(), &mut leaves);
        assert!(leaves.len() > 20, "{id}: {} strings", leaves.len());
        for (k, path) in leaves.iter().enumerate() {
            let p = PAYLOADS[k % PAYLOADS.len()];
            let mut v = base.clone();
            let cell = at(&mut v, path);
            *cell = Value::String(format!("{}{p}", cell.as_str().unwrap()));
            // A field the document check refuses so changed (a unit, an
            // id) never reaches a report.
            let Ok(doc) = ResultDocument::from_json(&v.to_string()) else {
                continue;
            };
            fields += 1;
            let html = render_html_with(&doc, &[], &hostile_options("plain")).unwrap();
            assert_inert(&html, css, &format!("{id}: payload {p:?} at {path:?}"));
        }
    }
    assert!(fields > 40, "only {fields} fields reached a report");
}

#[test]
fn every_dcc_field_is_escaped() {
    let mut doc = real("tumble");
    for p in PAYLOADS {
        doc.instrument.serial = Some(p.into());
        doc.instrument.model = Some(p.into());
        doc.title = p.into();
        let info = incal_report::dcc::DccInfo {
            number: p.into(),
            lab_name: p.into(),
            lab_address: p.into(),
            country: p.into(),
            customer: Some(p.into()),
            calibration_date: "2026-12-01".into(),
            issue_date: "2026-12-01".into(),
            signatory: Some((p.into(), p.into())),
            record: Some(p.into()),
        };
        let xml = incal_report::dcc::dcc_xml(&doc, &info);
        // Every markup character of a payload is escaped: the only tags
        // are the DCC's and D-SI's own.
        for tag in xml.split('<').skip(1) {
            let name = tag.split([' ', '>']).next().unwrap_or("");
            assert!(
                ["?xml", "dcc:", "/dcc:", "si:", "/si:"]
                    .iter()
                    .any(|ok| name.starts_with(ok)),
                "payload {p:?} made the tag <{name}"
            );
        }
        assert!(!xml.contains(p) || !p.contains(['<', '>', '"', '\'', '&']));
        assert!(
            xml.contains("<dcc:countryCodeISO3166_1>ZZ<"),
            "a country code that is not one is ZZ"
        );
    }
}
