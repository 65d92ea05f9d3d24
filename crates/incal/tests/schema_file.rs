//! The checked-in JSON Schema `schema/result.schema.json` is the schema of
//! the result type: this test fails when the file is stale. Regenerate it
//! with `INCAL_UPDATE_SCHEMA=1 cargo test -p incal --test schema_file`.

use std::path::PathBuf;

#[test]
fn schema_file_is_current() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../schema/result.schema.json");
    let want = format!(
        "{}\n",
        serde_json::to_string_pretty(&incal::document::json_schema()).unwrap()
    );
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
