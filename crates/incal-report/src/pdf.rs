//! The certificate as PDF: the HTML report printed by headless Chromium
//! with the page margins of its print stylesheet. Every front end
//! (`incal report --pdf`, Python's `Result.report(pdf=True)`) prints
//! through [`print()`], so a missing browser, one that cannot start and one
//! that printed nothing are told apart, and a PDF left from an earlier
//! run is never taken for this one.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The browsers tried, in order.
pub const BROWSERS: [&str; 3] = ["chromium", "chromium-browser", "google-chrome"];

/// Why no PDF was printed (each a failure: the HTML stays written).
#[derive(Debug, thiserror::Error)]
pub enum PdfError {
    /// No browser on the `PATH`.
    #[error("headless Chromium is not installed (apt-get install chromium); the HTML was written")]
    NotInstalled,
    /// A browser is installed but does not start (`--version` fails).
    #[error("{browser} is installed but cannot start: {why}; the HTML was written")]
    CannotStart {
        /// The browser's path.
        browser: String,
        /// Its first line on standard error, or its exit status.
        why: String,
    },
    /// The browser ran but left no PDF (or an empty one).
    #[error("{browser} printed no {pdf}: {why}")]
    NoPdf {
        /// The browser's path.
        browser: String,
        /// The PDF expected.
        pdf: String,
        /// Its first line on standard error, or its exit status.
        why: String,
    },
    /// The HTML file cannot be found or the old PDF cannot be removed.
    #[error("{0}")]
    File(String),
}

/// The first browser of [`BROWSERS`] found on `PATH` (an executable file).
fn find_browser() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    BROWSERS.iter().find_map(|b| {
        std::env::split_paths(&path)
            .map(|d| d.join(b))
            .find(|p| p.is_file())
    })
}

/// The first non-empty line a process wrote to standard error (clipped at
/// 160 characters, [`incal_io::clip_to`]), else its exit status.
fn why(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .map(|l| incal_io::clip_to(l, 160))
        .unwrap_or_else(|| format!("exit status {}", out.status))
}

/// Print the HTML file `html` to the same path with `.pdf`, through
/// headless Chromium; the PDF's path. A PDF already there is removed
/// first, so only this run's PDF counts.
pub fn print(html: &Path) -> Result<PathBuf, PdfError> {
    let browser = find_browser().ok_or(PdfError::NotInstalled)?;
    let name = browser.display().to_string();
    let version = Command::new(&browser)
        .arg("--version")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| PdfError::CannotStart {
            browser: name.clone(),
            why: e.to_string(),
        })?;
    if !version.status.success() {
        return Err(PdfError::CannotStart {
            browser: name,
            why: why(&version),
        });
    }
    let abs = std::fs::canonicalize(html)
        .map_err(|e| PdfError::File(format!("{}: {e}", html.display())))?;
    let pdf = abs.with_extension("pdf");
    match std::fs::remove_file(&pdf) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => {
            return Err(PdfError::File(format!(
                "{}: cannot replace: {e}",
                pdf.display()
            )))
        }
    }
    let profile = std::env::temp_dir().join(format!("incal-chromium-{}", std::process::id()));
    let out = Command::new(&browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--no-pdf-header-footer",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--print-to-pdf={}", pdf.display()))
        .arg(format!("file://{}", abs.display()))
        .stdin(Stdio::null())
        .output();
    let _ = std::fs::remove_dir_all(&profile);
    let failed = |why: String| PdfError::NoPdf {
        browser: name.clone(),
        pdf: pdf.display().to_string(),
        why,
    };
    let out = out.map_err(|e| failed(e.to_string()))?;
    if out.status.success() && pdf.metadata().is_ok_and(|m| m.len() > 0) {
        Ok(pdf)
    } else {
        let _ = std::fs::remove_file(&pdf);
        Err(failed(why(&out)))
    }
}
