//! Events: the lab's workflow (a submission, an approval, a rejection) and
//! its administration (an account added, a password set, a role changed,
//! an account disabled or enabled), written in the records' hash chain.
//!
//! # Place in the chain
//! Records and events share one sequence of ids (1, 2, 3, … in the order
//! written); each entry's `prev_hash` is the hash of the entry before it,
//! whichever it is, so [`Store::verify`](crate::Store::verify) walks one
//! chain and an event edited, removed or inserted behind incal's back
//! breaks it as a record would.
//!
//! # Canonical form (`incal.event/1`)
//! `event_hash = SHA-256(C)`, where `C` is these fields written as in
//! [`chain`](crate::chain) (`LEN:TEXT\n`, or `-\n` for null), in order:
//! 1. `incal.event/1`
//! 2. `prev_hash`
//! 3. `id` (decimal)
//! 4. `kind` ([`EventKind`])
//! 5. `created_utc` (`YYYY-MM-DDTHH:MM:SSZ`)
//! 6. `actor` (the account, or `console:NAME` for the server's console)
//! 7. `actor_role` ([`Role`])
//! 8. `record_id` (decimal, or null)
//! 9. `username` (or null)
//! 10. `role` (or null)
//! 11. `secret_sha256`: SHA-256 of the Argon2id password hash set (or null)
//! 12. `reason` (or null)
//!
//! Roles and account states are read from these events only: there is no
//! mutable table of roles to edit. The password hashes are kept beside
//! their event (`passwords`), each covered by its event's `secret_sha256`.

use serde::{Deserialize, Serialize};

use crate::chain::sha256_hex;

/// The version tag that opens every event's canonical form.
pub const EVENT_FORM: &str = "incal.event/1";

/// What a lab account may do (ISO/IEC 17025 §6.2.6: authorisation).
///
/// * `viewer`: read everything;
/// * `engineer`: also submit results;
/// * `signatory`: also approve or reject a submission (not their own) and
///   so issue its certificate;
/// * `admin`: also manage accounts (not approve: authorisation to sign is
///   the signatory's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// Reads.
    Viewer,
    /// Reads and submits.
    Engineer,
    /// Reads, submits, approves and rejects.
    Signatory,
    /// Reads, submits and manages accounts.
    Admin,
}

impl Role {
    /// Every role, least to most.
    pub const ALL: [Role; 4] = [Role::Viewer, Role::Engineer, Role::Signatory, Role::Admin];

    /// Its name.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Viewer => "viewer",
            Role::Engineer => "engineer",
            Role::Signatory => "signatory",
            Role::Admin => "admin",
        }
    }

    /// The role named `s`.
    pub fn parse(s: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.as_str() == s)
    }

    /// May submit results.
    pub fn may_submit(self) -> bool {
        self != Role::Viewer
    }

    /// May approve or reject a submission (and so issue certificates).
    pub fn may_approve(self) -> bool {
        self == Role::Signatory
    }

    /// May add accounts, set passwords and roles, disable accounts.
    pub fn may_administer(self) -> bool {
        self == Role::Admin
    }
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What an event records.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum EventKind {
    /// A result submitted for review by an account (written with its record).
    #[serde(rename = "record.submit")]
    Submit,
    /// A submission approved by a signatory: its certificate may be issued.
    #[serde(rename = "record.approve")]
    Approve,
    /// A submission rejected by a signatory, with a reason.
    #[serde(rename = "record.reject")]
    Reject,
    /// An account added, with its role and password.
    #[serde(rename = "user.add")]
    UserAdd,
    /// An account's password set.
    #[serde(rename = "user.passwd")]
    UserPasswd,
    /// An account's role changed.
    #[serde(rename = "user.role")]
    UserRole,
    /// An account disabled: it can no longer log in.
    #[serde(rename = "user.disable")]
    UserDisable,
    /// A disabled account enabled again.
    #[serde(rename = "user.enable")]
    UserEnable,
}

impl EventKind {
    /// Every kind.
    pub const ALL: [EventKind; 8] = [
        EventKind::Submit,
        EventKind::Approve,
        EventKind::Reject,
        EventKind::UserAdd,
        EventKind::UserPasswd,
        EventKind::UserRole,
        EventKind::UserDisable,
        EventKind::UserEnable,
    ];

    /// Its name, as stored.
    pub fn as_str(self) -> &'static str {
        match self {
            EventKind::Submit => "record.submit",
            EventKind::Approve => "record.approve",
            EventKind::Reject => "record.reject",
            EventKind::UserAdd => "user.add",
            EventKind::UserPasswd => "user.passwd",
            EventKind::UserRole => "user.role",
            EventKind::UserDisable => "user.disable",
            EventKind::UserEnable => "user.enable",
        }
    }

    /// The kind named `s`.
    pub fn parse(s: &str) -> Option<EventKind> {
        EventKind::ALL.into_iter().find(|k| k.as_str() == s)
    }

    /// True for the kinds about a record (`record.*`).
    pub fn is_record(self) -> bool {
        matches!(
            self,
            EventKind::Submit | EventKind::Approve | EventKind::Reject
        )
    }

    /// True for the kinds that set a password.
    pub fn sets_password(self) -> bool {
        matches!(self, EventKind::UserAdd | EventKind::UserPasswd)
    }
}

