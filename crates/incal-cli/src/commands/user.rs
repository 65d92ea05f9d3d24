//! `incal user …`: the accounts of the lab's web application, managed on
//! the server's store by whoever holds it (the console acts as
//! administrator, recorded as `console:$USER`). Every change is an event
//! in the store's hash chain. A password is read from standard input (one
//! line; not echoed on a terminal), never from the command line.

use clap::Subcommand;
use incal_records::{Actor, Role, Store};
use serde_json::json;

use crate::commands::record::DbArgs;
use crate::error::{CliError, CliResult};
use crate::output::json_text;

/// `incal user …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Add an account with a role (viewer, engineer, signatory, admin); the password is read from standard input.
    Add(AddArgs),
    /// Set an account's password, read from standard input (the account's open web sessions end at their next request).
    Passwd(NameArgs),
    /// Give an account another role.
    Role(RoleArgs),
    /// Disable an account: it can no longer log in, and its web sessions end at their next request.
    Disable(NameArgs),
    /// Enable a disabled account again.
    Enable(NameArgs),
    /// List the accounts: name, role, state, when added.
    List(ListArgs),
}

/// Options of `incal user add`.
#[derive(clap::Args, Debug)]
pub struct AddArgs {
    /// The account's name (letters, digits, . _ @ -).
    pub name: String,
    /// Its role: viewer, engineer, signatory or admin.
    #[arg(long)]
    pub role: String,
    #[command(flatten)]
    pub db: DbArgs,
}

/// An account named.
#[derive(clap::Args, Debug)]
pub struct NameArgs {
    /// The account's name.
    pub name: String,
    #[command(flatten)]
    pub db: DbArgs,
}

/// Options of `incal user role`.
#[derive(clap::Args, Debug)]
pub struct RoleArgs {
    /// The account's name.
    pub name: String,
    /// Its new role: viewer, engineer, signatory or admin.
    #[arg(long)]
    pub role: String,
    #[command(flatten)]
    pub db: DbArgs,
}

/// Options of `incal user list`.
#[derive(clap::Args, Debug)]
pub struct ListArgs {
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub db: DbArgs,
}

fn role(s: &str) -> CliResult<Role> {
    Role::parse(s).ok_or_else(|| {
        CliError::Input(format!(
            "--role '{}': one of viewer, engineer, signatory, admin",
            incal_io::clip(s)
        ))
    })
}

/// The console's actor: the operating-system user holding the store.
fn console() -> Actor {
    let who = std::env::var("USER")
        .or_else(|_| std::env::var("USERNAME"))
        .unwrap_or_else(|_| "unknown".into());
    Actor::console(&who)
}

/// A new password from standard input, checked and hashed.
fn read_password() -> CliResult<String> {
    use std::io::BufRead;
    let tty = std::io::IsTerminal::is_terminal(&std::io::stdin());
    if tty {
        eprint!("password (not shown): ");
    }
    let echo = tty.then(no_echo);
    let mut line = String::new();
    let read = std::io::stdin().lock().read_line(&mut line);
    if let Some(Some(saved)) = echo {
        restore_echo(saved);
        eprintln!();
    }
    read.map_err(|e| CliError::Input(format!("standard input: cannot read the password ({e})")))?;
    let pw = line.trim_end_matches(['\n', '\r']);
    incal_web::password::check_new(pw)
        .map_err(|m| CliError::Input(format!("standard input: {m}")))?;
    incal_web::password::hash(pw)
        .map_err(|e| CliError::Failure(anyhow::anyhow!("cannot hash the password: {e}")))
}

#[cfg(unix)]
fn no_echo() -> Option<libc::termios> {
    // SAFETY: tcgetattr/tcsetattr on standard input with a zeroed termios
    // the call fills; failures are returned and leave the terminal as is.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(0, &mut t) != 0 {
            return None;
        }
        let saved = t;
        t.c_lflag &= !libc::ECHO;
        (libc::tcsetattr(0, libc::TCSANOW, &t) == 0).then_some(saved)
    }
}

#[cfg(unix)]
fn restore_echo(saved: libc::termios) {
    // SAFETY: restores the attributes read by `no_echo`.
    unsafe {
        libc::tcsetattr(0, libc::TCSANOW, &saved);
    }
}

#[cfg(not(unix))]
fn no_echo() -> Option<()> {
    None
}

#[cfg(not(unix))]
fn restore_echo(_: ()) {}

fn open(db: &DbArgs) -> CliResult<Store> {
    Store::open(db.path()).map_err(|e| crate::options::store_error(&db.name(), e))
}

/// Run `incal user …`.
pub fn run(c: &Command) -> CliResult<()> {
    let err = |db: &DbArgs| {
        let name = db.name();
        move |e| crate::options::store_error(&name, e)
    };
    let done = match c {
        Command::Add(a) => {
            let r = role(&a.role)?;
            incal_records::check_username(&a.name).map_err(err(&a.db))?;
            let mut s = open(&a.db)?;
            let h = read_password()?;
            s.add_user(&console(), &a.name, r, &h).map_err(err(&a.db))?
        }
        Command::Passwd(a) => {
            let mut s = open(&a.db)?;
            let h = read_password()?;
            s.set_password(&console(), &a.name, &h)
                .map_err(err(&a.db))?
        }
        Command::Role(a) => {
            let r = role(&a.role)?;
            open(&a.db)?
                .set_role(&console(), &a.name, r)
                .map_err(err(&a.db))?
        }
        Command::Disable(a) => open(&a.db)?
            .set_disabled(&console(), &a.name, true)
            .map_err(err(&a.db))?,
        Command::Enable(a) => open(&a.db)?
            .set_disabled(&console(), &a.name, false)
            .map_err(err(&a.db))?,
        Command::List(a) => return list(a),
    };
    println!(
        "{} {}: event {} in the chain",
        done.kind.as_str(),
        done.username.as_deref().unwrap_or(""),
        done.id
    );
    Ok(())
}

fn list(a: &ListArgs) -> CliResult<()> {
    let name = a.db.name();
    let s = Store::open_existing(a.db.path()).map_err(|e| crate::options::store_error(&name, e))?;
    let accounts = s
        .accounts()
        .map_err(|e| crate::options::store_error(&name, e))?;
    if a.json {
        println!("{}", json_text(&json!({ "accounts": accounts })));
        return Ok(());
    }
    println!("{:<24} {:<10} {:<9} added", "account", "role", "state");
    for x in &accounts {
        let state = if x.disabled { "disabled" } else { "enabled" };
        println!(
            "{:<24} {:<10} {:<9} {}",
            x.username,
            x.role.as_str(),
            state,
            x.created_utc
        );
    }
    Ok(())
}
