//! The one hexadecimal form of a digest (SHA-256 of input files, of
//! result documents and of records): lower-case, two digits a byte, as
//! `sha256sum` prints it.

use sha2::{Digest, Sha256};

/// Lower-case hexadecimal of a digest.
pub fn hex(digest: &[u8]) -> String {
    const HEX: &[u8; 16] = b"0123456789abcdef";
    let mut s = String::with_capacity(digest.len() * 2);
    for &b in digest {
        s.push(HEX[(b >> 4) as usize] as char);
        s.push(HEX[(b & 15) as usize] as char);
    }
    s
}

/// SHA-256 of `bytes`, lower-case hex (equals `sha256sum` of a file of
/// these bytes).
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}
