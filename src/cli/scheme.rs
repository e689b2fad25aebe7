//! `mra scheme analyze`: eigen-analysis of a curve subdivision mask (notes §7.5.1, §7.6.1).

use super::CliResult;
use crate::curve::analysis::{analyze, named_mask, parse_mask};
use clap::{Args, Subcommand};

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Local subdivision matrix S of a mask, its eigenvalues, affine invariance and the
    /// smoothness the spectrum suggests.
    #[command(after_help = "Examples:\n  \
        mra scheme analyze --mask \"1/4,3/4,3/4,1/4\"                   # Chaikin: 1, 1/2, 1/4, 1/4 -> C1\n  \
        mra scheme analyze --mask \"-1/16,0,9/16,1,9/16,0,-1/16\"       # Dyn-Levin four-point\n  \
        mra scheme analyze --scheme cubic --matrix\n  \
        mra scheme analyze --surface loop --valence 5               # Loop at an extraordinary vertex")]
    Analyze(AnalyzeArgs),
}

#[derive(Args, Debug)]
pub struct AnalyzeArgs {
    /// Mask a_0,…,a_{L−1} (fractions or decimals): F_i = Σ_j a_{i−2j} C_j.
    #[arg(long, allow_hyphen_values = true, required_unless_present_any = ["scheme", "surface"])]
    pub mask: Option<String>,
    /// A named scheme instead: box, linear, chaikin, cubic, quartic, four-point.
    #[arg(long, conflicts_with = "mask")]
    pub scheme: Option<String>,
    /// Window size N of the local matrix (default: the mask length).
    #[arg(long)]
    pub window: Option<usize>,
    /// Also print the matrix S.
    #[arg(long)]
    pub matrix: bool,
    /// A surface scheme instead: loop, loop-warren or catmull-clark (with --valence).
    #[arg(long, conflicts_with_all = ["mask", "scheme"], requires = "valence")]
    pub surface: Option<String>,
    /// Valence of the vertex for --surface.
    #[arg(long)]
    pub valence: Option<usize>,
    /// JSON output (with --surface).
    #[arg(long)]
    pub json: bool,
}

pub fn run(c: Command) -> CliResult {
    match c {
        Command::Analyze(a) => analyze_cmd(a),
    }
}

fn analyze_cmd(a: AnalyzeArgs) -> CliResult {
    if let (Some(surface), Some(valence)) = (&a.surface, a.valence) {
        return super::mesh::analyze_surface(surface, valence, a.json);
    }
    let mask = match (&a.mask, &a.scheme) {
        (Some(m), _) => parse_mask(m)?,
        (None, Some(s)) => named_mask(s).ok_or_else(|| {
            super::Failure(format!(
                "invalid --scheme: {s} (expected box, linear, chaikin, cubic, quartic or four-point)"
            ))
        })?,
        (None, None) => unreachable!("clap requires one of --mask / --scheme / --surface"),
    };
    let r = analyze(&mask, a.window)?;
    let mut out = String::new();
    out.push_str(&format!(
        "mask: {}\n",
        r.mask
            .iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    out.push_str(&format!("local subdivision matrix: {0}x{0}\n", r.n));
    if a.matrix {
        for row in r.matrix.chunks(r.n) {
            out.push_str("  ");
            out.push_str(
                &row.iter()
                    .map(|x| format!("{x:>9.5}"))
                    .collect::<Vec<_>>()
                    .join(" "),
            );
            out.push('\n');
        }
    }
    out.push_str("eigenvalues (by modulus):\n");
    for e in &r.eigenvalues {
        // a defective (Jordan-block) eigenvalue, like the four-point scheme's double 1/4, is only
        // determined to about √ε ≈ 1e-8 in floating point: such tiny imaginary parts are noise
        if e.im.abs() > 1e-6 {
            out.push_str(&format!("  {:.12} {:+.12}i\n", e.re, e.im));
        } else {
            out.push_str(&format!("  {:.12}\n", clean(e.re)));
        }
    }
    out.push_str(&format!(
        "affine invariant: {}\n",
        if r.affine_invariant {
            "yes (both rules sum to 1)"
        } else {
            "no (a rule does not sum to 1)"
        }
    ));
    match r.smoothness {
        Some(m) => out.push_str(&format!(
            "spectrum suggests: C{m} (1, 1/2, …, 1/2^{m} leading, the rest smaller; necessary, not sufficient)\n"
        )),
        None => out.push_str("spectrum suggests: no convergence to a continuous limit (leading eigenvalue is not a simple dominant 1)\n"),
    }
    super::curve::emit(None, &out)
}

fn clean(x: f64) -> f64 {
    if x.abs() < 1e-14 {
        0.0
    } else {
        x
    }
}
