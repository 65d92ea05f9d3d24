//! Property tests of the estimation core: analytic Jacobians against finite
//! differences, exact recovery of noiseless data, and invariance of the
//! solution to the units of the parameters (column scaling).

use incal::estimation::{fit, numeric_jacobian, Design, Estimates, FitOptions, Variance};
use incal::models::Term;
use incal::procedures::tumble::plan::TumblePlan;
use incal::procedures::tumble::{default_terms, design, to_physical};
use incal::rigs::Mount;
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

/// The pendulum mount's default terms: K0, K1, K2, K3, δo, Kip.
fn terms() -> Vec<Term> {
    default_terms(Mount::Pendulum)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The covariance map of tumble's `to_physical` (analytic Jacobian)
    /// equals the one from a central-difference Jacobian.
    #[test]
    fn tumble_map_jacobian_matches_finite_differences(
        k1 in 0.5f64..20.0,
        others in proptest::collection::vec(-1e-2f64..1e-2, 5),
    ) {
        let p = DVector::from_vec(vec![k1 * others[0], k1, k1 * others[1], k1 * others[2], k1 * others[3], k1 * others[4]]);
        let names: Vec<String> = terms().iter().map(|t| t.name().to_string()).collect();
        let cov = DMatrix::from_fn(6, 6, |i, j| if i == j { 1e-8 * (1.0 + i as f64) } else { 1e-10 });
        let lin = Estimates::new(names, p.clone(), cov.clone(), f64::INFINITY).unwrap();
        let phys = to_physical(&lin, &terms()).unwrap();
        let f = |x: &DVector<f64>| DVector::from_fn(6, |j, _| if j == 1 { x[1] } else { x[j] / x[1] });
        let steps: Vec<f64> = p.iter().map(|v| 1e-6 * v.abs().max(1e-6)).collect();
        let j = numeric_jacobian(&f, &p, &steps);
        let expect = &j * &cov * j.transpose();
        for a in 0..6 {
            for b in 0..6 {
                let tol = 1e-5 * (expect[(a, a)] * expect[(b, b)]).sqrt() + 1e-30;
                prop_assert!((phys.covariance()[(a, b)] - expect[(a, b)]).abs() <= tol);
            }
        }
    }

    /// Noiseless data from any parameter vector are fitted exactly, on any
    /// plan that separates the terms.
    #[test]
    fn noiseless_tumble_is_recovered(
        step in 2.0f64..18.0,
        p in proptest::collection::vec(-1.0f64..1.0, 6),
    ) {
        let plan = TumblePlan::small_angle(step).unwrap();
        let d = design(Mount::Pendulum, &terms(), &plan.angles_rad()).unwrap();
        let x = DVector::from_vec(p);
        let y = d.matrix() * &x;
        let opts = FitOptions { variance: Variance::Known { dof: f64::INFINITY }, ..FitOptions::default() };
        let f = fit(&d, &y, &opts).unwrap();
        for k in 0..6 {
            let tol = 1e-6 * f.estimates.u_at(k).max(1e-9) + 1e-9;
            prop_assert!((f.estimates.values()[k] - x[k]).abs() <= tol,
                "term {k}: {} vs {}", f.estimates.values()[k], x[k]);
        }
    }

    /// Rescaling a column by s (a change of units) rescales its estimate and
    /// uncertainty by 1/s and leaves rank, condition number and residuals
    /// unchanged.
    #[test]
    fn column_scaling_is_a_change_of_units(
        scale in prop_oneof![1e-6f64..1e-3, 1e3f64..1e6],
        col in 0usize..6,
        noise in proptest::collection::vec(-1e-3f64..1e-3, 12),
    ) {
        let d = design(Mount::Pendulum, &terms(), &TumblePlan::gjb12().angles_rad()).unwrap();
        let y = d.matrix() * DVector::from_vec(vec![0.1, 10.0, 0.01, 0.02, 0.03, 0.04]) + DVector::from_vec(noise);
        let mut m = d.matrix().clone();
        m.column_mut(col).scale_mut(scale);
        let ds = Design::new(d.names().to_vec(), m).unwrap();
        let f = fit(&d, &y, &FitOptions::default()).unwrap();
        let g = fit(&ds, &y, &FitOptions::default()).unwrap();
        prop_assert_eq!(f.diagnostics.rank, g.diagnostics.rank);
        prop_assert!((f.diagnostics.condition / g.diagnostics.condition - 1.0).abs() < 1e-8);
        let (v, u) = (f.estimates.values()[col], f.estimates.u_at(col));
        let (vs, us) = (g.estimates.values()[col] * scale, g.estimates.u_at(col) * scale);
        prop_assert!((v - vs).abs() <= 1e-9 * v.abs().max(u));
        prop_assert!((u / us - 1.0).abs() < 1e-8);
        prop_assert!((&f.residuals - &g.residuals).amax() < 1e-12);
    }
}
