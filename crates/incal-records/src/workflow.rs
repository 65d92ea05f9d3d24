//! The lab's workflow and accounts on a store: submitting, approving and
//! rejecting results, adding accounts and setting their passwords, roles
//! and states, each written as an event in the hash chain
//! ([`events`](crate::events)); and reading them back: accounts, the state
//! of each record, the events of a record.
//!
//! The store checks every rule itself, whichever front end calls it: an
//! actor that is an account must exist, be enabled and hold the role it
//! acts in; only a signatory approves or rejects, never a submission of
//! their own; a record is approved or rejected once, and not after it is
//! superseded; only an administrator manages accounts.

use std::collections::HashMap;

use serde::Serialize;

use crate::db::{Conn, DbError, Mode, P};
use crate::error::db_err;
use crate::events::{Actor, Event, EventKind, Role};
use crate::write::chain_head;
use crate::{sha256_hex, time, Added, Error, NewRecord, Result, Store};

/// A lab account, as its events leave it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Account {
    /// Its name.
    pub username: String,
    /// Its role.
    pub role: Role,
    /// Disabled accounts cannot log in.
    pub disabled: bool,
    /// When it was added.
    pub created_utc: String,
    /// The Argon2id hash (PHC string) of its password.
    #[serde(skip)]
    pub password_hash: String,
}

/// Where a record stands in the review.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum State {
    /// Stored, waiting for a signatory.
    Submitted,
    /// Approved: its certificate may be issued.
    Approved,
    /// Rejected, with a reason.
    Rejected,
    /// Corrected by a later record.
    Superseded,
}

impl State {
    /// Its name.
    pub fn as_str(self) -> &'static str {
        match self {
            State::Submitted => "submitted",
            State::Approved => "approved",
            State::Rejected => "rejected",
            State::Superseded => "superseded",
        }
    }
}

/// A record's review: its state, who submitted it, and the decision.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Review {
    /// The record.
    pub record_id: i64,
    /// Where it stands (a superseded record stays approved or rejected in
    /// `decision`).
    pub state: State,
    /// The account that submitted it (its `record.submit` event), else the
    /// record's operator.
    pub submitted_by: Option<String>,
    /// The approval or rejection.
    pub decision: Option<Event>,
}

/// Longest account name.
pub const MAX_USERNAME: usize = 64;

/// An account name: 1 to 64 of `A–Z a–z 0–9 . _ @ -`, not starting with
/// `console:` (the console's actors).
pub fn check_username(name: &str) -> Result<()> {
    let ok = !name.is_empty()
        && name.len() <= MAX_USERNAME
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"._@-".contains(&b));
    if ok {
        Ok(())
    } else {
        Err(Error::Input(format!(
            "account name '{}': 1 to {MAX_USERNAME} of letters, digits and . _ @ -",
            incal_io::clip(name)
        )))
    }
}

/// The accounts as the chain's `user.*` events leave them, read inside
/// `tx`.
fn accounts_in(tx: &mut Conn) -> std::result::Result<Vec<Account>, DbError> {
    let rows = tx.query(
        "SELECT e.kind, e.username, e.role, e.created_utc, p.password_hash
         FROM events e LEFT JOIN passwords p ON p.event_id = e.id
         WHERE e.kind LIKE 'user.%' ORDER BY e.id",
        &[],
    )?;
    let mut out: Vec<Account> = Vec::new();
    for r in rows {
        let kind = EventKind::parse(&r.t(0)?);
        let name = r.ot(1)?.unwrap_or_default();
        let role = r.ot(2)?.as_deref().and_then(Role::parse);
        let hash = r.ot(4)?;
        if kind == Some(EventKind::UserAdd) {
            out.push(Account {
                username: name,
                role: role.unwrap_or(Role::Viewer),
                disabled: false,
                created_utc: r.t(3)?,
                password_hash: hash.unwrap_or_default(),
            });
            continue;
        }
        let Some(a) = out.iter_mut().find(|a| a.username == name) else {
            continue;
        };
        match kind {
            Some(EventKind::UserPasswd) => a.password_hash = hash.unwrap_or_default(),
            Some(EventKind::UserRole) => a.role = role.unwrap_or(a.role),
            Some(EventKind::UserDisable) => a.disabled = true,
            Some(EventKind::UserEnable) => a.disabled = false,
            _ => {}
        }
    }
    Ok(out)
}

