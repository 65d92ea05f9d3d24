//! The report parsed as HTML: every section, the coefficient table, every
//! document table, plots as inline SVG, nothing referenced outside the
//! file, every text escaped; history plots with limits; verdicts.

use incal::document::{
    Cell, Coefficient, DecisionCode, DocumentBuilder, Procedure, ResultDocument, Table, Warning,
    WarningCode,
};
use incal::units::Unit;
use incal_report::{render_html, render_html_with, HistoryPoint, HistorySeries, RenderOptions};
use scraper::{Html, Selector};

fn sel(s: &str) -> Selector {
    Selector::parse(s).unwrap()
}

/// Nothing in `html` loads from elsewhere: no `src`, `href`, `srcset`,
/// `action`, `data` or `xlink:href` attribute, no `<script>`, `<link>`,
/// `<iframe>`, `<object>` or `<img>`, no CSS `url(` or `@import`, and no
/// address (`://`) anywhere.
fn assert_self_contained(html: &str) {
    let doc = Html::parse_document(html);
    for el in doc.select(&sel("*")) {
        for (name, value) in el.value().attrs() {
            assert!(
                !matches!(
                    name,
                    "src" | "href" | "srcset" | "action" | "data" | "xlink:href" | "poster"
                ),
                "<{} {name}=\"{value}\">",
                el.value().name()
            );
            assert!(!value.contains("url("), "{name}=\"{value}\"");
        }
    }
    for tag in ["script", "link", "iframe", "object", "embed", "img", "base"] {
        assert_eq!(doc.select(&sel(tag)).count(), 0, "<{tag}>");
    }
    for style in doc.select(&sel("style")) {
        let css: String = style.text().collect();
        assert!(!css.contains("url("), "CSS url(");
        assert!(!css.contains("@import"), "CSS @import");
    }
    assert!(!html.contains("://"), "an address in the file");
}

/// A document of an imaginary procedure with hostile text everywhere,
/// two accelerometer-like blocks (dotted names) and one table with
/// residuals.
fn hostile() -> ResultDocument {
    let evil = "<script>alert(1)</script>";
    let mut b = DocumentBuilder::new(Procedure::Tumble, format!("Title {evil}"));
    for (name, v, unit) in [
        ("a.K0", 1e-4, Unit::Output),
        ("b.K0", -2e-4, Unit::Output),
        ("a.misalignment_rad", 2e-3, Unit::Rad),
        ("b.misalignment_rad", 1e-3, Unit::Rad),
    ] {
        b.coefficient(
            name,
            Coefficient::new(name, v, v.abs() / 10.0, unit, 12.0).unwrap(),
        )
        .unwrap();
    }
    let mut t = Table::new(
        "positions",
        &format!("Positions {evil}"),
        &[
            ("angle", Some(Unit::Deg)),
            ("pass", None),
            ("n", None),
            ("mean", Some(Unit::Output)),
            ("std", Some(Unit::Output)),
            ("residual", Some(Unit::Output)),
        ],
    );
    for (k, pass) in [(0.0, "cw"), (90.0, evil), (180.0, "cw"), (270.0, evil)] {
        t.push(vec![
            Cell::num(k),
            Cell::text(pass),
            Cell::num(5.0),
            Cell::num(f64::to_radians(k).sin()),
            Cell::num(1e-3),
            Cell::num(1e-4),
        ])
        .unwrap();
    }
    b.table(t);
    b.warnings([Warning::new(WarningCode::LackOfFit, evil.to_string())]);
    b.decision(DecisionCode::VarianceSource, evil);
    let mut doc = b.finish();
    doc.instrument.serial = Some(evil.into());
    doc.instrument.model = Some("M&M \"quoted\" 'single'".into());
    doc.instrument.meta.insert(evil.into(), evil.into());
    doc.inputs.push(incal::document::InputFile {
        role: "input".into(),
        path: format!("{evil}.csv"),
        sha256: "ab".repeat(32),
        rows: Some(4),
    });
    doc
}

fn fixed(doc: &ResultDocument, history: &[HistorySeries]) -> String {
    render_html_with(
        doc,
        history,
        &RenderOptions {
            date: Some("2026-01-02 03:04 UTC".into()),
            record: None,
            certificate: None,
        },
    )
    .unwrap()
}

