//! Instruments: the list with due dates, one instrument's calibrations,
//! and the history of one of its coefficients.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::response::Response;
use incal_records::{time, RecordSummary, Review, State as Rs};
use serde::Deserialize;

use crate::auth::User;
use crate::pages::{error, page, render, store_error, url};
use crate::views::{History, Instrument, InstrumentRow, Instruments, RecordRow};
use crate::Shared;

const DAY: i64 = 86_400;

/// Where an instrument stands against its recall interval.
pub struct Due {
    /// The last calibration that counts (approved or awaiting review, not
    /// rejected or superseded), its date and review state.
    pub last: Option<(String, Rs)>,
    /// `YYYY-MM-DD` the next is due.
    pub due: String,
    /// `overdue`, `due soon`, `current`, or `no calibration`.
    pub status: &'static str,
}

/// The due date of an instrument with `records`, recalled every
/// `recall_days`, due soon within `soon_days`, at `now` (Unix seconds).
pub fn due_of(
    records: &[&RecordSummary],
    reviews: &HashMap<i64, Review>,
    recall_days: i64,
    soon_days: i64,
    now: i64,
) -> Due {
    let last = records
        .iter()
        .filter_map(|r| {
            let st = reviews.get(&r.id).map_or(Rs::Submitted, |v| v.state);
            matches!(st, Rs::Approved | Rs::Submitted).then(|| (r.created_utc.clone(), st))
        })
        .max_by(|a, b| a.0.cmp(&b.0));
    let Some((when, st)) = last else {
        return Due {
            last: None,
            due: "-".into(),
            status: "no calibration",
        };
    };
    let t = time::parse_utc(&when).unwrap_or(now);
    let due_t = t + recall_days * DAY;
    let status = if due_t < now {
        "overdue"
    } else if due_t - now <= soon_days * DAY {
        "due soon"
    } else {
        "current"
    };
    Due {
        last: Some((when, st)),
        due: time::format_utc(due_t).chars().take(10).collect(),
        status,
    }
}

/// The class a status is shown with.
fn status_class(s: &str) -> &'static str {
    match s {
        "overdue" | "no calibration" => "overdue",
        "due soon" => "due",
        _ => "ok",
    }
}

/// The filter of the list.
#[derive(Deserialize, Default)]
pub struct ListQuery {
    #[serde(default)]
    q: String,
    #[serde(default)]
    show: String,
}

/// `GET /`: every instrument with its last calibration and next due date;
/// filtered by text (`q`, in serial or model) and by `show` (`overdue`,
/// `due`: overdue or due soon, `all`).
pub async fn list(State(app): State<Shared>, user: User, Query(f): Query<ListQuery>) -> Response {
    let read = app
        .with_store(|s| {
            Ok::<_, incal_records::Error>((s.instruments()?, s.list(None)?, s.reviews()?))
        })
        .await;
    let (instruments, records, reviews) = match read {
        Ok(x) => x,
        Err(e) => return store_error(&e),
    };
    let mut by_serial: HashMap<&str, Vec<&RecordSummary>> = HashMap::new();
    for r in &records {
        by_serial.entry(r.serial.as_str()).or_default().push(r);
    }
    let now = time::parse_utc(&time::now_utc()).unwrap_or(0);
    let needle = f.q.to_lowercase();
    let total = instruments.len();
    let mut rows = Vec::new();
    for (serial, model) in &instruments {
        let recs = by_serial.get(serial.as_str()).cloned().unwrap_or_default();
        let days = app
            .config
            .recall
            .days(serial, model.as_deref(), app.config.recall_days);
        let d = due_of(&recs, &reviews, days, app.config.due_soon_days, now);
        let model = model.clone().unwrap_or_default();
        let text_ok = needle.is_empty()
            || serial.to_lowercase().contains(&needle)
            || model.to_lowercase().contains(&needle);
        let show_ok = match f.show.as_str() {
            "overdue" => matches!(d.status, "overdue" | "no calibration"),
            "due" => d.status != "current",
            _ => true,
        };
        if !(text_ok && show_ok) {
            continue;
        }
        let procs: BTreeSet<&str> = recs.iter().map(|r| r.procedure.as_str()).collect();
        let (last, state) = match &d.last {
            Some((w, s)) => (w.clone(), s.as_str().to_string()),
            None => ("-".into(), "-".into()),
        };
        rows.push(InstrumentRow {
            serial: serial.clone(),
            serial_url: url(serial),
            model,
            procedures: procs.into_iter().collect::<Vec<_>>().join(", "),
            last,
            state,
            due: d.due,
            status: d.status.into(),
            status_class: status_class(d.status).into(),
            recall_days: days,
        });
    }
    let shows = [
        ("all", "all instruments"),
        ("due", "overdue or due soon"),
        ("overdue", "overdue only"),
    ]
    .iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect();
    render(&Instruments {
        p: page(&app, &user, "Instruments").await,
        q: f.q,
        show: if f.show.is_empty() {
            "all".into()
        } else {
            f.show
        },
        shows,
        recall_days: app.config.recall_days,
        due_soon_days: app.config.due_soon_days,
        total,
        rows,
    })
}

