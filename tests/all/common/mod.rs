//! Helpers shared by the integration tests (`use super::common;` in a test module).
//!
//! - [`corpus`]: a file of the shared corpus, or a printed skip. With `MRA_REQUIRE_CORPUS=1`
//!   a missing corpus or file fails the test instead.
//! - [`scratch_dir`] and [`scratch_file`]: a fresh directory per call, so tests running in
//!   parallel never share a file.
//! - [`mra_with_stdin`]: the `mra` binary run with bytes on its standard input.
//! - [`grid_obj`]: a bumpy grid of triangles as OBJ text.
//! - [`wave_field`]: a smooth wave with a little xorshift noise, the codec tests' raster.
//! - [`vector_builds`]: whether the kernels' AVX2 builds can be compared with the scalar
//!   one here; a printed skip otherwise, a failure with `MRA_REQUIRE_AVX2=1`.
//!
//! Skips are written straight to the process's standard error, past the test harness's
//! capture, so they show in the log of a passing run, and appended to `$MRA_SKIP_LOG`
//! when set (`.ci/run` counts them).

#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The variable that turns a missing corpus or corpus file into a failure.
pub const REQUIRE_CORPUS: &str = "MRA_REQUIRE_CORPUS";
/// The variable that turns a CPU without AVX2 (and FMA) into a failure of the CPU-level tests.
pub const REQUIRE_AVX2: &str = "MRA_REQUIRE_AVX2";

fn flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| v == "1")
}

fn test_name() -> String {
    std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string()
}

/// The variable naming a file to which every skip appends its line (`.ci/run` sets it
/// and prints how many tests skipped, and which, at the end of the run).
pub const SKIP_LOG: &str = "MRA_SKIP_LOG";

/// One line on the process's standard error, not captured by the test harness, and
/// appended to the file `$MRA_SKIP_LOG` when it is set.
pub fn skip(reason: std::fmt::Arguments<'_>) {
    let line = format!("{}: {reason}", test_name());
    let _ = writeln!(std::io::stderr(), "skipped: {line}");
    if let Some(log) = std::env::var_os(SKIP_LOG) {
        // one write of one line per skip: the lines of parallel tests do not interleave
        let _ = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(log)
            .and_then(|mut f| f.write_all(format!("{line}\n").as_bytes()));
    }
}

/// The shared corpus: `$MRA_CORPUS` when set, else `../shared/corpus` beside the repository.
pub fn corpus_root() -> PathBuf {
    std::env::var_os("MRA_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus"))
}

/// `rel` inside the shared corpus (a file or folder; `""` for the corpus itself).
///
/// Absent corpus or path: prints `skipped: <test>: …` and gives `None`, or panics when
/// `MRA_REQUIRE_CORPUS=1`.
pub fn corpus(rel: &str) -> Option<PathBuf> {
    let root = corpus_root();
    let require = flag(REQUIRE_CORPUS);
    if !root.is_dir() {
        if require {
            panic!(
                "{REQUIRE_CORPUS}=1 but the corpus is absent at {}",
                root.display()
            );
        }
        skip(format_args!("no corpus at {}", root.display()));
        return None;
    }
    let p = root.join(rel);
    if !p.exists() {
        if require {
            panic!(
                "{REQUIRE_CORPUS}=1 but {} is not in the corpus at {}",
                rel,
                root.display()
            );
        }
        skip(format_args!(
            "{rel} is not in the corpus at {}",
            root.display()
        ));
        return None;
    }
    Some(p)
}

/// Every path of `rels` inside the corpus, or `None` (with the skip or panic of [`corpus`])
/// as soon as one is missing.
pub fn corpus_all<const N: usize>(rels: [&str; N]) -> Option<[PathBuf; N]> {
    let mut out: [PathBuf; N] = std::array::from_fn(|_| PathBuf::new());
    for (o, rel) in out.iter_mut().zip(rels) {
        *o = corpus(rel)?;
    }
    Some(out)
}

static SCRATCH: AtomicUsize = AtomicUsize::new(0);

/// The folder holding every scratch directory of this test binary's runs.
fn scratch_root() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("mra-tests")
}

/// Removes the scratch directories of runs of this test binary that have ended (their
/// process id is gone), once per process, where `/proc` tells.
fn remove_stale() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let prefix = format!("{}-", env!("CARGO_CRATE_NAME"));
        let Ok(entries) = std::fs::read_dir(scratch_root()) else {
            return;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let Some(rest) = name.strip_prefix(&prefix) else {
                continue;
            };
            let Some(pid) = rest.split('-').next() else {
                continue;
            };
            if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    });
}

