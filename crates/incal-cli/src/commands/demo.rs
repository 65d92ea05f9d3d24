//! `incal demo`: virtual instruments through every rig, calibrated, with
//! estimate, truth and uncertainty side by side. Needs no input and no
//! network; the same seed prints the same numbers.

use incal::estimation::Estimates;
use incal::models::{AccelerometerModel, Term};
use incal::procedures::tumble::plan::TumblePlan;
use incal::procedures::tumble::{calibrate, TumbleOptions};
use incal::rigs::Mount;
use incal::sim::tumble::{simulate, TumbleSim};
use incal::units::arcsec_to_rad;

use crate::error::{core, CliResult};
use crate::output::{display_scale, sig, table};

/// Options of `incal demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Random seed of every simulation.
    #[arg(long, default_value_t = 2015)]
    pub seed: u64,
}

/// Rows `term, estimate, truth, u, (est − truth)/u` for accelerometer terms.
pub fn truth_rows(e: &Estimates, truth: impl Fn(&str) -> f64) -> Vec<Vec<String>> {
    e.names()
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let term = Term::parse(name).ok();
            let (scale, unit) = term.map_or((1.0, ""), display_scale);
            let (v, u, t) = (e.values()[k], e.u_at(k), truth(name));
            vec![
                name.clone(),
                sig(v * scale, 7),
                sig(t * scale, 7),
                sig(u * scale, 3),
                sig((v - t) / u, 2),
                unit.to_string(),
            ]
        })
        .collect()
}

/// Header of [`truth_rows`] tables.
pub const TRUTH_HEADER: [&str; 6] = ["term", "estimate", "truth", "u", "(est-truth)/u", "unit"];

fn tumble_section(seed: u64) -> CliResult<()> {
    let truth = AccelerometerModel {
        delta_p_rad: arcsec_to_rad(-300.0),
        k_io: 5e-7,
        ..AccelerometerModel::seed000()
    };
    println!("== Tumble test on a dividing head (seed 000, GJB 1037A) ==");
    println!("Virtual accelerometer: the seed 000 instrument (K1 = 10 output/g, K0 = 8 mg, ...),");
    println!("10 samples per position, output noise 1e-6, index-angle error 1 arcsec rms.\n");
    let cases = [
        (
            "pendulum mount, GJB 12-point",
            Mount::Pendulum,
            TumblePlan::gjb12(),
        ),
        ("gate mount, GJB 12-point", Mount::Gate, TumblePlan::gjb12()),
        (
            "pendulum mount, small-angle plan for a 0.5 g instrument",
            Mount::Pendulum,
            TumblePlan::for_range(0.5, 1.0).map_err(core)?,
        ),
    ];
    for (k, (title, mount, plan)) in cases.into_iter().enumerate() {
        let obs = simulate(&TumbleSim {
            truth,
            mount,
            angles_deg: plan.angles_deg.clone(),
            samples: 10,
            noise: 1e-6,
            index_error_rad: arcsec_to_rad(1.0),
            passes: 1,
            seed: seed.wrapping_add(k as u64),
        });
        let r = calibrate(&obs, &TumbleOptions::new(mount)).map_err(core)?;
        println!(
            "-- {title}: step {} deg, angles {:?}",
            plan.step_deg, plan.angles_deg
        );
        print!(
            "{}",
            table(
                &TRUTH_HEADER,
                &truth_rows(&r.coefficients, |n| Term::parse(n)
                    .map_or(f64::NAN, |t| truth.get(t)))
            )
        );
        for a in &r.absorbed {
            println!("note: {a}");
        }
        for w in &r.warnings {
            println!("warning: {w}");
        }
        println!();
    }
    Ok(())
}

/// `incal demo`.
pub fn run(a: &Args) -> CliResult<()> {
    println!(
        "incal demo (seed {}): simulate, calibrate, compare with the truth\n",
        a.seed
    );
    tumble_section(a.seed)?;
    crate::commands::gfimu::demo_section(a.seed)?;
    crate::commands::misalign::demo_section(a.seed)?;
    crate::commands::centrifuge::demo_section(a.seed)?;
    Ok(())
}
