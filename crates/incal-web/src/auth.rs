//! Who is asking: the session middleware that gives every request its
//! session (anonymous until login; in reverse-proxy mode, the proxy's
//! user), refuses every path but the public ones without a login, and the
//! extractor of the logged-in account with its role read from the chain.

use std::net::SocketAddr;

use axum::extract::{ConnectInfo, FromRequestParts, Request, State};
use axum::http::header::{COOKIE, LOCATION, SET_COOKIE};
use axum::http::request::Parts;
use axum::http::{HeaderValue, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use incal_records::{Account, Actor};

use crate::session::{self, same, Session};
use crate::Shared;

/// Paths open without a login.
pub fn is_public(path: &str) -> bool {
    path == "/health" || path == "/login"
}

/// The request's session, put in its extensions by [`sessions`].
#[derive(Debug, Clone)]
pub struct Ctx {
    /// The session id.
    pub sid: String,
    /// The session.
    pub session: Session,
    /// The peer's address (absent in tests that call the router directly).
    pub peer: Option<SocketAddr>,
}

impl Ctx {
    /// The key login failures of this address are counted under.
    pub fn addr_key(&self) -> String {
        match self.peer {
            Some(p) => format!("addr:{}", p.ip()),
            None => "addr:unknown".into(),
        }
    }

    /// True when `token` is this session's CSRF token.
    pub fn csrf_ok(&self, token: &str) -> bool {
        same(token, &self.session.csrf)
    }
}

/// The middleware: find or make the session, bind the proxy's user in
/// reverse-proxy mode, refuse a non-public path without a login (a GET is
/// sent to the login form, anything else is 401), set the cookie of a new
/// session.
pub async fn sessions(State(app): State<Shared>, mut req: Request, next: Next) -> Response {
    let peer = req
        .extensions()
        .get::<ConnectInfo<SocketAddr>>()
        .map(|c| c.0);
    let cookie_sid = req
        .headers()
        .get_all(COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .find_map(session::from_cookie_header)
        .map(str::to_string);
    let held = cookie_sid
        .as_deref()
        .and_then(|sid| app.sessions.get(sid).map(|s| (sid.to_string(), s)));
    let proxy_user = match (app.config.trusted_proxy, peer) {
        (Some(proxy), Some(p)) if p.ip() == proxy => req
            .headers()
            .get(app.config.user_header.as_str())
            .and_then(|v| v.to_str().ok())
            .map(str::to_string),
        _ => None,
    };
    let mut new_cookie = None;
    let (sid, session) = match (held, proxy_user) {
        (Some((sid, s)), None) => (sid, s),
        (Some((sid, s)), Some(u)) if s.username.as_deref() == Some(u.as_str()) => (sid, s),
        (_, user) => {
            if req.uri().path() == "/health" {
                return next.run(req).await;
            }
            let (sid, s) = app.sessions.create(user, None);
            new_cookie = Some(session::cookie(&sid, app.config.secure_cookies));
            (sid, s)
        }
    };
    let logged_in = session.username.is_some();
    let path = req.uri().path().to_string();
    req.extensions_mut().insert(Ctx { sid, session, peer });
    let mut resp = if logged_in || is_public(&path) {
        next.run(req).await
    } else if req.method() == Method::GET || req.method() == Method::HEAD {
        (StatusCode::SEE_OTHER, [(LOCATION, "/login")]).into_response()
    } else {
        (StatusCode::UNAUTHORIZED, "log in first").into_response()
    };
    if let Some(c) = new_cookie {
        set_cookie(&mut resp, &c);
    }
    security_headers(&mut resp);
    resp
}

/// Add the `Set-Cookie` header `value` ([`session::cookie`],
/// [`session::cleared`]) to `resp`.
pub fn set_cookie(resp: &mut Response, value: &str) {
    if let Ok(v) = HeaderValue::from_str(value) {
        resp.headers_mut().append(SET_COOKIE, v);
    }
}

/// Headers on every response: no framing, no sniffing, no referrer, no
/// script or outside resource at all, no caching of pages.
fn security_headers(resp: &mut Response) {
    let h = resp.headers_mut();
    let set = [
        ("content-security-policy", "default-src 'none'; style-src 'unsafe-inline'; img-src 'self' data:; form-action 'self'; frame-ancestors 'none'; base-uri 'none'"),
        ("x-frame-options", "DENY"),
        ("x-content-type-options", "nosniff"),
        ("referrer-policy", "no-referrer"),
        ("cache-control", "no-store"),
    ];
    for (k, v) in set {
        h.insert(k, HeaderValue::from_static(v));
    }
}

/// The logged-in account of a request, its role as the chain says now.
#[derive(Debug, Clone)]
pub struct User {
    /// The request's session.
    pub ctx: Ctx,
    /// The account.
    pub account: Account,
}

impl User {
    /// The account as an actor of the store.
    pub fn actor(&self) -> Actor {
        Actor {
            name: self.account.username.clone(),
            role: self.account.role,
        }
    }

    /// Refuse (403) unless `token` is the session's CSRF token.
    pub fn check_csrf(&self, token: &str) -> Result<(), Response> {
        if self.ctx.csrf_ok(token) {
            Ok(())
        } else {
            Err(crate::pages::error(
                StatusCode::FORBIDDEN,
                "the form's CSRF token is missing or not this session's: reload the page and try again",
            ))
        }
    }
}

impl FromRequestParts<Shared> for User {
    type Rejection = Response;

    async fn from_request_parts(parts: &mut Parts, app: &Shared) -> Result<User, Response> {
        let ctx = parts
            .extensions
            .get::<Ctx>()
            .cloned()
            .ok_or_else(|| StatusCode::UNAUTHORIZED.into_response())?;
        let Some(name) = ctx.session.username.clone() else {
            return Err((StatusCode::SEE_OTHER, [(LOCATION, "/login")]).into_response());
        };
        let account = app
            .with_store(move |s| s.account(&name))
            .await
            .map_err(|e| crate::pages::error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()))?;
        let same_password = |a: &Account| {
            ctx.session
                .password
                .as_deref()
                .is_none_or(|held| same(held, &session::password_tag(&a.password_hash)))
        };
        match account {
            Some(a) if !a.disabled && same_password(&a) => Ok(User { ctx, account: a }),
            _ => {
                // Disabled, gone or given a new password since login: the
                // session ends.
                app.sessions.remove(&ctx.sid);
                Err((StatusCode::SEE_OTHER, [(LOCATION, "/login")]).into_response())
            }
        }
    }
}
