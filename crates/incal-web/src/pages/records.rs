//! A record: its page, its result document, its certificate (HTML and
//! PDF, once approved), its approval or rejection; submitting a result;
//! comparing two records.

use axum::extract::{Multipart, Path, Query, State};
use axum::http::header::{CONTENT_DISPOSITION, CONTENT_TYPE, LOCATION};
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse, Response};
use axum::Form;
use incal_records::{NewRecord, State as Rs, StoredRecord};
use serde::Deserialize;

use crate::auth::User;
use crate::pages::instruments::verdict_line;
use crate::pages::{allowed, error, page, render, store_error, url};
use crate::views::{Compare, CompareRow, Record, Submit};
use crate::Shared;

/// A download: `body` as `content_type`, saved as `filename`.
fn attachment(content_type: &'static str, filename: &str, body: impl IntoResponse) -> Response {
    (
        [
            (CONTENT_TYPE, content_type.to_string()),
            (
                CONTENT_DISPOSITION,
                format!("attachment; filename=\"{filename}\""),
            ),
        ],
        body,
    )
        .into_response()
}

/// `GET /records/{id}`.
pub async fn one(State(app): State<Shared>, user: User, Path(id): Path<i64>) -> Response {
    let read = app
        .with_store(move |s| {
            Ok::<_, incal_records::Error>((s.show(id)?, s.review(id)?, s.events(Some(id), 1000)?))
        })
        .await;
    let (r, review, events) = match read {
        Ok(x) => x,
        Err(e) => return store_error(&e),
    };
    let (verdicts, verdict_class) =
        verdict_line(crate::pages::instruments::Summary::of(&r.document).as_ref());
    let decision = review
        .decision
        .as_ref()
        .map(|d| {
            format!(
                "{} by {} ({}) on {}{}",
                if d.kind == incal_records::EventKind::Approve {
                    "approved"
                } else {
                    "rejected"
                },
                d.actor,
                d.actor_role,
                d.created_utc,
                d.reason
                    .as_deref()
                    .map(|x| format!(": {x}"))
                    .unwrap_or_default()
            )
        })
        .unwrap_or_default();
    let esc = incal_report::format::esc;
    let supersedes = r
        .supersedes
        .as_ref()
        .map(|s| {
            format!(
                "<a href=\"/records/{0}\">record {0}</a>: {1}",
                s.old_id,
                esc(&s.reason)
            )
        })
        .unwrap_or_default();
    let superseded_by = r
        .superseded_by
        .map(|n| format!("<a href=\"/records/{n}\">record {n}</a>"))
        .unwrap_or_default();
    let may_decide = user.account.role.may_approve()
        && review.state == Rs::Submitted
        && review.submitted_by.as_deref() != Some(user.account.username.as_str());
    render(&Record {
        p: page(&app, &user, &format!("Record {id}")).await,
        id,
        serial_url: url(&r.serial),
        serial: r.serial,
        model: r.model.unwrap_or_else(|| "model not recorded".into()),
        procedure: r.procedure,
        created: r.created_utc,
        operator: r.operator.unwrap_or_else(|| "-".into()),
        station: r.station.unwrap_or_else(|| "-".into()),
        submitted_by: review.submitted_by.clone().unwrap_or_else(|| "-".into()),
        state: review.state.as_str().into(),
        decision,
        verdicts,
        verdict_class,
        prev_hash: r.prev_hash,
        record_hash: r.record_hash,
        sha256: r.sha256,
        supersedes,
        superseded_by,
        inputs: r.inputs,
        events,
        may_decide,
    })
}

/// `GET /records/{id}/document.json`: the result document exactly as
/// stored, as a download named after the record.
pub async fn document(State(app): State<Shared>, _user: User, Path(id): Path<i64>) -> Response {
    match app.with_store(move |s| s.show(id)).await {
        Ok(r) => attachment("application/json", &format!("record-{id}.json"), r.document),
        Err(e) => store_error(&e),
    }
}

