//! `mra curve …` (to be written).

use clap::Subcommand;

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Placeholder until the curve commands land.
    #[command(hide = true)]
    Placeholder,
}

pub fn run(_c: Command) -> super::CliResult {
    Err(super::Failure("not implemented yet".into()))
}
