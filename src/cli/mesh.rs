//! `mra mesh …`: information, subdivision, smoothing, simplification, normals, conversion,
//! orientation, rendering and subdivision-matrix analysis. A thin shell over `crate::mesh`.

use super::{stdio, CliResult, Failure};
use crate::mesh::{self, io, Features, HalfEdgeMesh, Mesh};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Counts, face degrees, components, boundary loops, χ, genus, manifold, orientable, bounds.
    ///
    /// Example: mra mesh info ../shared/corpus/meshes/bunny.ply --json
    Info {
        /// Input mesh: OBJ, PLY or OFF (`-`: standard input, told by its first bytes).
        input: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Subdivide with Loop, Catmull-Clark, Doo-Sabin or Butterfly (boundaries follow cubic
    /// B-spline curve rules; sharp edges from a file or by dihedral angle).
    ///
    /// Example: mra mesh subdivide ../shared/corpus/meshes/spot_quadrangulated.obj -o spot2.obj --scheme catmull-clark --steps 2 --crease-angle 60
    ///
    /// Adaptive: mra mesh subdivide ../shared/corpus/meshes/spot_triangulated.obj -o part.obj --scheme loop --steps 3 --box=-1,0,-1,1,1,1
    Subdivide(SubdivideArgs),
    /// Laplacian smoothing (uniform or cotangent, explicit or implicit).
    ///
    /// Example: mra mesh smooth ../shared/corpus/meshes/bunny.ply -o smooth.ply --laplacian cotangent --method implicit --lambda 1
    Smooth(SmoothArgs),
    /// Quadric-error simplification by edge collapses to a target face count.
    ///
    /// Example: mra mesh simplify ../shared/corpus/meshes/bunny.ply -o small.ply --faces 1000
    Simplify {
        #[command(flatten)]
        files: MeshInOut,
        /// Target number of faces.
        #[arg(long)]
        faces: usize,
    },
    /// Compute vertex normals and write them with the mesh (PLY nx ny nz, OBJ vn).
    ///
    /// Example: mra mesh normals ../shared/corpus/meshes/bunny.ply -o bunny_n.ply --weighting angle
    Normals {
        #[command(flatten)]
        files: MeshInOut,
        /// uniform, area or angle.
        #[arg(long, default_value = "angle")]
        weighting: String,
    },
    /// Convert between OBJ, PLY and OFF (by extension).
    ///
    /// Example: mra mesh convert ../shared/corpus/meshes/bunny.ply -o bunny.obj
    Convert {
        #[command(flatten)]
        files: MeshInOut,
        /// Write PLY as ASCII.
        #[arg(long)]
        ascii: bool,
        /// Write PLY as binary big endian.
        #[arg(long, conflicts_with = "ascii")]
        big_endian: bool,
    },
    /// Orient all faces consistently (fails on non-orientable meshes).
    ///
    /// Example: mra mesh orient ../shared/corpus/meshes/penguin.off -o oriented.obj
    Orient {
        #[command(flatten)]
        files: MeshInOut,
    },
    /// Render a shaded PNG picture (z-buffer, optional wireframe).
    ///
    /// Example: mra mesh render ../shared/corpus/meshes/bunny.ply -o bunny.png --size 800x600 --view 30,20 --wireframe
    Render {
        /// Input mesh: OBJ, PLY or OFF (`-`: standard input, told by its first bytes).
        input: PathBuf,
        /// Output PNG (`-`: standard output).
        #[arg(short, long)]
        output: PathBuf,
        /// Width x height in pixels.
        #[arg(long, default_value = "800x600")]
        size: String,
        /// Azimuth,elevation of the camera in degrees.
        #[arg(long, default_value = "30,20", allow_hyphen_values = true)]
        view: String,
        /// Draw the edges.
        #[arg(long)]
        wireframe: bool,
        /// The model's up axis is +z (default +y).
        #[arg(long)]
        z_up: bool,
    },
    /// Free-form deformation (Sederberg–Parry) by a trivariate B-spline lattice (notes §10.2):
    /// the lattice starts as the identity map over the mesh's bounding box (or the file's box);
    /// the file moves control points. JSON: `{"dims":[4,4,4], "degree":3, "box":{"min":[..],
    /// "max":[..]}` (optional), `"moves":[{"index":[i,j,k], "offset":[dx,dy,dz]}]}` or
    /// `"points": [[x,y,z], …]` (all nx·ny·nz, x index fastest). See docs/solid.md.
    ///
    /// Example: mra solid polygonize corpus/scenes/sphere.json -o ball.obj --resolution 48 &&
    /// mra mesh deform ball.obj -o bulged.obj --lattice corpus/lattices/bulge.json
    Deform {
        #[command(flatten)]
        files: MeshInOut,
        /// Lattice file (JSON).
        #[arg(long)]
        lattice: PathBuf,
    },
    /// Eigenvalues of the local subdivision matrix of Loop or Catmull-Clark at valence N.
    ///
    /// Example: mra mesh analyze --scheme loop --valence 5
    Analyze {
        /// loop or catmull-clark.
        #[arg(long)]
        scheme: String,
        #[arg(long)]
        valence: usize,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Args, Debug)]
pub struct SubdivideArgs {
    #[command(flatten)]
    files: MeshInOut,
    /// loop, loop-warren, catmull-clark, doo-sabin or butterfly.
    #[arg(long)]
    scheme: String,
    #[arg(long, default_value_t = 1)]
    steps: usize,
    /// Sidecar file of sharp edges (`a b` per line) and corners (`corner v`).
    #[arg(long)]
    creases: Option<PathBuf>,
    /// Tag edges whose dihedral angle exceeds DEG degrees as sharp.
    #[arg(long, value_name = "DEG", conflicts_with = "creases")]
    crease_angle: Option<f64>,
    /// Adaptive: refine only these faces (comma-separated indices), growing one ring per level.
    #[arg(long, value_name = "FACES")]
    adaptive: Option<String>,
    /// Adaptive: refine the faces with a vertex in the box x0,y0,z0,x1,y1,z1.
    #[arg(
        long,
        value_name = "BOX",
        conflicts_with = "adaptive",
        allow_hyphen_values = true
    )]
    r#box: Option<String>,
    /// Adaptive: refine the faces whose area exceeds A.
    #[arg(long, value_name = "A", conflicts_with_all = ["adaptive", "box"])]
    area_above: Option<f64>,
}

