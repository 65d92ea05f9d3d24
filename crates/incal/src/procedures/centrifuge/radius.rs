//! Tilt and test radius from the input-axis-radial runs (seed 001 §2.1).
//!
//! * Static tilt (seed 001 eq. 4): `λ = E0/K1 − K0` (rad; accelerations in
//!   g_L units), `E0` the mean at-rest output over both polarities (two
//!   table positions 180° apart).
//! * Static back-calculated radius (eq. 5–6, typo fixed as in methods.md
//!   §2): at the speed ω_g nearest 1 g, `a_g = E_a/K1 − K0` and
//!   `R = s (a_g − sin λ) g_L / ((ω_g² + 2ω_g Ωe sin Φ) cos λ)` with polarity
//!   `s = ±1`. Its uncertainty is propagated by GUM from `u(K0), u(K1),
//!   u(E_a), u(E0)`; this differs from the paper's eq. 6 uncertainty, which
//!   adds `u(K0)` through both `a_g` and `λ` although K0 cancels in
//!   `a_g − λ = (E_a − E0)/K1`. `u(ω_g)` is taken as 0 (the rate of a
//!   precision centrifuge is known to 1e-6 or better; add it to the table's
//!   own budget). [`super::calibrate`] adds the nonlinearity envelope at
//!   ~1 g (uniform, half-width `|K2 a_g² + K3 a_g³|` from the regression)
//!   as a type-B component, as seed 001 §2.1.1 suggests; without it the
//!   static radius is biased by K2·(1 g)², a few ppm.
//! * Regression–iteration radius (eq. 7), per polarity:
//!   `E/K1 = b + (1 + c) a_i + K2 a_i² (+ K3 a_i³)` with
//!   `a_i = s R (ω² + 2ωΩe sinΦ) cos λ / g_L + sin λ`; rescale
//!   `R ← R (1 + c)` and refit until `|c| < 1e-13` (so `R = R0 Π(1 + c_k)`).
//!   `u(R)² = (R u(c))² + (R u(K1)/K1)²` (the scale of `E/K1` is that of K1).
//!
//! Both radii are *effective* radii, as in the paper: whatever multiplies
//! `a_i` at the IA-radial station counts as radius. With the 1 g on the
//! vertical axis that includes the cross-coupling (`R_eff = R (1 + K_io)` at
//! `ip,0`, `R (1 + K_ip)` at `io,0`), a few ppm; the coefficients are
//! insensitive to it (c2 moves by twice that fraction).

use nalgebra::DVector;

use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::rigs::centrifuge::centripetal_rate_squared;

/// A value with its standard uncertainty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValueU {
    /// Value.
    pub value: f64,
    /// Standard uncertainty.
    pub u: f64,
}

/// Inputs from the 1 g calibration (tumble) and the rig that every radius
/// computation needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadiusContext {
    /// Bias K0 (g) and its u.
    pub k0_g: ValueU,
    /// Scale factor K1 (output/g) and its u.
    pub k1: ValueU,
    /// Latitude Φ (rad).
    pub latitude_rad: f64,
    /// Local gravity (m/s²).
    pub g_local_m_s2: f64,
    /// Table spins opposite to Earth's sense.
    pub opposite_sense: bool,
}

/// Static tilt λ (rad) from at-rest samples of the IA-radial station
/// (seed 001 eq. 4). `samples` are raw outputs.
pub fn static_tilt(samples: &[f64], ctx: &RadiusContext) -> Result<ValueU> {
    let st = PositionStats::of(samples)?;
    let u_e0 = if st.n > 1 {
        st.std / (st.n as f64).sqrt()
    } else {
        0.0
    };
    let k1 = ctx.k1.value;
    let lambda = st.mean / k1 - ctx.k0_g.value;
    let u = (ctx.k0_g.u.powi(2) + (u_e0 / k1).powi(2) + (st.mean * ctx.k1.u / (k1 * k1)).powi(2))
        .sqrt();
    Ok(ValueU { value: lambda, u })
}

