//! Writing files atomically: into a temporary file beside the target, then renamed,
//! so a failure never leaves a partial output behind.
//!
//! Temporary names are unique per call, `.NAME.mra-tmp-PID-COUNTER-RANDOM`, so parallel
//! writes of one name (threads of one process, or several processes) never share a file.
//! Every temporary file is registered while it exists; [`remove_temps_on_signals`] (called
//! once by the command line) removes the registered files on SIGINT (Ctrl-C) and SIGTERM
//! before the process dies of the signal.

use std::fs::{File, OpenOptions};
use std::hash::{BuildHasher, Hasher};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

/// The marker between the target's name and the per-call suffix.
const MARK: &str = ".mra-tmp-";

/// Temporary files that exist now (created, not yet renamed or removed).
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<PathBuf>> {
    // a panic while holding the lock leaves a list that is still valid
    LIVE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Write `path` through `fill`; on any error the temporary file is removed and the
/// target is left as it was. The writer is a buffered file (seekable, for formats such
/// as TIFF and EXR that patch offsets).
pub fn write_atomic<F, E>(path: &Path, fill: F) -> Result<(), E>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), E>,
    E: From<std::io::Error>,
{
    let (tmp, file) = create_temp(path)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    forget(&tmp);
    result
}

/// Create a new temporary file for `path` and register it, under the registry's lock
/// (so a signal's cleanup sees every file that exists).
fn create_temp(path: &Path) -> std::io::Result<(PathBuf, File)> {
    let mut list = live();
    let mut last = None;
    // a name already taken (left by a killed process with the same pid) is skipped
    for _ in 0..8 {
        let tmp = temp_path(path);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => {
                list.push(tmp.clone());
                return Ok((tmp, f));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("no free temporary name")))
}

fn forget(tmp: &Path) {
    live().retain(|p| p != tmp);
}

/// A fresh temporary name for `path`: hidden, beside the target (same file system, so
/// the rename is atomic), `.NAME.mra-tmp-PID-COUNTER-RANDOM`; no two calls return the same.
pub fn temp_path(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let count = COUNTER.fetch_add(1, Ordering::Relaxed);
    // std's hasher keys are random per process and distinct per `RandomState`
    let random = std::collections::hash_map::RandomState::new()
        .build_hasher()
        .finish()
        & 0xffff_ffff;
    path.with_file_name(format!(
        ".{name}{MARK}{}-{count}-{random:08x}",
        std::process::id()
    ))
}

/// Temporary files of `path` that exist beside it now (written by any process): empty
/// after every write has finished or been cleaned up.
pub fn leftover_temps(path: &Path) -> Vec<PathBuf> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let prefix = format!(".{name}{MARK}");
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .map(|e| e.path())
        .collect()
}

/// Remove every registered temporary file on SIGINT and SIGTERM, then die of the signal
/// (its default action, so the exit status still tells which). Call once, from the
/// command line's `main`; the library never installs handlers.
#[cfg(unix)]
pub fn remove_temps_on_signals() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("mra-signals".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                // hold the lock to the end: no new temporary file appears after this
                let list = live();
                for p in list.iter() {
                    let _ = std::fs::remove_file(p);
                }
                let _ = signal_hook::low_level::emulate_default_handler(sig);
                std::process::exit(128 + sig);
            }
        })?;
    Ok(())
}

/// Without Unix signals there is nothing to install.
#[cfg(not(unix))]
pub fn remove_temps_on_signals() -> std::io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_names_are_unique_per_call_and_found_as_leftovers() {
        let dir = std::env::temp_dir().join(format!("mra-fsutil-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.png");
        let names: std::collections::HashSet<PathBuf> =
            (0..100).map(|_| temp_path(&target)).collect();
        assert_eq!(names.len(), 100);
        assert!(names.iter().all(|p| p.parent() == Some(dir.as_path())));

        let (tmp, _f) = create_temp(&target).unwrap();
        assert_eq!(leftover_temps(&target), vec![tmp.clone()]);
        assert!(live().contains(&tmp));
        std::fs::remove_file(&tmp).unwrap();
        forget(&tmp);
        assert!(leftover_temps(&target).is_empty());
        assert!(!live().contains(&tmp));

        // a failed fill leaves neither the target nor a temporary file
        let r: std::io::Result<()> =
            write_atomic(&target, |_| Err(std::io::Error::other("fill failed")));
        assert!(r.is_err() && !target.exists() && leftover_temps(&target).is_empty());
        write_atomic(&target, |w| w.write_all(b"ok")).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"ok");
        assert!(leftover_temps(&target).is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