#[derive(Args, Debug)]
pub struct SmoothArgs {
    #[command(flatten)]
    files: MeshInOut,
    /// uniform or cotangent.
    #[arg(long, default_value = "uniform")]
    laplacian: String,
    /// explicit or implicit.
    #[arg(long, default_value = "explicit")]
    method: String,
    #[arg(long, default_value_t = 0.5)]
    lambda: f64,
    #[arg(long, default_value_t = 10)]
    iterations: usize,
    /// Keep boundary vertices fixed.
    #[arg(long)]
    fix_boundary: bool,
}

/// Where a mesh goes: a file whose extension picks the format, or standard output.
#[derive(Args, Debug)]
pub struct MeshOut {
    /// Output mesh: OBJ, PLY or OFF, by extension (`-`: standard output, with --format).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Format of `-o -` (standard output): obj, ply or off.
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
}

/// A mesh in and a mesh out: the arguments of most mesh commands.
#[derive(Args, Debug)]
pub struct MeshInOut {
    /// Input mesh: OBJ, PLY or OFF (`-`: standard input, told by its first bytes).
    input: PathBuf,
    #[command(flatten)]
    out: MeshOut,
}

impl MeshInOut {
    fn read(&self) -> Result<Mesh, Failure> {
        read(&self.input)
    }

    fn write(&self, m: &Mesh) -> CliResult {
        write(&self.out.output, self.out.format.as_deref(), m)
    }
}

/// A mesh file, or standard input for `-` (its format told by its first bytes).
fn read(path: &Path) -> Result<Mesh, Failure> {
    stdio::input(path, stdio::mesh_ext, |p| {
        io::read(p).map_err(|e| Failure::context(p.display(), e))
    })
}

/// The formats a mesh is written in, for the error of `-o -` without `--format`.
const MESH_FORMATS: &str = "obj, ply, off";

/// Write a mesh to `path` (its extension picks the format), or to standard output for `-`
/// in `format`.
fn write(path: &Path, format: Option<&str>, m: &Mesh) -> CliResult {
    stdio::output(path, format, None, MESH_FORMATS, |p| {
        io::write(p, m).map_err(|e| Failure::context(p.display(), e))
    })
}

