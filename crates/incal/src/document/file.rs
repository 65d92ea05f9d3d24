//! A result document handed to a procedure as one of its options: the
//! tumble result a centrifuge run chains to, the gyro-rate result a
//! multi-position test takes K1 from. A front end reads the file (or
//! holds the document) and gives its name, the SHA-256 of its bytes and
//! its text; the procedure parses and checks it as every command that
//! reads a result does ([`ResultDocument::from_json`]).

use super::ResultDocument;

/// A result document as an option's value (JSON: `{"name", "sha256",
/// "text"}`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DocumentFile {
    /// The file's name as given (recorded among the inputs, role `from`).
    pub name: String,
    /// SHA-256 of the file's bytes, lower-case hex (default: of `text`).
    #[serde(default)]
    pub sha256: Option<String>,
    /// The document's JSON text.
    pub text: String,
}

impl DocumentFile {
    /// The document's hash (given, or of the text) and the document,
    /// checked; an error names the file and the JSON path.
    pub fn parse(&self) -> Result<(String, ResultDocument), String> {
        let sha = match &self.sha256 {
            Some(s) if s.len() == 64 && s.bytes().all(|b| b.is_ascii_hexdigit()) => {
                s.to_ascii_lowercase()
            }
            Some(s) => {
                return Err(format!(
                    "{}: sha256 '{}' is not 64 hexadecimal digits",
                    incal_io::clip(&self.name),
                    incal_io::clip(s)
                ))
            }
            None => incal_io::sha256_hex(self.text.as_bytes()),
        };
        if self.text.trim().is_empty() {
            return Err(format!("{}: empty file", incal_io::clip(&self.name)));
        }
        let doc = ResultDocument::from_json(&self.text)
            .map_err(|e| format!("{}: {e}", incal_io::clip(&self.name)))?;
        Ok((sha, doc))
    }
}