/// The certificate of approved record `id` as HTML, or (`dcc`) as a
/// Digital Calibration Certificate, which needs the server's `--lab`;
/// its approver is the signatory (409 when it is not approved).
async fn certificate_text(app: &Shared, id: i64, dcc: bool) -> Result<String, Response> {
    if dcc && app.lab.is_none() {
        return Err(error(
            StatusCode::CONFLICT,
            "a Digital Calibration Certificate names the laboratory: start incal serve with --lab lab.toml",
        ));
    }
    let lab = app.lab.clone();
    let out = app
        .with_store(move |s| -> Result<String, Response> {
            let review = s.review(id).map_err(|e| store_error(&e))?;
            let Some(d) = review
                .decision
                .filter(|d| d.kind == incal_records::EventKind::Approve)
            else {
                return Err(error(
                    StatusCode::CONFLICT,
                    &format!(
                        "record {id} is {}: a certificate is issued only once it is approved",
                        review.state.as_str()
                    ),
                ));
            };
            let r: StoredRecord = s.show(id).map_err(|e| store_error(&e))?;
            let doc = incal::document::ResultDocument::from_json(&r.document).map_err(|e| {
                error(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    &format!("record {id}: {e}"),
                )
            })?;
            let profile = lab.map(|mut p| {
                p.signatory = vec![incal_report::certificate::Signatory {
                    name: d.actor.clone(),
                    role: format!(
                        "authorised signatory; approved {}",
                        &d.created_utc[..10.min(d.created_utc.len())]
                    ),
                }];
                p
            });
            let issue = incal_report::stored::Issue::default();
            let fail = |e: incal_report::stored::StoredError| {
                error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string())
            };
            match (dcc, profile) {
                (true, Some(p)) => {
                    incal_report::stored::dcc_of(&doc, &r.document, Some(s), p, &issue)
                        .map_err(fail)
                }
                (_, profile) => {
                    incal_report::stored::report_html(&doc, &r.document, Some(s), profile, &issue)
                        .map_err(fail)
                }
            }
        })
        .await?;
    Ok(out)
}

/// `GET /records/{id}/certificate`: the certificate as HTML (the renderer
/// of `incal report`; a report without certificate fields when the
/// server has no `--lab` profile).
pub async fn certificate(State(app): State<Shared>, _user: User, Path(id): Path<i64>) -> Response {
    match certificate_text(&app, id, false).await {
        Ok(html) => Html(html).into_response(),
        Err(r) => r,
    }
}

/// `GET /records/{id}/certificate.xml`: the certificate as a Digital
/// Calibration Certificate (PTB DCC 3.2.0 XML, D-SI quantities), as
/// `incal report --dcc` writes it.
pub async fn certificate_dcc(
    State(app): State<Shared>,
    _user: User,
    Path(id): Path<i64>,
) -> Response {
    match certificate_text(&app, id, true).await {
        Ok(xml) => attachment("application/xml", &format!("certificate-{id}.xml"), xml),
        Err(r) => r,
    }
}

/// `GET /records/{id}/certificate.pdf`: the certificate printed by
/// headless Chromium, as `incal report --pdf` prints it (503 when no
/// browser is installed).
pub async fn certificate_pdf(
    State(app): State<Shared>,
    _user: User,
    Path(id): Path<i64>,
) -> Response {
    let html = match certificate_text(&app, id, false).await {
        Ok(h) => h,
        Err(r) => return r,
    };
    let printed = tokio::task::spawn_blocking(move || {
        let dir =
            std::env::temp_dir().join(format!("incal-serve-{}", crate::password::random_token()));
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let file = dir.join(format!("certificate-{id}.html"));
        let out = std::fs::write(&file, html)
            .map_err(|e| e.to_string())
            .and_then(|_| incal_report::pdf::print(&file).map_err(|e| e.to_string()))
            .and_then(|pdf| std::fs::read(pdf).map_err(|e| e.to_string()));
        let _ = std::fs::remove_dir_all(&dir);
        out
    })
    .await
    .unwrap_or_else(|e| Err(e.to_string()));
    match printed {
        Ok(bytes) => attachment("application/pdf", &format!("certificate-{id}.pdf"), bytes),
        Err(e) => error(StatusCode::SERVICE_UNAVAILABLE, &format!("no PDF: {e}")),
    }
}

