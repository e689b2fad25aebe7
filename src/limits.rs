//! The memory budget: the most bytes one raster may take, checked before anything sized
//! by a file's header or by a command's arguments is allocated.
//!
//! ```text
//! budget = MRA_MAX_BYTES if set (a byte count: 1048576, 512K, 300M, 8G, 1T; powers of 1024)
//!        = 8 GiB         otherwise
//! ```
//! A reader checks the decoded size a header declares (and, where the format allows, the
//! most the file's length can hold); a command checks its planned output. Over the budget
//! is [`Error::LimitsExceeded`], reported before the allocation.

use crate::{Error, Result};

/// The environment variable that overrides the budget.
pub const ENV: &str = "MRA_MAX_BYTES";

/// The budget when [`ENV`] is not set: 8 GiB.
pub const DEFAULT_MAX_BYTES: u64 = 8 << 30;

/// How much memory one raster may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Most bytes of one decoded raster or one planned output.
    pub max_bytes: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_bytes: DEFAULT_MAX_BYTES,
        }
    }
}

impl Limits {
    /// The budget of this process: [`ENV`] when set, else [`DEFAULT_MAX_BYTES`].
    pub fn from_env() -> Result<Limits> {
        match crate::tuning::max_bytes_var() {
            Some(s) => {
                parse_bytes(&s)
                    .map(|max_bytes| Limits { max_bytes })
                    .ok_or(Error::Parameter {
                        name: "MRA_MAX_BYTES",
                        value: s,
                        expected: "a byte count such as 1048576, 512M or 8G",
                    })
            }
            None => Ok(Limits::default()),
        }
    }

    /// `Ok` when `bytes` fits the budget; otherwise [`Error::LimitsExceeded`] naming `what`.
    pub fn check(&self, what: &'static str, bytes: u64) -> Result<()> {
        if bytes > self.max_bytes {
            return Err(Error::LimitsExceeded {
                what,
                requested: bytes,
                limit: self.max_bytes,
            });
        }
        Ok(())
    }

    /// [`Limits::check`] of `count × size` bytes (an overflow is over any budget).
    pub fn check_elems(&self, what: &'static str, count: u64, size: u64) -> Result<()> {
        self.check(what, count.saturating_mul(size))
    }
}

/// [`Limits::check`] against the budget of this process ([`Limits::from_env`]): the one
/// call every reader and command makes before an allocation sized by a header or by
/// arguments. `what` names the allocation (the error adds the budget's name).
pub fn check(what: &'static str, bytes: u64) -> Result<()> {
    Limits::from_env()?.check(what, bytes)
}

/// [`check`] of `count × size` bytes (an overflow is over any budget).
pub fn check_elems(what: &'static str, count: u64, size: u64) -> Result<()> {
    check(what, count.saturating_mul(size))
}

/// A byte count: digits with an optional suffix K, M, G or T (powers of 1024, an optional
/// trailing `B` or `iB`, any case). `None` when malformed or over `u64`.
pub fn parse_bytes(s: &str) -> Option<u64> {
    let t = s.trim().to_ascii_uppercase();
    let t = t
        .strip_suffix("IB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(&t);
    let (digits, shift) = match t.chars().last()? {
        'K' => (&t[..t.len() - 1], 10),
        'M' => (&t[..t.len() - 1], 20),
        'G' => (&t[..t.len() - 1], 30),
        'T' => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let n: u64 = digits.trim().parse().ok()?;
    n.checked_mul(1u64 << shift)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_parse_with_binary_suffixes() {
        assert_eq!(parse_bytes("1048576"), Some(1 << 20));
        assert_eq!(parse_bytes("512M"), Some(512 << 20));
        assert_eq!(parse_bytes("8g"), Some(8 << 30));
        assert_eq!(parse_bytes("2GiB"), Some(2 << 30));
        assert_eq!(parse_bytes("64kb"), Some(64 << 10));
        assert_eq!(parse_bytes("-1"), None);
        assert_eq!(parse_bytes("lots"), None);
        assert_eq!(parse_bytes("99999999999T"), None);
    }

    #[test]
    fn check_refuses_over_the_budget_and_on_overflow() {
        let l = Limits { max_bytes: 1000 };
        assert!(l.check("x", 1000).is_ok());
        let e = l.check("x", 1001).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::LimitsExceeded);
        assert!(l.check_elems("x", u64::MAX, 2).is_err());
    }
}
