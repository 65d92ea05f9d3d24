//! A lab on a fresh SQLite store and a client that keeps its session
//! cookie, driving the router in process (no socket).

#![allow(dead_code)]

use std::path::PathBuf;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use http_body_util::BodyExt;
use incal::document::{Coefficient, DocumentBuilder, InputFile, Procedure};
use incal::units::Unit;
use incal_records::{Actor, NewRecord, Role, Store};
use incal_web::{AppState, Config, Shared};
use tower::ServiceExt;

pub const PASSWORD: &str = "correct horse battery";

/// A fresh directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("incal-web-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A tumble result of `serial` with K0 = `k0`, operator and station,
/// input file `path`.
pub fn doc(serial: &str, k0: f64, who: &str, path: &str) -> String {
    let mut b = DocumentBuilder::new(Procedure::Tumble, "Tumble calibration (test)");
    b.coefficient(
        "K0",
        Coefficient::new("K0", k0, 1e-5, Unit::G, 20.0).unwrap(),
    )
    .unwrap();
    let mut d = b.finish();
    d.instrument.serial = Some(serial.to_string());
    d.instrument.model = Some(format!("{who} model"));
    d.instrument.meta.insert("operator".into(), who.to_string());
    d.instrument.meta.insert("station".into(), who.to_string());
    d.inputs.push(InputFile {
        role: "input".into(),
        path: path.to_string(),
        sha256: format!("{:064x}", k0.to_bits() as u128),
        rows: Some(12),
    });
    d.to_json()
}

/// A store with accounts eve (engineer), ed (engineer), sam and sue
/// (signatories), vic (viewer), ada (admin); records 7 (SN-1, 2024) and 8
/// (SN-1, now) submitted by eve.
pub fn lab(name: &str) -> (PathBuf, Shared) {
    let path = temp_dir(name).join("lab.db");
    let mut s = Store::open(&path).unwrap();
    let root = Actor::console("root");
    let hash = incal_web::password::hash(PASSWORD).unwrap();
    for (u, r) in [
        ("eve", Role::Engineer),
        ("ed", Role::Engineer),
        ("sam", Role::Signatory),
        ("sue", Role::Signatory),
        ("vic", Role::Viewer),
        ("ada", Role::Admin),
    ] {
        s.add_user(&root, u, r, &hash).unwrap();
    }
    let eve = Actor {
        name: "eve".into(),
        role: Role::Engineer,
    };
    let old = doc("SN-1", 0.01, "lee", "a.csv");
    let req = NewRecord {
        created_utc: Some("2024-01-02T00:00:00Z"),
        ..NewRecord::new(&old)
    };
    assert_eq!(s.submit(&eve, &req).unwrap().id, 7);
    let new = doc("SN-1", 0.0101, "lee", "b.csv");
    assert_eq!(s.submit(&eve, &NewRecord::new(&new)).unwrap().id, 9);
    drop(s);
    let mut c = Config::new(&path);
    c.connections = 2;
    (path.clone(), AppState::open(c).unwrap())
}

/// A response read whole.
pub struct Resp {
    pub status: StatusCode,
    pub location: String,
    pub cookies: Vec<String>,
    pub body: String,
}

/// A browser: one cookie jar.
pub struct Client {
    pub app: Shared,
    pub cookie: Option<String>,
}

impl Client {
    pub fn new(app: &Shared) -> Client {
        Client {
            app: app.clone(),
            cookie: None,
        }
    }

    pub async fn send(&mut self, req: Request<Body>) -> Resp {
        let resp = incal_web::router(self.app.clone())
            .oneshot(req)
            .await
            .unwrap();
        let status = resp.status();
        let location = resp
            .headers()
            .get(header::LOCATION)
            .map(|v| v.to_str().unwrap().to_string())
            .unwrap_or_default();
        let cookies: Vec<String> = resp
            .headers()
            .get_all(header::SET_COOKIE)
            .iter()
            .map(|v| v.to_str().unwrap().to_string())
            .collect();
        for c in &cookies {
            let kv = c.split(';').next().unwrap();
            let v = kv.split_once('=').unwrap().1;
            self.cookie = (!v.is_empty()).then(|| kv.to_string());
        }
        let bytes = resp.into_body().collect().await.unwrap().to_bytes();
        Resp {
            status,
            location,
            cookies,
            body: String::from_utf8_lossy(&bytes).to_string(),
        }
    }

    fn builder(&self, method: &str, path: &str) -> axum::http::request::Builder {
        let mut b = Request::builder().method(method).uri(path);
        if let Some(c) = &self.cookie {
            b = b.header(header::COOKIE, c);
        }
        b
    }

    pub async fn get(&mut self, path: &str) -> Resp {
        let req = self.builder("GET", path).body(Body::empty()).unwrap();
        self.send(req).await
    }

    pub async fn post(&mut self, path: &str, fields: &[(&str, &str)]) -> Resp {
        let body: Vec<String> = fields
            .iter()
            .map(|(k, v)| format!("{k}={}", incal_web::pages::url(v)))
            .collect();
        let req = self
            .builder("POST", path)
            .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
            .body(Body::from(body.join("&")))
            .unwrap();
        self.send(req).await
    }

    pub async fn post_multipart(&mut self, path: &str, fields: &[(&str, &str)]) -> Resp {
        let boundary = "XyZincalBoundary42";
        let mut body = String::new();
        for (k, v) in fields {
            let file = if *k == "document" {
                "; filename=\"r.json\""
            } else {
                ""
            };
            body.push_str(&format!(
                "--{boundary}\r\nContent-Disposition: form-data; name=\"{k}\"{file}\r\n\r\n{v}\r\n"
            ));
        }
        body.push_str(&format!("--{boundary}--\r\n"));
        let req = self
            .builder("POST", path)
            .header(
                header::CONTENT_TYPE,
                format!("multipart/form-data; boundary={boundary}"),
            )
            .body(Body::from(body))
            .unwrap();
        self.send(req).await
    }

    /// The CSRF token of the page at `path`.
    pub async fn csrf(&mut self, path: &str) -> String {
        let r = self.get(path).await;
        token(&r.body)
    }

    /// Log in as `user` (password [`PASSWORD`]).
    pub async fn login(&mut self, user: &str) -> Resp {
        let csrf = self.csrf("/login").await;
        self.post(
            "/login",
            &[("csrf", &csrf), ("username", user), ("password", PASSWORD)],
        )
        .await
    }
}

/// The first CSRF token in a page.
pub fn token(body: &str) -> String {
    let at = body
        .find("name=\"csrf\" value=\"")
        .expect("a form with a CSRF token");
    body[at + 19..at + 19 + 64].to_string()
}

/// A logged-in client.
pub async fn logged_in(app: &Shared, user: &str) -> Client {
    let mut c = Client::new(app);
    let r = c.login(user).await;
    assert_eq!(r.status, StatusCode::SEE_OTHER, "login {user}: {}", r.body);
    c
}
