//! A throwaway PostgreSQL server for tests (shared by the records and
//! the CLI tests: `#[path]`-included by both).

#![allow(dead_code)]

/// The URL of a PostgreSQL server for this test process: `$INCAL_TEST_PG`
/// when set, else a throwaway server started by
/// `scripts/pg-test-server.sh` (stopped when this process ends). A
/// machine without the server binaries fails the test, naming them:
/// PostgreSQL support is part of the product, never skipped.
pub fn pg_server() -> &'static str {
    static URL: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    URL.get_or_init(|| {
        if let Ok(u) = std::env::var("INCAL_TEST_PG") {
            if !u.is_empty() {
                return u;
            }
        }
        let script = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scripts/pg-test-server.sh"
        );
        let out = std::process::Command::new("bash")
            .arg(script)
            .arg(std::process::id().to_string())
            .output()
            .expect("run scripts/pg-test-server.sh");
        assert!(
            out.status.success(),
            "no PostgreSQL server for the tests: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap().trim().to_string()
    })
}

/// A fresh, empty database on [`pg_server`] for one test: its URL.
pub fn pg_database(name: &str) -> String {
    let server = pg_server();
    let db = format!("t_{}_{}", std::process::id(), name.replace('-', "_"));
    let mut c = postgres::Client::connect(server, postgres::NoTls).unwrap();
    c.batch_execute(&format!("DROP DATABASE IF EXISTS {db}"))
        .unwrap();
    c.batch_execute(&format!("CREATE DATABASE {db}")).unwrap();
    let (base, _) = server.rsplit_once('/').unwrap();
    format!("{base}/{db}")
}

/// Run `sql` on a store as an outsider would (SQLite file or PostgreSQL
/// URL), without the foreign keys.
pub fn outsider(location: &str, sql: &str) {
    if incal_records::is_postgres_url(location) {
        let mut c = postgres::Client::connect(location, postgres::NoTls).unwrap();
        c.batch_execute(&format!("SET session_replication_role = replica; {sql}"))
            .unwrap_or_else(|e| panic!("{sql}: {e:?}"));
    } else {
        let c = rusqlite::Connection::open(location).unwrap();
        c.execute_batch("PRAGMA foreign_keys = OFF").unwrap();
        c.execute_batch(sql)
            .unwrap_or_else(|e| panic!("{sql}: {e}"));
    }
}
