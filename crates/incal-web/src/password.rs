//! Passwords: Argon2id hashes in PHC strings (RFC 9106, the argon2
//! crate's defaults: m = 19 MiB, t = 2, p = 1, as OWASP's password storage
//! guidance recommends), random salts, and the checks a new password
//! must pass.

use argon2::password_hash::{PasswordHash, PasswordHasher, PasswordVerifier, SaltString};
use argon2::Argon2;

/// Shortest password accepted.
pub const MIN_PASSWORD: usize = 10;
/// Longest password accepted (bytes): longer ones are refused before any
/// hashing, so a huge body cannot make the server hash megabytes.
pub const MAX_PASSWORD: usize = 256;

/// `n` bytes from the thread's cryptographically secure generator
/// (ChaCha12 seeded from the operating system).
pub fn random_bytes<const N: usize>() -> [u8; N] {
    use rand::Rng;
    let mut b = [0u8; N];
    rand::rng().fill_bytes(&mut b);
    b
}

/// 32 random bytes as lower-case hex ([`incal_io::hex`]): session ids and
/// CSRF tokens.
pub fn random_token() -> String {
    incal_io::hex(&random_bytes::<32>())
}

/// Why a password is not accepted.
pub fn check_new(password: &str) -> Result<(), String> {
    if password.chars().count() < MIN_PASSWORD {
        return Err(format!("a password has at least {MIN_PASSWORD} characters"));
    }
    if password.len() > MAX_PASSWORD {
        return Err(format!("a password has at most {MAX_PASSWORD} bytes"));
    }
    Ok(())
}

/// The Argon2id hash of `password` with a new random salt, as a PHC
/// string (`$argon2id$v=19$m=19456,t=2,p=1$SALT$HASH`).
pub fn hash(password: &str) -> Result<String, String> {
    let salt = SaltString::encode_b64(&random_bytes::<16>()).map_err(|e| e.to_string())?;
    Argon2::default()
        .hash_password(password.as_bytes(), &salt)
        .map(|h| h.to_string())
        .map_err(|e| e.to_string())
}

/// True when `password` matches the PHC string `phc` (false for a
/// malformed one, and for an over-long password without hashing it).
pub fn verify(password: &str, phc: &str) -> bool {
    if password.len() > MAX_PASSWORD {
        return false;
    }
    match PasswordHash::new(phc) {
        Ok(h) => Argon2::default()
            .verify_password(password.as_bytes(), &h)
            .is_ok(),
        Err(_) => false,
    }
}

/// A hash to verify against when the account does not exist, so a wrong
/// name costs the same time as a wrong password.
pub fn decoy() -> &'static str {
    static DECOY: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    DECOY.get_or_init(|| hash("incal decoy password").unwrap_or_default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_verify_and_differ() {
        let a = hash("correct horse battery").unwrap();
        let b = hash("correct horse battery").unwrap();
        assert!(a.starts_with("$argon2id$v=19$m=19456,t=2,p=1$"), "{a}");
        assert_ne!(a, b, "salts are random");
        assert!(verify("correct horse battery", &a));
        assert!(!verify("correct horse batterY", &a));
        assert!(!verify("x", "not a hash"));
        assert!(check_new("short").is_err());
        assert!(check_new(&"x".repeat(300)).is_err());
        assert_ne!(random_token(), random_token());
        assert_eq!(random_token().len(), 64);
    }
}
