//! `mra demo`.

use super::{CliResult, Failure};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
#[command(after_help = "Example:\n  mra demo --out /tmp/mra-demo")]
pub struct DemoArgs {
    /// Folder for the demo's output files.
    #[arg(long, default_value = "mra-demo")]
    pub out: PathBuf,
    /// Print the table as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: DemoArgs) -> CliResult {
    let rows = crate::demo::run(&a.out).map_err(|e| Failure::context(a.out.display(), e))?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).map_err(|e| Failure(e.to_string()))?
        );
        return Ok(());
    }
    let jw = rows.iter().map(|r| r.job.len()).max().unwrap_or(3).max(3);
    let dw = rows.iter().map(|r| r.data.len()).max().unwrap_or(4).max(4);
    println!("{:<jw$}  {:<dw$}  {:>8}  result", "job", "data", "time");
    for r in &rows {
        println!(
            "{:<jw$}  {:<dw$}  {:>7.3}s  {}",
            r.job, r.data, r.seconds, r.result
        );
    }
    println!("\noutputs in {}:", a.out.display());
    for r in rows.iter().filter_map(|r| r.output.as_ref()) {
        println!("  {}", r.display());
    }
    Ok(())
}
