//! He & Yin 2017 (centrifuge cross-coupling) reproduced: the ECM
//! offset and alignment error from Table 1, Δc2 of Tables 3–4 (eq. 8) and
//! K_ip of Table 5 (eq. 3). The paper's coefficients are in
//! (m/s²)/(m/s²)²; the algebra is unit-free, so they are used as printed.

use incal::procedures::centrifuge::budget::{
    c2_at, cross_coupling, delta_c2, ecm_offset, Budget, BudgetLine, UncertaintyType,
};
use incal::rigs::centrifuge::ecm_geometry;

/// Table 1 means: R+ = 0.714775 m, R− = 0.705794 m.
const R_PLUS: f64 = 0.714775;
const R_MINUS: f64 = 0.705794;
/// §2.2.1 / Table 5 (LXJ-100): K2, Kpp, Kip in (m/s²)/(m/s²)².
const K2: f64 = 3.94e-7;
const KPP: f64 = 4.7e-8;
const KIP: f64 = 7.1e-7;

/// Table 1 → r = |R+ − R−|/2 ≈ 4.49 mm (paper §2.2.1; tolerance: the
/// printed 3 significant digits, ±0.005 mm).
#[test]
fn table1_ecm_offset() {
    let (r_centre, r) = ecm_offset(R_PLUS, R_MINUS);
    assert!((r - 4.49e-3).abs() < 0.005e-3, "r = {r}");
    assert!((r_centre - 0.7102845).abs() < 1e-7);
}

/// Table 1 → Δφ ≈ 4.49×10⁻³ rad at φ0 = 45°. The paper's polarity-+
/// formula `atan(r sinφ0/(R − r cosφ0))` is, with the sign fixed by the
/// geometry (docs/src/centrifuge.md), the polarity − one: 4.49×10⁻³ (±0.005×10⁻³);
/// polarity + (`R + r cosφ0`) gives 4.45×10⁻³ with the opposite sign.
#[test]
fn table1_alignment_error_at_45_degrees() {
    let (r_centre, r) = ecm_offset(R_PLUS, R_MINUS);
    let phi = 45f64.to_radians();
    let minus = ecm_geometry(r_centre, r, phi, -1.0);
    let plus = ecm_geometry(r_centre, r, phi, 1.0);
    assert!(
        (minus.delta_phi_rad - 4.49e-3).abs() < 0.005e-3,
        "{minus:?}"
    );
    assert!((plus.delta_phi_rad + 4.45e-3).abs() < 0.005e-3, "{plus:?}");
    // Radii: R2 = sqrt((R − r cos)² + (r sin)²) for polarity −, and the
    // IA-radial limits R+ and R−.
    let r2 = ((r_centre - r * phi.cos()).powi(2) + (r * phi.sin()).powi(2)).sqrt();
    assert!((minus.radius_m - r2).abs() < 1e-12);
    assert!((ecm_geometry(r_centre, r, 0.0, 1.0).radius_m - R_PLUS).abs() < 1e-12);
    assert!((ecm_geometry(r_centre, r, 0.0, -1.0).radius_m - R_MINUS).abs() < 1e-12);
    // Transverse (§2.2.2): Δφ = atan(r/R) = 6.32×10⁻³ rad.
    let t = ecm_geometry(r_centre, r, 90f64.to_radians(), 1.0);
    assert!((t.delta_phi_rad.abs() - (r / r_centre).atan()).abs() < 1e-15);
}

/// Table 3: a 1° alignment error at 45° gives Δc2 = −6.1×10⁻⁹ (eq. 8,
/// (Kpp − K2)·Δφ; tolerance ±0.05×10⁻⁹, the printed digits), and the
/// measured c2 falls from 44° to 46° (5.84, 5.76, 5.68 ×10⁻⁷) as the sign
/// of Δc2 says.
#[test]
fn table3_delta_c2_at_45_degrees() {
    let one_deg = 1f64.to_radians();
    let d = delta_c2(K2, KPP, KIP, 45f64.to_radians(), one_deg);
    assert!((d - (-6.1e-9)).abs() < 0.05e-9, "{d}");
    let table3 = [5.84e-7, 5.76e-7, 5.68e-7];
    assert!(table3[1] - table3[0] < 0.0 && table3[2] - table3[1] < 0.0);
    assert!(d < 0.0);
}

/// Table 4: at 90° (PA radial) a 1° error gives Δc2 = ΔKpp = −Kip·Δφ =
/// −1.24×10⁻⁸ (tolerance ±0.005×10⁻⁸); Table 4's c2 falls from 90° to 91°.
#[test]
fn table4_delta_c2_at_90_degrees() {
    let one_deg = 1f64.to_radians();
    let d = delta_c2(K2, KPP, KIP, 90f64.to_radians(), one_deg);
    assert!((d - (-1.24e-8)).abs() < 0.005e-8, "{d}");
    let table4 = [6.01e-8, 4.72e-8, 4.26e-8];
    assert!(table4[2] < table4[1]);
}

/// Table 5 (LXJ-100): Kip = 2·5.76 − (3.94 + 0.47) = 7.11 (×10⁻⁷), eq. 3
/// (printed 7.10; tolerance ±0.005×10⁻⁷ on 7.11). LXJ-200:
/// 2·5.33 − (4.13 − 0.15) = 6.68 (printed 6.67; ±0.015×10⁻⁷).
#[test]
fn table5_kip_from_c2_k2_kpp() {
    let phi = 45f64.to_radians();
    let k = cross_coupling(5.76e-7, 3.94e-7, 0.47e-7, phi);
    assert!((k - 7.11e-7).abs() < 0.005e-7, "{k}");
    let k200 = cross_coupling(5.33e-7, 4.13e-7, -0.15e-7, phi);
    assert!((k200 - 6.67e-7).abs() < 0.015e-7, "{k200}");
    // eq. 2 forward gives back the c2.
    assert!((c2_at(3.94e-7, 0.47e-7, k, phi) - 5.76e-7).abs() < 1e-20);
}

/// Eq. 10 versus GUM: with the same five components, the paper weights
/// u²(c2) + u²(Δc2) by 2 where the sensitivity 2 of eq. 3 gives 4.
#[test]
fn eq10_paper_and_gum_conventions_differ_by_the_c2_weight() {
    let comp = [
        ("c2", 2.0, 3e-9, true),
        ("dc2", 2.0, 1e-9, true),
        ("K2", -1.0, 4e-9, false),
        ("Kpp", -1.0, 2e-9, false),
        ("dKpp", -1.0, 1e-9, false),
    ];
    let lines: Vec<BudgetLine> = comp
        .iter()
        .map(|(n, s, u, _)| BudgetLine {
            component: n.to_string(),
            kind: UncertaintyType::A,
            u: *u,
            sensitivity: *s,
            contribution: s.abs() * u,
        })
        .collect();
    let own: Vec<bool> = comp.iter().map(|c| c.3).collect();
    let b = Budget::from_lines("K_ip".into(), lines, &own, &[f64::INFINITY; 5], true);
    let gum = (4.0 * (9e-18 + 1e-18) + 16e-18 + 4e-18 + 1e-18f64).sqrt();
    let paper = (2.0 * (9e-18 + 1e-18) + 16e-18 + 4e-18 + 1e-18f64).sqrt();
    assert!((b.combined_u - gum).abs() < 1e-22);
    assert!((b.combined_u_paper_eq10.unwrap() - paper).abs() < 1e-22);
}
