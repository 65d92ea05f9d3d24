//! The server's state: its configuration, a small pool of store
//! connections used from blocking threads, the chain's status checked at
//! most every few seconds, and the sessions.

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use incal_records::{Store, Verified};

use crate::session::Sessions;

/// How `incal serve` runs.
#[derive(Debug, Clone)]
pub struct Config {
    /// The store: an SQLite path or a `postgresql://` URL.
    pub db: PathBuf,
    /// Where to listen (default `127.0.0.1:8080`).
    pub listen: SocketAddr,
    /// The laboratory profile (`lab.toml`) certificates are issued under.
    pub lab: Option<PathBuf>,
    /// Recall interval (days) of every instrument: the next calibration
    /// is due this long after the last one.
    pub recall_days: i64,
    /// Recall intervals per model and per instrument (`--recall FILE`),
    /// over `recall_days`.
    pub recall: Recall,
    /// Instruments due within this many days are listed as due soon.
    pub due_soon_days: i64,
    /// Reverse-proxy mode: the proxy's address, whose header
    /// [`Config::user_header`] names the logged-in account; from every
    /// other address the header is ignored.
    pub trusted_proxy: Option<IpAddr>,
    /// The header naming the user in reverse-proxy mode.
    pub user_header: String,
    /// Mark cookies `Secure` (served over TLS by a reverse proxy).
    pub secure_cookies: bool,
    /// Store connections kept open (one writes, the others read); 0: 4 on
    /// SQLite (the file is read in this process: more than the cores gains
    /// nothing), 12 on PostgreSQL (a read waits on the server's round trips).
    pub connections: usize,
}

impl Config {
    /// A configuration for the store `db` with every default.
    pub fn new(db: impl Into<PathBuf>) -> Config {
        Config {
            db: db.into(),
            listen: SocketAddr::from(([127, 0, 0, 1], 8080)),
            lab: None,
            recall_days: 365,
            recall: Recall::default(),
            due_soon_days: 30,
            trusted_proxy: None,
            user_header: "X-Remote-User".into(),
            secure_cookies: false,
            connections: 0,
        }
    }
}

/// Recall intervals per model and per instrument, read from a TOML file
/// (`incal serve --recall FILE`):
///
/// ```toml
/// [model]
/// "QA-2000" = 180      # days, for every instrument of this model
/// [serial]
/// "SN-042" = 90        # days, for this instrument (over its model's)
/// ```
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recall {
    /// Days per model.
    #[serde(default)]
    pub model: std::collections::BTreeMap<String, i64>,
    /// Days per serial.
    #[serde(default)]
    pub serial: std::collections::BTreeMap<String, i64>,
}

impl Recall {
    /// Read a recall file; every interval 1 to 36 500 days.
    pub fn parse(name: &str, text: &str) -> Result<Recall, String> {
        let r: Recall = toml::from_str(text).map_err(|e| {
            let first = e.to_string().lines().next().unwrap_or("").to_string();
            format!("{name}: {first}")
        })?;
        for (table, map) in [("model", &r.model), ("serial", &r.serial)] {
            for (k, d) in map {
                if !(1..=36_500).contains(d) {
                    return Err(format!(
                        "{name}: [{table}] \"{}\" = {d}: an interval is 1 to 36500 days",
                        incal_io::clip(k)
                    ));
                }
            }
        }
        Ok(r)
    }

    /// The interval of instrument `serial` of `model`: its own, else its
    /// model's, else `default`.
    pub fn days(&self, serial: &str, model: Option<&str>, default: i64) -> i64 {
        self.serial
            .get(serial)
            .or_else(|| model.and_then(|m| self.model.get(m)))
            .copied()
            .unwrap_or(default)
    }
}

/// How long a chain check is shown before it is made again.
pub const CHAIN_TTL: Duration = Duration::from_secs(30);

/// The chain's status as the footer shows it.
#[derive(Debug, Clone)]
pub enum Chain {
    /// Intact: its count and head.
    Intact(Verified),
    /// Broken (or unreadable): the message naming the first bad entry.
    Broken(String),
}

/// The state every handler shares.
pub struct AppState {
    /// The configuration.
    pub config: Config,
    /// The laboratory profile, read at start.
    pub lab: Option<incal_report::certificate::LabProfile>,
    stores: Vec<Mutex<Store>>,
    next: AtomicUsize,
    chain: Mutex<Option<(Instant, Chain)>>,
    refresh: Arc<tokio::sync::Mutex<()>>,
    writes: tokio::sync::Semaphore,
    reads: tokio::sync::Semaphore,
    /// Sessions and login failures.
    pub sessions: Sessions,
}

/// The shared state.
pub type Shared = Arc<AppState>;

