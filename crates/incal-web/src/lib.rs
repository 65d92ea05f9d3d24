//! The lab's web application (`incal serve`): instruments and their due
//! dates, an instrument's calibrations and the history of any coefficient,
//! a record with its review, its certificate (HTML, PDF) and its result
//! document, submission of results, approval and rejection by a
//! signatory, and the audit log; for accounts with roles, over a records
//! store (SQLite or PostgreSQL).
//!
//! * Server-rendered pages (askama templates, every field escaped), no
//!   script at all; axum on tokio; the store used from blocking threads
//!   through a small pool of connections ([`state`]).
//! * Every page but `/health` and the login form needs a session
//!   ([`session`]); every state-changing form carries the session's CSRF
//!   token; roles are read from the store's hash chain on every request,
//!   and the store checks every rule again ([`incal_records::Store::approve`]).
//! * Every page's footer shows the chain's `verify` status and head; a
//!   broken chain is shown in red and every write is refused.

// A handler's refusal is an axum Response (status and page): returned
// through `Result` at the few places a check can stop a handler, where
// boxing it would only add noise.
#![allow(clippy::result_large_err)]

pub mod auth;
pub mod pages;
pub mod password;
pub mod session;
pub mod state;
mod views;

use axum::routing::{get, post};
use axum::Router;

pub use state::{AppState, Config, Shared};

/// Largest request body accepted (a result document upload).
pub const MAX_BODY: usize = 16 << 20;

/// The application's routes on `state`.
pub fn router(state: Shared) -> Router {
    use pages::{admin, auth as login, instruments, records};
    Router::new()
        .route("/health", get(pages::health))
        .route("/login", get(login::form).post(login::submit))
        .route("/logout", post(login::logout))
        .route("/", get(instruments::list))
        .route("/instruments/{serial}", get(instruments::one))
        .route("/instruments/{serial}/history", get(instruments::history))
        .route("/compare", get(records::compare))
        .route("/records/{id}", get(records::one))
        .route("/records/{id}/document.json", get(records::document))
        .route("/records/{id}/certificate", get(records::certificate))
        .route(
            "/records/{id}/certificate.xml",
            get(records::certificate_dcc),
        )
        .route(
            "/records/{id}/certificate.pdf",
            get(records::certificate_pdf),
        )
        .route("/records/{id}/approve", post(records::approve))
        .route("/records/{id}/reject", post(records::reject))
        .route("/submit", get(records::submit_form).post(records::submit))
        .route("/events", get(admin::events))
        .route("/users", get(admin::users).post(admin::change_user))
        .fallback(pages::not_found)
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            auth::sessions,
        ))
        .layer(axum::extract::DefaultBodyLimit::max(MAX_BODY))
        .with_state(state)
}

/// Serve `config` until interrupted (Ctrl-C or SIGTERM): open the store,
/// listen, print the address on standard error.
pub fn serve(config: Config) -> Result<(), String> {
    let listen = config.listen;
    let state = AppState::open(config)?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the server's runtime: {e}"))?;
    rt.block_on(async move {
        let listener = tokio::net::TcpListener::bind(listen)
            .await
            .map_err(|e| format!("--listen {listen}: {e}"))?;
        let bound = listener.local_addr().map_err(|e| e.to_string())?;
        eprintln!("incal serve: http://{bound}/ (Ctrl-C stops)");
        let app = router(state).into_make_service_with_connect_info::<std::net::SocketAddr>();
        axum::serve(listener, app)
            .with_graceful_shutdown(shutdown())
            .await
            .map_err(|e| format!("the server stopped: {e}"))
    })
}

async fn shutdown() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        if let Ok(mut s) = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
        {
            s.recv().await;
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! { _ = ctrl_c => {}, _ = term => {} }
}