/// The approval and rejection forms.
#[derive(Deserialize)]
pub struct DecisionForm {
    #[serde(default)]
    csrf: String,
    #[serde(default)]
    reason: String,
}

async fn decide(app: Shared, user: User, id: i64, f: DecisionForm, approve: bool) -> Response {
    if let Err(r) = user.check_csrf(&f.csrf) {
        return r;
    }
    if let Err(r) = allowed(
        user.account.role.may_approve(),
        "approve or reject (signatory only)",
    ) {
        return r;
    }
    let actor = user.actor();
    let done = app
        .write_store(move |s| {
            if approve {
                s.approve(&actor, id, Some(f.reason.as_str()))
            } else {
                s.reject(&actor, id, &f.reason)
            }
        })
        .await;
    app.after_write(&done).await;
    match done {
        Ok(_) => (
            StatusCode::SEE_OTHER,
            [(LOCATION, format!("/records/{id}"))],
        )
            .into_response(),
        Err(e) => store_error(&e),
    }
}

/// `POST /records/{id}/approve` (signatory; not the submitter).
pub async fn approve(
    State(app): State<Shared>,
    user: User,
    Path(id): Path<i64>,
    Form(f): Form<DecisionForm>,
) -> Response {
    decide(app, user, id, f, true).await
}

/// `POST /records/{id}/reject` (signatory, with a reason).
pub async fn reject(
    State(app): State<Shared>,
    user: User,
    Path(id): Path<i64>,
    Form(f): Form<DecisionForm>,
) -> Response {
    decide(app, user, id, f, false).await
}

/// `GET /submit`.
pub async fn submit_form(State(app): State<Shared>, user: User) -> Response {
    if let Err(r) = allowed(user.account.role.may_submit(), "submit results") {
        return r;
    }
    render(&Submit {
        p: page(&app, &user, "Submit a result").await,
        message: String::new(),
    })
}

/// The fields of the submission form, read whole before anything is done.
#[derive(Default)]
struct Submission {
    csrf: String,
    document: Option<String>,
    serial: String,
    supersedes: String,
    reason: String,
}

async fn read_submission(mut m: Multipart) -> Result<Submission, String> {
    let mut s = Submission::default();
    while let Some(field) = m.next_field().await.map_err(|e| e.to_string())? {
        let name = field.name().unwrap_or("").to_string();
        let text = field.text().await.map_err(|e| e.to_string())?;
        match name.as_str() {
            "csrf" => s.csrf = text,
            "document" => s.document = Some(text),
            "serial" => s.serial = text,
            "supersedes" => s.supersedes = text,
            "reason" => s.reason = text,
            _ => {}
        }
    }
    Ok(s)
}

