//! `incal demo`: virtual instruments through every rig, calibrated, with
//! estimate, observable truth, U95 and degrees of freedom side by side.
//! The scenarios are data of the core ([`incal::sim::demo`]); this file
//! only renders them. Needs no input and no network; the same seed prints
//! the same numbers.

use std::path::PathBuf;

use incal::sim::demo::{sections, DemoCase};

use crate::error::{core, CliResult};
use crate::output::{dof_text, measured, render_table, shown_name, sig, table, write_text};

/// Options of `incal demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Random seed of every simulation.
    #[arg(long, default_value_t = 2015)]
    pub seed: u64,
    /// Write the demo to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// The estimate-versus-truth table of one case, in engineering units:
/// `(est − truth)/U95` lies within ±1 for 95 % of honest estimates.
fn truth_table(c: &DemoCase) -> String {
    let shown: Vec<(&str, &incal::document::Coefficient)> = c
        .document
        .coefficients
        .iter()
        .filter(|(name, _)| c.truth.contains_key(*name))
        .collect();
    let rows: Vec<Vec<String>> = shown
        .iter()
        .map(|&(name, k)| {
            let (scale, label) = k.unit.engineering_for(k.value);
            let truth = c.truth.get(name).copied();
            let (value, _, u95) = measured(k.value * scale, k.u * scale, k.u95 * scale);
            vec![
                shown_name(name, label),
                value,
                // The truth to the estimate's decimal place.
                truth.map_or("-".into(), |t| measured(t * scale, k.u * scale, 0.0).0),
                u95,
                dof_text(k.dof),
                truth.map_or("-".into(), |t| {
                    if k.u95 > 0.0 {
                        sig((k.value - t) / k.u95, 2)
                    } else {
                        "-".into()
                    }
                }),
                label.to_string(),
            ]
        })
        .collect();
    let mut s = table(
        &[
            "name",
            "estimate",
            "truth",
            "U95",
            "dof",
            "(est-truth)/U95",
            "unit",
        ],
        &rows,
    );
    let more = c.document.coefficients.len() - shown.len();
    if more > 0 {
        let (noun, verb) = if more == 1 {
            ("coefficient", "is")
        } else {
            ("coefficients", "are")
        };
        s.push_str(&format!(
            "({more} further {noun} without a simple truth {verb} in the result document)\n"
        ));
    }
    s
}

/// `incal demo`.
pub fn run(a: &Args) -> CliResult<()> {
    let mut s = format!(
        "incal demo (seed {}): simulate, calibrate, compare with the truth\n\
         U95 = k95 u with k95 from the degrees of freedom: |(est-truth)/U95| <= 1 for 95 % of estimates.\n\n",
        a.seed
    );
    for sec in sections(a.seed).map_err(core)? {
        s.push_str(&format!("== {} ==\n{}\n\n", sec.title, sec.description));
        for c in &sec.cases {
            s.push_str(&format!("-- {}\n", c.heading));
            s.push_str(&truth_table(c));
            for d in &c.document.decisions {
                if d.code == incal::document::DecisionCode::Absorbed {
                    s.push_str(&format!("note: {}\n", d.message));
                }
            }
            for w in &c.document.warnings {
                s.push_str(&format!("warning [{}]: {}\n", w.code, w.message));
            }
            for t in c
                .document
                .tables
                .iter()
                .filter(|t| t.id == "budget.K_ip")
                .chain(&c.tables)
            {
                s.push('\n');
                s.push_str(&render_table(t));
            }
            for n in &c.notes {
                s.push_str(&format!("{n}\n"));
            }
            s.push('\n');
        }
    }
    write_text(a.output.as_deref(), &s)
}
