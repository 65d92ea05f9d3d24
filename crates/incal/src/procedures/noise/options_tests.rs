//! The noise analysis' options from JSON and as documents record them.

use super::*;
use crate::options::from_json;

fn key_of(r: Result<impl std::fmt::Debug>) -> String {
    crate::options::refused_key(r)
}

#[test]
fn options_round_trip_and_name_a_bad_key() {
    let o: NoiseOptions = from_json(&serde_json::json!({})).unwrap();
    assert_eq!(o, NoiseOptions::default());
    let given = serde_json::json!({
        "rate_hz": 100.0, "quantity": "gyro", "unit": "deg/h", "data": "angle",
        "taus": "decade", "deviations": "oadev,theo1", "confidence": 0.95,
        "stability_tau_s": [1.0], "sort_time": true, "three_cornered_hat": true
    });
    let o: NoiseOptions = from_json(&given).unwrap();
    let shown = serde_json::to_value(&o).unwrap();
    assert_eq!(shown, given);
    assert_eq!(from_json::<NoiseOptions>(&shown).unwrap(), o);
    // The document records the unit in use and leaves out the defaults.
    let recorded = serde_json::to_value(NoiseOptions::default().settled(Some(10.0))).unwrap();
    assert_eq!(
        recorded,
        serde_json::json!({"rate_hz": 10.0, "quantity": "generic", "unit": "1",
            "data": "rate", "taus": "octave", "stability_tau_s": [10.0, 100.0],
            "confidence": 0.683})
    );
    let bad = |v: serde_json::Value| {
        key_of(from_json::<NoiseOptions>(&v).and_then(|o| Noise::validate(&o)))
    };
    assert_eq!(bad(serde_json::json!({"rate_hz": 0.0})), "rate_hz");
    assert_eq!(bad(serde_json::json!({"confidence": 1.5})), "confidence");
    assert_eq!(bad(serde_json::json!({"taus": "weekly"})), "taus");
    assert_eq!(
        bad(serde_json::json!({"deviations": "allan"})),
        "deviations"
    );
    assert_eq!(
        bad(serde_json::json!({"quantity": "gyro", "unit": "furlong/s"})),
        "unit"
    );
    assert_eq!(bad(serde_json::json!({"format": "f64le"})), "channels");
    assert_eq!(bad(serde_json::json!({"rate": 1.0})), "rate");
}