/// Static back-calculated radius (m) at one speed (module docs, eq. 5–6).
/// `e_a` = samples at speed `omega_rad_s`, `e0` = at-rest samples,
/// `polarity` = ±1.
pub fn static_radius(
    e_a: &[f64],
    e0: &[f64],
    omega_rad_s: f64,
    polarity: f64,
    ctx: &RadiusContext,
) -> Result<ValueU> {
    let a = PositionStats::of(e_a)?;
    let z = PositionStats::of(e0)?;
    let sem = |s: &PositionStats| {
        if s.n > 1 {
            s.std / (s.n as f64).sqrt()
        } else {
            0.0
        }
    };
    let rate2 = centripetal_rate_squared(omega_rad_s, ctx.latitude_rad, ctx.opposite_sense);
    if rate2 <= 0.0 {
        return Err(Error::InvalidValue {
            what: "rate for the static radius".into(),
            value: omega_rad_s.to_string(),
        });
    }
    let g = ctx.g_local_m_s2;
    let inputs = Estimates::new(
        vec!["K0".into(), "K1".into(), "E_a".into(), "E0".into()],
        DVector::from_vec(vec![ctx.k0_g.value, ctx.k1.value, a.mean, z.mean]),
        nalgebra::DMatrix::from_diagonal(&DVector::from_vec(vec![
            ctx.k0_g.u.powi(2),
            ctx.k1.u.powi(2),
            sem(&a).powi(2),
            sem(&z).powi(2),
        ])),
        f64::INFINITY,
    )?;
    let f = move |x: &DVector<f64>| {
        let lambda = x[3] / x[1] - x[0];
        let a_g = x[2] / x[1] - x[0];
        DVector::from_element(
            1,
            polarity * (a_g - lambda.sin()) * g / (rate2 * lambda.cos()),
        )
    };
    let r = inputs.map_numeric(vec!["R".into()], f)?;
    Ok(ValueU {
        value: r.values()[0],
        u: r.u_at(0),
    })
}

/// One regression–iteration radius (eq. 7).
#[derive(Debug, Clone, PartialEq)]
pub struct RadiusFit {
    /// Model order (1, 2 or 3).
    pub order: usize,
    /// Largest nominal input used (g).
    pub max_input_g: f64,
    /// Radius and u (m).
    pub radius_m: ValueU,
    /// Iterations until |c| < 1e-13.
    pub iterations: usize,
    /// The last fit (terms `b`, `scale`, `K2`, `K3` as the order has them).
    pub fit: Fit,
    /// Root-mean-square residual of the point means (g).
    pub residual_rms_g: f64,
}

/// One steady point: speed and the samples (raw output).
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedPoint {
    /// Table rate (rad/s).
    pub omega_rad_s: f64,
    /// Statistics of `E/K1` (g).
    pub stats: PositionStats,
}

/// Regression–iteration radius for one polarity (module docs).
/// `points` are the IA-radial points of that polarity (static ones
/// included: they pin the bias), `r0_m` the starting radius, `tilt_rad` λ.
pub fn regression_radius(
    points: &[SpeedPoint],
    polarity: f64,
    order: usize,
    r0_m: f64,
    tilt_rad: f64,
    ctx: &RadiusContext,
    noise: Noise,
) -> Result<RadiusFit> {
    if !(1..=3).contains(&order) {
        return Err(Error::Unsupported(format!(
            "model order {order} (use 1, 2 or 3)"
        )));
    }
    let mut names = vec!["b".to_string(), "scale".to_string()];
    if order >= 2 {
        names.push("K2".into());
    }
    if order >= 3 {
        names.push("K3".into());
    }
    let stats: Vec<PositionStats> = points.iter().map(|p| p.stats).collect();
    let rate2: Vec<f64> = points
        .iter()
        .map(|p| centripetal_rate_squared(p.omega_rad_s, ctx.latitude_rad, ctx.opposite_sense))
        .collect();
    let mut r = r0_m;
    let (sl, cl) = (tilt_rad.sin(), tilt_rad.cos());
    for iter in 1..=60 {
        let rows: Vec<Vec<f64>> = rate2
            .iter()
            .map(|k| {
                let x = polarity * r * k * cl / ctx.g_local_m_s2 + sl;
                (0..=order).map(|p| x.powi(p as i32)).collect()
            })
            .collect();
        let d = Design::from_rows(names.clone(), &rows)?;
        let (f, _) = fit_means(&d, &stats, noise)?;
        let (scale, u_scale) = f.estimates.get("scale").unwrap_or((f64::NAN, f64::NAN));
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::InvalidValue {
                what: "regression scale (1 + c)".into(),
                value: scale.to_string(),
            });
        }
        let c = scale - 1.0;
        if c.abs() < 1e-13 || iter == 60 {
            let u = ((r * u_scale).powi(2) + (r * ctx.k1.u / ctx.k1.value).powi(2)).sqrt();
            let rms = if f.dof > 0 {
                (f.residuals.norm_squared() / f.dof as f64).sqrt()
            } else {
                f64::NAN
            };
            let max_input_g = rate2
                .iter()
                .map(|k| r * k / ctx.g_local_m_s2)
                .fold(0.0, f64::max);
            return Ok(RadiusFit {
                order,
                max_input_g,
                radius_m: ValueU { value: r, u },
                iterations: iter,
                fit: f,
                residual_rms_g: rms,
            });
        }
        r *= scale;
    }
    Err(Error::Unsupported(
        "regression-iteration radius did not converge".into(),
    ))
}
