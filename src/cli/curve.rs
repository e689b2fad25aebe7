//! `mra curve …`: evaluate, split, elevate, insert knots and plot Bézier, B-spline and NURBS
//! curves given as CSV control points (see `mra::curve::csv`).

use super::{CliResult, Failure};
use crate::curve::csv::{self, PointTable};
use crate::curve::plot::{self, PlotData};
use crate::curve::{geometry, knot, BSpline, Bezier, Curve, KnotVector, Nurbs};
use crate::{Error, Result};
use clap::{Args, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Curve style transfer (§9.7.1): a stroke's details, in its local tangent/normal
    /// frame, added to a new base curve.
    Style(super::style::StyleArgs),
    /// Evaluate points or derivatives: one point per line (parameter first with --with-u).
    #[command(after_help = "Examples:\n  \
        mra curve eval --kind bezier --at 0.5 corpus/curves/example24.csv        # 3.5,1.5 (Example 2.4)\n  \
        mra curve eval --order 4 --knots open --samples 5 --with-u corpus/curves/wave.csv\n  \
        mra curve eval --kind nurbs --order 3 --knots corpus/curves/circle_knots.txt --samples 8 corpus/curves/circle.csv\n  \
        mra curve eval --order 3 --knots uniform --derivative 1 --at 2.5 corpus/curves/wave.csv\n  \
        mra curve eval --kind nurbs --order 3 --knots corpus/curves/circle_knots.txt --curvature --at 0.1 corpus/curves/circle.csv   # 1")]
    Eval(EvalArgs),
    /// Split a Bézier curve at u into two control polygons (de Casteljau, §2.6).
    #[command(
        after_help = "Example:\n  mra curve split --kind bezier --u 0.5 corpus/curves/example24.csv"
    )]
    Split(SplitArgs),
    /// Raise the degree of a Bézier curve without changing it.
    #[command(
        after_help = "Example:\n  mra curve elevate --kind bezier --times 2 corpus/curves/example24.csv"
    )]
    Elevate(ElevateArgs),
    /// Insert knots (Boehm, §7.2) or the midpoints of all knot intervals (one subdivision step).
    #[command(after_help = "Examples:\n  \
        mra curve insert-knot --order 3 --u 0.3 --u 0.6 corpus/curves/wave.csv\n  \
        mra curve insert-knot --order 3 --midpoints --knots-out /tmp/fine_knots.txt corpus/curves/wave.csv")]
    InsertKnot(InsertArgs),
    /// Draw the curve, its control polygon and knot points to SVG or PNG.
    #[command(
        after_help = "Example:\n  mra curve plot --order 4 corpus/curves/wave.csv -o /tmp/wave.svg\n  \
        mra curve plot --kind nurbs --order 3 --knots corpus/curves/circle_knots.txt corpus/curves/circle.csv -o /tmp/circle.png"
    )]
    Plot(PlotArgs),
}

/// Largest number of printed or plotted samples.
pub const MAX_SAMPLES: usize = 10_000_000;

/// How the control points become a curve.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Bézier curve of degree (number of points − 1).
    Bezier,
    /// B-spline of order --order on --knots.
    Bspline,
    /// NURBS: B-spline with the weights of the `w` column (1 when absent).
    Nurbs,
}

#[derive(Args, Debug, Clone)]
pub struct CurveSpec {
    /// Control points: CSV, one point per line; a header naming a `w` column gives NURBS
    /// weights (`-`: standard input).
    pub input: PathBuf,
    /// Curve representation.
    #[arg(long, value_enum, default_value = "bspline")]
    pub kind: Kind,
    /// Order k = degree + 1 (B-spline, NURBS).
    #[arg(long, default_value_t = 4)]
    pub order: usize,
    /// Knots: `open` (clamped on 0..1, §3.8.3), `uniform` (0, 1, 2, …) or a file of numbers.
    #[arg(long, default_value = "open")]
    pub knots: String,
}