/// Append `ev` (its id, `prev_hash` and hash set here) after the chain's
/// head inside the write transaction `tx`, with the password hash a
/// `user.add` or `user.passwd` event sets.
fn append(
    tx: &mut Conn,
    mut ev: Event,
    password: Option<&str>,
) -> std::result::Result<Event, DbError> {
    let (head, prev) = chain_head(tx)?;
    ev.id = head + 1;
    ev.prev_hash = prev;
    ev.secret_sha256 = password.map(|p| sha256_hex(p.as_bytes()));
    ev.event_hash = ev.hash();
    write_event(tx, &ev, password)?;
    Ok(ev)
}

/// The rows of one event (its password row too), as given.
pub(crate) fn write_event(
    tx: &mut Conn,
    ev: &Event,
    password: Option<&str>,
) -> std::result::Result<(), DbError> {
    tx.execute(
        "INSERT INTO events (id, kind, created_utc, actor, actor_role, record_id, username,
                             role, secret_sha256, reason, prev_hash, event_hash)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)",
        &[
            P::I(ev.id),
            P::T(Some(ev.kind.as_str())),
            P::T(Some(&ev.created_utc)),
            P::T(Some(&ev.actor)),
            P::T(Some(ev.actor_role.as_str())),
            P::OI(ev.record_id),
            P::T(ev.username.as_deref()),
            P::T(ev.role.map(Role::as_str)),
            P::T(ev.secret_sha256.as_deref()),
            P::T(ev.reason.as_deref()),
            P::T(Some(&ev.prev_hash)),
            P::T(Some(&ev.event_hash)),
        ],
    )?;
    if let Some(p) = password {
        tx.execute(
            "INSERT INTO passwords (event_id, password_hash) VALUES (?1, ?2)",
            &[P::I(ev.id), P::T(Some(p))],
        )?;
    }
    Ok(())
}

/// A new event of `kind` by `actor`, now, with nothing else set.
fn event(kind: EventKind, actor: &Actor) -> Event {
    Event {
        id: 0,
        kind,
        created_utc: time::now_utc(),
        actor: actor.name.clone(),
        actor_role: actor.role,
        record_id: None,
        username: None,
        role: None,
        secret_sha256: None,
        reason: None,
        prev_hash: String::new(),
        event_hash: String::new(),
    }
}

/// Check that `actor` may act as it says: the console always; an account
/// when it exists, is enabled and holds the role it acts in.
fn check_actor(accounts: &[Account], actor: &Actor) -> Result<()> {
    if actor.name.starts_with("console:") {
        return Ok(());
    }
    match accounts.iter().find(|a| a.username == actor.name) {
        Some(a) if a.disabled => Err(Error::Input(format!(
            "account '{}' is disabled",
            actor.name
        ))),
        Some(a) if a.role != actor.role => Err(Error::Input(format!(
            "account '{}' is {}, not {}",
            actor.name, a.role, actor.role
        ))),
        Some(_) => Ok(()),
        None => Err(Error::Input(format!(
            "no account '{}'",
            incal_io::clip(&actor.name)
        ))),
    }
}

/// A password hash as the store keeps it: an Argon2id PHC string.
fn check_password_hash(hash: &str) -> Result<()> {
    if hash.starts_with("$argon2id$") && hash.len() < 512 {
        Ok(())
    } else {
        Err(Error::Input(
            "a password is stored as an Argon2id hash ($argon2id$…)".into(),
        ))
    }
}

