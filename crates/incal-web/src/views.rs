//! The pages' templates (askama: every `{{ field }}` is HTML-escaped; the
//! only unescaped fields are the SVG plot and links this crate writes
//! itself from escaped text).

use askama::Template;
use incal_records::{Account, Event, InputHash};

/// What every page shows around its content.
#[derive(Debug, Clone, Default)]
pub struct Page {
    pub title: String,
    pub user: String,
    pub role: String,
    pub csrf: String,
    pub may_submit: bool,
    pub is_admin: bool,
    pub chain_ok: bool,
    pub chain_text: String,
}

#[derive(Template)]
#[template(path = "login.html")]
pub struct Login {
    pub p: Page,
    pub message: String,
}

#[derive(Template)]
#[template(path = "error.html")]
pub struct ErrorPage {
    pub p: Page,
    pub message: String,
}

pub struct InstrumentRow {
    pub serial: String,
    pub serial_url: String,
    pub model: String,
    pub procedures: String,
    pub last: String,
    pub state: String,
    pub due: String,
    pub status: String,
    pub status_class: String,
    pub recall_days: i64,
}

#[derive(Template)]
#[template(path = "instruments.html")]
pub struct Instruments {
    pub p: Page,
    pub q: String,
    pub show: String,
    pub shows: Vec<(String, String)>,
    pub recall_days: i64,
    pub due_soon_days: i64,
    pub total: usize,
    pub rows: Vec<InstrumentRow>,
}

pub struct RecordRow {
    pub id: i64,
    pub procedure: String,
    pub created: String,
    pub operator: String,
    pub state: String,
    pub verdicts: String,
    pub verdict_class: String,
}

#[derive(Template)]
#[template(path = "instrument.html")]
pub struct Instrument {
    pub p: Page,
    pub serial_url: String,
    pub model: String,
    pub due: String,
    pub status: String,
    pub status_class: String,
    pub recall_days: i64,
    pub rows: Vec<RecordRow>,
    /// (name, name URL-encoded)
    pub coefficients: Vec<(String, String)>,
}

#[derive(Template)]
#[template(path = "history.html")]
pub struct History {
    pub p: Page,
    pub serial: String,
    pub serial_url: String,
    pub svg: String,
    pub unit: String,
    /// (record, stored, value, U95)
    pub points: Vec<(i64, String, String, String)>,
    pub notes: Vec<String>,
    pub drift: String,
}

#[derive(Template)]
#[template(path = "record.html")]
pub struct Record {
    pub p: Page,
    pub id: i64,
    pub serial: String,
    pub serial_url: String,
    pub model: String,
    pub procedure: String,
    pub created: String,
    pub operator: String,
    pub station: String,
    pub submitted_by: String,
    pub state: String,
    pub decision: String,
    pub verdicts: String,
    pub verdict_class: String,
    pub prev_hash: String,
    pub record_hash: String,
    pub sha256: String,
    /// HTML made of escaped text and a link.
    pub supersedes: String,
    /// HTML: a link.
    pub superseded_by: String,
    pub inputs: Vec<InputHash>,
    pub events: Vec<Event>,
    pub may_decide: bool,
}

#[derive(Template)]
#[template(path = "submit.html")]
pub struct Submit {
    pub p: Page,
    pub message: String,
}

/// One coefficient of a comparison, as shown.
pub struct CompareRow {
    pub name: String,
    pub a: String,
    pub u95_a: String,
    pub b: String,
    pub u95_b: String,
    pub difference: String,
    pub en: String,
    pub class: String,
}

#[derive(Template)]
#[template(path = "compare.html")]
pub struct Compare {
    pub p: Page,
    pub a: i64,
    pub b: i64,
    pub convention: String,
    pub rows: Vec<CompareRow>,
}

#[derive(Template)]
#[template(path = "events.html")]
pub struct Events {
    pub p: Page,
    pub events: Vec<Event>,
}

#[derive(Template)]
#[template(path = "users.html")]
pub struct Users {
    pub p: Page,
    pub message: String,
    pub accounts: Vec<Account>,
    pub roles: Vec<&'static str>,
}