#[derive(Args, Debug)]
pub struct EvalArgs {
    #[command(flatten)]
    pub spec: CurveSpec,
    /// Number of evenly spaced parameters over the valid range (default 100).
    #[arg(long, conflicts_with = "at")]
    pub samples: Option<usize>,
    /// Comma-separated parameters.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<String>,
    /// Derivative order (0 = points).
    #[arg(long, default_value_t = 0)]
    pub derivative: usize,
    /// Print the parameter before each point.
    #[arg(long)]
    pub with_u: bool,
    /// Print the 2D normal (−y′, x′) of §1.3 instead of the point (planar curves).
    #[arg(long, conflicts_with_all = ["curvature", "derivative"])]
    pub normal: bool,
    /// Print the curvature κ (signed for planar curves) instead of the point.
    #[arg(long, conflicts_with = "derivative")]
    pub curvature: bool,
    /// Output file (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct SplitArgs {
    #[command(flatten)]
    pub spec: CurveSpec,
    /// Split parameter (inside the valid range).
    #[arg(long)]
    pub u: f64,
    /// Output file (default: standard output); the two polygons are separated by a blank line.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ElevateArgs {
    #[command(flatten)]
    pub spec: CurveSpec,
    /// How many degrees to add.
    #[arg(long, default_value_t = 1)]
    pub times: usize,
    /// Output file (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct InsertArgs {
    #[command(flatten)]
    pub spec: CurveSpec,
    /// Knot value to insert (repeatable).
    #[arg(long, allow_hyphen_values = true)]
    pub u: Vec<f64>,
    /// Insert the midpoint of every knot interval of the valid range (one subdivision step).
    #[arg(long)]
    pub midpoints: bool,
    /// Write the new knot sequence here (it is also printed as a `# knots:` comment line).
    #[arg(long)]
    pub knots_out: Option<PathBuf>,
    /// Output file (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct PlotArgs {
    #[command(flatten)]
    pub spec: CurveSpec,
    /// Output picture: .svg or .png (`-`: standard output, with --format).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output): svg or png.
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Curve samples.
    #[arg(long, default_value_t = 400)]
    pub samples: usize,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480")]
    pub size: String,
}

/// A curve read from the command line.
pub enum Loaded {
    Bezier(Bezier),
    BSpline(BSpline),
    Nurbs(Nurbs),
}

impl Loaded {
    pub fn curve(&self) -> &dyn Curve {
        match self {
            Loaded::Bezier(c) => c,
            Loaded::BSpline(c) => c,
            Loaded::Nurbs(c) => c,
        }
    }
    /// The control polygon (Euclidean points).
    pub fn polygon(&self) -> Vec<f64> {
        match self {
            Loaded::Bezier(c) => c.points().to_vec(),
            Loaded::BSpline(c) => c.points().to_vec(),
            Loaded::Nurbs(c) => c.points(),
        }
    }
    /// Knot values inside the valid range (none for Bézier curves).
    pub fn range_knots(&self) -> Vec<f64> {
        let (t, (a, b)) = match self {
            Loaded::Bezier(_) => return vec![],
            Loaded::BSpline(c) => (c.knots(), c.range()),
            Loaded::Nurbs(c) => (c.knots(), c.range()),
        };
        let mut v: Vec<f64> = t.iter().copied().filter(|&x| x >= a && x <= b).collect();
        v.dedup();
        v
    }
}

/// A text file, or standard input for `-`.
pub(crate) fn read_text(path: &Path) -> std::result::Result<String, Failure> {
    super::stdio::read_text(path)
}

pub(crate) fn read_table(path: &Path) -> std::result::Result<PointTable, Failure> {
    csv::parse(&read_text(path)?).map_err(|e| Failure::context(path.display(), e))
}

