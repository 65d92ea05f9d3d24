//! `--monte-carlo` on the command line: the document's section and its
//! warnings, the same bytes for the same seed, the text report, and the
//! refusals (exit 2, one line naming the option).

use crate::common;
use common::*;

/// A tumble recording whose K0 is a ratio with a poor denominator (K1
/// known to about 15 %): the GUM interval of K0 is not validated.
fn noisy_tumble(name: &str) -> std::path::PathBuf {
    let o = run(&[
        "simulate",
        "tumble",
        "--k1",
        "1",
        "--k0",
        "5",
        "--k2",
        "0",
        "--k3",
        "0",
        "--delta-o-arcsec",
        "0",
        "--k-ip",
        "0",
        "--noise",
        "0.8",
        "--samples",
        "4",
        "--index-error-arcsec",
        "0",
        "--seed",
        "3",
    ]);
    write_unique(name, &ok(&o))
}

#[test]
fn the_section_validates_or_not_and_repeats_with_its_seed() {
    let f = noisy_tumble("mc.csv");
    let args = [
        "tumble",
        "--mount",
        "pendulum",
        "--terms",
        "K0,K1",
        "--input",
        p(&f),
        "--json",
        "--monte-carlo",
        "1000",
        "--seed",
        "4",
    ];
    let a = run(&args);
    let doc = json_of(&a);
    let mc = &doc["monte_carlo"];
    // A trial whose K1 the reduction finds not observable is counted as
    // failed, with its reason; the rest are the statistics' trials.
    let failed = mc["failed"]["count"].as_u64().unwrap();
    assert_eq!(mc["trials"].as_u64().unwrap() + failed, 1000);
    assert!(failed < 10, "{}", mc["failed"]);
    assert_eq!(mc["requested"], 1000);
    assert_eq!(mc["seed"], 4);
    let k0 = &mc["coefficients"]["K0"];
    assert_eq!(k0["validated"], false, "{k0}");
    for key in ["mean", "std", "d_low", "d_high", "delta"] {
        assert!(k0[key].is_f64(), "{key}: {k0}");
    }
    assert!(k0["symmetric"][0].as_f64() < k0["symmetric"][1].as_f64());
    assert_eq!(mc["correlation"]["names"], serde_json::json!(["K0", "K1"]));
    assert!(!warnings_with(&doc, "gum-not-validated").is_empty());
    assert!(mc["drawn"][0]["input"].as_str().unwrap().contains("noise"));
    // Same seed, same document; another seed, other numbers.
    assert_eq!(ok(&run(&args)), ok(&a));
    let mut other = args.to_vec();
    let last = other.len() - 1;
    other[last] = "5";
    let b = json_of(&run(&other));
    assert_ne!(b["monte_carlo"]["coefficients"]["K0"]["mean"], k0["mean"]);
    // The text report shows the section.
    let text = ok(&run(&args[..args.len() - 5]
        .iter()
        .chain(&["--monte-carlo", "200"])
        .copied()
        .collect::<Vec<_>>()));
    assert!(text.contains("Monte Carlo (JCGM 101"), "{text}");
    assert!(
        text.contains("not validated: use the Monte Carlo interval"),
        "{text}"
    );
}

#[test]
fn refusals_name_the_option() {
    let f = noisy_tumble("mc-bad.csv");
    let base = [
        "tumble",
        "--mount",
        "pendulum",
        "--terms",
        "K0,K1",
        "--input",
        p(&f),
    ];
    let with = |extra: &[&str]| {
        let mut v = base.to_vec();
        v.extend_from_slice(extra);
        run(&v)
    };
    refused(
        &with(&["--monte-carlo", "10"]),
        &["--monte-carlo", "100 to 1000000"],
    );
    refused(
        &with(&["--monte-carlo", "many"]),
        &["--monte-carlo", "'many'"],
    );
    refused(&with(&["--seed", "3"]), &["--monte-carlo"]);
    refused(
        &with(&["--monte-carlo", "200", "--mc-digits", "5"]),
        &["--mc-digits"],
    );
    // The soak fit over result documents draws nothing: refused, not
    // ignored.
    refused(
        &run(&["thermal", "fit", p(&f), "--monte-carlo", "200"]),
        &["--monte-carlo", "thermal fit", "result documents"],
    );
}