/// Who acts: an account (or the server's console) in a role.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Actor {
    /// The account's name, or `console:NAME` for the server's console.
    pub name: String,
    /// The role it acts in.
    pub role: Role,
}

impl Actor {
    /// The server's console, as the operating-system user `os_user`: the
    /// one who holds the store's file acts as its administrator (the
    /// command `incal user`).
    pub fn console(os_user: &str) -> Actor {
        Actor {
            name: format!("console:{os_user}"),
            role: Role::Admin,
        }
    }
}

/// One event in the chain, with every field its hash covers (module docs).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Event {
    /// Position in the chain (shared with records).
    pub id: i64,
    /// What it records.
    pub kind: EventKind,
    /// `YYYY-MM-DDTHH:MM:SSZ`.
    pub created_utc: String,
    /// Who.
    pub actor: String,
    /// In which role.
    pub actor_role: Role,
    /// The record it concerns.
    pub record_id: Option<i64>,
    /// The account it concerns.
    pub username: Option<String>,
    /// The role given.
    pub role: Option<Role>,
    /// SHA-256 of the password hash set.
    pub secret_sha256: Option<String>,
    /// Why.
    pub reason: Option<String>,
    /// Hash of the entry before.
    pub prev_hash: String,
    /// This event's hash.
    pub event_hash: String,
}

impl Event {
    /// The canonical form `C` (module docs).
    pub fn canonical(&self) -> Vec<u8> {
        let mut c = Vec::with_capacity(256);
        let id = self.id.to_string();
        let record = self.record_id.map(|r| r.to_string());
        let fields: [Option<&str>; 12] = [
            Some(EVENT_FORM),
            Some(&self.prev_hash),
            Some(&id),
            Some(self.kind.as_str()),
            Some(&self.created_utc),
            Some(&self.actor),
            Some(self.actor_role.as_str()),
            record.as_deref(),
            self.username.as_deref(),
            self.role.map(Role::as_str),
            self.secret_sha256.as_deref(),
            self.reason.as_deref(),
        ];
        for f in fields {
            crate::chain::field(&mut c, f);
        }
        c
    }

    /// `event_hash = SHA-256(canonical form)`, lower-case hex.
    pub fn hash(&self) -> String {
        sha256_hex(&self.canonical())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn event() -> Event {
        Event {
            id: 3,
            kind: EventKind::Approve,
            created_utc: "2026-12-01T10:00:00Z".into(),
            actor: "ada".into(),
            actor_role: Role::Signatory,
            record_id: Some(2),
            username: None,
            role: None,
            secret_sha256: None,
            reason: Some("ok".into()),
            prev_hash: crate::GENESIS.into(),
            event_hash: String::new(),
        }
    }

    #[test]
    fn canonical_form_is_length_prefixed_lines() {
        let c = String::from_utf8(event().canonical()).unwrap();
        let g = crate::GENESIS;
        assert_eq!(
            c,
            format!("13:incal.event/1\n64:{g}\n1:3\n14:record.approve\n20:2026-12-01T10:00:00Z\n3:ada\n9:signatory\n1:2\n-\n-\n-\n2:ok\n")
        );
    }

    #[test]
    fn every_field_changes_the_hash() {
        let h = event().hash();
        let mut v = Vec::new();
        let edits: [fn(&mut Event); 8] = [
            |e| e.actor_role = Role::Admin,
            |e| e.record_id = Some(1),
            |e| e.kind = EventKind::Reject,
            |e| e.username = Some(String::new()),
            |e| e.role = Some(Role::Viewer),
            |e| e.reason = None,
            |e| e.actor = "ad".into(),
            |e| e.id = 4,
        ];
        for f in edits {
            let mut e = event();
            f(&mut e);
            v.push(e.hash());
        }
        assert!(v.iter().all(|x| *x != h));
    }

    #[test]
    fn names_round_trip() {
        for k in EventKind::ALL {
            assert_eq!(EventKind::parse(k.as_str()), Some(k));
            let j = serde_json::to_string(&k).unwrap();
            assert_eq!(j, format!("\"{}\"", k.as_str()));
        }
        for r in Role::ALL {
            assert_eq!(Role::parse(r.as_str()), Some(r));
        }
        assert!(Role::Signatory.may_approve() && !Role::Admin.may_approve());
        assert!(!Role::Viewer.may_submit() && Role::Engineer.may_submit());
    }
}
