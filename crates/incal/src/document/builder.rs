//! The builder every procedure's document goes through: coefficients from
//! estimates with their u, dof and U95, fits, tables, warnings and
//! decisions, in one shape.

use super::*;

/// Builds a [`ResultDocument`]: the procedure adds its coefficients
/// (block by block), fits, tables, warnings and decisions; the caller (the
/// command-line tool) adds instrument, inputs and options.
#[derive(Debug, Clone)]
pub struct DocumentBuilder {
    doc: ResultDocument,
    blocks: Vec<DMatrix<f64>>,
}

impl DocumentBuilder {
    /// A document of `procedure` with a title.
    pub fn new(procedure: Procedure, title: impl Into<String>) -> Self {
        Self {
            doc: ResultDocument {
                schema: SCHEMA.to_string(),
                procedure,
                title: title.into(),
                incal_version: env!("CARGO_PKG_VERSION").to_string(),
                instrument: Instrument::default(),
                inputs: Vec::new(),
                options: BTreeMap::new(),
                coefficients: Coefficients::default(),
                correlation: Correlation::default(),
                fits: Vec::new(),
                tables: Vec::new(),
                warnings: Vec::new(),
                decisions: Vec::new(),
                verdicts: None,
                verdict: None,
                decision_rule: None,
                monte_carlo: None,
                extra: BTreeMap::new(),
            },
            blocks: Vec::new(),
        }
    }

    /// Add every estimate of `e` as a coefficient named `prefix + name`,
    /// with the unit `unit_of(name)` and the block's degrees of freedom.
    /// `e` is one correlation block: it is taken as independent of every
    /// other block (module docs).
    pub fn estimates(
        &mut self,
        e: &Estimates,
        prefix: &str,
        unit_of: impl Fn(&str) -> Result<Unit>,
    ) -> Result<&mut Self> {
        self.estimates_dof(e, prefix, unit_of, |_| e.dof())
    }

    /// As [`DocumentBuilder::estimates`], with each coefficient's own
    /// effective degrees of freedom `dof_of(name)` (e.g. Welch–Satterthwaite
    /// from its budget, JCGM 100 eq. G.2b) instead of the block's.
    pub fn estimates_dof(
        &mut self,
        e: &Estimates,
        prefix: &str,
        unit_of: impl Fn(&str) -> Result<Unit>,
        dof_of: impl Fn(&str) -> f64,
    ) -> Result<&mut Self> {
        for (k, name) in e.names().iter().enumerate() {
            let full = format!("{prefix}{name}");
            let c = Coefficient::new(
                &full,
                e.values()[k],
                e.u_at(k),
                unit_of(name)?,
                dof_of(name),
            )?;
            self.doc.coefficients.push(full, c)?;
        }
        self.blocks.push(e.correlation());
        Ok(self)
    }

    /// Add one coefficient with no correlation to any other.
    pub fn coefficient(&mut self, name: &str, c: Coefficient) -> Result<&mut Self> {
        self.doc.coefficients.push(name.to_string(), c)?;
        self.blocks.push(DMatrix::identity(1, 1));
        Ok(self)
    }

    /// Add a fit summary.
    pub fn fit(&mut self, f: FitSummary) -> &mut Self {
        self.doc.fits.push(f);
        self
    }

    /// Add a table.
    pub fn table(&mut self, t: Table) -> &mut Self {
        self.doc.tables.push(t);
        self
    }

    /// Add warnings.
    pub fn warnings(&mut self, w: impl IntoIterator<Item = Warning>) -> &mut Self {
        self.doc.warnings.extend(w);
        self
    }

    /// Add a decision.
    pub fn decision(&mut self, code: DecisionCode, message: impl Into<String>) -> &mut Self {
        self.doc.decisions.push(Decision {
            code,
            message: message.into(),
        });
        self
    }

    /// Set a procedure-specific top-level object (fails on a reserved key).
    pub fn extra(&mut self, key: &str, value: Value) -> Result<&mut Self> {
        const RESERVED: [&str; 16] = [
            "schema",
            "procedure",
            "title",
            "incal_version",
            "instrument",
            "inputs",
            "options",
            "coefficients",
            "correlation",
            "fits",
            "tables",
            "warnings",
            "decisions",
            "verdicts",
            "verdict",
            "decision_rule",
        ];
        if RESERVED.contains(&key) {
            return Err(Error::Unsupported(format!(
                "result document: '{key}' is a reserved key"
            )));
        }
        self.doc.extra.insert(key.to_string(), value);
        Ok(self)
    }

    /// Set an option that shaped the result.
    pub fn option(&mut self, key: &str, value: Value) -> &mut Self {
        self.doc.options.insert(key.to_string(), value);
        self
    }

    /// The document, with the block-diagonal correlation matrix.
    pub fn finish(self) -> ResultDocument {
        let mut doc = self.doc;
        let n: usize = self.blocks.iter().map(|b| b.nrows()).sum();
        let mut m = vec![vec![0.0; n]; n];
        let mut at = 0;
        for b in &self.blocks {
            for j in 0..b.nrows() {
                for k in 0..b.ncols() {
                    let r = b[(j, k)];
                    // Round-off can leave |ρ| a hair off 1.
                    m[at + j][at + k] = if j == k {
                        1.0
                    } else if r.is_finite() {
                        r.clamp(-1.0, 1.0)
                    } else {
                        0.0
                    };
                }
            }
            at += b.nrows();
        }
        doc.correlation = Correlation {
            names: doc.coefficients.names(),
            matrix: m,
        };
        doc
    }
}

/// A coefficient's unit when every name is an accelerometer term
/// ([`crate::models::Term`]); fails on any other name.
pub fn term_unit(name: &str) -> Result<Unit> {
    crate::models::Term::parse(name).map(|t| t.unit())
}
