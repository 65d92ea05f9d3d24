//! `--columns`: which columns a command reads, and under which name.

use std::fmt;

/// One entry of a column map: incal's column name, and the header it is
/// read from when the file names it differently.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnEntry {
    /// incal's name of the column (`angle_deg`, `output`, a channel name).
    pub name: String,
    /// The file's header for it (`NAME=HEADER`); `None` when the file
    /// already uses `name`.
    pub header: Option<String>,
}

/// The columns a user selects and renames, one option on every command:
/// `--columns "angle_deg=Angle [deg],output=Out"` reads the header
/// `Angle [deg]` as `angle_deg` and `Out` as `output`; a bare `NAME`
/// selects a column by its own header (the channels of `incal noise`).
/// Every named header must exist in the file.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ColumnMap {
    entries: Vec<ColumnEntry>,
}

impl ColumnMap {
    /// No selection and no renaming.
    pub fn new() -> Self {
        Self::default()
    }

    /// From entries `NAME` or `NAME=HEADER` (one per element; the CLI
    /// splits `--columns` at commas). Refuses an empty entry, an empty
    /// side of `=`, and a name or a header given twice.
    pub fn from_entries<S: AsRef<str>>(entries: &[S]) -> Result<Self, String> {
        let mut out: Vec<ColumnEntry> = Vec::with_capacity(entries.len());
        for raw in entries {
            let raw = raw.as_ref().trim();
            if raw.is_empty() {
                return Err("an empty column entry (give NAME or NAME=HEADER)".into());
            }
            let entry = match raw.split_once('=') {
                Some((n, h)) => {
                    let (n, h) = (n.trim(), h.trim());
                    if n.is_empty() || h.is_empty() {
                        return Err(format!(
                            "'{}': give NAME=HEADER with both sides",
                            crate::clip(raw)
                        ));
                    }
                    ColumnEntry {
                        name: n.to_string(),
                        header: Some(h.to_string()),
                    }
                }
                None => ColumnEntry {
                    name: raw.to_string(),
                    header: None,
                },
            };
            if out.iter().any(|e| e.name == entry.name) {
                return Err(format!("column '{}' named twice", crate::clip(&entry.name)));
            }
            if out.iter().any(|e| e.source() == entry.source()) {
                return Err(format!(
                    "header '{}' mapped twice",
                    crate::clip(entry.source())
                ));
            }
            out.push(entry);
        }
        Ok(Self { entries: out })
    }

    /// Parse one `--columns` value: entries separated by commas.
    pub fn parse(spec: &str) -> Result<Self, String> {
        let parts: Vec<&str> = spec.split(',').collect();
        Self::from_entries(&parts)
    }

    /// The entries, in the order given.
    pub fn entries(&self) -> &[ColumnEntry] {
        &self.entries
    }

    /// True when nothing is selected or renamed.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// incal's names of the selected columns, in the order given.
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|e| e.name.as_str()).collect()
    }
}

impl ColumnEntry {
    /// The header this entry reads in the file.
    pub fn source(&self) -> &str {
        self.header.as_deref().unwrap_or(&self.name)
    }
}

impl fmt::Display for ColumnMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, e) in self.entries.iter().enumerate() {
            if k > 0 {
                f.write_str(",")?;
            }
            match &e.header {
                Some(h) => write!(f, "{}={h}", e.name)?,
                None => f.write_str(&e.name)?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_names_and_renames() {
        let m = ColumnMap::parse("angle_deg=Angle [deg], output=Out,pass").unwrap();
        assert_eq!(m.names(), ["angle_deg", "output", "pass"]);
        assert_eq!(m.entries()[0].source(), "Angle [deg]");
        assert_eq!(m.entries()[2].source(), "pass");
        assert_eq!(m.to_string(), "angle_deg=Angle [deg],output=Out,pass");
    }

    #[test]
    fn refuses_empty_and_repeated_entries() {
        assert!(ColumnMap::parse("a,,b").unwrap_err().contains("empty"));
        assert!(ColumnMap::parse("a=").unwrap_err().contains("both sides"));
        assert!(ColumnMap::parse("a,a").unwrap_err().contains("twice"));
        assert!(ColumnMap::parse("a=X,b=X").unwrap_err().contains("twice"));
    }
}