/// What a list needs of a result document: its coefficients' names and
/// its verdicts, read without building the rest.
#[derive(Deserialize)]
pub struct Summary {
    #[serde(default)]
    coefficients: BTreeMap<String, serde::de::IgnoredAny>,
    #[serde(default)]
    verdicts: Option<BTreeMap<String, VerdictOnly>>,
}

#[derive(Deserialize)]
struct VerdictOnly {
    verdict: String,
}

impl Summary {
    /// The summary of a stored document (`None`: not readable).
    pub fn of(document: &str) -> Option<Summary> {
        serde_json::from_str(document).ok()
    }

    /// The coefficients' names.
    pub fn names(&self) -> impl Iterator<Item = &String> {
        self.coefficients.keys()
    }
}

/// The verdicts of a result document in one line, and its class.
pub fn verdict_line(doc: Option<&Summary>) -> (String, String) {
    let Some(doc) = doc else {
        return ("unreadable".into(), "fail".into());
    };
    let Some(v) = &doc.verdicts else {
        return ("no limits".into(), String::new());
    };
    let failed: Vec<String> = v
        .iter()
        .filter(|(_, x)| x.verdict != "pass")
        .map(|(n, x)| format!("{n} {}", x.verdict))
        .collect();
    if failed.is_empty() {
        (format!("pass ({} limits)", v.len()), "pass".into())
    } else {
        (format!("not pass: {}", failed.join(", ")), "fail".into())
    }
}

/// `GET /instruments/{serial}`.
pub async fn one(State(app): State<Shared>, user: User, Path(serial): Path<String>) -> Response {
    let s2 = serial.clone();
    let read = app
        .with_store(move |s| {
            let model = s.instrument(&s2)?;
            let recs = s.list(Some(&s2))?;
            let mut docs = Vec::new();
            for r in &recs {
                docs.push(s.show(r.id)?.document);
            }
            Ok::<_, incal_records::Error>((model, recs, docs, s.reviews_of(&s2)?))
        })
        .await;
    let (model, recs, docs, reviews) = match read {
        Ok(x) => x,
        Err(e) => return store_error(&e),
    };
    let Some(model) = model else {
        return error(
            StatusCode::NOT_FOUND,
            &format!("no instrument '{}'", incal_io::clip(&serial)),
        );
    };
    let now = time::parse_utc(&time::now_utc()).unwrap_or(0);
    let refs: Vec<&RecordSummary> = recs.iter().collect();
    let days = app
        .config
        .recall
        .days(&serial, model.as_deref(), app.config.recall_days);
    let d = due_of(&refs, &reviews, days, app.config.due_soon_days, now);
    let mut coefficients = BTreeMap::new();
    let mut rows = Vec::new();
    for (r, text) in recs.iter().zip(&docs) {
        let summary = Summary::of(text);
        for name in summary.iter().flat_map(Summary::names) {
            coefficients.insert(name.to_string(), url(name));
        }
        let (verdicts, verdict_class) = verdict_line(summary.as_ref());
        rows.push(RecordRow {
            id: r.id,
            procedure: r.procedure.clone(),
            created: r.created_utc.clone(),
            operator: r.operator.clone().unwrap_or_default(),
            state: reviews
                .get(&r.id)
                .map_or("submitted", |v| v.state.as_str())
                .into(),
            verdicts,
            verdict_class,
        });
    }
    render(&Instrument {
        p: page(&app, &user, &format!("Instrument {serial}")).await,
        serial_url: url(&serial),
        model: model.unwrap_or_else(|| "model not recorded".into()),
        recall_days: days,
        due: d.due,
        status: d.status.into(),
        status_class: status_class(d.status).into(),
        rows,
        coefficients: coefficients.into_iter().collect(),
    })
}