fn floats(s: &str, n: usize, what: &'static str) -> Result<Vec<f64>, Failure> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            Failure(format!(
                "invalid {what}: {s:?} (expected {n} comma-separated numbers)"
            ))
        })?;
    if v.len() != n || !v.iter().all(|x| x.is_finite()) {
        return Err(Failure(format!(
            "invalid {what}: {s:?} (expected {n} comma-separated numbers)"
        )));
    }
    Ok(v)
}

pub fn run(c: Command) -> CliResult {
    match c {
        Command::Info { input, json } => {
            let m = read(&input)?;
            let r = mesh::topology::analyze(&m);
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&r).map_err(|e| Failure(e.to_string()))?
                );
            } else {
                print_info(&input, &r);
            }
            Ok(())
        }
        Command::Subdivide(a) => subdivide(a),
        Command::Smooth(a) => smooth(a),
        Command::Simplify { files, faces } => {
            files.write(&mesh::simplify::simplify(&files.read()?, faces)?)
        }
        Command::Normals { files, weighting } => {
            let mut m = files.read()?;
            let w = mesh::normals::Weighting::parse(&weighting)?;
            let n = mesh::normals::vertex_normals(&m, w);
            m.attributes
                .vertex
                .retain(|p| !matches!(p.name.as_str(), "nx" | "ny" | "nz"));
            m.attributes.normals.clear();
            m.attributes.corner_normal.clear();
            m.attributes.vertex_normals = Some(n);
            files.write(&m)
        }
        Command::Convert {
            files,
            ascii,
            big_endian,
        } => convert(&files, ascii, big_endian),
        Command::Orient { files } => files.write(&mesh::topology::orient(&files.read()?)?),
        Command::Render {
            input,
            output,
            size,
            view,
            wireframe,
            z_up,
        } => render(&input, &output, &size, &view, wireframe, z_up),
        Command::Deform { files, lattice } => {
            let m = files.read()?;
            let text = stdio::read_text(&lattice)?;
            let bbox = crate::solid::ffd::bounds(&m)
                .map_err(|e| Failure::context(files.input.display(), e))?;
            let lat = crate::solid::ffd::Lattice::parse(&text, bbox)
                .map_err(|e| Failure::context(lattice.display(), e))?;
            files.write(&lat.deform(&m))
        }
        Command::Analyze {
            scheme,
            valence,
            json,
        } => analyze_surface(&scheme, valence, json),
    }
}

fn smooth(a: SmoothArgs) -> CliResult {
    let m = a.files.read()?;
    let kind = mesh::laplacian::Kind::parse(&a.laplacian)?;
    let method = match a.method.as_str() {
        "explicit" => mesh::laplacian::Method::Explicit,
        "implicit" => mesh::laplacian::Method::Implicit,
        other => {
            return Err(Failure(format!(
                "invalid method: {other} (expected explicit or implicit)"
            )))
        }
    };
    let out = mesh::laplacian::smooth(&m, kind, method, a.lambda, a.iterations, a.fix_boundary)?;
    a.files.write(&out)
}

/// Write the mesh in the output's format (PLY binary little endian unless `ascii` or
/// `big_endian`).
fn convert(files: &MeshInOut, ascii: bool, big_endian: bool) -> CliResult {
    let m = files.read()?;
    stdio::output(
        &files.out.output,
        files.out.format.as_deref(),
        None,
        MESH_FORMATS,
        |p| {
            let mut fmt = io::Format::from_path(p).map_err(|e| Failure::context(p.display(), e))?;
            if let io::Format::Ply(_) = fmt {
                fmt = io::Format::Ply(if ascii {
                    io::ply::Encoding::Ascii
                } else if big_endian {
                    io::ply::Encoding::BinaryBigEndian
                } else {
                    io::ply::Encoding::BinaryLittleEndian
                });
            }
            io::write_as(p, &m, fmt).map_err(|e| Failure::context(p.display(), e))
        },
    )
}

fn render(
    input: &Path,
    output: &Path,
    size: &str,
    view: &str,
    wireframe: bool,
    z_up: bool,
) -> CliResult {
    let m = read(input)?;
    let (w, h) = size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<usize>().ok()?, h.parse::<usize>().ok()?)))
        .ok_or_else(|| Failure(format!("invalid size: {size:?} (expected WIDTHxHEIGHT)")))?;
    let v = floats(view, 2, "view")?;
    let opts = mesh::render::Options {
        width: w,
        height: h,
        azimuth: v[0],
        elevation: v[1],
        wireframe,
        z_up,
        ..Default::default()
    };
    let png = mesh::render::render_png(&m, &opts)?;
    stdio::write_bytes(output, &png)
}

