//! The `monte_carlo` section of a result (JCGM 101:2008) for people: one
//! table in engineering units, as the coefficients are shown, and what the
//! trials drew; the text report and the HTML report or certificate share
//! it.

use incal::document::ResultDocument;
use incal::montecarlo::{MonteCarlo, TrialsText};

use crate::format::{esc, measured, shown_name, sig};

/// Header of the table.
const HEADER: [&str; 7] = [
    "name",
    "MC mean",
    "MC u",
    "symmetric 95 %",
    "shortest 95 %",
    "GUM y ± U95",
    "decision",
];

/// The rows of the table: per coefficient (in the document's order) the
/// name, the Monte Carlo mean and u, both intervals and the GUM interval
/// (each at the place of the Monte Carlo u's second digit, in the
/// coefficient's engineering unit) and the decision.
fn rows(doc: &ResultDocument, mc: &MonteCarlo) -> Vec<Vec<String>> {
    doc.coefficients
        .iter()
        .filter_map(|(name, c)| {
            let m = mc.coefficients.get(name)?;
            let (scale, label) = c.unit.engineering_for(c.value);
            let at = |x: f64| measured(x * scale, m.std * scale, m.std * scale).0;
            let (mean, u, _) = measured(m.mean * scale, m.std * scale, m.std * scale);
            let pair = |p: [f64; 2]| format!("[{}, {}]", at(p[0]), at(p[1]));
            Some(vec![
                format!("{} ({label})", shown_name(name, label)),
                mean,
                u,
                pair(m.symmetric),
                pair(m.shortest),
                pair(m.gum),
                m.decision.clone(),
            ])
        })
        .collect()
}

/// The run in one line: trials, seed, failures, tolerance.
fn summary(mc: &MonteCarlo) -> String {
    let asked = match &mc.requested {
        TrialsText::Count(m) if *m == mc.trials => String::new(),
        TrialsText::Count(m) => format!(" of {m} asked"),
        TrialsText::Word(w) => format!(" ({w}: batches until stable"),
    };
    let stable = match (mc.stabilised, mc.tolerance_ratio) {
        (Some(true), Some(r)) => format!(", stable to δ, ratio {})", sig(r, 2)),
        (Some(false), Some(r)) => format!(", NOT stable to δ at the cap, ratio {})", sig(r, 2)),
        _ => String::new(),
    };
    format!(
        "{} trials{asked}{stable}, seed {}, {} failed; validation (JCGM 101 §8) at δ from u to {} significant digit{}",
        mc.trials,
        mc.seed,
        mc.failed.count,
        mc.digits,
        if mc.digits == 1 { "" } else { "s" }
    )
}

/// What the trials drew, one line each.
fn drawn(mc: &MonteCarlo) -> Vec<String> {
    mc.drawn
        .iter()
        .map(|d| {
            format!(
                "{}: {}, {} (from {})",
                d.input, d.distribution, d.parameters, d.source
            )
        })
        .collect()
}

/// The section in the text report (empty without a Monte Carlo).
pub fn text(doc: &ResultDocument) -> String {
    let Some(mc) = &doc.monte_carlo else {
        return String::new();
    };
    let mut s = String::from("\nMonte Carlo (JCGM 101, GUM Supplement 1)\n");
    s.push_str(&format!("{}\n", summary(mc)));
    s.push_str(&crate::text::table(&HEADER, &rows(doc, mc)));
    for d in drawn(mc) {
        s.push_str(&format!("drawn: {d}\n"));
    }
    s
}

/// The section in the HTML report and certificate (empty without a Monte
/// Carlo); every text escaped.
pub fn html(doc: &ResultDocument) -> String {
    let Some(mc) = &doc.monte_carlo else {
        return String::new();
    };
    let header: Vec<String> = HEADER.iter().map(|h| esc(h)).collect();
    let rows: Vec<Vec<(bool, String)>> = rows(doc, mc)
        .into_iter()
        .map(|r| {
            r.into_iter()
                .enumerate()
                .map(|(k, c)| (k > 0 && k < 6, esc(&c)))
                .collect()
        })
        .collect();
    let mut s =
        String::from("<section id=\"monte-carlo\">\n<h2>Monte Carlo propagation (JCGM 101)</h2>\n");
    s.push_str(&format!("<p class=\"note\">{}</p>\n", esc(&summary(mc))));
    s.push_str(&crate::html_table("monte-carlo", &header, &rows));
    s.push_str("<ul class=\"note\">\n");
    for d in drawn(mc) {
        s.push_str(&format!("<li>{}</li>\n", esc(&d)));
    }
    s.push_str("</ul>\n</section>\n");
    s
}
