//! Sessions, CSRF tokens and login throttling, kept in the server's
//! memory (a restart logs everyone out).
//!
//! * A session id is 256 random bits ([`random_token`]) in the cookie
//!   `incal_session`: `HttpOnly; SameSite=Strict; Path=/` (and `Secure`
//!   behind TLS). A visitor gets an anonymous session for the login form's
//!   CSRF token; a login replaces it with a new id (no fixation), a logout
//!   removes it from the server (a replayed cookie is worth nothing).
//! * Every state-changing form carries the session's CSRF token, compared
//!   in constant time.
//! * Sessions end after [`IDLE`] without a request, or [`LIFETIME`] after
//!   login.
//! * Login failures are counted per account and per address: after
//!   [`MAX_FAILURES`] within [`WINDOW`], that account or address is refused
//!   for [`LOCKOUT`] whatever the password.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use crate::password::random_token;

/// The session cookie's name.
pub const COOKIE: &str = "incal_session";
/// A session unused this long ends.
pub const IDLE: Duration = Duration::from_secs(8 * 3600);
/// A session ends this long after login whatever its use.
pub const LIFETIME: Duration = Duration::from_secs(24 * 3600);
/// Failed logins allowed per account or address within [`WINDOW`].
pub const MAX_FAILURES: u32 = 5;
/// The window failures are counted in.
pub const WINDOW: Duration = Duration::from_secs(15 * 60);
/// How long an account or address is refused after too many failures.
pub const LOCKOUT: Duration = Duration::from_secs(15 * 60);
/// Most sessions held at once: beyond, the least recently used go.
pub const MAX_SESSIONS: usize = 10_000;

/// One session.
#[derive(Debug, Clone)]
pub struct Session {
    /// The account logged in (`None`: anonymous, before login).
    pub username: Option<String>,
    /// The token every form of this session carries.
    pub csrf: String,
    /// SHA-256 (hex) of the account's password hash at login (`None` in
    /// reverse-proxy mode): a password set since, from the web or with
    /// `incal user passwd` on the store, ends the session at its next
    /// request ([`crate::auth::User`]).
    pub password: Option<String>,
    created: Instant,
    seen: Instant,
}

#[derive(Debug, Default)]
struct Failures {
    count: u32,
    first: Option<Instant>,
    locked_until: Option<Instant>,
}

/// The server's sessions and login failures.
#[derive(Debug, Default)]
pub struct Sessions {
    map: Mutex<HashMap<String, Session>>,
    failures: Mutex<HashMap<String, Failures>>,
}

/// What a session holds of the password hash (PHC string) it logged in
/// with: its SHA-256, hex ([`Session::password`]).
pub fn password_tag(phc: &str) -> String {
    incal_io::sha256_hex(phc.as_bytes())
}

/// Equal strings, compared in time independent of where they differ.
pub fn same(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

impl Sessions {
    /// The live session `id`, touched; `None` when unknown or expired.
    pub fn get(&self, id: &str) -> Option<Session> {
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        let alive = map.get(id).is_some_and(|s| {
            now.duration_since(s.seen) < IDLE && now.duration_since(s.created) < LIFETIME
        });
        if !alive {
            map.remove(id);
            return None;
        }
        let s = map.get_mut(id)?;
        s.seen = now;
        Some(s.clone())
    }

    /// A new session (anonymous when `username` is `None`), its id;
    /// `password` is [`Session::password`].
    pub fn create(&self, username: Option<String>, password: Option<String>) -> (String, Session) {
        let now = Instant::now();
        let s = Session {
            username,
            csrf: random_token(),
            password,
            created: now,
            seen: now,
        };
        let id = random_token();
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        if map.len() >= MAX_SESSIONS {
            map.retain(|_, s| now.duration_since(s.seen) < IDLE);
            if map.len() >= MAX_SESSIONS {
                let oldest = map
                    .iter()
                    .min_by_key(|(_, s)| s.seen)
                    .map(|(k, _)| k.clone());
                if let Some(k) = oldest {
                    map.remove(&k);
                }
            }
        }
        map.insert(id.clone(), s.clone());
        (id, s)
    }

    /// End session `id` (logout): its cookie no longer opens anything.
    pub fn remove(&self, id: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(id);
    }

    /// End every session of `username` (disabled, password changed from
    /// the web).
    pub fn remove_user(&self, username: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .retain(|_, s| s.username.as_deref() != Some(username));
    }

    /// True when `key` (`user:NAME` or `addr:IP`) is locked out now.
    pub fn locked(&self, key: &str) -> bool {
        let f = self.failures.lock().unwrap_or_else(|p| p.into_inner());
        f.get(key)
            .and_then(|x| x.locked_until)
            .is_some_and(|t| Instant::now() < t)
    }

    /// Count a failed login for `key`; locks it out at [`MAX_FAILURES`].
    pub fn failed(&self, key: &str) {
        let mut f = self.failures.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        if f.len() > MAX_SESSIONS {
            f.retain(|_, x| x.locked_until.is_some_and(|t| now < t));
        }
        let e = f.entry(key.to_string()).or_default();
        if e.first.is_none_or(|t| now.duration_since(t) > WINDOW) {
            e.first = Some(now);
            e.count = 0;
        }
        e.count += 1;
        if e.count >= MAX_FAILURES {
            e.locked_until = Some(now + LOCKOUT);
        }
    }

    /// Forget the failures of `key` (a successful login).
    pub fn succeeded(&self, key: &str) {
        self.failures
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(key);
    }
}

/// The `Set-Cookie` value of session `id`.
pub fn cookie(id: &str, secure: bool) -> String {
    format!(
        "{COOKIE}={id}; Path=/; HttpOnly; SameSite=Strict{}",
        if secure { "; Secure" } else { "" }
    )
}

/// The `Set-Cookie` value that removes the session cookie.
pub fn cleared(secure: bool) -> String {
    format!(
        "{COOKIE}=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0{}",
        if secure { "; Secure" } else { "" }
    )
}

/// The session id in a `Cookie` header, if any.
pub fn from_cookie_header(header: &str) -> Option<&str> {
    header
        .split(';')
        .map(str::trim)
        .find_map(|kv| kv.strip_prefix(COOKIE)?.strip_prefix('='))
        .filter(|v| v.len() == 64 && v.bytes().all(|b| b.is_ascii_hexdigit()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sessions_and_throttle() {
        let s = Sessions::default();
        let (id, sess) = s.create(Some("eve".into()), None);
        assert_eq!(s.get(&id).unwrap().csrf, sess.csrf);
        s.remove(&id);
        assert!(s.get(&id).is_none());
        for _ in 0..MAX_FAILURES - 1 {
            s.failed("user:eve");
        }
        assert!(!s.locked("user:eve"));
        s.failed("user:eve");
        assert!(s.locked("user:eve"));
        assert!(!s.locked("user:sam"));
        let c = cookie(&id, true);
        assert!(c.contains("HttpOnly") && c.contains("SameSite=Strict") && c.ends_with("Secure"));
        let h = format!("a=b; {COOKIE}={id}");
        assert_eq!(from_cookie_header(&h), Some(id.as_str()));
        assert_eq!(from_cookie_header("incal_session=../../etc"), None);
        assert!(same("abc", "abc") && !same("abc", "abd") && !same("abc", "ab"));
    }
}
