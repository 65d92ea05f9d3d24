//! The result document of a centrifuge calibration (He & Yin 2017).

use serde_json::{json, Map, Value};

use crate::document::{
    term_unit, Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
    Warning, WarningCode,
};
use crate::error::Result;
use crate::procedures::centrifuge::radius::ValueU;
use crate::procedures::centrifuge::{CentrifugeOptions, CentrifugeResult};
use crate::units::Unit;

/// Unit of a centrifuge coefficient: accelerometer terms, radii in m,
/// the tilt in rad.
fn unit_of(name: &str) -> Result<Unit> {
    if name.ends_with("_m") {
        Ok(Unit::M)
    } else if name.ends_with("_rad") {
        Ok(Unit::Rad)
    } else {
        term_unit(name)
    }
}

fn vu(v: Option<ValueU>) -> Value {
    match v.filter(|x| x.value.is_finite() && x.u.is_finite()) {
        Some(x) => json!({"value": x.value, "u": x.u}),
        None => Value::Null,
    }
}

impl CentrifugeResult {
    /// The result document: `K2, K3, K_oq, K_pp, K_oo, K_ip, K_io, K_po`
    /// (those the data supports, g units) and the radii `R_plus_m`,
    /// `R_minus_m` (regression), `R_plus_static_m`, `R_minus_static_m`,
    /// `R_centre_m`, `ecm_offset_m` and the static tilt `tilt_rad`, all with the
    /// joint covariance of [`CentrifugeResult::joint`]; the He & Yin 2017
    /// contract objects `radius` and `alignment`; radius-by-range, stations,
    /// the station points (input, mean E/K1, residual) and budgets as tables.
    pub fn document(&self, opts: &CentrifugeOptions) -> Result<ResultDocument> {
        let mut b = DocumentBuilder::new(
            Procedure::Centrifuge,
            format!(
                "Centrifuge calibration ({} stations, model order {})",
                self.stations.len(),
                opts.order
            ),
        );
        self.estimates_and_fits(&mut b)?;
        options(&mut b, opts);
        self.contract_objects(&mut b)?;
        b.table(self.radius_by_range_table()?);
        b.table(self.alignment_table()?);
        b.table(self.stations_table()?);
        b.table(self.points_table()?);
        self.budget_tables(&mut b)?;
        self.decisions_and_warnings(&mut b);
        Ok(b.finish())
    }

    /// The joint estimates (coefficients and radii) and the summary of
    /// every station and radius-regression fit.
    fn estimates_and_fits(&self, b: &mut DocumentBuilder) -> Result<()> {
        // One joint block: coefficients and radii share K1 (and K0, E0).
        // Each coefficient's dof is the Welch–Satterthwaite dof of its
        // budget; the radii take the joint's (the smallest of their inputs).
        b.estimates_dof(&self.joint, "", unit_of, |name| {
            self.budgets
                .iter()
                .find(|bu| bu.coefficient == name)
                .map_or(self.joint.dof(), |bu| bu.effective_dof)
        })?;
        for s in &self.stations {
            b.fit(FitSummary::of(
                &format!("station {}", s.label()),
                &s.fit,
                Unit::G,
            ));
        }
        for (k, f) in self.regression.iter().enumerate() {
            if let Some(f) = f {
                let pol = if k == 0 { "+" } else { "-" };
                b.fit(FitSummary::of(
                    &format!("radius regression, polarity {pol}"),
                    &f.fit,
                    Unit::G,
                ));
            }
        }
        Ok(())
    }

    /// The He & Yin 2017 contract objects `radius` (static and regression
    /// radii per polarity) and `alignment` (|ECM offset|), and the static
    /// radii exactly as eq. 5–6 give them.
    fn contract_objects(&self, b: &mut DocumentBuilder) -> Result<()> {
        let reg = |k: usize| self.regression[k].as_ref().map(|f| f.radius_m);
        b.extra(
            "radius",
            json!({
                "static": {"R_plus_m": vu(self.static_radius[0]), "R_minus_m": vu(self.static_radius[1])},
                "regression": {"R_plus_m": vu(reg(0)), "R_minus_m": vu(reg(1))},
            }),
        )?;
        b.extra(
            "radius_static_eq6_uncorrected",
            json!({"R_plus_m": vu(self.static_radius_uncorrected[0]), "R_minus_m": vu(self.static_radius_uncorrected[1])}),
        )?;
        b.extra(
            "alignment",
            json!({"ecm_offset_m": vu(Some(ValueU { value: self.ecm_offset_m.value.abs(), u: self.ecm_offset_m.u }))}),
        )?;
        Ok(())
    }

