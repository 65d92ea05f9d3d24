//! Centrifuge calibration of a pendulous accelerometer: test radius,
//! input-axis nonlinearity, cross-axis nonlinearity and cross-coupling
//! with ECM alignment errors and an uncertainty budget (He & Yin 2017;
//! IEEE Std 836; docs/src/centrifuge.md).
//!
//! # Pipeline
//! 1. Samples with the same plane, angle, polarity and rate form a point;
//!    points with the same plane and angle form a *station* (both
//!    polarities). Angles are taken modulo 180° (φ0 + 180° with polarity s
//!    is φ0 with polarity −s).
//! 2. At the IA-radial station (`ip,0`, else `io,0`): static tilt λ
//!    (eq. 4), static radius per polarity (eq. 5–6) and the
//!    regression–iteration radii R± (eq. 7) — see [`radius`]. A table of
//!    regression radii for model orders 1–3 over growing input ranges shows
//!    whether the model is adequate (He & Yin 2017 Table 2: order 1 drifts).
//! 3. The regression radii give the ECM offset `r = (R+ − R−)/2` and, at
//!    every position, the ECM radius and alignment error Δφ
//!    ([`crate::rigs::centrifuge`], He & Yin 2017 §2.2).
//! 4. Every station is fitted with the polarity model of eq. 9, against
//!    the centripetal input `x` (g) computed with those radii:
//!    `E/K1 = b± ± s± x + c2 x² ± q (w± x)² (+ ± c3 (w± x)³)` (`±` =
//!    polarity; `q` only with both polarities, `c3` with model order 3;
//!    `w± = cos(φ0 + Δφ±)/cos φ0` carries the ECM alignment error into the
//!    odd terms, 1 when IA is not in the radial plane or is perpendicular
//!    to the radial direction). Linear in the
//!    parameters, solved by [`crate::estimation::fit_means`]: position means
//!    weighted by the pooled sample scatter, never below the lack of fit.
//! 5. Physical coefficients (g units) by the algebra of [`budget`]: IA
//!    radial gives `K2 = c2`, `K3 = c3`, `K_oq = q`; PA radial (`ip,90` or
//!    `po,0`) gives `K_pp`; OA radial (`io,90` or `po,90`) gives `K_oo`;
//!    a cross station (`ip`, `io`, `po` at an angle off the axes, 45°
//!    preferred) gives `K_ip`, `K_io`, `K_po` by eq. 2–3. Uncertainties by
//!    GUM propagation (`Estimates::map`) with the budget printed line by
//!    line: the c2 of each station (type A), the alignment Δc2 of each
//!    station (eq. 8, type B, uniform with half-width
//!    `|dc2/dφ| (|Δφ_net| + tolerance)`, `Δφ_net` the ECM alignment error
//!    left after averaging both polarities, `tolerance` the fixture angle
//!    bound given by the user) and K1 (the scale of `E/K1`).
//! 6. One propagation for everything: the coefficients of step 5 and the
//!    radius quantities of steps 2–3 (`R±`, static `R±`, `R = (R+ + R−)/2`,
//!    `r`, λ) are one map of one input vector (K0, K1, the raw means E0 and
//!    E_a±, each regression fit's parameters, each station fit's c2, q, c3
//!    and the type-B Δc2) through `Estimates::map`, so the covariance is
//!    complete: K1, shared by every `E/K1`, enters R+ and R− fully
//!    correlated and does not average down in `R`
//!    (`CentrifugeResult::joint`). The coefficient budgets are the rows of
//!    that Jacobian for the coefficients.
//!
//! Because the ECM alignment error has opposite signs in the two
//! polarities (module docs of [`crate::rigs::centrifuge`]), its first-order
//! effect on the common c2 cancels; the paper's 1° deliberate errors (Tables
//! 3–4) are what the `tolerance` covers.
//!
//! # Modules
//! `options` ([`CentrifugeOptions`] and the `--from` chain to a tumble
//! result), `stations` (points, stations, the eq. 9
//! fit), `ia_station` (step 2), `estimate` and `joint_radius` (steps 5–6),
//! `calibrate` ([`calibrate`]: the steps composed), [`radius`] (eq. 4–7),
//! [`budget`] (eq. 2–3, 8, 10), [`document`], [`plan`], [`sim`],
//! [`input`].

