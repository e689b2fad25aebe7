//! Decoded levels kept between requests, least recently used first out, within a byte
//! budget. A level is decoded once however many requests ask for it at the same time:
//! the first decodes, the others wait for its result. A file replaced on disk has a new
//! length or modification time, so a new key: its old levels age out.

use crate::io::Raster;
use crate::{Error, Result};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// What names a decoded level (or one tile of it): the file, its version, the level,
/// the tile's coordinates (empty for the whole level).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Key {
    pub path: PathBuf,
    pub len: u64,
    pub mtime: u128,
    pub level: usize,
    pub tile: Vec<usize>,
}

/// A decode's result, shared by the requests that waited for it.
pub type Shared = std::result::Result<Arc<Raster>, Arc<Error>>;

type Cell = Arc<OnceLock<Shared>>;

struct Entry {
    key: Key,
    cell: Cell,
    bytes: u64,
    used: u64,
}

/// The cache of decoded levels.
pub struct LevelCache {
    budget: u64,
    inner: Mutex<Inner>,
}

#[derive(Default)]
struct Inner {
    entries: Vec<Entry>,
    tick: u64,
}

impl LevelCache {
    /// A cache of at most `budget` bytes of decoded samples.
    pub fn new(budget: u64) -> LevelCache {
        LevelCache {
            budget,
            inner: Mutex::new(Inner::default()),
        }
    }

    /// The largest level kept: a quarter of the budget, so that a few levels of the
    /// files being viewed stay together.
    pub fn entry_limit(&self) -> u64 {
        self.budget / 4
    }

    /// Bytes held now.
    pub fn held(&self) -> u64 {
        self.lock().entries.iter().map(|e| e.bytes).sum()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // a panic while holding the lock leaves the list valid: take it back
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The level of `key` (`bytes` large), decoded by `decode` unless held or being
    /// decoded by another request.
    pub fn get_or_decode(
        &self,
        key: Key,
        bytes: u64,
        decode: impl FnOnce() -> Result<Arc<Raster>>,
    ) -> Shared {
        let cell = {
            let mut g = self.lock();
            g.tick += 1;
            let tick = g.tick;
            if let Some(e) = g.entries.iter_mut().find(|e| e.key == key) {
                e.used = tick;
                e.cell.clone()
            } else {
                let mut held: u64 = g.entries.iter().map(|e| e.bytes).sum();
                while held + bytes > self.budget && !g.entries.is_empty() {
                    let oldest = (0..g.entries.len())
                        .min_by_key(|&i| g.entries[i].used)
                        .unwrap_or(0);
                    held -= g.entries.swap_remove(oldest).bytes;
                }
                let cell: Cell = Arc::new(OnceLock::new());
                g.entries.push(Entry {
                    key: key.clone(),
                    cell: cell.clone(),
                    bytes,
                    used: tick,
                });
                cell
            }
        };
        let r = cell.get_or_init(|| decode().map_err(Arc::new)).clone();
        if r.is_err() {
            // a failure is not kept: the file may be fixed or replaced
            self.lock().entries.retain(|e| e.key != key);
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{DataKind, Samples};

    fn key(level: usize) -> Key {
        Key {
            path: "a.mra".into(),
            len: 1,
            mtime: 2,
            level,
            tile: Vec::new(),
        }
    }

    fn raster() -> Result<Arc<Raster>> {
        Ok(Arc::new(Raster::new(
            vec![2, 2],
            1,
            Samples::U8(vec![1, 2, 3, 4]),
            DataKind::Image,
        )?))
    }

    #[test]
    fn a_level_is_decoded_once_and_the_oldest_leaves_first() {
        let c = LevelCache::new(100);
        let mut calls = 0;
        for _ in 0..3 {
            c.get_or_decode(key(0), 40, || {
                calls += 1;
                raster()
            })
            .unwrap();
        }
        assert_eq!(calls, 1);
        c.get_or_decode(key(1), 40, raster).unwrap();
        c.get_or_decode(key(0), 40, raster).unwrap();
        // over the budget: level 1 (used least recently) goes
        c.get_or_decode(key(2), 40, raster).unwrap();
        assert_eq!(c.held(), 80);
        let mut again = false;
        c.get_or_decode(key(0), 40, || {
            again = true;
            raster()
        })
        .unwrap();
        assert!(!again, "level 0 was used last and stays");
    }

    #[test]
    fn a_failed_decode_is_not_kept() {
        let c = LevelCache::new(100);
        let e = c.get_or_decode(key(0), 10, || Err(Error::format("x".to_string(), "y")));
        assert!(e.is_err());
        assert_eq!(c.held(), 0);
        assert!(c.get_or_decode(key(0), 10, raster).is_ok());
    }
}
