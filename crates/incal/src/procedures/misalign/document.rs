//! The result documents of the misalignment tests (gyro on a rate table,
//! accelerometer on a vertical face; Li et al. 2012).

use serde_json::{json, Map, Value};

use crate::document::variance_decision;
use crate::document::{
    position_stats, position_table, Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure,
    ResultDocument, Table,
};
use crate::error::{Error, Result};
use crate::estimation::{Estimates, Fit};
use crate::procedures::misalign::accel::{AccelOptions, AccelResult};
use crate::procedures::misalign::averaging::RecordMean;
use crate::procedures::misalign::gyro::{GyroOptions, GyroResult};
use crate::procedures::misalign::{with_azimuth, with_gamma, AZIMUTH, GAMMA};
use crate::units::Unit;

/// Every estimate of the fit plus γ and ψ, with the joint covariance, in
/// the order `angles…, gamma, azimuth, others…` (biases or offset).
fn joint(fit: &Fit, angles: &[&str]) -> Result<Estimates> {
    let e = &fit.estimates;
    let idx = |n: &str| {
        e.index(n)
            .ok_or_else(|| Error::Unsupported(format!("misalignment fit lost {n}")))
    };
    let (iy, iz) = (idx("dtheta_y2")?, idx("dtheta_z2")?);
    let all = with_azimuth(&with_gamma(e, iy, iz)?, iy, iz)?;
    let mut order: Vec<&str> = angles.to_vec();
    order.extend([GAMMA, AZIMUTH]);
    let others: Vec<String> = e
        .names()
        .iter()
        .filter(|n| !angles.contains(&n.as_str()))
        .cloned()
        .collect();
    order.extend(others.iter().map(String::as_str));
    all.select(&order)
}

/// `{NAME: {"value", "u", "unit"}}` of some estimates (the Li et al. 2012
/// contract objects `angles`, `biases`).
fn value_u_map(e: &Estimates, names: &[String], unit: &str) -> Value {
    let mut m = Map::new();
    for n in names {
        if let Some((v, u)) = e.get(n) {
            m.insert(n.clone(), json!({"value": v, "u": u, "unit": unit}));
        }
    }
    Value::Object(m)
}

fn unit_of(name: &str) -> Unit {
    if name.starts_with("dtheta_") || name == GAMMA || name == AZIMUTH {
        Unit::Rad
    } else {
        Unit::Output
    }
}

/// The parts both tests share: the joint estimates of `angles` with γ, ψ
/// and the rest of the fit as coefficients, the fit, the variance
/// decision and the `angles`/`azimuth` contract objects. Returns the joint.
fn common(
    b: &mut DocumentBuilder,
    fit: &Fit,
    angles: &[&str],
    noise: crate::estimation::Noise,
) -> Result<Estimates> {
    let joint = joint(fit, angles)?;
    let known_noise = matches!(noise, crate::estimation::Noise::Known { .. });
    b.estimates(&joint, "", |n| Ok(unit_of(n)))?;
    b.fit(FitSummary::of("main", fit, Unit::Output));
    b.decision(
        DecisionCode::VarianceSource,
        variance_decision(fit.variance_source, known_noise),
    );
    let angle_names: Vec<String> = joint
        .names()
        .iter()
        .filter(|n| n.starts_with("dtheta_") || *n == GAMMA)
        .cloned()
        .collect();
    b.extra("angles", value_u_map(&joint, &angle_names, "rad"))?;
    if let Some((v, u)) = joint.get(AZIMUTH) {
        b.extra("azimuth", json!({"value": v, "u": u, "unit": "rad"}))?;
    }
    Ok(joint)
}

