//! The typed entry points of the registry (`Entry::reduction`: options as
//! JSON, keyed as the documents' `options`) give the same document as the
//! command line: the contract every non-CLI front end (Python, fuzzing)
//! relies on. The JSON options are the registry example's command-line
//! options, each flag turned into its key by the CLI's own argument table.

use incal::procedures::registry::REGISTRY;
use serde_json::{json, Map, Value};

use crate::common::{json_of, ok, p, registry_cases, run, unique};

/// `--flag value …` of `command` as JSON options keyed by argument id.
fn options_json(command: &[&str], args: &[&str]) -> Value {
    let mut c = incal_cli::command();
    for w in command {
        c = c
            .find_subcommand(w)
            .unwrap_or_else(|| panic!("no subcommand {w}"))
            .clone();
    }
    let mut out = Map::new();
    let mut it = args.iter().peekable();
    while let Some(flag) = it.next() {
        let long = flag.trim_start_matches("--");
        let arg = c
            .get_arguments()
            .find(|a| {
                a.get_long() == Some(long) || a.get_all_aliases().is_some_and(|v| v.contains(&long))
            })
            .unwrap_or_else(|| panic!("{}: no option {flag}", command.join(" ")));
        let key = arg.get_id().to_string();
        if !arg.get_action().takes_values() {
            out.insert(key, json!(true));
            continue;
        }
        let text = it.next().expect("a value");
        let scalar = |t: &str| {
            t.parse::<f64>()
                .ok()
                .and_then(|x| serde_json::Number::from_f64(x).map(Value::Number))
                .map(|v| match t.parse::<i64>() {
                    Ok(i) => json!(i),
                    Err(_) => v,
                })
                .unwrap_or_else(|| json!(t))
        };
        let value = if arg.get_value_delimiter().is_some() {
            Value::Array(text.split(',').map(scalar).collect())
        } else {
            scalar(text)
        };
        out.insert(key, value);
    }
    Value::Object(out)
}

#[test]
fn every_typed_reduction_equals_the_command_line() {
    let mut checked = 0;
    for case in registry_cases() {
        let entry = REGISTRY.iter().find(|e| e.id == case.id).unwrap();
        let Some(typed) = entry.reduction else {
            continue;
        };
        let file = unique(&format!("{}.csv", case.id));
        let mut sim = case.simulate.clone();
        sim.extend_from_slice(&["-o", p(&file)]);
        let mut words = vec!["simulate"];
        words.extend(sim);
        ok(&run(&words));
        let mut cli = case.reduce(p(&file));
        cli.push("--json");
        let a = json_of(&run(&cli));
        let options = options_json(case.command, case.options);
        let mut src = std::fs::File::open(&file).unwrap();
        let doc = (typed.run)(
            p(&file),
            &mut src,
            &incal_io::ReadOptions::default(),
            &options,
            &incal::procedures::Silent,
            None,
        )
        .unwrap_or_else(|e| panic!("{}: typed reduction with {options}: {e}", case.id));
        // Through text, as the CLI's document was read (same float parsing).
        let b: Value = serde_json::from_str(&doc.to_json()).unwrap();
        for key in ["procedure", "coefficients", "options", "warnings", "inputs"] {
            assert_eq!(
                a[key], b[key],
                "{}: {key} differs (options {options})",
                case.id
            );
        }
        // A misspelt key is refused naming it.
        let mut bad = options.as_object().cloned().unwrap_or_default();
        bad.insert("no_such_option_hz".into(), json!(1));
        let mut src = std::fs::File::open(&file).unwrap();
        match (typed.run)(
            p(&file),
            &mut src,
            &incal_io::ReadOptions::default(),
            &Value::Object(bad),
            &incal::procedures::Silent,
            None,
        ) {
            Err(incal::Error::InvalidOption { key, .. }) => {
                assert_eq!(key, "no_such_option_hz", "{}", case.id)
            }
            other => panic!("{}: a misspelt option gave {other:?}", case.id),
        }
        checked += 1;
    }
    assert!(checked >= 3, "only {checked} typed reductions");
}

#[test]
fn every_typed_plan_and_simulator_publishes_an_object_schema() {
    for e in REGISTRY {
        for (what, schema) in [
            ("reduction", e.reduction.map(|t| (t.schema)())),
            ("plan", e.planner.map(|t| (t.schema)())),
            ("simulator", e.simulator.map(|t| (t.schema)())),
        ] {
            if let Some(s) = schema {
                assert!(
                    s["properties"].as_object().is_some_and(|p| !p.is_empty()),
                    "{} {what}: schema without properties: {s}",
                    e.id
                );
            }
        }
        if let Some(t) = e.planner {
            match (t.run)(&json!({"no_such_option_hz": 1})) {
                Err(incal::Error::InvalidOption { key, .. }) => {
                    assert_eq!(key, "no_such_option_hz", "{} plan", e.id)
                }
                other => panic!("{} plan: a misspelt option gave {other:?}", e.id),
            }
        }
    }
}

#[test]
fn every_typed_simulator_writes_the_bytes_of_the_command_line() {
    let mut checked = 0;
    for e in REGISTRY {
        let (Some(typed), Some(words), Some(example)) = (e.simulator, e.simulate, e.example) else {
            continue;
        };
        let file = unique(&format!("{}-sim.csv", e.id));
        let mut cli = words.to_vec();
        cli.extend_from_slice(example.simulate);
        cli.extend_from_slice(&["-o", p(&file)]);
        ok(&run(&cli));
        let options = options_json(words, example.simulate);
        let mut bytes = Vec::new();
        (typed.run)(&options, &mut bytes)
            .unwrap_or_else(|err| panic!("{}: typed simulator with {options}: {err}", e.id));
        assert!(
            bytes == std::fs::read(&file).unwrap(),
            "{}: the typed simulator wrote other bytes than the command line",
            e.id
        );
        checked += 1;
    }
    assert!(checked >= 1, "no typed simulator");
}

#[test]
fn every_procedure_has_its_typed_reduction_plan_and_simulator() {
    use incal::procedures::registry::InputKind;
    let mut gaps = Vec::new();
    for e in REGISTRY {
        if e.input == InputKind::Recording && e.reduction.is_none() {
            gaps.push(format!("procedure {}: no typed reduction", e.id));
        }
        if e.plan.is_some() && e.planner.is_none() {
            gaps.push(format!(
                "procedure {}: a plan command but no typed plan",
                e.id
            ));
        }
        if e.simulate.is_some() && e.simulator.is_none() {
            gaps.push(format!(
                "procedure {}: a simulate command but no typed simulator",
                e.id
            ));
        }
    }
    assert!(gaps.is_empty(), "{}", gaps.join("\n"));
}