/// What an account event changes.
enum UserChange<'a> {
    Add(Role, &'a str),
    Passwd(&'a str),
    Role(Role),
    Disable,
    Enable,
}

impl Store {
    /// Run `f` in one write transaction on a chain verified first, naming
    /// the store in database errors.
    fn write_tx<T>(&mut self, f: impl FnOnce(&mut Conn, &str) -> Result<T>) -> Result<T> {
        self.verify_before_writing()?;
        let name = self.path.display().to_string();
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Write).map_err(|e| db_err(&name, e))?;
        let out = f(&mut tx, &name)?;
        tx.commit().map_err(|e| db_err(&name, e))?;
        Ok(out)
    }

    fn change_user(&mut self, actor: &Actor, username: &str, change: UserChange) -> Result<Event> {
        check_username(username)?;
        self.write_tx(|tx, name| {
            let accounts = accounts_in(tx).map_err(|e| db_err(name, e))?;
            check_actor(&accounts, actor)?;
            if !actor.role.may_administer() {
                return Err(Error::Input(format!(
                    "{} may not manage accounts (admin only)",
                    actor.role
                )));
            }
            let have = accounts.iter().find(|a| a.username == username);
            let (kind, role, password) = match (&change, have) {
                (UserChange::Add(..), Some(_)) => {
                    return Err(Error::Input(format!("account '{username}' exists")))
                }
                (UserChange::Add(r, p), None) => (EventKind::UserAdd, Some(*r), Some(*p)),
                (_, None) => return Err(Error::Input(format!("no account '{username}'"))),
                (UserChange::Passwd(p), Some(_)) => (EventKind::UserPasswd, None, Some(*p)),
                (UserChange::Role(r), Some(_)) => (EventKind::UserRole, Some(*r), None),
                (UserChange::Disable, Some(_)) => (EventKind::UserDisable, None, None),
                (UserChange::Enable, Some(_)) => (EventKind::UserEnable, None, None),
            };
            if let Some(p) = password {
                check_password_hash(p)?;
            }
            let mut ev = event(kind, actor);
            ev.username = Some(username.to_string());
            ev.role = role;
            append(tx, ev, password).map_err(|e| db_err(name, e))
        })
    }

    /// Add account `username` with `role` and the Argon2id hash of its
    /// password (`user.add`).
    pub fn add_user(
        &mut self,
        actor: &Actor,
        username: &str,
        role: Role,
        password_hash: &str,
    ) -> Result<Event> {
        self.change_user(actor, username, UserChange::Add(role, password_hash))
    }

    /// Set the password of `username` (`user.passwd`).
    pub fn set_password(
        &mut self,
        actor: &Actor,
        username: &str,
        password_hash: &str,
    ) -> Result<Event> {
        self.change_user(actor, username, UserChange::Passwd(password_hash))
    }

    /// Give `username` another role (`user.role`).
    pub fn set_role(&mut self, actor: &Actor, username: &str, role: Role) -> Result<Event> {
        self.change_user(actor, username, UserChange::Role(role))
    }

    /// Disable (`user.disable`) or enable (`user.enable`) `username`.
    pub fn set_disabled(&mut self, actor: &Actor, username: &str, disabled: bool) -> Result<Event> {
        let change = if disabled {
            UserChange::Disable
        } else {
            UserChange::Enable
        };
        self.change_user(actor, username, change)
    }

    /// Every account, in the order added.
    pub fn accounts(&self) -> Result<Vec<Account>> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        accounts_in(&mut tx).map_err(self.db())
    }

    /// Account `username`, if there is one.
    pub fn account(&self, username: &str) -> Result<Option<Account>> {
        Ok(self
            .accounts()?
            .into_iter()
            .find(|a| a.username == username))
    }

    /// Store `req` as a new record submitted for review by `actor` (an
    /// engineer, signatory or admin): the record and its `record.submit`
    /// event in one transaction. The same document again is the record
    /// already held, and nothing is written.
    pub fn submit(&mut self, actor: &Actor, req: &NewRecord) -> Result<Added> {
        if !actor.role.may_submit() {
            return Err(Error::Input(format!(
                "a {} may not submit results",
                actor.role
            )));
        }
        self.check_account(actor)?;
        self.insert_as(req, None, Some(actor))
    }

    /// [`Store::supersede`] as a submission by `actor`.
    pub fn supersede_as(
        &mut self,
        actor: &Actor,
        old_id: i64,
        req: &NewRecord,
        reason: &str,
    ) -> Result<Added> {
        if !actor.role.may_submit() {
            return Err(Error::Input(format!(
                "a {} may not submit results",
                actor.role
            )));
        }
        if reason.trim().is_empty() {
            return Err(Error::Input("the reason of a supersession is empty".into()));
        }
        self.check_account(actor)?;
        self.insert_as(req, Some((old_id, reason)), Some(actor))
    }

    fn check_account(&self, actor: &Actor) -> Result<()> {
        check_actor(&self.accounts()?, actor)
    }

    /// Write the `record.submit` event of record `record_id` by `actor`
    /// inside the record's own transaction.
    pub(crate) fn submit_event(
        tx: &mut Conn,
        actor: &Actor,
        record_id: i64,
        at: &str,
    ) -> std::result::Result<Event, DbError> {
        let mut ev = event(EventKind::Submit, actor);
        ev.record_id = Some(record_id);
        ev.created_utc = at.to_string();
        append(tx, ev, None)
    }

    /// Approve record `record_id` (`record.approve`), with an optional
    /// remark: only a signatory, not the submitter, once, and not after
    /// the record is superseded or rejected.
    pub fn approve(
        &mut self,
        actor: &Actor,
        record_id: i64,
        remark: Option<&str>,
    ) -> Result<Event> {
        self.decide(
            actor,
            record_id,
            EventKind::Approve,
            remark.filter(|r| !r.trim().is_empty()),
        )
    }

    /// Reject record `record_id` (`record.reject`) because of `reason`
    /// (required), under the rules of [`Store::approve`].
    pub fn reject(&mut self, actor: &Actor, record_id: i64, reason: &str) -> Result<Event> {
        if reason.trim().is_empty() {
            return Err(Error::Input("a rejection needs a reason".into()));
        }
        self.decide(actor, record_id, EventKind::Reject, Some(reason))
    }

    fn decide(
        &mut self,
        actor: &Actor,
        record_id: i64,
        kind: EventKind,
        reason: Option<&str>,
    ) -> Result<Event> {
        if !actor.role.may_approve() {
            return Err(Error::Input(format!(
                "a {} may not approve or reject (signatory only)",
                actor.role
            )));
        }
        self.write_tx(|tx, name| {
            let e = |e| db_err(name, e);
            check_actor(&accounts_in(tx).map_err(e)?, actor)?;
            let review = review_in(tx, record_id).map_err(e)?.ok_or_else(|| {
                Error::Input(format!("record {record_id}: no such record"))
            })?;
            match review.state {
                State::Submitted => {}
                s => {
                    return Err(Error::Input(format!(
                        "record {record_id} is {}: it cannot be {}",
                        s.as_str(),
                        if kind == EventKind::Approve { "approved" } else { "rejected" }
                    )))
                }
            }
            if review.submitted_by.as_deref() == Some(actor.name.as_str()) {
                return Err(Error::Input(format!(
                    "record {record_id} was submitted by {}: a submission is approved by someone else",
                    actor.name
                )));
            }
            let mut ev = event(kind, actor);
            ev.record_id = Some(record_id);
            ev.reason = reason.map(str::to_string);
            append(tx, ev, None).map_err(e)
        })
    }

    /// The review of record `record_id` (bad input when there is none).
    pub fn review(&self, record_id: i64) -> Result<Review> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        review_in(&mut tx, record_id)
            .map_err(self.db())?
            .ok_or_else(|| Error::Input(format!("record {record_id}: no such record")))
    }

    /// The review of every record, by record id.
    pub fn reviews(&self) -> Result<HashMap<i64, Review>> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        reviews_in(&mut tx, None).map_err(self.db())
    }

    /// The review of every record of instrument `serial`, by record id.
    pub fn reviews_of(&self, serial: &str) -> Result<HashMap<i64, Review>> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        reviews_in(&mut tx, Some(Only::Serial(serial))).map_err(self.db())
    }

    /// The events about record `record_id`, or (when `None`) the last
    /// `limit` events of the chain, oldest first.
    pub fn events(&self, record_id: Option<i64>, limit: i64) -> Result<Vec<Event>> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        let rows = match record_id {
            Some(r) => tx.query(
                &format!("SELECT {EVENT_COLUMNS} FROM events WHERE record_id = ?1 ORDER BY id LIMIT ?2"),
                &[P::I(r), P::I(limit)],
            ),
            None => tx.query(
                &format!("SELECT * FROM (SELECT {EVENT_COLUMNS} FROM events ORDER BY id DESC LIMIT ?1) AS t ORDER BY id"),
                &[P::I(limit)],
            ),
        }
        .map_err(self.db())?;
        rows.iter()
            .map(|r| event_row(r).map_err(self.db()))
            .collect()
    }
}

