//! The `mra` command line: a thin shell over the library (see `src/cli/`).

fn main() {
    std::process::exit(mra::cli::main());
}