    /// Table `radius-by-range`: the regression radius by range and model
    /// order (He & Yin 2017 Table 2).
    fn radius_by_range_table(&self) -> Result<Table> {
        let mut t = Table::new(
            "radius-by-range",
            "Regression radius by range and model order (He & Yin 2017, Table 2)",
            &[
                ("order", None),
                ("polarity", None),
                ("max_input_g", None),
                ("radius", Some(Unit::M)),
                ("u_radius", Some(Unit::M)),
                ("lack_of_fit_p", Some(Unit::One)),
                ("error", None),
            ],
        );
        for row in &self.radius_table {
            let (r, u, e) = match &row.radius {
                Ok(v) => (Cell::num(v.value), Cell::num(v.u), Cell::Null),
                Err(e) => (Cell::Null, Cell::Null, Cell::text(e.clone())),
            };
            t.push(vec![
                Cell::num(row.order as f64),
                Cell::num(f64::from(row.polarity)),
                Cell::num(row.max_input_g),
                r,
                u,
                Cell::opt(row.chi2_p_value),
                e,
            ])?;
        }
        Ok(t)
    }

    /// Table `alignment`: ECM radius, alignment error Δφ and its Δc2
    /// (eq. 8) per station and polarity.
    fn alignment_table(&self) -> Result<Table> {
        let mut t = Table::new(
            "alignment",
            "ECM radius and alignment error per station and polarity",
            &[
                ("station", None),
                ("polarity", None),
                ("ecm_radius", Some(Unit::M)),
                ("delta_phi", Some(Unit::Rad)),
                ("delta_c2", Some(Unit::GPerG2)),
            ],
        );
        for s in &self.stations {
            for a in &s.alignment {
                t.push(vec![
                    Cell::text(s.label()),
                    Cell::num(f64::from(a.polarity)),
                    Cell::num(a.radius_m),
                    Cell::num(a.delta_phi_rad),
                    Cell::num(a.delta_c2),
                ])?;
            }
        }
        Ok(t)
    }

    /// Table `stations`: each station fit of eq. 9 (c2, q, c3 with u, the
    /// type-B Δc2 half-width, dof and lack-of-fit p-value).
    fn stations_table(&self) -> Result<Table> {
        let mut t = Table::new(
            "stations",
            "Station fits (eq. 9)",
            &[
                ("station", None),
                ("points", None),
                ("c2", Some(Unit::GPerG2)),
                ("u_c2", Some(Unit::GPerG2)),
                ("q", Some(Unit::GPerG2)),
                ("u_q", Some(Unit::GPerG2)),
                ("c3", Some(Unit::GPerG3)),
                ("u_c3", Some(Unit::GPerG3)),
                ("delta_c2_half_width", Some(Unit::GPerG2)),
                ("dof", None),
                ("chi2_p", Some(Unit::One)),
            ],
        );
        for s in &self.stations {
            let (q, uq) = s.q.map_or((None, None), |v| (Some(v.value), Some(v.u)));
            let (c3, uc3) = s.c3.map_or((None, None), |v| (Some(v.value), Some(v.u)));
            t.push(vec![
                Cell::text(s.label()),
                Cell::num(s.points as f64),
                Cell::num(s.c2.value),
                Cell::num(s.c2.u),
                Cell::opt(q),
                Cell::opt(uq),
                Cell::opt(c3),
                Cell::opt(uc3),
                Cell::num(s.delta_c2_half_width),
                Cell::num(s.fit.dof as f64),
                Cell::opt(s.fit.chi2_p_value),
            ])?;
        }
        Ok(t)
    }