#[test]
fn hostile_text_is_escaped_and_the_file_is_self_contained() {
    let doc = hostile();
    let html = fixed(&doc, &[]);
    assert_self_contained(&html);
    assert!(!html.contains("<script>"), "unescaped markup");
    assert!(html.contains("&lt;script&gt;alert(1)&lt;/script&gt;"));
    let parsed = Html::parse_document(&html);
    // The serial reads as text in the identity table.
    let cells: Vec<String> = parsed
        .select(&sel("header table.identity td"))
        .map(|c| c.text().collect())
        .collect();
    assert!(
        cells.iter().any(|c| c == "<script>alert(1)</script>"),
        "{cells:?}"
    );
    assert!(cells.iter().any(|c| c == "M&M \"quoted\" 'single'"));
    // The full SHA-256 of the input.
    assert!(parsed
        .select(&sel("header table.inputs .hash"))
        .any(|h| h.text().collect::<String>() == "ab".repeat(32)));
    // The legend and the plot (SVG text) of a hostile pass label escape too.
    let legend: Vec<String> = parsed
        .select(&sel("p.legend .key"))
        .map(|k| k.text().collect::<String>().trim().to_string())
        .collect();
    assert!(
        legend.contains(&"<script>alert(1)</script>".to_string()),
        "{legend:?}"
    );
    assert!(html.contains("2026-01-02 03:04 UTC"));
}

#[test]
fn every_section_table_and_plot_is_present() {
    let doc = hostile();
    let html = fixed(&doc, &[]);
    let parsed = Html::parse_document(&html);
    for id in ["header", "coefficients", "fits", "notes", "tables", "plots"] {
        assert_eq!(parsed.select(&sel(&format!("#{id}"))).count(), 1, "#{id}");
    }
    assert_eq!(
        parsed.select(&sel("#history")).count(),
        0,
        "no history given"
    );
    // Every coefficient by its JSON name; shown without a unit suffix that
    // contradicts the unit column (misalignment_rad is shown in arcsec).
    let names: Vec<String> = parsed
        .select(&sel("table.coefficients tbody tr td:first-child span"))
        .map(|c| c.value().attr("data-name").unwrap().to_string())
        .collect();
    assert_eq!(names, doc.coefficients.names());
    let shown: Vec<String> = parsed
        .select(&sel("table.coefficients tbody tr td:first-child"))
        .map(|c| c.text().collect())
        .collect();
    assert_eq!(shown, ["a.K0", "b.K0", "a.misalignment", "b.misalignment"]);
    assert_eq!(
        parsed
            .select(&sel("div.doc-table[data-table=\"positions\"] table"))
            .count(),
        1
    );
    let kinds: Vec<&str> = parsed
        .select(&sel("figure.plot"))
        .map(|f| f.value().attr("data-plot").unwrap())
        .collect();
    assert_eq!(
        kinds,
        ["residual", "fitted", "coefficients", "coefficients"],
        "residual and fitted from the table, one plot per shared coefficient name"
    );
    for f in parsed.select(&sel("figure.plot")) {
        assert_eq!(f.select(&sel("svg")).count(), 1);
        assert!(f.select(&sel("svg circle")).count() >= 2);
        assert!(!f
            .select(&sel("figcaption"))
            .next()
            .unwrap()
            .text()
            .collect::<String>()
            .is_empty());
    }
    // SVG text in the generic family only.
    for t in parsed.select(&sel("svg text")) {
        assert_eq!(t.value().attr("font-family"), Some("sans-serif"));
    }
    // A4 print stylesheet; sections flow on (no page holding only a
    // heading), a plot or a table row never split.
    let css: String = parsed
        .select(&sel("style"))
        .next()
        .unwrap()
        .text()
        .collect();
    assert!(css.contains("@media print"));
    assert!(css.contains("size: A4"));
    assert!(css.contains("section { page-break-before: auto; break-before: auto;"));
    assert!(css.contains("figure.plot"));
    // Same input, same bytes.
    assert_eq!(html, fixed(&doc, &[]));
}

