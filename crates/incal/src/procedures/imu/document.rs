//! The result documents of the IMU triad calibrations.

use serde_json::json;

use super::autocal::AutocalResult;
use super::ferraris::{FerrarisResult, QUANTITIES, SECTIONS};
use super::multipos::MultiposResult;
use super::sim::TriadParams;
use super::{rows, SectionStats, AXES};
use crate::document::{Cell, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table};
use crate::error::Result;
use crate::units::Unit;

/// Unit of a Ferraris element (`K_a.xy` → `output/(m/s^2)`).
pub fn ferraris_unit(name: &str) -> Result<Unit> {
    let q = name.split('.').next().unwrap_or(name);
    Ok(Unit::Other(
        match q {
            "K_a" | "K_ga" => "output/(m/s^2)",
            "K_g" => "output/(deg/s)",
            "R_a" | "R_g" => "1",
            _ => "output",
        }
        .into(),
    ))
}

/// The per-section statistics table (label, samples, means and scatter of
/// the six channels).
fn section_table(labels: &[&str], stats: &[SectionStats]) -> Result<Table> {
    let ch = ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"];
    let mut cols: Vec<(String, Option<Unit>)> =
        vec![("section".into(), None), ("samples".into(), None)];
    for c in ch {
        cols.push((format!("{c}_mean"), Some(Unit::Output)));
    }
    for c in ch {
        cols.push((format!("{c}_std"), Some(Unit::Output)));
    }
    let cols_ref: Vec<(&str, Option<Unit>)> =
        cols.iter().map(|(n, u)| (n.as_str(), u.clone())).collect();
    let mut t = Table::new(
        "sections",
        "Sections: samples, mean and standard deviation of each channel",
        &cols_ref,
    );
    for (l, s) in labels.iter().zip(stats) {
        let mut row = vec![Cell::text(*l), Cell::num(s.n as f64)];
        row.extend((0..6).map(|k| Cell::num(s.mean[k])));
        row.extend((0..6).map(|k| Cell::num(s.std(k))));
        t.push(row)?;
    }
    Ok(t)
}

impl FerrarisResult {
    /// The result document: every element as `K_a.xx`, `R_a.xy`, `b_a.x`,
    /// … in `coefficients` (with u, one correlation block), and the
    /// matrices at the top level in imucal's keys and definitions
    /// (`K_a`, `R_a`, `b_a`, `K_g`, `R_g`, `K_ga`, `b_g`; lists of rows),
    /// plus `acc_unit`, `gyr_unit` as imucal writes them.
    pub fn document(&self) -> Result<ResultDocument> {
        let o = &self.options;
        let mut b = DocumentBuilder::new(
            Procedure::ImuFerraris,
            format!(
                "IMU Ferraris calibration (6 positions + 3 rotations of {} deg, g = {} m/s^2{})",
                o.rotation_deg,
                o.gravity_m_s2,
                match o.convention {
                    super::ferraris::Convention::Standard => "",
                    super::ferraris::Convention::Imucal => ", imucal's sign convention",
                }
            ),
        );
        // K_a and K_g are diagonal by the method's construction (Ferraris
        // et al. 1995): their off-diagonal elements are zeros, not
        // estimates, and are not listed (the matrices below keep them).
        let fixed = |n: &str| {
            n.strip_prefix("K_a.")
                .or_else(|| n.strip_prefix("K_g."))
                .is_some_and(|ij| ij.len() == 2 && ij[..1] != ij[1..])
        };
        let kept: Vec<&str> = self
            .estimates
            .names()
            .iter()
            .map(String::as_str)
            .filter(|n| !fixed(n))
            .collect();
        b.estimates(&self.estimates.select(&kept)?, "", ferraris_unit)?;
        if kept.len() < self.estimates.names().len() {
            b.decision(
                crate::document::DecisionCode::FixedByModel,
                "K_a and K_g are diagonal by construction (Ferraris et al. 1995; the misalignments are in R_a, R_g): their off-diagonal elements are 0, not estimated, and not listed as coefficients",
            );
        }
        for (k, v) in crate::procedures::options_map(o)? {
            b.option(&k, v);
        }
        let m = &self.matrices;
        for q in QUANTITIES {
            let v = match m.matrix(q) {
                Some(mm) => json!(rows(&mm)),
                None => {
                    let v = if q == "b_a" { m.b_a } else { m.b_g };
                    json!([v[0], v[1], v[2]])
                }
            };
            b.extra(q, v)?;
        }
        b.extra("acc_unit", json!("m/s^2"))?;
        b.extra("gyr_unit", json!("deg/s"))?;
        b.extra("cal_type", json!("Ferraris"))?;
        b.warnings(self.warnings.iter().cloned());
        b.table(section_table(&SECTIONS, &self.sections)?);
        Ok(b.finish())
    }
}