/// Resolve `open` / `uniform` / FILE for `n` points of order `k`.
pub(crate) fn knots_for(spec: &str, n: usize, k: usize) -> std::result::Result<Vec<f64>, Failure> {
    match spec {
        "open" => Ok(KnotVector::open(n, k)?.as_slice().to_vec()),
        "uniform" => Ok(KnotVector::uniform(n, k).as_slice().to_vec()),
        file => {
            let p = Path::new(file);
            csv::parse_numbers(&read_text(p)?, "knot").map_err(|e| Failure::context(p.display(), e))
        }
    }
}

/// Build the curve described by the arguments.
pub fn load(spec: &CurveSpec) -> std::result::Result<Loaded, Failure> {
    load_path(&spec.input, spec.kind, spec.order, &spec.knots)
}

/// Build a curve from a CSV file with the given representation, order and knots.
pub fn load_path(
    path: &Path,
    kind: Kind,
    order: usize,
    knots: &str,
) -> std::result::Result<Loaded, Failure> {
    let t = read_table(path)?;
    let ctx = |e: Error| Failure::context(path.display(), e);
    if t.rows > 1 {
        return Err(ctx(Error::format(
            format!("{} rows separated by blank lines", t.rows),
            "one curve: no blank lines between points",
        )));
    }
    let n = t.cols;
    Ok(match kind {
        Kind::Bezier => {
            if t.weights.is_some() {
                return Err(ctx(Error::Unsupported {
                    what: "weights for a Bézier curve",
                    value: "use --kind nurbs".into(),
                }));
            }
            Loaded::Bezier(Bezier::new(t.points, t.dim).map_err(ctx)?)
        }
        Kind::Bspline => {
            if t.weights.is_some() {
                return Err(ctx(Error::Unsupported {
                    what: "weights for a B-spline",
                    value: "use --kind nurbs".into(),
                }));
            }
            check_order(n, order).map_err(ctx)?;
            let knots = knots_for(knots, n, order)?;
            Loaded::BSpline(BSpline::new(t.points, t.dim, order, knots).map_err(ctx)?)
        }
        Kind::Nurbs => {
            check_order(n, order).map_err(ctx)?;
            let knots = knots_for(knots, n, order)?;
            let w = t.weights.unwrap_or_else(|| vec![1.0; n]);
            Loaded::Nurbs(Nurbs::new(&t.points, &w, t.dim, order, knots).map_err(ctx)?)
        }
    })
}

impl Loaded {
    /// The curve as an owned trait object.
    pub fn boxed(self) -> Box<dyn Curve> {
        match self {
            Loaded::Bezier(c) => Box::new(c),
            Loaded::BSpline(c) => Box::new(c),
            Loaded::Nurbs(c) => Box::new(c),
        }
    }
}

pub(crate) fn check_order(n: usize, k: usize) -> Result<()> {
    if k == 0 {
        return Err(Error::parameter("order", 0, "at least 1"));
    }
    if n < k {
        return Err(Error::Parameter {
            name: "number of control points",
            value: format!("{n} for order {k}"),
            expected: "at least the order (degree + 1)",
        });
    }
    Ok(())
}

/// `n` evenly spaced parameters over `[a, b]`, the last exactly `b`.
pub fn sample_params((a, b): (f64, f64), n: usize) -> Vec<f64> {
    match n {
        0 => vec![],
        1 => vec![a],
        _ => (0..n)
            .map(|i| {
                if i + 1 == n {
                    b
                } else {
                    a + (b - a) * i as f64 / (n - 1) as f64
                }
            })
            .collect(),
    }
}

/// Write `bytes` to `path` through a temporary file in the same folder, then rename (never a
/// partial output file; `crate::fsutil`); `-`: standard output.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> std::result::Result<(), Failure> {
    super::stdio::write_bytes(path, bytes)
}