    /// Table `points`: every point of the station fits (input, mean and
    /// scatter of E/K1, residual).
    fn points_table(&self) -> Result<Table> {
        let mut t = Table::new(
            "points",
            "Station points (eq. 9 fit): mean E/K1 against the centripetal input",
            &[
                ("station", None),
                ("polarity", None),
                ("input_g", None),
                ("n", None),
                ("mean", Some(Unit::G)),
                ("std", Some(Unit::G)),
                ("residual", Some(Unit::G)),
            ],
        );
        for s in &self.stations {
            for (k, p) in s.point_data.iter().enumerate() {
                t.push(vec![
                    Cell::text(s.label()),
                    Cell::num(f64::from(p.polarity)),
                    Cell::num(p.input_g),
                    Cell::num(p.stats.n as f64),
                    Cell::num(p.stats.mean),
                    Cell::num(p.stats.std),
                    Cell::opt(s.fit.residuals.get(k).copied()),
                ])?;
            }
        }
        Ok(t)
    }

    /// One table `budget.<coefficient>` per coefficient (GUM lines and the
    /// combined u) and the extra object `budgets` (combined u, the paper's
    /// eq. 10 u, effective dof and unit of each).
    fn budget_tables(&self, b: &mut DocumentBuilder) -> Result<()> {
        let mut budgets = Map::new();
        for bu in &self.budgets {
            let unit = unit_of(&bu.coefficient)?;
            let mut t = Table::new(
                &format!("budget.{}", bu.coefficient),
                &format!(
                    "Uncertainty budget of {} (GUM; contributions in {}){}",
                    bu.coefficient,
                    unit.engineering().1,
                    bu.combined_u_paper_eq10.map_or(String::new(), |p| format!(
                        "; paper eq. 10 would give u = {:.3e} {}",
                        p,
                        unit.as_str()
                    ))
                ),
                &[
                    ("component", None),
                    ("type", None),
                    ("u", None),
                    ("sensitivity", None),
                    ("contribution", Some(unit.clone())),
                ],
            );
            for l in &bu.lines {
                t.push(vec![
                    Cell::text(l.component.clone()),
                    Cell::text(l.kind.as_str()),
                    Cell::num(l.u),
                    Cell::num(l.sensitivity),
                    Cell::num(l.contribution),
                ])?;
            }
            t.push(vec![
                Cell::text("combined"),
                Cell::Null,
                Cell::Null,
                Cell::Null,
                Cell::num(bu.combined_u),
            ])?;
            budgets.insert(
                bu.coefficient.clone(),
                json!({
                    "combined_u": bu.combined_u,
                    "combined_u_paper_eq10": bu.combined_u_paper_eq10,
                    "effective_dof": bu.effective_dof.is_finite().then_some(bu.effective_dof),
                    "unit": unit.as_str(),
                }),
            );
            b.table(t);
        }
        b.extra("budgets", Value::Object(budgets))?;
        Ok(())
    }

    /// The decisions (variance source, coefficients not determined) and
    /// the warnings (stations not fitted, then the reduction's).
    fn decisions_and_warnings(&self, b: &mut DocumentBuilder) {
        b.decision(
            DecisionCode::VarianceSource,
            "each station and radius fit: variance from the pooled scatter of repeated samples, or from its residuals when they show lack of fit (chi-square, 5 %); see the Fits",
        );
        for (t, why) in &self.unsupported {
            b.decision(DecisionCode::NotDetermined, format!("{t}: {why}"));
        }
        for (st, e) in &self.station_errors {
            b.warnings([Warning::new(
                WarningCode::PartFailed,
                format!("station {st} could not be fitted: {e}"),
            )]);
        }
        b.warnings(self.warnings.iter().cloned());
    }
}

/// The options as used (`options` of the document; type docs of
/// [`super::CentrifugeOptions`]).
fn options(b: &mut DocumentBuilder, opts: &CentrifugeOptions) {
    b.option("k0", json!(opts.k0_u().value));
    b.option("u_k0", json!(opts.k0_u().u));
    b.option("k1", json!(opts.k1_u().value));
    b.option("cov_k0_k1", json!(opts.cov_k0_k1()));
    b.option("u_k1", json!(opts.k1_u().u));
    b.option("radius_m", json!(opts.radius_m));
    b.option("latitude_deg", json!(opts.latitude_deg));
    b.option("gravity_m_s2", json!(opts.gravity_m_s2));
    b.option("opposite_sense", json!(opts.opposite_sense));
    b.option("order", json!(opts.order));
    b.option(
        "alignment_tolerance_deg",
        json!(opts.alignment_tolerance_deg),
    );
}
