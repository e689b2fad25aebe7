//! The `mra` command line: a thin shell over the library (see `src/cli/`).

fn main() {
    restore_sigpipe();
    return_large_buffers();
    // temporary outputs are removed on Ctrl-C and SIGTERM; without the handler (no
    // thread could be started) a signal still kills the process, only less tidily
    let _ = mra::fsutil::remove_temps_on_signals();
    // past a file-size limit a write fails (EFBIG) and is reported like a full disk
    let _ = mra::fsutil::survive_file_size_limit();
    std::process::exit(mra::cli::main());
}

/// Die quietly when standard output is a closed pipe (`mra … | head`), as other Unix
/// tools do: Rust ignores SIGPIPE, which turns every later `println!` into a panic.
#[cfg(unix)]
fn restore_sigpipe() {
    extern "C" {
        fn signal(signum: i32, handler: usize) -> usize;
    }
    const SIGPIPE: i32 = 13; // Linux, macOS and the BSDs
    const SIG_DFL: usize = 0;
    // SAFETY: resetting a signal to its default action before any thread starts.
    unsafe {
        signal(SIGPIPE, SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_sigpipe() {}

/// Buffers of 1 MiB or more mapped on their own and returned to the system when freed.
/// glibc's malloc raises its mapping threshold after each large free (up to 32 MiB) and
/// then serves buffers under it from its heap, which keeps what they freed: a 256³ u16
/// encode at `--bpp 1` held 101 MB of memory for 86 MB of live buffers, 93 MB with the
/// threshold fixed (the same bytes; 0.1 s more of system time for the page faults).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn return_large_buffers() {
    extern "C" {
        fn mallopt(param: i32, value: i32) -> i32;
    }
    const M_MMAP_THRESHOLD: i32 = -3; // <malloc.h>
                                      // SAFETY: an allocator setting, changed before any thread starts or allocates much;
                                      // its result is ignored (refused, the allocator keeps its own threshold).
    unsafe {
        mallopt(M_MMAP_THRESHOLD, 1 << 20);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn return_large_buffers() {}