/// `POST /submit` (engineer, signatory, admin): the uploaded result
/// document stored as a record submitted by the account, or a correction
/// of a record (with a reason); then its page.
pub async fn submit(State(app): State<Shared>, user: User, m: Multipart) -> Response {
    let sub = match read_submission(m).await {
        Ok(s) => s,
        Err(e) => {
            return error(
                StatusCode::BAD_REQUEST,
                &format!("the form cannot be read: {e}"),
            )
        }
    };
    if let Err(r) = user.check_csrf(&sub.csrf) {
        return r;
    }
    if let Err(r) = allowed(user.account.role.may_submit(), "submit results") {
        return r;
    }
    let Some(text) = sub.document.filter(|d| !d.trim().is_empty()) else {
        return error(
            StatusCode::UNPROCESSABLE_ENTITY,
            "no result document was uploaded",
        );
    };
    let old = match sub.supersedes.trim() {
        "" => None,
        t => match t.parse::<i64>() {
            Ok(n) => Some(n),
            Err(_) => {
                return error(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    "supersedes: not a record number",
                )
            }
        },
    };
    let actor = user.actor();
    let done = app
        .write_store(move |s| {
            let serial = sub.serial.trim();
            let req = NewRecord {
                serial: (!serial.is_empty()).then_some(serial),
                ..NewRecord::new(&text)
            };
            match old {
                Some(o) => s.supersede_as(&actor, o, &req, &sub.reason),
                None => s.submit(&actor, &req),
            }
        })
        .await;
    app.after_write(&done).await;
    match done {
        Ok(a) => (
            StatusCode::SEE_OTHER,
            [(LOCATION, format!("/records/{}", a.id))],
        )
            .into_response(),
        Err(e) => store_error(&e),
    }
}

/// The two records compared.
#[derive(Deserialize)]
pub struct CompareQuery {
    a: i64,
    b: i64,
}

/// `GET /compare?a=ID&b=ID`: record `a` against the reference `b`,
/// coefficient by coefficient, with En.
pub async fn compare(
    State(app): State<Shared>,
    user: User,
    Query(q): Query<CompareQuery>,
) -> Response {
    let read = app
        .with_store(move |s| {
            Ok::<_, incal_records::Error>((s.show(q.a)?.document, s.show(q.b)?.document))
        })
        .await;
    let (ta, tb) = match read {
        Ok(x) => x,
        Err(e) => return store_error(&e),
    };
    let parse = |t: &str, id: i64| {
        incal::document::ResultDocument::from_json(t).map_err(|e| {
            error(
                StatusCode::UNPROCESSABLE_ENTITY,
                &format!("record {id}: {e}"),
            )
        })
    };
    let (da, db) = match (parse(&ta, q.a), parse(&tb, q.b)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(r), _) | (_, Err(r)) => return r,
    };
    let (na, nb) = (format!("record {}", q.a), format!("record {}", q.b));
    let cmp = match incal::document::compare::compare_documents(&na, &da, &nb, &db) {
        Ok(c) => c,
        Err(e) => return error(StatusCode::UNPROCESSABLE_ENTITY, &e.to_string()),
    };
    let mut rows = Vec::new();
    for (name, x) in da.coefficients.iter() {
        let Some(y) = db.coefficients.get(name) else {
            continue;
        };
        let c = incal::document::compare::compare(x, y);
        // Digits follow the uncertainty (GUM 7.2.6): each value to its own
        // u's second digit, the difference to the finer of the two.
        let (va, _, ua) = incal_report::format::measured(x.value, x.u, x.u95);
        let (vb, _, ub) = incal_report::format::measured(y.value, y.u, y.u95);
        let (d, _, _) = incal_report::format::measured(c.difference, x.u.min(y.u), 0.0);
        rows.push(CompareRow {
            name: name.to_string(),
            a: va,
            u95_a: ua,
            b: vb,
            u95_b: ub,
            difference: d,
            en: c
                .en
                .map(|e| format!("{e:.2}"))
                .unwrap_or_else(|| "-".into()),
            class: if c.en.is_some_and(|e| e.abs() > 1.0) {
                "fail"
            } else {
                "pass"
            }
            .into(),
        });
    }
    drop(cmp);
    render(&Compare {
        p: page(
            &app,
            &user,
            &format!(
                "{}: record {} against record {}",
                da.instrument.serial.as_deref().unwrap_or("-"),
                q.a,
                q.b
            ),
        )
        .await,
        a: q.a,
        b: q.b,
        convention: incal::document::compare::CONVENTION.into(),
        rows,
    })
}