/// The coefficient asked for.
#[derive(Deserialize)]
pub struct HistoryQuery {
    #[serde(default)]
    coefficient: String,
}

/// `GET /instruments/{serial}/history?coefficient=NAME`: the plot of the
/// coefficient across the calibrations (U95 bars, drift band, limits of
/// the latest result), the table, drift and notes.
pub async fn history(
    State(app): State<Shared>,
    user: User,
    Path(serial): Path<String>,
    Query(q): Query<HistoryQuery>,
) -> Response {
    let (s2, c2) = (serial.clone(), q.coefficient.clone());
    let read = app
        .with_store(move |s| {
            let h = s.history(&s2, &c2)?;
            let last = h.points.last().map(|p| s.show(p.id)).transpose()?;
            Ok::<_, incal_records::Error>((h, last))
        })
        .await;
    let (h, last) = match read {
        Ok(x) => x,
        Err(e) => return store_error(&e),
    };
    let limits = last
        .and_then(|r| incal::document::ResultDocument::from_json(&r.document).ok())
        .and_then(|d| {
            d.verdicts
                .and_then(|v| v.get(&q.coefficient).map(|x| (x.min, x.max)))
        });
    let series = incal_report::HistorySeries {
        coefficient: q.coefficient.clone(),
        unit: h.unit.clone(),
        points: h
            .points
            .iter()
            .map(|p| incal_report::HistoryPoint {
                id: p.id,
                created_utc: p.created_utc.clone(),
                value: p.value,
                u95: p.u95,
            })
            .collect(),
        min: limits.and_then(|l| l.0),
        max: limits.and_then(|l| l.1),
        drift: h.drift.as_ref().map(|d| incal_report::DriftLine {
            intercept: d.intercept,
            rate_per_day: d.value,
            covariance: d.covariance,
            k95: incal::estimation::coverage_factor(d.dof.unwrap_or(f64::INFINITY), 0.95),
        }),
    };
    let svg = if series.points.is_empty() {
        String::new()
    } else {
        incal_report::plots::render_svg(&incal_report::plots::history_plot(&series))
            .unwrap_or_default()
    };
    let drift = h
        .drift
        .as_ref()
        .map(|d| {
            let k = incal::estimation::coverage_factor(d.dof.unwrap_or(f64::INFINITY), 0.95);
            let (v, u, u95) = incal_report::format::measured(d.value, d.u, k * d.u);
            format!("{v} {}, u {u}, U95 {u95}", d.unit)
        })
        .unwrap_or_default();
    render(&History {
        p: page(
            &app,
            &user,
            &format!("{serial}: history of {}", q.coefficient),
        )
        .await,
        serial_url: url(&serial),
        serial,
        svg,
        unit: h.unit.to_string(),
        points: h
            .points
            .iter()
            .map(|p| {
                let (v, _, u95) = incal_report::format::measured(p.value, p.u, p.u95);
                (p.id, p.created_utc.clone(), v, u95)
            })
            .collect(),
        notes: h.notes.clone(),
        drift,
    })
}
