-- incal records store, migration 0001: instruments, records, their input
-- files, supersessions.
--
-- Portable SQL: the same statements run on SQLite and PostgreSQL (BIGINT
-- ids assigned by incal, TEXT everywhere else, no AUTOINCREMENT, SERIAL,
-- STRICT or WITHOUT ROWID). Times are RFC 3339 UTC text
-- (YYYY-MM-DDTHH:MM:SSZ), hashes lower-case hex SHA-256.
--
-- Append-only: incal never updates or deletes a row. A correction is a new
-- record plus a supersessions row, written in one transaction.

CREATE TABLE instruments (
    id BIGINT PRIMARY KEY,
    serial TEXT NOT NULL UNIQUE,
    -- model as first recorded (from the result's instrument.model)
    model TEXT
);

CREATE TABLE records (
    -- 1, 2, 3, ... in the order written: the order of the hash chain
    id BIGINT PRIMARY KEY,
    instrument_id BIGINT NOT NULL REFERENCES instruments (id),
    procedure TEXT NOT NULL,
    created_utc TEXT NOT NULL,
    operator TEXT,
    station TEXT,
    -- the result document (incal.result/1) text exactly as given
    document TEXT NOT NULL,
    -- SHA-256 of the UTF-8 bytes of document
    document_sha256 TEXT NOT NULL,
    -- record_hash of the record before (id - 1); 64 zeros for the first
    prev_hash TEXT NOT NULL,
    -- SHA-256 of the canonical form (README, "Calibration records")
    record_hash TEXT NOT NULL UNIQUE
);

CREATE INDEX records_instrument ON records (instrument_id);

-- The input files of each record, from the document's "inputs", in order.
CREATE TABLE record_inputs (
    record_id BIGINT NOT NULL REFERENCES records (id),
    position BIGINT NOT NULL,
    role TEXT NOT NULL,
    path TEXT NOT NULL,
    sha256 TEXT NOT NULL,
    PRIMARY KEY (record_id, position)
);

CREATE INDEX record_inputs_sha256 ON record_inputs (sha256);

-- A correction: new_id supersedes old_id. A record is superseded at most
-- once (supersede the newest record of a correction chain).
CREATE TABLE supersessions (
    old_id BIGINT NOT NULL UNIQUE REFERENCES records (id),
    new_id BIGINT NOT NULL UNIQUE REFERENCES records (id),
    reason TEXT NOT NULL,
    created_utc TEXT NOT NULL,
    PRIMARY KEY (old_id, new_id)
);