/// The columns of an event row, in [`event_row`]'s order.
pub(crate) const EVENT_COLUMNS: &str = "id, kind, created_utc, actor, actor_role, record_id, username, role, secret_sha256, reason, prev_hash, event_hash";

/// An event from a row of [`EVENT_COLUMNS`]; a kind or role incal never
/// writes is a type error (the column does not read as stored).
pub(crate) fn event_row(r: &crate::db::Row) -> std::result::Result<Event, DbError> {
    let bad = |column, found| DbError::Type {
        column,
        found,
        wanted: "a name incal writes",
    };
    let kind = EventKind::parse(&r.t(1)?).ok_or(bad(1, "an unknown kind"))?;
    let actor_role = Role::parse(&r.t(4)?).ok_or(bad(4, "an unknown role"))?;
    let role = match r.ot(7)? {
        Some(s) => Some(Role::parse(&s).ok_or(bad(7, "an unknown role"))?),
        None => None,
    };
    Ok(Event {
        id: r.i(0)?,
        kind,
        created_utc: r.t(2)?,
        actor: r.t(3)?,
        actor_role,
        record_id: r.oi(5)?,
        username: r.ot(6)?,
        role,
        secret_sha256: r.ot(8)?,
        reason: r.ot(9)?,
        prev_hash: r.t(10)?,
        event_hash: r.t(11)?,
    })
}

