//! `mra serve`: the `.mra` files of a folder over HTTP with the IIIF Image API 3.0 at
//! compliance level 2, and a deep-zoom viewer page (OpenSeadragon) at `/`.
//!
//! ```text
//! /                                        the files, each a link to the viewer
//! /viewer.html?id={identifier}             OpenSeadragon on one file
//! /iiif/3/{identifier}                     303 to its info.json
//! /iiif/3/{identifier}/info.json           width, height, sizes (the levels), tiles
//! /iiif/3/{identifier}/{region}/{size}/{rotation}/{quality}.{format}[?window=lo,hi]
//! ```
//!
//! One file per job: the request grammar in [`iiif`], identifiers in [`ident`], a file
//! and its level windows in [`source`], decoded levels kept in [`cache`], a request
//! rendered in [`render`], `info.json` in [`info`], the pages in [`viewer`], the HTTP
//! stack (axum on tokio, the limits) in [`http`].

pub mod cache;
pub mod http;
pub mod ident;
pub mod iiif;
pub mod info;
pub mod render;
pub mod source;
pub mod viewer;

use crate::limits::Limits;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;

/// Why a request failed.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// A malformed or unsatisfiable request (400).
    #[error("{0}")]
    Bad(iiif::BadRequest),
    /// No file that may be served under that identifier (404).
    #[error("no such image")]
    NotFound,
    /// The request would take more memory than `MRA_MAX_BYTES` allows (400).
    #[error("{0}")]
    Limits(crate::Error),
    /// The file could not be read or decoded (500).
    #[error("{0}")]
    File(Arc<crate::Error>),
}

impl ServeError {
    /// A [`ServeError::Bad`] of `part`, the value given and what was expected.
    pub fn bad(part: &'static str, value: &str, expected: &'static str) -> ServeError {
        ServeError::Bad(iiif::BadRequest {
            part,
            value: value.to_string(),
            expected,
        })
    }
}

impl From<crate::Error> for ServeError {
    fn from(e: crate::Error) -> Self {
        match e.kind() {
            crate::ErrorKind::LimitsExceeded => ServeError::Limits(e),
            _ => ServeError::File(Arc::new(e)),
        }
    }
}

impl From<iiif::BadRequest> for ServeError {
    fn from(e: iiif::BadRequest) -> Self {
        ServeError::Bad(e)
    }
}

/// How to serve.
#[derive(Clone, Debug)]
pub struct Config {
    /// The folder whose `.mra` files are served.
    pub root: PathBuf,
    /// The address to listen on.
    pub bind: SocketAddr,
    /// Allow an address other than loopback.
    pub public: bool,
    /// Bytes of decoded levels kept between requests.
    pub cache_bytes: u64,
    /// The memory budget of one request.
    pub limits: Limits,
    /// Requests decoding at the same time (the others wait).
    pub workers: usize,
    /// Decode the levels the cache keeps of every one-piece 3.0 file before serving.
    pub warm: bool,
}

/// Why the server could not start or stopped.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    #[error("{root}: not a folder")]
    NotAFolder { root: PathBuf },
    #[error("--bind {bind}: not a loopback address (expected 127.0.0.1 or ::1, or --public)")]
    NotLoopback { bind: SocketAddr },
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// The threads handling connections: `MRA_SERVE_THREADS` (1 to 64) when set, else
/// tokio's default (one per core).
fn runtime_threads() -> Option<usize> {
    std::env::var("MRA_SERVE_THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|n: &usize| (1..=64).contains(n))
}

/// Serve until the process ends; `ready` is told the address bound (port 0 picks one).
pub fn serve(config: Config, ready: impl FnOnce(SocketAddr)) -> Result<(), StartError> {
    if !config.public && !config.bind.ip().is_loopback() {
        return Err(StartError::NotLoopback { bind: config.bind });
    }
    let root = config
        .root
        .canonicalize()
        .ok()
        .filter(|r| r.is_dir())
        .ok_or_else(|| StartError::NotAFolder {
            root: config.root.clone(),
        })?;
    let mut rt = tokio::runtime::Builder::new_multi_thread();
    if let Some(n) = runtime_threads() {
        rt.worker_threads(n);
    }
    let rt = rt.enable_all().thread_name("mra-serve").build()?;
    rt.block_on(async move {
        let listener = tokio::net::TcpListener::bind(config.bind).await?;
        let addr = listener.local_addr()?;
        let state = http::State::new(root, addr, &config);
        if config.warm {
            let st = state.clone();
            let _ = tokio::task::spawn_blocking(move || http::warm_all(&st)).await;
        }
        ready(addr);
        http::run(listener, state).await
    })?;
    Ok(())
}
