//! `incal serve`: the lab's web application on a records store
//! (`incal-web`; the chapter "The lab's web application").

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;

use crate::commands::record::DbArgs;
use crate::error::{CliError, CliResult};

/// Options of `incal serve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub db: DbArgs,
    /// Address and port to listen on (loopback by default: put a reverse proxy with TLS in front to serve a network).
    #[arg(long, default_value = "127.0.0.1:8080", value_name = "ADDR:PORT")]
    pub listen: SocketAddr,
    /// Laboratory profile (lab.toml, as for incal report --lab): certificates are issued under it, signed by the approving signatory.
    #[arg(long, value_name = "FILE")]
    pub lab: Option<PathBuf>,
    /// Recall interval in days: an instrument's next calibration is due this long after its last one.
    #[arg(long, default_value_t = 365, value_name = "DAYS")]
    pub recall_days: i64,
    /// Recall intervals per model and per instrument (TOML: [model] "QA-2000" = 180, [serial] "SN-042" = 90, in days), over --recall-days.
    #[arg(long, value_name = "FILE")]
    pub recall: Option<PathBuf>,
    /// Instruments due within this many days are listed as due soon.
    #[arg(long, default_value_t = 30, value_name = "DAYS")]
    pub due_soon_days: i64,
    /// Reverse-proxy mode: trust the user header (--user-header) only on connections from this address (the proxy's).
    #[arg(long, value_name = "IP")]
    pub trusted_proxy: Option<IpAddr>,
    /// The header naming the authenticated account in reverse-proxy mode.
    #[arg(long, default_value = "X-Remote-User", value_name = "NAME")]
    pub user_header: String,
    /// Mark the session cookie Secure: the proxy serves the application over TLS.
    #[arg(long)]
    pub secure_cookies: bool,
    /// Store connections kept open, one of them for writes (default: 4 on SQLite, 12 on PostgreSQL).
    #[arg(long, value_name = "N")]
    pub connections: Option<usize>,
}

/// Run `incal serve` until interrupted.
pub fn run(a: &Args) -> CliResult<()> {
    if a.recall_days < 1 || a.recall_days > 36_500 {
        return Err(CliError::Input(format!(
            "--recall-days {}: 1 to 36500",
            a.recall_days
        )));
    }
    if a.due_soon_days < 0 || a.due_soon_days > 36_500 {
        return Err(CliError::Input(format!(
            "--due-soon-days {}: 0 to 36500",
            a.due_soon_days
        )));
    }
    let mut c = incal_web::Config::new(a.db.path());
    c.listen = a.listen;
    c.lab = a.lab.clone();
    c.recall_days = a.recall_days;
    if let Some(p) = &a.recall {
        let (name, text) = crate::io::read_text(p)?;
        c.recall = incal_web::state::Recall::parse(&name, &text).map_err(CliError::Input)?;
    }
    c.due_soon_days = a.due_soon_days;
    c.trusted_proxy = a.trusted_proxy;
    c.user_header = a.user_header.clone();
    c.secure_cookies = a.secure_cookies;
    if let Some(n) = a.connections {
        if !(2..=64).contains(&n) {
            return Err(CliError::Input(format!("--connections {n}: 2 to 64")));
        }
        c.connections = n;
    }
    incal_web::serve(c).map_err(CliError::Input)
}