fn review_in(tx: &mut Conn, record_id: i64) -> std::result::Result<Option<Review>, DbError> {
    Ok(reviews_in(tx, Some(Only::Record(record_id)))?.remove(&record_id))
}

/// Which records' reviews to read.
#[derive(Clone, Copy)]
enum Only<'a> {
    Record(i64),
    Serial(&'a str),
}

/// The reviews of every record (or of `only`), from the records, their
/// supersessions and their `record.*` events.
fn reviews_in(
    tx: &mut Conn,
    only: Option<Only>,
) -> std::result::Result<HashMap<i64, Review>, DbError> {
    let (cond, params): (&str, Vec<P>) = match only {
        Some(Only::Record(id)) => ("WHERE r.id = ?1", vec![P::I(id)]),
        Some(Only::Serial(s)) => (
            "WHERE r.instrument_id = (SELECT id FROM instruments WHERE serial = ?1)",
            vec![P::T(Some(s))],
        ),
        None => ("", vec![]),
    };
    let rows = tx.query(
        &format!(
            "SELECT r.id, r.operator, s.new_id FROM records r
             LEFT JOIN supersessions s ON s.old_id = r.id {cond}"
        ),
        &params,
    )?;
    let mut out = HashMap::new();
    for r in rows {
        let id = r.i(0)?;
        let state = if r.oi(2)?.is_some() {
            State::Superseded
        } else {
            State::Submitted
        };
        out.insert(
            id,
            Review {
                record_id: id,
                state,
                submitted_by: r.ot(1)?,
                decision: None,
            },
        );
    }
    let cond = match only {
        Some(Only::Record(_)) => "AND record_id = ?1",
        Some(Only::Serial(_)) => {
            "AND record_id IN (SELECT r.id FROM records r JOIN instruments i ON i.id = r.instrument_id WHERE i.serial = ?1)"
        }
        None => "",
    };
    let evs = tx.query(
        &format!(
            "SELECT {EVENT_COLUMNS} FROM events WHERE kind LIKE 'record.%' {cond} ORDER BY id"
        ),
        &params,
    )?;
    for r in &evs {
        let ev = event_row(r)?;
        let Some(rv) = ev.record_id.and_then(|id| out.get_mut(&id)) else {
            continue;
        };
        match ev.kind {
            EventKind::Submit => rv.submitted_by = Some(ev.actor.clone()),
            EventKind::Approve | EventKind::Reject => {
                if rv.state == State::Submitted {
                    rv.state = if ev.kind == EventKind::Approve {
                        State::Approved
                    } else {
                        State::Rejected
                    };
                }
                rv.decision = Some(ev);
            }
            _ => {}
        }
    }
    Ok(out)
}
