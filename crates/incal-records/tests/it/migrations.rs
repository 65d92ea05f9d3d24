//! The migrations in `migrations/`: every numbered file is applied, in
//! order, and the tables use only SQL that PostgreSQL runs as well.

use std::path::Path;

#[test]
fn every_migration_file_is_listed_in_order() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("migrations");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".sql") && n.as_bytes()[0].is_ascii_digit())
        .collect();
    files.sort();
    let listed: Vec<String> = incal_records::MIGRATIONS
        .iter()
        .map(|m| format!("{}.sql", m.1))
        .collect();
    assert_eq!(files, listed);
    for (k, (version, name, sql)) in incal_records::MIGRATIONS.iter().enumerate() {
        assert_eq!(*version, k as i64 + 1);
        assert!(name.starts_with(&format!("{version:04}_")), "{name}");
        let on_disk = std::fs::read_to_string(dir.join(format!("{name}.sql"))).unwrap();
        assert_eq!(*sql, on_disk);
    }
}

#[test]
fn tables_use_portable_sql_only() {
    let mut all = incal_records::SCHEMA_MIGRATIONS.to_string();
    for m in incal_records::MIGRATIONS {
        all.push_str(m.2);
    }
    // Without the comments.
    let code: String = all
        .lines()
        .map(|l| l.split("--").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
        .to_uppercase();
    let tokens: Vec<&str> = code
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|t| !t.is_empty())
        .collect();
    for sqlite_only in [
        "AUTOINCREMENT",
        "ROWID",
        "STRICT",
        "PRAGMA",
        "REPLACE",
        "DATETIME",
        "GLOB",
        "BLOB",
        "REAL",
        "COLLATE",
    ] {
        assert!(
            !tokens.contains(&sqlite_only),
            "{sqlite_only} in the migrations"
        );
    }
    // Column types: BIGINT and TEXT only.
    for line in code.lines().map(str::trim) {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() >= 2
            && !["CREATE", "PRIMARY", ")", ");"].contains(&words[0])
            && words[0]
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            let ty = words[1].trim_end_matches(',');
            assert!(["BIGINT", "TEXT"].contains(&ty), "type {ty} in: {line}");
        }
    }
}