impl AppState {
    /// Open `config.connections` connections to the store (created and
    /// migrated when missing) and read the lab profile.
    pub fn open(config: Config) -> Result<Shared, String> {
        let name = incal_records::store_name(&config.db);
        let mut stores = Vec::new();
        let wanted = match config.connections {
            0 if config
                .db
                .to_str()
                .is_some_and(incal_records::is_postgres_url) =>
            {
                12
            }
            0 => 4,
            n => n,
        };
        for _ in 0..wanted.max(2) {
            let s = Store::open(&config.db).map_err(|e| incal_records::store_message(&name, &e))?;
            stores.push(Mutex::new(s));
        }
        let lab = match &config.lab {
            Some(p) => {
                let text = std::fs::read_to_string(p)
                    .map_err(|e| format!("{}: cannot read ({e})", p.display()))?;
                Some(
                    incal_report::certificate::LabProfile::parse(&text)
                        .map_err(|e| format!("{}: {e}", p.display()))?,
                )
            }
            None => None,
        };
        let read_connections = stores.len().saturating_sub(1).max(1);
        Ok(Arc::new(AppState {
            config,
            lab,
            stores,
            next: AtomicUsize::new(0),
            chain: Mutex::new(None),
            refresh: Arc::new(tokio::sync::Mutex::new(())),
            writes: tokio::sync::Semaphore::new(1),
            reads: tokio::sync::Semaphore::new(read_connections),
            sessions: Sessions::default(),
        }))
    }

    /// Run `f` on one of the store connections in a blocking thread.
    pub async fn with_store<T: Send + 'static>(
        self: &Arc<Self>,
        f: impl FnOnce(&mut Store) -> T + Send + 'static,
    ) -> T {
        self.on_store(false, f).await
    }

    /// Run `f` on a store connection in a blocking thread: writes always on
    /// the first (the store skips its whole-chain check before a write when
    /// nothing but this connection has committed since its last one),
    /// reads on a free one, the others first.
    async fn on_store<T: Send + 'static>(
        self: &Arc<Self>,
        write: bool,
        f: impl FnOnce(&mut Store) -> T + Send + 'static,
    ) -> T {
        // Readers queue in order (a fair semaphore, one permit per read
        // connection), so no request waits behind later ones.
        let _permit = if write {
            None
        } else {
            self.reads.acquire().await.ok()
        };
        let me = Arc::clone(self);
        let n = me.stores.len();
        let k = if write || n == 1 {
            0
        } else {
            1 + me.next.fetch_add(1, Ordering::Relaxed) % (n - 1)
        };
        let run = move || {
            let free = if write {
                None
            } else {
                (0..n)
                    .map(|i| (k + i) % n)
                    .filter(|&j| j != 0 || n == 1)
                    .find_map(|j| me.stores[j].try_lock().ok())
            };
            let mut s = match free {
                Some(s) => s,
                None => me.stores[k].lock().unwrap_or_else(|p| p.into_inner()),
            };
            f(&mut s)
        };
        match tokio::task::spawn_blocking(run).await {
            Ok(v) => v,
            Err(e) => std::panic::resume_unwind(e.into_panic()),
        }
    }

    /// Run the write `f` on a store connection, one write at a time: the
    /// store checks the whole chain before every write and the database
    /// takes writes one by one anyway, so writers queue here and leave
    /// the other cores to the readers.
    pub async fn write_store<T: Send + 'static>(
        self: &Arc<Self>,
        f: impl FnOnce(&mut Store) -> T + Send + 'static,
    ) -> T {
        let _one = self.writes.acquire().await;
        self.on_store(true, f).await
    }

    /// After a write: a write refused on a broken chain shows it at once
    /// (the next check is made now); a write done was preceded by the
    /// store's own check of the whole chain, and the footer catches up
    /// within [`CHAIN_TTL`].
    pub async fn after_write<T>(self: &Arc<Self>, done: &Result<T, incal_records::Error>) {
        if let Err(
            incal_records::Error::Tampered { .. } | incal_records::Error::HeadMissing { .. },
        ) = done
        {
            self.chain(true).await;
        }
    }

    /// The chain's status, checked again when older than [`CHAIN_TTL`] or
    /// when `fresh` is asked for.
    pub async fn chain(self: &Arc<Self>, fresh: bool) -> Chain {
        let cached = |since: Option<Instant>| {
            let held = self.chain.lock().unwrap_or_else(|p| p.into_inner());
            held.as_ref()
                .filter(|(at, _)| at.elapsed() < CHAIN_TTL && since.is_none_or(|t| *at > t))
                .map(|(_, c)| c.clone())
        };
        let asked = Instant::now();
        if !fresh {
            if let Some(c) = cached(None) {
                return c;
            }
        }
        if !fresh {
            // Stale: one request starts the check in the background and
            // every request shows the last status meanwhile, so no page
            // waits for a whole-chain check.
            let held = self.chain.lock().unwrap_or_else(|p| p.into_inner()).clone();
            if let Some((_, c)) = held {
                if let Ok(guard) = Arc::clone(&self.refresh).try_lock_owned() {
                    let me = Arc::clone(self);
                    tokio::spawn(async move {
                        let _one = guard;
                        me.check_now().await;
                    });
                }
                return c;
            }
        }
        // One check at a time: the requests that waited take its result.
        let _one = self.refresh.lock().await;
        if let Some(c) = cached(if fresh { Some(asked) } else { None }) {
            return c;
        }
        self.check_now().await
    }

    /// Check the whole chain now and keep the status.
    async fn check_now(self: &Arc<Self>) -> Chain {
        let c = self
            .with_store(|s| match s.verify() {
                Ok(v) => Chain::Intact(v),
                Err(e) => Chain::Broken(e.to_string()),
            })
            .await;
        *self.chain.lock().unwrap_or_else(|p| p.into_inner()) = Some((Instant::now(), c.clone()));
        c
    }
}