impl GyroResult {
    /// The result document: misalignment angles `dtheta_*`, `gamma` and
    /// `azimuth` (rad) and the bias(es) (output) as coefficients with their
    /// joint covariance; positions, and the raw records when the input was
    /// a time series (`records`: file line and reduction of each).
    pub fn document(
        &self,
        opts: &GyroOptions,
        records: &[(usize, RecordMean)],
    ) -> Result<ResultDocument> {
        let mut b = DocumentBuilder::new(
            Procedure::MisalignGyro,
            format!(
                "Gyro misalignment on a rate table (Li et al. 2012), {}",
                if opts.per_config_bias {
                    "bias per configuration"
                } else {
                    "common bias"
                }
            ),
        );
        let j = common(
            &mut b,
            &self.fit,
            &crate::procedures::misalign::gyro::GYRO_ANGLES,
            opts.noise,
        )?;
        b.extra(
            "biases",
            value_u_map(&j, self.biases.names(), Unit::Output.as_str()),
        )?;
        b.option("scale_factor", json!(opts.scale_factor));
        b.option("scale_factor_unit", json!(Unit::OutputPerDegS.as_str()));
        b.option("per_config_bias", json!(opts.per_config_bias));
        for (line, r) in records {
            b.warnings(
                r.warnings
                    .iter()
                    .map(|w| w.clone().prefixed(&format!("line {line}"))),
            );
        }
        b.warnings(self.warnings.iter().cloned());
        let mut t = position_table(
            "positions",
            "Positions",
            &[
                ("alpha", Some(Unit::Deg)),
                ("beta", Some(Unit::Deg)),
                ("rate", Some(Unit::DegPerS)),
            ],
        );
        for p in &self.positions {
            let mut row = vec![
                Cell::num(p.config.alpha_rad.to_degrees()),
                Cell::num(p.config.beta_rad.to_degrees()),
                Cell::num(p.rate_deg_s),
            ];
            row.extend(position_stats(
                &p.stats,
                p.residual,
                p.standardized_residual,
            ));
            t.push(row)?;
        }
        b.table(t);
        if !records.is_empty() {
            let mut t = Table::new(
                "records",
                "Raw records averaged over whole table turns",
                &[
                    ("line", None),
                    ("alpha", Some(Unit::Deg)),
                    ("beta", Some(Unit::Deg)),
                    ("rate", Some(Unit::DegPerS)),
                    ("samples", None),
                    ("samples_used", None),
                    ("turns", Some(Unit::One)),
                    ("turns_used", Some(Unit::One)),
                    ("measured_rate", Some(Unit::DegPerS)),
                    ("mean", Some(Unit::Output)),
                ],
            );
            for (line, r) in records {
                let o = &r.observation;
                t.push(vec![
                    Cell::num(*line as f64),
                    Cell::num(o.alpha_rad.to_degrees()),
                    Cell::num(o.beta_rad.to_degrees()),
                    Cell::num(o.rate_deg_s),
                    Cell::num(r.n_total as f64),
                    Cell::num(r.n_used as f64),
                    Cell::num(r.turns_total),
                    Cell::num(r.turns_used),
                    Cell::num(r.measured_rate_deg_s),
                    Cell::num(o.output),
                ])?;
            }
            b.table(t);
        }
        Ok(b.finish())
    }
}

impl AccelResult {
    /// The result document: `dtheta_y2`, `dtheta_z2`, `gamma`, `azimuth`
    /// (rad) and the `offset` (output) with their joint covariance; positions.
    pub fn document(&self, opts: &AccelOptions) -> Result<ResultDocument> {
        let mut b = DocumentBuilder::new(
            Procedure::MisalignAccel,
            "Accelerometer misalignment on a vertical face (Li et al. 2012)",
        );
        let j = common(
            &mut b,
            &self.fit,
            &crate::procedures::misalign::accel::ACCEL_ANGLES,
            opts.noise,
        )?;
        if let Some((v, u)) = j.get("offset") {
            b.extra("offset", json!({"value": v, "u": u, "unit": "output"}))?;
        }
        b.option("scale_factor", json!(opts.scale_factor));
        b.option("scale_factor_unit", json!(Unit::OutputPerG.as_str()));
        b.warnings(self.warnings.iter().cloned());
        let mut t = position_table("positions", "Positions", &[("beta", Some(Unit::Deg))]);
        for p in &self.positions {
            let mut row = vec![Cell::num(p.beta_rad.to_degrees())];
            row.extend(position_stats(
                &p.stats,
                p.residual,
                p.standardized_residual,
            ));
            t.push(row)?;
        }
        b.table(t);
        Ok(b.finish())
    }
}
