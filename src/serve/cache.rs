//! What is kept between requests, least recently used first out, within a byte budget:
//! decoded levels, tiles of levels and patches of levels ([`LevelCache`]), files parsed
//! once ([`OpenedCache`]) and encoded answers ([`AnswerCache`], as iipsrv keeps its JPEG
//! tiles). A value is made once
//! however many requests ask for it at the same time: the first makes it, the others
//! wait for its result. A file replaced on disk has a new length or modification time,
//! so new keys: its old values age out.

use crate::io::Raster;
use crate::{Error, Result};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// What names a decoded level (or one tile or patch of it): the file, its version, the
/// level, the piece's coordinates (empty for the whole level).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Key {
    pub path: PathBuf,
    pub len: u64,
    pub mtime: u128,
    pub level: usize,
    pub tile: Vec<usize>,
}

/// What names an encoded answer: the file, its version, and the request's path and
/// query as received.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct AnswerKey {
    pub path: PathBuf,
    pub len: u64,
    pub mtime: u128,
    pub request: String,
}

/// A decode's result, shared by the requests that waited for it.
pub type Shared = std::result::Result<Arc<Raster>, Arc<Error>>;

/// Decoded samples by [`Key`].
pub type LevelCache = Lru<Key, Arc<Raster>>;

/// Files parsed once ([`crate::codec::Opened`]) by path and version (a [`Key`] of level
/// 0 and no tile), counted at the file's length (what their indices take at most).
pub type OpenedCache = Lru<Key, Arc<crate::codec::Opened>>;

/// Encoded answers (the bytes sent) by [`AnswerKey`].
pub type AnswerCache = Lru<AnswerKey, axum::body::Bytes>;

/// How many keys [`Lru::seen_before`] remembers.
pub const SEEN_MAX: usize = 1 << 16;

type Cell<V> = Arc<OnceLock<std::result::Result<V, Arc<Error>>>>;

struct Entry<K, V> {
    key: K,
    cell: Cell<V>,
    bytes: u64,
    used: u64,
}

/// A least-recently-used map of at most `budget` bytes whose values are made once.
pub struct Lru<K, V> {
    budget: u64,
    inner: Mutex<Inner<K, V>>,
}

struct Inner<K, V> {
    entries: std::collections::HashMap<K, Entry<K, V>>,
    /// Keys asked by [`Lru::seen_before`] (at most [`SEEN_MAX`], forgotten together).
    seen: std::collections::HashSet<K>,
    held: u64,
    tick: u64,
}

impl<K: Clone + Eq + std::hash::Hash, V: Clone> Lru<K, V> {
    /// A cache of at most `budget` bytes.
    pub fn new(budget: u64) -> Lru<K, V> {
        Lru {
            budget,
            inner: Mutex::new(Inner {
                entries: std::collections::HashMap::new(),
                seen: std::collections::HashSet::new(),
                held: 0,
                tick: 0,
            }),
        }
    }

    /// The largest value kept: a quarter of the budget, so that a few levels of the
    /// files being viewed stay together.
    pub fn entry_limit(&self) -> u64 {
        self.budget / 4
    }

    /// Bytes held now.
    pub fn held(&self) -> u64 {
        self.lock().held
    }

