//! The web application's behaviour and security, driven in process: no
//! page without a session, roles, CSRF, escaping of every stored field,
//! inert injection strings, session fixation and replayed cookies, path
//! traversal, throttled logins, the workflow to a certificate, a broken
//! chain.

mod common;

use axum::http::StatusCode;
use common::{doc, lab, logged_in, token, Client, PASSWORD};

/// Every page and download, as a GET.
const PAGES: &[&str] = &[
    "/",
    "/?show=overdue",
    "/instruments/SN-1",
    "/instruments/SN-1/history?coefficient=K0",
    "/compare?a=7&b=9",
    "/records/7",
    "/records/7/document.json",
    "/records/7/certificate",
    "/records/7/certificate.pdf",
    "/records/7/certificate.xml",
    "/submit",
    "/events",
    "/users",
    "/no/such/page",
];

/// Every state-changing form.
const FORMS: &[&str] = &[
    "/records/7/approve",
    "/records/7/reject",
    "/submit",
    "/users",
    "/logout",
];

#[tokio::test]
async fn nothing_is_readable_without_a_login() {
    let (_, app) = lab("anonymous");
    let mut c = Client::new(&app);
    for p in PAGES {
        let r = c.get(p).await;
        assert_eq!(r.status, StatusCode::SEE_OTHER, "{p}");
        assert_eq!(r.location, "/login", "{p}");
        assert!(!r.body.contains("SN-1"), "{p}: {}", r.body);
    }
    for p in FORMS {
        let r = c.post(p, &[("csrf", "x")]).await;
        assert!(
            matches!(r.status, StatusCode::UNAUTHORIZED | StatusCode::FORBIDDEN),
            "{p}: {}",
            r.status
        );
    }
    let r = Client::new(&app).get("/health").await;
    assert_eq!((r.status, r.body.as_str()), (StatusCode::OK, "ok\n"));
    let r = c.get("/login").await;
    assert_eq!(r.status, StatusCode::OK);
    assert!(!r.body.contains("SN-1") && !r.body.contains("records,"));
}

#[tokio::test]
async fn cookies_are_http_only_and_strict() {
    let (_, app) = lab("cookies");
    let mut c = Client::new(&app);
    let r = c.get("/login").await;
    assert_eq!(r.cookies.len(), 1);
    let k = &r.cookies[0];
    assert!(
        k.contains("HttpOnly") && k.contains("SameSite=Strict"),
        "{k}"
    );
    let r = c.login("eve").await;
    assert!(r.cookies[0].contains("HttpOnly") && r.cookies[0].contains("SameSite=Strict"));
}

