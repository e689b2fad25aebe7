//! `mra surface …`: tensor-product patches, exact NURBS primitives and the curve-based surfaces
//! of notes ch. 5, tessellated to OBJ / PLY / OFF meshes with vertex normals (written by
//! `mesh::io`); shaded PNG previews (drawn by `mesh::render`).

use super::curve::{check_order, knots_for, load_path, parse_size, read_table, write_atomic, Kind};
use super::{CliResult, Failure};
use crate::curve::csv;
use crate::mesh::io::{self as mesh_io, ply::Encoding, Format};
use crate::mesh::render::{render_png, Options};
use crate::surface::{
    tessellate, Coons, CrossBlend, FaceKind, Loft, Revolution, RotationalBlend, Surface, Sweep,
    TensorPatch,
};
use crate::Error;
use clap::{Args, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Tensor-product Bézier / B-spline / NURBS patch from a control net (§5.3).
    #[command(after_help = "Examples:\n  \
        mra surface patch --kind bezier corpus/curves/patch44.csv -o /tmp/patch.obj\n  \
        mra surface patch --kind bspline --order 3,3 --resolution 40,40 --quads corpus/curves/patch44.csv -o /tmp/patch.ply")]
    Patch(PatchArgs),
    /// Exact NURBS sphere, torus or cylinder (revolved rational profiles, §4.1 + §5.2.3).
    #[command(
        after_help = "Example:\n  mra surface primitive --shape torus --radius 2 --minor 0.6 -o /tmp/torus.obj"
    )]
    Primitive(PrimitiveArgs),
    /// Ruled (lofted) surface between two curves (§5.2.1).
    #[command(
        after_help = "Example:\n  mra surface loft --kind bezier corpus/curves/coons_p0.csv corpus/curves/coons_p1.csv -o /tmp/loft.obj"
    )]
    Loft(LoftArgs),
    /// Bilinearly blended Coons patch from four boundary curves (§5.2.2).
    #[command(
        after_help = "Example:\n  mra surface coons --kind bezier --p0 corpus/curves/coons_p0.csv --p1 corpus/curves/coons_p1.csv \\\n      --q0 corpus/curves/coons_q0.csv --q1 corpus/curves/coons_q1.csv -o /tmp/coons.obj"
    )]
    Coons(CoonsArgs),
    /// Surface of revolution of a planar profile (x = radius, y = height) about the z axis (§5.2.3).
    #[command(
        after_help = "Examples:\n  mra surface revolve --order 3 corpus/curves/profile.csv -o /tmp/vase.obj\n  \
        mra surface revolve --order 3 --exact --angle 270 corpus/curves/profile.csv -o /tmp/vase.ply"
    )]
    Revolve(RevolveArgs),
    /// Sweep a planar profile along a 3D path with a rotation-minimising frame (§5.2.5).
    #[command(
        after_help = "Example:\n  mra surface sweep --order 3 --profile corpus/curves/section.csv --path corpus/curves/helix.csv -o /tmp/sweep.obj"
    )]
    Sweep(SweepArgs),
    /// Rotational blending surface between two planar strokes (§5.2.4).
    #[command(
        after_help = "Example:\n  mra surface rotational-blend --order 4 --left corpus/curves/left.csv --right corpus/curves/right.csv -o /tmp/pear.obj"
    )]
    RotationalBlend(BlendArgs),
    /// Cross-sectional blending surface: two strokes and a drawn section (§5.2.6).
    #[command(
        after_help = "Example:\n  mra surface cross-blend --order 4 --left corpus/curves/left.csv --right corpus/curves/right.csv \\\n      --section corpus/curves/section_leaf.csv --mirror -o /tmp/leaf.obj"
    )]
    CrossBlend(CrossArgs),
    /// Shaded PNG preview of a mesh (OBJ, PLY or OFF), z axis up, back faces in a warm tint.
    #[command(
        after_help = "Example:\n  mra surface primitive --shape torus -o /tmp/torus.obj && mra surface render /tmp/torus.obj -o /tmp/torus.png"
    )]
    Render(RenderArgs),
}

