//! `mra serve`: the `.mra` files of a folder over HTTP (IIIF Image API 3.0 at level 2,
//! a deep-zoom viewer at `/`), a shell over [`crate::serve`].

use super::{CliResult, Failure};
use crate::serve::{self, Config};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  mra generate zone-plate -o z.png --size 4096 && mra encode z.png -o pics/z.mra\n  mra serve pics            # then open http://127.0.0.1:8182/\n\nURLs: /iiif/3/{identifier}/info.json and /iiif/3/{identifier}/{region}/{size}/{rotation}/{quality}.{format};\nthe identifier is the file's path under DIR, percent-encoded; a volume slice is `vol.mra;z=12`\n(also ;y= and ;x=); 16-bit and float data take ?window=lo,hi. See docs/serve.md."
)]
pub struct ServeArgs {
    /// The folder whose .mra files are served (nothing outside it is).
    pub dir: PathBuf,
    /// Address and port to listen on (port 0: any free port, printed).
    #[arg(long, default_value = "127.0.0.1:8182")]
    pub bind: std::net::SocketAddr,
    /// Allow a bind address other than loopback (the server has no authentication).
    #[arg(long)]
    pub public: bool,
    /// Bytes of decoded levels kept between requests (e.g. 512M; at most MRA_MAX_BYTES).
    #[arg(long, default_value = "512M")]
    pub cache: String,
    /// Requests decoding at the same time (default: twice the number of cores, so that
    /// requests answered from the cache are not held behind a long decode).
    #[arg(long)]
    pub workers: Option<usize>,
    /// Before serving, decode the levels of every one-piece 3.0 file (mra encode --blocks)
    /// that the cache keeps (otherwise done in the background after a file's first request).
    #[arg(long)]
    pub warm: bool,
}

pub fn run(a: ServeArgs) -> CliResult {
    let cache_bytes = crate::limits::parse_bytes(&a.cache).ok_or_else(|| {
        Failure(format!(
            "invalid --cache: {} (expected a byte count such as 512M)",
            a.cache
        ))
    })?;
    if a.workers == Some(0) {
        return Err(Failure("invalid --workers: 0 (expected at least 1)".into()));
    }
    let workers = a
        .workers
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(2, |n| n.get()) * 2);
    let config = Config {
        root: a.dir.clone(),
        bind: a.bind,
        public: a.public,
        cache_bytes,
        limits: crate::limits::Limits::from_env()?,
        workers,
        warm: a.warm,
    };
    let dir = a.dir.display().to_string();
    serve::serve(config, |addr| {
        // the line scripts wait for: the address actually bound
        println!("mra serve: {dir} at http://{addr}/");
        use std::io::Write;
        let _ = std::io::stdout().flush();
    })
    .map_err(|e| Failure(e.to_string()))
}