/// Print to standard output or write atomically to `out`.
pub(crate) fn emit(out: Option<&Path>, text: &str) -> CliResult {
    match out {
        Some(p) => write_atomic(p, text.as_bytes()),
        None => {
            use std::io::Write;
            let mut so = std::io::stdout().lock();
            so.write_all(text.as_bytes())
                .map_err(|e| Failure::context("standard output", e))
        }
    }
}

fn parse_list(s: &str) -> std::result::Result<Vec<f64>, Failure> {
    Ok(csv::parse_numbers(s, "--at")?)
}

pub fn run(c: Command) -> CliResult {
    match c {
        Command::Eval(a) => eval(a),
        Command::Split(a) => split(a),
        Command::Elevate(a) => elevate(a),
        Command::InsertKnot(a) => insert_knot(a),
        Command::Plot(a) => plot_cmd(a),
        Command::Style(a) => super::style::style(a),
    }
}

fn eval(a: EvalArgs) -> CliResult {
    let loaded = load(&a.spec)?;
    let c = loaded.curve();
    let samples = a.samples.unwrap_or(100);
    if samples > MAX_SAMPLES {
        return Err(Error::LimitsExceeded {
            what: "--samples",
            requested: samples as u64,
            limit: MAX_SAMPLES as u64,
        }
        .into());
    }
    let params = match &a.at {
        Some(s) => parse_list(s)?,
        None => sample_params(c.domain(), samples),
    };
    let mut out = String::new();
    let mut p = vec![0.0; c.dim()];
    for &u in &params {
        if a.normal {
            p = geometry::normal_2d(c, u)?.to_vec();
        } else if a.curvature {
            p = vec![geometry::curvature(c, u)?];
        } else {
            c.eval_derivative_into(u, a.derivative, &mut p)?;
        }
        let mut line: Vec<String> = Vec::with_capacity(c.dim() + 1);
        if a.with_u {
            line.push(u.to_string());
        }
        line.extend(p.iter().map(|x| x.to_string()));
        out.push_str(&line.join(","));
        out.push('\n');
    }
    emit(a.output.as_deref(), &out)
}

fn bezier_only(l: Loaded) -> std::result::Result<Bezier, Failure> {
    match l {
        Loaded::Bezier(b) => Ok(b),
        _ => Err(Error::Unsupported {
            what: "curve kind for this command",
            value: "B-spline/NURBS (use --kind bezier)".into(),
        }
        .into()),
    }
}

fn split(a: SplitArgs) -> CliResult {
    let mut out = String::new();
    match load(&a.spec)? {
        Loaded::Bezier(b) => {
            let (l, r) = b.split(a.u)?;
            csv::write_points(&mut out, l.points(), Curve::dim(&l), None);
            out.push('\n');
            csv::write_points(&mut out, r.points(), Curve::dim(&r), None);
        }
        Loaded::BSpline(c) => {
            let (l, r) = knot::split(&c, a.u)?;
            for h in [l, r] {
                out.push_str(&format!("# knots: {}\n", join(h.knots())));
                csv::write_points(&mut out, h.points(), h.dim(), None);
                out.push('\n');
            }
            out.pop();
        }
        Loaded::Nurbs(c) => {
            let (l, r) = knot::split_nurbs(&c, a.u)?;
            for h in [l, r] {
                out.push_str(&format!("# knots: {}\n", join(h.knots())));
                out.push_str(&header(Curve::dim(&h)));
                csv::write_points(&mut out, &h.points(), Curve::dim(&h), Some(&h.weights()));
                out.push('\n');
            }
            out.pop();
        }
    }
    emit(a.output.as_deref(), &out)
}