#[tokio::test]
async fn roles_limit_what_each_may_do() {
    let (_, app) = lab("roles");
    let mut vic = logged_in(&app, "vic").await;
    assert_eq!(vic.get("/").await.status, StatusCode::OK);
    assert_eq!(vic.get("/submit").await.status, StatusCode::FORBIDDEN);
    assert_eq!(vic.get("/users").await.status, StatusCode::FORBIDDEN);
    let csrf = vic.csrf("/records/9").await;
    let r = vic
        .post_multipart(
            "/submit",
            &[
                ("csrf", &csrf),
                ("document", &doc("SN-2", 0.1, "v", "v.csv")),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::FORBIDDEN, "{}", r.body);
    let r = vic.post("/records/9/approve", &[("csrf", &csrf)]).await;
    assert_eq!(r.status, StatusCode::FORBIDDEN);
    let r = vic
        .post(
            "/users",
            &[
                ("csrf", &csrf),
                ("username", "vic"),
                ("action", "role"),
                ("role", "admin"),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::FORBIDDEN);
    // An engineer submits but does not approve.
    let mut ed = logged_in(&app, "ed").await;
    let csrf = ed.csrf("/records/9").await;
    assert!(!ed.get("/records/9").await.body.contains("id=\"approve\""));
    assert_eq!(
        ed.post("/records/9/approve", &[("csrf", &csrf)])
            .await
            .status,
        StatusCode::FORBIDDEN
    );
    // A signatory does not approve their own submission.
    let mut sam = logged_in(&app, "sam").await;
    let csrf = sam.csrf("/submit").await;
    let r = sam
        .post_multipart(
            "/submit",
            &[
                ("csrf", &csrf),
                ("document", &doc("SN-3", 0.2, "s", "s.csv")),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "{}", r.body);
    let own = r.location.clone();
    assert!(!sam.get(&own).await.body.contains("id=\"approve\""));
    let r = sam
        .post(&format!("{own}/approve"), &[("csrf", &csrf)])
        .await;
    assert_eq!(r.status, StatusCode::UNPROCESSABLE_ENTITY);
    assert!(r.body.contains("approved by someone else"), "{}", r.body);
    // The admin manages accounts but does not approve.
    let mut ada = logged_in(&app, "ada").await;
    let csrf = ada.csrf("/users").await;
    assert_eq!(
        ada.post("/records/9/approve", &[("csrf", &csrf)])
            .await
            .status,
        StatusCode::FORBIDDEN
    );
    let r = ada
        .post(
            "/users",
            &[("csrf", &csrf), ("username", "ed"), ("action", "disable")],
        )
        .await;
    assert_eq!(r.status, StatusCode::OK, "{}", r.body);
    // A disabled account's session ends at its next request.
    assert_eq!(ed.get("/").await.location, "/login");
    assert_eq!(
        Client::new(&app).login("ed").await.status,
        StatusCode::UNAUTHORIZED
    );
    // The role change is in the chain.
    let r = ada.get("/events").await;
    assert!(r.body.contains("user.disable"), "{}", r.body);
}

#[tokio::test]
async fn a_form_without_its_csrf_token_is_refused() {
    let (_, app) = lab("csrf");
    let mut sam = logged_in(&app, "sam").await;
    let mut sue = logged_in(&app, "sue").await;
    let other = sue.csrf("/").await;
    for fields in [vec![], vec![("csrf", "")], vec![("csrf", other.as_str())]] {
        let r = sam.post("/records/9/approve", &fields).await;
        assert_eq!(r.status, StatusCode::FORBIDDEN, "{fields:?}");
        let r = sam
            .post(
                "/records/9/reject",
                &[fields.as_slice(), &[("reason", "x")]].concat(),
            )
            .await;
        assert_eq!(r.status, StatusCode::FORBIDDEN);
        let r = sam.post("/logout", &fields).await;
        assert_eq!(r.status, StatusCode::FORBIDDEN);
        let r = sam
            .post_multipart(
                "/submit",
                &[
                    fields.as_slice(),
                    &[("document", &doc("SN-4", 0.3, "c", "c.csv"))],
                ]
                .concat(),
            )
            .await;
        assert_eq!(r.status, StatusCode::FORBIDDEN);
    }
    let mut anon = Client::new(&app);
    anon.get("/login").await;
    let r = anon
        .post("/login", &[("username", "sam"), ("password", PASSWORD)])
        .await;
    assert_eq!(r.status, StatusCode::FORBIDDEN);
    // Nothing was written.
    assert_eq!(
        sam.get("/records/9").await.body.matches("record.").count(),
        1
    );
}

#[tokio::test]
async fn session_fixation_and_replayed_logout_cookies_are_refused() {
    let (_, app) = lab("fixation");
    // The attacker's anonymous session, planted in the victim's browser.
    let mut attacker = Client::new(&app);
    attacker.get("/login").await;
    let planted = attacker.cookie.clone().unwrap();
    let mut victim = Client {
        app: app.clone(),
        cookie: Some(planted.clone()),
    };
    let r = victim.login("sam").await;
    assert_eq!(r.status, StatusCode::SEE_OTHER);
    assert_ne!(
        victim.cookie.as_deref(),
        Some(planted.as_str()),
        "a login gets a new id"
    );
    assert_eq!(attacker.get("/").await.location, "/login");
    // Logout ends the session on the server: the old cookie is worthless.
    let held = victim.cookie.clone();
    let csrf = victim.csrf("/").await;
    let r = victim.post("/logout", &[("csrf", &csrf)]).await;
    assert_eq!(r.status, StatusCode::SEE_OTHER);
    assert!(r.cookies[0].contains("Max-Age=0"));
    let mut replay = Client {
        app: app.clone(),
        cookie: held,
    };
    let r = replay.get("/").await;
    assert_eq!(r.location, "/login");
    // A forged cookie opens nothing either.
    let mut forged = Client {
        app: app.clone(),
        cookie: Some(format!("incal_session={}", "a".repeat(64))),
    };
    assert_eq!(forged.get("/events").await.location, "/login");
}

#[tokio::test]
async fn a_password_set_on_the_store_ends_open_sessions() {
    let (path, app) = lab("passwd");
    let mut eve = logged_in(&app, "eve").await;
    let mut sam = logged_in(&app, "sam").await;
    assert_eq!(eve.get("/events").await.status, StatusCode::OK);
    // As `incal user passwd eve` does: on the store, behind the server.
    let mut s = incal_records::Store::open(&path).unwrap();
    let hash = incal_web::password::hash("a new passphrase for eve").unwrap();
    s.set_password(&incal_records::Actor::console("root"), "eve", &hash)
        .unwrap();
    drop(s);
    assert_eq!(eve.get("/events").await.location, "/login");
    // The session is gone, not only refused once.
    assert_eq!(eve.get("/").await.location, "/login");
    // Another account's session is untouched; the old password opens
    // nothing, the new one does.
    assert_eq!(sam.get("/events").await.status, StatusCode::OK);
    let mut again = Client::new(&app);
    assert_eq!(again.login("eve").await.status, StatusCode::UNAUTHORIZED);
    let csrf = again.csrf("/login").await;
    let r = again
        .post(
            "/login",
            &[
                ("csrf", &csrf),
                ("username", "eve"),
                ("password", "a new passphrase for eve"),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "{}", r.body);
    assert_eq!(again.get("/events").await.status, StatusCode::OK);
}

#[tokio::test]
async fn brute_force_is_throttled() {
    let (_, app) = lab("throttle");
    let mut c = Client::new(&app);
    for _ in 0..5 {
        let csrf = c.csrf("/login").await;
        let r = c
            .post(
                "/login",
                &[
                    ("csrf", &csrf),
                    ("username", "sue"),
                    ("password", "guess guess guess"),
                ],
            )
            .await;
        assert_eq!(r.status, StatusCode::UNAUTHORIZED);
    }
    let r = c.login("sue").await;
    assert_eq!(
        r.status,
        StatusCode::TOO_MANY_REQUESTS,
        "the right password is refused too"
    );
    // Per address too: another account from the same address.
    let r = c.login("sam").await;
    assert_eq!(r.status, StatusCode::TOO_MANY_REQUESTS);
}

#[tokio::test]
async fn traversal_and_injection_strings_are_inert() {
    let (_, app) = lab("inject");
    let mut c = logged_in(&app, "vic").await;
    for p in [
        "/records/..%2F..%2Fetc%2Fpasswd/document.json",
        "/records/7/../../../../etc/passwd",
        "/records/7%20OR%201=1/document.json",
        "/records/-1/document.json",
        "/records/99999999999999999999/certificate",
        "/instruments/..%2F..%2Fetc%2Fpasswd",
        "/instruments/SN-1'%20OR%20'1'='1",
        "/compare?a=7%20OR%201=1&b=9",
    ] {
        let r = c.get(p).await;
        assert!(r.status.is_client_error(), "{p}: {}", r.status);
        assert!(!r.body.contains("root:"), "{p}");
        assert!(!r.body.contains("\"schema\""), "{p}: a document leaked");
    }
    for q in [
        "' OR 1=1 --",
        "SN-1'; DROP TABLE records; --",
        "%' OR '%'='",
    ] {
        let r = c.get(&format!("/?q={}", incal_web::pages::url(q))).await;
        assert_eq!(r.status, StatusCode::OK);
        assert!(r.body.contains("0 of 1 instruments"), "{q}");
    }
    let r = c
        .get("/instruments/SN-1/history?coefficient=K0'%20OR%201=1--")
        .await;
    assert!(r.status.is_client_error());
    assert!(c.get("/").await.body.contains("1 of 1 instruments"));
}

#[tokio::test]
async fn the_workflow_reaches_a_certificate() {
    let (_, app) = lab("workflow");
    let mut eve = logged_in(&app, "eve").await;
    let csrf = eve.csrf("/submit").await;
    let r = eve
        .post_multipart(
            "/submit",
            &[
                ("csrf", &csrf),
                ("document", &doc("SN-9", 0.5, "eve", "e.csv")),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "{}", r.body);
    let rec = r.location;
    assert_eq!(
        eve.get(&format!("{rec}/certificate")).await.status,
        StatusCode::CONFLICT
    );
    // The same document again is the record already held.
    let r = eve
        .post_multipart(
            "/submit",
            &[
                ("csrf", &csrf),
                ("document", &doc("SN-9", 0.5, "eve", "e.csv")),
            ],
        )
        .await;
    assert_eq!(r.location, rec);
    let mut sam = logged_in(&app, "sam").await;
    let page = sam.get(&rec).await.body;
    assert!(page.contains("id=\"approve\""));
    let r = sam
        .post(
            &format!("{rec}/approve"),
            &[("csrf", &token(&page)), ("reason", "checked")],
        )
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "{}", r.body);
    let page = sam.get(&rec).await.body;
    assert!(page.contains("approved by sam (signatory)"), "{page}");
    let cert = sam.get(&format!("{rec}/certificate")).await;
    assert_eq!(cert.status, StatusCode::OK);
    assert!(cert.body.contains("SN-9"));
    // A rejection needs a reason; a decided record is not decided again.
    let r = sam
        .post(
            "/records/9/reject",
            &[("csrf", &token(&page)), ("reason", " ")],
        )
        .await;
    assert_eq!(r.status, StatusCode::UNPROCESSABLE_ENTITY);
    let r = sam
        .post(
            &format!("{rec}/reject"),
            &[("csrf", &token(&page)), ("reason", "late")],
        )
        .await;
    assert_eq!(r.status, StatusCode::UNPROCESSABLE_ENTITY);
    assert!(r.body.contains("is approved"));
    // The instrument list shows it, due in a year.
    let list = sam.get("/").await.body;
    assert!(list.contains("SN-9") && list.contains("current"), "{list}");
    // SN-1's last calibration is current; with a short recall it is overdue.
    assert!(sam
        .get("/?show=overdue")
        .await
        .body
        .contains("0 of 2 instruments"));
}

#[tokio::test]
async fn every_stored_field_is_escaped_on_every_page() {
    let (_, app) = lab("escape");
    let x = "<script>alert(1)</script><img src=x onerror=alert(2)>\"'&";
    let mut eve = logged_in(&app, "eve").await;
    let csrf = eve.csrf("/submit").await;
    let d = doc(x, 0.7, x, x);
    let r = eve
        .post_multipart("/submit", &[("csrf", &csrf), ("document", &d)])
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "{}", r.body);
    let rec = r.location.clone();
    let fix = doc(x, 0.71, x, x);
    let r = eve
        .post_multipart(
            "/submit",
            &[
                ("csrf", &csrf),
                ("document", &fix),
                ("supersedes", rec.trim_start_matches("/records/")),
                ("reason", x),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "{}", r.body);
    let fixed = r.location.clone();
    let mut sam = logged_in(&app, "sam").await;
    let page = sam.get(&fixed).await.body;
    let r = sam
        .post(
            &format!("{fixed}/reject"),
            &[("csrf", &token(&page)), ("reason", x)],
        )
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER);
    let serial = incal_web::pages::url(x);
    let mut ada = logged_in(&app, "ada").await;
    let csrf = ada.csrf("/users").await;
    let r = ada
        .post(
            "/users",
            &[
                ("csrf", &csrf),
                ("username", x),
                ("action", "add"),
                ("role", "viewer"),
                ("password", PASSWORD),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::UNPROCESSABLE_ENTITY);
    for p in [
        "/".to_string(),
        format!("/?q={serial}"),
        format!("/instruments/{serial}"),
        format!("/instruments/{serial}/history?coefficient=K0"),
        rec.clone(),
        fixed.clone(),
        "/events".into(),
        format!(
            "/compare?a={}&b={}",
            fixed.trim_start_matches("/records/"),
            rec.trim_start_matches("/records/")
        ),
    ] {
        for (who, c) in [("sam", &mut sam), ("ada", &mut ada)] {
            let r = c.get(&p).await;
            assert_eq!(r.status, StatusCode::OK, "{who} {p}: {}", r.body);
            assert!(!r.body.contains("<script>"), "{p}: a script tag");
            assert!(!r.body.contains("<img"), "{p}: an img tag");
            // Inside an attribute a quote would end it: every quote of
            // the payload is escaped there too.
            assert!(!r.body.contains("onerror=alert(2)>\""), "{p}: {}", r.body);
            let shown = ["&lt;script&gt;", "&#60;script&#62;"]
                .iter()
                .any(|e| r.body.contains(e));
            assert!(
                shown || p == "/events",
                "{p}: the payload is shown escaped: {}",
                r.body
            );
        }
    }
    let r = ada.get("/users").await;
    assert!(!r.body.contains("<script>"));
}

#[tokio::test]
async fn a_broken_chain_is_shown_and_refuses_writes() {
    let (path, app) = lab("broken");
    let mut eve = logged_in(&app, "eve").await;
    assert!(eve.get("/").await.body.contains("Chain intact"));
    let c = rusqlite::Connection::open(&path).unwrap();
    c.execute_batch("UPDATE events SET role = 'admin' WHERE username = 'eve'")
        .unwrap();
    drop(c);
    let csrf = eve.csrf("/submit").await;
    let r = eve
        .post_multipart(
            "/submit",
            &[
                ("csrf", &csrf),
                ("document", &doc("SN-5", 0.4, "x", "x.csv")),
            ],
        )
        .await;
    assert_eq!(r.status, StatusCode::CONFLICT, "{}", r.body);
    let page = eve.get("/").await.body;
    assert!(
        page.contains("CHAIN BROKEN") && page.contains("class=\"broken\""),
        "{page}"
    );
    assert_eq!(
        Client::new(&app).get("/health").await.status,
        StatusCode::SERVICE_UNAVAILABLE
    );
}

#[tokio::test]
async fn the_dcc_of_an_approved_record_names_its_approver() {
    let (path, app) = lab("dcc");
    let mut sam = logged_in(&app, "sam").await;
    let page = sam.get("/records/9").await.body;
    let r = sam
        .post("/records/9/approve", &[("csrf", &token(&page))])
        .await;
    assert_eq!(r.status, StatusCode::SEE_OTHER);
    // Without --lab there is no laboratory to name.
    assert_eq!(
        sam.get("/records/9/certificate.xml").await.status,
        StatusCode::CONFLICT
    );
    let toml = path.with_file_name("lab.toml");
    std::fs::write(
        &toml,
        "[lab]\nname = \"ITL\"\naddress = \"1 Gyro Road\"\ncertificate_prefix = \"ITL-\"\ncountry = \"CN\"\n\n[[signatory]]\nname = \"Someone Else\"\nrole = \"head\"\n",
    )
    .unwrap();
    let mut c = incal_web::Config::new(&path);
    c.lab = Some(toml);
    let app = incal_web::AppState::open(c).unwrap();
    let mut sam = logged_in(&app, "sam").await;
    let r = sam.get("/records/9/certificate.xml").await;
    assert_eq!(r.status, StatusCode::OK, "{}", r.body);
    assert!(r.body.contains("schemaVersion=\"3.2.0\""));
    assert!(
        r.body
            .contains("<dcc:uniqueIdentifier>ITL-000009</dcc:uniqueIdentifier>"),
        "{}",
        r.body
    );
    assert!(r.body.contains("<dcc:content>sam</dcc:content>") && !r.body.contains("Someone Else"));
    assert_eq!(
        sam.get("/records/7/certificate.xml").await.status,
        StatusCode::CONFLICT
    );
    let html = sam.get("/records/9/certificate").await.body;
    assert!(html.contains("sam") && !html.contains("Someone Else"));
}

#[tokio::test]
async fn recall_intervals_per_model_and_instrument() {
    let (path, _) = lab("recall");
    let mut c = incal_web::Config::new(&path);
    c.recall = incal_web::state::Recall::parse(
        "recall.toml",
        "[model]\n\"lee model\" = 3650\n[serial]\n\"SN-1\" = 1\n",
    )
    .unwrap();
    let app = incal_web::AppState::open(c).unwrap();
    let mut vic = logged_in(&app, "vic").await;
    // SN-1 (model "lee model") is recalled daily: its last calibration,
    // stored today, is due tomorrow.
    let r = vic.get("/?show=due").await.body;
    assert!(
        r.contains("1 of 1 instruments") && r.contains("due soon"),
        "{r}"
    );
    assert!(vic
        .get("/instruments/SN-1")
        .await
        .body
        .contains("Recall interval 1 days"));
    for bad in [
        "[model]\n\"x\" = 0\n",
        "[models]\n",
        "[serial]\n\"x\" = \"soon\"\n",
    ] {
        let e = incal_web::state::Recall::parse("recall.toml", bad).unwrap_err();
        assert!(e.starts_with("recall.toml: "), "{e}");
    }
}

#[tokio::test]
async fn the_proxy_header_is_believed_from_the_proxy_only() {
    use axum::body::Body;
    use axum::extract::ConnectInfo;
    use axum::http::Request;
    use tower::ServiceExt;
    let (path, _) = lab("proxy");
    let mut c = incal_web::Config::new(&path);
    c.trusted_proxy = Some("127.0.0.1".parse().unwrap());
    let app = incal_web::AppState::open(c).unwrap();
    let ask = |from: &str, user: &str| {
        let mut req = Request::builder()
            .uri("/events")
            .header("X-Remote-User", user)
            .body(Body::empty())
            .unwrap();
        let addr: std::net::SocketAddr = format!("{from}:50000").parse().unwrap();
        req.extensions_mut().insert(ConnectInfo(addr));
        incal_web::router(app.clone()).oneshot(req)
    };
    let r = ask("127.0.0.1", "sam").await.unwrap();
    assert_eq!(
        r.status(),
        StatusCode::OK,
        "from the proxy: logged in as sam"
    );
    let r = ask("10.0.0.5", "sam").await.unwrap();
    assert_eq!(
        r.status(),
        StatusCode::SEE_OTHER,
        "from elsewhere the header is ignored"
    );
    let r = ask("127.0.0.1", "nobody").await.unwrap();
    assert_eq!(
        r.status(),
        StatusCode::SEE_OTHER,
        "an unknown account is not logged in"
    );
}
