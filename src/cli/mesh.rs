//! `mra mesh …` (to be written).

use clap::Subcommand;

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Placeholder until the mesh commands land.
    #[command(hide = true)]
    Placeholder,
}

pub fn run(_c: Command) -> super::CliResult {
    Err(super::Failure("not implemented yet".into()))
}