#[test]
fn a_result_without_residuals_or_blocks_still_gets_a_plot() {
    let mut b = DocumentBuilder::new(Procedure::MisalignAccel, "plain");
    for (name, unit) in [("x", Unit::Rad), ("y", Unit::Rad), ("z", Unit::Output)] {
        b.coefficient(
            name,
            Coefficient::new(name, 1e-3, 1e-4, unit, f64::INFINITY).unwrap(),
        )
        .unwrap();
    }
    let html = render_html(&b.finish(), &[]).unwrap();
    assert_self_contained(&html);
    let parsed = Html::parse_document(&html);
    let sources: Vec<&str> = parsed
        .select(&sel("figure.plot[data-plot=\"coefficients\"]"))
        .map(|f| f.value().attr("data-source").unwrap())
        .collect();
    assert_eq!(sources, ["unit rad", "unit output"]);
    // The date defaults to now, in UTC.
    let date: String = parsed
        .select(&sel("header table.identity tr"))
        .map(|r| r.text().collect::<String>())
        .find(|t| t.starts_with("report date"))
        .unwrap();
    assert!(date.ends_with(" UTC"), "{date}");
}

#[test]
fn history_plots_show_every_calibration_and_the_limits() {
    let doc = hostile();
    let series = |name: &str, min, max| HistorySeries {
        coefficient: name.into(),
        unit: Unit::G,
        points: (0..3)
            .map(|i| HistoryPoint {
                id: 10 + i,
                created_utc: format!("2026-01-0{}T00:00:00Z", i + 1),
                value: 8e-3 + 1e-6 * i as f64,
                u95: 5e-7,
            })
            .collect(),
        min,
        max,
        // A drift line on the limited coefficient only.
        drift: min.map(|_: f64| incal_report::DriftLine {
            intercept: 8e-3,
            rate_per_day: 1e-6,
            covariance: [[1e-14, 0.0], [0.0, 1e-15]],
            k95: 2.0,
        }),
    };
    let history = [
        series("K0", Some(7.9e-3), Some(8.1e-3)),
        series("K<2>", None, None),
    ];
    let html = fixed(&doc, &history);
    assert_self_contained(&html);
    let parsed = Html::parse_document(&html);
    let section = parsed
        .select(&sel("section#history"))
        .next()
        .expect("history");
    let figures: Vec<_> = section
        .select(&sel("figure[data-plot=\"history\"]"))
        .collect();
    assert_eq!(figures.len(), 2);
    // Three calibrations: three dots; limits: two red lines on the first.
    assert_eq!(figures[0].select(&sel("svg circle")).count(), 3);
    let red = |f: &scraper::ElementRef| {
        f.select(&sel("svg polyline"))
            .filter(|p| p.value().attr("stroke") == Some("#C80000"))
            .count()
    };
    assert_eq!(red(&figures[0]), 2);
    assert_eq!(red(&figures[1]), 0);
    // Against the date (days since the first), with the drift line and
    // its band where there is a drift; values in µg in the table.
    assert!(figures[0]
        .text()
        .any(|t| t.contains("days since the first calibration (2026-01-01)")));
    let caption = |f: &scraper::ElementRef| {
        f.select(&sel("figcaption"))
            .flat_map(|c| c.text())
            .collect::<String>()
    };
    assert!(
        caption(&figures[0]).contains("the drift, 1 ug/day"),
        "{}",
        caption(&figures[0])
    );
    assert!(!caption(&figures[1]).contains("drift"));
    let rows: Vec<String> = section
        .select(&sel("table.history tbody tr"))
        .map(|r| r.text().collect::<Vec<_>>().join("|"))
        .collect();
    assert_eq!(rows.len(), 6);
    // The value to the second digit of its U95 (GUM 7.2.6).
    assert_eq!(rows[0], "10|2026-01-01T00:00:00Z|8000.00|0.50");
    assert!(html.contains("History of K&lt;2&gt;"));
}

