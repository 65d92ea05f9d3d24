-- incal records store, migration 0002: the lab's workflow and its users.
--
-- Events (a submission, an approval, a rejection, a user added, a role
-- changed, an account disabled, a password set) share the records' hash
-- chain: ids of records and events are one sequence (1, 2, 3, ... in the
-- order written), and each entry's prev_hash is the hash of the entry
-- before, whichever table holds it. Roles and account states live only in
-- the events, so an edit behind incal's back breaks the chain.
--
-- Portable SQL, append-only, as migration 0001.

CREATE TABLE events (
    -- position in the chain, shared with records.id
    id BIGINT PRIMARY KEY,
    -- record.submit, record.approve, record.reject, user.add, user.passwd,
    -- user.role, user.disable, user.enable
    kind TEXT NOT NULL,
    created_utc TEXT NOT NULL,
    -- who did it, and in which role
    actor TEXT NOT NULL,
    actor_role TEXT NOT NULL,
    -- the record it concerns (record.*)
    record_id BIGINT REFERENCES records (id),
    -- the account it concerns (user.*)
    username TEXT,
    -- the role given (user.add, user.role)
    role TEXT,
    -- SHA-256 of the password hash set (user.add, user.passwd)
    secret_sha256 TEXT,
    -- why (required for record.reject)
    reason TEXT,
    prev_hash TEXT NOT NULL,
    event_hash TEXT NOT NULL UNIQUE
);

CREATE INDEX events_record ON events (record_id);
CREATE INDEX events_username ON events (username);

-- The Argon2id password hash (PHC string) set by a user.add or
-- user.passwd event; the account's password is its latest event's.
CREATE TABLE passwords (
    event_id BIGINT PRIMARY KEY REFERENCES events (id),
    password_hash TEXT NOT NULL
);
