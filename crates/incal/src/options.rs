//! Options of reductions, plans and simulators: one way to type, read,
//! check and name them.
//!
//! Every options type derives `Serialize`, `Deserialize` and `JsonSchema`
//! with snake_case keys carrying their unit (`latitude_deg`, `rate_hz`):
//! the keys are those of the document's `options`, of the JSON Schema the
//! registry publishes, of Python's keyword arguments and (kebab-cased) of
//! the command line. Values are in engineering units as the user gives them;
//! a procedure converts to radians in one place (its options' accessor,
//! e.g. `latitude_rad()`), never in a twin type.
//!
//! A bad option is [`Error::InvalidOption`] naming the key: each front end
//! spells the key its own way from its own table (the CLI from its argument
//! definitions, Python from the keyword name). A message that names another
//! option puts its key in backticks (`` `u_k1` ``) for the front end to
//! spell the same way.

use schemars::JsonSchema;
use serde::de::DeserializeOwned;

use crate::error::{Error, Result};
use crate::estimation::Noise;

/// `Err(InvalidOption)` for `key` with a message for people.
pub fn invalid<T>(key: &str, message: impl Into<String>) -> Result<T> {
    Err(Error::InvalidOption {
        key: key.into(),
        message: message.into(),
    })
}

/// Every non-integral number of `options` (a procedure's options as JSON)
/// within 1e15 in magnitude, the bound the CSV reader puts on a recording:
/// an option is echoed into the result document, and a number beyond it
/// (`k1 = 1e300`, an angle of 1e300) is nothing a rig sets and would make
/// the result unusable downstream. Else [`Error::InvalidOption`] naming
/// the key (`key`, `runs[2].rate_deg_s`).
pub fn check_magnitudes(options: &serde_json::Value) -> Result<()> {
    check_magnitudes_at(options, "")
}

/// [`check_magnitudes`] of the value at key `path` (`""`: the top).
pub fn check_magnitudes_at(v: &serde_json::Value, path: &str) -> Result<()> {
    match v {
        serde_json::Value::Number(n) if !(n.is_i64() || n.is_u64()) => {
            let x = n.as_f64().unwrap_or(f64::NAN);
            if x.abs() > incal_io::MAX_ABS_VALUE {
                return invalid(
                    path,
                    format!(
                        "{} is beyond 1e15 in magnitude",
                        crate::error::short_number(&x.to_string())
                    ),
                );
            }
            Ok(())
        }
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .try_for_each(|(i, x)| check_magnitudes_at(x, &format!("{path}[{i}]"))),
        serde_json::Value::Object(m) => m.iter().try_for_each(|(k, x)| {
            let at = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            check_magnitudes_at(x, &at)
        }),
        _ => Ok(()),
    }
}

/// A finite number within `lo..=hi`, or [`Error::InvalidOption`] naming
/// `key`, the range and the value (`unit` is appended to the bounds).
pub fn check_range(key: &str, value: f64, lo: f64, hi: f64, unit: &str) -> Result<()> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        invalid(
            key,
            format!(
                "must be within {}..{}{unit}, got {}",
                crate::error::short_number(&lo.to_string()),
                crate::error::short_number(&hi.to_string()),
                crate::error::short_number(&value.to_string())
            ),
        )
    }
}

/// A finite number above zero, or [`Error::InvalidOption`] naming `key`.
pub fn check_positive(key: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        invalid(
            key,
            format!(
                "must be a positive number, got {}",
                crate::error::short_number(&value.to_string())
            ),
        )
    }
}

/// The one latitude check: φ in degrees, finite and within ±90°, for every
/// option spelled `latitude_deg`.
pub fn check_latitude_deg(latitude_deg: f64) -> Result<()> {
    check_range("latitude_deg", latitude_deg, -90.0, 90.0, "deg")
}

/// Options from a JSON value (a Python keyword dict, a fuzz input, a
/// stored plan): unknown keys (against the type's JSON Schema, so that a
/// flattened group of options is checked too), missing keys and values of
/// the wrong type are [`Error::InvalidOption`] naming the key path
/// (`runs[2].rate_deg_s`).
pub fn from_json<T: DeserializeOwned + JsonSchema>(value: &serde_json::Value) -> Result<T> {
    if let serde_json::Value::Object(given) = value {
        let known = known_keys(&schema_of::<T>());
        if !known.is_empty() {
            if let Some(k) = given.keys().find(|k| !known.contains(k.as_str())) {
                let list: Vec<&str> = known.iter().map(String::as_str).collect();
                return invalid(k, format!("unknown option (known: {})", list.join(", ")));
            }
        }
    }
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // serde names the culprit of unknown/missing fields itself.
        let field = |pat: &str| {
            inner
                .split_once(pat)
                .and_then(|(_, rest)| rest.split('`').next())
                .map(str::to_string)
        };
        let key = if path == "." || path.is_empty() {
            field("unknown field `")
                .or_else(|| field("missing field `"))
                .unwrap_or_else(|| "options".into())
        } else {
            path
        };
        Error::InvalidOption {
            key,
            message: inner,
        }
    })
}

