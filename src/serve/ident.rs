//! IIIF identifiers: a file's path under the served folder, percent-encoded, with an
//! optional slice of a volume after a `;`:
//!
//! ```text
//! scans/ct.mra;z=120      the slice z = 120 (full-resolution index) of a volume
//! scans/ct.mra;y=64       a slice across y (an x–z image); ;x=… likewise (a y–z image)
//! scans/ct.mra            a volume's middle z slice
//! ```
//!
//! A path is refused (as not found) when it is empty, absolute, has a `.`, `..` or empty
//! component, a NUL or a backslash, does not end in `.mra`, or when, with every symlink
//! resolved, it does not lie inside the served folder.

use percent_encoding::percent_decode_str;
use std::path::{Path, PathBuf};

/// A slice through a volume: the axis (0 = z, 1 = y, 2 = x, slowest first) and the
/// full-resolution index along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slice {
    pub axis: usize,
    pub index: u64,
}

/// A parsed identifier.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ident {
    /// The path under the served folder, `/`-separated.
    pub rel: String,
    pub slice: Option<Slice>,
}

/// The longest identifier accepted (decoded bytes).
pub const MAX_IDENT: usize = 1024;

/// Why an identifier names no file that may be served.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdentError {
    /// Not valid percent-encoded UTF-8, too long, or a slice suffix that does not parse.
    Malformed,
    /// A path that may not be served (outside the folder, not `.mra`, absent).
    NotFound,
}

/// Parse an identifier as it appears in the URL (still percent-encoded).
pub fn parse(encoded: &str) -> Result<Ident, IdentError> {
    if encoded.len() > 3 * MAX_IDENT {
        return Err(IdentError::Malformed);
    }
    let s = percent_decode_str(encoded)
        .decode_utf8()
        .map_err(|_| IdentError::Malformed)?;
    if s.is_empty() || s.len() > MAX_IDENT {
        return Err(IdentError::Malformed);
    }
    let (rel, slice) = match s.split_once(';') {
        None => (s.as_ref(), None),
        Some((p, q)) => (p, Some(parse_slice(q)?)),
    };
    if !safe_relative(rel) {
        return Err(IdentError::NotFound);
    }
    Ok(Ident {
        rel: rel.to_string(),
        slice,
    })
}

fn parse_slice(q: &str) -> Result<Slice, IdentError> {
    let (a, n) = q.split_once('=').ok_or(IdentError::Malformed)?;
    let axis = match a {
        "z" => 0,
        "y" => 1,
        "x" => 2,
        _ => return Err(IdentError::Malformed),
    };
    if n.is_empty() || n.len() > 12 || !n.bytes().all(|b| b.is_ascii_digit()) {
        return Err(IdentError::Malformed);
    }
    let index = n.parse().map_err(|_| IdentError::Malformed)?;
    Ok(Slice { axis, index })
}

/// A relative `/`-separated path of plain components ending in `.mra`.
fn safe_relative(rel: &str) -> bool {
    !rel.starts_with('/')
        && !rel.contains('\\')
        && !rel.contains('\0')
        && rel.ends_with(".mra")
        && rel
            .split('/')
            .all(|c| !c.is_empty() && c != "." && c != "..")
}

/// The file an identifier names: `root` (canonical) joined with its path, canonicalized
/// (symlinks resolved) and checked to lie inside `root` and to be a regular file.
pub fn locate(root: &Path, id: &Ident) -> Result<PathBuf, IdentError> {
    let joined = root.join(&id.rel);
    let real = joined.canonicalize().map_err(|_| IdentError::NotFound)?;
    if !real.starts_with(root) || !real.is_file() {
        return Err(IdentError::NotFound);
    }
    Ok(real)
}

/// The identifier of a path under the folder, percent-encoded for a URL path segment
/// (everything but unreserved characters is encoded, `/` included).
pub fn encode(rel: &str) -> String {
    use percent_encoding::{utf8_percent_encode, AsciiSet, NON_ALPHANUMERIC};
    const KEEP: &AsciiSet = &NON_ALPHANUMERIC
        .remove(b'-')
        .remove(b'.')
        .remove(b'_')
        .remove(b'~');
    utf8_percent_encode(rel, KEEP).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_decode_with_their_slices() {
        assert_eq!(
            parse("a%2Fb.mra").unwrap(),
            Ident {
                rel: "a/b.mra".into(),
                slice: None
            }
        );
        let v = parse("ct.mra;z=12").unwrap();
        assert_eq!(v.slice, Some(Slice { axis: 0, index: 12 }));
        assert_eq!(parse("ct.mra%3Bx%3D3").unwrap().slice.unwrap().axis, 2);
        assert_eq!(encode("a b/c.mra"), "a%20b%2Fc.mra");
        assert_eq!(parse(&encode("dir/é x.mra")).unwrap().rel, "dir/é x.mra");
    }

    #[test]
    fn traversal_and_other_paths_are_refused() {
        for s in [
            "..%2Fsecret.mra",
            "%2e%2e%2fsecret.mra",
            "a/../../b.mra",
            "%2Fetc%2Fpasswd.mra",
            "/etc/x.mra",
            "./a.mra",
            "a//b.mra",
            "a%5C..%5Cb.mra",
            "a%00.mra",
            "a.png",
            "a.mra/",
        ] {
            assert_eq!(parse(s), Err(IdentError::NotFound), "{s}");
        }
        for s in [
            "",
            "%ff.mra",
            "a.mra;w=1",
            "a.mra;z=",
            "a.mra;z=-1",
            "a.mra;z",
        ] {
            assert_eq!(parse(s), Err(IdentError::Malformed), "{s}");
        }
        assert_eq!(parse(&"a".repeat(5000)), Err(IdentError::Malformed));
    }
}