/// Unit of an autocalibration parameter (`acc.s_x` → `(m/s^2)/output`;
/// gyro scales in `(deg/s)/output`, the gyro unit of every IMU procedure).
pub fn autocal_unit(name: &str) -> Result<Unit> {
    let (triad, p) = name.split_once('.').unwrap_or(("", name));
    Ok(Unit::Other(
        match (triad, p.split('_').next().unwrap_or("")) {
            (_, "m") => "1",
            ("acc", "s") => "(m/s^2)/output",
            ("gyr", "s") => "(deg/s)/output",
            _ => "output",
        }
        .into(),
    ))
}

fn triad_json(p: &TriadParams) -> serde_json::Value {
    json!({
        "T": rows(&p.t()),
        "K": rows(&p.k()),
        "b": p.bias,
    })
}

impl AutocalResult {
    /// The result document: `acc.m_yz … acc.b_z` (and `gyr.*`) in
    /// `coefficients` with their joint covariance; top-level `acc` and
    /// `gyr` as `{"T", "K", "b"}` in imu_tk's convention
    /// (`calibrated = T K (raw − b)`), `intervals` (`start_s`, `end_s` of
    /// every still interval used), the threshold kept and the number of
    /// distinct orientations; tables of the intervals and the thresholds.
    pub fn document(&self) -> Result<ResultDocument> {
        let o = &self.options;
        let mut b = DocumentBuilder::new(
            Procedure::ImuAutocal,
            format!(
                "IMU autocalibration, method {} ({} still intervals, {} orientations{})",
                o.method.name(),
                self.intervals.len(),
                self.orientations,
                if self.gyr.is_some() {
                    ", accelerometer and gyro"
                } else {
                    ", accelerometer"
                }
            ),
        );
        // One gyro unit across the IMU procedures: the gyro scales in
        // (deg/s)/output as Ferraris and multipos give theirs; the imu_tk
        // matrices at the top level stay in rad/s, as imu_tk writes them.
        let deg = 180.0 / std::f64::consts::PI;
        let factor = nalgebra::DVector::from_iterator(
            self.estimates.len(),
            self.estimates
                .names()
                .iter()
                .map(|n| if n.starts_with("gyr.s_") { deg } else { 1.0 }),
        );
        let shown = self.estimates.map(
            self.estimates.names().to_vec(),
            |x| x.component_mul(&factor),
            |_| nalgebra::DMatrix::from_diagonal(&factor),
        )?;
        b.estimates(&shown, "", autocal_unit)?;
        b.fit(FitSummary::of(
            "acc",
            &self.acc_fit,
            Unit::Other("m/s^2".into()),
        ));
        if let Some(gf) = &self.gyr_fit {
            b.fit(FitSummary::of("gyr", gf, Unit::One));
        }
        b.option("method", json!(o.method.name()));
        b.option("gravity_m_s2", json!(o.gravity));
        b.option("init_static_s", json!(o.init_static_s));
        b.option("window_samples", json!(o.window));
        b.option("min_samples", json!(o.min_samples));
        b.option("settle_s", json!(o.settle_s));
        b.extra("acc", triad_json(&self.acc))?;
        if let Some(g) = &self.gyr {
            b.extra("gyr", triad_json(g))?;
        }
        b.extra(
            "intervals",
            json!(self
                .intervals
                .iter()
                .map(|i| json!({"start_s": i.start_s, "end_s": i.end_s}))
                .collect::<Vec<_>>()),
        )?;
        b.extra(
            "threshold",
            json!({"k": self.k, "variance_norm": self.threshold}),
        )?;
        b.extra("orientations", json!(self.orientations))?;
        b.warnings(self.warnings.iter().cloned());
        let mut t = Table::new(
            "intervals",
            "Still intervals used: time span, samples, raw accelerometer mean and standard deviation",
            &[
                ("start_s", Some(Unit::Other("s".into()))),
                ("end_s", Some(Unit::Other("s".into()))),
                ("samples", None),
                ("acc_x_mean", Some(Unit::Output)),
                ("acc_y_mean", Some(Unit::Output)),
                ("acc_z_mean", Some(Unit::Output)),
                ("acc_x_std", Some(Unit::Output)),
                ("acc_y_std", Some(Unit::Output)),
                ("acc_z_std", Some(Unit::Output)),
            ],
        );
        for i in &self.intervals {
            let mut row = vec![
                Cell::num(i.start_s),
                Cell::num(i.end_s),
                Cell::num(i.used as f64),
            ];
            row.extend(i.mean.iter().map(|v| Cell::num(*v)));
            row.extend(i.std.iter().map(|v| Cell::num(*v)));
            t.push(row)?;
        }
        b.table(t);
        let mut th = Table::new(
            "thresholds",
            "Thresholds tried: k times the variance norm of the initial still interval",
            &[
                ("k", None),
                ("intervals", None),
                ("cost", Some(Unit::Other("(m/s^2)^2".into()))),
            ],
        );
        for tr in &self.trials {
            th.push(vec![
                Cell::num(tr.k),
                Cell::num(tr.intervals as f64),
                Cell::opt(tr.cost),
            ])?;
        }
        b.table(th);
        Ok(b.finish())
    }
}

