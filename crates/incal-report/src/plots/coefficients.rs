//! Coefficient plots (module docs of `plots`): the value ±U95 of the
//! coefficients that share a name across groups, or the elements of a
//! matrix or vector, on one axis per unit and magnitude; every
//! coefficient per unit when nothing else gives a plot.

use incal::document::ResultDocument;
use incal::units::Unit;

use super::{display_unit, with_unit, HLine, Plot, Pt, Series, Style, XAxis};

/// Limits `(min, max)` of a coefficient, when a verdict gives them.
pub type Limits = (Option<f64>, Option<f64>);

/// Value ±U95 of `names` (all in one unit) as categories.
fn coefficient_plot(
    doc: &ResultDocument,
    names: &[&str],
    labels: Vec<String>,
    limits: Option<Limits>,
    source: String,
    title: String,
    caption: String,
) -> Option<Plot> {
    let coefs: Vec<_> = names
        .iter()
        .filter_map(|n| doc.coefficients.get(n))
        .collect();
    let first = coefs.first()?;
    let mag = coefs.iter().fold(0.0, |m, c| f64::max(m, c.value.abs()));
    let (s, l) = display_unit(Some(&first.unit), mag);
    let points = coefs
        .iter()
        .enumerate()
        .map(|(i, c)| Pt {
            x: i as f64,
            y: c.value * s,
            bar: Some(c.u95 * s),
        })
        .collect();
    let mut hlines = Vec::new();
    if let Some((lo, hi)) = limits {
        hlines.extend(lo.into_iter().chain(hi).map(|y| HLine {
            y: y * s,
            limit: true,
        }));
    }
    Some(Plot {
        kind: "coefficients",
        source,
        title: title.clone(),
        x_desc: String::new(),
        y_desc: with_unit(&title, &l),
        x_axis: XAxis::Categories(labels),
        dodge: false,
        series: vec![Series {
            key: 0,
            style: Style::Dots,
            points,
        }],
        legend: Vec::new(),
        hlines,
        caption,
        log_log: false,
        heat: None,
    })
}

/// Coefficient plots (module docs): one per `NAME` of `GROUP.NAME`
/// coefficients shared by two or more groups in one unit; when `fallback`,
/// and there are none, one per unit over every coefficient. `limits` gives
/// a coefficient's limits, if any.
pub fn coefficient_plots(
    doc: &ResultDocument,
    fallback: bool,
    limits: &dyn Fn(&str) -> Option<Limits>,
) -> Vec<Plot> {
    let out: Vec<Plot> = split_by_decades(doc, groups(doc))
        .iter()
        .filter(|g| g.names.len() >= 2)
        .filter_map(|g| group_plot(doc, g, limits))
        .collect();
    if out.is_empty() && fallback {
        return unit_plots(doc, limits);
    }
    out
}

/// Coefficients plotted together, all in one unit.
struct Group<'a> {
    /// What tells groups apart (`R_a.` plus the part, `*.NAME`).
    key: String,
    /// Title of the plot.
    title: String,
    /// The elements of one matrix or vector (labelled by their suffix),
    /// rather than one `NAME` across groups (labelled by their prefix).
    by_prefix: bool,
    /// Their unit.
    unit: Unit,
    /// Their names, in the document's order.
    names: Vec<&'a str>,
}

/// True for the suffix of a matrix or vector element: one or two of
/// `x`, `y`, `z` (`R_a.xy`, `b_a.x`).
fn is_axis(s: &str) -> bool {
    (1..=2).contains(&s.len()) && s.chars().all(|c| matches!(c, 'x' | 'y' | 'z'))
}

/// The `GROUP.NAME` coefficients in groups, in the order of first
/// appearance: a matrix or vector (`R_a.xy`, `b_a.x`: axis components) is
/// one group per name, its diagonal apart from its off-diagonal elements;
/// any other `GROUP.NAME` (`gx.ARW`, `a.K0`) is one group per NAME across
/// groups. Each in one unit.
fn groups(doc: &ResultDocument) -> Vec<Group<'_>> {
    let mut groups: Vec<Group> = Vec::new();
    for (name, c) in doc.coefficients.iter() {
        let Some((prefix, suffix)) = name.rsplit_once('.') else {
            continue;
        };
        let (key, title, by_prefix) = if is_axis(suffix) {
            let part = match suffix.len() {
                1 => "",
                _ if suffix[..1] == suffix[1..] => " (diagonal)",
                _ => " (off-diagonal)",
            };
            (format!("{prefix}.{part}"), format!("{prefix}{part}"), true)
        } else {
            (format!("*.{suffix}"), suffix.to_string(), false)
        };
        match groups.iter_mut().find(|g| g.key == key && g.unit == c.unit) {
            Some(g) => g.names.push(name),
            None => groups.push(Group {
                key,
                title,
                by_prefix,
                unit: c.unit.clone(),
                names: vec![name],
            }),
        }
    }
    groups
}