fn join(v: &[f64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// A CSV header naming the coordinates and the weight column.
fn header(dim: usize) -> String {
    let names = ["x", "y", "z"];
    let mut h: Vec<String> = (0..dim)
        .map(|i| names.get(i).map_or(format!("x{i}"), |s| s.to_string()))
        .collect();
    h.push("w".into());
    h.join(",") + "\n"
}

fn elevate(a: ElevateArgs) -> CliResult {
    let mut b = bezier_only(load(&a.spec)?)?;
    for _ in 0..a.times {
        b = b.elevate();
    }
    let mut out = String::new();
    csv::write_points(&mut out, b.points(), Curve::dim(&b), None);
    emit(a.output.as_deref(), &out)
}

fn insert_knot(a: InsertArgs) -> CliResult {
    if a.u.is_empty() && !a.midpoints {
        return Err(Failure(
            "nothing to insert: give --u U (repeatable) or --midpoints".into(),
        ));
    }
    let loaded = load(&a.spec)?;
    let (pts, dim, w, knots) = match loaded {
        Loaded::Bezier(_) => {
            return Err(Error::Unsupported {
                what: "knot insertion for a Bézier curve",
                value: "use --kind bspline or nurbs".into(),
            }
            .into())
        }
        Loaded::BSpline(mut c) => {
            for &u in &a.u {
                c = knot::insert(&c, u)?;
            }
            if a.midpoints {
                c = knot::insert_midpoints(&c)?;
            }
            (c.points().to_vec(), c.dim(), None, c.knots().to_vec())
        }
        Loaded::Nurbs(mut c) => {
            for &u in &a.u {
                c = knot::insert_nurbs(&c, u)?;
            }
            if a.midpoints {
                c = knot::insert_midpoints_nurbs(&c)?;
            }
            (
                c.points(),
                Curve::dim(&c),
                Some(c.weights()),
                c.knots().to_vec(),
            )
        }
    };
    let knot_text = knots
        .iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let mut out = format!("# knots: {knot_text}\n");
    if w.is_some() {
        let names = ["x", "y", "z"];
        let mut h: Vec<String> = (0..dim)
            .map(|i| names.get(i).map_or(format!("x{i}"), |s| s.to_string()))
            .collect();
        h.push("w".into());
        out.push_str(&h.join(","));
        out.push('\n');
    }
    csv::write_points(&mut out, &pts, dim, w.as_deref());
    if let Some(p) = &a.knots_out {
        write_atomic(p, format!("{knot_text}\n").as_bytes())?;
    }
    emit(a.output.as_deref(), &out)
}

pub(crate) fn parse_size(s: &str) -> std::result::Result<(usize, usize), Failure> {
    let bad = || {
        Failure(format!(
            "invalid --size: {s} (expected WIDTHxHEIGHT, e.g. 640x480)"
        ))
    };
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    Ok((
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    ))
}

fn plot_cmd(a: PlotArgs) -> CliResult {
    if a.samples > MAX_SAMPLES {
        return Err(Error::LimitsExceeded {
            what: "--samples",
            requested: a.samples as u64,
            limit: MAX_SAMPLES as u64,
        }
        .into());
    }
    let loaded = load(&a.spec)?;
    let c = loaded.curve();
    let (w, h) = parse_size(&a.size)?;
    let dim = c.dim();
    let xy = |p: &[f64]| [p[0], if dim > 1 { p[1] } else { 0.0 }];
    let mut d = PlotData::default();
    for u in sample_params(c.domain(), a.samples.max(2)) {
        d.curve.push(xy(&c.point(u)?));
    }
    d.polygon = loaded.polygon().chunks(dim).map(xy).collect();
    for u in loaded.range_knots() {
        d.knots.push(xy(&c.point(u)?));
    }
    let ext = if super::stdio::is_std(&a.output) {
        super::stdio::std_format(a.format.as_deref(), None, "svg, png")?
    } else {
        a.output
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase()
    };
    let bytes = match ext.as_str() {
        "svg" => plot::svg(&d, w, h).into_bytes(),
        "png" => plot::png(&d, w, h)?,
        other => {
            return Err(Error::Unsupported {
                what: "picture format",
                value: format!("{other:?} (use .svg or .png)"),
            }
            .into())
        }
    };
    write_atomic(&a.output, &bytes)
}