/// The rate-transfer test draws the table's rate error once per trial:
/// its K1's Monte Carlo u is the GUM u (the ppm dominates), validated.
#[test]
fn gyro_rate_draws_the_table_rate_error() {
    let sim = ok(&run(&[
        "simulate",
        "gyro-rate",
        "--samples",
        "4",
        "--seed",
        "16",
    ]));
    let g = write_unique("mc-gyro.csv", &sim);
    let doc = json_of(&run(&[
        "gyro",
        "rate",
        "--input",
        p(&g),
        "--latitude-deg",
        "45",
        "--rate-uncertainty-ppm",
        "20",
        "--json",
        "--monte-carlo",
        "auto",
    ]));
    let mc = &doc["monte_carlo"];
    assert_eq!(mc["stabilised"], true, "{mc}");
    assert!(mc["drawn"]
        .as_array()
        .unwrap()
        .iter()
        .any(|d| d["source"] == "rate_uncertainty_ppm"));
    for (name, c) in mc["coefficients"].as_object().unwrap() {
        assert_eq!(c["validated"], true, "{name}: {c}");
        let u = doc["coefficients"][name]["u"].as_f64().unwrap();
        let s = c["std"].as_f64().unwrap();
        assert!((s / u - 1.0).abs() < 0.05, "{name}: {s} vs {u}");
    }
}

/// The accelerometer misalignment: with γ far above its u every GUM
/// interval is validated; with γ below its u (a weakly excited unit) the
/// GUM's symmetric interval of γ, which reaches below zero, is not.
#[test]
fn misalignment_gamma_is_validated_only_when_well_excited() {
    let mc = |extra: &[&str], name: &str| {
        let mut sim = vec!["simulate", "misalign", "accel", "--seed", "2"];
        sim.extend_from_slice(extra);
        let f = write_unique(name, &ok(&run(&sim)));
        let args = [
            "misalign",
            "accel",
            "--input",
            p(&f),
            "--scale-factor",
            "1.299",
            "--json",
            "--monte-carlo",
            "2000",
            "--seed",
            "7",
        ];
        json_of(&run(&args))
    };
    let strong = mc(&[], "mis-strong.csv");
    let m = &strong["monte_carlo"];
    assert_eq!(m["failed"]["count"], 0, "{m}");
    for (name, c) in m["coefficients"].as_object().unwrap() {
        if name != "azimuth" {
            assert_eq!(c["validated"], true, "{name}: {c}");
        }
    }
    // MC std of a linear angle within 10 % of its u (M = 2000: ±3 %).
    let dz = &m["coefficients"]["dtheta_z2"];
    let u = strong["coefficients"]["dtheta_z2"]["u"].as_f64().unwrap();
    let ratio = dz["std"].as_f64().unwrap() / u;
    assert!((ratio - 1.0).abs() < 0.1, "{ratio}");
    let weak = mc(
        &[
            "--dtheta-y2-arcsec",
            "1",
            "--dtheta-z2-arcsec",
            "1",
            "--noise",
            "1e-4",
            "--samples",
            "4",
        ],
        "mis-weak.csv",
    );
    let g = &weak["monte_carlo"]["coefficients"]["gamma"];
    assert_eq!(g["validated"], false, "{g}");
    assert!(!warnings_with(&weak, "gum-not-validated").is_empty());
    // The angles stay linear: their Monte Carlo std is their u with the t
    // of the noise's 12 dof (×1.10), while γ's GUM interval reaches below
    // zero and its Monte Carlo mean lies well above the estimate.
    let dy = &weak["monte_carlo"]["coefficients"]["dtheta_y2"];
    let u = weak["coefficients"]["dtheta_y2"]["u"].as_f64().unwrap();
    let ratio = dy["std"].as_f64().unwrap() / u;
    assert!((1.0..1.2).contains(&ratio), "{ratio}");
    assert!(g["gum"][0].as_f64().unwrap() < 0.0, "{g}");
    let est = weak["coefficients"]["gamma"]["value"].as_f64().unwrap();
    assert!(g["mean"].as_f64().unwrap() > 1.5 * est, "{g} {est}");
}