fn subdivide(a: SubdivideArgs) -> CliResult {
    let m = a.files.read()?;
    let scheme = mesh::subdivide::Scheme::parse(&a.scheme)?;
    let features = if let Some(path) = &a.creases {
        let text = stdio::read_text(path)?;
        Features::parse(&text).map_err(|e| Failure::context(path.display(), e))?
    } else if let Some(deg) = a.crease_angle {
        let he =
            HalfEdgeMesh::build(&m).map_err(|e| Failure::context(a.files.input.display(), e))?;
        Features::from_crease_angle(&m, &he, deg)?
    } else {
        Features::default()
    };
    let selection = if let Some(list) = &a.adaptive {
        Some(
            list.split(',')
                .map(|t| t.trim().parse::<u32>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(|_| {
                    Failure(format!(
                        "invalid face list: {list:?} (expected comma-separated face indices)"
                    ))
                })?,
        )
    } else if let Some(b) = &a.r#box {
        let v = floats(b, 6, "box")?;
        Some(mesh::adaptive::faces_in_box(
            &m,
            [v[0], v[1], v[2]],
            [v[3], v[4], v[5]],
        ))
    } else if let Some(area) = a.area_above {
        if !(area.is_finite() && area >= 0.0) {
            return Err(Failure(format!(
                "invalid area: {area} (expected a number ≥ 0)"
            )));
        }
        Some(mesh::adaptive::faces_larger_than(&m, area))
    } else {
        None
    };
    let out = match selection {
        Some(sel) => mesh::adaptive::subdivide(&m, scheme, a.steps, &sel, &features),
        None => mesh::subdivide::subdivide(&m, scheme, a.steps, &features),
    }
    .map_err(|e| Failure::context(a.files.input.display(), e))?;
    a.files.write(&out)
}

fn print_info(path: &Path, r: &mesh::topology::Report) {
    println!("{}", path.display());
    println!(
        "  vertices {}  edges {}  faces {}",
        r.vertices, r.edges, r.faces
    );
    let hist: Vec<String> = r
        .face_degrees
        .iter()
        .map(|(d, n)| format!("{d}-gons: {n}"))
        .collect();
    println!("  face degrees: {}", hist.join(", "));
    println!(
        "  components {}  boundary loops {} ({} edges)  isolated vertices {}",
        r.components.len(),
        r.boundary_loops,
        r.boundary_edges,
        r.isolated_vertices
    );
    println!(
        "  euler characteristic {}  genus {}",
        r.euler,
        r.genus
            .map(|g| g.to_string())
            .unwrap_or_else(|| "n/a".into())
    );
    println!(
        "  manifold {}  orientable {}  consistently oriented {}  closed {}",
        r.manifold, r.orientable, r.oriented, r.closed
    );
    if !r.manifold {
        println!(
            "  non-manifold edges {:?}  non-manifold vertices {:?}",
            &r.non_manifold_edges[..r.non_manifold_edges.len().min(10)],
            &r.non_manifold_vertices[..r.non_manifold_vertices.len().min(10)]
        );
    }
    if r.components.len() > 1 {
        for (i, c) in r.components.iter().enumerate().take(20) {
            println!(
                "  component {i}: V {} E {} F {} χ {} boundary loops {} genus {}",
                c.vertices,
                c.edges,
                c.faces,
                c.euler,
                c.boundary_loops,
                c.genus
                    .map(|g| g.to_string())
                    .unwrap_or_else(|| "n/a".into())
            );
        }
    }
    if let Some((lo, hi)) = r.bounding_box {
        println!("  bounding box {lo:?} .. {hi:?}");
    }
}

/// Eigenvalues of the local subdivision matrix of a surface scheme at a vertex of the
/// given valence (`mra mesh analyze` and `mra scheme analyze --surface`).
pub fn analyze_surface(scheme: &str, valence: usize, json: bool) -> CliResult {
    let s = mesh::analysis::Surface::parse(scheme)?;
    let ev = mesh::analysis::local_eigenvalues(s, valence)?;
    if json {
        println!(
            "{}",
            serde_json::json!({"scheme": scheme, "valence": valence, "eigenvalues": ev})
        );
    } else {
        println!("{scheme} valence {valence}: local subdivision matrix eigenvalues (descending)");
        for e in ev {
            println!("  {e:.12}");
        }
    }
    Ok(())
}
