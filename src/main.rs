//! The `mra` command line: a thin shell over the library (see `src/cli/`).

fn main() {
    restore_sigpipe();
    mra::tuning::use_allocator(mra::tuning::Allocator::ReturnLarge);
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
