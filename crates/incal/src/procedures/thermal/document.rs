//! The thermal result documents: the polynomials' coefficients and
//! `thermal` entries, and the tables of the ramp's blocks, the soak's
//! plateaus and the compensated value ([`super::ramp`], [`super::soak`]).

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};

use super::ramp::RampOptions;
use super::soak::SoakInput;
use super::{power_unit, Degree, PolyFit, ThermalEntry, ValueU};
use crate::document::{Cell, DocumentBuilder, Table};
use crate::error::{Error, Result};
use crate::estimation::Estimates;
use crate::units::Unit;

/// A channel's polynomial coefficients `NAME.ck` into the document, and
/// its `thermal` entry (with the hysteresis and `dT/dt` terms when
/// fitted).
pub(crate) fn channel_entry(
    b: &mut DocumentBuilder,
    name: &str,
    f: &super::PolyFit,
    o: &RampOptions,
    unit: &Unit,
) -> Result<ThermalEntry> {
    let p = f.degree + 1;
    let dof = f.fit.estimates.dof();
    let e = Estimates::new(
        (0..p).map(|k| format!("c{k}")).collect(),
        f.values.rows(0, p).into_owned(),
        f.covariance.view((0, 0), (p, p)).into_owned(),
        dof,
    )?;
    b.estimates(&e, &format!("{name}."), |n| {
        let k: usize = n[1..].parse().map_err(|_| Error::Unsupported(n.into()))?;
        Ok(power_unit(unit, k))
    })?;
    let extra_u = |label: &str, unit_text: String| {
        f.names.iter().position(|n| n == label).map(|j| {
            ValueU::new(
                f.values[j],
                f.covariance[(j, j)].max(0.0).sqrt(),
                &unit_text,
                dof,
            )
        })
    };
    Ok(ThermalEntry {
        degree: f.degree,
        t_ref_c: o.t_ref_c,
        t_min_c: f.t_range_c.0,
        t_max_c: f.t_range_c.1,
        unit: unit.as_str().to_string(),
        hysteresis: extra_u("hysteresis", unit.as_str().to_string()),
        rate_term: extra_u("rate_term", format!("{}/(degC/s)", unit.as_str())),
    })
}

/// The table `ramp.NAME`: the block means against the sensor temperature
/// with the polynomial and the residual, at most about 60 rows
/// (consecutive blocks of one branch merged as weighted means, so a
/// report stays readable).
pub(crate) fn block_table(
    name: &str,
    unit: &Unit,
    d: &super::ramp::ChannelBlocks,
    branch: &[i8],
    f: &super::PolyFit,
) -> Result<Table> {
    let (keep, u, y, tk) = (&d.keep, &d.u, &d.y, &d.t);
    let mut tab = Table::new(
        &format!("ramp.{name}"),
        &format!("{name}: block means against the sensor temperature (consecutive blocks of a branch merged)"),
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("branch", None),
            ("mean", Some(unit.clone())),
            ("u", Some(unit.clone())),
            ("polynomial", Some(unit.clone())),
            ("residual", Some(unit.clone())),
        ],
    );
    let group = keep.len().div_ceil(60).max(1);
    let mut j = 0;
    while j < keep.len() {
        let br = branch[keep[j]];
        let mut end = j;
        while end < keep.len() && end - j < group && branch[keep[end]] == br {
            end += 1;
        }
        let (mut sw, mut st, mut sy, mut sr) = (0.0, 0.0, 0.0, 0.0);
        for q in j..end {
            let w = 1.0 / (u[q] * u[q]);
            let fitted: f64 = (0..f.values.len())
                .map(|k| f.values[k] * regressor(f, &d.extra, q, k, tk[q]))
                .sum();
            sw += w;
            st += w * tk[q];
            sy += w * y[q];
            sr += w * (y[q] - fitted);
        }
        let t_mean = st / sw;
        let (poly_only, _) = f.eval(t_mean);
        tab.push(vec![
            Cell::num(t_mean),
            Cell::text(match br {
                1 => "heating",
                -1 => "cooling",
                _ => "start",
            }),
            Cell::num(sy / sw),
            Cell::num(sw.sqrt().recip()),
            Cell::num(poly_only),
            Cell::num(sr / sw),
        ])?;
        j = end;
    }
    Ok(tab)
}

/// The value of regressor `k` of fit `f` at point `j`.
fn regressor(f: &super::PolyFit, extra: &[(String, Vec<f64>)], j: usize, k: usize, t: f64) -> f64 {
    if k <= f.degree {
        (t - f.t_ref_c).powi(k as i32)
    } else {
        extra[k - f.degree - 1].1[j]
    }
}

