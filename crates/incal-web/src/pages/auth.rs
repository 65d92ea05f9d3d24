//! Logging in and out.

use axum::extract::State;
use axum::http::header::LOCATION;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::{Extension, Form};
use serde::Deserialize;

use crate::auth::{set_cookie, Ctx};
use crate::pages::{error, render};
use crate::views::{Login, Page};
use crate::{password, session, Shared};

fn login_page(ctx: &Ctx, message: &str, status: StatusCode) -> Response {
    let p = Page {
        title: "Log in".into(),
        csrf: ctx.session.csrf.clone(),
        chain_ok: true,
        chain_text: "shown after login".into(),
        ..Page::default()
    };
    let page = Login {
        p,
        message: message.to_string(),
    };
    (status, render(&page)).into_response()
}

/// `GET /login`.
pub async fn form(Extension(ctx): Extension<Ctx>) -> Response {
    if ctx.session.username.is_some() {
        return (StatusCode::SEE_OTHER, [(LOCATION, "/")]).into_response();
    }
    login_page(&ctx, "", StatusCode::OK)
}

/// The login form.
#[derive(Deserialize)]
pub struct LoginForm {
    #[serde(default)]
    csrf: String,
    #[serde(default)]
    username: String,
    #[serde(default)]
    password: String,
}

/// `POST /login`: check the CSRF token, the throttles, the password; on
/// success a new session (new id: no fixation) replaces the anonymous one.
pub async fn submit(
    State(app): State<Shared>,
    Extension(ctx): Extension<Ctx>,
    Form(f): Form<LoginForm>,
) -> Response {
    if !ctx.csrf_ok(&f.csrf) {
        return error(
            StatusCode::FORBIDDEN,
            "the login form's CSRF token is missing or stale: reload the page",
        );
    }
    let user_key = format!("user:{}", f.username);
    let addr_key = ctx.addr_key();
    if app.sessions.locked(&user_key) || app.sessions.locked(&addr_key) {
        return login_page(
            &ctx,
            "too many failed logins for this account or address: try again in 15 minutes",
            StatusCode::TOO_MANY_REQUESTS,
        );
    }
    let name = f.username.clone();
    let account = match app.with_store(move |s| s.account(&name)).await {
        Ok(a) => a,
        Err(e) => return crate::pages::store_error(&e),
    };
    let (phc, usable) = match &account {
        Some(a) => (a.password_hash.clone(), !a.disabled),
        None => (password::decoy().to_string(), false),
    };
    let pw = f.password;
    let matches = tokio::task::spawn_blocking(move || password::verify(&pw, &phc))
        .await
        .unwrap_or(false);
    if !(matches && usable) {
        app.sessions.failed(&user_key);
        app.sessions.failed(&addr_key);
        return login_page(
            &ctx,
            "wrong account or password, or the account is disabled",
            StatusCode::UNAUTHORIZED,
        );
    }
    app.sessions.succeeded(&user_key);
    app.sessions.remove(&ctx.sid);
    let held = account.map(|a| session::password_tag(&a.password_hash));
    let (sid, _) = app.sessions.create(Some(f.username), held);
    let mut resp = (StatusCode::SEE_OTHER, [(LOCATION, "/")]).into_response();
    set_cookie(&mut resp, &session::cookie(&sid, app.config.secure_cookies));
    resp
}

/// The logout form.
#[derive(Deserialize)]
pub struct LogoutForm {
    #[serde(default)]
    csrf: String,
}

/// `POST /logout`: the session ends on the server (its cookie, replayed,
/// opens nothing) and the cookie is cleared.
pub async fn logout(
    State(app): State<Shared>,
    Extension(ctx): Extension<Ctx>,
    Form(f): Form<LogoutForm>,
) -> Response {
    if !ctx.csrf_ok(&f.csrf) {
        return error(
            StatusCode::FORBIDDEN,
            "the form's CSRF token is missing or not this session's",
        );
    }
    app.sessions.remove(&ctx.sid);
    let mut resp = (StatusCode::SEE_OTHER, [(LOCATION, "/login")]).into_response();
    set_cookie(&mut resp, &session::cleared(app.config.secure_cookies));
    resp
}