/// The multi-position test draws the gyro's K1 once per trial from
/// `--u-k1` (the reduction divides by the stated K1): the Monte Carlo u of
/// a drift term agrees with the GUM's, which holds the same share, and a
/// K1 known to 2 % widens the bias' interval accordingly.
#[test]
fn gyro_positions_draw_the_scale_factor_once_per_trial() {
    let f = write_unique(
        "mc-pos.csv",
        &ok(&run(&[
            "simulate",
            "gyro-positions",
            "--latitude-deg",
            "45",
            "--azimuths-deg",
            "90",
            "--b-deg-h",
            "20",
            "--seed",
            "7",
        ])),
    );
    let mc = |u: &str| {
        json_of(&run(&[
            "gyro",
            "positions",
            "--input",
            p(&f),
            "--latitude-deg",
            "45",
            "--azimuth-deg",
            "90",
            "--axial",
            "sa",
            "--k1",
            "0.02",
            "--u-k1",
            u,
            "--json",
            "--monte-carlo",
            "4000",
            "--seed",
            "3",
        ]))
    };
    let (tight, loose) = (mc("1e-6"), mc("4e-4"));
    for (u, doc) in [("1e-6", &tight), ("4e-4", &loose)] {
        let m = &doc["monte_carlo"];
        assert_eq!(m["failed"]["count"], 0, "{m}");
        let drawn = m["drawn"].to_string();
        assert!(drawn.contains("scale factor K1"), "{drawn}");
        for (name, c) in m["coefficients"].as_object().unwrap() {
            let gum = doc["coefficients"][name]["u"].as_f64().unwrap();
            let ratio = c["std"].as_f64().unwrap() / gum;
            // M = 4000: the std's own sampling error is about 1.1 %.
            assert!((ratio - 1.0).abs() < 0.06, "u_k1 {u}, {name}: {ratio}");
        }
    }
    let width = |d: &serde_json::Value| {
        let s = &d["monte_carlo"]["coefficients"]["B"]["symmetric"];
        s[1].as_f64().unwrap() - s[0].as_f64().unwrap()
    };
    assert!(
        width(&loose) > 1.2 * width(&tight),
        "{} {}",
        width(&loose),
        width(&tight)
    );
}

/// The gyro misalignment test on a rate table, a bias per configuration:
/// the five angles are linear in the outputs, so their Monte Carlo std is
/// their u (with the t of the noise's dof) and every bias is drawn.
#[test]
fn gyro_misalignment_angles_propagate_linearly() {
    let f = write_unique(
        "mc-mis-gyro.csv",
        &ok(&run(&[
            "simulate",
            "misalign",
            "gyro",
            "--seed",
            "3",
            "--bias-shift",
            "2e-3",
        ])),
    );
    let doc = json_of(&run(&[
        "misalign",
        "gyro",
        "--input",
        p(&f),
        "--scale-factor",
        "-2.9222",
        "--per-config-bias",
        "--json",
        "--monte-carlo",
        "2000",
        "--seed",
        "5",
    ]));
    let m = &doc["monte_carlo"];
    assert_eq!(m["failed"]["count"], 0, "{m}");
    for name in [
        "dtheta_y0",
        "dtheta_x0",
        "dtheta_y1",
        "dtheta_y2",
        "dtheta_z2",
    ] {
        let c = &m["coefficients"][name];
        let u = doc["coefficients"][name]["u"].as_f64().unwrap();
        let ratio = c["std"].as_f64().unwrap() / u;
        assert!((0.95..1.25).contains(&ratio), "{name}: {ratio}");
    }
    let biases = m["coefficients"]
        .as_object()
        .unwrap()
        .keys()
        .filter(|k| k.starts_with("bias("))
        .count();
    assert_eq!(biases, 5, "{}", m["coefficients"]);
}