/// Groups whose values are decades apart (a sensing axis near 1 beside
/// cross-axis terms near 1e-3) split where the sorted magnitudes jump by
/// more than 1.5 decades: values so far apart are not read on one axis.
fn split_by_decades<'a>(doc: &ResultDocument, groups: Vec<Group<'a>>) -> Vec<Group<'a>> {
    let mut split: Vec<Group> = Vec::new();
    for g in groups {
        let mut order: Vec<(f64, &str)> = g
            .names
            .iter()
            .filter_map(|n| {
                doc.coefficients
                    .get(n)
                    .map(|c| (c.value.abs().max(1e-300).log10(), *n))
            })
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut cuts = vec![0];
        for i in 1..order.len() {
            if order[i].0 - order[i - 1].0 > 1.5 {
                cuts.push(i);
            }
        }
        if cuts.len() == 1 {
            split.push(g);
            continue;
        }
        cuts.push(order.len());
        for w in cuts.windows(2) {
            let members: Vec<&str> = order[w[0]..w[1]].iter().map(|(_, n)| *n).collect();
            // Keep the document's order within each part.
            let names: Vec<&str> = g
                .names
                .iter()
                .copied()
                .filter(|n| members.contains(n))
                .collect();
            let top = order[w[1] - 1].0.round() as i64;
            split.push(Group {
                key: format!("{} ~1e{top}", g.key),
                title: format!("{} (about 1e{top})", g.title),
                by_prefix: g.by_prefix,
                unit: g.unit.clone(),
                names,
            });
        }
    }
    split
}

/// The limits of `names` when every one has the same.
fn common_limits(limits: &dyn Fn(&str) -> Option<Limits>, names: &[&str]) -> Option<Limits> {
    let first = limits(names.first()?)?;
    names
        .iter()
        .all(|n| limits(n) == Some(first))
        .then_some(first)
}

/// The plot of one group: its coefficients labelled by what tells them
/// apart (the element of a matrix, the group of a shared name).
fn group_plot(
    doc: &ResultDocument,
    g: &Group,
    limits: &dyn Fn(&str) -> Option<Limits>,
) -> Option<Plot> {
    let names = &g.names;
    let part = |n: &&str| -> String {
        match n.rsplit_once('.') {
            Some((p, s)) => if g.by_prefix { s } else { p }.to_string(),
            None => n.to_string(),
        }
    };
    let labels: Vec<String> = names.iter().map(part).collect();
    coefficient_plot(
        doc,
        names,
        labels.clone(),
        common_limits(limits, names),
        g.key.clone(),
        g.title.clone(),
        format!(
            "{} {} with their ±U95 (k95·u of each coefficient){}.",
            if g.by_prefix { "The elements" } else { "Every" },
            if g.by_prefix {
                format!("{} of {}", labels.join(", "), g.title)
            } else {
                format!("{} of {}", g.title, labels.join(", "))
            },
            if common_limits(limits, names).is_some() {
                "; red lines: its limits"
            } else {
                ""
            }
        ),
    )
}

/// The fallback: every coefficient's value ±U95, one plot per unit.
fn unit_plots(doc: &ResultDocument, limits: &dyn Fn(&str) -> Option<Limits>) -> Vec<Plot> {
    let mut units: Vec<(Unit, Vec<&str>)> = Vec::new();
    for (name, c) in doc.coefficients.iter() {
        match units.iter_mut().find(|(u, _)| *u == c.unit) {
            Some(g) => g.1.push(name),
            None => units.push((c.unit.clone(), vec![name])),
        }
    }
    units
        .iter()
        .filter_map(|(unit, names)| {
            coefficient_plot(
                doc,
                names,
                names.iter().map(|n| n.to_string()).collect(),
                common_limits(limits, names),
                format!("unit {unit}"),
                "value".into(),
                format!(
                    "Every coefficient in {unit} with its ±U95 (k95·u); no table of this result has residuals to plot."
                ),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A matrix is plotted per matrix, its diagonal apart from its
    /// off-diagonal elements; a term shared by units is split where its
    /// values are decades apart (a sensing axis beside cross-axis terms).
    #[test]
    fn coefficients_decades_apart_or_of_a_matrix_get_their_own_axis() {
        use incal::document::{Coefficient, DocumentBuilder, Procedure};
        let mut b = DocumentBuilder::new(Procedure::ImuFerraris, "t");
        for (n, v) in [
            ("R.xx", 1.0),
            ("R.yy", 0.999),
            ("R.xy", 1e-3),
            ("R.yx", -2e-3),
            ("a.Ks_x", 1.0),
            ("b.Ks_x", 1e-3),
            ("c.Ks_x", -2e-3),
        ] {
            b.coefficient(n, Coefficient::new(n, v, 1e-5, Unit::One, 10.0).unwrap())
                .unwrap();
        }
        let doc = b.finish();
        let titles: Vec<String> = coefficient_plots(&doc, false, &|_| None)
            .into_iter()
            .map(|p| p.title)
            .collect();
        assert_eq!(
            titles,
            ["R (diagonal)", "R (off-diagonal)", "Ks_x (about 1e-3)"],
            "{titles:?}"
        );
    }
}
