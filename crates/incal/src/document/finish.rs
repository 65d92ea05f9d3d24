//! What every front end adds to a reduced document before it is written:
//! the instrument's identity, the output unit and the verdict against a
//! limits file. One place for the CLI's `--serial`, `--model`, `--meta`,
//! `--output-unit` and `--limits` and the Python keywords of the same
//! names.

use super::limits::{self, Limits};
use super::{InputFile, ResultDocument};
use crate::{Error, Result};

/// A limits file as read by a front end: its name (as given) and text.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LimitsText {
    /// The file as the user named it (`-` or `<stdin>`: standard input).
    pub name: String,
    /// Its TOML text.
    pub text: String,
}

/// Identity, unit and limits to put into a result document.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Finish {
    /// Serial number of the instrument.
    pub serial: Option<String>,
    /// Model or part number.
    pub model: Option<String>,
    /// Further identity or conditions, each `KEY=VALUE`.
    pub meta: Vec<String>,
    /// The instrument's output unit (`V`, `mA`, `LSB`): every unit that
    /// says "output" is written with it; values are unchanged.
    pub output_unit: Option<String>,
    /// Limits to judge every limited coefficient against.
    pub limits: Option<LimitsText>,
    /// With `limits`: which overall verdicts stop a script ([`Finish::stop`]).
    pub fail_on: Option<FailOn>,
}

/// Which overall verdicts stop a script (the CLI's `--fail-on`, exit 3
/// after the result is written; Python's `fail_on`, an error carrying the
/// result).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FailOn {
    /// Stop on fail, conditional-fail and not-determined (no conformity
    /// can be stated).
    Fail,
    /// Also stop on conditional-pass.
    Conditional,
}

impl FailOn {
    /// Its name (`fail`, `conditional`).
    pub fn as_str(self) -> &'static str {
        match self {
            FailOn::Fail => "fail",
            FailOn::Conditional => "conditional",
        }
    }

    /// `verdict V (NAME V, …)` when `doc`'s overall verdict is one this
    /// stops on, naming (up to six of) the coefficients behind it.
    pub fn stop(self, doc: &ResultDocument) -> Option<String> {
        use limits::Verdict;
        let v = doc.verdict?;
        let from = match self {
            FailOn::Fail => Verdict::NotDetermined,
            FailOn::Conditional => Verdict::ConditionalPass,
        };
        if v < from {
            return None;
        }
        let names: Vec<String> = doc
            .verdicts
            .iter()
            .flatten()
            .filter(|(_, c)| c.verdict >= from)
            .map(|(n, c)| format!("{n} {}", c.verdict))
            .collect();
        let shown = names.iter().take(6).cloned().collect::<Vec<_>>().join(", ");
        let more = if names.len() > 6 {
            format!(" and {} more", names.len() - 6)
        } else {
            String::new()
        };
        Some(format!("verdict {v} ({shown}{more})"))
    }
}

fn option(key: &str, message: String) -> Error {
    Error::InvalidOption {
        key: key.into(),
        message,
    }
}

impl Finish {
    /// [`FailOn::stop`] of `fail_on`, if given.
    pub fn stop(&self, doc: &ResultDocument) -> Option<String> {
        self.fail_on.and_then(|f| f.stop(doc))
    }

    /// Put the identity and unit into `doc` and judge it against the
    /// limits (the limits file's SHA-256 joins the inputs). A chained
    /// result (centrifuge `from`) already names its instrument: `serial`
    /// may repeat it, never contradict it. Errors name the option
    /// (`serial`, `meta`, `output_unit`) or the limits file.
    pub fn apply(&self, doc: &mut ResultDocument) -> Result<()> {
        match (&doc.instrument.serial, &self.serial) {
            (Some(had), Some(given)) if had != given => {
                return Err(option(
                    "serial",
                    format!(
                        "{} is not the chained result's serial {} (a result of another instrument cannot be chained)",
                        incal_io::clip(given),
                        incal_io::clip(had)
                    ),
                ))
            }
            (_, Some(given)) => doc.instrument.serial = Some(given.clone()),
            _ => {}
        }
        if self.model.is_some() {
            doc.instrument.model = self.model.clone();
        }
        for kv in &self.meta {
            let (k, v) = kv.split_once('=').ok_or_else(|| {
                option("meta", format!("'{}' is not KEY=VALUE", incal_io::clip(kv)))
            })?;
            let k = k.trim();
            if k.is_empty() || k == "serial" || k == "model" {
                return Err(option(
                    "meta",
                    format!(
                        "'{}' needs a key other than serial and model (those are options of their own)",
                        incal_io::clip(kv)
                    ),
                ));
            }
            doc.instrument
                .meta
                .insert(k.to_string(), v.trim().to_string());
        }
        if let Some(u) = &self.output_unit {
            doc.declare_output_unit(u)
                .map_err(|m| option("output_unit", m))?;
        }
        if let Some(l) = &self.limits {
            let in_file = |m: String| Error::Input(incal_io::InputError::file(&l.name, m));
            let parsed = Limits::parse(&l.text).map_err(in_file)?;
            limits::apply(doc, &parsed).map_err(in_file)?;
            let shown = if l.name == incal_io::source::STDIN_NAME {
                "-"
            } else {
                l.name.as_str()
            };
            doc.inputs.push(InputFile {
                role: "limits".into(),
                path: shown.into(),
                sha256: incal_io::sha256_hex(l.text.as_bytes()),
                rows: None,
            });
        }
        Ok(())
    }
}