/// Unit of a multi-position parameter (`acc.A_xy` → `output/(m/s^2)`).
pub fn multipos_unit(name: &str) -> Result<Unit> {
    let (triad, p) = name.split_once('.').unwrap_or(("", name));
    Ok(Unit::Other(
        match (triad, p.split('_').next().unwrap_or("")) {
            (_, "b") => "output",
            (_, "M") => "rad",
            (_, "G") => "output/(m/s^2)",
            ("acc", _) => "output/(m/s^2)",
            _ => "output/(deg/s)",
        }
        .into(),
    ))
}

impl MultiposResult {
    /// The result document: every parameter in `coefficients`; top-level
    /// `acc` (`A`, `b`, `S`, `M`) and `gyr` (`b`, `G`, and `A`, `S`, `M`
    /// when estimated) with matrices as lists of rows (zero where the
    /// convention fixes an element, 1 on the diagonal of M); per-position
    /// and per-axis-fit tables.
    pub fn document(&self) -> Result<ResultDocument> {
        let o = &self.options;
        let mut b = DocumentBuilder::new(
            Procedure::ImuMultipos,
            format!(
                "IMU multi-position calibration ({} positions, {} rotations, accelerometer matrix {})",
                self.statics.len(),
                self.rotations.len(),
                o.matrix.name()
            ),
        );
        // Each axis is its own fit: its coefficients (and the scale and
        // misalignments derived from them) carry that fit's dof.
        let dof_of = |name: &str| -> f64 {
            let (triad, p) = name.split_once('.').unwrap_or(("", name));
            let axis = p.split_once('_').map_or("", |(_, r)| &r[..1.min(r.len())]);
            let label = format!("{triad}.{axis}");
            self.fits
                .iter()
                .find(|(l, _)| *l == label)
                .map_or(self.estimates.dof(), |(_, f)| f.estimates.dof())
        };
        b.estimates_dof(&self.estimates, "", multipos_unit, dof_of)?;
        for (label, f) in &self.fits {
            b.fit(FitSummary::of(label, f, Unit::Output));
        }
        b.option("gravity_m_s2", json!(o.gravity));
        b.option("matrix", json!(o.matrix.name()));
        b.option("rate_hz", json!(o.rate_hz));
        b.option("latitude_deg", json!(o.latitude_deg));
        b.option("rotation_deg", json!(o.rotation_deg));
        let e = &self.estimates;
        let get = |n: String| e.value(&n).unwrap_or(0.0);
        let mat = |t: &str, m: &str, diag: f64| -> serde_json::Value {
            json!((0..3)
                .map(|j| (0..3)
                    .map(|k| if m == "M" && j == k {
                        diag
                    } else {
                        get(format!("{t}.{m}_{}{}", AXES[j], AXES[k]))
                    })
                    .collect::<Vec<f64>>())
                .collect::<Vec<_>>())
        };
        let vec3 = |t: &str, m: &str| -> serde_json::Value {
            json!((0..3)
                .map(|j| get(format!("{t}.{m}_{}", AXES[j])))
                .collect::<Vec<f64>>())
        };
        b.extra(
            "acc",
            json!({"A": mat("acc", "A", 0.0), "b": vec3("acc", "b"), "S": vec3("acc", "S"), "M": mat("acc", "M", 1.0)}),
        )?;
        if o.gyro {
            let mut g = serde_json::Map::new();
            g.insert("b".into(), vec3("gyr", "b"));
            g.insert("G".into(), mat("gyr", "G", 0.0));
            if self.gyro_scale {
                g.insert("A".into(), mat("gyr", "A", 0.0));
                g.insert("S".into(), vec3("gyr", "S"));
                g.insert("M".into(), mat("gyr", "M", 1.0));
            }
            b.extra("gyr", serde_json::Value::Object(g))?;
        }
        b.warnings(self.warnings.iter().cloned());
        let mut t = Table::new(
            "positions",
            "Positions: up direction in the IMU frame, samples, channel means",
            &[
                ("position", None),
                ("up_x", None),
                ("up_y", None),
                ("up_z", None),
                ("samples", None),
                ("acc_x_mean", Some(Unit::Output)),
                ("acc_y_mean", Some(Unit::Output)),
                ("acc_z_mean", Some(Unit::Output)),
                ("gyr_x_mean", Some(Unit::Output)),
                ("gyr_y_mean", Some(Unit::Output)),
                ("gyr_z_mean", Some(Unit::Output)),
            ],
        );
        for p in &self.statics {
            let mut row = vec![
                Cell::text(p.label.clone()),
                Cell::num(p.up[0]),
                Cell::num(p.up[1]),
                Cell::num(p.up[2]),
                Cell::num(p.stats.n as f64),
            ];
            row.extend((0..6).map(|k| {
                if k >= 3 && !o.gyro {
                    Cell::Null
                } else {
                    Cell::num(p.stats.mean[k])
                }
            }));
            t.push(row)?;
        }
        for r in &self.rotations {
            let mut row = vec![
                Cell::text(r.label.clone()),
                Cell::Null,
                Cell::Null,
                Cell::Null,
                Cell::num(r.stats.n as f64),
            ];
            row.extend((0..6).map(|k| Cell::num(r.stats.mean[k])));
            t.push(row)?;
        }
        b.table(t);
        Ok(b.finish())
    }
}
