//! Helpers shared by the records tests: small result documents, a seeded
//! random generator, fresh store paths.

#![allow(dead_code)]

use std::path::PathBuf;

use incal::document::{Coefficient, DocumentBuilder, InputFile, Procedure};
use incal::units::Unit;

/// A fresh, empty directory for one test (named after the calling test
/// module too: every module of the one test binary has its own).
#[track_caller]
pub fn temp_dir(name: &str) -> PathBuf {
    let module = std::path::Path::new(std::panic::Location::caller().file())
        .file_stem()
        .map_or_else(|| "test".into(), |s| s.to_string_lossy().to_string());
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "incal-records-{}-{module}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A tumble result of `serial` (none when `None`) with K0 = `k0` ± `u`
/// (g, `dof` degrees of freedom), K1 = 10 and one input file.
pub fn tumble_doc(serial: Option<&str>, k0: f64, u: f64, dof: f64) -> String {
    let mut b = DocumentBuilder::new(Procedure::Tumble, "Tumble calibration (test)");
    b.coefficient("K0", Coefficient::new("K0", k0, u, Unit::G, dof).unwrap())
        .unwrap();
    b.coefficient(
        "K1",
        Coefficient::new("K1", 10.0, 1e-6, Unit::OutputPerG, dof).unwrap(),
    )
    .unwrap();
    let mut doc = b.finish();
    doc.instrument.serial = serial.map(str::to_string);
    doc.inputs.push(InputFile {
        role: "input".into(),
        path: "t.csv".into(),
        sha256: format!("{:064x}", (k0.to_bits() ^ u.to_bits()) as u128),
        rows: Some(12),
    });
    doc.to_json()
}

/// SplitMix64: a small seeded generator, enough for test data.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

#[path = "pg.rs"]
mod pg;
#[allow(unused_imports)]
pub use pg::{outsider, pg_database, pg_server};