/// The top-level keys a schema allows: its `properties`, and those of the
/// schemas it combines (`allOf`, `anyOf`, `oneOf`, `$ref` into `$defs`).
fn known_keys(schema: &serde_json::Value) -> std::collections::BTreeSet<String> {
    fn walk(
        s: &serde_json::Value,
        root: &serde_json::Value,
        depth: usize,
        out: &mut std::collections::BTreeSet<String>,
    ) {
        if depth > 8 {
            return;
        }
        if let Some(p) = s.get("properties").and_then(|p| p.as_object()) {
            out.extend(p.keys().cloned());
        }
        for k in ["allOf", "anyOf", "oneOf"] {
            for sub in s.get(k).and_then(|v| v.as_array()).into_iter().flatten() {
                walk(sub, root, depth + 1, out);
            }
        }
        if let Some(r) = s.get("$ref").and_then(|r| r.as_str()) {
            if let Some(name) = r.strip_prefix("#/$defs/") {
                if let Some(d) = root.get("$defs").and_then(|d| d.get(name)) {
                    walk(d, root, depth + 1, out);
                }
            }
        }
    }
    let mut out = std::collections::BTreeSet::new();
    walk(schema, schema, 0, &mut out);
    out
}

/// The JSON Schema of an options type (draft 2020-12, as schemars writes).
pub fn schema_of<T: JsonSchema>() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(T)).unwrap_or(serde_json::Value::Null)
}

// `Noise` at the edges is the known σ of one sample, or null for "from the
// data": `{"noise": 0.001}` / `{"noise": null}`.
impl serde::Serialize for Noise {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.sigma().serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for Noise {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let sigma = Option::<f64>::deserialize(d)?;
        Ok(match sigma {
            None => Noise::Auto,
            Some(sigma) => Noise::Known { sigma },
        })
    }
}

impl JsonSchema for Noise {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Noise".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "Standard deviation of one output sample (output units), known beforehand; null: from the data.",
            "type": ["number", "null"],
            "exclusiveMinimum": 0.0
        })
    }
}

/// Serde and JSON Schema of an enum spelled by a fixed set of names at the
/// edges, from its `name(self) -> &'static str`, its
/// `parse(&str) -> Result<Self>` and every value (anything iterable):
/// `named_enum!(Mount, [Mount::Pendulum, Mount::Gate]);`,
/// `named_enum!(Term, Term::ALL);`.
#[macro_export]
macro_rules! named_enum {
    ($t:ty, $all:expr) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }

        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                let s = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(d)?;
                <$t>::parse(&s).map_err(|e| serde::de::Error::custom(e.to_string()))
            }
        }

        impl schemars::JsonSchema for $t {
            fn schema_name() -> std::borrow::Cow<'static, str> {
                stringify!($t).into()
            }

            fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
                let names: Vec<&'static str> = $all.into_iter().map(<$t>::name).collect();
                schemars::json_schema!({"type": "string", "enum": names})
            }
        }
    };
}

/// The key an option error names, for tests: panics, showing what came
/// instead, when `r` is not [`Error::InvalidOption`].
#[cfg(test)]
pub(crate) fn refused_key<T: std::fmt::Debug>(r: Result<T>) -> String {
    match r {
        Err(Error::InvalidOption { key, .. }) => key,
        other => panic!("expected InvalidOption, got {other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    struct Demo {
        #[allow(dead_code)]
        rate_hz: f64,
        #[allow(dead_code)]
        noise: Noise,
    }

    fn key_of(v: serde_json::Value) -> String {
        refused_key(from_json::<Demo>(&v))
    }

    #[test]
    fn a_bad_json_option_names_its_key() {
        assert_eq!(
            key_of(serde_json::json!({"rate_hz": "x", "noise": null})),
            "rate_hz"
        );
        assert_eq!(key_of(serde_json::json!({"noise": null})), "rate_hz");
        assert_eq!(
            key_of(serde_json::json!({"rate_hz": 1.0, "noise": null, "rate_hx": 2})),
            "rate_hx"
        );
        #[derive(Debug, serde::Deserialize, JsonSchema)]
        struct Outer {
            #[serde(flatten)]
            #[allow(dead_code)]
            inner: Demo,
            #[allow(dead_code)]
            samples: usize,
        }
        let flat = serde_json::json!({"rate_hz": 1.0, "noise": null, "samples": 2, "sample": 3});
        match from_json::<Outer>(&flat) {
            Err(Error::InvalidOption { key, message }) => {
                assert_eq!(key, "sample");
                assert!(message.contains("rate_hz"), "{message}");
            }
            other => panic!("a flattened unknown key passed: {other:?}"),
        }
        let ok: Demo = from_json(&serde_json::json!({"rate_hz": 1.0, "noise": 0.5})).unwrap();
        assert_eq!(ok.noise, Noise::Known { sigma: 0.5 });
    }

    #[test]
    fn ranges_name_the_key_and_the_value() {
        let e = check_latitude_deg(91.0).unwrap_err().to_string();
        assert_eq!(e, "latitude_deg: must be within -90..90 deg, got 91");
        assert!(check_latitude_deg(f64::NAN).is_err());
        assert!(check_positive("rate_hz", 0.0).is_err());
        let s = schema_of::<Demo>();
        assert!(s["properties"]["noise"].is_object(), "{s}");
    }
}