/// The polynomials' coefficients `NAME.ck` into the document as one joint
/// block: the polynomials of coefficients of one run are correlated
/// through the runs' own correlations (module docs), each coefficient
/// with its own fit's dof.
pub(crate) fn joint_estimates(
    b: &mut DocumentBuilder,
    inputs: &[SoakInput],
    fits: &[(String, Unit, PolyFit)],
) -> Result<()> {
    let sizes: Vec<usize> = fits.iter().map(|(_, _, f)| f.degree + 1).collect();
    let total: usize = sizes.iter().sum();
    let mut cov = DMatrix::zeros(total, total);
    let mut values = DVector::zeros(total);
    let mut coef_names = Vec::with_capacity(total);
    let mut at = Vec::with_capacity(fits.len());
    let mut pos = 0;
    for (name, _, f) in fits {
        at.push(pos);
        for k in 0..=f.degree {
            values[pos + k] = f.values[k];
            coef_names.push(format!("{name}.c{k}"));
        }
        pos += f.degree + 1;
    }
    for (ia, (na, _, fa)) in fits.iter().enumerate() {
        for (ib, (nb, _, fb)) in fits.iter().enumerate() {
            let (pa, pb) = (fa.degree + 1, fb.degree + 1);
            let block = if ia == ib {
                fa.covariance.view((0, 0), (pa, pa)).into_owned()
            } else {
                let s = DVector::from_fn(inputs.len(), |i, _| {
                    inputs[i].doc.covariance(na, nb).unwrap_or(0.0)
                });
                let ga = fa.gain.rows(0, pa);
                let gb = fb.gain.rows(0, pb);
                (ga * DMatrix::from_diagonal(&s) * gb.transpose())
                    * (fa.variance_factor * fb.variance_factor).sqrt()
            };
            cov.view_mut((at[ia], at[ib]), (pa, pb)).copy_from(&block);
        }
    }
    let dof_of: BTreeMap<String, f64> = fits
        .iter()
        .flat_map(|(name, _, f)| {
            let d = f.fit.estimates.dof();
            (0..=f.degree).map(move |k| (format!("{name}.c{k}"), d))
        })
        .collect();
    let unit_of: BTreeMap<String, Unit> = fits
        .iter()
        .flat_map(|(name, unit, f)| {
            (0..=f.degree).map(move |k| (format!("{name}.c{k}"), power_unit(unit, k)))
        })
        .collect();
    let e = Estimates::new(coef_names, values, cov, f64::INFINITY)?;
    b.estimates_dof(
        &e,
        "",
        |n| {
            unit_of
                .get(n)
                .cloned()
                .ok_or_else(|| Error::Unsupported(format!("no unit for {n}")))
        },
        |n| dof_of.get(n).copied().unwrap_or(f64::INFINITY),
    )?;
    Ok(())
}

/// Why a polynomial got its degree.
pub fn degree_reason(
    name: &str,
    f: &PolyFit,
    asked: Degree,
    trials: &[super::DegreeTrial],
) -> String {
    let tried: Vec<String> = trials
        .iter()
        .map(|t| match t.p_value {
            Some(p) => format!(
                "degree {}: chi2 {:.3} on {} dof, p {:.3}",
                t.degree, t.chi2, t.dof, p
            ),
            None => format!("degree {}: no residual dof", t.degree),
        })
        .collect();
    let how = match asked {
        Degree::Fixed(d) => format!("degree {d} as asked"),
        Degree::Auto => format!(
            "degree {} by the degree rule (smallest degree whose lack-of-fit p >= 0.05, at most min(3, plateaus - 2))",
            f.degree
        ),
    };
    format!("{name}: {how}; {}", tried.join("; "))
}

/// The table `plateaus.NAME`: the value at each plateau against the
/// polynomial, with the residual.
pub(crate) fn plateau_table(
    name: &str,
    unit: &Unit,
    f: &PolyFit,
    t: &[f64],
    y: &[f64],
    u: &[f64],
) -> Result<Table> {
    let mut tab = Table::new(
        &format!("plateaus.{name}"),
        &format!("{name} at each plateau: value, polynomial and residual"),
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("value", Some(unit.clone())),
            ("u", Some(unit.clone())),
            ("polynomial", Some(unit.clone())),
            ("residual", Some(unit.clone())),
            ("normalized_residual", Some(Unit::One)),
        ],
    );
    for i in 0..t.len() {
        let (p, _) = f.eval(t[i]);
        tab.push(vec![
            Cell::num(t[i]),
            Cell::num(y[i]),
            Cell::num(u[i]),
            Cell::num(p),
            Cell::num(y[i] - p),
            Cell::num((y[i] - p) / u[i]),
        ])?;
    }
    Ok(tab)
}

/// The compensated value over the valid range: `y(T)` with u and U95 at
/// eleven temperatures from `t_min` to `t_max` (table `model.NAME`).
pub fn compensated_table(name: &str, unit: &Unit, f: &PolyFit) -> Result<Table> {
    polynomial_table(
        &format!("model.{name}"),
        &format!("{name} from the polynomial over the valid range, with its uncertainty"),
        unit,
        f,
    )
}

/// The table `id` titled `title`: the polynomial `y(T)` of `f` with u and
/// U95 (its dof's coverage factor) at eleven temperatures over its range,
/// columns `temperature_c`, `polynomial`, `u`, `U95`.
pub fn polynomial_table(id: &str, title: &str, unit: &Unit, f: &PolyFit) -> Result<Table> {
    let mut tab = Table::new(
        id,
        title,
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("polynomial", Some(unit.clone())),
            ("u", Some(unit.clone())),
            ("U95", Some(unit.clone())),
        ],
    );
    let (lo, hi) = f.t_range_c;
    let k = crate::estimation::coverage_factor(f.fit.estimates.dof(), 0.95);
    for i in 0..=10 {
        let t = lo + (hi - lo) * i as f64 / 10.0;
        let (v, u) = f.eval(t);
        tab.push(vec![
            Cell::num(t),
            Cell::num(v),
            Cell::num(u),
            Cell::num(k * u),
        ])?;
    }
    Ok(tab)
}
