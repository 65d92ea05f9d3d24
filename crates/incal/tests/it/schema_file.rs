//! The checked-in JSON Schemas `schema/result.schema.json` and
//! `schema/plan.schema.json` are the schemas of the result and plan types:
//! this test fails when a file is stale. Regenerate them with
//! `INCAL_UPDATE_SCHEMA=1 cargo test -p incal --test schema_file`.

use std::path::PathBuf;

fn check(file: &str, schema: serde_json::Value) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../schema")
        .join(file);
    let want = format!("{}\n", serde_json::to_string_pretty(&schema).unwrap());
    if std::env::var_os("INCAL_UPDATE_SCHEMA").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "{} is stale: run INCAL_UPDATE_SCHEMA=1 cargo test -p incal --test schema_file",
        path.display()
    );
}

#[test]
fn result_schema_file_is_current() {
    check("result.schema.json", incal::document::json_schema());
}

#[test]
fn plan_schema_file_is_current() {
    check(
        "plan.schema.json",
        incal::document::plan::plan_json_schema(),
    );
}