    /// The budget.
    pub fn budget(&self) -> u64 {
        self.budget
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner<K, V>> {
        // a panic while holding the lock leaves the map valid: take it back
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Make room for `bytes` more: the least recently used entries leave.
    fn evict(&self, g: &mut Inner<K, V>, bytes: u64) {
        while g.held + bytes > self.budget && !g.entries.is_empty() {
            let Some(oldest) = g
                .entries
                .values()
                .min_by_key(|e| e.used)
                .map(|e| e.key.clone())
            else {
                break;
            };
            if let Some(e) = g.entries.remove(&oldest) {
                g.held -= e.bytes;
            }
        }
    }

    /// Whether `key` is held, being made, or was asked here before; it is recorded as
    /// asked (the records of at most [`SEEN_MAX`] keys, forgotten together past that).
    pub fn seen_before(&self, key: &K) -> bool {
        let mut g = self.lock();
        if g.entries.contains_key(key) {
            return true;
        }
        if g.seen.len() >= SEEN_MAX {
            g.seen.clear();
        }
        !g.seen.insert(key.clone())
    }

    /// The value of `key`, if held and made.
    pub fn get(&self, key: &K) -> Option<V> {
        let mut g = self.lock();
        g.tick += 1;
        let tick = g.tick;
        let e = g.entries.get_mut(key)?;
        e.used = tick;
        e.cell.get().and_then(|r| r.as_ref().ok()).cloned()
    }

    /// Keep `value` (`bytes` large) under `key`; a value over the budget is not kept.
    pub fn put(&self, key: K, bytes: u64, value: V) {
        if bytes > self.budget {
            return;
        }
        let mut g = self.lock();
        g.tick += 1;
        let tick = g.tick;
        if let Some(e) = g.entries.remove(&key) {
            g.held -= e.bytes;
        }
        self.evict(&mut g, bytes);
        let cell: Cell<V> = Arc::new(OnceLock::new());
        let _ = cell.set(Ok(value));
        g.held += bytes;
        g.entries.insert(
            key.clone(),
            Entry {
                key,
                cell,
                bytes,
                used: tick,
            },
        );
    }

    /// The value of `key` (`bytes` large), made by `make` unless held or being made by
    /// another request (which this one then waits for).
    pub fn get_or_decode(
        &self,
        key: K,
        bytes: u64,
        make: impl FnOnce() -> Result<V>,
    ) -> std::result::Result<V, Arc<Error>> {
        if bytes > self.budget {
            // never kept: made for this request alone
            return make().map_err(Arc::new);
        }
        let cell = {
            let mut g = self.lock();
            g.tick += 1;
            let tick = g.tick;
            if let Some(e) = g.entries.get_mut(&key) {
                e.used = tick;
                e.cell.clone()
            } else {
                self.evict(&mut g, bytes);
                let cell: Cell<V> = Arc::new(OnceLock::new());
                g.held += bytes;
                g.entries.insert(
                    key.clone(),
                    Entry {
                        key: key.clone(),
                        cell: cell.clone(),
                        bytes,
                        used: tick,
                    },
                );
                cell
            }
        };
        let r = cell.get_or_init(|| make().map_err(Arc::new)).clone();
        if r.is_err() {
            // a failure is not kept: the file may be fixed or replaced
            let mut g = self.lock();
            if g.entries
                .get(&key)
                .is_some_and(|e| Arc::ptr_eq(&e.cell, &cell))
            {
                if let Some(e) = g.entries.remove(&key) {
                    g.held -= e.bytes;
                }
            }
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

    #[test]
    fn concurrent_requests_for_one_key_decode_once() {
        let c = Arc::new(LevelCache::new(1000));
        let calls = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let threads: Vec<_> = (0..8)
            .map(|_| {
                let (c, calls) = (c.clone(), calls.clone());
                std::thread::spawn(move || {
                    c.get_or_decode(key(3), 40, || {
                        calls.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                        std::thread::sleep(std::time::Duration::from_millis(50));
                        raster()
                    })
                    .unwrap()
                })
            })
            .collect();
        let got: Vec<_> = threads.into_iter().map(|t| t.join().unwrap()).collect();
        assert_eq!(calls.load(std::sync::atomic::Ordering::SeqCst), 1);
        assert!(got.iter().all(|r| Arc::ptr_eq(r, &got[0])));
    }

    #[test]
    fn a_key_is_seen_once_asked_or_held() {
        let c = LevelCache::new(100);
        assert!(!c.seen_before(&key(0)), "first ask");
        assert!(c.seen_before(&key(0)), "asked before");
        c.get_or_decode(key(1), 10, raster).unwrap();
        assert!(c.seen_before(&key(1)), "held");
        for k in 2..SEEN_MAX + 3 {
            c.seen_before(&key(k));
        }
        // the records are bounded: past SEEN_MAX they are forgotten
        assert!(c.lock().seen.len() <= SEEN_MAX);
    }

    #[test]
    fn the_budget_is_never_exceeded() {
        let c = AnswerCache::new(1000);
        for i in 0..100u64 {
            let bytes = 37 + i * 7 % 300;
            let k = AnswerKey {
                path: "a.mra".into(),
                len: 1,
                mtime: 2,
                request: format!("r{i}"),
            };
            c.put(k.clone(), bytes, vec![0u8; bytes as usize].into());
            assert!(c.held() <= 1000, "{} held after {i}", c.held());
            assert!(c.get(&k).is_some(), "the value just kept is there");
        }
        // one over the budget is not kept and evicts nothing
        let held = c.held();
        let big = AnswerKey {
            path: "a.mra".into(),
            len: 1,
            mtime: 2,
            request: "big".into(),
        };
        c.put(big.clone(), 1001, Vec::new().into());
        assert!(c.get(&big).is_none());
        assert_eq!(c.held(), held);
        let l = LevelCache::new(100);
        for k in 0..20 {
            l.get_or_decode(key(k), 30, raster).unwrap();
            assert!(l.held() <= 100);
        }
    }
}