#[test]
fn verdicts_show_in_the_coefficient_table_and_the_header() {
    let mut doc = hostile();
    use incal::document::limits::{CoefficientVerdict, DecisionRule, Verdict};
    let judged = |verdict| CoefficientVerdict {
        min: Some(-1e-3),
        max: Some(1e-3),
        verdict,
    };
    doc.verdicts = Some(
        [
            ("a.K0".to_string(), judged(Verdict::Pass)),
            ("b.K0".to_string(), judged(Verdict::Fail)),
        ]
        .into_iter()
        .collect(),
    );
    doc.verdict = Some(Verdict::Fail);
    doc.decision_rule = Some(DecisionRule::GuardBand);
    let html = fixed(&doc, &[]);
    let parsed = Html::parse_document(&html);
    let header: Vec<String> = parsed
        .select(&sel("table.coefficients thead th"))
        .map(|c| c.text().collect())
        .collect();
    assert_eq!(header.last().unwrap(), "verdict");
    assert!(header.contains(&"limits".to_string()));
    let verdicts: Vec<String> = parsed
        .select(&sel("table.coefficients tbody tr td:last-child"))
        .map(|c| c.text().collect())
        .collect();
    assert_eq!(verdicts, ["pass", "fail", "–", "–"]);
    assert_eq!(
        parsed
            .select(&sel("table.coefficients .verdict-fail"))
            .count(),
        1
    );
    assert_eq!(parsed.select(&sel("header .verdict-fail")).count(), 1);
    // The K0 plot draws the common limits.
    let k0 = parsed
        .select(&sel("figure[data-source=\"*.K0\"]"))
        .next()
        .unwrap();
    assert_eq!(
        k0.select(&sel("svg polyline"))
            .filter(|p| p.value().attr("stroke") == Some("#C80000"))
            .count(),
        2
    );
}

mod digits {
    //! GUM 7.2.6 on every display: each value shown in the text and HTML
    //! coefficient tables differs from the JSON value (in the unit shown)
    //! by less than a tenth of the U95 shown beside it.
    use super::*;
    use proptest::prelude::*;

    /// `(name, value, U95)` parsed from the coefficient table of the text
    /// report.
    fn text_rows(text: &str) -> Vec<(String, f64, f64)> {
        text.lines()
            .skip_while(|l| !l.starts_with("name "))
            .skip(2)
            .take_while(|l| !l.starts_with("u: "))
            .map(|l| {
                let c: Vec<&str> = l.split_whitespace().collect();
                (
                    c[0].to_string(),
                    c[1].parse().unwrap(),
                    c[3].parse().unwrap(),
                )
            })
            .collect()
    }

    fn html_rows(html: &str) -> Vec<(String, f64, f64)> {
        let d = Html::parse_document(html);
        d.select(&sel("table.coefficients tbody tr"))
            .map(|tr| {
                let c: Vec<String> = tr.select(&sel("td")).map(|t| t.text().collect()).collect();
                (c[0].clone(), c[1].parse().unwrap(), c[3].parse().unwrap())
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        #[test]
        fn every_value_shown_is_within_a_tenth_of_its_u95(
            mant in -9.99f64..9.99, exp in -12i32..7, rel_u in -9.0f64..1.0,
            dof in 2.0f64..500.0, unit in 0usize..4,
        ) {
            let value = mant * 10f64.powi(exp);
            let u = (value.abs().max(1e-300) * 10f64.powf(rel_u)).max(1e-300);
            let unit = [Unit::G, Unit::Rad, Unit::M, Unit::Output][unit].clone();
            let mut b = DocumentBuilder::new(Procedure::Tumble, "digits".to_string());
            let c = Coefficient::new("X_rad", value, u, unit.clone(), dof).unwrap();
            let (scale, _) = unit.engineering_for(value);
            let (v, u95) = (c.value * scale, c.u95 * scale);
            b.coefficient("X_rad", c).unwrap();
            let doc = b.finish();
            let text = incal_report::text::render(&doc);
            let html = fixed(&doc, &[]);
            for (what, rows) in [("text", text_rows(&text)), ("html", html_rows(&html))] {
                prop_assert_eq!(rows.len(), 1, "{}: {}", what, text);
                let (_, shown, shown_u95) = &rows[0];
                prop_assert!(
                    (shown - v).abs() < 0.1 * shown_u95,
                    "{}: shown {} for {} with U95 {} (shown {})", what, shown, v, u95, shown_u95
                );
            }
        }
    }
}
