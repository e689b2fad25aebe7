//! Writing files atomically: into a temporary file beside the target, then renamed,
//! so a failure never leaves a partial output behind.
//!
//! The output path is resolved first ([`resolve_output`]): a symbolic link is followed
//! (the file it names is written, the link stays); a FIFO or character device (a pipe,
//! `/dev/null`, a terminal) is written through: the bytes are made in a temporary file
//! (so formats that seek still can), then copied into it; a block device, socket or
//! folder is refused.
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

/// Where an output named `path` is written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OutputTarget {
    /// A regular file (or none yet) at this path, symbolic links followed: written
    /// atomically beside it.
    File(PathBuf),
    /// A FIFO or character device at this path: written through, after the bytes are
    /// complete.
    Stream(PathBuf),
}

/// How an output named `path` is written: symbolic links followed (up to 40, as the
/// kernel does; a dangling link names the file to create), FIFOs and character devices
/// written through, block devices, sockets and folders refused (`InvalidInput`).
pub fn resolve_output(path: &Path) -> std::io::Result<OutputTarget> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        let md = match std::fs::symlink_metadata(&p) {
            Ok(md) => md,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(OutputTarget::File(p)),
            Err(e) => return Err(e),
        };
        let ft = md.file_type();
        if ft.is_symlink() {
            let link = std::fs::read_link(&p)?;
            p = match p.parent() {
                Some(dir) if link.is_relative() => dir.join(link),
                _ => link,
            };
            continue;
        }
        if ft.is_file() {
            return Ok(OutputTarget::File(p));
        }
        if is_stream(&ft) {
            return Ok(OutputTarget::Stream(p));
        }
        let what = if ft.is_dir() {
            "a folder"
        } else {
            "a block device or socket"
        };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("the output is {what} (expected a file, a FIFO or a character device)"),
        ));
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        "too many levels of symbolic links",
    ))
}

/// A FIFO or character device (written through).
#[cfg(unix)]
fn is_stream(ft: &std::fs::FileType) -> bool {
    use std::os::unix::fs::FileTypeExt;
    ft.is_fifo() || ft.is_char_device()
}

#[cfg(not(unix))]
fn is_stream(_ft: &std::fs::FileType) -> bool {
    false
}

/// Write `path` through `fill`; on any error the temporary file is removed and the
/// target is left as it was. The writer is a buffered file (seekable, for formats such
/// as TIFF and EXR that patch offsets). See the module doc for symbolic links, FIFOs and
/// devices.
pub fn write_atomic<F, E>(path: &Path, fill: F) -> Result<(), E>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), E>,
    E: From<std::io::Error>,
{
    let (target, stream) = match resolve_output(path)? {
        OutputTarget::File(p) => (p, false),
        OutputTarget::Stream(p) => (p, true),
    };
    // a stream's bytes are made in the temporary folder (its own folder, /dev say, may
    // not be writable), then copied into it
    let (tmp, file) = if stream {
        create_temp_in(&std::env::temp_dir(), &target)?
    } else {
        create_temp(&target)?
    };
    let result = (|| {
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        w.flush()?;
        let mut file = w.into_inner().map_err(|e| e.into_error())?;
        if stream {
            use std::io::Seek;
            file.seek(std::io::SeekFrom::Start(0))?;
            let mut out = OpenOptions::new().write(true).open(&target)?;
            std::io::copy(&mut file, &mut out)?;
            out.flush()?;
        } else {
            file.sync_all()?;
            std::fs::rename(&tmp, &target)?;
        }
        Ok(())
    })();
    if result.is_err() || stream {
        let _ = std::fs::remove_file(&tmp);
    }
    forget(&tmp);
    result
}

/// A writer that remembers whether a write, flush or seek through it failed, so that a
/// caller can tell a failing output (full disk, file-size limit) from a failing input.
pub struct Watch<W> {
    inner: W,
    failed: bool,
}

impl<W> Watch<W> {
    pub fn new(inner: W) -> Self {
        Watch {
            inner,
            failed: false,
        }
    }

    /// Did an operation on the output fail?
    pub fn failed(&self) -> bool {
        self.failed
    }

    fn note<T>(&mut self, r: std::io::Result<T>) -> std::io::Result<T> {
        self.failed |= r.is_err();
        r
    }
}

impl<W: Write> Write for Watch<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let r = self.inner.write(buf);
        self.note(r)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        let r = self.inner.flush();
        self.note(r)
    }
}

impl<W: std::io::Seek> std::io::Seek for Watch<W> {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        let r = self.inner.seek(pos);
        self.note(r)
    }
}

/// Let a file-size limit (`ulimit -f`, RLIMIT_FSIZE) fail the write that passes it with
/// `EFBIG` instead of killing the process with SIGXFSZ, so that the usual error path
/// runs: a one-line message naming the output, and the temporary file removed. Call
/// once, from the command line's `main`.
#[cfg(unix)]
pub fn survive_file_size_limit() -> std::io::Result<()> {
    // a caught signal (the flag is never read) makes the kernel return EFBIG
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGXFSZ, flag)?;
    Ok(())
}

/// Without Unix signals there is nothing to install.
#[cfg(not(unix))]
pub fn survive_file_size_limit() -> std::io::Result<()> {
    Ok(())
}

/// Create a new temporary file for `path` and register it, under the registry's lock
/// (so a signal's cleanup sees every file that exists).
fn create_temp(path: &Path) -> std::io::Result<(PathBuf, File)> {
    let dir = path.parent().unwrap_or(Path::new(""));
    create_temp_in(dir, path)
}

/// [`create_temp`] in folder `dir` instead of beside `path`.
fn create_temp_in(dir: &Path, path: &Path) -> std::io::Result<(PathBuf, File)> {
    let mut list = live();
    let mut last = None;
    // a name already taken (left by a killed process with the same pid) is skipped
    for _ in 0..8 {
        let tmp = dir.join(temp_path(path).file_name().unwrap_or_default());
        // readable too: a stream's bytes are read back to be copied into it
        match OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
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
