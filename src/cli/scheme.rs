//! `mra scheme analyze`: eigen-analysis of a curve subdivision mask (notes §7.5.1, §7.6.1).
//! `mra scheme keep`: the notes' Figure 9.19 protocol (keep P% of the details) per MRA scheme.

use super::{CliResult, Failure};
use crate::curve::analysis::{analyze, named_mask, parse_mask};
use crate::scheme::{Boundary, Scheme};
use clap::{Args, Subcommand};
use std::path::PathBuf;

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
    /// PSNR after keeping the largest P% of the details (gain-weighted, no quantization), one
    /// row per MRA scheme: the notes' Figure 9.19 protocol on your own image.
    #[command(after_help = "Examples:\n  \
        mra scheme keep corpus/zone_plate_256.png                            # every scheme, 1/2/5/10/20%\n  \
        mra scheme keep corpus/noise_rgb_128.png --gray --scheme haar,cdf97,linear --json\n  \
        mra scheme keep dem.tif --percent 0.5,1,2 --levels 6\n\n\
        The details of every band are weighted by the norm of their synthesis function (the\n\
        gain), the largest P% are kept, the rest set to zero, and the image is reconstructed.\n\
        Colour images are kept in YCoCg as the codec does; --gray takes the luma first.")]
    Keep(KeepArgs),
}

#[derive(Args, Debug)]
pub struct KeepArgs {
    /// Image, heightmap or volume.
    pub input: PathBuf,
    /// Percentages of the details to keep, comma-separated.
    #[arg(long, default_value = "1,2,5,10,20", value_delimiter = ',')]
    pub percent: Vec<f64>,
    /// Schemes to compare, comma-separated (default: every scheme).
    #[arg(long, value_delimiter = ',')]
    pub scheme: Vec<Scheme>,
    /// Levels of the decomposition.
    #[arg(long, default_value_t = 5)]
    pub levels: usize,
    /// Boundary mode.
    #[arg(long, default_value = "symmetric")]
    pub boundary: Boundary,
    /// Convert a colour image to its luma (BT.601, rounded) first.
    #[arg(long)]
    pub gray: bool,
    /// One JSON object: {"percent": [...], "rows": [{"scheme": .., "psnr": [...]}]}.
    #[arg(long)]
    pub json: bool,
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
        Command::Keep(k) => keep_cmd(k),
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

fn keep_cmd(k: KeepArgs) -> CliResult {
    if let Some(p) = k.percent.iter().find(|p| !(**p > 0.0 && **p <= 100.0)) {
        return Err(Failure(format!(
            "invalid --percent: {p} (expected percentages in (0, 100])"
        )));
    }
    if k.levels == 0 || k.levels > 16 {
        return Err(Failure(format!(
            "invalid --levels: {} (expected 1 to 16)",
            k.levels
        )));
    }
    let mut r = super::io_cmds::read_input(&k.input, &Default::default())?;
    if k.gray && r.channels >= 3 {
        r = crate::metrics::luma(&r).map_err(|e| Failure::context(k.input.display(), e))?;
    }
    let schemes = if k.scheme.is_empty() {
        Scheme::ALL.to_vec()
    } else {
        k.scheme.clone()
    };
    let mut rows = Vec::new();
    for &s in &schemes {
        let mut psnr = Vec::new();
        for &p in &k.percent {
            let v = crate::codec::keep_psnr(&r, s, k.boundary, k.levels, p, true)
                .map_err(|e| Failure::context(k.input.display(), e))?;
            psnr.push(v);
        }
        rows.push((s, psnr));
    }
    if k.json {
        let rows: Vec<_> = rows
            .iter()
            .map(|(s, p)| serde_json::json!({"scheme": s.name(), "psnr": p}))
            .collect();
        let v = serde_json::json!({
            "input": k.input.display().to_string(),
            "levels": k.levels,
            "boundary": k.boundary.name(),
            "percent": k.percent,
            "rows": rows,
        });
        println!("{v}");
    } else {
        let head: Vec<String> = k.percent.iter().map(|p| format!("{p}%")).collect();
        println!("| scheme | {} |", head.join(" | "));
        println!("|---|{}", "---|".repeat(head.len()));
        for (s, p) in rows {
            let cells: Vec<String> = p.iter().map(|v| format!("{v:.2}")).collect();
            println!("| {s} | {} |", cells.join(" | "));
        }
    }
    Ok(())
}
