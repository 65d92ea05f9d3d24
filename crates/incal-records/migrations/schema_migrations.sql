-- The table that tracks which migrations a store has had. Created (if
-- missing) before the migrations are applied; portable SQL, as they are.
CREATE TABLE IF NOT EXISTS schema_migrations (
    version BIGINT PRIMARY KEY,
    name TEXT NOT NULL,
    applied_utc TEXT NOT NULL
);