/// A new, empty directory that no other call (in this process or another) returns:
/// `$CARGO_TARGET_TMPDIR/mra-tests/<test binary>-<process id>-<count>-<tag>`.
pub fn scratch_dir(tag: &str) -> PathBuf {
    remove_stale();
    let n = SCRATCH.fetch_add(1, Ordering::Relaxed);
    let tag: String = tag
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let d = scratch_root().join(format!(
        "{}-{}-{n}-{tag}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    d
}

/// `name` inside a new [`scratch_dir`]: the file name is kept as given (readers may go by
/// its extension), the folder is unique to this call.
pub fn scratch_file(name: &str) -> PathBuf {
    scratch_dir(name).join(name)
}

/// Whether a wider build of the kernels than the scalar one runs here (AVX2 with FMA or
/// more, and `MRA_CPU` not capping it to scalar), so CPU-level tests compare builds.
///
/// When not: prints `skipped: <test>: …`, or panics when `MRA_REQUIRE_AVX2=1`.
pub fn vector_builds() -> bool {
    let n = mra::kernel::CpuLevel::available().len();
    if n > 1 {
        return true;
    }
    if flag(REQUIRE_AVX2) {
        panic!("{REQUIRE_AVX2}=1 but only the scalar build of the kernels runs here");
    }
    skip(format_args!(
        "the AVX2 and AVX-512 builds of the kernels (not run here: no AVX2 with FMA, or \
         MRA_CPU=scalar); the scalar build is still checked"
    ));
    false
}

/// Whether this CPU runs AVX2 with FMA (whatever `MRA_CPU` says), for tests that set
/// `MRA_CPU` in child processes. When not: prints a skip, or panics when
/// `MRA_REQUIRE_AVX2=1`.
pub fn cpu_has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    let has =
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma");
    #[cfg(not(target_arch = "x86_64"))]
    let has = false;
    if !has {
        if flag(REQUIRE_AVX2) {
            panic!("{REQUIRE_AVX2}=1 but this CPU has no AVX2 with FMA");
        }
        skip(format_args!("this CPU has no AVX2 with FMA"));
    }
    has
}

/// `mra args` (in `dir` when given) with `stdin` fed from a thread, so a large input
/// cannot block against a full output pipe; the child may exit before reading it all
/// (on bad arguments): the broken pipe is ignored.
pub fn mra_with_stdin(dir: Option<&Path>, args: &[&str], stdin: &[u8]) -> std::process::Output {
    use std::process::{Command, Stdio};
    let mut c = Command::new(env!("CARGO_BIN_EXE_mra"));
    c.args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(d) = dir {
        c.current_dir(d);
    }
    let mut child = c.spawn().unwrap();
    let mut input = child.stdin.take().unwrap();
    let bytes = stdin.to_vec();
    let feed = std::thread::spawn(move || {
        let _ = input.write_all(&bytes);
    });
    let o = child.wait_with_output().unwrap();
    let _ = feed.join();
    o
}

/// An `n × n` grid of `2 (n − 1)²` triangles as OBJ text, vertex `(x, y)` at height
/// `((x·y) mod bumps)·step`.
pub fn grid_obj(n: usize, bumps: usize, step: f64) -> String {
    let mut obj = String::new();
    for y in 0..n {
        for x in 0..n {
            obj += &format!("v {x} {y} {}\n", ((x * y) % bumps) as f64 * step);
        }
    }
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let v = |dx: usize, dy: usize| (y + dy) * n + x + dx + 1;
            obj += &format!("f {} {} {}\n", v(0, 0), v(1, 0), v(1, 1));
            obj += &format!("f {} {} {}\n", v(0, 0), v(1, 1), v(0, 1));
        }
    }
    obj
}

/// The frequencies and noise of [`wave_field`].
#[derive(Clone, Copy)]
pub struct Wave {
    /// Radians per sample along the last axis.
    pub fx: f64,
    /// Radians per row (position / last extent).
    pub fy: f64,
    /// Peak-to-peak noise, as a fraction of `hi`.
    pub noise: f64,
}

/// A raster of `dims` (a volume from three axes on) whose sample `i` (channel `c`, at `x`
/// along the last axis and row `y` before it) is
/// `hi · clamp(0.5 + 0.35·sin(fx·x + c)·cos(fy·y) + noise·(u − 0.5), 0, 1)`,
/// `u` uniform in [0, 1) from an xorshift stream seeded by `seed`.
pub fn wave_field(
    dims: &[usize],
    channels: usize,
    ty: mra::io::SampleType,
    seed: u64,
    hi: f64,
    wave: Wave,
) -> mra::io::Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let mut x = seed | 1;
    let v: Vec<f64> = (0..n)
        .map(|i| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let p = i / channels;
            let (px, py) = ((p % w) as f64, (p / w) as f64);
            let s =
                0.5 + 0.35 * (px * wave.fx + (i % channels) as f64).sin() * (py * wave.fy).cos();
            let u = (x >> 40) as f64 / (1u64 << 24) as f64;
            hi * (s + wave.noise * (u - 0.5)).clamp(0.0, 1.0)
        })
        .collect();
    let kind = if dims.len() >= 3 {
        mra::io::DataKind::Volume
    } else {
        mra::io::DataKind::Image
    };
    mra::io::Raster::new(
        dims.to_vec(),
        channels,
        mra::io::Samples::from_f64(&v, ty),
        kind,
    )
    .unwrap()
}

/// `f` run on a pool of `threads` threads (files and decodes must not depend on it).
pub fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// The options of the streamed tests: `rate` at `levels` levels, CDF 9/7 with symmetric
/// ends, code-blocks, the default effort.
pub fn stream_opts(rate: mra::codec::Rate, levels: usize) -> mra::codec::EncodeOptions {
    mra::codec::EncodeOptions {
        rate,
        levels,
        boundary: mra::scheme::Boundary::Symmetric,
        scheme: mra::scheme::Scheme::Cdf97,
        format: mra::codec::Format::Blocks,
        effort: mra::codec::DEFAULT_EFFORT,
    }
}

/// The one-transform file of `r` (`codec::encode_streamed` of the raster as a slab
/// source); the byte count it returns is the file's length.
pub fn stream_encode(r: &mra::io::Raster, o: &mra::codec::EncodeOptions) -> Vec<u8> {
    let mut out = Vec::new();
    let n =
        mra::codec::encode_streamed(&mut mra::io::slab::MemorySlabs::new(r), o, &mut out).unwrap();
    assert_eq!(n as usize, out.len());
    out
}
