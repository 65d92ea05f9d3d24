//! The handlers, one module per part of the application, and what they
//! share: the frame of every page, errors as pages, URL encoding.

pub mod admin;
pub mod auth;
pub mod instruments;
pub mod records;

use askama::Template;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse, Response};

use crate::auth::User;
use crate::state::Chain;
use crate::views::{ErrorPage, Page};
use crate::Shared;

/// `GET /health`: `ok` (200) while the store answers and its chain is
/// intact, `broken` (503) otherwise; nothing else is told without a login.
pub async fn health(State(app): State<Shared>) -> Response {
    match app.chain(false).await {
        Chain::Intact(_) => (StatusCode::OK, "ok\n").into_response(),
        Chain::Broken(_) => (StatusCode::SERVICE_UNAVAILABLE, "broken\n").into_response(),
    }
}

/// Any other path: 404.
pub async fn not_found() -> Response {
    error(StatusCode::NOT_FOUND, "no such page")
}

/// An error page without the frame of a logged-in page.
pub fn error(status: StatusCode, message: &str) -> Response {
    let page = ErrorPage {
        p: Page {
            title: format!(
                "{} {}",
                status.as_u16(),
                status.canonical_reason().unwrap_or("")
            ),
            chain_ok: true,
            chain_text: "not checked for this page".into(),
            ..Page::default()
        },
        message: message.to_string(),
    };
    (status, render(&page)).into_response()
}

/// A template as HTML (a template that fails to render is a 500).
pub fn render(t: &impl Template) -> Response {
    match t.render() {
        Ok(s) => Html(s).into_response(),
        Err(e) => (
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("cannot render the page: {e}"),
        )
            .into_response(),
    }
}

/// The frame of a page titled `title` for `user`, with the chain's status.
pub async fn page(app: &Shared, user: &User, title: &str) -> Page {
    let (chain_ok, chain_text) = match app.chain(false).await {
        Chain::Intact(v) => (
            true,
            format!(
                "{} records, {} events, head {}",
                v.records, v.events, v.head
            ),
        ),
        Chain::Broken(m) => (false, m),
    };
    Page {
        title: title.to_string(),
        user: user.account.username.clone(),
        role: user.account.role.to_string(),
        csrf: user.ctx.session.csrf.clone(),
        may_submit: user.account.role.may_submit(),
        is_admin: user.account.role.may_administer(),
        chain_ok,
        chain_text,
    }
}

/// `s` percent-encoded for a URL path segment or query value (every byte
/// but `A–Z a–z 0–9 - . _ ~`).
pub fn url(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// A store error as a page: bad input is 400 (422 for a refused rule),
/// a broken chain 409, anything else 500.
pub fn store_error(e: &incal_records::Error) -> Response {
    let status = match e {
        incal_records::Error::Input(_) | incal_records::Error::Store { .. } => {
            StatusCode::UNPROCESSABLE_ENTITY
        }
        incal_records::Error::Tampered { .. } | incal_records::Error::HeadMissing { .. } => {
            StatusCode::CONFLICT
        }
        _ => StatusCode::INTERNAL_SERVER_ERROR,
    };
    error(status, &e.to_string())
}

/// Refuse (403) unless `ok`, saying what the role may not do.
pub fn allowed(ok: bool, what: &str) -> Result<(), Response> {
    if ok {
        Ok(())
    } else {
        Err(error(
            StatusCode::FORBIDDEN,
            &format!("your role may not {what}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn url_encodes_all_but_unreserved() {
        assert_eq!(super::url("SN 1/../<x>"), "SN%201%2F..%2F%3Cx%3E");
    }
}
