//! The audit log and the accounts (admin).

use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Form;
use incal_records::Role;
use serde::Deserialize;

use crate::auth::User;
use crate::pages::{allowed, page, render, store_error};
use crate::views::{Events, Users};
use crate::{password, Shared};

/// Events shown by the audit log.
pub const AUDIT_EVENTS: i64 = 500;

/// `GET /events`: the last events of the chain (every role may read it).
pub async fn events(State(app): State<Shared>, user: User) -> Response {
    match app.with_store(|s| s.events(None, AUDIT_EVENTS)).await {
        Ok(events) => render(&Events {
            p: page(&app, &user, "Audit log").await,
            events,
        }),
        Err(e) => store_error(&e),
    }
}

async fn users_page(app: &Shared, user: &User, message: String, status: StatusCode) -> Response {
    match app.with_store(|s| s.accounts()).await {
        Ok(accounts) => {
            let page = Users {
                p: page(app, user, "Accounts").await,
                message,
                accounts,
                roles: Role::ALL.iter().map(|r| r.as_str()).collect(),
            };
            (status, render(&page)).into_response()
        }
        Err(e) => store_error(&e),
    }
}

/// `GET /users` (admin).
pub async fn users(State(app): State<Shared>, user: User) -> Response {
    if let Err(r) = allowed(
        user.account.role.may_administer(),
        "manage accounts (admin only)",
    ) {
        return r;
    }
    users_page(&app, &user, String::new(), StatusCode::OK).await
}

/// The account form.
#[derive(Deserialize)]
pub struct UserForm {
    #[serde(default)]
    csrf: String,
    #[serde(default)]
    username: String,
    #[serde(default)]
    action: String,
    #[serde(default)]
    role: String,
    #[serde(default)]
    password: String,
}

/// `POST /users` (admin): add an account, set its role or password,
/// disable or enable it; each an event in the chain. A disabled account's
/// sessions end at once.
pub async fn change_user(
    State(app): State<Shared>,
    user: User,
    Form(f): Form<UserForm>,
) -> Response {
    if let Err(r) = user.check_csrf(&f.csrf) {
        return r;
    }
    if let Err(r) = allowed(
        user.account.role.may_administer(),
        "manage accounts (admin only)",
    ) {
        return r;
    }
    let bad = |m: String| (m, StatusCode::UNPROCESSABLE_ENTITY);
    let role = Role::parse(&f.role);
    let hashed = if matches!(f.action.as_str(), "add" | "passwd") {
        match password::check_new(&f.password).and_then(|_| {
            let pw = f.password.clone();
            password::hash(&pw)
        }) {
            Ok(h) => Some(h),
            Err(m) => {
                let (m, s) = bad(m);
                return users_page(&app, &user, m, s).await;
            }
        }
    } else {
        None
    };
    let actor = user.actor();
    let (name, action) = (f.username.clone(), f.action.clone());
    let done = app
        .write_store(move |s| match (action.as_str(), role, hashed) {
            ("add", Some(r), Some(h)) => s.add_user(&actor, &name, r, &h).map(|_| ()),
            ("passwd", _, Some(h)) => s.set_password(&actor, &name, &h).map(|_| ()),
            ("role", Some(r), _) => s.set_role(&actor, &name, r).map(|_| ()),
            ("disable", _, _) => s.set_disabled(&actor, &name, true).map(|_| ()),
            ("enable", _, _) => s.set_disabled(&actor, &name, false).map(|_| ()),
            _ => Err(incal_records::Error::Input("unknown action or role".into())),
        })
        .await;
    app.after_write(&done).await;
    let (message, status) = match done {
        Ok(()) => {
            if matches!(f.action.as_str(), "disable" | "passwd") {
                app.sessions.remove_user(&f.username);
            }
            (format!("{}: {} done", f.username, f.action), StatusCode::OK)
        }
        Err(e) => bad(e.to_string()),
    };
    users_page(&app, &user, message, status).await
}