pub mod budget;
mod calibrate;
pub mod document;
mod estimate;
mod ia_station;
pub mod input;
mod joint_radius;
mod montecarlo;
mod options;
pub mod plan;
pub mod radius;
pub mod sim;
mod stations;

pub use calibrate::{calibrate, CentrifugeResult};
pub use ia_station::{correct_static_radius, RadiusRangeRow};
pub use options::{CentrifugeOptions, ChainedResult, Resolved};
pub use stations::{Alignment, Station, StationPoint};

use crate::document::ResultDocument;
use crate::error::Result;
use crate::models::Term;
use crate::rigs::centrifuge::Position;
// The checks of the options (`plan` uses two of them).
use options::{check_options, check_order, check_u_omega_ppm};

/// One recorded sample (one row of the input CSV).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Fixture position.
    pub position: Position,
    /// Table rate ω (rad/s); 0 = at rest.
    pub omega_rad_s: f64,
    /// Instrument output E (output units).
    pub output: f64,
}

/// Coefficients a centrifuge run can give, in report order.
pub const CENTRIFUGE_TERMS: [Term; 8] = [
    Term::K2,
    Term::K3,
    Term::Koq,
    Term::Kpp,
    Term::Koo,
    Term::Kip,
    Term::Kio,
    Term::Kpo,
];

/// The centrifuge test as one [`super::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct CentrifugeTest;

impl CentrifugeTest {
    /// Every check of the options, each naming its option (the noise and
    /// the rate's u first, then K0 and K1 as resolved and the rest).
    pub fn validate_options(o: &CentrifugeOptions) -> Result<()> {
        o.noise.validate()?;
        check_u_omega_ppm(o.u_omega_ppm)?;
        check_options(&o.resolve()?.options)
    }
}

impl super::Procedure for CentrifugeTest {
    const ID: crate::document::Procedure = crate::document::Procedure::Centrifuge;
    type Options = CentrifugeOptions;
    type Input = Vec<Observation>;

    fn example() -> CentrifugeOptions {
        CentrifugeOptions {
            from: None,
            k0: Some(1.2e-4),
            u_k0: None,
            k1: Some(1.3),
            u_k1: None,
            cov_k0_k1: None,
            radius_m: 0.71,
            latitude_deg: 39.9,
            gravity_m_s2: crate::units::STANDARD_GRAVITY_M_S2,
            opposite_sense: false,
            order: 3,
            alignment_tolerance_deg: 0.0,
            noise: crate::estimation::Noise::Auto,
            terms: None,
            u_omega_ppm: 0.0,
        }
    }

    fn validate(o: &CentrifugeOptions) -> Result<()> {
        Self::validate_options(o)
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &CentrifugeOptions,
    ) -> Result<Vec<Observation>> {
        input::read(rows)
    }

    fn reduce(
        obs: &Vec<Observation>,
        o: &CentrifugeOptions,
        _: &dyn super::Progress,
    ) -> Result<ResultDocument> {
        let Resolved { options, warnings } = o.resolve()?;
        let r = calibrate(obs, &options)?;
        let mut doc = r.document(&options)?;
        if let Some(f) = &o.from {
            f.record_in(&mut doc);
        }
        doc.warnings.splice(0..0, warnings);
        Ok(doc)
    }

    /// Synthetic recordings from the reported coefficients and radii
    /// (this folder's `montecarlo.rs`).
    fn synthesis(
        obs: &Vec<Observation>,
        o: &CentrifugeOptions,
        _: &ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<Observation>>>> {
        montecarlo::synthesis(obs, o).map(Some)
    }

    /// The options as used: K0, K1, their u and covariance as resolved.
    fn recorded(
        _: &Vec<Observation>,
        o: &CentrifugeOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        super::options_map(&o.resolve()?.options)
    }
}