/// The centrifuge: the radii and coefficients come through the nonlinear
/// radius regression and ECM geometry. The Monte Carlo u of each agrees
/// with the GUM u, the type-B inputs (K0, K1, the fixture angle) are
/// drawn, and the trials' mean of K_ip moves from the estimate by the
/// reduction's own bias: what a noise-free recording of the same rig
/// gives (the second-order ECM alignment error the GUM budget holds as a
/// rectangular Δc2), 0.5 u at this noise.
#[test]
fn centrifuge_radii_and_coefficients_propagate() {
    let sim = |noise: &str| {
        ok(&run(&[
            "simulate",
            "centrifuge",
            "--seed",
            "5",
            "--noise",
            noise,
        ]))
    };
    let reduce = |f: &std::path::Path, extra: &[&str]| {
        let mut a = vec![
            "centrifuge",
            "--input",
            p(f),
            "--k0",
            "1.2e-4",
            "--k1",
            "1.3",
            "--radius-m",
            "0.71",
            "--latitude-deg",
            "39.9",
            "--json",
        ];
        a.extend_from_slice(extra);
        json_of(&run(&a))
    };
    let clean = reduce(
        &write_unique("mc-centrifuge0.csv", &sim("0")),
        &["--noise", "1e-9"],
    );
    let bias = clean["coefficients"]["K_ip"]["value"].as_f64().unwrap() - 7e-6;
    let f = write_unique("mc-centrifuge.csv", &sim("5e-7"));
    let mc_args = [
        "--u-k0",
        "2e-6",
        "--u-k1",
        "1.3e-4",
        "--alignment-tolerance-deg",
        "0.01",
        "--monte-carlo",
        "1000",
        "--seed",
        "2",
    ];
    let doc = reduce(&f, &mc_args);
    let mc = &doc["monte_carlo"];
    assert_eq!(mc["failed"]["count"], 0, "{}", mc["failed"]);
    let sources: Vec<&str> = mc["drawn"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["source"].as_str().unwrap())
        .collect();
    assert!(sources.iter().any(|s| s.starts_with("u_k0")), "{sources:?}");
    assert!(sources.contains(&"alignment_tolerance_deg"), "{sources:?}");
    // M = 1000: the std of a std is about 2 %, of a mean 3 % of u.
    let at = |name: &str| {
        let c = &doc["coefficients"][name];
        let m = &mc["coefficients"][name];
        let u = c["u"].as_f64().unwrap();
        let s = m["std"].as_f64().unwrap();
        assert!((s / u - 1.0).abs() < 0.15, "{name}: MC {s} vs GUM {u}");
        (
            m["mean"].as_f64().unwrap() - c["value"].as_f64().unwrap(),
            u,
        )
    };
    for name in ["K2", "R_plus_m", "R_minus_m", "tilt_rad"] {
        let (shift, u) = at(name);
        assert!(
            shift.abs() < 0.15 * u,
            "{name}: MC mean off by {shift} (u {u})"
        );
    }
    let (shift, u) = at("K_ip");
    assert!(bias.abs() > 0.4 * u, "bias {bias}, u {u}");
    assert!(
        (shift - bias).abs() < 0.15 * u,
        "K_ip: MC shift {shift}, bias {bias} (u {u})"
    );
}

/// The stepped sine: every dwell goes through its sine fits and the model
/// fit again; the reference's type-B terms are drawn per dwell, and the
/// Monte Carlo u of the gain and the corner agree with the GUM u where
/// the model is close to linear (the corner inside the dwells).
#[test]
fn response_sine_draws_each_dwell_and_the_reference() {
    let sim = ok(&run(&[
        "simulate",
        "response-sine",
        "--dwells-hz",
        "2,5,10,20",
        "--seconds-per-dwell",
        "1",
        "--rate-hz",
        "200",
        "--order",
        "first",
        "--corner-hz",
        "8",
        "--seed",
        "5",
    ]));
    let f = write_unique("mc-sine.csv", &sim);
    let doc = json_of(&run(&[
        "response",
        "sine",
        "--input",
        p(&f),
        "--order",
        "first",
        "--u-reference-pct",
        "0.5",
        "--json",
        "--monte-carlo",
        "400",
    ]));
    let mc = &doc["monte_carlo"];
    assert_eq!(mc["failed"]["count"], 0, "{}", mc["failed"]);
    assert!(mc["drawn"]
        .as_array()
        .unwrap()
        .iter()
        .any(|d| d["source"] == "u_reference_pct, u_reference_phase_deg"));
    assert!(mc["drawn"]
        .as_array()
        .unwrap()
        .iter()
        .any(|d| d["input"].as_str().unwrap().contains("interpolation error")));
    for name in ["k_dc", "fc_hz", "bandwidth_hz", "bandwidth_interp_hz"] {
        let c = &mc["coefficients"][name];
        let u = doc["coefficients"][name]["u"].as_f64().unwrap();
        let s = c["std"].as_f64().unwrap();
        assert!((s / u - 1.0).abs() < 0.25, "{name}: MC {s} vs GUM {u}");
    }
}