/// Output mesh options shared by every surface command.
#[derive(Args, Debug, Clone)]
pub struct MeshOut {
    /// Output mesh: .obj, .ply (ASCII) or .off (OFF carries no normals); `-`: standard
    /// output, with --format.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output): obj, ply or off.
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Samples along u and v, "U,V".
    #[arg(long, default_value = "48,48")]
    pub resolution: String,
    /// Quads instead of triangles.
    #[arg(long)]
    pub quads: bool,
}

/// How every input curve file becomes a curve.
#[derive(Args, Debug, Clone)]
pub struct CurveOpts {
    /// Curve representation of every input curve.
    #[arg(long, value_enum, default_value = "bspline")]
    pub kind: Kind,
    /// Order k of every input curve (B-spline, NURBS).
    #[arg(long, default_value_t = 4)]
    pub order: usize,
    /// Knots of every input curve: open, uniform or a file.
    #[arg(long, default_value = "open")]
    pub knots: String,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
pub enum PatchKind {
    Bezier,
    Bspline,
    Nurbs,
}

#[derive(Args, Debug)]
pub struct PatchArgs {
    /// Control net: CSV, one point per line, rows (along u) separated by blank lines.
    pub input: PathBuf,
    /// Patch representation.
    #[arg(long, value_enum, default_value = "bspline")]
    pub kind: PatchKind,
    /// Orders "KU,KV" (B-spline, NURBS).
    #[arg(long, default_value = "4,4")]
    pub order: String,
    /// Knots along u: open, uniform or a file.
    #[arg(long, default_value = "open")]
    pub knots_u: String,
    /// Knots along v: open, uniform or a file.
    #[arg(long, default_value = "open")]
    pub knots_v: String,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
pub enum Shape {
    Sphere,
    Torus,
    Cylinder,
}

#[derive(Args, Debug)]
pub struct PrimitiveArgs {
    /// Which primitive.
    #[arg(long, value_enum)]
    pub shape: Shape,
    /// Sphere / cylinder radius, or the torus' major radius.
    #[arg(long, default_value_t = 1.0)]
    pub radius: f64,
    /// Torus tube radius.
    #[arg(long, default_value_t = 0.35)]
    pub minor: f64,
    /// Cylinder height.
    #[arg(long, default_value_t = 2.0)]
    pub height: f64,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct LoftArgs {
    /// First curve P0(u).
    pub p0: PathBuf,
    /// Second curve P1(u).
    pub p1: PathBuf,
    #[command(flatten)]
    pub curves: CurveOpts,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct CoonsArgs {
    /// Boundary Q(u, 0).
    #[arg(long)]
    pub p0: PathBuf,
    /// Boundary Q(u, 1).
    #[arg(long)]
    pub p1: PathBuf,
    /// Boundary Q(0, v).
    #[arg(long)]
    pub q0: PathBuf,
    /// Boundary Q(1, v).
    #[arg(long)]
    pub q1: PathBuf,
    #[command(flatten)]
    pub curves: CurveOpts,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct RevolveArgs {
    /// Planar profile (x = distance from the axis, y = height).
    pub profile: PathBuf,
    /// Sweep angle in degrees.
    #[arg(long, default_value_t = 360.0)]
    pub angle: f64,
    /// Build the exact rational tensor-product patch (NURBS circle × profile).
    #[arg(long)]
    pub exact: bool,
    #[command(flatten)]
    pub curves: CurveOpts,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct SweepArgs {
    /// Planar profile c(v) (x along the normal N, y along the binormal B).
    #[arg(long)]
    pub profile: PathBuf,
    /// 3D trajectory t(u).
    #[arg(long)]
    pub path: PathBuf,
    /// Initial normal direction "x,y,z" (default: the axis least aligned with the start tangent).
    #[arg(long, allow_hyphen_values = true)]
    pub up: Option<String>,
    #[command(flatten)]
    pub curves: CurveOpts,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct BlendArgs {
    /// Left constructive stroke q_l(u).
    #[arg(long)]
    pub left: PathBuf,
    /// Right constructive stroke q_r(u).
    #[arg(long)]
    pub right: PathBuf,
    #[command(flatten)]
    pub curves: CurveOpts,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct CrossArgs {
    /// Left constructive stroke q_l(u).
    #[arg(long)]
    pub left: PathBuf,
    /// Right constructive stroke q_r(u).
    #[arg(long)]
    pub right: PathBuf,
    /// Planar cross-section stroke, drawn from its left end to its right end.
    #[arg(long)]
    pub section: PathBuf,
    /// Close the surface with the mirrored section underneath.
    #[arg(long)]
    pub mirror: bool,
    #[command(flatten)]
    pub curves: CurveOpts,
    #[command(flatten)]
    pub mesh: MeshOut,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Mesh to draw (OBJ, PLY or OFF; `-`: standard input, told by its first bytes).
    pub input: PathBuf,
    /// Output PNG (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Picture size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Camera azimuth in degrees.
    #[arg(long, default_value_t = 35.0, allow_hyphen_values = true)]
    pub azimuth: f64,
    /// Camera elevation in degrees.
    #[arg(long, default_value_t = 25.0, allow_hyphen_values = true)]
    pub elevation: f64,
}

pub fn run(c: Command) -> CliResult {
    match c {
        Command::Patch(a) => patch(a),
        Command::Primitive(a) => {
            let s = match a.shape {
                Shape::Sphere => TensorPatch::sphere(a.radius)?,
                Shape::Torus => TensorPatch::torus(a.radius, a.minor)?,
                Shape::Cylinder => TensorPatch::cylinder(a.radius, a.height)?,
            };
            write_mesh(&s, &a.mesh)
        }
        Command::Loft(a) => {
            let s = Loft {
                p0: curve(&a.p0, &a.curves)?,
                p1: curve(&a.p1, &a.curves)?,
            };
            write_mesh(&s, &a.mesh)
        }
        Command::Coons(a) => {
            let c = &a.curves;
            let s = Coons::new(
                curve(&a.p0, c)?,
                curve(&a.p1, c)?,
                curve(&a.q0, c)?,
                curve(&a.q1, c)?,
            )?;
            write_mesh(&s, &a.mesh)
        }
        Command::Revolve(a) => revolve(a),
        Command::Sweep(a) => {
            let up = match &a.up {
                Some(s) => {
                    let v = csv::parse_numbers(s, "--up")?;
                    if v.len() != 3 {
                        return Err(Failure(format!("invalid --up: {s} (expected x,y,z)")));
                    }
                    Some([v[0], v[1], v[2]])
                }
                None => None,
            };
            let s = Sweep::new(
                curve(&a.profile, &a.curves)?,
                curve(&a.path, &a.curves)?,
                2048,
                up,
            )?;
            write_mesh(&s, &a.mesh)
        }
        Command::RotationalBlend(a) => {
            let s = RotationalBlend::new(curve(&a.left, &a.curves)?, curve(&a.right, &a.curves)?)?;
            write_mesh(&s, &a.mesh)
        }
        Command::CrossBlend(a) => {
            let c = &a.curves;
            let s = CrossBlend::new(
                curve(&a.left, c)?,
                curve(&a.right, c)?,
                curve(&a.section, c)?,
                a.mirror,
            )?;
            write_mesh(&s, &a.mesh)
        }
        Command::Render(a) => {
            let m = super::stdio::input(&a.input, super::stdio::mesh_ext, |p| {
                mesh_io::read(p).map_err(|e| Failure::context(p.display(), e))
            })?;
            let (width, height) = parse_size(&a.size)?;
            let png = render_png(
                &m,
                &Options {
                    width,
                    height,
                    azimuth: a.azimuth,
                    elevation: a.elevation,
                    z_up: true,
                    back_color: Some(BACK_COLOR),
                    supersample: 2,
                    ..Options::default()
                },
            )?;
            write_atomic(&a.output, &png)
        }
    }
}

/// Base colour of the inside (back faces) of an open surface in previews.
const BACK_COLOR: [u8; 3] = [225, 170, 110];

fn curve(path: &Path, o: &CurveOpts) -> std::result::Result<Box<dyn crate::curve::Curve>, Failure> {
    Ok(load_path(path, o.kind, o.order, &o.knots)?.boxed())
}

fn pair(s: &str, what: &str) -> std::result::Result<(usize, usize), Failure> {
    let bad = || {
        Failure(format!(
            "invalid {what}: {s} (expected two integers \"U,V\")"
        ))
    };
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    Ok((
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ))
}

fn write_mesh(s: &dyn Surface, o: &MeshOut) -> CliResult {
    let (ru, rv) = pair(&o.resolution, "--resolution")?;
    let kind = if o.quads {
        FaceKind::Quads
    } else {
        FaceKind::Triangles
    };
    let m = tessellate(s, ru, rv, kind)?;
    super::stdio::output(&o.output, o.format.as_deref(), None, "obj, ply, off", |p| {
        let format = match Format::from_path(p).map_err(|e| Failure::context(p.display(), e))? {
            // ASCII keeps tessellated surfaces readable as text
            Format::Ply(_) => Format::Ply(Encoding::Ascii),
            f => f,
        };
        mesh_io::write_as(p, &m, format).map_err(|e| Failure::context(p.display(), e))
    })
}

fn patch(a: PatchArgs) -> CliResult {
    let t = read_table(&a.input)?;
    let ctx = |e: Error| Failure::context(a.input.display(), e);
    let (nu, nv) = (t.rows, t.cols);
    let s = match a.kind {
        PatchKind::Bezier => TensorPatch::bezier(t.points, t.dim, (nu, nv)).map_err(ctx)?,
        PatchKind::Bspline | PatchKind::Nurbs => {
            let (ku, kv) = pair(&a.order, "--order")?;
            check_order(nu, ku).map_err(ctx)?;
            check_order(nv, kv).map_err(ctx)?;
            let tu = knots_for(&a.knots_u, nu, ku)?;
            let tv = knots_for(&a.knots_v, nv, kv)?;
            match (a.kind, &t.weights) {
                (PatchKind::Bspline, None) => {
                    TensorPatch::bspline(t.points, t.dim, (nu, nv), (ku, kv), tu, tv)
                        .map_err(ctx)?
                }
                (PatchKind::Bspline, Some(_)) => {
                    return Err(ctx(Error::Unsupported {
                        what: "weights for a B-spline patch",
                        value: "use --kind nurbs".into(),
                    }))
                }
                _ => {
                    let w = t.weights.clone().unwrap_or_else(|| vec![1.0; nu * nv]);
                    TensorPatch::nurbs(&t.points, &w, t.dim, (nu, nv), (ku, kv), tu, tv)
                        .map_err(ctx)?
                }
            }
        }
    };
    if s.dim() != 3 && s.dim() != 2 {
        return Err(ctx(Error::parameter(
            "point dimension",
            s.dim(),
            "2 or 3 for a surface",
        )));
    }
    write_mesh(&s, &a.mesh)
}

fn revolve(a: RevolveArgs) -> CliResult {
    if !(a.angle > 0.0 && a.angle <= 360.0) {
        return Err(Failure(format!(
            "invalid --angle: {} (expected 0 < angle ≤ 360)",
            a.angle
        )));
    }
    let angle = a.angle.to_radians();
    if a.exact {
        let c = load_path(&a.profile, a.curves.kind, a.curves.order, &a.curves.knots)?;
        let n = match c {
            super::curve::Loaded::Nurbs(n) => n,
            super::curve::Loaded::BSpline(b) => {
                let w = vec![1.0; b.len()];
                crate::curve::Nurbs::new(b.points(), &w, b.dim(), b.order(), b.knots().to_vec())?
            }
            super::curve::Loaded::Bezier(b) => {
                let s = b.to_bspline();
                let w = vec![1.0; s.len()];
                crate::curve::Nurbs::new(s.points(), &w, s.dim(), s.order(), s.knots().to_vec())?
            }
        };
        let s = TensorPatch::revolve(&n, angle)
            .map_err(|e| Failure::context(a.profile.display(), e))?;
        return write_mesh(&s, &a.mesh);
    }
    let p = curve(&a.profile, &a.curves)?;
    if p.dim() != 2 {
        return Err(Failure::context(
            a.profile.display(),
            Error::parameter("profile dimension", p.dim(), "2 (radius, height)"),
        ));
    }
    write_mesh(&Revolution { profile: p, angle }, &a.mesh)
}
