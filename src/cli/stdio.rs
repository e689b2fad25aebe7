//! `-` as a file argument: standard input for an input, standard output for `-o -`, the same
//! for every command.
//!
//! Readers and writers work on files (a TIFF writer seeks, every output is written
//! atomically), so `-` passes through a file in a fresh private folder: standard input is
//! read whole (within the memory budget) before the command reads it; an output is made in
//! that folder under the name `stdout.EXT` and copied to standard output once the command
//! has succeeded, so a failure writes nothing. The format of `-o -` is `--format EXT` or,
//! for a command that writes one format only, that format; else the command refuses in
//! one line naming `--format`.

use std::path::{Path, PathBuf};

use super::{CliResult, Failure};

/// Whether a file argument is `-`: standard input (or output).
pub fn is_std(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// A fresh private folder through which standard input or output passes as a file;
/// removed on drop.
pub struct StdTemp(PathBuf);

impl StdTemp {
    pub fn new() -> Result<StdTemp, Failure> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let d = std::env::temp_dir().join(format!(
            "mra-std-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&d).map_err(|e| Failure::context(d.display(), e))?;
        Ok(StdTemp(d))
    }

    /// `name` inside the folder.
    pub fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for StdTemp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Standard input, whole, read with a bound: at most the memory budget
/// ([`crate::limits`], `MRA_MAX_BYTES`); more is refused before it is kept.
pub fn stdin_bytes() -> Result<Vec<u8>, Failure> {
    use std::io::Read as _;
    let budget = crate::limits::Limits::from_env()?;
    let mut bytes = Vec::new();
    std::io::stdin()
        .lock()
        .take(budget.max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Failure::context("standard input", e))?;
    budget
        .check(
            "bytes of standard input (memory budget MRA_MAX_BYTES)",
            bytes.len() as u64,
        )
        .map_err(|e| Failure::context("standard input", e))?;
    Ok(bytes)
}

/// A text file, or standard input for `-`, naming it in any error.
pub fn read_text(path: &Path) -> Result<String, Failure> {
    if is_std(path) {
        return String::from_utf8(stdin_bytes()?)
            .map_err(|_| Failure("standard input: not UTF-8 text".into()));
    }
    std::fs::read_to_string(path).map_err(|e| Failure::context(path.display(), e))
}

/// Write `bytes` to standard output; a closed pipe is not an error.
pub fn write_stdout(bytes: &[u8]) -> CliResult {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|_| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure::context("standard output", e))
        }
        _ => Ok(()),
    }
}

/// `bytes` written to `path` atomically, or to standard output for `-`.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> CliResult {
    if is_std(path) {
        return write_stdout(bytes);
    }
    crate::fsutil::write_atomic(path, |w| std::io::Write::write_all(w, bytes))
        .map_err(|e| Failure::context(path.display(), e))
}

/// The extension `-o -` is written as: `format` (`--format`, with or without its dot),
/// else `only` (the one format the command writes); `None` with a one-line error when
/// neither is given. `choices` lists the formats in that error.
pub fn std_format(
    format: Option<&str>,
    only: Option<&str>,
    choices: &str,
) -> Result<String, Failure> {
    match (format, only) {
        (Some(f), _) => Ok(f.trim_start_matches('.').to_ascii_lowercase()),
        (None, Some(o)) => Ok(o.to_string()),
        (None, None) => Err(Failure(format!(
            "standard output: -o - needs --format ({choices})"
        ))),
    }
}

/// Run `write` on the output `path`; for `-` on a file `stdout.EXT` of a private folder
/// (EXT from [`std_format`]), whose bytes then go to standard output. Errors naming the
/// private file name standard output instead.
pub fn output(
    path: &Path,
    format: Option<&str>,
    only: Option<&str>,
    choices: &str,
    write: impl FnOnce(&Path) -> CliResult,
) -> CliResult {
    if !is_std(path) {
        return write(path);
    }
    let ext = std_format(format, only, choices)?;
    let t = StdTemp::new()?;
    let f = t.join(&format!("stdout.{ext}"));
    let shown = f.display().to_string();
    write(&f).map_err(|e| Failure(e.0.replace(&shown, "standard output")))?;
    let bytes = std::fs::read(&f).map_err(|e| Failure::context("standard output", e))?;
    write_stdout(&bytes)
}

/// Run `read` on the input `path`; for `-` on a file of a private folder holding standard
/// input, named `stdin.EXT` with EXT given by `ext` from the input's first bytes. Errors
/// naming the private file name standard input instead.
pub fn input<T>(
    path: &Path,
    ext: impl FnOnce(&[u8]) -> &'static str,
    read: impl FnOnce(&Path) -> Result<T, Failure>,
) -> Result<T, Failure> {
    if !is_std(path) {
        return read(path);
    }
    let bytes = stdin_bytes()?;
    let t = StdTemp::new()?;
    let f = t.join(&format!("stdin.{}", ext(&bytes)));
    std::fs::write(&f, &bytes).map_err(|e| Failure::context(f.display(), e))?;
    drop(bytes);
    let shown = f.display().to_string();
    read(&f).map_err(|e| Failure(e.0.replace(&shown, "standard input")))
}

/// The extension of a mesh by its first bytes: PLY (`ply`), OFF (`OFF`, `COFF`, `NOFF`,
/// …), else OBJ.
pub fn mesh_ext(head: &[u8]) -> &'static str {
    let text = String::from_utf8_lossy(&head[..head.len().min(16)]).into_owned();
    let t = text.trim_start();
    if t.starts_with("ply") {
        "ply"
    } else if t
        .split_whitespace()
        .next()
        .is_some_and(|w| w.ends_with("OFF"))
    {
        "off"
    } else {
        "obj"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meshes_on_standard_input_are_told_apart_by_their_first_bytes() {
        assert_eq!(mesh_ext(b"ply\nformat ascii 1.0\n"), "ply");
        assert_eq!(mesh_ext(b"OFF\n3 1 0\n"), "off");
        assert_eq!(mesh_ext(b"COFF\n"), "off");
        assert_eq!(mesh_ext(b"v 0 0 0\nv 1 0 0\n"), "obj");
        assert_eq!(mesh_ext(b""), "obj");
    }

    #[test]
    fn standard_output_needs_a_format_unless_the_command_writes_one() {
        assert_eq!(std_format(Some(".PNG"), None, "").unwrap(), "png");
        assert_eq!(std_format(None, Some("png"), "").unwrap(), "png");
        let e = std_format(None, None, "obj, ply, off").unwrap_err();
        assert!(
            e.0.contains("--format") && e.0.contains("obj, ply, off"),
            "{e}"
        );
    }
}
