//! The hash chain: the canonical form of a record and its SHA-256.
//!
//! # Canonical form (`incal.record/1`)
//! A record's hash is `record_hash = SHA-256(C)` (lower-case hex), where
//! `C` is the concatenation of these fields, in this order, each written
//! as `LEN:TEXT\n` (`LEN` = the number of UTF-8 bytes of `TEXT`, in
//! decimal) or, when the field is null, as `-\n`:
//!
//! 1. `incal.record/1` (the version of this form)
//! 2. `prev_hash`: the `record_hash` of record `id − 1`, or 64 zeros for
//!    record 1
//! 3. `id` (decimal)
//! 4. `serial` of the instrument
//! 5. `procedure` (`tumble`, `centrifuge`, …)
//! 6. `created_utc` (`YYYY-MM-DDTHH:MM:SSZ`)
//! 7. `operator` (or null)
//! 8. `station` (or null)
//! 9. `document_sha256`: SHA-256 of the stored document's UTF-8 bytes
//! 10. the number of input files `n` (decimal), then for each input file in
//!     the document's order: `role`, `path`, `sha256` (3·n fields)
//! 11. `supersedes`: the id of the record this one corrects (or null)
//! 12. `reason` of the correction (or null)
//!
//! Because every field carries its length, no choice of text can make two
//! different records share a canonical form. In Python:
//! `b"".join(b"-\n" if f is None else b"%d:%s\n" % (len(f.encode()), f.encode()) for f in fields)`.

pub use incal_io::sha256_hex;

/// The version tag that opens every canonical form.
pub const FORM: &str = "incal.record/1";

/// `prev_hash` of the first record: 64 zeros.
pub const GENESIS: &str = "0000000000000000000000000000000000000000000000000000000000000000";

/// One input file of a record, from the document's `inputs`.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputHash {
    /// What the file was to the procedure (`input`, `from`, …).
    pub role: String,
    /// The path as given when the result was made.
    pub path: String,
    /// SHA-256 of the file's bytes.
    pub sha256: String,
}

/// Every field the record hash covers (module docs).
#[derive(Debug, Clone, Copy)]
pub struct ChainFields<'a> {
    /// Hash of the record before (or [`GENESIS`]).
    pub prev_hash: &'a str,
    /// Record id.
    pub id: i64,
    /// Instrument serial.
    pub serial: &'a str,
    /// Procedure id.
    pub procedure: &'a str,
    /// Creation time, `YYYY-MM-DDTHH:MM:SSZ`.
    pub created_utc: &'a str,
    /// Operator.
    pub operator: Option<&'a str>,
    /// Station (rig, bench).
    pub station: Option<&'a str>,
    /// SHA-256 of the stored document.
    pub document_sha256: &'a str,
    /// Input files of the document.
    pub inputs: &'a [InputHash],
    /// The record this one supersedes.
    pub supersedes: Option<i64>,
    /// Why it supersedes it.
    pub reason: Option<&'a str>,
}

/// One field of a canonical form: `LEN:TEXT\n`, or `-\n` for null.
pub(crate) fn field(out: &mut Vec<u8>, f: Option<&str>) {
    match f {
        Some(t) => {
            out.extend_from_slice(t.len().to_string().as_bytes());
            out.push(b':');
            out.extend_from_slice(t.as_bytes());
            out.push(b'\n');
        }
        None => out.extend_from_slice(b"-\n"),
    }
}

impl ChainFields<'_> {
    /// The canonical form `C` (module docs).
    pub fn canonical(&self) -> Vec<u8> {
        let mut c = Vec::with_capacity(512);
        field(&mut c, Some(FORM));
        field(&mut c, Some(self.prev_hash));
        field(&mut c, Some(&self.id.to_string()));
        field(&mut c, Some(self.serial));
        field(&mut c, Some(self.procedure));
        field(&mut c, Some(self.created_utc));
        field(&mut c, self.operator);
        field(&mut c, self.station);
        field(&mut c, Some(self.document_sha256));
        field(&mut c, Some(&self.inputs.len().to_string()));
        for i in self.inputs {
            field(&mut c, Some(&i.role));
            field(&mut c, Some(&i.path));
            field(&mut c, Some(&i.sha256));
        }
        field(&mut c, self.supersedes.map(|s| s.to_string()).as_deref());
        field(&mut c, self.reason);
        c
    }

    /// `record_hash = SHA-256(canonical form)`, lower-case hex.
    pub fn record_hash(&self) -> String {
        sha256_hex(&self.canonical())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields<'a>(inputs: &'a [InputHash]) -> ChainFields<'a> {
        ChainFields {
            prev_hash: GENESIS,
            id: 1,
            serial: "SN-1",
            procedure: "tumble",
            created_utc: "2025-01-01T00:00:00Z",
            operator: Some("lee"),
            station: None,
            document_sha256: "ab",
            inputs,
            supersedes: None,
            reason: None,
        }
    }

    #[test]
    fn canonical_form_is_length_prefixed_lines() {
        let inputs = [InputHash {
            role: "input".into(),
            path: "t.csv".into(),
            sha256: "cd".into(),
        }];
        let c = String::from_utf8(fields(&inputs).canonical()).unwrap();
        let expect = format!(
            "14:incal.record/1\n64:{GENESIS}\n1:1\n4:SN-1\n6:tumble\n20:2025-01-01T00:00:00Z\n3:lee\n-\n2:ab\n1:1\n5:input\n5:t.csv\n2:cd\n-\n-\n"
        );
        assert_eq!(c, expect);
        // Lengths count bytes, not characters.
        let mut f = fields(&[]);
        f.operator = Some("Łukasz");
        assert!(String::from_utf8(f.canonical())
            .unwrap()
            .contains("\n7:Łukasz\n"));
    }

    #[test]
    fn every_field_changes_the_hash() {
        let base = fields(&[]);
        let h = base.record_hash();
        assert_eq!(h.len(), 64);
        let mut v = Vec::new();
        let mut f = base;
        f.id = 2;
        v.push(f.record_hash());
        let mut f = base;
        f.operator = None;
        v.push(f.record_hash());
        let mut f = base;
        f.station = Some("");
        v.push(f.record_hash());
        let mut f = base;
        f.supersedes = Some(1);
        v.push(f.record_hash());
        // A field's text cannot slide into the next one.
        let mut f = base;
        f.serial = "SN-1\n6:tumble";
        f.procedure = "";
        v.push(f.record_hash());
        assert!(v.iter().all(|x| *x != h), "{v:?}");
    }
}
